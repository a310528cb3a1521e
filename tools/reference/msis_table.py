#!/usr/bin/env python3
"""Writes data/nrlmsis21.csv: the NRLMSIS 2.1 atmosphere that `aurora` uses by
default (`[atmosphere] model = "nrlmsis21"`, src/physics/atmosphere.rs).

An auroral-zone winter night: 67 N, 20 E, 2020-01-15 00:00 UT,
F10.7 = F10.7a = 150 sfu, Ap = 15 (all seven Ap slots), 50-700 km every 0.5 km.
Columns: altitude_km, rho_g_cm3 (total mass density), n2_cm3, o2_cm3, o_cm3
(number densities), temperature_k, then n4s_cm3 (ground-state atomic
nitrogen N(4S)) and no_cm3 (nitric oxide, NRLMSIS 2.1's new NO model), which
the emission chemistry (src/physics/chemistry/) needs. Six significant digits.

Model: Emmert et al. 2022, "NRLMSIS 2.1: an empirical model of nitric oxide
incorporated into MSIS", J. Geophys. Res. Space Physics 127; run through the
`pymsis` package (PyPI). Rerun: `python tools/reference/msis_table.py [OUT.csv]`.
"""
import sys
from pathlib import Path

import numpy as np
import pymsis

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402
from aurora_tools.files import write_altitude_table  # noqa: E402

LAT, LON = 67.0, 20.0
DATE = np.datetime64("2020-01-15T00:00")
F107 = F107A = 150.0
AP = 15.0
ALTITUDES = np.arange(50.0, 700.0 + 0.25, 0.5)


def table(altitudes=ALTITUDES):
    """Rows [alt km, rho g/cm^3, n(N2), n(O2), n(O) cm^-3, T K, n(N), n(NO) cm^-3]."""
    out = pymsis.calculate(
        np.full(len(altitudes), DATE), np.full(len(altitudes), LON), np.full(len(altitudes), LAT),
        altitudes, np.full(len(altitudes), F107), np.full(len(altitudes), F107A),
        np.full((len(altitudes), 7), AP), version=2.1)
    out = np.asarray(out).reshape(len(altitudes), -1)
    v = pymsis.Variable
    rho = out[:, v.MASS_DENSITY] * 1e-3  # kg/m^3 -> g/cm^3
    n = [out[:, s] * 1e-6 for s in (v.N2, v.O2, v.O)]  # m^-3 -> cm^-3
    minor = [out[:, s] * 1e-6 for s in (v.N, v.NO)]
    rows = np.column_stack([altitudes, rho, *n, out[:, v.TEMPERATURE], *minor])
    # NRLMSIS leaves atomic oxygen undefined (NaN) at its 50 km boundary:
    # extend the next two rows' exponential down to it (flagged in the header).
    # The same for N(4S) and NO where undefined.
    for k in (4, 6, 7):
        o = rows[:, k]
        for i in np.flatnonzero(~np.isfinite(o))[::-1]:
            o[i] = o[i + 1] * (o[i + 1] / o[i + 2]) ** ((altitudes[i + 1] - altitudes[i]) / (altitudes[i + 2] - altitudes[i + 1]))
    return rows


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "data" / "nrlmsis21.csv")
    rows = table()
    assert np.all(np.isfinite(rows)) and np.all(rows[:, 1:] > 0), "NRLMSIS returned a non-positive value"
    write_altitude_table(path, [
        f"NRLMSIS 2.1 via pymsis {pymsis.__version__}: {LAT} N, {LON} E, {DATE} UT, "
        f"F10.7 = F10.7a = {F107}, Ap = {AP}; "
        f"O (and N, NO where undefined) at 50 km extrapolated (NRLMSIS leaves them undefined there); made by tools/reference/msis_table.py",
        "terms: NRLMSIS 2.1 (MSIS, NRL-SOF-014-1): research, academic and non-profit use only; commercial use needs the U.S. Naval Research Laboratory's written consent (NOTICE, docs/data.md); not compiled into aurora",
    ], "altitude_km,rho_g_cm3,n2_cm3,o2_cm3,o_cm3,temperature_k,n4s_cm3,no_cm3", rows)


if __name__ == "__main__":
    main()
