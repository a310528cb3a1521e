"""The scene file a bake from Blender runs: `scene.aurora` plus the shot.

`scene_document` gathers the panel's values (properties.py: only keys that
differ from their defaults), the active camera (camera_export.py), the
render size, the frame rate and each curtain's path (curve_path.py); a
curtain with a path gets `path` and no `center` / `length` / `rotation_deg`
(the binary refuses both). `to_toml` writes it: Blender's Python has a
TOML reader (tomllib) and no writer, and a scene file needs only numbers,
booleans, strings, arrays, tables and an array of tables.
"""

from __future__ import annotations

import json
import math

import bpy

from . import properties as P
from .camera_export import camera_table, render_size
from .curve_path import curve_path

#: Keys a path replaces (src/scene/: giving both is an error).
STRAIGHT_KEYS = ("center", "length", "rotation_deg")


def curtain_table(c, depsgraph=None) -> dict:
    t = P.table_values(c, "curtain", P.SCHEMA["curtain"])
    path = None
    if c.path_object is not None:
        path = curve_path(c.path_object, depsgraph)
    elif c.path_points.strip():
        path = json.loads(c.path_points)
    if path is not None:
        for k in STRAIGHT_KEYS:
            t.pop(k, None)
        t["path"] = [[P.short_float(x), P.short_float(y)] for x, y in path]
    if isinstance(t.get("magnetic_path"), str):
        # [[latitude, mlt], ...] as JSON: the points in magnetic coordinates.
        for k in STRAIGHT_KEYS:
            t.pop(k, None)
        t["magnetic_path"] = [[float(a), float(b)] for a, b in json.loads(t["magnetic_path"])]
    return t


def scene_document(scene: bpy.types.Scene, depsgraph=None) -> dict:
    """The scene file's contents (a dict for `to_toml`)."""
    s = scene.aurora
    doc: dict = P.table_values(s, "", P.SCHEMA[""])
    for t in P.TABLE_GROUPS:
        values = P.table_values(getattr(s, t), t, P.panel_keys(t))
        if values:
            doc[t] = values
    w, h = render_size(scene)
    doc.setdefault("render", {}).update({"width": w, "height": h})
    doc.setdefault("animation", {})["fps"] = scene.render.fps / scene.render.fps_base
    if scene.camera is not None:
        doc["camera"] = camera_table(scene.camera, scene, depsgraph)
    if len(s.curtains):
        doc["curtain"] = [curtain_table(c, depsgraph) for c in s.curtains]
    return doc


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"not a finite number: {v}")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a TOML basic string
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def to_toml(doc: dict) -> str:
    lines = [f"{k} = {_value(v)}" for k, v in doc.items() if k != "curtain" and not isinstance(v, dict)]
    for k, v in doc.items():
        if isinstance(v, dict):
            lines += ["", f"[{k}]"] + [f"{kk} = {_value(vv)}" for kk, vv in v.items()]
    for c in doc.get("curtain", []):
        lines += ["", "[[curtain]]"] + [f"{kk} = {_value(vv)}" for kk, vv in c.items()]
    return "\n".join(lines) + "\n"
