#!/usr/bin/env python3
"""Ionization profiles q(z) of Fang et al. (2010) against NCAR GLOW's
two-stream transport on the default atmosphere, and what a shape
correction of Fang's monoenergetic profile towards GLOW's would do.

Measures, per case (monoenergetic or Maxwellian electrons of E0 keV): the
peak altitude, the altitudes where q falls to half its peak below and above
it, the share of the column above the peak, the centroid, the share above
250 km, the fraction of the incident energy deposited (80-400 km), and the
normalised L1 distance between profiles (each normalised to sum 1 on 0.5
km bins from 80 to 400 km). Profiles:
- `fang`: Fang 2010 (monoenergetic, or integrated over the Maxwellian's
  energy-flux density Gamma(3, E0)), evaluated here in numpy on the column
  mass of data/nrlmsis21.csv (the same model as src/physics/deposition/fang.rs: its Maxwellian
  profiles are `aurora profile`'s to L1 0.003-0.01);
- `corr`: the same with `--corr S0,A0,EF,P`: in Fang's variable ln y every
  deposit of energy E moved to smaller y (higher) by S0 phi(E) plus an
  exponentially distributed amount of mean A0 phi(E), phi = 1 / (1 + (E /
  EF)^P); the kernel is a probability density, so the deposited total is
  unchanged;
- `glow`: GLOW 4.0.4 (tools/reference/glow_run.py in .venv-glow, nightglow subtracted);
- `aurora`: `aurora profile` of the single uniform curtain of
  tests/python/test_glow.py (with --aurora; Maxwellian cases);
- `fang08`: Fang et al. 2008's Maxwellian fit (eppaurora; Maxwellian cases).

Run in .venv (numpy, eppaurora, pymsis), with GLOW's venv beside it:
    .venv/bin/python tools/reference/deposition_glow.py [--mono] [--aurora] [--corr 0,0.15,1.5,3] [--e0 0.5 1 2]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import eppaurora.electrons
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402

KEV_PER_ION_PAIR = 0.035
KEV_PER_ERG = 6.241509074e8
Z = np.arange(80.25, 400.0, 0.5)  # bin centres, km

#: Fang et al. (2010), Table 1: P_ij, i = 1..8 (rows), j = 0..3 (columns), as eppaurora holds it.
P_2010 = np.array(eppaurora.electrons.POLY_F2010)


def atmosphere():
    """Altitude (km), density and column mass (g cm^-2) of the default
    atmosphere: piecewise exponential between the table's nodes, as
    src/physics/atmosphere.rs integrates it."""
    rows = [r for r in open(ROOT / "data" / "nrlmsis21.csv") if not r.startswith("#")]
    rd = list(csv.DictReader(rows))
    h = np.array([float(r["altitude_km"]) for r in rd])
    rho = np.array([float(r["rho_g_cm3"]) for r in rd])
    sh = np.diff(h) / np.log(rho[:-1] / rho[1:]) * 1e5  # cm
    col = np.zeros(len(h))
    col[-1] = rho[-1] * sh[-1]
    for i in range(len(h) - 2, -1, -1):
        col[i] = col[i + 1] + sh[i] * (rho[i] - rho[i + 1])
    return h, rho, col


H_TAB, RHO_TAB, COL_TAB = atmosphere()


def column(z):
    return np.exp(np.interp(z, H_TAB, np.log(COL_TAB)))


def coefficients(e):
    x = np.log(np.clip(e, 0.1, 1000.0))
    return np.exp(P_2010[:, 0] + x * (P_2010[:, 1] + x * (P_2010[:, 2] + x * P_2010[:, 3])))


def f_of_y(c, y):
    return c[0] * y ** c[1] * np.exp(-c[2] * y ** c[3]) + c[4] * y ** c[5] * np.exp(-c[6] * y ** c[7])


def shape(e, k):
    """Shift and exponential-kernel mean, in ln y, of the correction at
    energy `e` keV (both fade as 1 / (1 + (E / E_fade)^p))."""
    if not k:
        return 0.0, 0.0
    fade = 1.0 / (1.0 + (e / k["E_FADE_KEV"]) ** k["FADE_POWER"])
    return k["SHIFT_0"] * fade, k["SKEW_0"] * fade


LNY = np.arange(-12.0, 5.0 + 1e-9, 0.02)


def mono_cumulative(e, k=None):
    """D_E on the ln y grid (fraction deposited above), with the correction
    `k` applied: D'(ln y) = int_0^inf D(ln y + s + u) exp(-u / a) / a du
    (shifted by s and smeared by an exponential of mean a towards small y,
    that is to higher altitudes; D(inf) is unchanged)."""
    c = coefficients(e)
    f = f_of_y(c, np.exp(LNY))
    d = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * 0.02)]) / 0.7
    s, a = shape(e, k)
    if s == 0.0 and a == 0.0:
        return d
    if a <= 1e-9:
        return np.interp(LNY + s, LNY, d)
    u = np.arange(0.0, 30.0 * a, 0.01)
    w = np.exp(-u / a)
    w[0] *= 0.5
    w /= w.sum()
    out = np.zeros_like(d)
    for ui, wi in zip(u, w):
        out += wi * np.interp(LNY + s + ui, LNY, d)
    return out


def mono_q(e, k=None, z=Z):
    """Ionization per unit energy flux (ion pairs cm^-3 s^-1 per keV cm^-2 s^-1)
    on 0.5 km bins centred on `z`, from the difference of D across each bin."""
    d = mono_cumulative(e, k)
    def dd(zz):
        ly = np.log(2.0 / e * (column(zz) / 6e-6) ** 0.7)
        return np.interp(ly, LNY, d, left=0.0, right=d[-1])
    return (dd(z - 0.25) - dd(z + 0.25)) / 0.5e5 / KEV_PER_ION_PAIR


def maxwellian_q(e0, k=None, z=Z):
    x = np.linspace(0.1, 45.0, 450)
    w = 0.5 * x * x * np.exp(-x)
    w /= w.sum()
    return sum(wi * mono_q(xi * e0, k, z) for xi, wi in zip(x, w))


def glow(e0, mono, q=1.0):
    py = Path(os.environ.get("AURORA_GLOW_PYTHON", ROOT / ".venv-glow" / "bin" / "python"))
    cmd = [str(py), str(ROOT / "tools" / "reference" / "glow_run.py"), "--e0", str(e0), "--q", str(q), "--json"] + (["--mono"] if mono else [])
    g = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    zg, ion = np.array(g["alt_km"]), np.array(g["rates"]["ionization"])
    return np.interp(Z, zg, ion, left=0.0, right=0.0) / (q * KEV_PER_ERG), g


def aurora(e0, q=1.0):
    sys.path.insert(0, str(ROOT / "tests" / "python"))
    from test_glow import aurora as profile  # `aurora profile` of the GLOW test's own scene
    p = profile(e0, q)
    return np.interp(Z, p["altitude_km"], p["ionization"], left=0.0, right=0.0)


def fang2008(e0):
    sys.path.insert(0, str(ROOT / "tests" / "python"))
    from test_profile import fang2008_on_msis
    return fang2008_on_msis(Z, e0)


def stats(q):
    i = int(q.argmax())
    half = q >= 0.5 * q[i]
    lo = Z[np.argmax(half)]
    hi = Z[len(Z) - 1 - np.argmax(half[::-1])]
    n = q / q.sum()
    return dict(peak=Z[i], lo=lo, hi=hi, above=float(n[i + 1:].sum()), centroid=float((Z * n).sum()), a250=float(n[Z > 250].sum()))


def l1(a, b):
    return float(np.abs(a / a.sum() - b / b.sum()).sum())


def report(e0, mono, with_aurora, k):
    g, raw = glow(e0, mono)
    profiles = {"glow": g, "fang": (mono_q if mono else maxwellian_q)(e0)}
    if k:
        profiles["corr"] = (mono_q if mono else maxwellian_q)(e0, k)
    if not mono:
        profiles["fang08"] = fang2008(e0)
        if with_aurora:
            profiles["aurora"] = aurora(e0)
    kind = "mono" if mono else "maxw"
    for name, q in profiles.items():
        s = stats(q)
        # Deposited share of the incident flux: only for profiles per unit flux.
        tot = f" deposited {q.sum() * 0.5e5 * KEV_PER_ION_PAIR:.3f}" if name in ("glow", "fang", "corr") else ""
        extra = f" L1 vs glow {l1(q, g):.3f}" + (f" vs fang08 {l1(q, profiles['fang08']):.3f}" if "fang08" in profiles else "")
        print(f"{kind} E {e0:5.2f} {name:7s} peak {s['peak']:6.2f} half-max {s['lo']:6.2f}-{s['hi']:6.2f} "
              f"(-{s['peak'] - s['lo']:.2f}/+{s['hi'] - s['peak']:.2f}) above-peak {s['above']:.3f} "
              f"centroid {s['centroid']:6.2f} >250 {s['a250']:.4f}{tot}{extra}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--e0", type=float, nargs="*", default=[0.5, 0.7, 1.0, 1.5, 2.0, 3.0])
    ap.add_argument("--mono", action="store_true", help="monoenergetic electrons instead of Maxwellians")
    ap.add_argument("--aurora", action="store_true", help="also run `aurora profile` (AURORA_BIN)")
    ap.add_argument("--corr", help="S0,A0,EF,P: also print Fang 2010 with this shape correction")
    a = ap.parse_args()
    k = None
    if a.corr:
        s0, a0, ef, p = (float(v) for v in a.corr.split(","))
        k = dict(SHIFT_0=s0, SKEW_0=a0, E_FADE_KEV=ef, FADE_POWER=p)
    for e in a.e0:
        report(e, a.mono, a.aurora, k)
    return 0


if __name__ == "__main__":
    sys.exit(main())
