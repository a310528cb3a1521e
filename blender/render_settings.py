"""Cycles settings that make a render comparable with `aurora render`.

Each one is a measured fact (docs/guide.md, "How Cycles reads the VDB") or
from this add-on's tests:
- film: Standard view transform, no look, exposure 0, gamma 1 (the EXR is
  linear anyway), then the scene file's `render.view_transform` with its
  look when a scene file sets the scene up (`set_view`: what the viewport
  and a PNG show); film_transparent so alpha = 1 - T (the background then goes
  to the Environment pass, which is switched on: add it back to RGB);
- pixel filter: BOX averages over the pixel square (spp > 1); GAUSSIAN of
  width 0.01 point-samples pixel centres (spp = 1), as `aurora render` does;
- no denoising, no adaptive sampling, no clamping (the defaults clamp
  indirect light at 10 and stop early in dark pixels);
- light paths: no volume scattering bounce (emission-absorption only), no
  glossy/transmission, many transparent bounces; the terrain is lit directly
  by the aurora and nothing else: with terrain_lighting "lights" by point
  lights made from the emission (emission_lights.py; next-event estimation,
  no bounce needed), with "paths" by one diffuse bounce that meets the
  volume (brute force, ~100x noisier on curtains);
- volume: `volume_biased` picks jittered ray marching (step = voxel size *
  step_rate) over the default unbiased null scattering; max steps at the
  ceiling so long rays through the aurora are never cut short.
"""

from __future__ import annotations

from dataclasses import dataclass

import bpy

#: Defaults chosen from the noise and bias measurements in tests/python/
#: bench_cycles_noise.py (see the add-on README): jittered ray marching at a
#: step of a tenth of a voxel resolves one-voxel curtains (the default step
#: rate 1 underestimates their optical depth) and is ~10x less noisy per
#: sample than null scattering.
DEFAULT_VOLUME_BIASED = True
DEFAULT_STEP_RATE = 0.1
MAX_STEPS = 65536  # Cycles' hard maximum


@dataclass(frozen=True)
class CyclesSettings:
    samples: int = 64
    volume_biased: bool = DEFAULT_VOLUME_BIASED
    step_rate: float = DEFAULT_STEP_RATE
    seed: int = 0
    #: True: point-sample pixel centres (what `aurora render` does at spp = 1).
    point_sample: bool = False
    film_transparent: bool = True
    #: Volume scattering bounces (0: emission-absorption only).
    volume_bounces: int = 0
    #: How the aurora lights the terrain: "lights" (clustered point lights,
    #: low noise) or "paths" (a diffuse bounce into the volume, brute force).
    terrain_lighting: str = "lights"
    #: At most this many point lights in "lights" mode.
    max_lights: int = 512
    threads: int = 0  # 0 = all cores


#: Blender's smallest render resolution: a smaller one is silently raised to
#: 4 pixels, which would change the pixel size (measured).
MIN_RESOLUTION = 4


def configure_cycles(scene: bpy.types.Scene, width: int, height: int, s: CyclesSettings = CyclesSettings()) -> None:
    if min(width, height) < MIN_RESOLUTION:
        raise ValueError(f"Blender renders at least {MIN_RESOLUTION}x{MIN_RESOLUTION} pixels, got {width}x{height}")
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = int(width)
    r.resolution_y = int(height)
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.film_transparent = s.film_transparent
    r.use_compositing = False
    r.use_sequencer = False
    r.use_motion_blur = False
    if s.threads > 0:
        r.threads_mode = "FIXED"
        r.threads = s.threads
    else:
        r.threads_mode = "AUTO"

    v = scene.view_settings
    v.view_transform = "Standard"
    v.look = "None"
    v.exposure = 0.0
    v.gamma = 1.0
    v.use_curve_mapping = False

    c = scene.cycles
    c.device = "CPU"
    c.samples = int(s.samples)
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.seed = int(s.seed)
    c.use_animated_seed = False
    c.sample_offset = 0
    c.time_limit = 0.0
    if s.point_sample:
        c.pixel_filter_type = "GAUSSIAN"
        c.filter_width = 0.01
    else:
        c.pixel_filter_type = "BOX"
        c.filter_width = 1.0
    c.volume_biased = bool(s.volume_biased)
    c.volume_step_rate = float(s.step_rate)
    c.volume_max_steps = MAX_STEPS
    c.volume_bounces = int(s.volume_bounces)
    if s.terrain_lighting not in ("lights", "paths"):
        raise ValueError(f"terrain_lighting must be \"lights\" or \"paths\", got {s.terrain_lighting!r}")
    diffuse = 1 if s.terrain_lighting == "paths" else 0
    c.diffuse_bounces = diffuse
    c.glossy_bounces = 0
    c.transmission_bounces = 0
    c.transparent_max_bounces = 1024
    c.max_bounces = diffuse + int(s.volume_bounces)
    c.caustics_reflective = False
    c.caustics_refractive = False
    c.blur_glossy = 0.0

    for layer in scene.view_layers:
        layer.use_pass_combined = True
        # With a transparent film the background radiance (times T) lands
        # here instead of in Combined; cycles_render adds it back.
        layer.use_pass_environment = True


def blender_view(view_transform: str) -> tuple[str, str]:
    """Blender's view transform and look for a `render.view_transform` word:
    "standard" is Standard, "agx" AgX with no look, "agx_<look>" AgX with
    Blender 5.0's look "AgX - <Look>" (agx_punchy: "AgX - Punchy",
    agx_very_high_contrast: "AgX - Very High Contrast")."""
    if view_transform == "standard":
        return "Standard", "None"
    if view_transform == "agx":
        return "AgX", "None"
    if view_transform.startswith("agx_"):
        return "AgX", "AgX - " + view_transform[4:].replace("_", " ").title()
    raise ValueError(f"render.view_transform = {view_transform!r} is not a view aurora knows")


def set_view(scene: bpy.types.Scene, view_transform: str) -> None:
    """The scene's colour management shows what `aurora render`'s PNG shows:
    the view transform and look of `render.view_transform` (the EXR stays
    linear whatever they are)."""
    v = scene.view_settings
    v.view_transform, v.look = blender_view(view_transform)


def set_scene_units(scene: bpy.types.Scene) -> None:
    """1 Blender unit = 1 km (display only; Cycles is unit-free)."""
    u = scene.unit_settings
    u.system = "METRIC"
    u.scale_length = 1000.0
    u.length_unit = "KILOMETERS"
