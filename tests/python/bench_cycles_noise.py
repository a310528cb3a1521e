"""Benchmark (not a test): Cycles' error vs samples in both volume modes.

    .venv/bin/python tests/python/bench_cycles_noise.py [--out DIR] [--quick]

Renders a synthetic one-voxel-thick curtain (synth.curtain_arrays) through
tools/cycles/cycles_render.py with pixel-centre sampling (scene spp = 1) and
compares with the brute-force oracle (synth.march) at the same pixel
centres. For each volume mode, step rate and sample count it prints one CSV
row: mean relative error over pixels brighter than 1% of the peak (compare.py's
definition), total flux ratio, max alpha error, render seconds. A second
render with another seed gives the seed-to-seed noise, so bias
(mean error that does not fall with samples) and noise can be told apart.
A terrain view measures the noise of terrain lit by the curtain (seed to
seed), with the terrain lit by clustered point lights (default) and by
brute-force diffuse bounces; last, render times at 160x90 for a synthetic
stand-in of the default bake. The machine's load average is printed first:
times on a shared machine are upper bounds.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "tools" / "cycles"))

import synth  # noqa: E402

VIEWS = {
    # Broadside: the curtain seen across, paths cross the sheet (about a voxel).
    "broadside": {"position": [0.0, -90.0, 40.0], "look_at": [0.0, 0.0, 118.0], "up": [0, 0, 1],
                  "projection": "perspective", "fov_deg": 50.0},
    # Grazing: looking along the sheet, long paths inside it (optical depth ~1).
    "grazing": {"position": [-75.0, -12.0, 95.0], "look_at": [0.0, 0.0, 118.0], "up": [0, 0, 1],
                "projection": "perspective", "fov_deg": 40.0},
}


def oracle(spec_cam, width, height, origin, density, emission, voxel):
    sys.path.insert(0, str(ROOT))
    from blender.scene_toml import Camera, pixel_ray

    cam = Camera(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in spec_cam.items()})
    o, d = [], []
    for r in range(height):
        for c in range(width):
            oo, dd = pixel_ray(cam, width, height, c + 0.5, r + 0.5)
            o.append(oo)
            d.append(dd)
    L, T = synth.march(np.array(o), np.array(d), voxel, origin, density, emission, (0, 0, 0), n_steps=3000)
    return L.reshape(height, width, 3), (1 - T).reshape(height, width)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="/tmp/aurora-bench-noise")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--width", type=int, default=96)
    ap.add_argument("--height", type=int, default=54)
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    import compare
    import cycles_render

    voxel = 0.5
    origin, density, emission = synth.curtain_arrays(voxel)
    vdb = synth.write_vdb(out / "curtain.vdb", voxel, origin, density, emission)
    w, h = a.width, a.height
    rows = []
    runs = [("unbiased", None, [16, 64, 256, 1024]), ("biased", 1.0, [16, 64, 256]),
            ("biased", 0.25, [16, 64, 256]), ("biased", 0.1, [4, 16, 64, 256]), ("biased", 0.05, [16, 64])]
    if a.quick:
        runs = [("unbiased", None, [64]), ("biased", 1.0, [64]), ("biased", 0.1, [64])]
    import os

    print(f"# load average {os.getloadavg()}, {os.cpu_count()} CPUs", file=sys.stderr)
    writer = csv.writer(sys.stdout)
    writer.writerow(["view", "mode", "step_rate", "spp", "mean_rel_err", "seed_noise_rel", "flux_ratio",
                     "max_alpha_err", "render_s"])
    for view, cam in VIEWS.items():
        t = time.perf_counter()
        ref, ref_alpha = oracle(cam, w, h, origin, density, emission, voxel)
        print(f"# oracle {view}: {time.perf_counter() - t:.1f} s, peak {ref.max():.4g}, "
              f"max alpha {ref_alpha.max():.4f}", file=sys.stderr)
        scene = synth.write_scene(out / f"{view}.toml", cam, w, h, spp=1)
        for mode, rate, spps in runs:
            for spp in spps:
                imgs = []
                for seed in (0, 1):
                    exr = out / f"{view}-{mode}-{rate}-{spp}-{seed}.exr"
                    info = cycles_render.render(scene, vdb, exr, spp, seed=seed, volume_biased=(mode == "biased"),
                                                step_rate=rate or 1.0, quiet=True)
                    imgs.append(compare.read_rgba(exr))
                m = compare.metrics(imgs[0], np.dstack([ref, ref_alpha]))
                noise = compare.metrics(imgs[0], imgs[1])["mean_rel_err"] / np.sqrt(2)
                row = [view, mode, rate or "", spp, f"{m['mean_rel_err']:.5f}", f"{noise:.5f}",
                       f"{m['flux_ratio']:.5f}", f"{m['max_alpha_diff']:.5f}", f"{info['render_s']:.2f}"]
                writer.writerow(row)
                sys.stdout.flush()
                rows.append(row)
    # Terrain lit by the curtain: seed-to-seed noise on the pixels wholly on the terrain.
    cam = {"position": [0.0, -150.0, 1.5], "look_at": [0.0, 0.0, 40.0], "up": [0, 0, 1],
           "projection": "perspective", "fov_deg": 50.0}
    scene = synth.write_scene(out / "terrain.toml", cam, w, h, spp=16,
                              terrain={"kind": "plane", "height": 0.0, "albedo": [0.3, 0.3, 0.3]})
    mask = compare.terrain_mask(scene, w, h)
    terrain_runs = [("lights", [16, 64, 256]), ("paths", [64, 256])] if not a.quick else [("lights", [64])]
    for lighting, spps in terrain_runs:
        for spp in spps:
            imgs = []
            for seed in (0, 1):
                exr = out / f"terrain-{lighting}-{spp}-{seed}.exr"
                info = cycles_render.render(scene, vdb, exr, spp, seed=seed, quiet=True, terrain_lighting=lighting)
                imgs.append(compare.read_rgba(exr))
            m = compare.metrics(imgs[0], imgs[1], mask)
            noise = m["mask_mean_rel_err"] / np.sqrt(2)
            writer.writerow([f"terrain-{lighting}", "biased", 0.1, spp, "", f"{noise:.5f}", "", "",
                             f"{info['render_s']:.2f}"])
            sys.stdout.flush()
    if not a.quick:
        default_like_timing(out, writer)


def default_like_timing(out: Path, writer):
    """Render times at 160x90 for a synthetic stand-in of the default bake
    (three bent one-voxel sheets at the default scene's places, 0.5 km voxels,
    ~2M active voxels) with the cross-check's settings."""
    import pyopenvdb as vdb
    import cycles_render

    h = 0.5
    dg, eg = vdb.FloatGrid(), vdb.Vec3SGrid()
    dg.name, eg.name = "density", "emission"
    m = [[h, 0, 0, 0], [0, h, 0, 0], [0, 0, h, 0], [0, 0, 0, 1]]
    dg.transform = vdb.createLinearTransform(m)
    eg.transform = vdb.createLinearTransform(m)
    for cx, cy, rot in [(-20, 0, 4), (25, 45, -6), (-5, 95, 2)]:
        x = np.arange(-90, 90.01, h) + cx
        y = np.arange(-15, 15.01, h) + cy
        z = np.arange(88, 262.01, h)
        X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
        c, s_ = np.cos(np.radians(rot)), np.sin(np.radians(rot))
        u, v = (X - cx) * c + (Y - cy) * s_, -(X - cx) * s_ + (Y - cy) * c
        vc = 8 * np.sin(2 * np.pi * u / 70) + 3 * np.sin(2 * np.pi * u / 23)
        prof = np.exp(-0.5 * ((v - vc) / 0.4) ** 2) * (np.abs(u) < 80)
        prof *= (np.exp(-0.5 * ((Z - 110) / 10) ** 2) + 0.3 * np.exp(-0.5 * ((Z - 180) / 25) ** 2))
        prof *= 0.5 + 0.5 * np.cos(2 * np.pi * u / 11) ** 2
        prof[prof < 1e-4] = 0
        red = np.clip((Z - 120) / 80, 0, 1)
        em = (np.stack([0.1 + 0.8 * red, 1 - 0.8 * red, 0.3 + 0 * red], -1) * prof[..., None]).astype(np.float32)
        de = (0.02 * np.exp(-0.02 * (Z - 90)) * (prof > 0)).astype(np.float32)
        ijk = (int(round(x[0] / h)), int(round(y[0] / h)), int(round(z[0] / h)))
        eg.copyFromArray(em, ijk, (0.0, 0.0, 0.0))
        dg.copyFromArray(de, ijk, 0.0)
    path = out / "default_like.vdb"
    vdb.write(str(path), grids=[dg, eg])
    cam = {"position": [0.0, -260.0, 1.5], "look_at": [0.0, 0.0, 110.0], "up": [0, 0, 1],
           "projection": "perspective", "fov_deg": 50.0}
    for name, look_z, terrain, spp in (("default-volume", 110.0, None, 64),
                                       ("default-terrain", 40.0, {"kind": "plane", "height": 0.0}, 256)):
        scene = synth.write_scene(out / f"{name}.toml", dict(cam, look_at=[0.0, 0.0, look_z]), 160, 90, spp=16,
                                  terrain=terrain)
        info = cycles_render.render(scene, path, out / f"{name}.exr", spp, quiet=True)
        writer.writerow([name, "biased", 0.1, spp, "", "", "", "", f"{info['render_s']:.2f}"])
        sys.stdout.flush()


if __name__ == "__main__":
    main()
