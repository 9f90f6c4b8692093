"""The Blender side of twist-mocap: everything that touches bpy. Core stays bpy-free."""

import bpy

from . import (
    body,
    cycle,
    export,
    fit,
    hinges,
    markers,
    overlay,
    panels,
    properties,
    refine,
    retarget,
    smooth,
    templates,
    track,
    views,
)

MODULES = (properties, views, templates, hinges, track, markers, fit, refine, body, smooth,
           cycle, retarget, export, panels, overlay)


def register():
    for module in MODULES:
        for cls in module.CLASSES:
            bpy.utils.register_class(cls)
        if hasattr(module, "register"):
            module.register()


def unregister():
    for module in reversed(MODULES):
        if hasattr(module, "unregister"):
            module.unregister()
        for cls in reversed(module.CLASSES):
            bpy.utils.unregister_class(cls)
