"""A Curve object as a curtain's `path`: [[x, y], ...] in km.

The curve is evaluated as Blender draws it (the evaluated object's mesh:
Bezier and NURBS splines tessellated at their `resolution_u`, poly splines
as their points, modifiers applied), in world space (the object's matrix),
z dropped: the path is the ground track of the curtain's lower border, so
only its map position counts. One Blender unit is one km in this add-on
(render_settings.set_scene_units). The points follow the spline from its
first control point to its last; a cyclic spline is closed by repeating its
first point. The binary draws its own smooth curve through the points, so
the tessellation only has to be fine enough to keep the shape: Blender's
default of 12 segments per Bezier span is.
"""

from __future__ import annotations

import bpy


class CurvePathError(ValueError):
    """The object cannot serve as a curtain path."""


def curve_path(obj: bpy.types.Object, depsgraph=None) -> list[list[float]]:
    """World-space (x, y) of the evaluated curve, consecutive duplicates
    (zero-length segments) removed."""
    if obj is None or obj.type != "CURVE":
        raise CurvePathError(f"{getattr(obj, 'name', obj)!r} is not a Curve object")
    splines = obj.data.splines
    if len(splines) != 1:
        raise CurvePathError(f"curve {obj.name!r} has {len(splines)} splines: a curtain path is one spline")
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        m = ev.matrix_world
        pts = []
        for v in mesh.vertices:
            w = m @ v.co
            p = [float(w.x), float(w.y)]
            if not pts or pts[-1] != p:
                pts.append(p)
        cyclic = splines[0].use_cyclic_u
    finally:
        ev.to_mesh_clear()
    if cyclic and pts and pts[0] != pts[-1]:
        pts.append(list(pts[0]))
    if len(pts) < 2:
        raise CurvePathError(f"curve {obj.name!r} has fewer than 2 distinct points in plan view")
    return pts
