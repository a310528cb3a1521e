"""The scene file's terrain: a plane or the heightfield mesh `aurora terrain` writes.

- "plane": `aurora render` intersects the plane z = height. Blender gets a
  square of half-size PLANE_HALF_SIZE_KM centred under the camera; its edge is
  atan(h / 1e4 km) below the horizon (1.5e-4 rad for a camera 1.5 km up,
  a tenth of a pixel at 50 degrees over 360 rows).
- "heightfield": the OBJ written by `aurora terrain SCENE --out terrain.obj`
  (km, z up) is imported with forward +Y, up +Z so no axis is swapped, and
  shaded flat: `aurora render` shades each triangle with its geometric normal.
Both get the Lambertian terrain material (material.terrain_material).
"""

from __future__ import annotations

from pathlib import Path

import bpy

from .material import terrain_material

PLANE_HALF_SIZE_KM = 1.0e4


class TerrainError(RuntimeError):
    """The terrain cannot be built (missing or unreadable OBJ)."""


def plane_terrain(scene, height: float, albedo, center_xy=(0.0, 0.0), volume_alpha: bool = True,
                  name: str = "AuroraTerrain") -> bpy.types.Object:
    cx, cy = center_xy
    r = PLANE_HALF_SIZE_KM
    verts = [(cx - r, cy - r, height), (cx + r, cy - r, height), (cx + r, cy + r, height), (cx - r, cy + r, height)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], [(0, 1, 2, 3)])
    mesh.validate()
    mesh.materials.append(terrain_material(name + "Material", albedo, volume_alpha))
    for p in mesh.polygons:
        p.use_smooth = False
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def heightfield_terrain(scene, obj_path, albedo, volume_alpha: bool = True,
                        name: str = "AuroraTerrain") -> bpy.types.Object:
    path = Path(obj_path)
    if not path.is_file():
        raise TerrainError(f"{path}: terrain OBJ not found (write it with `aurora terrain SCENE --out {path.name}`)")
    before = set(bpy.data.objects)
    # The importer links into the active collection of the context's view layer.
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
        result = bpy.ops.wm.obj_import(filepath=str(path), forward_axis="Y", up_axis="Z", global_scale=1.0,
                                       use_split_objects=False, use_split_groups=False, validate_meshes=True)
    new = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    if "FINISHED" not in result or len(new) != 1:
        raise TerrainError(f"{path}: expected one mesh from the OBJ, got {len(new)}")
    obj = new[0]
    obj.name = name
    obj.matrix_world.identity()
    mesh = obj.data
    if hasattr(mesh, "has_custom_normals") and mesh.has_custom_normals:
        with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj],
                                       selected_editable_objects=[obj]):
            bpy.ops.mesh.customdata_custom_splitnormals_clear()
    for p in mesh.polygons:
        p.use_smooth = False
    mesh.materials.clear()
    mesh.materials.append(terrain_material(name + "Material", albedo, volume_alpha))
    for p in mesh.polygons:
        p.material_index = 0
    return obj
