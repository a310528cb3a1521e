"""Two linear RGBA EXR renders compared: error figures and a picture
(tools/cycles/compare.py is its command line).

Figures (A and B play symmetric roles; neither is assumed exact):
- mean_rel_err: mean over "bright" pixels of |A - B|_1 / ((|A|_1 + |B|_1) / 2),
  where |.|_1 sums the R, G, B channels (colour errors count) and a pixel is
  bright when (|A|_1 + |B|_1) / 2 exceeds `threshold` (1%) of its peak;
- flux_ratio: sum of A's RGB over sum of B's (the total flux);
- max_alpha_diff, mean_alpha_diff: |A.a - B.a| over all pixels;
- with a mask: the same mean relative error and flux ratio over the mask's
  pixels, brightness threshold relative to the peak inside the mask.
`--terrain-mask SCENE.toml` builds the mask of pixels lying wholly on a
"plane" terrain (centre and four corners of the pixel hit z = height).

Picture: A, B (same exposure: the 99.5th percentile of both maps to 1, sRGB)
and the signed relative difference (A - B) / mean on a blue-white-red scale
of +-range (pixels below the threshold in dark grey), with a labelled colour
bar and the figures printed underneath. PNG written with numpy + zlib.
Needs numpy and OpenEXR only (and ../blender/scene_toml.py for --terrain-mask).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from . import addon
from .exr_io import read_rgba
from .files import write_atomic
from .png import read_png, write_png



# ---------------------------------------------------------------- images

def read_mask(path) -> np.ndarray:
    """Boolean (H, W): nonzero first channel of an EXR or 8/16-bit PNG."""
    p = Path(path)
    if p.suffix.lower() == ".exr":
        return read_rgba(p)[..., 0] > 0
    return read_png(p)[..., 0] > 0


# ---------------------------------------------------------------- figures

def metrics(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None, threshold: float = 0.01) -> dict:
    """The error figures of the module doc for (H, W, 4) images a and b."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    if a.shape != b.shape or a.ndim != 3 or a.shape[2] != 4:
        raise ValueError(f"images must both be (H, W, 4); got {a.shape} and {b.shape}")
    sa = np.abs(a[..., :3]).sum(-1)
    sb = np.abs(b[..., :3]).sum(-1)
    ref = 0.5 * (sa + sb)
    diff = np.abs(a[..., :3] - b[..., :3]).sum(-1)
    out = _rel(diff, ref, np.ones(ref.shape, bool), threshold)
    flux_b = b[..., :3].sum()
    out["flux_ratio"] = float(a[..., :3].sum() / flux_b) if flux_b != 0 else float("nan")
    da = np.abs(a[..., 3] - b[..., 3])
    out["max_alpha_diff"] = float(da.max())
    out["mean_alpha_diff"] = float(da.mean())
    out["threshold"] = threshold
    out["pixels"] = int(ref.size)
    if mask is not None:
        mask = np.asarray(mask, bool)
        if mask.shape != ref.shape:
            raise ValueError(f"mask is {mask.shape}, images are {ref.shape}")
        m = _rel(diff, ref, mask, threshold)
        out["mask_pixels"] = int(mask.sum())
        out["mask_mean_rel_err"] = m["mean_rel_err"]
        out["mask_bright_pixels"] = m["bright_pixels"]
        fb = b[..., :3][mask].sum()
        out["mask_flux_ratio"] = float(a[..., :3][mask].sum() / fb) if fb != 0 else float("nan")
    return out


def _rel(diff, ref, sel, threshold):
    if not sel.any():
        return {"mean_rel_err": float("nan"), "bright_pixels": 0, "peak": 0.0}
    peak = float(ref[sel].max())
    bright = sel & (ref > threshold * peak) & (ref > 0)
    if not bright.any():
        return {"mean_rel_err": float("nan"), "bright_pixels": 0, "peak": peak}
    return {"mean_rel_err": float((diff[bright] / ref[bright]).mean()), "bright_pixels": int(bright.sum()),
            "peak": peak}


def relative_difference(a, b, threshold: float = 0.01):
    """Signed (|A|_1 - |B|_1) / mean per pixel, NaN where not bright."""
    sa = a[..., :3].sum(-1)
    sb = b[..., :3].sum(-1)
    ref = 0.5 * (np.abs(a[..., :3]).sum(-1) + np.abs(b[..., :3]).sum(-1))
    peak = ref.max() if ref.size else 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = (sa - sb) / ref
    rel[~((ref > threshold * peak) & (ref > 0))] = np.nan
    return rel


def terrain_mask(scene_toml, width: int, height: int) -> np.ndarray:
    """Pixels whose centre and four corners all see the "plane" terrain in
    front of the camera: the plane z = terrain.height on flat ground, the
    sphere of radius R + terrain.height about (0, 0, -R) on a round Earth
    (`earth.radius_km` = R > 0), as `aurora render` and the add-on lay it."""
    st = addon.scene_toml()
    load_scene, pixel_ray = st.load_scene, st.pixel_ray

    spec = load_scene(scene_toml)
    if spec.terrain.kind != "plane":
        raise ValueError(f"{scene_toml}: --terrain-mask needs terrain.kind = \"plane\" (got {spec.terrain.kind!r})")
    if (spec.render.width, spec.render.height) != (width, height):
        raise ValueError(f"{scene_toml}: scene is {spec.render.width}x{spec.render.height}, images {width}x{height}")
    z = spec.terrain.height
    R = spec.earth.radius_km

    def hits(o, d):
        if R <= 0.0:
            return d[2] != 0 and (z - o[2]) / d[2] > 0
        # |o + t d - c|^2 = (R + z)^2, c = (0, 0, -R): a root with t > 0.
        oc = (o[0], o[1], o[2] + R)
        b = sum(oc[i] * d[i] for i in range(3))
        cc = sum(v * v for v in oc) - (R + z) ** 2
        disc = b * b - cc * sum(v * v for v in d)
        return disc >= 0.0 and (-b + disc ** 0.5) > 0.0

    mask = np.ones((height, width), bool)
    for dx, dy in ((0.5, 0.5), (0, 0), (1, 0), (0, 1), (1, 1)):
        for r in range(height):
            for c in range(width):
                o, d = pixel_ray(spec.camera, width, height, c + dx, r + dy)
                mask[r, c] &= hits(o, d)
    return mask


# ---------------------------------------------------------------- picture

def _srgb8(x):
    x = np.clip(x, 0.0, 1.0)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (y * 255 + 0.5).astype(np.uint8)


def diverging(t):
    """Blue (-1) - white (0) - red (+1), linear in each half; t in [-1, 1]."""
    t = np.clip(t, -1, 1)[..., None]
    blue = np.array([0.23, 0.30, 0.75])
    red = np.array([0.71, 0.02, 0.15])
    white = np.ones(3)
    return np.where(t < 0, white + (blue - white) * (-t), white + (red - white) * t)


def nice_range(rel) -> float:
    """A round colour-bar range covering the 99th percentile of |rel|."""
    v = np.abs(rel[np.isfinite(rel)])
    q = float(np.percentile(v, 99)) if v.size else 0.01
    for r in (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0):
        if q <= r:
            return r
    return 2.0


def make_picture(a, b, m: dict, threshold: float = 0.01, rel_range: float | None = None,
                 mask: np.ndarray | None = None) -> np.ndarray:
    """uint8 (H, W, 3) picture: A | B | relative difference + colour bar + figures."""
    h, w = a.shape[:2]
    scale = max(1, int(math.ceil(320 / w)))
    both = np.concatenate([a[..., :3].ravel(), b[..., :3].ravel()])
    white = float(np.percentile(both, 99.5)) if both.size else 1.0
    white = white if white > 0 else 1.0
    rel = relative_difference(a, b, threshold)
    r = rel_range or nice_range(rel)
    dimg = diverging(np.nan_to_num(rel / r))
    dimg[~np.isfinite(rel)] = 0.15
    if mask is not None:  # outline the mask: darken outside it a little
        dimg[~mask] *= 0.6
    tiles = [_srgb8(a[..., :3] / white), _srgb8(b[..., :3] / white), (dimg * 255 + 0.5).astype(np.uint8)]
    tiles = [t.repeat(scale, 0).repeat(scale, 1) for t in tiles]
    th, tw = tiles[0].shape[:2]
    pad, bar_w, label_h = 8, 14, 14
    text_lines = [
        f"MEAN REL ERR {100 * m['mean_rel_err']:.3f}%  FLUX A/B {m['flux_ratio']:.5f}",
        f"MAX ALPHA DIFF {m['max_alpha_diff']:.4f}  BRIGHT PX {m['bright_pixels']}",
    ]
    if "mask_mean_rel_err" in m:
        text_lines.append(f"MASK: MEAN REL ERR {100 * m['mask_mean_rel_err']:.3f}%  FLUX A/B {m['mask_flux_ratio']:.5f}")
    text_h = len(text_lines) * 10 + 4
    W = 3 * tw + 4 * pad + bar_w + 48
    H = label_h + th + 2 * pad + text_h
    img = np.full((H, W, 3), 32, np.uint8)
    for i, t in enumerate(tiles):
        x0 = pad + i * (tw + pad)
        img[label_h + pad:label_h + pad + th, x0:x0 + tw] = t
    _text(img, pad, 3, "A")
    _text(img, pad + tw + pad, 3, "B")
    _text(img, pad + 2 * (tw + pad), 3, "(A-B)/MEAN")
    # Colour bar: +r at the top, -r at the bottom.
    bx = 3 * (tw + pad) + pad
    ys = np.linspace(1, -1, th)
    img[label_h + pad:label_h + pad + th, bx:bx + bar_w] = (diverging(ys)[:, None, :] * 255 + 0.5).astype(np.uint8)
    pct = f"{100 * r:g}%"
    _text(img, bx + bar_w + 3, label_h + pad, "+" + pct)
    _text(img, bx + bar_w + 3, label_h + pad + th // 2 - 3, "0")
    _text(img, bx + bar_w + 3, label_h + pad + th - 7, "-" + pct)
    for i, line in enumerate(text_lines):
        _text(img, pad, label_h + th + 2 * pad + 2 + 10 * i, line)
    return img


# A 5x7 bitmap font for the labels: each glyph is 7 rows of 5 bits.
_FONT = {
    " ": "00000" * 7,
    "0": "01110100011001110101110011000101110", "1": "00100011000010000100001000010001110",
    "2": "01110100010000100010001000100011111", "3": "11111000100010000010000011000101110",
    "4": "00010001100101010010111110001000010", "5": "11111100001111000001000011000101110",
    "6": "00110010001000011110100011000101110", "7": "11111000010001000100010000100001000",
    "8": "01110100011000101110100011000101110", "9": "01110100011000101111000010001001100",
    ".": "00000000000000000000000000110001100", "-": "00000000000000011111000000000000000",
    "+": "00000001000010011111001000010000000", "%": "11000110010001000100010001001100011",
    "/": "00000000010001000100010001000000000", "(": "00010001000100001000010000010000010",
    ")": "01000001000001000010000100010001000", ":": "00000011000110000000011000110000000",
    "A": "01110100011000111111100011000110001", "B": "11110100011000111110100011000111110",
    "C": "01110100011000010000100001000101110", "D": "11100100101000110001100011001011100",
    "E": "11111100001000011110100001000011111", "F": "11111100001000011110100001000010000",
    "G": "01110100011000010111100011000101111", "H": "10001100011000111111100011000110001",
    "I": "01110001000010000100001000010001110", "K": "10001100101010011000101001001010001",
    "L": "10000100001000010000100001000011111", "M": "10001110111010110101100011000110001",
    "N": "10001100011100110101100111000110001", "O": "01110100011000110001100011000101110",
    "P": "11110100011000111110100001000010000", "R": "11110100011000111110101001001010001",
    "S": "01111100001000001110000010000111110", "T": "11111001000010000100001000010000100",
    "U": "10001100011000110001100011000101110", "W": "10001100011000110101101011010101010",
    "X": "10001100010101000100010101000110001", "Y": "10001100010101000100001000010000100",
}


def _text(img, x, y, s, color=(230, 230, 230)):
    for ch in s.upper():
        g = _FONT.get(ch, _FONT[" "])
        for row in range(7):
            for col in range(5):
                if g[row * 5 + col] == "1" and 0 <= y + row < img.shape[0] and 0 <= x + col < img.shape[1]:
                    img[y + row, x + col] = color
        x += 6


def compare(a_path, b_path, out_png=None, json_path=None, mask=None, threshold: float = 0.01,
            rel_range: float | None = None) -> dict:
    a = read_rgba(a_path)
    b = read_rgba(b_path)
    m = metrics(a, b, mask, threshold)
    m["a"] = str(a_path)
    m["b"] = str(b_path)
    if out_png:
        write_png(out_png, make_picture(a, b, m, threshold, rel_range, mask))
    if json_path:
        write_atomic(json_path, (json.dumps(m, indent=2, sort_keys=True) + "\n").encode())
    return m
