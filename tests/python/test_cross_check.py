"""`aurora render` against Cycles (tools/cycles/cycles_render.py) on the default bake.

    aurora bake SCENE --out DIR
    aurora render SCENE --vdb DIR/aurora.vdb --out A.exr
    tools/cycles/cycles_render.py SCENE --vdb DIR/aurora.vdb --out B.exr

at 160x90, for two scenes derived from `aurora scene default`, its stars
off (a star's footprint lands on other pixel centres in the two renderers'
point-sampled images; tests/render/airglow.rs checks their flux):
- volume only (no terrain), with `[airglow] on = false`, so the volume is
  compared alone: mean relative error over pixels brighter than 1% of the
  peak <= 2%, total flux within 1%, alpha within 0.01 everywhere (the same
  view in front of the default airglow, which the add-on shows as `aurora
  sky`'s map, is test_cross_check_sequence.py's, frame by frame, with these
  tolerances; the panoramas below show it too);
- terrain ("plane") lit by the aurora, the camera's look-at lowered from
  110 to 40 km so the ground fills the lower third of the frame, on flat
  ground and on the round Earth (its sphere up to the horizon): mean
  relative error over the pixels wholly on the terrain <= 5%.
The binary is target/release/aurora (AURORA_BIN overrides); without it this
test fails. Images, difference pictures and figures are kept under
target/cross-check/.

Noise budget (measured, tests/python/bench_cycles_noise.py and the add-on
blender/README.md): Cycles at 64 samples, biased ray marching at step rate
0.1, has ~0.6% mean relative noise on one-voxel curtains; terrain lit
through emission_lights.py has ~1-2% at 256 samples. `aurora render` runs
at 1 spp (volume) and 64 spp (terrain).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np

import synth

ROOT = Path(__file__).resolve().parent.parent.parent
OUT = ROOT / "target" / "cross-check"
WIDTH, HEIGHT = 160, 90
# Volume: spp = 1 point-samples pixel centres in both renderers (exact in
# `aurora render`, GAUSSIAN filter width 0.01 in Cycles). The curtains are
# streaks thinner than a pixel at 160x90, so area sampling with jittered
# samples adds each renderer's own pixel-integration noise (measured: 5.4%
# mean at 64 spp each, flux within 0.2%), which says nothing about the
# radiance model; point sampling leaves only Cycles' volume noise.
# Terrain: the plane is smooth under the pixel, and the shadow rays need
# samples, so both average 64 / 256 samples over the pixel square.
AURORA_SPP = {"volume": 1, "terrain": 64, "fisheye": 1, "equirectangular": 1, "sky": 1}
# Emissive shadow samples per terrain hit: at 1 (64 per pixel) `aurora
# render`'s terrain had 4.3% per-pixel noise against Cycles' 1.0% (adjacent-
# pixel differences on the plane); 8 brings it to about 1.5%.
AURORA_SHADOW = {"volume": 1, "terrain": 8, "fisheye": 1, "equirectangular": 1, "sky": 1}
CYCLES_SAMPLES = {"volume": 64, "terrain": 256, "fisheye": 64, "equirectangular": 64, "sky": 64}
# The terrain check looks at terrain pixels only; at the aurora's optical
# depth per voxel (~0.01) step rate 0.25 is as exact as 0.1 and 2x faster.
STEP_RATE = {"volume": 0.1, "terrain": 0.25, "fisheye": 0.1, "equirectangular": 0.1, "sky": 0.1}
#: The panoramas: from the ground under the middle curtain (y = 45 km),
#: a 180-degree fisheye looking straight up, north at the top (a dome
#: master), and a 360 x 180 panorama looking north.
UNDER = [0.0, 45.0, 1.0]
PANORAMAS = {
    "fisheye": ({"projection": "fisheye", "fov_deg": 180.0, "position": UNDER,
                 "look_at": [UNDER[0], UNDER[1], 100.0], "up": [0.0, 1.0, 0.0]}, 256, 256),
    "equirectangular": ({"projection": "equirectangular", "position": UNDER,
                         "look_at": [UNDER[0], UNDER[1] + 100.0, UNDER[2]], "up": [0.0, 0.0, 1.0]}, 256, 128),
}


def aurora_bin() -> Path:
    p = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    assert p.is_file() and os.access(p, os.X_OK), f"{p}: the aurora binary is missing (cargo build --release)"
    return p


def run(cmd, **kw):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    assert r.returncode == 0, f"{' '.join(map(str, cmd))} failed ({r.returncode}):\n{r.stdout[-2000:]}\n{r.stderr[-4000:]}"
    return r


def default_scene(binary: Path) -> dict:
    """`aurora scene default`, its stars off (module doc)."""
    doc = tomllib.loads(run([binary, "scene", "default"]).stdout)
    assert "camera" in doc and "curtain" in doc, f"`{binary} scene default` printed no scene"
    doc["background"] = {**doc.get("background", {}), "stars": False}
    return doc


def render_both(binary, scene_doc: dict, name: str, vdb: Path, extra=(), kind=None):
    """Both renders of `scene_doc` under OUT/name, with the sample counts of
    `kind` (the name unless given)."""
    d = OUT / name
    d.mkdir(parents=True, exist_ok=True)
    scene = d / "scene.toml"
    name = kind or name
    scene_doc = {**scene_doc, "render": {**scene_doc.get("render", {}), "spp": AURORA_SPP[name]}}
    scene.write_text(synth.toml_dumps(scene_doc))
    a, b = d / "aurora.exr", d / "cycles.exr"
    run([binary, "render", scene, "--vdb", vdb, "--out", a, "--spp", AURORA_SPP[name],
         "--shadow-samples", AURORA_SHADOW[name], "--png", d / "aurora.png"])
    run([sys.executable, ROOT / "tools" / "cycles" / "cycles_render.py", scene, "--vdb", vdb, "--out", b,
         "--samples", CYCLES_SAMPLES[name], "--step-rate", STEP_RATE[name], *extra])
    return scene, a, b


def render_at_one_sample(out_dir: Path, doc: dict, vdb: Path, cycles_args) -> tuple[Path, Path]:
    """`doc` written to out_dir/scene.toml and rendered from `vdb` by
    `aurora render` at 1 sample a pixel (out_dir/aurora.exr) and by Cycles
    with `cycles_args` (out_dir/cycles.exr)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    scene = out_dir / "scene.toml"
    scene.write_text(synth.toml_dumps(doc))
    a, b = out_dir / "aurora.exr", out_dir / "cycles.exr"
    run([aurora_bin(), "render", scene, "--vdb", vdb, "--out", a, "--spp", 1])
    run([sys.executable, ROOT / "tools" / "cycles" / "cycles_render.py", scene, "--vdb", vdb, "--out", b, *cycles_args])
    return a, b


def test_aurora_render_matches_cycles_on_the_default_bake(compare):
    binary = aurora_bin()
    OUT.mkdir(parents=True, exist_ok=True)
    doc = default_scene(binary)
    doc.setdefault("render", {}).update({"width": WIDTH, "height": HEIGHT})
    doc["terrain"] = {**doc.get("terrain", {}), "kind": "none"}
    bake_dir = OUT / "bake"
    (OUT / "bake.toml").write_text(synth.toml_dumps(doc))
    run([binary, "bake", OUT / "bake.toml", "--out", bake_dir])
    vdb = bake_dir / "aurora.vdb"
    assert vdb.is_file(), f"aurora bake wrote no {vdb}"

    # Volume only, alone (module doc: in front of the airglow, it is the
    # sequence's check).
    d = {**doc, "airglow": {**doc.get("airglow", {}), "on": False}}
    scene, a, b = render_both(binary, d, "volume", vdb)
    A, B = compare.read_rgba(a), compare.read_rgba(b)
    assert A.shape == B.shape == (HEIGHT, WIDTH, 4)
    m = compare.compare(a, b, OUT / "volume" / "diff.png", OUT / "volume" / "figures.json")
    print("volume:", json.dumps(m))
    assert m["mean_rel_err"] <= 0.02, m
    assert abs(m["flux_ratio"] - 1.0) <= 0.01, m
    assert m["max_alpha_diff"] <= 0.01, m

    # Terrain lit by the aurora, without the air: the add-on dims the
    # volume's emission towards the camera, not the terrain's light
    # (blender/air.py), so this check compares the terrain's lighting alone:
    # the `plane` terrain on flat ground (`earth.radius_km = 0`: the plane)
    # and on the default round Earth (its sphere, which the camera sees out
    # to a horizon 1 degree down and 113 km away; the add-on's cap of it).
    for name, earth in (("terrain", {"radius_km": 0.0}), ("terrain-round", {})):
        ter = {
            **doc,
            "terrain": {**doc["terrain"], "kind": "plane"},
            "sky": {**doc.get("sky", {}), "extinction": False},
            "earth": {**doc.get("earth", {}), **earth},
        }
        ter["camera"] = {**doc["camera"], "look_at": [doc["camera"]["look_at"][0], doc["camera"]["look_at"][1], 40.0]}
        scene, a, b = render_both(binary, ter, name, vdb, kind="terrain")
        mask = compare.terrain_mask(scene, WIDTH, HEIGHT)
        assert mask.sum() > 0.2 * WIDTH * HEIGHT
        m = compare.compare(a, b, OUT / name / "diff.png", OUT / name / "figures.json", mask=mask)
        print(f"{name}:", json.dumps(m))
        assert m["mask_mean_rel_err"] <= 0.05, (name, m)
        assert np.isfinite(m["mask_flux_ratio"]), (name, m)


def test_panoramic_cameras_match_cycles(compare):
    """A 180-degree fisheye (256x256) and an equirectangular panorama
    (256x128) of the default bake from under the curtains, against Cycles'
    FISHEYE_EQUIDISTANT and EQUIRECTANGULAR cameras set up by the add-on:
    mean relative error <= 2%, flux within 1%, alpha within 0.01, and
    outside the fisheye's image circle both images empty (RGBA 0).
    The bake is made for the fisheye (pruning follows the scene's camera)."""
    binary = aurora_bin()
    out = OUT / "panorama"
    out.mkdir(parents=True, exist_ok=True)
    doc = default_scene(binary)
    doc["terrain"] = {**doc.get("terrain", {}), "kind": "none"}
    cam, w, h = PANORAMAS["fisheye"]
    bake = {**doc, "camera": {**doc["camera"], **cam}, "render": {**doc.get("render", {}), "width": w, "height": h}}
    (out / "bake.toml").write_text(synth.toml_dumps(bake))
    run([binary, "bake", out / "bake.toml", "--out", out / "bake"])
    vdb = out / "bake" / "aurora.vdb"
    for name, (cam, w, h) in PANORAMAS.items():
        d = {**doc, "camera": {**doc["camera"], **cam}, "render": {**doc.get("render", {}), "width": w, "height": h}}
        scene, a, b = render_both(binary, d, name, vdb)
        A, B = compare.read_rgba(a), compare.read_rgba(b)
        assert A.shape == B.shape == (h, w, 4)
        m = compare.compare(a, b, OUT / name / "diff.png", OUT / name / "figures.json")
        print(name, json.dumps(m))
        assert m["mean_rel_err"] <= 0.02, (name, m)
        assert abs(m["flux_ratio"] - 1.0) <= 0.01, (name, m)
        if name == "fisheye":
            # Outside the image circle `aurora render` writes RGBA 0; Cycles
            # ends those camera rays without light (RGB 0) but counts them
            # opaque (alpha 1), so alpha is compared inside the circle.
            y, x = np.mgrid[0:h, 0:w]
            r = np.hypot((2 * (x + 0.5) / w - 1), (1 - 2 * (y + 0.5) / h))
            outside, inside = r > 1.0 + 2.0 / w, r < 1.0 - 2.0 / w
            assert outside.sum() > 0.15 * w * h
            assert np.all(A[outside] == 0.0) and np.all(np.abs(B[outside][..., :3]) < 1e-6)
            assert np.abs(A[inside][..., 3] - B[inside][..., 3]).max() <= 0.01, (name, m)
            # The default's air is optically thin (alpha ~0 everywhere), so
            # the curtains show by their light: the brightest pixel of the
            # dome stands well above the airglow's median there.
            lum = A[inside][..., :3].max(axis=-1)
            assert lum.max() > 5.0 * np.median(lum), ("the curtains are in the dome", lum.max(), np.median(lum))
        else:
            assert m["max_alpha_diff"] <= 0.01, (name, m)


def _write_sky(path: Path, w: int = 64, h: int = 32) -> None:
    """A smooth synthetic sky: RGB varying with azimuth and altitude."""
    import OpenEXR

    u = (np.arange(w) + 0.5) / w
    v = 1.0 - (np.arange(h) + 0.5) / h  # row 0 at the top
    uu, vv = np.meshgrid(u, v)
    rgba = np.stack([0.2 + 0.1 * np.sin(2 * np.pi * uu), 0.1 + 0.2 * vv,
                     0.05 + 0.05 * np.cos(2 * np.pi * uu) * vv, np.ones_like(uu)], axis=-1).astype(np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {c: np.ascontiguousarray(rgba[..., i]) for i, c in enumerate("RGBA")}) as f:
        f.write(str(path))


def test_sky_image_maps_like_blenders_world(compare):
    """`[background] image`: an equirectangular panorama (128x64) of the
    default bake in front of a synthetic sky, against Cycles with the
    add-on's World (Environment Texture, default mapping): mean relative
    error <= 2% over the whole frame (sky everywhere), so the sky's
    orientation and interpolation agree."""
    binary = aurora_bin()
    out = OUT / "sky"
    out.mkdir(parents=True, exist_ok=True)
    _write_sky(out / "sky.exr")
    doc = default_scene(binary)
    doc["terrain"] = {**doc.get("terrain", {}), "kind": "none"}
    cam, _, _ = PANORAMAS["equirectangular"]
    doc = {**doc, "camera": {**doc["camera"], **cam}, "render": {**doc.get("render", {}), "width": 128, "height": 64},
           "background": {"image": "sky.exr", "stars": False}}
    (out / "bake.toml").write_text(synth.toml_dumps(doc))
    run([binary, "bake", out / "bake.toml", "--out", out / "bake"])
    scene, a, b = render_both(binary, doc, "sky", out / "bake" / "aurora.vdb")
    m = compare.compare(a, b, OUT / "sky" / "diff.png", OUT / "sky" / "figures.json", threshold=0.0)
    print("sky", json.dumps(m))
    assert m["mean_rel_err"] <= 0.02, m
    assert abs(m["flux_ratio"] - 1.0) <= 0.01, m
