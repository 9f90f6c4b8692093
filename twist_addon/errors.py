"""The add-on's error policy: the project's own errors (``core.errors.InputError``: a bad job,
image, skeleton, click or scene, each with a message for the user) and the operating system's
(a missing folder, a file that cannot be written) are the user's to fix, so an operator reports
them and cancels; anything else is a bug, and reaches Blender's traceback as one."""

from __future__ import annotations

from ..core.errors import InputError

INPUT_ERRORS = (InputError, OSError)
