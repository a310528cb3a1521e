"""The add-on develops Cycles' picture as `aurora render` develops its PNG
(blender/display.py, src/render/develop.rs): the camera's white balance
(the same matrix, in the compositor) and the exposure (the view's).

A 180-degree fisheye (32 x 32) from the ground looks straight up at the
default sky (airglow, broadband light, air; stars off) through the
Standard view at +1.5 stops and the default 3200 K white balance; the
volume is one small box below the horizon. `aurora render`'s PNG and
Blender's picture of its Cycles render (the composite through its view,
saved as an 8-bit PNG) agree within 3 code values on every pixel inside
the circle (the linear skies agree within 0.1 %, tests/python/
test_airglow_sky.py; the rest is 8-bit rounding). Undeveloped (the
compositor's white balance off) the two differ by far more: the
comparison sees the matrix. `render.exposure = "auto"`: the add-on sets
the EV the binary meters.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np

import synth
from aurora_tools.png import read_png

ROOT = Path(__file__).resolve().parent.parent.parent
N = 32


def aurora_bin() -> Path:
    p = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    assert p.is_file() and os.access(p, os.X_OK), f"{p}: the aurora binary is missing (cargo build --release)"
    return p


def _scene(path: Path, exposure) -> Path:
    path.write_text(synth.toml_dumps({
        "camera": {"projection": "fisheye", "fov_deg": 180.0, "position": [0.0, 0.0, 0.0],
                   "look_at": [0.0, 0.0, 100.0], "up": [0.0, 1.0, 0.0]},
        "render": {"width": N, "height": N, "spp": 1, "exposure": exposure, "view_transform": "standard"},
        "terrain": {"kind": "none"},
        "background": {"stars": False},
    }))
    return path


def _inside() -> np.ndarray:
    y, x = np.mgrid[0:N, 0:N]
    return np.hypot(2 * (x + 0.5) / N - 1, 1 - 2 * (y + 0.5) / N) < 0.97


def _cycles_png(bpy, addon, scene: Path, vdb: Path, png: Path, develop: bool) -> np.ndarray:
    os.environ.setdefault("AURORA_BIN", str(aurora_bin()))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    built = addon.setup_scene_from_toml(scene, vdb=vdb, settings=addon.CyclesSettings(samples=4), develop=develop)
    sc = bpy.context.scene
    sc.view_settings.view_transform, sc.view_settings.look = "Standard", "None"
    sc.render.dither_intensity = 0.0
    s = sc.render.image_settings
    s.file_format, s.color_mode, s.color_depth = "PNG", "RGB", "8"
    bpy.ops.render.render()
    bpy.data.images["Render Result"].save_render(str(png), scene=sc)
    assert built.world is not None
    return read_png(png)[..., :3].astype(int)


def test_cycles_develops_the_picture_as_aurora_render_does(bpy, addon, tmp_path):
    box = np.full((2, 2, 2, 3), 0.1, np.float32)
    vdb = synth.write_vdb(tmp_path / "box.vdb", 1.0, (0.0, 0.0, -50.0), None, box)
    scene = _scene(tmp_path / "up.toml", 1.5)
    ours = tmp_path / "aurora.png"
    r = subprocess.run([aurora_bin(), "render", scene, "--vdb", vdb, "--png", ours, "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    a = read_png(ours)[..., :3].astype(int)
    b = _cycles_png(bpy, addon, scene, vdb, tmp_path / "cycles.png", True)
    inside = _inside()
    d = np.abs(a - b).max(-1)[inside]
    assert a[inside].max() > 100, "the sky is lit"
    assert d.max() <= 3, f"max {d.max()}, mean {d.mean():.2f}"
    raw = _cycles_png(bpy, addon, scene, vdb, tmp_path / "raw.png", False)
    assert np.abs(a - raw).max(-1)[inside].mean() > 10, "the development shows"


def test_auto_exposure_reaches_the_film(bpy, addon, tmp_path):
    box = np.full((2, 2, 2, 3), 0.1, np.float32)
    vdb = synth.write_vdb(tmp_path / "box.vdb", 1.0, (0.0, 0.0, -50.0), None, box)
    scene = _scene(tmp_path / "auto.toml", "auto")
    ev = addon.display.metered_ev(scene, vdb, str(aurora_bin()))
    os.environ.setdefault("AURORA_BIN", str(aurora_bin()))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.setup_scene_from_toml(scene, vdb=vdb, settings=addon.CyclesSettings(samples=1))
    assert ev != 0.0 and abs(bpy.context.scene.view_settings.exposure - ev) < 1e-6  # a float32 property
