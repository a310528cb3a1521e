"""Shaders that reproduce `aurora render`'s radiance model in Cycles.

Volume (emission-absorption, no scattering unless asked):

    dL/ds = -sigma_t L + Le,   sigma_t = density_scale * density(x),
                               Le      = emission_scale * emission(x)

so along a ray L = integral Le(s) T(s) ds + T L_behind with
T(s) = exp(-integral_0^s sigma_t). Built from one Principled Volume
(measured: docs/guide.md, "How Cycles reads the VDB"):
- Density input = density_scale multiplies the `density` grid (Density
  Attribute), so sigma_t = density_scale * density;
- Color = 0 turns scattering off; Absorption Color = 0 makes all of sigma_t
  absorption (Cycles: sigma_a = sigma_t * (1 - Color) * (1 - Absorption Color));
- Emission Color from an Attribute node (`emission`, Color output: a vec3 grid
  keeps its channels, a float grid reads as grey), Emission Strength =
  emission_scale; Principled emission is per unit length and is *not*
  multiplied by density;
- Blackbody Intensity = 0, or Cycles adds blackbody light.
With `scattering_albedo` a > 0, Color = a: sigma_s = a sigma_t,
sigma_a = (1 - a) sigma_t; sigma_t is unchanged.
With `air` (`[sky] extinction`, air.py), the emission is multiplied by the
air's transmittance towards the camera ray's direction,
T_c = sum_i w_ic exp(-tau_i X(e)), sin e = -Incoming.z (the Geometry node's
Incoming points back along the ray), as `aurora render` applies it.

High column (`grid.high_voxel_factor` > 1, the default): the bake stores
the faint column above `grid.high_above_km` in grids of their own at a
coarser voxel size, `density_high` and `emission_high`, which the field is
the sum of: density = density + density_high, emission = emission +
emission_high, each grid trilinear on its own transform (Cycles keeps a
transform per grid).

Terrain: Lambertian diffuse with the albedo (roughness 0 is Lambert in
Cycles), plus an almost-1 holdout so that the film alpha of camera rays
that end on the terrain is the volume coverage 1 - T (see `terrain_material`).
"""

from __future__ import annotations

import bpy

#: Weight of the holdout closure on the terrain: 1 - HOLDOUT_EPS. A holdout of
#: weight exactly 1 makes Cycles terminate the path (no terrain radiance);
#: below 1 the path goes on and the film's transparency gains
#: (1 - HOLDOUT_EPS) * T. The alpha error this leaves is HOLDOUT_EPS * T.
HOLDOUT_EPS = 1e-6


def _clear(tree):
    for n in list(tree.nodes):
        tree.nodes.remove(n)


def volume_material(
    name: str,
    density_scale: float,
    emission_scale: float,
    has_density: bool = True,
    has_emission: bool = True,
    scattering_albedo=0.0,
    anisotropy: float = 0.0,
    air=None,
    has_high: bool = False,
) -> bpy.types.Material:
    """A material for a Volume object holding `density` and/or `emission`.

    `has_high`: the file also holds the high column (`density_high`,
    `emission_high`: the same fields above `grid.high_above_km`, at a coarser
    voxel size, see the module doc), added to `density` and `emission`.

    A missing `density` grid gives Density 0 (Principled would otherwise fill
    the padded bounds with its constant Density); a missing `emission` grid
    gives Emission Strength 0. `air`: None, or (tau, weights, up) with tau the
    zenith depth above the camera of each line, weights[c][i] channel c's
    share of line i (air.py) and up the camera's local vertical, dimming the
    emission as seen by camera rays.
    """
    if density_scale < 0 or emission_scale < 0:
        raise ValueError("density_scale and emission_scale must be >= 0")
    albedo = _rgb(scattering_albedo)
    if any(not 0.0 <= a <= 1.0 for a in albedo):
        raise ValueError(f"scattering_albedo must be in [0, 1], got {scattering_albedo!r}")
    mat = bpy.data.materials.new(name)
    tree = mat.node_tree  # materials always have a node tree in Blender 5
    _clear(tree)
    pv = tree.nodes.new("ShaderNodeVolumePrincipled")
    pv.location = (0, 0)
    pv.inputs["Color"].default_value = (*albedo, 1.0)
    pv.inputs["Absorption Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    pv.inputs["Anisotropy"].default_value = anisotropy
    pv.inputs["Blackbody Intensity"].default_value = 0.0
    pv.inputs["Density"].default_value = density_scale if has_density else 0.0
    pv.inputs["Density Attribute"].default_value = "density" if has_density else ""
    if has_density and has_high:
        # Principled multiplies Density by one attribute; a sum of two grids is
        # linked into Density instead (an empty attribute name is not found,
        # and Cycles then leaves Density as it is).
        pv.inputs["Density Attribute"].default_value = ""
        total = _math(tree, "ADD", _attribute(tree, "density", "Fac"), _attribute(tree, "density_high", "Fac"))
        tree.links.new(_math(tree, "MULTIPLY", total, density_scale), pv.inputs["Density"])
    pv.inputs["Temperature Attribute"].default_value = ""
    pv.inputs["Emission Strength"].default_value = emission_scale if has_emission else 0.0
    pv.inputs["Emission Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    if has_emission:
        colour = _attribute(tree, "emission", "Color")
        if has_high:
            add = tree.nodes.new("ShaderNodeVectorMath")
            add.operation = "ADD"
            tree.links.new(colour, add.inputs[0])
            tree.links.new(_attribute(tree, "emission_high", "Color"), add.inputs[1])
            colour = add.outputs["Vector"]
        if air is not None:
            colour = _air_transmittance(tree, colour, *air)
        tree.links.new(colour, pv.inputs["Emission Color"])
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    out.target = "ALL"
    tree.links.new(pv.outputs["Volume"], out.inputs["Volume"])
    mat.cycles.volume_interpolation = "LINEAR"  # trilinear, as `aurora render`
    mat.cycles.volume_step_rate = 1.0  # the scene's step rate alone decides
    mat["aurora_density_scale"] = float(density_scale)
    mat["aurora_emission_scale"] = float(emission_scale)
    return mat


def _attribute(tree, name, output):
    """The geometry attribute `name` (a grid of the Volume object), its
    `output` socket ("Fac" for a float grid, "Color" for a vec3 grid)."""
    attr = tree.nodes.new("ShaderNodeAttribute")
    attr.location = (-250, -200)
    attr.attribute_type = "GEOMETRY"
    attr.attribute_name = name
    return attr.outputs[output]


def _math(tree, op, a, b=None, clamp=False):
    n = tree.nodes.new("ShaderNodeMath")
    n.operation = op
    n.use_clamp = clamp
    for k, v in enumerate((a, b)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            n.inputs[k].default_value = float(v)
        else:
            tree.links.new(v, n.inputs[k])
    return n.outputs["Value"]


def _air_transmittance(tree, colour, tau, weights, up=(0.0, 0.0, 1.0)):
    """`colour` times T_c of the ray's direction (see the module doc); `up`
    is the camera's local vertical."""
    geo = tree.nodes.new("ShaderNodeNewGeometry")
    dot = tree.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    tree.links.new(geo.outputs["Incoming"], dot.inputs[0])
    dot.inputs[1].default_value = tuple(float(u) for u in up)
    # sin e = -Incoming . up, clamped to [0, 1]: below the horizon, the horizon.
    sin_e = _math(tree, "MULTIPLY", dot.outputs["Value"], -1.0, clamp=True)
    e_deg = _math(tree, "DEGREES", _math(tree, "ARCSINE", sin_e))
    term = _math(tree, "MULTIPLY", _math(tree, "POWER", _math(tree, "ADD", e_deg, 6.07995), -1.6364), 0.50572)
    x = _math(tree, "DIVIDE", 1.0, _math(tree, "ADD", term, sin_e))
    acc = None
    for i, t in enumerate(tau):
        ti = _math(tree, "EXPONENT", _math(tree, "MULTIPLY", x, -float(t)))
        v = tree.nodes.new("ShaderNodeVectorMath")
        v.operation = "SCALE"
        v.inputs["Vector"].default_value = tuple(float(weights[c][i]) for c in range(3))
        tree.links.new(ti, v.inputs["Scale"])
        if acc is None:
            acc = v.outputs["Vector"]
        else:
            add = tree.nodes.new("ShaderNodeVectorMath")
            add.operation = "ADD"
            tree.links.new(acc, add.inputs[0])
            tree.links.new(v.outputs["Vector"], add.inputs[1])
            acc = add.outputs["Vector"]
    mul = tree.nodes.new("ShaderNodeVectorMath")
    mul.operation = "MULTIPLY"
    tree.links.new(colour, mul.inputs[0])
    tree.links.new(acc, mul.inputs[1])
    return mul.outputs["Vector"]


def terrain_material(name: str, albedo, volume_alpha: bool = True) -> bpy.types.Material:
    """Lambertian terrain. With `volume_alpha`, a holdout of weight
    1 - HOLDOUT_EPS is added for camera rays (Cycles only applies holdouts
    to camera-visible paths), so film alpha = 1 - T_volume in front of the
    terrain instead of 1; the diffuse closure still shades the terrain."""
    rgb = _rgb(albedo)
    mat = bpy.data.materials.new(name)
    tree = mat.node_tree
    _clear(tree)
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*rgb, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    out.location = (500, 0)
    out.target = "ALL"
    shader = diffuse.outputs["BSDF"]
    if volume_alpha:
        holdout = tree.nodes.new("ShaderNodeHoldout")
        nothing = tree.nodes.new("ShaderNodeEmission")
        nothing.inputs["Strength"].default_value = 0.0
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = HOLDOUT_EPS  # (1 - eps) holdout + eps nothing
        tree.links.new(holdout.outputs["Holdout"], mix.inputs[1])
        tree.links.new(nothing.outputs["Emission"], mix.inputs[2])
        add = tree.nodes.new("ShaderNodeAddShader")
        tree.links.new(mix.outputs["Shader"], add.inputs[0])
        tree.links.new(diffuse.outputs["BSDF"], add.inputs[1])
        shader = add.outputs["Shader"]
    tree.links.new(shader, out.inputs["Surface"])
    return mat


def _rgb(x):
    if isinstance(x, (int, float)):
        return (float(x),) * 3
    t = tuple(float(v) for v in x)
    if len(t) != 3:
        raise ValueError(f"expected a number or 3 numbers, got {x!r}")
    return t
