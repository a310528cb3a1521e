"""Aurora for Blender: bake from the Aurora panel, import with File > Import.

The Aurora panel (3D viewport sidebar, ui/) edits `scene.aurora`, every
scene key (properties.py), and `bpy.ops.aurora.bake()` bakes it for the
active camera with the `aurora` binary and loads the result
(operators/bake.py); in background mode it runs synchronously, so scripts
use it. `bpy.ops.aurora.import_vdb()` (File > Import > Aurora) imports a
bake (operators/import_vdb.py); the binary's path is an add-on preference
(preferences.py).

Imports an `aurora bake` as a Volume object whose material reproduces
`aurora render`'s emission-absorption model, and optionally builds the scene
file's camera, background and terrain with the Cycles settings accuracy
needs, so that a Cycles render and `aurora render` show the same picture.

Scripts use the functions, the operators are thin wrappers:

    from aurora_importer import import_aurora, setup_scene_from_toml
    import_aurora("aurora-out/aurora.vdb", density_scale=1.0, emission_scale=1.0)
    setup_scene_from_toml("scene.toml", vdb="aurora-out/aurora.vdb")

Installs as a Blender 4.2+ extension (blender_manifest.toml) or as a legacy
add-on (bl_info, for add-on paths); relative imports only, so the package
works under any name (`bl_ext.<repo>.aurora_importer` as an extension,
`aurora_importer` when a script imports the folder as a package).

Registration: every module with Blender classes lists them in `classes`;
`register` registers them all in one loop (properties, preferences,
operators, ui, in that order), then adds `scene.aurora` and the File >
Import entry.
"""

bl_info = {
    "name": "Aurora",
    "author": "aurora project",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "View3D > Sidebar > Aurora; File > Import > Aurora (.vdb / .usda)",
    "description": "Bake aurora from a panel, import aurora volumes with the reference radiance model",
    "category": "Import-Export",
}

import bpy  # noqa: E402
from bpy.props import PointerProperty  # noqa: E402

from . import display, operators, preferences, properties, ui  # noqa: E402
from .material import terrain_material, volume_material  # noqa: E402
from .render_settings import CyclesSettings, configure_cycles, set_scene_units  # noqa: E402
from .scene_setup import AuroraScene, setup_scene_from_toml  # noqa: E402
from .scene_toml import SceneFileError, SceneSpec, load_scene  # noqa: E402
from .volume_import import AuroraImportError, import_aurora  # noqa: E402

__all__ = [
    "AuroraImportError", "AuroraScene", "CyclesSettings", "SceneFileError", "SceneSpec",
    "configure_cycles", "import_aurora", "load_scene", "set_scene_units", "setup_scene_from_toml",
    "terrain_material", "volume_material", "register", "unregister",
]

#: Every class the add-on registers, in registration order.
classes = (*properties.classes, *preferences.classes, *operators.classes, *ui.classes)

_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.Scene.aurora = PointerProperty(type=properties.AuroraSettings)
    bpy.types.TOPBAR_MT_file_import.append(ui.menus.file_import_entry)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(ui.menus.file_import_entry)
    del bpy.types.Scene.aurora
    _unregister_classes()
