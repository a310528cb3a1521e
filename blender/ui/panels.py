"""The Aurora panel (3D viewport sidebar, tab "Aurora"), its preset menu,
the curtain list and the add-on preferences (the `aurora` binary).

The panel draws `scene.aurora` (properties.py): the output folder, the
preset menu, the bake buttons, the curtains (a list to add to and remove
from; the active one's keys and its optional Path curve below it), then one
closed sub-panel per scene table. Presets are the binary's own:
`aurora scene --list` names them, `aurora scene NAME` prints one, which is
read into `scene.aurora` (its camera, resolution and frame rate are the
shot's, not the preset's, and are left alone).
"""

from __future__ import annotations

import subprocess
import tomllib

import bpy
from bpy.props import StringProperty

from . import properties as P
from .bake_job import BakeError, find_binary

#: Presets when the binary predates `aurora scene --list`.
FALLBACK_PRESETS = ("default", "seed2014")


def _binary(context) -> str:
    addon = context.preferences.addons.get(__package__)
    return find_binary(getattr(addon.preferences, "binary", "") if addon else None)


def list_presets(binary: str) -> list[str]:
    """`aurora scene --list`: one preset per line, its name first; the
    fallback names when the binary cannot be run or predates `--list`."""
    try:
        out = subprocess.run([binary, "scene", "--list"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return list(FALLBACK_PRESETS)
    if out.returncode != 0:
        return list(FALLBACK_PRESETS)
    names = [line.split()[0] for line in out.stdout.splitlines() if line.strip()]
    return names or list(FALLBACK_PRESETS)


def preset_document(binary: str, name: str) -> dict:
    out = subprocess.run([binary, "scene", name], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise BakeError(f"aurora scene {name}: {out.stderr.strip() or f'exit status {out.returncode}'}")
    return tomllib.loads(out.stdout)


_preset_cache: dict[str, list[str]] = {}


class AURORA_OT_load_preset(bpy.types.Operator):
    """Set the Aurora panel from one of the binary's built-in scenes"""

    bl_idname = "aurora.load_preset"
    bl_label = "Load Aurora Preset"
    bl_options = {"REGISTER", "UNDO"}

    name: StringProperty(name="Preset", default="default")

    def execute(self, context):
        try:
            doc = preset_document(_binary(context), self.name)
        except (BakeError, OSError, subprocess.SubprocessError, tomllib.TOMLDecodeError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        P.load_document(context.scene.aurora, doc)
        context.scene.aurora.preset = self.name
        return {"FINISHED"}


class AURORA_MT_presets(bpy.types.Menu):
    bl_idname = "AURORA_MT_presets"
    bl_label = "Presets"

    def draw(self, context):
        try:
            binary = _binary(context)
        except BakeError as e:
            self.layout.label(text=str(e), icon="ERROR")
            return
        if binary not in _preset_cache:
            _preset_cache[binary] = list_presets(binary)
        for name in _preset_cache[binary]:
            self.layout.operator(AURORA_OT_load_preset.bl_idname, text=name).name = name


class AURORA_OT_curtain_add(bpy.types.Operator):
    """Add a curtain with the defaults of an empty [[curtain]] table"""

    bl_idname = "aurora.curtain_add"
    bl_label = "Add Curtain"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        P.add_curtain(context.scene.aurora)
        return {"FINISHED"}


class AURORA_OT_curtain_remove(bpy.types.Operator):
    """Remove the active curtain (no curtains: the default scene's three)"""

    bl_idname = "aurora.curtain_remove"
    bl_label = "Remove Curtain"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return len(context.scene.aurora.curtains) > 0

    def execute(self, context):
        s = context.scene.aurora
        s.curtains.remove(s.active_curtain)
        s.active_curtain = max(0, min(s.active_curtain, len(s.curtains) - 1))
        return {"FINISHED"}


class AURORA_UL_curtains(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0):
        where = item.path_object.name if item.path_object else ("path" if item.path_points else "straight")
        layout.label(text=f"Curtain {index + 1} ({where}, {item.energy_flux:g} mW/m^2, {item.char_energy_kev:g} keV)")


class AuroraPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    binary: StringProperty(name="aurora binary", subtype="FILE_PATH", default="",
                           description="Path of the `aurora` executable (empty: $AURORA_BIN, else aurora on PATH)")

    def draw(self, context):
        self.layout.prop(self, "binary")


class VIEW3D_PT_aurora(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Aurora"
    bl_label = "Aurora"
    bl_idname = "VIEW3D_PT_aurora"

    def draw(self, context):
        s = context.scene.aurora
        col = self.layout.column()
        col.menu(AURORA_MT_presets.bl_idname, text=f"Preset: {s.preset}")
        col.prop(s, "output_dir")
        for key in P.SCHEMA[""]:
            col.prop(s, key)
        row = col.row(align=True)
        row.operator("aurora.bake", text="Bake", icon="RENDER_STILL").frames = False
        row.operator("aurora.bake", text="Bake Frames", icon="RENDER_ANIMATION").frames = True
        if context.scene.camera is None:
            col.label(text="No active camera: the default scene camera is used", icon="INFO")
        col.separator()
        col.label(text="Curtains (none: the default scene's three)")
        row = col.row()
        row.template_list("AURORA_UL_curtains", "", s, "curtains", s, "active_curtain", rows=3)
        sub = row.column(align=True)
        sub.operator(AURORA_OT_curtain_add.bl_idname, icon="ADD", text="")
        sub.operator(AURORA_OT_curtain_remove.bl_idname, icon="REMOVE", text="")
        if 0 <= s.active_curtain < len(s.curtains):
            c = s.curtains[s.active_curtain]
            box = col.box()
            box.prop(c, "path_object")
            straight = c.path_object is None and not c.path_points
            for key in P.SCHEMA["curtain"]:
                r = box.row()
                r.enabled = straight or key not in ("center", "length", "rotation_deg")
                r.prop(c, key)


def _table_panel(table: str):
    def draw(self, context):
        g = getattr(context.scene.aurora, table)
        col = self.layout.column()
        for key in P.panel_keys(table):
            if P.allows_auto(table, key):
                row = col.row(align=True)
                row.prop(g, f"{key}_auto", text="auto")
                sub = row.row()
                sub.enabled = not getattr(g, f"{key}_auto")
                sub.prop(g, key)
            else:
                col.prop(g, key)
        if table == "animation":
            col.label(text="fps: the scene's frame rate")
        if table == "render":
            col.label(text="width, height: the scene's resolution")

    return type(f"VIEW3D_PT_aurora_{table}", (bpy.types.Panel,), {
        "bl_space_type": "VIEW_3D", "bl_region_type": "UI", "bl_category": "Aurora",
        "bl_label": f"[{table}]", "bl_parent_id": "VIEW3D_PT_aurora", "bl_options": {"DEFAULT_CLOSED"},
        "bl_idname": f"VIEW3D_PT_aurora_{table}", "draw": draw,
    })


CLASSES = [AURORA_OT_load_preset, AURORA_MT_presets, AURORA_OT_curtain_add, AURORA_OT_curtain_remove,
           AURORA_UL_curtains, AuroraPreferences, VIEW3D_PT_aurora, *(_table_panel(t) for t in P.panel_tables())]


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
