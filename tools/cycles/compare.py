#!/usr/bin/env python3
"""Compare two linear RGBA EXR renders: error figures and a picture.

    .venv/bin/python tools/cycles/compare.py A.exr B.exr --out DIFF.png [--json out.json]
        [--mask MASK.exr|MASK.png | --terrain-mask SCENE.toml] [--threshold 0.01] [--range R]

The figures and the picture are described in aurora_tools/image_compare.py,
which does the work; this is its command line. `import compare` (with
tools/cycles/ on sys.path) gives every function (read_rgba, metrics,
compare, terrain_mask, read_png, ...).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.files import write_atomic  # noqa: E402, F401 - part of this module's interface
from aurora_tools.exr_io import read_rgba  # noqa: E402
from aurora_tools.image_compare import (  # noqa: E402, F401 - part of this module's interface
    compare, diverging, make_picture, metrics, nice_range, read_mask, relative_difference, terrain_mask,
)
from aurora_tools.png import read_png, write_png  # noqa: E402, F401 - part of this module's interface


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("a", help="first image (EXR, linear RGBA)")
    p.add_argument("b", help="second image (EXR, linear RGBA), same size")
    p.add_argument("--out", required=True, help="comparison picture (PNG)")
    p.add_argument("--json", help="write the figures as JSON")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mask", help="mask image (EXR or PNG, nonzero = inside)")
    g.add_argument("--terrain-mask", metavar="SCENE.toml", help="mask of pixels wholly on the scene's plane terrain")
    p.add_argument("--threshold", type=float, default=0.01, help="bright pixels: above this fraction of the peak")
    p.add_argument("--range", type=float, dest="rel_range", help="colour bar range (0.05 = +-5%%)")
    a = p.parse_args(argv)
    try:
        mask = None
        if a.mask:
            mask = read_mask(a.mask)
        elif a.terrain_mask:
            h, w = read_rgba(a.a).shape[:2]
            mask = terrain_mask(a.terrain_mask, w, h)
        m = compare(a.a, a.b, a.out, a.json, mask, a.threshold, a.rel_range)
    except (OSError, ValueError, RuntimeError) as e:
        print(f"compare: error: {e}", file=sys.stderr)
        return 2
    keys = ["mean_rel_err", "flux_ratio", "max_alpha_diff", "bright_pixels", "mask_mean_rel_err", "mask_flux_ratio"]
    print(" ".join(f"{k}={m[k]:.6g}" for k in keys if k in m))
    return 0


if __name__ == "__main__":
    sys.exit(main())
