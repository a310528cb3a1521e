"""The airglow in Cycles: the add-on's world (blender/world.py) shows the
map `aurora sky` writes (src/render/sky_map.rs), so a Cycles frame has the
same sky as `aurora render`.

A 180-degree fisheye (64 x 64) from the ground looks straight up with the
default airglow (its lines and the broadband light) and air (round Earth, extinction on), stars off (their
per-pixel footprints are compared in tests/render/airglow.rs, not here);
the volume is one small box below the horizon, out of view. Compared: the
mean radiance of the zenith's 4 x 4 pixels and of the ring of pixels 5-15
degrees above the horizon (where van Rhijn's factor and the air's
extinction act together), per channel, within 2 %. Both renderers read the
same radiance per direction; what differs is Cycles' bilinear lookup in the
map (512 x 256, 0.7 degrees a pixel) against `aurora render`'s table every
0.05 degree: at 10 degrees elevation the airglow's curvature over one map
pixel makes under 0.1 % of difference, the rest is float rounding. The
airglow switched off, the sky is black in both.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import synth
from test_cross_check import render_at_one_sample

ROOT = Path(__file__).resolve().parent.parent.parent
OUT = ROOT / "target" / "cross-check" / "airglow"
N = 64


def _scene(airglow: bool) -> dict:
    return {
        "camera": {"projection": "fisheye", "fov_deg": 180.0, "position": [0.0, 0.0, 0.0],
                   "look_at": [0.0, 0.0, 100.0], "up": [0.0, 1.0, 0.0]},
        "render": {"width": N, "height": N, "spp": 1},
        "terrain": {"kind": "none"},
        "background": {"stars": False},
        "airglow": {"on": airglow},
    }


def _renders(name: str, doc: dict, vdb: Path):
    return render_at_one_sample(OUT / name, doc, vdb, ["--samples", 4])


def _elevation_deg() -> np.ndarray:
    """Each pixel centre's elevation for the equidistant fisheye looking up."""
    y, x = np.mgrid[0:N, 0:N]
    r = np.hypot(2 * (x + 0.5) / N - 1, 1 - 2 * (y + 0.5) / N)
    return np.where(r <= 1.0, 90.0 * (1.0 - r), -90.0)


def test_cycles_shows_the_airglow_aurora_render_draws(compare, tmp_path):
    box = np.zeros((2, 2, 2, 3), np.float32)
    box[...] = 0.1
    vdb = synth.write_vdb(tmp_path / "box.vdb", 1.0, (0.0, 0.0, -50.0), None, box)
    a, b = _renders("on", _scene(True), vdb)
    A, B = compare.read_rgba(a), compare.read_rgba(b)
    el = _elevation_deg()
    c = N // 2
    zenith = (slice(c - 2, c + 2), slice(c - 2, c + 2))
    ring = (el > 5.0) & (el < 15.0)
    figures = {}
    for where, sel in (("zenith", zenith), ("horizon", ring)):
        ra = A[sel][..., :3].reshape(-1, 3).mean(axis=0)
        rb = B[sel][..., :3].reshape(-1, 3).mean(axis=0)
        figures[where] = {"aurora": ra.tolist(), "cycles": rb.tolist()}
        assert np.all(ra > 0.0), (where, ra)
        assert np.all(np.abs(rb / ra - 1.0) <= 0.02), (where, ra, rb)
    # The line layers brighten towards the horizon (van Rhijn; the red and
    # orange lines hold most of the red channel); the light from outside the
    # air (zodiacal light, starlight: most of the blue) does not, and the
    # air dims it there.
    assert figures["horizon"]["aurora"][0] > 1.2 * figures["zenith"]["aurora"][0], figures
    assert figures["horizon"]["aurora"][2] < figures["zenith"]["aurora"][2], figures
    print("airglow", json.dumps(figures))
    (OUT / "figures.json").write_text(json.dumps(figures, indent=1))

    a, b = _renders("off", _scene(False), vdb)
    A, B = compare.read_rgba(a), compare.read_rgba(b)
    inside = el > 0.0
    assert np.abs(A[inside][..., :3]).max() == 0.0
    assert np.abs(B[inside][..., :3]).max() < 1e-6
