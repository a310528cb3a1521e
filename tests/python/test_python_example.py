"""docs/examples/physicist.py, the notebook-style example of docs/python.md,
run as documented (`.venv/bin/python docs/examples/physicist.py --out
DIR`): it must finish, draw its two figures, and say what docs/python.md
says it shows:

- the Maxwellian's column ratios against NCAR GLOW's (glowpython 4.0.4 in
  .venv-glow, which tools/setup makes: its absence is a failure here) within
  tests/python/test_glow.py's targets for the same case (E0 = 2 keV, Q = 5
  erg cm^-2 s^-1): 557.7 / 427.8 within 15 %, 630.0 / 427.8 within 25 %;
- the accelerated spectrum's deposition peaks higher than the Maxwellian of
  the same energy flux: its electrons arrive between 3 and a few keV, none
  in the Maxwellian's tail above 10 keV that ionizes below 105 km;
- the zenith keogram's brightest row moves toward the north horizon as the
  arc drifts north (frames 1-4, drift 0, 20, 35 and 40 km north), and stays
  north of the zenith.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent


def test_the_physicists_example_runs_as_documented(tmp_path):
    assert (ROOT / ".venv-glow" / "bin" / "python").is_file(), "NCAR GLOW's venv is missing (run tools/setup)"
    r = subprocess.run([sys.executable, str(ROOT / "docs" / "examples" / "physicist.py"), "--out", str(tmp_path)],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-4000:]
    print(r.stdout)
    assert "python docs/examples/physicist.py --out" in (ROOT / "docs" / "python.md").read_text()
    for png in ("profiles.png", "keogram.png"):
        assert (tmp_path / png).stat().st_size > 10_000, png
    s = json.loads((tmp_path / "summary.json").read_text())
    g = s["glow"]
    assert abs(g["oi_5577/n2p_4278"]["ratio"] - 1) <= 0.15, g
    assert abs(g["oi_6300/n2p_4278"]["ratio"] - 1) <= 0.25, g
    mx, acc = s["Maxwellian E0 2 keV"], s["accelerated 0.5 keV through 3 kV"]
    assert acc["ionization_peak_km"] > mx["ionization_peak_km"] + 2.0, (mx, acc)
    b = s["keogram"]["brightest_scan_deg"]
    assert all(x > y for x, y in zip(b, b[1:])) and b[0] < 90.0, b
    assert s["keogram"]["units"].startswith("R (rayleigh)") and s["keogram"]["largest"] > 1000.0
