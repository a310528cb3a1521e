"""The menus: the panel's preset menu and the File > Import entry."""

from __future__ import annotations

import bpy

from ..bake_job import BakeError
from ..operators.import_vdb import AURORA_OT_import_vdb
from ..operators.presets import AURORA_OT_load_preset, cached_presets
from ..preferences import aurora_binary


class AURORA_MT_presets(bpy.types.Menu):
    """The binary's built-in scenes (`aurora scene --list`)"""

    bl_idname = "AURORA_MT_presets"
    bl_label = "Presets"

    def draw(self, context):
        try:
            binary = aurora_binary(context)
        except BakeError as e:
            self.layout.label(text=str(e), icon="ERROR")
            return
        for name in cached_presets(binary):
            self.layout.operator(AURORA_OT_load_preset.bl_idname, text=name).name = name


def file_import_entry(self, context):
    """File > Import > Aurora (.vdb / .usda)."""
    self.layout.operator(AURORA_OT_import_vdb.bl_idname, text="Aurora (.vdb / .usda)")


classes = (AURORA_MT_presets,)
