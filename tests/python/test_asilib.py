"""Synthetic all-sky frames read by asilib (asilib 0.30.1, installed by
tools/setup into the tests' environment; missing is a failure): a zenith
fisheye's 557.7 nm images of a drifting arc, each written with its skymap
(`aurora.write_frame`: azimuth, elevation, and latitude and longitude at
110 km on the round Earth), become an `asilib.Imager` through its plug-in
dictionaries (`aurora.asilib_imager`, as asilib's `fake_asi` builds them),
and asilib draws its keogram.

asilib's keogram takes the image's middle column (the geographic meridian,
north at the top); `aurora keogram` traces the magnetic meridian. With the
field's declination 0 the two are one plane, and the two keograms must
agree:
- position: each frame's brightest row of asilib's keogram, taken to scan
  angle through the skymap (elevation toward north, 180 less elevation
  toward south), within one image row (180 / 61 degrees, the pixel's
  angle) of `aurora keogram`'s brightest row;
- brightness: over the samples brighter than a tenth of the peak, the
  median of asilib's values over the median of `aurora keogram`'s at the
  same scan angles (interpolated between its 0.5 degree rows) within 1 %.
  A pixel averages its square (4 samples a pixel, jittered), the keogram
  samples its centre ray; on an arc 40 km wide, 10 or more pixels across,
  the two differ by the curvature over a pixel, well under 1 % in the
  median (measured below).
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np

import aurora

W = 61
# An arc 200 km long (east-west) and 40 km wide, drifting north 40 km over
# the sequence, on a near-vertical field with declination 0, over a camera
# on the ground at the origin looking straight up, north at the top.
SCENE = f"""seed = 5
[[curtain]]
center = [0.0, 30.0]
length = 200.0
width = 40.0
bend_km = 0.0
energy_flux = 5.0
char_energy_kev = 3.0
soft_fraction = 0.0
[footprint]
resolution = [64, 16]
uniform = true
[beams]
count = 6000
b_inclination_deg = 85.0
b_declination_deg = 0.0
[grid]
voxel_size = 2.0
density_a = 0.0
lines = ["5577"]
[photons]
radius_km = 2.0
[animation]
fps = 0.05
drift_km = 40.0
drift_period_s = 240.0
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, 1.0]
up = [0.0, 1.0, 0.0]
projection = "fisheye"
fov_deg = 180.0
[render]
width = {W}
height = {W}
spp = 4
[terrain]
kind = "none"
"""
ORIGIN = (65.12, -147.47)
FRAMES = [1, 2, 3]


def test_asilib_keogram_of_rendered_frames_matches_aurora_keogram(tmp_path):
    scene_file = tmp_path / "arc.toml"
    scene_file.write_text(SCENE)
    seq = tmp_path / "seq"
    s = aurora.Scene(str(scene_file))
    aurora.bake(s, seq, frames=FRAMES)
    assert sorted(p.name for p in seq.glob("aurora.*.vdb")) == ["aurora.0001.vdb", "aurora.0002.vdb", "aurora.0003.vdb"]
    sky = aurora.skymap(s, 110.0, origin=ORIGIN)
    t0 = dt.datetime(2026, 12, 7, 10, 0, 0)
    paths = []
    for f in FRAMES:
        img = aurora.render(s, seq, grid="line_5577", frame=f)
        assert img.units.startswith("R (rayleigh)")
        paths.append(aurora.write_frame(tmp_path / f"frame{f}.npz", img, t0 + dt.timedelta(seconds=s.frame_time(f)), sky))

    imager = aurora.asilib_imager(paths)
    times, lats, ak = imager.keogram()
    assert ak.shape[0] == len(FRAMES), f"asilib's keogram has {ak.shape[0]} times"
    # asilib's rows are the middle column's pixels above the horizon: their
    # scan angles from the skymap.
    col = W // 2
    mid_lat, mid_el, mid_az = sky["lat"][:, col], sky["el"][:, col], sky["az"][:, col]
    rows = [int(np.flatnonzero(np.isclose(mid_lat, la))[0]) for la in lats]
    north = np.abs(((mid_az[rows] + 180) % 360) - 180) < 90
    scan = np.where(north, mid_el[rows], 180.0 - mid_el[rows])
    assert np.all(np.diff(scan) > 0), "asilib's keogram rows run north to south"

    k = aurora.keogram(s, seq, FRAMES)
    row_deg = 180.0 / W
    ratios_a, ratios_k = [], []
    for j in range(len(FRAMES)):
        a_peak = scan[np.argmax(ak[j])]
        k_peak = k.scan_deg[np.argmax(k.values[:, j])]
        print(f"frame {FRAMES[j]}: brightest scan angle asilib {a_peak:.2f}, aurora keogram {k_peak:.2f} degrees")
        assert abs(a_peak - k_peak) <= row_deg, f"frame {FRAMES[j]}: {a_peak:.2f} vs {k_peak:.2f} degrees"
        at = np.interp(scan, k.scan_deg, k.values[:, j])
        bright = ak[j] > 0.1 * ak[j].max()
        ratios_a.extend(ak[j][bright])
        ratios_k.extend(at[bright])
    ma, mk = float(np.median(ratios_a)), float(np.median(ratios_k))
    print(f"median brightness of {len(ratios_a)} samples: asilib {ma:.1f} R, aurora keogram {mk:.1f} R, ratio {ma / mk:.4f}")
    assert mk > 100.0
    assert abs(ma / mk - 1) <= 0.01


def test_a_scene_with_a_site_maps_from_the_site():
    s = aurora.Scene("default")
    for k, v in {"camera.up": [0.0, 1.0, 0.0], "camera.projection": "fisheye", "camera.fov_deg": 180.0,
                 "camera.position": [0.0, 0.0, 0.0], "camera.look_at": [0.0, 0.0, 1.0], "render.width": 9,
                 "render.height": 9, "site": {"latitude_deg": 69.65, "longitude_deg": 18.96, "utc": "2026-12-07T22:00:00Z"}}.items():
        s.set(k, v)
    m = aurora.skymap(s, 110.0)
    assert m["origin"] == (69.65, 18.96)
    assert abs(m["lat"][4, 4] - 69.65) < 1e-9 and abs(m["lon"][4, 4] - 18.96) < 1e-9
