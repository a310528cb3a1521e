"""The Aurora panel (3D viewport sidebar, tab "Aurora") and its curtain list.

The panel draws `scene.aurora` (properties.py): the preset menu
(menus.py), the output folder, the top-level keys, the bake buttons, the
curtains (a list to add to and remove from; the active one's keys and its
optional Path curve below it), then one closed sub-panel per scene table.
"""

from __future__ import annotations

import bpy

from .. import properties as P
from ..operators.bake import AURORA_OT_bake
from ..operators.curtains import AURORA_OT_curtain_add, AURORA_OT_curtain_remove
from ..scene_write import STRAIGHT_KEYS
from .menus import AURORA_MT_presets


class AURORA_UL_curtains(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0):
        where = item.path_object.name if item.path_object else ("path" if item.path_points else "straight")
        layout.label(text=f"Curtain {index + 1} ({where}, {item.energy_flux:g} mW/m^2, {item.char_energy_kev:g} keV)")


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
        row.operator(AURORA_OT_bake.bl_idname, text="Bake", icon="RENDER_STILL").frames = False
        row.operator(AURORA_OT_bake.bl_idname, text="Bake Frames", icon="RENDER_ANIMATION").frames = True
        if context.scene.camera is None:
            col.label(text="No active camera: the default scene camera is used", icon="INFO")
        col.separator()
        col.label(text="Curtains (none: the default scene's three)")
        row = col.row()
        row.template_list(AURORA_UL_curtains.__name__, "", s, "curtains", s, "active_curtain", rows=3)
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
                r.enabled = straight or key not in STRAIGHT_KEYS
                r.prop(c, key)


def _table_panel(table: str):
    def draw(self, context):
        g = getattr(context.scene.aurora, table)
        col = self.layout.column()
        if table in P.OPTIONAL_TABLES:
            col.prop(g, "enabled")
            col = col.column()
            col.enabled = g.enabled
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
        if table == "grid":
            # grid.prune drops the leaves faintest as seen from the active
            # camera: another camera can lose faint aurora.
            col.label(text="prune follows the active camera:")
            col.label(text="for several cameras bake with prune = 0")
            col.label(text="or once per camera")

    return type(f"VIEW3D_PT_aurora_{table}", (bpy.types.Panel,), {
        "bl_space_type": "VIEW_3D", "bl_region_type": "UI", "bl_category": "Aurora",
        "bl_label": f"[{table}]", "bl_parent_id": VIEW3D_PT_aurora.bl_idname, "bl_options": {"DEFAULT_CLOSED"},
        "bl_idname": f"VIEW3D_PT_aurora_{table}", "draw": draw,
    })


classes = (AURORA_UL_curtains, VIEW3D_PT_aurora, *(_table_panel(t) for t in P.panel_tables()))
