"""OpenEXR images as numpy arrays (row 0 at the top), through the OpenEXR
module: aurora's RGBA output, Cycles' multi-layer passes, and an RGBA writer."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np


def read_rgba(path) -> np.ndarray:
    """(H, W, 4) float64, row 0 at the top. Takes R, G, B, A channels (or a
    single RGB/RGBA group); a missing alpha reads as 1."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels, dtype=np.float64) for k, v in f.channels().items()}
    names = {k.split(".")[-1]: k for k in ch}
    if all(c in names for c in "RGB"):
        rgb = [ch[names[c]] for c in "RGB"]
        a = ch[names["A"]] if "A" in names else np.ones_like(rgb[0])
        return np.dstack(rgb + [a])
    raise ValueError(f"{path}: no R, G, B channels (have {sorted(ch)})")


def read_exr_layers(path) -> dict[str, np.ndarray]:
    """Every channel group of a (multi-part, multi-layer) EXR as float32 arrays
    (H, W, C), keyed by name (e.g. 'ViewLayer.Combined'); row 0 is the top."""
    import OpenEXR

    out = {}
    with OpenEXR.File(str(path), separate_channels=False) as f:
        for part in f.parts:
            for key, ch in part.channels.items():
                a = np.asarray(ch.pixels, dtype=np.float32)
                out[key] = a if a.ndim == 3 else a[..., None]
    return out


def write_rgba_exr(path, rgba: np.ndarray, metadata: dict[str, str] | None = None) -> None:
    """RGBA float32 scanline EXR (ZIP), written to a temporary name and renamed."""
    import OpenEXR

    path = Path(path)
    rgba = np.ascontiguousarray(rgba, dtype=np.float32)
    if rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"expected (H, W, 4), got {rgba.shape}")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in (metadata or {}).items():
        header[k] = str(v)
    channels = {c: np.ascontiguousarray(rgba[..., i]) for i, c in enumerate("RGBA")}
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp.exr", dir=path.parent)
    os.close(fd)
    try:
        with OpenEXR.File(header, channels) as f:
            f.write(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
