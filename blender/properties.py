"""`scene.aurora`: every scene key as a Blender property, built from the schema.

One source: `scene_schema.json` (`aurora scene --schema`: default, range,
allowed words) and `scene_keys.json` (unit and description of each key,
the table docs/scene.md is made from) decide every property here; nothing is
restated. A key becomes a property of the group named after its table
(`scene.aurora.beams.count`), top-level keys sit on `scene.aurora` itself
(`scene.aurora.seed`), and `[[curtain]]` tables are the collection
`scene.aurora.curtains`, each with an optional `path_object` (a Curve object
whose world-space shape, z dropped, becomes the curtain's `path`).

Keys that come from the Blender scene, not the panel: `[camera]` (the active
camera, camera_export.py), `render.width` / `render.height` (the scene's
resolution, so the aspect ratio the camera was framed for is the bake's) and
`animation.fps` (the scene's frame rate, so a baked sequence plays in real
time).

Mapping from a schema entry to a property (by its default): bool -> Bool,
int -> Int, float -> Float (min / max from the range; an open bound is left to
the binary's check, which names the key), word with `values` -> Enum, null ->
a file path ("" = absent), 2-4 numbers -> a vector, anything else (the
colour map's rows) -> its JSON text. A rule allowing the word "auto" (grid
voxel size) adds a Bool `<key>_auto`. Blender stores floats in 32 bits, so
a value equal to its default at float32 precision is not written to the
scene file at all: the binary then takes its exact default, and a panel left
alone bakes exactly the CLI's scene.
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    IntVectorProperty,
    PointerProperty,
    StringProperty,
)
from bpy.types import PropertyGroup

_HERE = Path(__file__).resolve().parent
SCHEMA: dict = json.loads((_HERE / "scene_schema.json").read_text())
KEYS: dict = json.loads((_HERE / "scene_keys.json").read_text())

#: Keys taken from the Blender scene instead of the panel.
FROM_BLENDER = {("render", "width"), ("render", "height"), ("animation", "fps")}
#: Tables taken whole from the Blender scene.
TABLES_FROM_BLENDER = {"camera"}
#: Blender's IntProperty is 32-bit signed.
_INT_MAX = 2**31 - 1
#: Tables a scene may leave out whole (`[site]`, `[oval]`): the panel writes
#: one only when its `enabled` switch is on, then with every key shown. Their
#: required keys have no default, so the panel starts from the schema's
#: `default_in_table` (an example: the `tromso` preset's site); a key with
#: neither (`site.pressure_hpa`, standard when omitted; `oval.al_nt` and
#: `oval.mlt_h`, Kp's AL and the site's hour when omitted) is left to scene
#: files. The oval's activity is `oval.kp`.
OPTIONAL_TABLES = {"site", "oval"}


def panel_tables() -> list[str]:
    """Tables shown as sub-panels, in the schema's order (top level and
    curtains apart)."""
    return [t for t in SCHEMA if t not in ("", "curtain") and t not in TABLES_FROM_BLENDER]


def panel_keys(table: str) -> list[str]:
    keys = [k for k in SCHEMA[table] if (table, k) not in FROM_BLENDER]
    if table in OPTIONAL_TABLES:
        keys = [k for k in keys if _panel_default(table, k) is not None]
    return keys


def _panel_default(table: str, key: str):
    """A key's default in the panel: the schema's, or in an optional table
    its `default_in_table` example when it has none."""
    entry = SCHEMA[table][key]
    d = entry["default"]
    if d is None and table in OPTIONAL_TABLES:
        d = entry.get("default_in_table")
    return d


def _bound(x):
    if isinstance(x, str):
        return {"inf": math.inf, "-inf": -math.inf}[x]
    return float(x)


def _label(table: str, key: str) -> tuple[str, str]:
    """(name, description): the name carries the unit, `Top Km` -> `Top (km)`."""
    doc = KEYS.get(table, {}).get(key, {})
    unit = doc.get("unit", "")
    words = key
    for suffix in ("_km", "_deg", "_kev", "_kms", "_hz", "_s"):
        if words.endswith(suffix) and unit:
            words = words[: -len(suffix)]
            break
    name = words.replace("_", " ").capitalize() + (f" ({unit})" if unit else "")
    desc = doc.get("description", "").replace("`", "")
    entry = SCHEMA[table][key]
    if "rule" in entry:
        desc += f". Allowed: {entry['rule']}"
    elif "min" in entry:
        lo = "[" if entry.get("min_inclusive", True) else "("
        hi = "]" if entry.get("max_inclusive", True) else ")"
        desc += f". Range {lo}{entry['min']}, {entry['max']}{hi}"
    desc += f". Default {json.dumps(entry['default'])}"
    return name, desc


def _limits(entry: dict, integer: bool) -> dict:
    out = {}
    for k in ("min", "max"):
        if k in entry:
            v = _bound(entry[k])
            if math.isfinite(v):
                out[k] = int(max(-_INT_MAX, min(_INT_MAX, v))) if integer else v
    return out


def make_property(table: str, key: str):
    """The bpy property of one schema key (see the module doc)."""
    entry = SCHEMA[table][key]
    d = _panel_default(table, key)
    name, desc = _label(table, key)
    if table in OPTIONAL_TABLES and isinstance(d, str) and "values" not in entry:
        return StringProperty(name=name, description=desc, default=d)
    if isinstance(d, bool):
        return BoolProperty(name=name, description=desc, default=d)
    if isinstance(d, int):
        lim = _limits(entry, True)
        lim.setdefault("min", 0)  # seeds: unsigned in the scene file
        return IntProperty(name=name, description=desc, default=d, **lim)
    if isinstance(d, float):
        return FloatProperty(name=name, description=desc, default=d, precision=4, **_limits(entry, False))
    if isinstance(d, str) and "values" in entry:
        items = [(v, v, "") for v in entry["values"]]
        return EnumProperty(name=name, description=desc, items=items, default=d)
    if d is None or isinstance(d, str):
        return StringProperty(name=name, description=desc + " (empty: none)", default=d or "", subtype="FILE_PATH")
    if isinstance(d, list) and 2 <= len(d) <= 4 and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in d):
        if all(isinstance(x, int) for x in d):
            return IntVectorProperty(name=name, description=desc, default=d, size=len(d), **_limits(entry, True))
        return FloatVectorProperty(name=name, description=desc, default=[float(x) for x in d], size=len(d),
                                   **_limits(entry, False))
    return StringProperty(name=name, description=desc + " (JSON)", default=json.dumps(d))


def allows_auto(table: str, key: str) -> bool:
    return '"auto"' in SCHEMA[table][key].get("rule", "")


def _annotations(table: str, keys) -> dict:
    ann = {}
    for key in keys:
        ann[key] = make_property(table, key)
        if allows_auto(table, key):
            ann[f"{key}_auto"] = BoolProperty(name=f"{key.replace('_', ' ').capitalize()}: auto",
                                              description=f"{table}.{key} = \"auto\"", default=False)
    return ann


def _is_curve(_self, obj) -> bool:
    return obj.type == "CURVE"


def _curtain_annotations() -> dict:
    ann = _annotations("curtain", SCHEMA["curtain"])
    ann["path_object"] = PointerProperty(
        name="Path",
        type=bpy.types.Object,
        poll=_is_curve,
        description="A Curve object (Bezier, poly or NURBS): its world-space shape with z dropped, in km, becomes "
                    "the curtain's `path` (the ground track of its lower border) instead of center, length and rotation",
    )
    ann["path_points"] = StringProperty(
        name="Path points", default="",
        description="The curtain's `path` as JSON [[x, y], ...] in km, from a preset; used when no Path object is set",
    )
    return ann


def _group(name: str, annotations: dict):
    return type(name, (PropertyGroup,), {"__annotations__": annotations})


def _table_annotations(table: str) -> dict:
    ann = _annotations(table, panel_keys(table))
    if table in OPTIONAL_TABLES:
        ann["enabled"] = BoolProperty(name=f"Use [{table}]", default=False,
                                      description=f"Write the [{table}] table (off: the scene has none)")
    return ann


AuroraCurtain = _group("AuroraCurtain", _curtain_annotations())
TABLE_GROUPS = {t: _group(f"Aurora{t.capitalize()}Settings", _table_annotations(t)) for t in panel_tables()}


def _settings_annotations() -> dict:
    ann = _annotations("", SCHEMA[""])
    for t, cls in TABLE_GROUPS.items():
        ann[t] = PointerProperty(type=cls)
    ann["curtains"] = CollectionProperty(type=AuroraCurtain, name="Curtains")
    ann["active_curtain"] = IntProperty(name="Active curtain", default=0, min=0)
    # "//" is resolved by the bake (operators/bake.py: output_dir); Blender
    # 4.5+ is told so, or it warns on every "//" path. 4.2-4.4 know no such option.
    relative = {"PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (4, 5, 0) else set()
    relative.add("ANIMATABLE")  # the default options, kept
    ann["output_dir"] = StringProperty(
        name="Output folder", subtype="DIR_PATH", default="//aurora_bake", options=relative,
        description="Where the bake goes (aurora.vdb, or aurora.NNNN.vdb for frames); replaced whole when a bake "
                    "completes, untouched when it fails or is cancelled",
    )
    ann["preset"] = StringProperty(name="Preset", default="default", description="The last preset loaded")
    return ann


AuroraSettings = _group("AuroraSettings", _settings_annotations())

classes = (AuroraCurtain, *TABLE_GROUPS.values(), AuroraSettings)


# --- values <-> scene document ------------------------------------------------


def f32(x: float) -> float:
    return struct.unpack("f", struct.pack("f", x))[0]


def short_float(x: float) -> float:
    """The shortest decimal that reads back as the same float32: what the
    user typed (0.3, not 0.30000001192092896)."""
    want = f32(x)
    for digits in range(1, 10):
        y = float(f"{x:.{digits}g}")
        if f32(y) == want:
            return y
    return x


def _same(value, default) -> bool:
    """Equal at the precision Blender stores."""
    if isinstance(default, bool) or isinstance(value, bool):
        return value == default
    if isinstance(default, float) or isinstance(value, float):
        return f32(float(value)) == f32(float(default))
    if isinstance(default, list):
        return isinstance(value, list) and len(value) == len(default) and all(_same(a, b) for a, b in zip(value, default))
    return value == default


def _plain(v):
    if isinstance(v, float):
        return short_float(v)
    if isinstance(v, (list, tuple)) or hasattr(v, "__len__") and not isinstance(v, str):
        return [_plain(x) for x in v]
    return v


def read_key(group, table: str, key: str):
    """The scene-file value of one property, or None for "not written" (equal
    to its default, or an empty path)."""
    entry = SCHEMA[table][key]
    d = entry["default"]
    if allows_auto(table, key) and getattr(group, f"{key}_auto"):
        return "auto"
    v = getattr(group, key)
    if d is None or (isinstance(d, str) and "values" not in entry):
        return v or None
    if isinstance(d, list) and isinstance(v, str):
        try:
            v = json.loads(v)
        except ValueError as e:
            raise ValueError(f"{table}.{key}: not valid JSON: {v!r} ({e})") from e
    v = _plain(v) if not isinstance(v, (bool, int, str)) else v
    return None if _same(v, d) else v


def table_values(group, table: str, keys) -> dict:
    if table in OPTIONAL_TABLES:
        # Written whole when enabled (module doc), never otherwise.
        return {k: _plain(getattr(group, k)) for k in keys} if group.enabled else {}
    out = {}
    for key in keys:
        v = read_key(group, table, key)
        if v is not None:
            out[key] = v
    return out


def write_key(group, table: str, key: str, value) -> None:
    """Set one property from a scene-file value (a preset's)."""
    entry = SCHEMA[table][key]
    d = _panel_default(table, key)
    if allows_auto(table, key):
        setattr(group, f"{key}_auto", value == "auto")
        if value == "auto":
            return
    if value is None:
        value = "" if (d is None or isinstance(d, str)) else d
    prop = group.bl_rna.properties[key]
    if prop.type == "STRING" and not isinstance(value, str):
        value = json.dumps(value)
    setattr(group, key, value)


def reset(settings) -> None:
    """Every key back to its schema default, no curtains (= the default
    scene's three)."""
    for key in SCHEMA[""]:
        write_key(settings, "", key, SCHEMA[""][key]["default"])
    for t in TABLE_GROUPS:
        g = getattr(settings, t)
        for key in panel_keys(t):
            write_key(g, t, key, _panel_default(t, key))
        if t in OPTIONAL_TABLES:
            g.enabled = False
    settings.curtains.clear()


def add_curtain(settings):
    """A new curtain with the defaults of a `[[curtain]]` table that omits every key."""
    c = settings.curtains.add()
    for key in SCHEMA["curtain"]:
        write_key(c, "curtain", key, SCHEMA["curtain"][key]["default"])
    settings.active_curtain = len(settings.curtains) - 1
    return c


def load_document(settings, doc: dict) -> None:
    """Set `scene.aurora` from a parsed scene file (a preset): keys it omits
    take their defaults; its camera, resolution and fps are not applied (they
    belong to the Blender scene)."""
    reset(settings)
    for key, v in doc.items():
        if key in SCHEMA[""]:
            write_key(settings, "", key, v)
    for t in TABLE_GROUPS:
        g = getattr(settings, t)
        if t in OPTIONAL_TABLES:
            g.enabled = t in doc
        for key, v in doc.get(t, {}).items():
            if key in panel_keys(t):
                write_key(g, t, key, v)
    for ct in doc.get("curtain", []):
        c = add_curtain(settings)
        for key, v in ct.items():
            if key == "path":
                c.path_points = json.dumps(v)
            elif key == "magnetic_path":
                c.magnetic_path = json.dumps(v)
            elif key in SCHEMA["curtain"]:
                write_key(c, "curtain", key, v)

