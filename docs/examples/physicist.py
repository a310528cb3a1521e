"""A physicist's walk-through of the Python module `aurora`, as a notebook
would run it cell by cell (docs/python.md; tests/python/test_python_example.py
runs it as written):

1. a Maxwellian and an accelerated electron spectrum (Evans 1974: a source
   Maxwellian accelerated through a field-aligned potential drop) of the
   same energy flux, their altitude profiles side by side;
2. a zenith keogram of a drifting arc, baked as a frame sequence;
3. the Maxwellian's column ratios against NCAR GLOW's (Solomon 2017),
   where glowpython is present (tools/setup puts it in .venv-glow;
   tools/reference/glow_run.py runs it there).

Run from the repository:  .venv/bin/python docs/examples/physicist.py --out DIR
It writes DIR/profiles.png, DIR/keogram.png and DIR/summary.json.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import aurora  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]

# One curtain on a uniform footprint (every beam carries the energy flux, as
# GLOW's one column does), on the data the chemistry was validated on.
ARC = """seed = 3
[[curtain]]
length = 40.0
width = 16.0
bend_km = 0.0
energy_flux = 5.0
char_energy_kev = 2.0
soft_fraction = 0.0
[footprint]
resolution = [64, 32]
uniform = true
[beams]
count = 600
[atmosphere]
model = "nrlmsis21"
ionosphere = "glow"
"""

# A zenith all-sky camera under an east-west arc drifting north, field
# declination 0: the keogram's meridian is the geographic one.
SKY = """seed = 5
[[curtain]]
center = [0.0, 10.0]
length = 200.0
width = 20.0
bend_km = 0.0
energy_flux = 5.0
char_energy_kev = 3.0
soft_fraction = 0.0
[footprint]
resolution = [64, 16]
uniform = true
[beams]
count = 3000
b_inclination_deg = 85.0
b_declination_deg = 0.0
[grid]
voxel_size = 2.0
density_a = 0.0
lines = ["5577"]
[photons]
radius_km = 2.0
[animation]
fps = 0.05
drift_km = 40.0
drift_period_s = 240.0
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, 1.0]
up = [0.0, 1.0, 0.0]
projection = "fisheye"
fov_deg = 180.0
[render]
width = 61
height = 61
[terrain]
kind = "none"
"""


def peak_km(p: dict, column: str) -> float:
    return float(p["altitude_km"][np.argmax(p[column])])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args(argv)
    out = a.out
    out.mkdir(parents=True, exist_ok=True)
    summary = {}

    # --- 1. Two spectra of the same energy flux, side by side.
    (out / "arc.toml").write_text(ARC)
    maxwellian = aurora.Scene(str(out / "arc.toml"))
    accelerated = aurora.Scene(str(out / "arc.toml"))
    accelerated.set("curtain[0].spectrum", "accelerated")
    accelerated.set("curtain[0].char_energy_kev", 0.5)
    accelerated.set("curtain[0].potential_kv", 3.0)
    profiles = {"Maxwellian E0 2 keV": aurora.profile(maxwellian), "accelerated 0.5 keV through 3 kV": aurora.profile(accelerated)}
    fig, axes = plt.subplots(1, 2, figsize=(9, 5), sharey=True)
    for name, pr in profiles.items():
        p = pr.curtain(0)
        for ax, col in zip(axes, ("ionization", "oi_5577_ver_cm3_s")):
            peak = p[col].max()
            ax.plot(p[col] / peak, p["altitude_km"], label=f"{name} (peak {peak:.3g} {pr.units[col]})")
        summary[name] = {
            "ionization_peak_km": peak_km(p, "ionization"),
            "oi_5577_peak_km": peak_km(p, "oi_5577_ver_cm3_s"),
            "oi_5577_r": float(pr.column_brightness["oi_5577_r"][0]),
            "oi_6300_r": float(pr.column_brightness["oi_6300_r"][0]),
        }
        print(f"{name}: ionization peak {summary[name]['ionization_peak_km']:.2f} km, 557.7 nm peak "
              f"{summary[name]['oi_5577_peak_km']:.2f} km, columns 557.7 nm {summary[name]['oi_5577_r']:.0f} R, "
              f"630.0 nm {summary[name]['oi_6300_r']:.0f} R")
    axes[0].set_xlabel("ionization rate, over its peak")
    axes[1].set_xlabel("557.7 nm volume emission rate, over its peak")
    axes[0].set_ylabel("altitude (km)")
    for ax in axes:
        ax.set_ylim(80, 200)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "profiles.png", dpi=80)

    # --- 2. A zenith keogram of a drifting arc.
    (out / "sky.toml").write_text(SKY)
    sky = aurora.Scene(str(out / "sky.toml"))
    aurora.bake(sky, out / "seq", frames="1-4")
    k = aurora.keogram(sky, out / "seq", "1-4")
    brightest = [float(k.scan_deg[np.argmax(k.values[:, j])]) for j in range(len(k.frames))]
    summary["keogram"] = {"frames": k.frames.tolist(), "times_s": k.times_s.tolist(), "brightest_scan_deg": brightest,
                          "largest": float(k.values.max()), "units": k.values.units}
    print(f"keogram: brightest scan angle per frame {brightest} degrees (0 the north horizon), largest {k.values.max():.0f} R")
    fig, ax = plt.subplots(figsize=(5, 5))
    im = ax.pcolormesh(k.times_s, k.scan_deg, k.values, shading="nearest")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("scan angle from the magnetic north horizon (degrees)")
    ax.invert_yaxis()
    fig.colorbar(im, label="557.7 nm (R)")
    fig.tight_layout()
    fig.savefig(out / "keogram.png", dpi=80)

    # --- 3. The Maxwellian's column ratios against GLOW's, where it is present.
    glow_python = ROOT / ".venv-glow" / "bin" / "python"
    if glow_python.is_file():
        r = subprocess.run([str(glow_python), str(ROOT / "tools" / "reference" / "glow_run.py"), "--e0", "2", "--q", "5", "--json"],
                           capture_output=True, text=True, check=True)
        g = json.loads(r.stdout)["columns"]
        p = profiles["Maxwellian E0 2 keV"].curtain(0)
        ours = {"oi_5577/n2p_4278": p["oi_5577"].sum() / p["n2p_4278"].sum(),
                "oi_6300/n2p_4278": p["oi_6300"].sum() / p["n2p_4278"].sum()}
        theirs = {"oi_5577/n2p_4278": g["oi_5577"] / g["n2p_4278"], "oi_6300/n2p_4278": g["oi_6300"] / g["n2p_4278"]}
        summary["glow"] = {k2: {"aurora": float(ours[k2]), "glow": float(theirs[k2]), "ratio": float(ours[k2] / theirs[k2])}
                           for k2 in ours}
        for k2, v in summary["glow"].items():
            print(f"{k2}: aurora {v['aurora']:.4f}, GLOW {v['glow']:.4f}, ratio {v['ratio']:.3f}")
    else:
        print(f"{glow_python}: no GLOW here (tools/setup makes it); its comparison left out")
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
