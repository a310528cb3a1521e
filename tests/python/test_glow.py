"""`aurora profile` against NCAR GLOW, the field's standard open model of
auroral emission (glowpython 4.0.4, run by tools/reference/glow_run.py in .venv-glow,
which tools/setup makes; GLOW missing is a failure, never a skip).

Cases: single curtains with a Maxwellian of E0 keV and energy flux Q
erg cm^-2 s^-1, no soft component, on a uniform footprint
(`footprint.uniform = true`: every beam carries Q, as GLOW's one column
does), on the data the chemistry was validated on, selected explicitly
(`[atmosphere] model = "nrlmsis21"`, `ionosphere = "glow"`: NRLMSIS 2.1 at
67 N, 20 E, 2020-01-15 00:00 UT, F10.7 = 150, Ap = 15, and GLOW's ambient
ionosphere and NO; GLOW's run uses the same place, time and indices).
AURORA_VALIDATE_ON=default runs them on the compiled-in default instead,
to measure it (docs/data.md). GLOW's ambient ionosphere glows on its own; its nightglow run is
subtracted (tools/reference/glow_run.py). E0 = 1, 3, 10 keV at Q = 1 and 10, plus
0.5 / 1, 2 / 5, 5 / 20 and 7 / 2.

Targets (column totals: aurora's summed over its 0.5 km bins, GLOW's
integrated over altitude; the curtain's area cancels in every ratio):
- 427.8 nm photons per ion pair within 15% of GLOW's (both count ion
  pairs the same way: GLOW's `ionrate`, ours deposited power / 35 eV);
- 557.7 / 427.8 within 15%;
- 630.0 / 427.8 within 25% for E0 <= 2.5 keV, 40% above (the red column
  is a few per cent of the green at 3-10 keV and rides on the deposition's
  tail above 200 km, GLOW's least certain part: its electron density comes
  from IRI above 200 km);
- the 557.7 nm volume emission profile's shape (each normalised to sum 1
  on aurora's 0.5 km bins, GLOW interpolated linearly onto their centres)
  within L1 0.2;
- the 630.0 nm centroid within 20 km. GLOW's 630.0 nm profile has a step
  at 200 km (its electron density switches to IRI there), left as it is:
  the centroid, a column-weighted mean, is barely moved by it, a peak
  would be.
- the ionization profile (report, and bounds a regression would break):
  peak within 3 km of GLOW's for E0 >= 1 keV (measured 1-2.5 km, ours
  lower), at 0.5 keV where GLOW is within 10 % of its flat peak; normalised
  L1 within 0.25 (measured 0.14-0.16). Fang et al. (2008, 2010) fitted
  their parameterisations to their own multi-stream transport runs; GLOW's
  two-stream transport (Banks & Nagy) differs from them by that much, most
  at low energies, where GLOW also reflects more (deposits 0.80-0.92 of the
  incident energy, Fang 0.94-0.99). Below a few keV the deposition's upper
  side is stretched towards GLOW's (src/physics/deposition/glow_calibration.rs), its peak kept at
  Fang 2008's (tests/python/test_profile.py). The tail is checked
  separately: the share of the ionization above 250 km within 30 % of
  GLOW's for E0 = 0.5-10 keV (measured 0.97-1.00; docs/physics.md, "The
  deposition above 250 km").

Every target holds for every case (measured: 427.8 nm per ion pair
0.99-1.05 of GLOW's, 557.7 / 427.8 0.92-0.93, 630.0 / 427.8 0.80-0.93,
557.7 nm shape L1 0.10-0.19, 630.0 nm centroid within 10 km). The hardest
is the 557.7 nm shape at E0 = 0.5 keV, measured L1 0.192: there GLOW's
ionization is flat from 141 to 154 km and its green peaks at 156 km, and
lifting ours lifts the ionization peak away from Fang 2008's (141.75 km),
which test_profile.py holds ours to within 1.5 km. The low-energy
correction's constants (src/physics/deposition/glow_calibration.rs) were chosen to meet both: the
shape below 0.2 and that peak at 143.25 km, 1.5 km up, on a plateau of
our profile flat to 0.1 % from 141.25 km.

The green's agreement below 3 keV comes mostly from the chemistry's
ambient NO being GLOW's own (src/physics/chemistry/ambient.rs): with NRLMSIS
2.1's NO, 2.7-4.4 times lower above 120 km, 557.7 / 427.8 was 0.77-0.81
of GLOW's at E0 <= 1 keV; the deposition's shape moves it by 1-2 %.

Each test prints the numbers it compares. The line targets are what the
chemistry line model must meet; the simple line model (yields proportional
to mole fractions) misses them.
"""

from __future__ import annotations

import csv
import functools
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from test_profile import scene_text as profile_scene

ROOT = Path(__file__).resolve().parent.parent.parent

MAIN = [(1.0, 1.0), (3.0, 1.0), (10.0, 1.0), (1.0, 10.0), (3.0, 10.0), (10.0, 10.0)]
OTHERS = [(0.5, 1.0), (2.0, 5.0), (5.0, 20.0), (7.0, 2.0)]
CASES = MAIN + OTHERS

IDS = [f"E0={e}keV-Q={q}" for e, q in CASES]


def aurora_bin() -> Path:
    p = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    assert p.is_file() and os.access(p, os.X_OK), f"{p}: the aurora binary is missing (cargo build --release)"
    return p


def glow_python() -> Path:
    p = Path(os.environ.get("AURORA_GLOW_PYTHON", ROOT / ".venv-glow" / "bin" / "python"))
    assert p.is_file(), f"{p}: NCAR GLOW's venv is missing (run tools/setup)"
    return p


def run(cmd) -> subprocess.CompletedProcess:
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    assert r.returncode == 0, f"{' '.join(map(str, cmd))} failed ({r.returncode}):\n{r.stderr[-4000:]}"
    return r


@functools.lru_cache(maxsize=None)
def glow(e0: float, q: float) -> dict:
    r = run([glow_python(), ROOT / "tools" / "reference" / "glow_run.py", "--e0", e0, "--q", q, "--json"])
    g = json.loads(r.stdout)
    out = {"z": np.array(g["alt_km"])}
    out.update({k: np.array(v) for k, v in g["rates"].items()})
    out["columns"] = g["columns"]
    return out


def scene_text(e0: float, q: float) -> str:
    """One straight curtain of energy flux `q` on a uniform footprint."""
    return profile_scene(e0, 600, bend_km=0.0, energy_flux=q, footprint="resolution = [64, 32]\nuniform = true")


@functools.lru_cache(maxsize=None)
def aurora(e0: float, q: float) -> dict:
    import tempfile

    with tempfile.TemporaryDirectory(prefix="aurora-glow-") as d:
        scene, out = Path(d) / "s.toml", Path(d) / "p.csv"
        scene.write_text(scene_text(e0, q))
        run([aurora_bin(), "profile", scene, "--out", out, "--quiet"])
        with open(out) as f:
            rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert rows, "empty profile"
    p = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    assert set(p["curtain"]) == {0.0}
    return p


def both(e0: float, q: float):
    """aurora's bins inside GLOW's valid altitude range, and GLOW's rates
    interpolated linearly onto their centres."""
    a, g = aurora(e0, q), glow(e0, q)
    z = a["altitude_km"]
    keep = (z >= g["z"][0]) & (z <= g["z"][-1])
    a = {k: v[keep] for k, v in a.items()}
    gi = {k: np.interp(a["altitude_km"], g["z"], g[k]) for k in ("ionization", "n2p_4278", "oi_5577", "oi_6300")}
    return a, g, gi


def normalised(v: np.ndarray) -> np.ndarray:
    return v / v.sum()


def centroid(z: np.ndarray, w: np.ndarray) -> float:
    return float((z * w).sum() / w.sum())


@pytest.mark.parametrize("e0,q", CASES, ids=IDS)
def test_4278_photons_per_ion_pair(e0, q):
    a, g, _ = both(e0, q)
    ours = a["n2p_4278"].sum() / a["ionization"].sum()
    theirs = g["columns"]["n2p_4278"] / g["columns"]["ionization"]
    print(f"E0 {e0} keV Q {q}: 427.8 nm photons per ion pair {ours:.5f}, GLOW {theirs:.5f}, ratio {ours / theirs:.3f}")
    assert abs(ours / theirs - 1) <= 0.15, f"427.8 per ion pair {ours:.5f} vs GLOW {theirs:.5f} (ratio {ours / theirs:.3f}, allowed 0.85-1.15)"


def over_4278(e0: float, q: float, line: str) -> tuple[float, float]:
    """The column of `line` over 427.8 nm's: ours, and GLOW's."""
    a, g, _ = both(e0, q)
    return a[line].sum() / a["n2p_4278"].sum(), g["columns"][line] / g["columns"]["n2p_4278"]


@pytest.mark.parametrize("e0,q", CASES, ids=IDS)
def test_5577_over_4278(e0, q):
    ours, theirs = over_4278(e0, q, "oi_5577")
    print(f"E0 {e0} keV Q {q}: 557.7/427.8 {ours:.3f}, GLOW {theirs:.3f}, ratio {ours / theirs:.3f}")
    assert abs(ours / theirs - 1) <= 0.15, f"557.7/427.8 {ours:.3f} vs GLOW {theirs:.3f} (ratio {ours / theirs:.3f}, allowed +-15%)"


@pytest.mark.parametrize("e0,q", CASES, ids=IDS)
def test_6300_over_4278(e0, q):
    ours, theirs = over_4278(e0, q, "oi_6300")
    tol = 0.25 if e0 <= 2.5 else 0.40
    print(f"E0 {e0} keV Q {q}: 630.0/427.8 {ours:.4f}, GLOW {theirs:.4f}, ratio {ours / theirs:.3f} (allowed +-{tol:.0%})")
    assert abs(ours / theirs - 1) <= tol, f"630.0/427.8 {ours:.4f} vs GLOW {theirs:.4f} (ratio {ours / theirs:.3f}, allowed +-{tol:.0%})"


@pytest.mark.parametrize("e0,q", CASES, ids=IDS)
def test_5577_profile_shape(e0, q):
    a, _, gi = both(e0, q)
    l1 = float(np.abs(normalised(a["oi_5577"]) - normalised(gi["oi_5577"])).sum())
    z = a["altitude_km"]
    pk, pk_g = z[a["oi_5577"].argmax()], z[gi["oi_5577"].argmax()]
    print(f"E0 {e0} keV Q {q}: 557.7 nm shape L1 {l1:.3f} (peak {pk:.2f} km, GLOW {pk_g:.2f} km)")
    assert l1 <= 0.2, f"557.7 nm profile shape: normalised L1 {l1:.3f} against GLOW (allowed 0.2); peaks {pk:.2f} / {pk_g:.2f} km"


@pytest.mark.parametrize("e0,q", CASES, ids=IDS)
def test_6300_centroid(e0, q):
    # Each profile's centroid over its whole range (aurora's bins up to its
    # highest deposit, GLOW's grid up to 962 km, trapezoid-weighted), so
    # neither depends on where the other stops.
    a, g = aurora(e0, q), glow(e0, q)
    ours = centroid(a["altitude_km"], a["oi_6300"])
    zg, vg = g["z"], g["oi_6300"]
    theirs = float(np.trapz(zg * vg, zg) / np.trapz(vg, zg))
    print(f"E0 {e0} keV Q {q}: 630.0 nm centroid {ours:.1f} km, GLOW {theirs:.1f} km ({ours - theirs:+.1f} km)")
    assert abs(ours - theirs) <= 20.0, f"630.0 nm centroid {ours:.1f} km vs GLOW {theirs:.1f} km (allowed 20 km)"


@pytest.mark.parametrize("e0,q", CASES, ids=IDS)
def test_ionization_profile(e0, q):
    a, _, gi = both(e0, q)
    z = a["altitude_km"]
    l1 = float(np.abs(normalised(a["ionization"]) - normalised(gi["ionization"])).sum())
    i, i_g = a["ionization"].argmax(), gi["ionization"].argmax()
    pk, pk_g = z[i], z[i_g]
    at_ours = gi["ionization"][i] / gi["ionization"][i_g]
    print(f"E0 {e0} keV Q {q}: ionization peak {pk:.2f} km, GLOW {pk_g:.2f} km (GLOW at our peak {at_ours:.3f} of its own); normalised L1 {l1:.3f}")
    if e0 >= 1.0:
        assert abs(pk - pk_g) <= 3.0, f"ionization peak {pk:.2f} km vs GLOW {pk_g:.2f} km (allowed 3 km)"
    else:
        # Below 1 keV GLOW's peak is flat (within 8 % from 141 to 154 km at
        # 0.5 keV): its argmax is no altitude to compare; ours must sit
        # where GLOW is within 10 % of its peak.
        assert at_ours >= 0.9, f"ionization peak {pk:.2f} km: GLOW there is {at_ours:.3f} of its peak (at {pk_g:.2f} km)"
    assert l1 <= 0.25, f"ionization profile: normalised L1 {l1:.3f} against GLOW (allowed 0.25)"


@pytest.mark.parametrize("e0", [0.5, 1.0, 2.0, 3.0, 10.0])
def test_ionization_above_250_km(e0):
    a, g, _ = both(e0, 1.0)
    ours = a["ionization"][a["altitude_km"] > 250.0].sum() / a["ionization"].sum()
    zg, ig = g["z"], g["ionization"]
    # GLOW's share above 250 km by the same trapezoid as its columns.
    seg = 0.5 * (ig[1:] + ig[:-1]) * np.diff(zg)
    mid = 0.5 * (zg[1:] + zg[:-1])
    theirs = seg[mid > 250.0].sum() / seg.sum()
    print(f"E0 {e0} keV: ionization above 250 km {ours:.4%} of the column, GLOW {theirs:.4%}, ratio {ours / theirs:.3f}")
    assert abs(ours / theirs - 1) <= 0.30, f"share above 250 km {ours:.4%} vs GLOW {theirs:.4%} (ratio {ours / theirs:.3f}, allowed 0.7-1.3)"
