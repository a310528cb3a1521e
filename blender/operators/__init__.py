"""The add-on's operators: import, bake, presets and curtains (`bpy.ops.aurora.*`)."""

from . import bake, curtains, import_vdb, presets

classes = (*import_vdb.classes, *bake.classes, *presets.classes, *curtains.classes)
