"""Aurora for Blender: bake from the Aurora panel, import with File > Import.

The Aurora panel (3D viewport sidebar) edits `scene.aurora`, every scene key
(properties.py), and `bpy.ops.aurora.bake()` bakes it for the active camera
with the `aurora` binary and loads the result (bake_ops.py); in background
mode it runs synchronously, so scripts use it.

Imports an `aurora bake` as a Volume object whose material reproduces
`aurora render`'s emission-absorption model, and optionally builds the scene
file's camera, background and terrain with the Cycles settings accuracy
needs, so that a Cycles render and `aurora render` show the same picture.

Scripts use the functions, the operator is a thin wrapper:

    from <this package> import import_aurora, setup_scene_from_toml
    import_aurora("aurora-out/aurora.vdb", density_scale=1.0, emission_scale=1.0)
    setup_scene_from_toml("scene.toml", vdb="aurora-out/aurora.vdb")

Installs as a Blender 4.2+ extension (blender_manifest.toml) or as a legacy
add-on (bl_info, for add-on paths); relative imports only, so the package
works under any name (`bl_ext.<repo>.aurora_importer`, or `blender` when the
repository root is on sys.path, as tools/cycles/cycles_render.py does).
"""

bl_info = {
    "name": "Aurora Importer",
    "author": "aurora project",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "View3D > Sidebar > Aurora; File > Import > Aurora (.vdb / .usda)",
    "description": "Bake aurora from a panel, import aurora volumes with the reference radiance model",
    "category": "Import-Export",
}

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


def _modules():
    from . import bake_ops, operators, panel, properties

    return [properties, operators, bake_ops, panel]


def register():
    for m in _modules():
        m.register()


def unregister():
    for m in reversed(_modules()):
        m.unregister()
