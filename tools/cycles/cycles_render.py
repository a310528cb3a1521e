#!/usr/bin/env python3
"""Render an aurora scene with Blender Cycles (CPU), exactly as `aurora render` frames it.

    .venv/bin/python tools/cycles/cycles_render.py SCENE.toml --vdb FILE.vdb --out IMAGE.exr \
        [--samples N] [--terrain-obj terrain.obj] [--seed S] [--volume-mode biased|unbiased] [--step-rate R]

What it renders, and the output's channels (RGB = Combined + Environment,
A = 1 - T): the module documentation of aurora_tools/cycles.py, which this
script is the command line of.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.addon import load_addon  # noqa: E402, F401 - part of this module's interface
from aurora_tools.cycles import DEFAULT_SAMPLES, render  # noqa: E402
from aurora_tools.exr_io import read_exr_layers, write_rgba_exr  # noqa: E402, F401 - part of this module's interface


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help="scene TOML (units km, z up)")
    p.add_argument("--vdb", required=True, help="the bake (.vdb, or the .usda pointing at it)")
    p.add_argument("--out", required=True, help="output IMAGE.exr (linear RGBA float)")
    p.add_argument("--samples", type=int, default=DEFAULT_SAMPLES, help=f"Cycles samples per pixel (default {DEFAULT_SAMPLES})")
    p.add_argument("--terrain-obj", help="terrain OBJ from `aurora terrain` (heightfield terrain)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--volume-mode", choices=["biased", "unbiased"], default=None,
                   help="Cycles volume integrator (default: biased ray marching at a small step)")
    p.add_argument("--step-rate", type=float, default=None, help="biased mode step, in voxels (default 0.1)")
    p.add_argument("--terrain-lighting", choices=["lights", "paths"], default=None,
                   help="how the aurora lights the terrain: clustered point lights (default, low noise) "
                        "or diffuse bounces into the volume (brute force)")
    p.add_argument("--max-lights", type=int, default=None, help="at most this many point lights for the terrain (default 512)")
    p.add_argument("--threads", type=int, default=None, help="CPU threads (default: all)")
    p.add_argument("--no-pad", action="store_true",
                   help="render the VDB as it is (default: a copy with a shell of active zero voxels, "
                        "which makes Cycles' biased mode exact at the edges)")
    p.add_argument("-q", "--quiet", action="store_true")
    a = p.parse_args(argv)
    if a.samples < 1:
        p.error("--samples must be at least 1")
    for f in [a.scene, a.vdb] + ([a.terrain_obj] if a.terrain_obj else []):
        if not Path(f).is_file():
            print(f"cycles_render: error: {f}: no such file", file=sys.stderr)
            return 2
    biased = None if a.volume_mode is None else a.volume_mode == "biased"
    try:
        render(a.scene, a.vdb, a.out, a.samples, a.terrain_obj, a.seed, a.quiet, pad=not a.no_pad, volume_biased=biased,
               step_rate=a.step_rate, terrain_lighting=a.terrain_lighting, max_lights=a.max_lights, threads=a.threads)
    except Exception as e:  # noqa: BLE001 - one place maps errors to an exit status
        # Bad input (scene file, VDB, terrain OBJ, resolution): 2; anything else: 1.
        addon = sys.modules.get("aurora_importer")
        user_errors = (ValueError, FileNotFoundError)
        if addon is not None:
            from aurora_importer.terrain import TerrainError

            user_errors += (addon.SceneFileError, addon.AuroraImportError, TerrainError)
        print(f"cycles_render: error: {e}", file=sys.stderr)
        return 2 if isinstance(e, user_errors) else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
