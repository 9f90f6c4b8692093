"""The shape most of the add-on's operators share: act on the scene's armature, report what
was done, or report why not and change nothing."""

from __future__ import annotations

from ..core.image import ImageError
from ..core.job import JobError
from .bridge import BridgeError

EXPECTED = (BridgeError, ImageError, JobError, ValueError, OSError)  # bad input, not bugs


class ArmatureAction:
    """Mixin for a ``bpy.types.Operator``: it polls for the scene's armature, and its
    ``run(context)`` returns the message to report; an expected error is reported instead
    and the operator is cancelled."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.twist.armature is not None

    def execute(self, context):
        try:
            message = self.run(context)
        except EXPECTED as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, message)
        return {"FINISHED"}
