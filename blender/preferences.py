"""The add-on's preferences (Edit > Preferences > Add-ons > Aurora): the path
of the `aurora` binary.

The preferences are stored under the add-on's package name
(`aurora_importer`, or `bl_ext.<repo>.aurora_importer` as an extension), so
`bl_idname` is `__package__`. `addon_preferences` is the one lookup of them,
and `aurora_binary` the one way the operators and menus find the binary.
"""

from __future__ import annotations

import bpy
from bpy.props import StringProperty

from .bake_job import find_binary


class AuroraPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    binary: StringProperty(name="aurora binary", subtype="FILE_PATH", default="",
                           description="Path of the `aurora` executable (empty: the one the extension brought, else $AURORA_BIN, else aurora on PATH)")

    def draw(self, context):
        self.layout.prop(self, "binary")


def addon_preferences(context=None) -> AuroraPreferences | None:
    """This add-on's preferences, or None while it is not enabled (a script
    that imports the package without enabling it)."""
    context = context or bpy.context
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon is not None else None


def aurora_binary(context=None) -> str:
    """The `aurora` executable: the preference if set, else the one the
    extension zip brought, else $AURORA_BIN, else `aurora` on PATH
    (bake_job.find_binary; raises BakeError without one)."""
    prefs = addon_preferences(context)
    return find_binary(prefs.binary if prefs is not None and prefs.binary else None)


classes = (AuroraPreferences,)
