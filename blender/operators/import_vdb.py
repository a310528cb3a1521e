"""`bpy.ops.aurora.import_vdb()`, File > Import > Aurora (.vdb / .usda): a thin
operator over import_aurora and setup_scene_from_toml."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, StringProperty
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
    units: EnumProperty(
        name="Units",
        items=(("KM", "Set Scene to km", "Make the scene's unit 1 Blender unit = 1 km (the volume's own) and import at scale 1"),
               ("SCENE", "Keep Scene Units", "Leave the scene's unit settings; scale the volume to them (a shot in metres: 1000 per km)"),
               ("CUSTOM", "Units per km", "Leave the scene's unit settings; scale the volume by Units per km")),
        default="KM")
    units_per_km: FloatProperty(name="Units per km", default=1000.0, min=1e-6, soft_max=1e6,
                                description="Blender units per km of the volume (Units: Units per km)")
    set_frame_range: BoolProperty(name="Set Frame Range and fps", default=True,
                                  description="A sequence sets the scene's frame range, fps and current frame to its own")
    film_transparent: BoolProperty(name="Transparent Film", default=False,
                                   description="Alpha = volume coverage; the background then goes to the Environment pass")

    def draw(self, context):
        col = self.layout.column()
        for key in ("density_scale", "emission_scale", "scattering_albedo"):
            col.prop(self, key)
        col.separator()
        col.prop(self, "units")
        sub = col.row()
        sub.enabled = self.units == "CUSTOM"
        sub.prop(self, "units_per_km")
        col.prop(self, "set_frame_range")
        col.separator()
        for key in ("scene_file", "terrain_obj", "film_transparent"):
            col.prop(self, key)
        if self.scene_file:
            col.label(text="A scene file sets up the whole shot in km, range and fps included")

    def execute(self, context):
        units = {"KM": "km", "SCENE": "scene", "CUSTOM": self.units_per_km}[self.units]
        try:
            if self.scene_file:
                if units != "km" or not self.set_frame_range:
                    raise ValueError("a scene file sets up the whole shot in km, with its frame range; "
                                     "import without the scene file to keep the shot's units or range")
                setup_scene_from_toml(
                    bpy.path.abspath(self.scene_file),
                    vdb=self.filepath,
                    terrain_obj=bpy.path.abspath(self.terrain_obj) if self.terrain_obj else None,
                    scene=context.scene,
                    settings=CyclesSettings(film_transparent=self.film_transparent),
                )
            else:
                import_aurora(self.filepath, self.density_scale, self.emission_scale,
                              scattering_albedo=tuple(self.scattering_albedo), scene=context.scene, units=units,
                              set_frame_range=self.set_frame_range)
        except (AuroraImportError, ValueError, RuntimeError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


classes = (AURORA_OT_import_vdb,)
