"""The active Blender camera as the scene file's `[camera]` table.

The inverse of camera.py (which builds a Blender camera from the table).
A Blender camera looks down its local -Z with +Y up, so from its world
matrix: position = translation, look_at = position + (-Z column), up = +Y
column. `aurora render` takes a *vertical* field of view (perspective) or a
vertical extent (`ortho_height`), the image centre on the optical axis.

Blender's sensor fit decides which image side the sensor (perspective) or
`ortho_scale` (orthographic) spans: HORIZONTAL the width, VERTICAL the
height, AUTO the longer side (always measured with `sensor_width`). With
aspect a = width / height of the render (pixel aspect included), a sensor
spanning the width gives a vertical half-angle
tan(fov_v / 2) = tan(fov_h / 2) / a and an `ortho_scale` spanning the width
a vertical extent ortho_scale / a. Lens shift has no counterpart in
`aurora render` and is refused, as are panoramas other than the equidistant
fisheye and the full-sphere equirectangular (src/geometry/camera.rs).
"""

from __future__ import annotations

import math

import bpy


class CameraExportError(ValueError):
    """A camera `aurora render` cannot reproduce."""


def render_size(scene: bpy.types.Scene) -> tuple[int, int]:
    """The render's size in pixels (resolution percentage applied)."""
    r = scene.render
    s = r.resolution_percentage / 100.0
    return max(1, round(r.resolution_x * s)), max(1, round(r.resolution_y * s))


def _spans_width(cam: bpy.types.Camera, aspect: float) -> bool:
    fit = cam.sensor_fit
    return fit == "HORIZONTAL" or (fit == "AUTO" and aspect >= 1.0)


def camera_table(obj: bpy.types.Object, scene: bpy.types.Scene, depsgraph=None) -> dict:
    """`[camera]` of the scene file for camera object `obj` rendered at the
    scene's resolution (its evaluated transform: constraints, parents and
    animation at the current frame applied)."""
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    cam = obj.data
    ev = obj.evaluated_get(depsgraph)
    w, h = render_size(scene)
    aspect = (w * scene.render.pixel_aspect_x) / (h * scene.render.pixel_aspect_y)
    m = ev.matrix_world.normalized()
    pos = m.translation
    fwd = -m.col[2].xyz
    up = m.col[1].xyz
    t = {
        "position": [float(x) for x in pos],
        "look_at": [float(a + b) for a, b in zip(pos, fwd)],
        "up": [float(x) for x in up],
    }
    if cam.type != "PANO" and (cam.shift_x != 0.0 or cam.shift_y != 0.0):
        raise CameraExportError(f"camera {obj.name!r}: lens shift ({cam.shift_x}, {cam.shift_y}) is not supported: set it to 0")
    wide = _spans_width(cam, aspect)
    if cam.type == "PERSP":
        sensor = cam.sensor_width if cam.sensor_fit in ("AUTO", "HORIZONTAL") else cam.sensor_height
        half = math.atan(sensor / (2.0 * cam.lens))  # half-angle across the side the sensor spans
        tan_v = math.tan(half) / aspect if wide else math.tan(half)
        t["projection"] = "perspective"
        t["fov_deg"] = math.degrees(2.0 * math.atan(tan_v))
    elif cam.type == "ORTHO":
        t["projection"] = "orthographic"
        t["ortho_height"] = cam.ortho_scale / aspect if wide else cam.ortho_scale
    elif cam.type == "PANO" and cam.panorama_type == "FISHEYE_EQUIDISTANT":
        t["projection"] = "fisheye"
        t["fov_deg"] = math.degrees(cam.fisheye_fov)
    elif cam.type == "PANO" and cam.panorama_type == "EQUIRECTANGULAR":
        full = (cam.latitude_min, cam.latitude_max, cam.longitude_min, cam.longitude_max)
        want = (-math.pi / 2, math.pi / 2, -math.pi, math.pi)
        if any(abs(a - b) > 1e-6 for a, b in zip(full, want)):
            raise CameraExportError(f"camera {obj.name!r}: an equirectangular camera must cover the full sphere")
        t["projection"] = "equirectangular"
    else:
        raise CameraExportError(f"camera {obj.name!r}: panorama type {cam.panorama_type} is not supported "
                                "(perspective, orthographic, equidistant fisheye or equirectangular)")
    return t
