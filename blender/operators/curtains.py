"""Adding and removing the curtains of `scene.aurora` (the panel's list)."""

from __future__ import annotations

import bpy

from .. import properties as P


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


classes = (AURORA_OT_curtain_add, AURORA_OT_curtain_remove)
