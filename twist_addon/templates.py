"""Template armatures: the bodies the tracker knows, added as armatures whose bone locks say
which joints are hinges and balls.

Operator id (a public contract): ``twist.add_template_armature``."""

from __future__ import annotations

import bpy

from .bridge import armature_from_skeleton

# name: (label, description, core template function, its arguments)
TEMPLATES = {
    "HUMAN": ("Human (19 degrees of freedom)", "The paper's body: ball hips, shoulders and "
              "neck; hinge knees and elbows, bending one way", "human_template", {}),
    "HUMAN_LOWER_BACK": ("Human, lower back free (22)", "The human with its spine a ball too, "
                         "so that the pelvis turns against the chest: better for a walker "
                         "seen in several views, worse in one", "human_template",
                         {"lower_back": True}),
    "WALKER": ("Walker (6, from the side)", "Hinge hips, knees and ankles turning in the view's "
               "plane", "walker_template", {}),
    "QUADRUPED": ("Quadruped (planar)", "Trunk, neck, head and four two-joint legs, all "
                  "turning in the view's plane", "planar_quadruped_template", {}),
}


class TWIST_OT_add_template_armature(bpy.types.Operator):
    """Add an armature for tracking, its bones locked to the template's hinges and balls"""

    bl_idname = "twist.add_template_armature"
    bl_label = "Add Template Armature"
    bl_options = {"REGISTER", "UNDO"}

    template: bpy.props.EnumProperty(
        name="Template", description="The body to track",
        items=[(k, v[0], v[1]) for k, v in TEMPLATES.items()])

    def execute(self, context):
        from ..core import skeleton

        _, _, build, kwargs = TEMPLATES[self.template]
        sk = getattr(skeleton, build)(**kwargs)
        if context.object and context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        arm = armature_from_skeleton(sk, self.template.replace("_", " ").title(),
                                     context.collection)
        context.scene.twist.armature = arm
        self.report({"INFO"}, f"added '{arm.name}': {len(sk.dof_names())} degrees of freedom")
        return {"FINISHED"}


CLASSES = (TWIST_OT_add_template_armature,)
