#!/usr/bin/env python3
"""Recompress 8-bit RGB(A) PNGs in place, losslessly: each row's PNG filter
chosen by the least sum of absolute filtered bytes (the libpng heuristic),
then zlib at level 9. The pixels are checked to read back identical.

    .venv/bin/python tools/png_optimize.py IMAGE.png [IMAGE.png ...]

`aurora render` writes PNGs for speed; the gallery's pictures are kept small
with this (tools/gallery). Needs numpy only.
"""

from __future__ import annotations

import os
import struct
import sys
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))


def read(path):
    """(IHDR bytes, other chunks before IEND, pixels as rows of bytes, channels)."""
    b = open(path, "rb").read()
    if b[:8] != SIGNATURE:
        raise ValueError(f"{path}: not a PNG")
    i, idat, chunks, ihdr = 8, b"", [], None
    while i < len(b):
        (n,) = struct.unpack(">I", b[i:i + 4])
        t, d = b[i + 4:i + 8], b[i + 8:i + 8 + n]
        i += 12 + n
        if t == b"IHDR":
            ihdr = d
        elif t == b"IDAT":
            idat += d
        elif t != b"IEND":
            chunks.append((t, d))
    w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", ihdr)
    if depth != 8 or colour not in (2, 6) or interlace:
        raise ValueError(f"{path}: only 8-bit RGB or RGBA, not interlaced")
    c = 3 if colour == 2 else 4
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, 1 + w * c)
    out = np.zeros((h, w * c), np.int32)
    prev = np.zeros(w * c, np.int32)
    for y in range(h):
        f, r = raw[y, 0], raw[y, 1:].astype(np.int32)
        if f == 0:
            cur = r
        elif f == 2:
            cur = (r + prev) & 255
        else:
            # Sub, Average and Paeth depend on the pixel to the left: per pixel.
            cur = np.zeros(w * c, np.int32)
            for x in range(0, w * c, c):
                a = cur[x - c:x] if x else np.zeros(c, np.int32)
                up = prev[x:x + c]
                ul = prev[x - c:x] if x else np.zeros(c, np.int32)
                pred = a if f == 1 else (a + up) // 2 if f == 3 else _paeth(a, up, ul)
                cur[x:x + c] = (r[x:x + c] + pred) & 255
        out[y], prev = cur, cur
    return ihdr, chunks, out, c


def encode(ihdr, chunks, img, c) -> bytes:
    rows, prev = [], np.zeros(img.shape[1], np.int32)
    zero = np.zeros(c, np.int32)
    for cur in img:
        a = np.concatenate([zero, cur[:-c]])
        ul = np.concatenate([zero, prev[:-c]])
        cands = [cur, (cur - a) & 255, (cur - prev) & 255, (cur - (a + prev) // 2) & 255, (cur - _paeth(a, prev, ul)) & 255]
        k = int(np.argmin([np.minimum(x, 256 - x).sum() for x in cands]))
        rows.append(bytes([k]) + cands[k].astype(np.uint8).tobytes())
        prev = cur

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    body = b"".join(chunk(t, d) for t, d in chunks)
    return SIGNATURE + chunk(b"IHDR", ihdr) + body + chunk(b"IDAT", zlib.compress(b"".join(rows), 9)) + chunk(b"IEND", b"")


def main(argv) -> int:
    for path in argv:
        ihdr, chunks, img, c = read(path)
        data = encode(ihdr, chunks, img, c)
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
