"""`bpy.ops.aurora.import_vdb()`, File > Import > Aurora (.vdb / .usda): a thin
operator over import_aurora and setup_scene_from_toml."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, FloatProperty, FloatVectorProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from ..render_settings import CyclesSettings
from ..scene_setup import setup_scene_from_toml
from ..volume_import import AuroraImportError, import_aurora


class AURORA_OT_import_vdb(bpy.types.Operator, ImportHelper):
    """Import an aurora bake as a Volume with the reference emission-absorption material"""

    bl_idname = "aurora.import_vdb"
    bl_label = "Import Aurora"
    bl_options = {"REGISTER", "UNDO", "PRESET"}

    filter_glob: StringProperty(default="*.vdb;*.usda;*.usd;*.usdc;*.usdz", options={"HIDDEN"})
    density_scale: FloatProperty(name="Density Scale", default=1.0, min=0.0, description="extinction = density scale * density grid (per km)")
    emission_scale: FloatProperty(name="Emission Scale", default=1.0, min=0.0, description="radiance per km = emission scale * emission grid")
    scattering_albedo: FloatVectorProperty(name="Scattering Albedo", subtype="COLOR", size=3, default=(0.0, 0.0, 0.0), min=0.0, max=1.0,
                                           description="0: no scattering (the reference model)")
    scene_file: StringProperty(name="Scene TOML", default="", subtype="FILE_PATH",
                               description="Optional aurora scene file: camera, background, terrain, scales and render settings from it")
    terrain_obj: StringProperty(name="Terrain OBJ", default="", subtype="FILE_PATH",
                                description="OBJ from `aurora terrain` (heightfield terrain only)")
    film_transparent: BoolProperty(name="Transparent Film", default=False,
                                   description="Alpha = volume coverage; the background then goes to the Environment pass")

    def execute(self, context):
        try:
            if self.scene_file:
                setup_scene_from_toml(
                    bpy.path.abspath(self.scene_file),
                    vdb=self.filepath,
                    terrain_obj=bpy.path.abspath(self.terrain_obj) if self.terrain_obj else None,
                    scene=context.scene,
                    settings=CyclesSettings(film_transparent=self.film_transparent),
                )
            else:
                import_aurora(self.filepath, self.density_scale, self.emission_scale,
                              scattering_albedo=tuple(self.scattering_albedo), scene=context.scene)
        except (AuroraImportError, ValueError, RuntimeError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


classes = (AURORA_OT_import_vdb,)
