"""The shape most of the add-on's operators share: act on the scene's armature, report what
was done, or report why not and change nothing."""

from __future__ import annotations

from .errors import INPUT_ERRORS


class ArmatureAction:
    """Mixin for a ``bpy.types.Operator``: it polls for the scene's armature, and its
    ``run(context)`` returns the message to report; an input error (``errors``) is reported
    instead and the operator is cancelled."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is not None and context.scene.twist.armature is not None:
            return True
        cls.poll_message_set("Set the armature to track first (Twist Mocap > Armature)")
        return False

    def execute(self, context):
        try:
            message = self.run(context)
        except INPUT_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, message)
        return {"FINISHED"}
