#!/usr/bin/env python3
"""Recompress 8-bit RGB(A) PNGs in place, losslessly: each row's PNG filter
chosen by the least sum of absolute filtered bytes (the libpng heuristic),
then zlib at level 9. The pixels are checked to read back identical.

    .venv/bin/python tools/cycles/png_optimize.py IMAGE.png [IMAGE.png ...]

`aurora render` writes PNGs for speed; the gallery's pictures are kept small
with this (tools/gallery). Needs numpy only (and tools/aurora_tools/png.py).
"""

from __future__ import annotations

import os
import struct
import sys
import zlib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.png import SIGNATURE, chunk, chunks, paeth, unfilter  # noqa: E402


def read(path):
    """(IHDR bytes, other chunks before IEND, pixels as rows of bytes, channels)."""
    ihdr, idat, other = None, b"", []
    for t, d in chunks(path):
        if t == b"IHDR":
            ihdr = d
        elif t == b"IDAT":
            idat += d
        elif t != b"IEND":
            other.append((t, d))
    w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", ihdr)
    if depth != 8 or colour not in (2, 6) or interlace:
        raise ValueError(f"{path}: only 8-bit RGB or RGBA, not interlaced")
    c = 3 if colour == 2 else 4
    return ihdr, other, unfilter(zlib.decompress(idat), h, w * c, c), c


def encode(ihdr, extra, img, c) -> bytes:
    rows, prev = [], np.zeros(img.shape[1], np.int32)
    zero = np.zeros(c, np.int32)
    for cur in img:
        a = np.concatenate([zero, cur[:-c]])
        ul = np.concatenate([zero, prev[:-c]])
        cands = [cur, (cur - a) & 255, (cur - prev) & 255, (cur - (a + prev) // 2) & 255, (cur - paeth(a, prev, ul)) & 255]
        k = int(np.argmin([np.minimum(x, 256 - x).sum() for x in cands]))
        rows.append(bytes([k]) + cands[k].astype(np.uint8).tobytes())
        prev = cur

    body = b"".join(chunk(t, d) for t, d in extra)
    return SIGNATURE + chunk(b"IHDR", ihdr) + body + chunk(b"IDAT", zlib.compress(b"".join(rows), 9)) + chunk(b"IEND", b"")


def main(argv) -> int:
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip(), file=sys.stdout if argv else sys.stderr)
        return 0 if argv else 2
    for path in argv:
        ihdr, extra, img, c = read(path)
        data = encode(ihdr, extra, img, c)
        tmp = path + ".tmp"
        with open(tmp, "wb") as f:
            f.write(data)
        if not np.array_equal(read(tmp)[2], img):
            os.remove(tmp)
            raise RuntimeError(f"{path}: the recompressed pixels differ")
        before = os.path.getsize(path)
        if len(data) < before:
            os.replace(tmp, path)
        else:
            os.remove(tmp)
        print(f"{path}: {before} -> {min(before, len(data))} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
