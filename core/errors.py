"""The root of the project's own errors: input a user can fix (a malformed job, an unreadable
image, clicks that pin nothing). Each message names the file, view, bone or frame and what to
do; anything else that escapes is a bug and is reported as one."""


class InputError(ValueError):
    """Bad input, with a message for the user."""
