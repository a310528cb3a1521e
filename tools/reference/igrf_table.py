#!/usr/bin/env python3
"""Writes the IGRF-14 coefficient table the binary compiles in
(data/igrf14.csv) and the field the tests check it against
(tests/data/igrf14_oracle.csv).

Source: the International Geomagnetic Reference Field, 14th generation
(IAGA Division V, Working Group V-MOD, 2024; doi 10.5281/zenodo.14012302;
the method: Alken et al. 2021, Earth Planets Space 73, 49), as the file
IGRF14.shc that the package ppigrf 2.1.0 (MIT) ships. The table copies its
Gauss coefficients g(n, m) and h(n, m), nT, degree 1-13, at the 27 epochs
1900.0, 1905.0, ..., 2025.0 and 2030.0 (the 2030 column is the 2025 model
advanced five years by its secular variation, as the .shc format writes
predictive models). The file's SHA-256 and the package version are in the
table's header.

Oracle: ppigrf.igrf_gc (geocentric radius, colatitude, longitude; returns
B_r, B_theta, B_phi, nT) at 10 sites and 3 heights (0, 110 and 300 km above
the WGS 84 ellipsoid, converted to geocentric radius and colatitude by
ppigrf.geod2geoc's ellipsoid), each site at its own date.

Run: tools/reference/igrf_table.py [OUT_ROOT] in a virtual environment with
ppigrf==2.1.0 (numpy, pandas).
"""
import datetime as dt
import hashlib
import sys
from importlib.metadata import version
from pathlib import Path

import numpy as np
import ppigrf

ROOT = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2]
SHC = Path(ppigrf.__file__).parent / "IGRF14.shc"

# name, geodetic latitude, longitude (east), date (UTC)
SITES = [
    ("tromso", 69.65, 18.96, dt.datetime(2026, 12, 7, 22, 0)),
    ("longyearbyen", 78.22, 15.65, dt.datetime(2025, 1, 15, 6, 0)),
    ("fairbanks", 64.84, -147.72, dt.datetime(2024, 3, 1, 9, 30)),
    ("yellowknife", 62.45, -114.37, dt.datetime(2029, 10, 31, 6, 0)),
    ("reykjavik", 64.15, -21.94, dt.datetime(2010, 6, 30, 0, 0)),
    ("kiruna", 67.86, 20.23, dt.datetime(1995, 2, 14, 20, 0)),
    ("mcmurdo", -77.85, 166.67, dt.datetime(2026, 7, 1, 12, 0)),
    ("hobart", -42.88, 147.33, dt.datetime(2022, 5, 11, 14, 0)),
    ("equator_atlantic", 0.5, -30.0, dt.datetime(2020, 1, 1, 0, 0)),
    ("south_pole", -89.9, 0.0, dt.datetime(1965, 8, 20, 3, 0)),
]
HEIGHTS_KM = [0.0, 110.0, 300.0]
WGS84_A, WGS84_F = 6378.137, 1.0 / 298.257223563


def geocentric(lat_deg, lon_deg, h_km):
    """Geocentric radius (km) and colatitude (deg) of a geodetic point."""
    sp, cp = np.sin(np.radians(lat_deg)), np.cos(np.radians(lat_deg))
    e2 = WGS84_F * (2.0 - WGS84_F)
    n = WGS84_A / np.sqrt(1.0 - e2 * sp * sp)
    rho, z = (n + h_km) * cp, (n * (1.0 - e2) + h_km) * sp
    return float(np.hypot(rho, z)), float(90.0 - np.degrees(np.arctan2(z, rho)))


def table():
    data = SHC.read_bytes()
    sha = hashlib.sha256(data).hexdigest()
    lines = [l for l in data.decode().splitlines() if not l.startswith("#")]
    epochs = [float(x) for x in lines[1].split()]
    out = [
        "# IGRF-14 Gauss coefficients, nT (IAGA V-MOD 2024, doi 10.5281/zenodo.14012302)",
        f"# from IGRF14.shc of ppigrf {version('ppigrf')}, SHA-256 {sha}",
        "# m < 0: h(n, |m|); m >= 0: g(n, m); one column per epoch (year, 1 January 00:00 UTC)",
        "n,m," + ",".join(f"{e:.1f}" for e in epochs),
    ]
    for l in lines[2:]:
        f = l.split()
        out.append(",".join([f[0], f[1]] + f[2:]))
    (ROOT / "data" / "igrf14.csv").write_text("\n".join(out) + "\n")
    return sha


def oracle(sha):
    rows = [
        f"# ppigrf {version('ppigrf')} igrf_gc (IGRF14.shc, SHA-256 {sha}); geocentric r km, colatitude deg, longitude deg; B nT",
        "site,latitude_deg,longitude_deg,height_km,utc,r_km,theta_deg,phi_deg,b_r,b_theta,b_phi",
    ]
    for name, lat, lon, date in SITES:
        for h in HEIGHTS_KM:
            r, th = geocentric(lat, lon, h)
            br, bt, bp = (float(np.ravel(x)[0]) for x in ppigrf.igrf_gc(r, th, lon, date))
            rows.append(
                f"{name},{lat},{lon},{h},{date.strftime('%Y-%m-%dT%H:%M:%SZ')},{r:.9f},{th:.9f},{lon},{br:.4f},{bt:.4f},{bp:.4f}"
            )
    (ROOT / "tests" / "data" / "igrf14_oracle.csv").write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    oracle(table())
