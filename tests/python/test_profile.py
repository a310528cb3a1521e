"""`aurora profile` against Fang et al. 2008 computed live by eppaurora on
pymsis (NRLMSIS 2.1), the community's own implementations.

Single curtains with Maxwellians of E0 = 0.5, 1, 3, 10, 30 keV (no soft
component) on the atmosphere the deposition was validated on, selected
explicitly (`[atmosphere] model = "nrlmsis21"`, `ionosphere = "glow"`, read
from the source tree's data/: NRLMSIS 2.1, 67 N, 20 E, 2020-01-15 00:00 UT,
F10.7 = F10.7a = 150, Ap = 15). AURORA_VALIDATE_ON=default runs the same
comparisons on the compiled-in default (U.S. Standard Atmosphere 1976 and
the closed-form ionosphere) to measure what it moves (docs/data.md). The reference is
eppaurora.fang2008 with rho from pymsis and the hydrostatic scale height
H = k T / (m g) (m the mean molecular mass of every species pymsis returns,
g at altitude), evaluated at the profile's 0.5 km bin centres. Criteria:
ionization peak within 1.5 km of Fang's, normalised profile
(sum 1) within L1 0.15.

Then the grid: a bake of one 3 keV curtain with colour noise off; its green
channel summed per altitude layer against the profile's 557.7 nm column
(L1 within 0.1). Green comes from 557.7 nm only in this spectrum: the other
lines' gamut-mapped colours (427.8 violet, 630/636.4 red, N2 1P red) carry
no green (spectrum.rs), and the photon kernel blurs altitude by 0.5 km.

The binary is target/release/aurora (AURORA_BIN overrides).
"""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent.parent
K_B = 1.380649e-16  # erg / K
AMU = 1.66053907e-24  # g
# pymsis species columns and their masses, amu (N2, O2, O, He, H, Ar, N).
SPECIES = {1: 28.0134, 2: 31.9988, 3: 15.999, 4: 4.0026, 5: 1.008, 6: 39.948, 7: 14.007}


def aurora_bin() -> Path:
    p = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    assert p.is_file() and os.access(p, os.X_OK), f"{p}: the aurora binary is missing (cargo build --release)"
    return p


def run(cmd):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    assert r.returncode == 0, f"{' '.join(map(str, cmd))} failed ({r.returncode}):\n{r.stderr[-4000:]}"
    return r


# The data the deposition and the chemistry were validated on (docs/data.md).
VALIDATED = '[atmosphere]\nmodel = "nrlmsis21"\nionosphere = "glow"\n'


def atmosphere_table() -> str:
    """The [atmosphere] table of every validation scene: the validated data,
    or with AURORA_VALIDATE_ON=default none (the default)."""
    return "" if os.environ.get("AURORA_VALIDATE_ON") == "default" else VALIDATED


def scene_text(e0: float, beams: int, extra: str = "", *, bend_km: float = 3.0, energy_flux: float | None = None,
               footprint: str = "resolution = [128, 48]") -> str:
    """One curtain of Maxwellian electrons of E0 = `e0` keV (no soft
    component), `beams` beams; `energy_flux` (erg cm^-2 s^-1) when given,
    `footprint` the [footprint] table's lines, `extra` tables after [beams],
    then the validated [atmosphere] (also tests/python/test_glow.py's scene)."""
    flux = "" if energy_flux is None else f"energy_flux = {energy_flux}\n"
    return f"""seed = 3
[[curtain]]
length = 40.0
width = 16.0
bend_km = {bend_km}
{flux}char_energy_kev = {e0}
soft_fraction = 0.0
[footprint]
{footprint}
[beams]
count = {beams}
{extra}{atmosphere_table()}"""


def read_profile(path: Path) -> dict[str, np.ndarray]:
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert rows, f"{path}: empty"
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def fang2008_on_msis(alt_km: np.ndarray, e0: float) -> np.ndarray:
    """Energy dissipation of a Maxwellian (eppaurora.fang2008) per cm at
    `alt_km`, on NRLMSIS 2.1 for the default atmosphere's date and place."""
    import eppaurora
    import pymsis

    n = len(alt_km)
    out = np.asarray(pymsis.calculate(
        np.full(n, np.datetime64("2020-01-15T00:00")), np.full(n, 20.0), np.full(n, 67.0), alt_km,
        np.full(n, 150.0), np.full(n, 150.0), np.full((n, 7), 15.0), version=2.1)).reshape(n, -1)
    rho = out[:, 0] * 1e-3  # g / cm^3
    num = np.zeros(n)
    for k in SPECIES:
        num += np.nan_to_num(out[:, k]) * 1e-6
    m = rho / num
    g = 980.665 * (6371.0 / (6371.0 + alt_km)) ** 2
    h = K_B * out[:, 10] / (m * g)
    return np.ravel(eppaurora.fang2008(e0, 1.0, h, rho))


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("profile")


@pytest.mark.parametrize("e0", [0.5, 1.0, 3.0, 10.0, 30.0])
def test_ionization_profile_matches_fang_2008(work, e0):
    scene = work / f"maxw{e0}.toml"
    scene.write_text(scene_text(e0, 600))
    out = work / f"maxw{e0}.csv"
    run([aurora_bin(), "profile", scene, "--out", out, "--quiet"])
    p = read_profile(out)
    header = next(line for line in open(out) if not line.startswith("#")).strip()
    assert header.startswith("curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300"), header
    assert set(p["curtain"]) == {0.0}
    z, ion = p["altitude_km"], p["ionization"]
    ref = fang2008_on_msis(z, e0)
    ours, theirs = ion / ion.sum(), ref / ref.sum()
    peak, peak_ref = z[ion.argmax()], z[ref.argmax()]
    l1 = np.abs(ours - theirs).sum()
    print(f"E0 {e0} keV: peak {peak:.2f} km (Fang 2008 {peak_ref:.2f}), L1 {l1:.3f}")
    assert abs(peak - peak_ref) <= 1.5, f"E0 {e0}: peak {peak} km vs Fang 2008 {peak_ref} km"
    assert l1 <= 0.15, f"E0 {e0}: normalised L1 {l1:.3f}"


def test_grid_green_channel_has_the_profile_557_7_shape(work):
    import pyopenvdb as openvdb
    extra = "[colour]\nnoise_km = 0.0\n[grid]\nprune = 0.0\nvoxel_size = 0.5\n"
    scene = work / "green.toml"
    scene.write_text(scene_text(3.0, 600, extra))
    out = work / "green.csv"
    run([aurora_bin(), "profile", scene, "--out", out, "--quiet"])
    run([aurora_bin(), "bake", scene, "--out", work / "green-bake", "--quiet"])
    p = read_profile(out)
    grid = openvdb.read(str(work / "green-bake" / "aurora.vdb"), "emission")
    (i0, j0, k0), (i1, j1, k1) = grid.evalActiveVoxelBoundingBox()
    arr = np.zeros((i1 - i0 + 1, j1 - j0 + 1, k1 - k0 + 1, 3), np.float32)
    grid.copyToArray(arr, ijk=(i0, j0, k0))
    vs = grid.transform.voxelSize()[2]
    z_vox = np.array([grid.transform.indexToWorld((i0, j0, k))[2] for k in range(k0, k1 + 1)])
    green = arr[..., 1].sum(axis=(0, 1)).astype(np.float64)
    # Voxel layers (0.5 km, centred on multiples of 0.5) onto the profile's
    # bins (centres at .25/.75): average the two layers around each bin.
    zb, g5577 = p["altitude_km"], p["oi_5577"]
    grid_on_bins = np.interp(zb, z_vox, green, left=0.0, right=0.0)
    a, b = grid_on_bins / grid_on_bins.sum(), g5577 / g5577.sum()
    l1 = np.abs(a - b).sum()
    print(f"green channel vs 557.7 nm profile: L1 {l1:.3f} (voxel {vs} km)")
    assert l1 <= 0.1, f"green channel L1 {l1:.3f} against the profile's 557.7 nm"
