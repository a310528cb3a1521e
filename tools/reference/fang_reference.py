#!/usr/bin/env python3
"""Writes data/fang_reference.csv: Fang et al. 2008 and 2010 energy
dissipation computed by `eppaurora` (PyPI), the oracle of src/physics/deposition/fang.rs's tests.

Columns: model, energy_kev, column_g_cm2, scale_height_cm, dissipation_per_cm
(energy dissipated per cm per unit incident energy flux, 1/cm: eppaurora's
en_diss with flux = 1 keV cm^-2 s^-1). Models:
- fang2010_mono: eppaurora.fang2010_mono (monoenergetic electrons);
- fang2008: eppaurora.fang2008 (Maxwellian, E = characteristic energy);
- fang2010_maxw: eppaurora.fang2010_maxw_int, Fang 2010 integrated over a
  Maxwellian, bounds 0.1-1000 keV, 2048 log-spaced energies.
rho is set to column / H, so eppaurora sees the column mass rho H exactly.
Rerun: `python tools/reference/fang_reference.py [OUT.csv]`.
"""
import io
import sys
from pathlib import Path

import numpy as np
import eppaurora

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402
from aurora_tools.files import write_atomic  # noqa: E402

H_CM = (6.0e5, 2.5e6)


def rows():
    out = []
    cols = np.logspace(-8, -1, 15)
    for e in (0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 1000.0):
        for h in H_CM:
            v = eppaurora.fang2010_mono(e, 1.0, h, cols / h)
            out += [("fang2010_mono", e, m, h, x) for m, x in zip(cols, np.ravel(v))]
    for e0 in (0.5, 1.0, 3.0, 10.0, 30.0):
        for h in H_CM:
            v = eppaurora.fang2008(e0, 1.0, h, cols / h)
            out += [("fang2008", e0, m, h, x) for m, x in zip(cols, np.ravel(v))]
    fine = np.logspace(-7, -1, 40)
    for e0 in (1.0, 3.0, 10.0, 30.0):
        h = H_CM[0]
        v = eppaurora.fang2010_maxw_int(e0, 1.0, h, fine / h, bounds=(0.1, 1000.0), nstep=2048)
        out += [("fang2010_maxw", e0, m, h, x) for m, x in zip(fine, np.ravel(v))]
    return out


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "data" / "fang_reference.csv")
    with io.StringIO() as f:
        f.write(f"# eppaurora {eppaurora.__version__}; made by tools/reference/fang_reference.py\n")
        f.write('# terms: numbers computed with eppaurora (GPL-2.0) from the published formulas of Fang et al. 2008 and 2010; used by the tests only, not compiled into aurora (NOTICE, docs/data.md)\n')
        f.write("model,energy_kev,column_g_cm2,scale_height_cm,dissipation_per_cm\n")
        for model, e, m, h, x in rows():
            f.write(f"{model},{e:g},{m:.17g},{h:.17g},{x:.17g}\n")
        write_atomic(path, f.getvalue().encode())
    print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
