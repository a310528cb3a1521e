"""tools/readme_pictures' file work, without aurora: text chunks put after
IHDR (replacing their old values) and PNG frames joined into an animated
PNG whose frames decode to the pictures given."""

from __future__ import annotations

import importlib.machinery
import importlib.util
import struct
import zlib
from pathlib import Path

import numpy as np

from aurora_tools.png import chunks, read_png, write_png

ROOT = Path(__file__).resolve().parents[2]


def _script():
    path = ROOT / "tools" / "readme_pictures"
    loader = importlib.machinery.SourceFileLoader("readme_pictures", str(path))
    spec = importlib.util.spec_from_loader("readme_pictures", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def _picture(seed: int, w: int = 7, h: int = 5) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)


def test_text_chunks_follow_ihdr_and_replace_their_old_values(tmp_path):
    rp = _script()
    write_png(tmp_path / "a.png", _picture(1))
    once = rp.with_text((tmp_path / "a.png").read_bytes(), [("aurora_command", "one"), ("aurora_vdb_sha256", "x  a.vdb")])
    twice = rp.with_text(once, [("aurora_command", "two")])
    (tmp_path / "b.png").write_bytes(twice)
    got = chunks(tmp_path / "b.png")
    assert got[0][0] == b"IHDR" and got[1] == (b"tEXt", b"aurora_command\0two")
    texts = sorted(d for t, d in got if t == b"tEXt")
    assert texts == [b"aurora_command\0two", b"aurora_vdb_sha256\0x  a.vdb"]
    assert np.array_equal(read_png(tmp_path / "b.png"), _picture(1))


def test_frames_join_into_an_animated_png(tmp_path):
    rp = _script()
    frames = []
    for i in range(3):
        frames.append(tmp_path / f"f{i}.png")
        write_png(frames[-1], _picture(i))
    data = rp.apng(frames, 250)
    pos, seen = 8, []
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body, crc = data[pos + 8:pos + 8 + n], struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])[0]
        assert crc == zlib.crc32(tag + body) & 0xFFFFFFFF, tag
        seen.append((tag, body))
        pos += 12 + n
    assert struct.unpack(">II", dict(seen)[b"acTL"]) == (3, 0)
    controls = [struct.unpack(">IIIIIHHBB", b) for t, b in seen if t == b"fcTL"]
    assert [c[5:7] for c in controls] == [(250, 1000)] * 3 and [c[1:3] for c in controls] == [(7, 5)] * 3
    numbers = [struct.unpack(">I", b[:4])[0] for t, b in seen if t in (b"fcTL", b"fdAT")]
    assert numbers == list(range(len(numbers)))
    # The first frame is the image every PNG reader shows; the others decode
    # from their fdAT data to the same rows as the frames given.
    (tmp_path / "anim.png").write_bytes(data)
    assert np.array_equal(read_png(tmp_path / "anim.png"), _picture(0))
    later = [zlib.decompress(b[4:]) for t, b in seen if t == b"fdAT"]
    assert later == [zlib.decompress(b"".join(d for t, d in chunks(f) if t == b"IDAT")) for f in frames[1:]]
