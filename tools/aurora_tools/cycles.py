"""Render an aurora scene with Blender Cycles (CPU), exactly as `aurora
render` frames it (tools/cycles/cycles_render.py is the command line).

Everything goes through the add-on in ../blender (setup_scene_from_toml):
same camera, resolution, pixel footprint (spp = 1: pixel centres, else the
pixel square), background, terrain and emission-absorption model.

Output: linear Rec.709 OpenEXR, RGBA 32-bit float, row 0 at the top:
- A = Cycles' film alpha with a transparent film: 1 - T, T the volume
  transmittance along the primary ray (up to the terrain, whose holdout of
  weight 1 - 1e-6 makes its pixels transparent too; see blender/material.py);
- RGB = Combined + Environment. With a transparent film Cycles does not add
  the background radiance to Combined; it writes throughput * L_bg of the
  escaping camera paths, the same paths that make alpha, into the
  Environment pass. Their sum is exactly what an opaque film would give:
  volume emission + T * L_bg (+ terrain radiance where the terrain is hit).

Needs bpy 5.0.1, numpy, OpenEXR and the standard library only. The image is
written to a temporary name in the output folder and renamed.
"""

from __future__ import annotations

import contextlib
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .addon import load_addon
from .exr_io import read_exr_layers, write_rgba_exr

#: Cycles samples per pixel by default: see DEFAULTS in the add-on README
#: (noise vs samples measured by tests/python/bench_cycles_noise.py).
DEFAULT_SAMPLES = 128



def render(scene_toml, vdb, out, samples: int = DEFAULT_SAMPLES, terrain_obj=None, seed: int = 0,
           quiet: bool = False, pad: bool = True, adaptive_threshold: float | None = None,
           shutter_s: float | None = None, **overrides) -> dict:
    """Render and write `out`; returns timings and settings (for reports):
    setup_s (scene set-up, padding included), render_s and render_cpu_s (wall
    and process CPU time of bpy.ops.render.render: Cycles' sync, the VDB load,
    sampling and the EXR write).
    `overrides` are CyclesSettings fields (volume_biased, step_rate,
    terrain_lighting, max_lights, threads); None leaves the default.
    pad: render a copy of the VDB with a shell of active zero voxels
    (blender/vdb_pad.py), so the biased volume mode is exact at the edges.
    adaptive_threshold: None keeps the add-on's setting (adaptive sampling
    off); a number turns Cycles' adaptive sampling on with that noise
    threshold (Blender's default is 0.01) and automatic minimum samples;
    `samples` is then the maximum per pixel.
    shutter_s: None takes the scene's `render.shutter_s`; 0 keeps motion blur
    off; seconds of shutter centred on the frame turn it on (Cycles advects the volume along its velocity
    grid, set by the add-on when the VDB holds `v`)."""
    import bpy

    addon = load_addon()
    kw = {k: v for k, v in overrides.items() if v is not None}
    settings = addon.CyclesSettings(samples=samples, seed=seed, **kw)
    with tempfile.TemporaryDirectory(prefix="cycles_render.") as tmp:
        t0 = time.perf_counter()
        bpy.ops.wm.read_factory_settings(use_empty=True)
        # The linear passes are compared: the picture's development
        # (white balance in the compositor, exposure) stays off.
        built = addon.setup_scene_from_toml(scene_toml, vdb=vdb, terrain_obj=terrain_obj, settings=settings,
                                            pad_dir=tmp if pad else None, develop=False)
        scene = bpy.context.scene
        if shutter_s is None:
            shutter_s = built.spec.render.shutter_s
        if shutter_s:
            scene.render.use_motion_blur = True
            scene.render.motion_blur_position = "CENTER"
            scene.render.motion_blur_shutter = shutter_s * scene.render.fps / scene.render.fps_base
        if adaptive_threshold is not None:
            scene.cycles.use_adaptive_sampling = True
            scene.cycles.adaptive_threshold = adaptive_threshold
            scene.cycles.adaptive_min_samples = 0
        t_setup = time.perf_counter() - t0
        raw = Path(tmp) / "passes.exr"
        scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
        scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
        scene.render.image_settings.color_depth = "32"
        scene.render.image_settings.exr_codec = "ZIP"
        scene.render.filepath = str(raw)
        t1 = time.perf_counter()
        cpu1 = _cpu_seconds()
        with _stdout_to_devnull(quiet):
            bpy.ops.render.render(write_still=True)
        t_render = time.perf_counter() - t1
        cpu_render = _cpu_seconds() - cpu1
        layers = read_exr_layers(raw)
    combined = _find(layers, "Combined")
    env = _find(layers, "Environment")
    rgba = combined.copy()
    rgba[..., :3] += env[..., :3]
    s = built.settings
    meta = {
        "aurora_renderer": "Blender Cycles " + bpy.app.version_string,
        "aurora_samples": s.samples,
        "aurora_volume_mode": "biased" if s.volume_biased else "unbiased",
        "aurora_step_rate": s.step_rate,
        "aurora_seed": s.seed,
        "aurora_pixel_filter": "point (pixel centres)" if s.point_sample else "box (pixel square)",
        "aurora_alpha": "1 - T_volume along the primary ray",
        "aurora_terrain_lighting": s.terrain_lighting if built.terrain is not None else "no terrain",
        "aurora_emission_lights": len(built.lights),
        "aurora_vdb_padded": "yes" if pad else "no",
        "aurora_motion_blur_s": shutter_s or 0.0,
        "aurora_adaptive_sampling": (f"on, threshold {adaptive_threshold}" if scene.cycles.use_adaptive_sampling
                                     else "off"),
    }
    write_rgba_exr(out, rgba, meta)
    info = {"setup_s": t_setup, "render_s": t_render, "render_cpu_s": cpu_render, "width": rgba.shape[1],
            "height": rgba.shape[0], **meta}
    if not quiet:
        print(f"cycles_render: wrote {out} ({rgba.shape[1]}x{rgba.shape[0]}, {s.samples} spp, "
              f"{meta['aurora_volume_mode']} step rate {s.step_rate}) render {t_render:.2f} s", file=sys.stderr)
    return info


@contextlib.contextmanager
def _stdout_to_devnull(on: bool):
    """With `on`, file descriptor 1 points at /dev/null for the block:
    Blender's C code prints its "Saved: ..." and "Time: ..." lines there,
    past sys.stdout."""
    if not on:
        yield
        return
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def _cpu_seconds() -> float:
    """User + system CPU time of this process, all threads (Cycles' included)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _find(layers: dict, suffix: str) -> np.ndarray:
    for k, v in layers.items():
        if k.split(".")[-1] == suffix or k.endswith("." + suffix):
            return v
    raise RuntimeError(f"pass {suffix} missing from Cycles output (have {sorted(layers)})")
