"""twist-mocap as a Blender extension: this folder is the package (``bl_ext.<repo>.twist_mocap``).

Nothing is imported at module level, so that tools which import this file (pytest, the
extension builder) need neither bpy nor the bundled wheels.
"""


def register():
    from . import twist_addon

    twist_addon.register()


def unregister():
    from . import twist_addon

    twist_addon.unregister()
