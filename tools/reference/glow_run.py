#!/usr/bin/env python3
"""NCAR GLOW (glowpython 4.0.4) as the oracle of `aurora profile`: altitude
profiles of the ionization rate and of the auroral lines' volume emission
rates for a Maxwellian of characteristic energy E0 and energy flux Q, at the
place and time of the default atmosphere (data/nrlmsis21.csv: 67 N, 20 E,
2020-01-15 00:00 UT, F10.7 = F10.7a = F10.7p = 150, Ap = 15).

GLOW (Solomon 2017, doi 10.5065/D6VQ30PC; Solomon, Hays & Abreu 1988, J.
Geophys. Res. 93, 9867) solves two-stream electron transport, the ion
chemistry and the excited-state balances on MSIS and IRI. Its ambient
ionosphere glows on its own (about 23 R of 630.0 nm, 3 R of 557.7 nm), so
the same call without precipitation (`glowpython.no_precipitation`) is
subtracted from every rate: what remains is the aurora's.

Lines: 427.8 nm (N2+ 1N 0-1), 557.7 nm (O(1S)), 630.0 nm (O(1D), 630.0 alone;
GLOW computes no 636.4 nm, so none is reported). Units: ionization in ion
pairs cm^-3 s^-1, volume emission rates in photons cm^-3 s^-1, columns
(integral over altitude, trapezoid on GLOW's grid) in ion pairs cm^-2 s^-1
and rayleigh (1 R = 1e6 photons cm^-2 s^-1 column).

NaNs: GLOW leaves its lowest levels (60-72 km, where it does not solve the
chemistry) as NaN in `ionrate` and `ver`, in both calls. Those levels are
dropped (listed in `dropped_km`); a NaN above `NAN_FLOOR_KM`, where a
Maxwellian of up to 30 keV deposits energy, is an error, not a zero.

Run in .venv-glow (tools/setup makes it):
    .venv-glow/bin/python tools/reference/glow_run.py --e0 3 --q 1 [--mono] [--csv out.csv] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
from datetime import datetime

import numpy as np

TIME = datetime(2020, 1, 15, 0, 0)
GLAT, GLON = 67.0, 20.0
GEOMAG = dict(f107a=150.0, f107=150.0, f107p=150.0, Ap=15.0)
NBINS = 250
LINES = {"n2p_4278": "4278", "oi_5577": "5577", "oi_6300": "6300"}
NAN_FLOOR_KM = 75.0
# Energy per erg, keV; 1 R per erg cm^-2 s^-1 = 1.602e-3 photons per keV.
KEV_PER_ERG = 6.241509e8


def _column(z_km: np.ndarray, rate: np.ndarray) -> float:
    """Integral over altitude, per cm^2 (trapezoid on GLOW's own grid)."""
    return float(np.sum(0.5 * (rate[1:] + rate[:-1]) * np.diff(z_km)) * 1e5)


def run(e0_kev: float, q_erg: float, mono: bool = False) -> dict:
    """GLOW's aurora (precipitation minus nightglow) for a Maxwellian of
    characteristic energy `e0_kev` and energy flux `q_erg` erg cm^-2 s^-1,
    or (`mono`) for electrons of the one energy `e0_kev`."""
    import glowpython

    if mono:
        aur = glowpython.monoenergetic(TIME, GLAT, GLON, NBINS, q_erg, e0_kev * 1e3, geomag_params=GEOMAG)
    else:
        aur = glowpython.maxwellian(TIME, GLAT, GLON, NBINS, q_erg, e0_kev * 1e3, geomag_params=GEOMAG)
    quiet = glowpython.no_precipitation(TIME, GLAT, GLON, NBINS, geomag_params=GEOMAG)
    z = aur.alt_km.values.astype(float)
    if not np.allclose(z, quiet.alt_km.values):
        raise RuntimeError("GLOW: the two calls have different altitude grids")

    def field(ds, name, wl=None):
        a = ds[name].sel(wavelength=wl).values if wl else ds[name].values
        return a.astype(float)

    rates = {"ionization": field(aur, "ionrate") - field(quiet, "ionrate")}
    for key, wl in LINES.items():
        rates[key] = field(aur, "ver", wl) - field(quiet, "ver", wl)
    bad = np.zeros(len(z), bool)
    for r in rates.values():
        bad |= ~np.isfinite(r)
    if np.any(bad & (z > NAN_FLOOR_KM)):
        raise RuntimeError(f"GLOW: NaN above {NAN_FLOOR_KM} km at {z[bad & (z > NAN_FLOOR_KM)]}")
    keep = ~bad
    z = z[keep]
    rates = {k: v[keep] for k, v in rates.items()}
    cols = {k: _column(z, v) for k, v in rates.items()}
    # Energy GLOW deposits: the electron-impact heating plus what ionization
    # and excitation took is not an output; report the incident flux instead.
    return {
        "e0_kev": e0_kev,
        "spectrum": "monoenergetic" if mono else "maxwellian",
        "q_erg_cm2_s": q_erg,
        "incident_kev_cm2_s": q_erg * KEV_PER_ERG,
        "dropped_km": [float(v) for v in aur.alt_km.values[bad]],
        "alt_km": z.tolist(),
        "rates": {k: v.tolist() for k, v in rates.items()},
        # Ion pairs cm^-2 s^-1 and photons cm^-2 s^-1 (rayleigh = / 1e6).
        "columns": cols,
        "rayleigh": {k: cols[k] / 1e6 for k in LINES},
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--e0", type=float, required=True, help="characteristic energy, keV")
    ap.add_argument("--q", type=float, default=1.0, help="energy flux, erg cm^-2 s^-1")
    ap.add_argument("--mono", action="store_true", help="monoenergetic electrons of energy --e0 instead of a Maxwellian")
    ap.add_argument("--csv", help="write the altitude profile here")
    ap.add_argument("--json", action="store_true", help="print everything as JSON on stdout")
    a = ap.parse_args(argv)
    r = run(a.e0, a.q, a.mono)
    if a.csv:
        keys = list(r["rates"])
        with open(a.csv, "w") as f:
            f.write("altitude_km," + ",".join(keys) + "\n")
            for i, z in enumerate(r["alt_km"]):
                f.write(f"{z:.4f}," + ",".join(f"{r['rates'][k][i]:.6e}" for k in keys) + "\n")
    if a.json:
        json.dump(r, sys.stdout)
        print()
    else:
        c, ray = r["columns"], r["rayleigh"]
        print(f"GLOW, Maxwellian E0 {a.e0} keV, Q {a.q} erg cm^-2 s^-1 (nightglow subtracted)")
        print(f"  ionization column {c['ionization']:.4e} cm^-2 s^-1")
        for k in LINES:
            print(f"  {k}: {ray[k]:.2f} R ({ray[k] / a.q:.1f} R/erg), {c[k] / c['ionization']:.4f} photons per ion pair")
        print(f"  557.7/427.8 {c['oi_5577'] / c['n2p_4278']:.3f}, 630.0/427.8 {c['oi_6300'] / c['n2p_4278']:.3f}")
        print(f"  dropped (NaN in GLOW) {len(r['dropped_km'])} levels below {NAN_FLOOR_KM} km")
    return 0


if __name__ == "__main__":
    sys.exit(main())
