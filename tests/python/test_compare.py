"""tools/cycles/compare.py on synthetic images whose differences are known exactly."""

from __future__ import annotations

import json
import struct
import zlib

import numpy as np
import pytest

import synth


def image(h=30, w=40, seed=0):
    """A smooth positive image with a dim corner (below 1% of the peak)."""
    y, x = np.mgrid[0:h, 0:w]
    rgb = np.stack([1.0 + 0.5 * np.sin(x / 5.0), 2.0 + np.cos(y / 7.0), 0.5 + 0.01 * x], -1)
    rgb[:5, :5] = 1e-4  # dim: excluded from the relative error
    alpha = np.clip(0.2 + 0.01 * x, 0, 1)
    return np.dstack([rgb, alpha])


def test_uniform_gain(compare):
    a = image()
    b = a.copy()
    b[..., :3] *= 1.02
    b[..., 3] += 0.005
    m = compare.metrics(a, b)
    # |A - B| / ((A + B) / 2) = 0.02 / 1.01 on every bright pixel.
    assert m["mean_rel_err"] == pytest.approx(0.02 / 1.01, rel=1e-9)
    assert m["flux_ratio"] == pytest.approx(1 / 1.02, rel=1e-9)
    assert m["max_alpha_diff"] == pytest.approx(0.005, abs=1e-12)
    assert m["bright_pixels"] == 30 * 40 - 25


def test_dim_pixels_are_excluded_and_colour_errors_count(compare):
    a = image()
    b = a.copy()
    b[:5, :5, :3] *= 3.0  # huge relative error, but below 1% of the peak
    assert compare.metrics(a, b)["mean_rel_err"] == 0.0
    c = a.copy()
    c[..., 0], c[..., 2] = a[..., 2], a[..., 0]  # swap R and B: same luminance-ish sum, wrong colour
    m = compare.metrics(a, c)
    assert m["flux_ratio"] == pytest.approx(1.0)
    assert m["mean_rel_err"] > 0.1


def test_mask_figures(compare):
    a = image()
    b = a.copy()
    mask = np.zeros(a.shape[:2], bool)
    mask[20:, :] = True
    b[20:, :, :3] *= 1.10  # 10% only inside the mask
    m = compare.metrics(a, b, mask)
    assert m["mask_mean_rel_err"] == pytest.approx(0.10 / 1.05, rel=1e-9)
    assert m["mask_flux_ratio"] == pytest.approx(1 / 1.10, rel=1e-9)
    assert m["mask_pixels"] == 10 * 40
    n_bright = 30 * 40 - 25
    assert m["mean_rel_err"] == pytest.approx(0.10 / 1.05 * 400 / n_bright, rel=1e-9)


def test_cli_writes_json_and_a_readable_png(compare, cycles_render, tmp_path):
    a = image()
    b = a.copy()
    b[10:20, 10:20, :3] *= 0.9
    cycles_render.write_rgba_exr(tmp_path / "a.exr", a)
    cycles_render.write_rgba_exr(tmp_path / "b.exr", b)
    assert np.allclose(compare.read_rgba(tmp_path / "a.exr"), a.astype(np.float32))  # float32 round trip
    rc = compare.main([str(tmp_path / "a.exr"), str(tmp_path / "b.exr"), "--out", str(tmp_path / "d.png"),
                       "--json", str(tmp_path / "d.json")])
    assert rc == 0
    m = json.loads((tmp_path / "d.json").read_text())
    expected = compare.metrics(compare.read_rgba(tmp_path / "a.exr"), compare.read_rgba(tmp_path / "b.exr"))
    assert m["mean_rel_err"] == pytest.approx(expected["mean_rel_err"])
    # 100 pixels 10% dimmer: relative error 0.1 / 0.95 each.
    assert m["mean_rel_err"] == pytest.approx(100 * (0.1 / 0.95) / (30 * 40 - 25), rel=1e-5)
    png = (tmp_path / "d.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    w, h, depth, ctype = struct.unpack(">IIBB", png[16:26])
    assert (depth, ctype) == (8, 2)
    assert w > 3 * 40 * 8 and h > 30 * 8  # three tiles scaled up (small images are enlarged)
    # Decode the pixel data back (filter byte 0 on every row).
    idat = b"".join(png[i + 8:i + 8 + struct.unpack(">I", png[i:i + 4])[0]]
                    for i in _chunks(png, b"IDAT"))
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, 1 + 3 * w)
    assert np.all(raw[:, 0] == 0)
    assert compare.read_png(tmp_path / "d.png").shape == (h, w, 3)


def _chunks(png, tag):
    pos = 8
    while pos < len(png):
        n = struct.unpack(">I", png[pos:pos + 4])[0]
        if png[pos + 4:pos + 8] == tag:
            yield pos
        pos += 12 + n


def test_picture_puts_sign_and_scale_where_promised(compare):
    a = image()
    b = a.copy()
    b[10:20, 10:20, :3] *= 0.9  # A brighter than B there: positive (red)
    m = compare.metrics(a, b)
    pic = compare.make_picture(a, b, m, rel_range=0.2)
    scale = max(1, int(np.ceil(320 / 40)))
    x0 = 8 + 2 * (40 * scale + 8)  # third tile
    y0 = 14 + 8
    red = pic[y0 + 15 * scale, x0 + 15 * scale]
    white = pic[y0 + 25 * scale, x0 + 35 * scale]
    assert red[0] > 200 and red[2] < red[0] - 20
    assert np.all(white > 245)


def test_terrain_mask_matches_the_horizon(compare, tmp_path):
    """Camera 1.5 km up looking level: the plane z = 0 fills exactly the rows
    whose upper edge points below the horizon (row edge angle by pinhole geometry)."""
    cam = {"position": [0.0, 0.0, 1.5], "look_at": [0.0, 100.0, 1.5], "up": [0, 0, 1],
           "projection": "perspective", "fov_deg": 40.0}
    w, h = 16, 20
    scene = synth.write_scene(tmp_path / "m.toml", cam, w, h, terrain={"kind": "plane", "height": 0.0})
    mask = compare.terrain_mask(scene, w, h)
    # Row r's top edge is at screen y = 1 - 2 r / h; it points down when y < 0:
    # r > h / 2 (row h / 2 has its top edge on the horizon: not wholly terrain).
    expected_rows = np.arange(h) > h / 2
    assert np.array_equal(mask.all(axis=1), expected_rows)
    assert np.array_equal(mask.any(axis=1), expected_rows)
    assert mask.sum() == w * (h // 2 - 1)


def test_mask_png_round_trip(compare, tmp_path):
    m = np.zeros((12, 9), bool)
    m[3:7, 2:5] = True
    rgb = np.repeat((m * 255).astype(np.uint8)[..., None], 3, -1)
    compare.write_png(tmp_path / "m.png", rgb)
    assert np.array_equal(compare.read_mask(tmp_path / "m.png"), m)


def test_shape_mismatch_is_an_error(compare):
    with pytest.raises(ValueError):
        compare.metrics(image(30, 40), image(30, 41))
