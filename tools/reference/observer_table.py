#!/usr/bin/env python3
"""Writes the camera observer: data/observer_camera_inputs.csv (the spectra
it is made from, as colour-science ships them) and data/observer_camera.csv
(per nm, 380-780 nm, what a camera records of one unit of radiant power, in
linear Rec.709, beside the CIE 1931 2-degree table of the eye).

Camera: the Nikon D5100's spectral sensitivities measured at the National
Physical Laboratory, Darrodi, Finlayson, Goodman & Mackiewicz (2015),
"Reference data set for camera spectral sensitivity estimation", J. Opt.
Soc. Am. A 32, 381 (5 nm steps), as colour-science ships them
(`colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]`, BSD-3-Clause).

Processing, as a raw converter does it:
1. White balance for daylight D55 (CIE 15:2004): each channel divided by its
   response to the D55 spectrum, so a grey under D55 records equal RGB.
2. A 3x3 matrix from white-balanced camera RGB to linear Rec.709 (D65
   white), fitted by least squares on the 24 patches of the ColorChecker
   (BabelColor average reflectances, 380-730 nm every 10 nm) lit by D55:
   the targets are the patches' CIE 1931 XYZ under D55, adapted to D65 by
   the Bradford transform (white Y = 1), to linear Rec.709 (IEC 61966-2-1).
   The fit uses the 10 nm rows, where all spectra are given.
3. Per nm: the camera's 5 nm curves linear between rows, white balanced,
   through the matrix, scaled so that D55 light gives the same Y as the
   CIE 1931 observer's (the camera's table is then in the units of ybar).

The inputs' SHA-256, the package versions, the white balance, the matrix
and its fit residual are in the table's header; tests/python/test_observer_table.py
checks the committed table against the committed inputs without the package.
Rerun with `tools/observer_table` (it makes its own virtual environment).
"""
import hashlib
import sys
from pathlib import Path

import colour
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
CAMERA = "Nikon 5100 (NPL)"
CHECKER = "BabelColor Average"
CMFS = "CIE 1931 2 Degree Standard Observer"
STEP_NM = 5
LAMBDA = np.arange(380, 781, STEP_NM)
FIT_LAMBDA = np.arange(380, 731, 10)
# IEC 61966-2-1's XYZ to linear sRGB, as src/util/colour.rs prints it.
XYZ_TO_REC709 = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
BRADFORD = np.array([[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]])
D65_XYZ = np.array([0.95047, 1.0, 1.08883])


def fmt(x):
    return f"{x:.9g}"


def inputs_table():
    """The 5 nm rows of every input spectrum; the patches only on their 10 nm rows."""
    cam = colour.MSDS_CAMERA_SENSITIVITIES[CAMERA]
    d55 = colour.SDS_ILLUMINANTS["D55"]
    cmfs = colour.MSDS_CMFS[CMFS]
    checker = colour.SDS_COLOURCHECKERS[CHECKER]
    names = list(checker.keys())
    header = ["wavelength_nm", "camera_r", "camera_g", "camera_b", "d55", "xbar", "ybar", "zbar"] + [
        "patch_" + n.replace(" ", "_").replace("(", "").replace(")", "").replace(".", "") for n in names
    ]
    rows = []
    for lam in LAMBDA:
        row = [str(int(lam))] + [fmt(v) for v in cam[lam]] + [fmt(d55[lam])] + [fmt(v) for v in cmfs[lam]]
        in_checker = lam % 10 == 0 and lam <= 730
        row += [fmt(checker[n][lam]) if in_checker else "" for n in names]
        rows.append(row)
    return header, rows


def derive(header, rows):
    """White balance, matrix and per-nm table from the inputs' rows (the same
    arithmetic the test repeats)."""
    a = {h: np.array([float(r[i]) if r[i] else np.nan for r in rows]) for i, h in enumerate(header)}
    lam = a["wavelength_nm"]
    cam = np.stack([a["camera_r"], a["camera_g"], a["camera_b"]], axis=1)
    cmf = np.stack([a["xbar"], a["ybar"], a["zbar"]], axis=1)
    d55 = a["d55"]
    fit = np.isin(lam, FIT_LAMBDA)
    white = (d55[fit, None] * cam[fit]).sum(axis=0)
    patches = np.stack([a[h][fit] for h in header if h.startswith("patch_")], axis=0)
    raw = patches @ (d55[fit, None] * cam[fit]) / white
    xyz_white = (d55[fit, None] * cmf[fit]).sum(axis=0)
    xyz = patches @ (d55[fit, None] * cmf[fit]) / xyz_white[1]
    w55 = xyz_white / xyz_white[1]
    cone_src, cone_dst = BRADFORD @ w55, BRADFORD @ D65_XYZ
    adapt = np.linalg.inv(BRADFORD) @ np.diag(cone_dst / cone_src) @ BRADFORD
    target = xyz @ (XYZ_TO_REC709 @ adapt).T
    m_t, *_ = np.linalg.lstsq(raw, target, rcond=None)
    matrix = m_t.T
    resid = raw @ matrix.T - target
    rms = float(np.sqrt((resid**2).mean()))
    # Photometric scale: D55 light gives the eye's Y (5 nm sums over 380-780 nm).
    y_eye = float((d55 * cmf[:, 1]).sum())
    per_nm = np.arange(380, 781)
    cam_nm = np.stack([np.interp(per_nm, lam, cam[:, k]) for k in range(3)], axis=1)
    wb_full = (d55[:, None] * cam).sum(axis=0)
    rgb = (cam_nm / wb_full) @ matrix.T * y_eye
    return white, matrix, rms, per_nm, rgb


def main(out_dir):
    header, rows = inputs_table()
    inputs_text = "wavelength rows every 5 nm; patch columns on the 10 nm rows up to 730 nm\n"
    inputs_text = "# " + inputs_text + ",".join(header) + "\n" + "".join(",".join(r) + "\n" for r in rows)
    inputs_path = out_dir / "observer_camera_inputs.csv"
    white, matrix, rms, per_nm, rgb = derive(header, rows)
    sha = hashlib.sha256(inputs_text.encode()).hexdigest()
    cmfs = colour.MSDS_CMFS[CMFS]
    lines = [
        "# The camera observer: linear Rec.709 recorded per unit radiant power at each nm (camera_r/g/b,",
        "# in the units of ybar: D55 light gives the CIE 1931 observer's Y), beside the CIE 1931 2-degree table.",
        f"# camera: {CAMERA}, Darrodi et al. 2015, J. Opt. Soc. Am. A 32, 381 (NPL); terms: docs/data.md",
        f"# made by: tools/observer_table (tools/reference/observer_table.py), colour-science {colour.__version__}, numpy {np.__version__}",
        f"# inputs: observer_camera_inputs.csv sha256 {sha}",
        "# white balance: D55; camera response to D55 (10 nm sums, 380-730 nm): " + " ".join(fmt(v) for v in white),
        f"# matrix ({CHECKER} ColorChecker under D55, Bradford to D65, least squares): "
        + " ".join(fmt(v) for v in matrix.ravel()),
        f"# fit residual, rms over 24 patches x 3 channels, linear Rec.709: {rms:.6g}",
        "wavelength_nm,camera_r,camera_g,camera_b,xbar,ybar,zbar",
    ]
    for lam, c in zip(per_nm, rgb):
        e = cmfs[lam]
        lines.append(",".join([str(int(lam))] + [f"{v:.7g}" for v in c] + [f"{v:.7g}" for v in e]))
    for path, text in [(inputs_path, inputs_text), (out_dir / "observer_camera.csv", "\n".join(lines) + "\n")]:
        tmp = path.with_suffix(".csv.tmp")
        tmp.write_text(text)
        tmp.replace(path)
        print(f"wrote {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")
    print(f"fit residual rms {rms:.4g}; matrix rows " + "; ".join(" ".join(f"{v:.4f}" for v in r) for r in matrix))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "data")
