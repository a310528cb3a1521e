"""The scene file's terrain: a plane or the heightfield mesh `aurora terrain` writes.

- "plane" on flat ground (`earth.radius_km = 0`): `aurora render` intersects
  the plane z = height. Blender gets a square of half-size PLANE_HALF_SIZE_KM
  centred under the camera; its edge is atan(h / 1e4 km) below the horizon
  (1.5e-4 rad for a camera 1.5 km up, a tenth of a pixel at 50 degrees over
  360 rows).
- "plane" on a round Earth: `aurora render` intersects the sphere of radius
  R' = R + height about (0, 0, -R). Blender gets a cap of that sphere about
  the camera's nadir (`sphere_cap`), out to twice the central angle of the
  camera's horizon, so every camera ray that meets the sphere meets the cap
  and nothing beyond the horizon shows through. Its vertices lie on the
  sphere; its rings and the facets round them are spaced so that each chord
  sags below the sphere by at most delta = 1e-3 of the camera's altitude a
  (a chord of central angle d theta sags R' d theta^2 / 8), a facet's middle
  by at most 2 delta. That lowers the horizon as a camera 2 delta higher
  would: its dip, about sqrt(2 a / R'), grows by at most the factor
  1 + delta / a, 1e-3 of it (0.0012 degrees for a camera 1.5 km up). With
  delta proportional to a the cap has about 32 rings of 200 facets at any
  altitude.
- "heightfield": the OBJ written by `aurora terrain SCENE --out terrain.obj`
  (km, z up) is imported with forward +Y, up +Z so no axis is swapped, and
  shaded smooth: Blender's vertex normals (face normals weighted by corner
  angle) interpolated over each triangle, which `aurora render` computes
  the same way (src/render/terrain.rs).
Both get the Lambertian terrain material (material.terrain_material).
"""

from __future__ import annotations

import math
from pathlib import Path

import bpy

from .material import terrain_material
from .scene_toml import _cross, _normalize

PLANE_HALF_SIZE_KM = 1.0e4
#: The cap's largest sagitta as a share of the camera's altitude.
CAP_SAG_PER_ALTITUDE = 1.0e-3
#: The camera altitude the cap assumes for a camera on or below the ground, km.
CAP_MIN_ALTITUDE_KM = 1.0e-3
#: Most facets of a cap (for a camera so high that its horizon is far round
#: the sphere): beyond it the sagitta grows instead.
CAP_MAX_FACETS = 1_000_000


class TerrainError(RuntimeError):
    """The terrain cannot be built (missing or unreadable OBJ)."""


def sphere_cap(radius: float, centre, camera):
    """The vertices and faces of the cap of the sphere (`radius` km about
    `centre`) that the camera at `camera` can see, with margin: about the
    camera's nadir out to twice the central angle of its horizon,
    acos(R' / (R' + a)) (at most pi), in rings of equal central angle; the
    sagitta bound of the module doc sets the spacing of the rings and of the
    facets round them. Coordinates in km, computed in double precision."""
    c = [float(v) for v in centre]
    d = [float(camera[i]) - c[i] for i in range(3)]
    dist = math.sqrt(sum(v * v for v in d))
    n = _normalize(d) if dist > 0.0 else [0.0, 0.0, 1.0]
    a = max(dist - radius, CAP_MIN_ALTITUDE_KM)
    theta_max = min(2.0 * math.acos(radius / (radius + a)), math.pi)
    sag = CAP_SAG_PER_ALTITUDE * a
    step = math.sqrt(8.0 * sag / radius)  # a chord of central angle `step` sags `sag`
    rings = max(8, math.ceil(theta_max / step))
    around = max(64, math.ceil(2.0 * math.pi * math.sin(min(theta_max, math.pi / 2)) / step))
    if rings * around > CAP_MAX_FACETS:
        k = math.sqrt(CAP_MAX_FACETS / (rings * around))
        rings, around = max(8, int(rings * k)), max(64, int(around * k))
    # An orthonormal pair across the nadir.
    e1 = _normalize(_cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]))
    e2 = _cross(n, e1)

    def point(theta, phi):
        ct, st = math.cos(theta), math.sin(theta)
        cp, sp = math.cos(phi), math.sin(phi)
        return tuple(c[i] + radius * (ct * n[i] + st * (cp * e1[i] + sp * e2[i])) for i in range(3))

    verts = [point(0.0, 0.0)]
    for k in range(1, rings + 1):
        theta = theta_max * k / rings
        verts += [point(theta, 2.0 * math.pi * j / around) for j in range(around)]
    ring = lambda k, j: 1 + (k - 1) * around + j % around  # noqa: E731 (vertex j of ring k >= 1)
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(around)]
    for k in range(1, rings):
        faces += [(ring(k, j), ring(k + 1, j), ring(k + 1, j + 1), ring(k, j + 1)) for j in range(around)]
    return verts, faces


def plane_terrain(scene, height: float, albedo, camera=(0.0, 0.0, 0.0), earth_radius_km: float = 0.0,
                  volume_alpha: bool = True, name: str = "AuroraTerrain") -> bpy.types.Object:
    """The plane at `height` (module doc): on flat ground a square under the
    camera, on a round Earth the visible cap of the sphere of radius
    `earth_radius_km + height` about (0, 0, -earth_radius_km)."""
    if earth_radius_km > 0.0:
        verts, faces = sphere_cap(earth_radius_km + height, (0.0, 0.0, -earth_radius_km), camera)
    else:
        cx, cy = camera[0], camera[1]
        r = PLANE_HALF_SIZE_KM
        verts = [(cx - r, cy - r, height), (cx + r, cy - r, height), (cx + r, cy + r, height), (cx - r, cy + r, height)]
        faces = [(0, 1, 2, 3)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.validate()
    mesh.materials.append(terrain_material(name + "Material", albedo, volume_alpha))
    # The sphere is smooth: vertex normals are its radial directions (the
    # normal `aurora render` shades with); the square is one flat face.
    smooth = earth_radius_km > 0.0
    for p in mesh.polygons:
        p.use_smooth = smooth
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
    # Smooth shading: Blender's angle-weighted vertex normals, interpolated
    # (the normals `aurora render` computes; the OBJ says `s off`).
    for p in mesh.polygons:
        p.use_smooth = True
    mesh.materials.clear()
    mesh.materials.append(terrain_material(name + "Material", albedo, volume_alpha))
    for p in mesh.polygons:
        p.material_index = 0
    return obj
