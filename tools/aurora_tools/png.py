"""PNG files with zlib and numpy only: the chunks of a file, the rows'
filters undone (and the Paeth predictor the filters share), any
non-interlaced 8- or 16-bit PNG as an array, and 8-bit RGB written."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from .files import write_atomic

SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: Channels per colour type: grey, RGB, grey + alpha, RGBA.
CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}


def chunk(tag: bytes, data: bytes) -> bytes:
    """One chunk: length, tag, data and CRC."""
    return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)


def chunks(path) -> list[tuple[bytes, bytes]]:
    """The (tag, data) of every chunk of the PNG at `path`, in file order."""
    data = Path(path).read_bytes()
    if data[:8] != SIGNATURE:
        raise ValueError(f"{path}: not a PNG")
    pos, out = 8, []
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos:pos + 8])
        out.append((tag, data[pos + 8:pos + 8 + n]))
        pos += 12 + n
    return out


def paeth(a, b, c):
    """The Paeth predictor of left `a`, up `b` and up-left `c` (arrays)."""
    p = a + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))


def unfilter(raw: bytes, height: int, stride: int, bpp: int) -> np.ndarray:
    """The filtered scanlines `raw` (a filter byte, then `stride` bytes, per
    row) as (height, stride) int32 bytes; `bpp` is bytes per pixel."""
    rows = np.frombuffer(raw, np.uint8, height * (stride + 1)).reshape(height, stride + 1)
    out = np.zeros((height, stride), np.int32)
    prev = np.zeros(stride, np.int32)
    zero = np.zeros(bpp, np.int32)
    for y in range(height):
        f, r = rows[y, 0], rows[y, 1:].astype(np.int32)
        if f == 0:
            cur = r
        elif f == 2:
            cur = (r + prev) & 255
        else:
            # Sub, Average and Paeth depend on the pixel to the left: per pixel.
            cur = np.zeros(stride, np.int32)
            for x in range(0, stride, bpp):
                a = cur[x - bpp:x] if x else zero
                up = prev[x:x + bpp]
                ul = prev[x - bpp:x] if x else zero
                pred = a if f == 1 else (a + up) // 2 if f == 3 else paeth(a, up, ul)
                cur[x:x + bpp] = (r[x:x + bpp] + pred) & 255
        out[y], prev = cur, cur
    return out


def read_png(path) -> np.ndarray:
    """A non-interlaced 8- or 16-bit PNG as (H, W, C): uint8 or uint16
    values, C channels of its colour type (grey, grey + alpha, RGB, RGBA)."""
    parts = chunks(path)
    w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", next(d for t, d in parts if t == b"IHDR"))
    if interlace or depth not in (8, 16) or ctype not in CHANNELS:
        raise ValueError(f"{path}: unsupported PNG (depth {depth}, colour type {ctype}, interlace {interlace})")
    ch = CHANNELS[ctype]
    bpp = ch * depth // 8
    raw = zlib.decompress(b"".join(d for t, d in parts if t == b"IDAT"))
    px = unfilter(raw, h, w * bpp, bpp).astype(np.uint8)
    if depth == 16:
        return px.view(">u2").astype(np.uint16).reshape(h, w, ch)
    return px.reshape(h, w, ch)


def write_png(path, rgb8: np.ndarray) -> None:
    """8-bit RGB PNG (filter 0 rows, zlib), written to a temporary name and renamed."""
    rgb8 = np.ascontiguousarray(rgb8, np.uint8)
    h, w = rgb8.shape[:2]
    raw = b"".join(b"\x00" + rgb8[y].tobytes() for y in range(h))
    png = (SIGNATURE + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    write_atomic(path, png)
