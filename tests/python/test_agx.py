"""`aurora render`'s AgX PNGs against Blender's own AgX view of the same EXR.

The linear EXR `aurora render` writes, developed as its PNG is (the
camera's white balance, src/render/develop.rs: the add-on's matrix,
blender/display.py, applied to the EXR's pixels), is shown through
Blender's colour management with bpy (display sRGB, view AgX, look None, exposure the
scene's, gamma 1, dither 0) and saved as an 8-bit PNG; `aurora render`'s
PNG of the same render (`render.view_transform = "agx"`, the default) must
agree within 3/255 per channel on 99% of the pixels (8-bit quantisation
alone differs by 1 where the two sides round a value near a half step
differently; the rest is the LUT's float precision). Two images: a reduced
aurora bake, and a chart of saturated colour lines (pure primaries and
secondaries, the aurora's green and red) over 16 stops, which is where a
view transform's gamut handling shows.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import synth
from aurora_tools.png import read_png

ROOT = Path(__file__).resolve().parent.parent.parent


def aurora_bin() -> Path:
    p = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    assert p.is_file() and os.access(p, os.X_OK), f"{p}: the aurora binary is missing (cargo build --release)"
    return p


def read_png_rgb8(path: Path) -> np.ndarray:
    """An 8-bit RGB (or RGBA) non-interlaced PNG as (H, W, 3) uint8."""
    px = read_png(path)
    assert px.dtype == np.uint8 and px.shape[2] in (3, 4), (px.dtype, px.shape)
    return px[..., :3]


def developed(addon, exr: Path, white_balance_k: float = 3200.0) -> Path:
    """`exr`'s pixels through the camera's white balance at
    `white_balance_k` (the default), as `aurora render` develops its PNG:
    the add-on's matrix (blender/display.py), written beside it."""
    from aurora_tools.exr_io import read_rgba, write_rgba_exr

    rgba = read_rgba(exr)
    w = np.asarray(addon.display.white_balance_matrix(white_balance_k))
    rgba[..., :3] = rgba[..., :3] @ w.T
    out = exr.with_name(exr.stem + "-developed.exr")
    write_rgba_exr(out, rgba.astype(np.float32))
    return out


def blender_agx_png(bpy, exr: Path, png: Path, exposure: float, look: str = "None") -> np.ndarray:
    """`exr` through Blender's AgX view for an sRGB display with `look`, as 8-bit PNG."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    img = bpy.data.images.load(str(exr))
    sc = bpy.context.scene
    sc.display_settings.display_device = "sRGB"
    vs = sc.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = "AgX", look, exposure, 1.0
    assert vs.look == look, (vs.look, look)
    sc.render.dither_intensity = 0.0
    s = sc.render.image_settings
    s.file_format, s.color_mode, s.color_depth = "PNG", "RGB", "8"
    img.save_render(str(png), scene=sc)
    return read_png_rgb8(png)


def compare_png(ours: np.ndarray, theirs: np.ndarray, what: str):
    assert ours.shape == theirs.shape, (ours.shape, theirs.shape)
    d = np.abs(ours.astype(int) - theirs.astype(int)).max(-1)
    within = (d <= 3).mean()
    print(f"{what}: {within:.4%} of pixels within 3/255, {(d <= 1).mean():.4%} within 1/255, max {d.max()}")
    assert within >= 0.99, f"{what}: only {within:.3%} of pixels within 3/255 of Blender's AgX (max {d.max()})"
    return d


def saturated_share(exr: Path, compare_mod) -> float:
    rgb = compare_mod.read_rgba(exr)[..., :3].astype(np.float64)
    mx = rgb.max(-1)
    bright = mx > 0.18 * 2.0 ** -6
    chroma = np.where(mx > 0, (mx - rgb.min(-1)) / np.where(mx > 0, mx, 1), 0)
    return float((bright & (chroma > 0.9)).mean())


def test_agx_png_matches_blender_on_an_aurora_render(bpy, addon, compare, tmp_path):
    scene = tmp_path / "aurora.toml"
    scene.write_text(synth.toml_dumps({
        "beams": {"count": 3000},
        "footprint": {"resolution": [128, 32]},
        "grid": {"voxel_size": 1.0},
        "photons": {"radius_km": 1.0},
        "render": {"width": 160, "height": 90, "spp": 4, "exposure": 4.0},
    }))
    exr, png = tmp_path / "a.exr", tmp_path / "a.png"
    r = subprocess.run([aurora_bin(), "render", scene, "--out", exr, "--png", png, "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    ours = read_png_rgb8(png)
    theirs = blender_agx_png(bpy, developed(addon, exr), tmp_path / "blender.png", 4.0)
    d = compare_png(ours, theirs, "aurora render")
    # The picture is not black: the comparison covers lit pixels.
    assert (ours.max(-1) > 30).mean() > 0.05
    assert d.max() <= 8


def lines_chart(tmp_path: Path, colours) -> tuple[Path, Path]:
    """Bars of colour, each an emission ramp over 16 stops (bottom to top),
    seen orthographically through a 2 km thick slab: the scene and its VDB."""
    h, nz, bar, ny = 0.5, 64, 6, 4
    em = np.zeros((len(colours) * bar, ny, nz, 3), np.float32)
    level = 0.18 * 2.0 ** np.linspace(-10.0, 6.0, nz) / (ny * h)
    for i, c in enumerate(colours):
        em[i * bar:(i + 1) * bar - 1] = np.asarray(c, np.float32)[None, None, None, :] * level[None, None, :, None]
    vdb = synth.write_vdb(tmp_path / "lines.vdb", h, (0.0, 0.0, 0.0), None, em)
    cx, cz = (em.shape[0] - 1) * h / 2, (nz - 1) * h / 2
    cam = {"position": [cx, -50.0, cz], "look_at": [cx, 0.0, cz], "up": [0, 0, 1], "projection": "orthographic",
           "ortho_height": nz * h}
    return synth.write_scene(tmp_path / "lines.toml", cam, 96 if len(colours) == 8 else 12 * len(colours), 128, spp=4), vdb


#: Pure primaries and secondaries, the aurora's green and red.
SATURATED = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (0, 1, 1), (1, 0, 1), (0.06, 1.0, 0.03), (1.0, 0.02, 0.05)]


def test_agx_png_matches_blender_on_saturated_lines(bpy, addon, compare, tmp_path):
    scene, vdb = lines_chart(tmp_path, SATURATED)
    exr, png = tmp_path / "l.exr", tmp_path / "l.png"
    r = subprocess.run([aurora_bin(), "render", scene, "--vdb", vdb, "--out", exr, "--png", png, "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert saturated_share(exr, compare) > 0.3  # the chart is mostly saturated colour
    ours = read_png_rgb8(png)
    theirs = blender_agx_png(bpy, developed(addon, exr), tmp_path / "blender.png", 0.0)
    compare_png(ours, theirs, "saturated lines")


#: Every `render.view_transform` with a look (the scene schema's words).
LOOKS = [w for w in json.loads((ROOT / "blender" / "scene_schema.json").read_text())["render"]["view_transform"]["values"]
         if w.startswith("agx_")]


def test_every_look_blender_ships_for_agx_is_a_view_transform(bpy, addon):
    """The looks Blender's colour management configuration defines for AgX
    ("AgX - ..." in its config.ocio) are exactly the `agx_` words, each
    named as the add-on names it, and Blender takes each name."""
    config = Path(bpy.utils.system_resource("DATAFILES")) / "colormanagement" / "config.ocio"
    assert config.is_file(), config
    theirs = {line.split("name:", 1)[1].strip() for line in config.read_text().splitlines()
              if line.strip().startswith("name: AgX - ")}
    ours = {addon.render_settings.blender_view(w)[1] for w in LOOKS}
    assert len(LOOKS) == 9 and ours == theirs, (sorted(ours), sorted(theirs))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    vs = bpy.context.scene.view_settings
    vs.view_transform = "AgX"
    for name in sorted(ours):
        vs.look = name
        assert vs.look == name


@pytest.mark.parametrize("view", LOOKS)
def test_agx_looks_match_blender(bpy, addon, compare, tmp_path, view):
    """`render.view_transform = "agx_<look>"` against Blender's AgX view with
    that look, on the saturated chart plus a grey bar over 16 stops, within
    AgX's own tolerance (3/255 on 99 % of the pixels)."""
    scene, vdb = lines_chart(tmp_path, SATURATED + [(1.0, 1.0, 1.0)])
    exr, png = tmp_path / "l.exr", tmp_path / "l.png"
    r = subprocess.run([aurora_bin(), "render", scene, "--vdb", vdb, "--out", exr, "--png", png, "--quiet",
                        "--set", f'render.view_transform="{view}"'], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    ours = read_png_rgb8(png)
    look = addon.render_settings.blender_view(view)[1]
    theirs = blender_agx_png(bpy, developed(addon, exr), tmp_path / "blender.png", 0.0, look)
    plain = blender_agx_png(bpy, developed(addon, exr), tmp_path / "plain.png", 0.0)
    compare_png(ours, theirs, view)
    # The look changes the picture: a test of a look that did nothing would pass on plain AgX.
    assert np.abs(theirs.astype(int) - plain.astype(int)).max() > 10, view


def test_standard_view_is_the_clipped_srgb_of_the_exr(bpy, addon, compare, tmp_path):
    """`view_transform = "standard"` keeps the old preview: Blender's
    Standard view of the same EXR."""
    scene = tmp_path / "s.toml"
    scene.write_text(synth.toml_dumps({
        "beams": {"count": 1000}, "footprint": {"resolution": [64, 16]}, "grid": {"voxel_size": 2.0},
        "photons": {"radius_km": 1.5}, "render": {"width": 64, "height": 36, "spp": 2, "exposure": 5.0,
                                                    "view_transform": "standard"},
    }))
    exr, png = tmp_path / "s.exr", tmp_path / "s.png"
    r = subprocess.run([aurora_bin(), "render", scene, "--out", exr, "--png", png, "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    bpy.ops.wm.read_factory_settings(use_empty=True)
    img = bpy.data.images.load(str(developed(addon, exr)))
    sc = bpy.context.scene
    sc.display_settings.display_device = "sRGB"
    sc.view_settings.view_transform, sc.view_settings.look, sc.view_settings.exposure = "Standard", "None", 5.0
    sc.render.dither_intensity = 0.0
    sc.render.image_settings.file_format, sc.render.image_settings.color_mode = "PNG", "RGB"
    img.save_render(str(tmp_path / "b.png"), scene=sc)
    d = np.abs(read_png_rgb8(png).astype(int) - read_png_rgb8(tmp_path / "b.png").astype(int)).max(-1)
    assert (d <= 1).mean() >= 0.999, f"max {d.max()}"


def test_agx_png_tool_writes_through_a_temporary_and_renames(bpy, compare, tmp_path):
    """tools/cycles/agx_png.py gives Blender's AgX picture of the EXR, replaces an
    existing PNG and leaves no temporary file beside it."""
    scene = tmp_path / "t.toml"
    scene.write_text(synth.toml_dumps({
        "beams": {"count": 1000}, "footprint": {"resolution": [64, 16]}, "grid": {"voxel_size": 2.0},
        "photons": {"radius_km": 1.5}, "render": {"width": 64, "height": 36, "spp": 2, "exposure": 5.0},
    }))
    exr = tmp_path / "t.exr"
    r = subprocess.run([aurora_bin(), "render", scene, "--out", exr, "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out_dir = tmp_path / "pictures"
    out_dir.mkdir()
    png = out_dir / "t.png"
    png.write_bytes(b"an older picture")
    tool = ROOT / "tools" / "cycles" / "agx_png.py"
    r = subprocess.run([sys.executable, tool, exr, png, "--exposure", "5"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out_dir.iterdir()) == ["t.png"]
    theirs = blender_agx_png(bpy, exr, tmp_path / "blender.png", 5.0)
    assert np.array_equal(read_png_rgb8(png), theirs)
