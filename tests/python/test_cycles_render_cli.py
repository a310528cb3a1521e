"""tools/cycles/cycles_render.py as a command: output file, channels, exit codes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

import synth

ROOT = Path(__file__).resolve().parent.parent.parent
TOOL = ROOT / "tools" / "cycles" / "cycles_render.py"


def test_cli_writes_rgba_float_exr_with_background_in_rgb(tmp_path):
    import OpenEXR

    em = np.zeros((8, 8, 8, 3), np.float32)
    em[..., 0] = 1.0
    vdb = synth.write_vdb(tmp_path / "v.vdb", 0.25, (-1.0, -1.0, -1.0), np.full((8, 8, 8), 2.0, np.float32), em)
    cam = {"position": [-0.125, -10.0, -0.125], "look_at": [-0.125, 0.0, -0.125], "up": [0, 0, 1],
           "projection": "orthographic", "ortho_height": 4.0}
    scene = synth.write_scene(tmp_path / "s.toml", cam, 12, 8, spp=1, background=(0.0, 0.5, 0.0))
    out = tmp_path / "sub" / "o.exr"
    r = subprocess.run([sys.executable, TOOL, scene, "--vdb", vdb, "--out", out, "--samples", "16", "-q"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "Saved:" not in r.stdout, r.stdout  # -q: not even Blender's own lines
    assert sorted(p.name for p in out.parent.iterdir()) == ["o.exr"]  # no temporary file left
    with OpenEXR.File(str(out), separate_channels=True) as f:
        ch = f.channels()
        assert sorted(ch) == ["A", "B", "G", "R"]
        assert all(c.pixels.dtype == np.float32 for c in ch.values())
        hdr = f.header()
        assert hdr["aurora_pixel_filter"].startswith("point")
        assert hdr["aurora_volume_mode"] == "biased"
        rgba = np.dstack([ch[c].pixels for c in "RGBA"])
    # Corner: background only (green 0.5, alpha 0). Centre: optical depth
    # 2 * 8 * 0.25 = 4 through the box: T = e^-4, R = (1 / 2)(1 - T), G = 0.5 T.
    assert np.allclose(rgba[0, 0], [0.0, 0.5, 0.0, 0.0], atol=1e-6)
    T = np.exp(-4.0)
    c = rgba[3:5, 5:7].reshape(-1, 4).mean(0)
    assert np.allclose(c, [0.5 * (1 - T), 0.5 * T, 0.0, 1 - T], atol=0.005), c


def test_cli_exit_codes(tmp_path):
    cam = {"position": [0, -5, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "projection": "orthographic",
           "ortho_height": 1.0}
    scene = synth.write_scene(tmp_path / "s.toml", cam, 8, 8)
    r = subprocess.run([sys.executable, TOOL, scene, "--vdb", tmp_path / "none.vdb", "--out", tmp_path / "o.exr"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "no such file" in r.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text("[render]\nwidth = -3\n")
    vdb = synth.write_vdb(tmp_path / "v.vdb", 1.0, (0, 0, 0), None, np.ones((2, 2, 2), np.float32))
    r = subprocess.run([sys.executable, TOOL, bad, "--vdb", vdb, "--out", tmp_path / "o.exr"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "render.width" in r.stderr, r.stderr
    assert not (tmp_path / "o.exr").exists()
    hf = synth.write_scene(tmp_path / "hf.toml", cam, 8, 8, terrain={"kind": "heightfield"})
    r = subprocess.run([sys.executable, TOOL, hf, "--vdb", vdb, "--out", tmp_path / "o.exr"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "aurora terrain" in r.stderr, r.stderr
