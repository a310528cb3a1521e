#!/usr/bin/env python3
"""Writes data/us1976.csv: the U.S. Standard Atmosphere 1976 that `aurora`
compiles in and uses by default (`[atmosphere] model = "us1976"`,
src/physics/atmosphere.rs).

The standard (NOAA, NASA, USAF, "U.S. Standard Atmosphere, 1976",
NOAA-S/T 76-1562, NASA-TM-X-74335) is a U.S. Government work: public
domain. It is computed here with the `ussa1976` package (PyPI, MIT licence),
which implements the standard's equations, 50-700 km every 0.5 km (the
NRLMSIS table's grid; the standard goes on to 1000 km).
Columns: altitude_km, rho_g_cm3 (total mass density), n2_cm3, o2_cm3, o_cm3
(number densities), temperature_k, ar_cm3, he_cm3, h_cm3. Six significant
digits. The standard defines atomic oxygen from 86 km only: below, the
exponential of its first two tabulated altitudes is continued down (flagged in the header); He and
Ar are defined throughout, H from 150 km (0 below, as the standard leaves it).

Rerun: `python tools/reference/ussa1976_table.py [OUT.csv]` in a Python with
`pip install ussa1976`.
"""
import sys
from pathlib import Path

import numpy as np
import ussa1976

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402
from aurora_tools.files import write_altitude_table  # noqa: E402

ALTITUDES = np.arange(50.0, 700.0 + 0.25, 0.5)
O_FROM_KM = 86.0


def table(altitudes=ALTITUDES):
    """Rows [alt km, rho g/cm^3, n(N2), n(O2), n(O) cm^-3, T K, n(Ar), n(He), n(H) cm^-3]."""
    ds = ussa1976.compute(z=altitudes * 1e3, variables=["t", "n", "rho"])
    n = {s: ds["n"].sel(s=s).values * 1e-6 for s in ("N2", "O2", "O", "Ar", "He", "H")}  # m^-3 -> cm^-3
    rho = ds["rho"].values * 1e-3  # kg/m^3 -> g/cm^3
    o = n["O"].copy()
    i0 = int(np.flatnonzero(o > 0)[0])  # the first altitude the package gives O at
    below = np.arange(len(o)) < i0
    slope = np.log(o[i0 + 1] / o[i0]) / (altitudes[i0 + 1] - altitudes[i0])
    o[below] = o[i0] * np.exp(slope * (altitudes[below] - altitudes[i0]))
    return np.column_stack([altitudes, rho, n["N2"], n["O2"], o, ds["t"].values, n["Ar"], n["He"], n["H"]])


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "data" / "us1976.csv")
    rows = table()
    assert np.all(np.isfinite(rows)) and np.all(rows[:, 1:6] > 0), "a non-positive density or temperature"
    write_altitude_table(path, [
        f"U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562) via ussa1976 {ussa1976.__version__}; "
        f"O below {O_FROM_KM:g} km extrapolated (the standard defines it from {O_FROM_KM:g} km), H 0 below 150 km; "
        "made by tools/reference/ussa1976_table.py",
        "terms: public domain (a work of the U.S. Government); the ussa1976 package is MIT-licensed",
    ], "altitude_km,rho_g_cm3,n2_cm3,o2_cm3,o_cm3,temperature_k,ar_cm3,he_cm3,h_cm3", rows)


if __name__ == "__main__":
    main()
