"""The air between the aurora and the camera in the add-on (blender/air.py)
against the library (blender/extinction.json, written and checked by
tests/render/extinction.rs), and `aurora render` against Cycles with `[sky]
extinction` on: a uniform emitting slab 100-110 km up seen low (10 degrees
elevation, perspective) and as a dome master (a 180-degree fisheye looking
straight up).

Tolerances: the port's transmittances are the same formulas in double
precision (1e-12 relative). The renders: mean relative error over pixels
brighter than 1 % of the peak and flux within 1 %; Cycles' biased ray
marching at step rate 0.1 on a smooth slab has about 0.2 % noise at 64
samples (docs: "How Cycles reads the VDB"), so 1 % leaves room for
noise only; the air alone scales the slab by 0.39-0.85 per channel here,
so a missing or mis-signed air would fail by tens of percent.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np

import synth
from test_cross_check import render_at_one_sample

ROOT = Path(__file__).resolve().parent.parent.parent
OUT = ROOT / "target" / "cross-check" / "air"


def _air():
    spec = importlib.util.spec_from_file_location("aurora_air", ROOT / "blender" / "air.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class _Sky:
    extinction = True
    ozone_du = 300.0
    aerosol_optical_depth = 0.05
    angstrom = 1.3
    aerosol_scale_height_km = 1.2


def test_port_reproduces_the_library():
    air = _air()
    checks = air.TABLE["checks"]
    assert len(checks) >= 8
    for c in checks:
        got = air.transmittance(_Sky, c["observer_km"], c["elevation_deg"], c["observer"])
        for g, w in zip(got, c["transmittance"]):
            assert abs(g / w - 1.0) < 1e-12, (c, got)
    # The schema's defaults are the sky used for the checks.
    schema = json.loads((ROOT / "blender" / "scene_schema.json").read_text())["sky"]
    for k in ("ozone_du", "aerosol_optical_depth", "angstrom", "aerosol_scale_height_km"):
        assert schema[k]["default"] == getattr(_Sky, k), k
    assert schema["extinction"]["default"] is True


def _slab(path: Path) -> Path:
    """A uniform emitting slab: 2 km voxels, 100-110 km up, 300 x 300 km
    around the origin (index 0 at (-150, -150, 100) km)."""
    n, nz = 151, 6
    em = np.zeros((n, n, nz, 3), np.float32)
    em[...] = (0.6, 1.0, 0.3)
    return synth.write_vdb(path, 2.0, (-150.0, -150.0, 100.0), None, em)


def _scene(camera: dict, width: int, height: int) -> dict:
    # The slab alone: no stars, no airglow (tests/python/test_airglow_sky.py).
    return {"camera": camera, "render": {"width": width, "height": height, "spp": 1},
            "terrain": {"kind": "none"}, "sky": {"extinction": True}, "background": {"stars": False},
            "airglow": {"on": False}}


def _both(compare, name: str, doc: dict, vdb: Path) -> dict:
    d = OUT / name
    a, b = render_at_one_sample(d, doc, vdb, ["--samples", 64, "--step-rate", 0.1])
    m = compare.compare(a, b, d / "diff.png", d / "figures.json")
    print(name, json.dumps(m))
    return m


def test_cycles_shows_the_same_air(compare, tmp_path):
    vdb = _slab(tmp_path / "slab.vdb")
    # Low: from 600 km west of the slab's centre, the view's centre 9.9
    # degrees up meets the slab 29 km west of it; the view spans 6-14
    # degrees (the rays below about 8 degrees pass under the slab).
    low = _scene({"projection": "perspective", "position": [-600.0, 0.0, 0.0], "look_at": [0.0, 0.0, 105.0],
                  "up": [0.0, 0.0, 1.0], "fov_deg": 8.0}, 96, 64)
    m = _both(compare, "low", low, vdb)
    assert m["bright_pixels"] > 1000, m
    assert m["mean_rel_err"] <= 0.01, m
    assert abs(m["flux_ratio"] - 1.0) <= 0.01, m
    dome = _scene({"projection": "fisheye", "position": [0.0, 0.0, 0.0], "look_at": [0.0, 0.0, 100.0],
                   "up": [0.0, 1.0, 0.0], "fov_deg": 180.0}, 128, 128)
    m = _both(compare, "dome", dome, vdb)
    assert m["bright_pixels"] > 3000, m
    assert m["mean_rel_err"] <= 0.01, m
    assert abs(m["flux_ratio"] - 1.0) <= 0.01, m
