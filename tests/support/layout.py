"""A stand-in for Blender's UILayout that records what a panel draws."""

import types


class Recorder:
    """Stands in for a UILayout: records what is drawn, and sub-layouts record into it too."""

    def __init__(self, calls=None):
        self.calls = [] if calls is None else calls

    def __getattr__(self, name):
        if name in ("row", "column", "box", "split", "grid_flow", "column_flow"):
            return lambda *a, **k: Recorder(self.calls)
        def record(*a, **k):
            self.calls.append((name, a, k))
            return types.SimpleNamespace()  # what operator() gives: properties to set

        return record

    def __setattr__(self, name, value):
        if name == "calls":
            object.__setattr__(self, name, value)


def draw_panel(bpy, panel_cls) -> list:
    """The calls ``panel_cls.draw`` makes on a recording layout: (name, args, kwargs)."""
    rec = Recorder()
    panel_cls.draw(types.SimpleNamespace(layout=rec), bpy.context)
    return rec.calls
