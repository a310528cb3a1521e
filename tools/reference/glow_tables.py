#!/usr/bin/env python3
"""Writes the two tables the emission chemistry takes from NCAR GLOW
(Solomon 2017; `glowpython` 4.0.4, run in its own venv):

- data/ionosphere.csv: the ambient (IRI) night-time ionosphere GLOW keeps at
  the place and time of data/nrlmsis21.csv (67 N, 20 E, 2020-01-15 00:00 UT,
  F10.7 = F10.7a = F10.7p = 150, Ap = 15): per GLOW altitude, the electron
  temperature Te, the ion temperature Ti, the electron density and the NO
  density (GLOW's empirical NO, the Marsh et al. 2004 NOEM model; the same
  with and without precipitation) of the GLOW call without precipitation
  (`glowpython.no_precipitation`). src/physics/chemistry/ambient.rs reads it.
- tests/data/glow_chemistry.csv: GLOW's own auroral runs
  (`glowpython.maxwellian`, E0 = 1, 3, 10 keV, Q = 1 and 10 erg cm^-2 s^-1)
  with their ionization rate, neutral densities, temperatures and the
  volume emission rates of 427.8, 557.7 and 630.0 nm, the nightglow (the
  run without precipitation) subtracted: the fixture of the chemistry's
  oracle test (tests/physics/chemistry.rs), which drives our chemistry with
  GLOW's q(z) and densities.

Rerun: `python tools/reference/glow_tables.py` with a Python that has glowpython
4.0.4 and numpy 1.26 (see tools/setup).
"""
import datetime
import io
import sys
from pathlib import Path

import glowpython
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402
from aurora_tools.files import write_atomic  # noqa: E402

TIME = datetime.datetime(2020, 1, 15, 0, 0)
LAT, LON = 67.0, 20.0
GEOMAG = dict(f107a=150.0, f107=150.0, f107p=150.0, Ap=15.0)
NBINS = 250
CASES = [(e0, q) for e0 in (1.0, 3.0, 10.0) for q in (1.0, 10.0)]


def header():
    return (f"# NCAR GLOW via glowpython {glowpython.__version__ if hasattr(glowpython, '__version__') else '4.0.4'}: "
            f"{LAT} N, {LON} E, {TIME.isoformat()} UT, F10.7 = F10.7a = F10.7p = 150, Ap = 15; made by tools/reference/glow_tables.py\n")


def main():
    night = glowpython.no_precipitation(TIME, LAT, LON, NBINS, geomag_params=GEOMAG)
    z = night.alt_km.values.astype(float)
    with io.StringIO() as f:
        f.write(header().rstrip("\n") + "; ambient ionosphere (IRI above 200 km, GLOW's chemistry below), no precipitation\n")
        f.write('# terms: NCAR GLOW Open Source Academic Research License (UCAR): research, academic and non-profit use; no sale; derivative works open source (NOTICE, docs/data.md); not compiled into aurora\n')
        f.write("altitude_km,te_k,ti_k,ne_cm3,no_cm3\n")
        for i in range(len(z)):
            # GLOW leaves the lowest levels undefined (NaN): rows start where
            # every value is finite (the chemistry holds the first row below).
            if not all(np.isfinite(float(x)) and float(x) > 0 for x in (night.Te[i], night.Ti[i], night.NeOut[i], night.NO[i])):
                continue
            f.write(f"{z[i]:.3f},{float(night.Te[i]):.6g},{float(night.Ti[i]):.6g},{float(night.NeOut[i]):.6g},{float(night.NO[i]):.6g}\n")
        write_atomic(str(ROOT / "data" / "ionosphere.csv"), f.getvalue().encode())
    ver0 = night.ver
    with io.StringIO() as f:
        f.write(header().rstrip("\n") + "; Maxwellian, ver minus the run without precipitation (nightglow)\n")
        f.write("e0_kev,q_erg_cm2_s,altitude_km,ionrate_cm3_s,n2_cm3,o2_cm3,o_cm3,no_cm3,n4s_cm3,tn_k,te_k,ne_cm3,"
                "ver_4278,ver_5577,ver_6300\n")
        for e0, q in CASES:
            a = glowpython.maxwellian(TIME, LAT, LON, NBINS, q, e0 * 1e3, geomag_params=GEOMAG)
            ver = {w: (a.ver.sel(wavelength=w) - ver0.sel(wavelength=w)).values for w in ("4278", "5577", "6300")}
            for i in range(len(z)):
                row = [e0, q, z[i], a.ionrate[i], a.N2[i], a.O2[i], a.O[i], a.NO[i], a.NS[i], a.Tn[i], a.Te[i], a.NeOut[i],
                       ver["4278"][i], ver["5577"][i], ver["6300"][i]]
                # From 80 km up, where GLOW defines every quantity.
                if z[i] < 80.0 or not all(np.isfinite(float(x)) for x in row):
                    continue
                f.write(",".join(f"{float(x):.6g}" for x in row) + "\n")
        write_atomic(str(ROOT / "tests" / "data" / "glow_chemistry.csv"), f.getvalue().encode())
    print("wrote data/ionosphere.csv and tests/data/glow_chemistry.csv", file=sys.stderr)


if __name__ == "__main__":
    main()
