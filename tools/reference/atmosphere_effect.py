#!/usr/bin/env python3
"""What the atmosphere choice does to the light: `aurora profile` of one
Maxwellian curtain (no soft part, 1 erg cm^-2 s^-1, uniform footprint, the
scene of tests/python/test_glow.py) at E0 = 1, 3, 5 and 10 keV, on the
compiled-in default (`us1976` with the closed-form ionosphere) and on the
validated data (`nrlmsis21` with GLOW's ionosphere, read from the source
tree's data/). Prints per case the ionization peak altitude, 557.7 nm
photons per erg deposited, 630.0 / 557.7, and the ratio of the two
atmospheres' numbers (docs/data.md quotes them).

Rerun: `python tools/reference/atmosphere_effect.py` after
`cargo build --release` (AURORA_BIN overrides target/release/aurora).
"""
import csv
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402

ERG_PER_KEV = 1.602176634e-9
CHOICES = {"default": "", "validated": '[atmosphere]\nmodel = "nrlmsis21"\nionosphere = "glow"\n'}


def scene(e0: float, atmosphere: str) -> str:
    return f"""seed = 3
[[curtain]]
length = 40.0
width = 16.0
bend_km = 0.0
energy_flux = 1.0
char_energy_kev = {e0}
soft_fraction = 0.0
[footprint]
resolution = [64, 32]
uniform = true
[beams]
count = 600
{atmosphere}"""


def measure(binary: Path, e0: float, atmosphere: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="aurora-atm-") as d:
        s, out = Path(d) / "s.toml", Path(d) / "p.csv"
        s.write_text(scene(e0, atmosphere))
        subprocess.run([str(binary), "profile", str(s), "--out", str(out), "--quiet"], check=True)
        rows = list(csv.DictReader(line for line in open(out) if not line.startswith("#")))
    col = {k: [float(r[k]) for r in rows] for k in rows[0]}
    z, ion = col["altitude_km"], col["ionization"]
    green, red = sum(col["oi_5577"]), sum(col["oi_6300"])
    return {
        "peak_km": z[max(range(len(ion)), key=ion.__getitem__)],
        "green_per_erg": green / (sum(col["deposited_kev_s"]) * ERG_PER_KEV),
        "red_over_green": red / green,
    }


def main():
    binary = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    print("E0 keV | peak km default / validated | 557.7 nm per erg default / validated (ratio) | 630.0/557.7 default / validated (ratio)")
    for e0 in (1.0, 3.0, 5.0, 10.0):
        d, v = (measure(binary, e0, CHOICES[k]) for k in ("default", "validated"))
        print(f"{e0:g} | {d['peak_km']:.2f} / {v['peak_km']:.2f} | "
              f"{d['green_per_erg']:.4g} / {v['green_per_erg']:.4g} ({d['green_per_erg'] / v['green_per_erg']:.3f}) | "
              f"{d['red_over_green']:.4f} / {v['red_over_green']:.4f} ({d['red_over_green'] / v['red_over_green']:.3f})")


if __name__ == "__main__":
    main()
