"""A picture of the sidebar tab for the README: the add-on's panels drawn from their own draw
calls, on the bundled example after Track.

    python scripts/panel_tour.py [--out docs/panel_tour.png]

Blender run as a Python module has no window to take a screenshot of, so each panel's
``draw`` runs against a layout that records what it lays out (rows, columns, boxes,
properties with their current values, operator buttons, lists), and that record is drawn in
the colours of Blender's default theme. Folded sub-panels are drawn folded, except the bone
map, shown open with the CMU to Rigify preset loaded.
"""

from __future__ import annotations

import argparse
import sys
import types
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

from addon_dev import load_addon  # noqa: E402

EXAMPLE = ROOT / "example_blends" / "walk_3view.blend"
ICONS = {"ADD": "+", "REMOVE": "-", "X": "x"}  # icon-only buttons, as a glyph
ICON_WIDTH = 28
WIDTH, ROW, PAD = 380, 26, 8
FONT, SCALE = cv2.FONT_HERSHEY_SIMPLEX, 0.42
BG, HEADER, BUTTON, FIELD, TEXT, DIM, ACCENT = ((48, 48, 48), (61, 61, 61), (84, 84, 84),
                                               (29, 29, 29), (230, 230, 230), (150, 150, 150),
                                               (210, 120, 70))


class Layout:
    """Stands in for a UILayout: a tree of rows, columns and boxes whose leaves are the items
    drawn (kind, text, value)."""

    def __init__(self, kind="column"):
        self.kind, self.children = kind, []
        self.use_property_split = False
        self.scale_y = 1.0

    def _child(self, kind):
        node = Layout(kind)
        self.children.append(node)
        return node

    def row(self, **_):
        return self._child("row")

    def column(self, heading="", **_):
        node = self._child("column")
        if heading:
            node.children.append(("label", heading, None))
        return node

    def box(self):
        return self._child("box")

    def separator(self, **_):
        self.children.append(("gap", "", None))

    def label(self, text="", **_):
        self.children.append(("label", text, None))

    def prop(self, data, name, text=None, expand=False, **_):
        rna = data.bl_rna.properties[name]
        value = getattr(data, name)
        label = rna.name if text is None else text
        if rna.type == "BOOLEAN":
            self.children.append(("check", label, bool(value)))
        elif rna.type == "ENUM" and expand:
            items = [(i.identifier, i.name) for i in rna.enum_items]
            self.children.append(("tabs", label, [(n, ident == value) for ident, n in items]))
        elif rna.type == "ENUM":
            name_of = {i.identifier: i.name for i in rna.enum_items}
            self.children.append(("field", label, name_of.get(value, str(value))))
        elif rna.type == "POINTER":
            self.children.append(("field", label, value.name if value else ""))
        elif rna.type == "FLOAT":
            self.children.append(("field", label, f"{value:.{min(rna.precision, 4)}f}"))
        else:
            self.children.append(("field", label, str(value)))

    def prop_search(self, data, name, *_, **__):
        self.prop(data, name)

    def operator(self, idname, text=None, icon="", **_):
        mod, fn = idname.split(".")
        label = getattr(getattr(__import__("bpy").ops, mod), fn).get_rna_type().name
        if text == "":  # an icon button
            self.children.append(("icon", ICONS.get(icon, "o"), None))
        else:
            self.children.append(("button", label if text is None else text, None))
        return types.SimpleNamespace()

    def operator_menu_enum(self, idname, prop, text=None, **kw):
        self.operator(idname, text=(text or "") + " v" if text else None, **kw)
        self.children[-1] = ("button", self.children[-1][1] + "  v", None)

    def template_list(self, _list, _id, data, propname, *_, rows=3, **__):
        items = getattr(data, propname)
        lines = []
        for item in list(items)[:rows]:
            if hasattr(item, "camera"):
                lines.append(f"{item.camera.name if item.camera else '-'}   {item.images}")
            else:
                lines.append(f"{item.source}  ->  {item.target}")
        lines += [""] * (rows - len(lines))
        self.children.append(("list", "", lines))


def _text(img, text, x, y, color=TEXT):
    cv2.putText(img, text, (x, y), FONT, SCALE, color, 1, cv2.LINE_AA)


def _width(text):
    return cv2.getTextSize(text, FONT, SCALE, 1)[0][0]


def _fit(text, room):
    while text and _width(text) > room:
        text = text[:-2] + "~"
    return text


def _icons_only(node) -> bool:
    """An icon button, or a column of nothing else: drawn narrow."""
    if isinstance(node, tuple):
        return node[0] == "icon"
    return bool(node.children) and all(_icons_only(c) for c in node.children)


def draw_node(img, node, x, y, w) -> int:
    """Draw a layout node in the box (x, y, w); returns the y under it."""
    if isinstance(node, tuple):
        return draw_item(img, node, x, y, w)
    if node.kind == "row" and node.children:
        narrow = [_icons_only(c) for c in node.children]
        each = (w - ICON_WIDTH * sum(narrow)) // max(len(narrow) - sum(narrow), 1)
        bottom = y
        for child, thin in zip(node.children, narrow):
            cw = ICON_WIDTH if thin else each
            bottom = max(bottom, draw_node(img, child, x, y, cw - 2))
            x += cw
        return bottom
    top = y
    inner_x, inner_w = (x + 6, w - 12) if node.kind == "box" else (x, w)
    if node.kind == "box":
        y += 4
    for child in node.children:
        y = draw_node(img, child, inner_x, y, inner_w)
    if node.kind == "box":
        cv2.rectangle(img, (x, top), (x + w, y + 2), DIM, 1)
        y += 6
    return y


def draw_item(img, item, x, y, w) -> int:
    kind, label, value = item
    h = ROW - 4
    if kind == "gap":
        return y + 8
    if kind == "label":
        _text(img, _fit(label, w), x + 2, y + 16, DIM)
        return y + ROW
    if kind in ("button", "icon"):
        cv2.rectangle(img, (x, y), (x + w, y + h), BUTTON, -1)
        t = _fit(label, w - 8)
        _text(img, t, x + (w - _width(t)) // 2, y + 16)
        return y + ROW
    if kind == "check":
        cv2.rectangle(img, (x + 2, y + 5), (x + 14, y + 17), ACCENT if value else FIELD, -1)
        if value:
            cv2.polylines(img, [np.array([(x + 4, y + 11), (x + 7, y + 15), (x + 13, y + 7)])],
                          False, TEXT, 2, cv2.LINE_AA)
        _text(img, _fit(label, w - 22), x + 20, y + 16)
        return y + ROW
    if kind == "tabs":
        each = w // len(value)
        for i, (name, on) in enumerate(value):
            cv2.rectangle(img, (x + i * each, y), (x + (i + 1) * each - 1, y + h),
                          ACCENT if on else BUTTON, -1)
            t = _fit(name, each - 6)
            _text(img, t, x + i * each + (each - _width(t)) // 2, y + 16)
        return y + ROW
    if kind == "field":
        split = x + int(0.42 * w)
        _text(img, _fit(label, split - x - 6), x + 2, y + 16, DIM)
        cv2.rectangle(img, (split, y), (x + w, y + h), FIELD, -1)
        _text(img, _fit(str(value), x + w - split - 8), split + 5, y + 16)
        return y + ROW
    if kind == "list":
        cv2.rectangle(img, (x, y), (x + w, y + len(value) * 20 + 4), FIELD, -1)
        for i, line in enumerate(value):
            _text(img, _fit(line, w - 10), x + 5, y + 16 + 20 * i)
        return y + len(value) * 20 + 10
    raise ValueError(kind)


def panel_image(bpy, panels, open_subpanels: set[str]) -> np.ndarray:
    """Every panel of the tab, top to bottom, as one image."""
    img = np.full((2400, WIDTH, 3), BG, np.uint8)
    y = PAD
    for cls in panels:
        if not issubclass(cls, bpy.types.Panel):
            continue
        sub = getattr(cls, "bl_parent_id", "")
        x = PAD + (12 if sub else 0)
        folded = sub and "DEFAULT_CLOSED" in getattr(cls, "bl_options", set()) and \
            cls.__name__ not in open_subpanels
        cv2.rectangle(img, (x, y), (WIDTH - PAD, y + ROW), HEADER, -1)
        mark = ">" if folded else "v"
        _text(img, f"{mark}  {cls.bl_label}", x + 6, y + 17)
        y += ROW + 6
        if folded:
            continue
        root = Layout()
        cls.draw(types.SimpleNamespace(layout=root), bpy.context)
        y = draw_node(img, root, x + 6, y, WIDTH - PAD - x - 12) + 8
    return img[:y + PAD]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "panel_tour.png")
    a = ap.parse_args(argv)
    import bpy

    addon = load_addon()
    addon.register()
    bpy.ops.wm.open_mainfile(filepath=str(EXAMPLE))
    scene = bpy.context.scene
    scene.frame_set(scene.frame_start)
    bpy.ops.twist.track()
    bpy.ops.twist.load_bone_map(source_preset="CMU", target_preset="RIGIFY")
    scene.twist.marker_bone = "LeftKnee"
    img = panel_image(bpy, addon.twist_addon.panels.CLASSES, {"TWIST_PT_bone_map"})
    header = np.full((34, WIDTH, 3), (35, 35, 35), np.uint8)
    _text(header, "3D Viewport > Sidebar (N) > Twist Mocap", PAD, 22)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(a.out), np.vstack([header, img]))
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
