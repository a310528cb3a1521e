"""The scene file's camera as a Blender camera.

`aurora render`: forward = normalize(look_at - position),
right = normalize(forward x up), up' = right x forward; perspective with a
*vertical* field of view, orthographic with `ortho_height` the vertical
extent; the image centre is on the optical axis. A Blender camera looks down
its local -Z with +Y up, so its world matrix has columns (right, up',
-forward, position); sensor fit VERTICAL makes `angle_y` and `ortho_scale`
vertical quantities whatever the aspect ratio.

Panoramas (`projection = "fisheye"` / `"equirectangular"`) are Cycles'
panoramic camera (type PANO), FISHEYE_EQUIDISTANT with `fisheye_fov = fov`
or EQUIRECTANGULAR over the full sphere; Cycles turns its panoramic camera
space so that the image centre looks down the object's -Z, the same matrix
serves. The equidistant fisheye ignores the sensor: its image circle spans
the frame (an ellipse when the image is not square), as `aurora render`'s
does (src/geometry/camera.rs).
"""

from __future__ import annotations

import math

import bpy
from mathutils import Matrix

from .scene_toml import Camera, camera_basis

#: Near clip, km (1 cm): rays start at the camera as in `aurora render`.
CLIP_START_KM = 1e-5
#: Far clip, km: beyond any aurora (the terrain plane ends at 1e4 km).
CLIP_END_KM = 1e6


def camera_matrix(cam: Camera) -> Matrix:
    right, up, forward = camera_basis(cam)
    back = [-f for f in forward]
    p = cam.position
    return Matrix(
        (
            (right[0], up[0], back[0], p[0]),
            (right[1], up[1], back[1], p[1]),
            (right[2], up[2], back[2], p[2]),
            (0.0, 0.0, 0.0, 1.0),
        )
    )


def build_camera(scene: bpy.types.Scene, cam: Camera, name: str = "AuroraCamera") -> bpy.types.Object:
    """Create the camera object, link it to the scene and make it active."""
    data = bpy.data.cameras.new(name)
    data.sensor_fit = "VERTICAL"
    data.shift_x = data.shift_y = 0.0
    data.clip_start = CLIP_START_KM
    data.clip_end = CLIP_END_KM
    if cam.projection == "perspective":
        data.type = "PERSP"
        data.angle_y = math.radians(cam.fov_deg)
    elif cam.projection == "fisheye":
        data.type = "PANO"
        data.panorama_type = "FISHEYE_EQUIDISTANT"
        data.fisheye_fov = math.radians(cam.fov_deg)
    elif cam.projection == "equirectangular":
        data.type = "PANO"
        data.panorama_type = "EQUIRECTANGULAR"
        data.latitude_min, data.latitude_max = -math.pi / 2.0, math.pi / 2.0
        data.longitude_min, data.longitude_max = -math.pi, math.pi
    else:
        data.type = "ORTHO"
        data.ortho_scale = cam.ortho_height
    obj = bpy.data.objects.new(name, data)
    scene.collection.objects.link(obj)
    obj.matrix_world = camera_matrix(cam)
    scene.camera = obj
    return obj
