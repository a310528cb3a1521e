"""The camera observer's committed table (data/observer_camera.csv) is what
tools/observer_table makes of its committed inputs
(data/observer_camera_inputs.csv), checked without colour-science or the
network: the inputs' SHA-256 in the header, the D55 white balance, the
ColorChecker matrix refitted by least squares and its residual, and every
per-nm row, recomputed here with numpy from the inputs."""

import hashlib

import numpy as np

from conftest import ROOT

DATA = ROOT / "data"
XYZ_TO_REC709 = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
BRADFORD = np.array([[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]])
D65_XYZ = np.array([0.95047, 1.0, 1.08883])


def header_and_rows(path):
    lines = path.read_text().splitlines()
    comments = [line[2:] for line in lines if line.startswith("# ")]
    body = [line for line in lines if not line.startswith("#")]
    names = body[0].split(",")
    rows = [[float(v) if v else np.nan for v in line.split(",")] for line in body[1:]]
    return comments, names, np.array(rows)


def header_value(comments, key):
    line = next(c for c in comments if c.startswith(key))
    return line.split(":", 1)[1].split()


def inputs():
    _, names, a = header_and_rows(DATA / "observer_camera_inputs.csv")
    col = {n: a[:, i] for i, n in enumerate(names)}
    lam = col["wavelength_nm"]
    cam = np.stack([col["camera_r"], col["camera_g"], col["camera_b"]], axis=1)
    cmf = np.stack([col["xbar"], col["ybar"], col["zbar"]], axis=1)
    patches = np.stack([col[n] for n in names if n.startswith("patch_")], axis=0)
    return lam, cam, col["d55"], cmf, patches


def test_the_header_names_the_inputs_by_their_hash():
    comments, _, _ = header_and_rows(DATA / "observer_camera.csv")
    want = header_value(comments, "inputs")[-1]
    got = hashlib.sha256((DATA / "observer_camera_inputs.csv").read_bytes()).hexdigest()
    assert got == want
    made = next(c for c in comments if c.startswith("made by"))
    assert "colour-science 0.4.7" in made


def test_the_matrix_is_the_least_squares_fit_on_the_colorchecker_and_fits_it():
    comments, _, _ = header_and_rows(DATA / "observer_camera.csv")
    lam, cam, d55, cmf, patches = inputs()
    fit = (lam % 10 == 0) & (lam <= 730)
    assert fit.sum() == 36 and patches.shape[0] == 24 and not np.isnan(patches[:, fit]).any()
    white = (d55[fit, None] * cam[fit]).sum(axis=0)
    raw = patches[:, fit] @ (d55[fit, None] * cam[fit]) / white
    xyz_white = (d55[fit, None] * cmf[fit]).sum(axis=0)
    xyz = patches[:, fit] @ (d55[fit, None] * cmf[fit]) / xyz_white[1]
    adapt = np.linalg.inv(BRADFORD) @ np.diag((BRADFORD @ D65_XYZ) / (BRADFORD @ (xyz_white / xyz_white[1]))) @ BRADFORD
    target = xyz @ (XYZ_TO_REC709 @ adapt).T
    m = np.linalg.lstsq(raw, target, rcond=None)[0].T
    committed = np.array([float(v) for v in header_value(comments, "matrix")[-9:]]).reshape(3, 3)
    # Written with 9 significant digits.
    np.testing.assert_allclose(m, committed, rtol=0, atol=1e-8)
    np.testing.assert_allclose(white, [float(v) for v in header_value(comments, "white balance")[-3:]], rtol=1e-8)
    rms = float(np.sqrt(((raw @ m.T - target) ** 2).mean()))
    assert abs(rms - float(header_value(comments, "fit residual")[-1])) < 1e-6
    # A 3x3 matrix reaches the patches' linear Rec.709 to about 1 % of white
    # (rms 0.0087): the camera is close to colorimetric on surface colours.
    assert rms < 0.015
    # White balanced, a grey stays grey: the rows sum to about 1.
    np.testing.assert_allclose(m.sum(axis=1), 1.0, atol=0.03)


def test_every_row_of_the_table_is_recomputed_from_the_inputs():
    comments, names, table = header_and_rows(DATA / "observer_camera.csv")
    assert names == ["wavelength_nm", "camera_r", "camera_g", "camera_b", "xbar", "ybar", "zbar"]
    lam, cam, d55, cmf, _ = inputs()
    m = np.array([float(v) for v in header_value(comments, "matrix")[-9:]]).reshape(3, 3)
    per_nm = np.arange(380, 781)
    np.testing.assert_array_equal(table[:, 0], per_nm)
    cam_nm = np.stack([np.interp(per_nm, lam, cam[:, k]) for k in range(3)], axis=1)
    rgb = (cam_nm / (d55[:, None] * cam).sum(axis=0)) @ m.T * (d55 * cmf[:, 1]).sum()
    # 7 significant digits written (values up to 2: 1e-7), and the header's
    # 9-digit matrix: within 1e-6 of the table's largest value.
    np.testing.assert_allclose(table[:, 1:4], rgb, rtol=0, atol=1e-6 * np.abs(table[:, 1:4]).max())
    on5 = np.isin(per_nm, lam)
    np.testing.assert_allclose(table[on5, 4:7], cmf, rtol=1e-6, atol=1e-9)
    # The camera sees 557.7 nm green (red and blue negative out of the
    # matrix), 630 nm red.
    g = table[per_nm == 558, 1:4][0]
    assert g[1] > 0 > g[0] and g[2] < 0
    r = table[per_nm == 630, 1:4][0]
    assert r[0] > 10 * abs(r[1]) and r[0] > 10 * abs(r[2])
