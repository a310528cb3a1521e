"""Synthetic inputs and closed forms for the Cycles tests.

- VDB writing with pyopenvdb, as *leaf voxels* (an active tile is interpolated
  differently at a box's low edge: docs/guide.md, "How Cycles reads the VDB");
- a small TOML writer for scene files;
- the trilinear "box" field of an N^3 block of voxels and the pixel-averaged
  closed forms for emission, absorption and both;
- a brute-force numpy ray marcher over a dense voxel array (the oracle for
  perspective views and thin curtains).

Trilinear field of a box (voxel centres at index points, OpenVDB/Cycles):
voxels i = 0..N-1 of value v, centred at o + i*h, inactive (0) outside. Along
one axis the interpolated profile is w(x) = 1 on [o, o + (N-1)h], falling
linearly to 0 at o - h and o + N h, so integral w dx = (N-1) h + 2 * h/2 = N h,
and the field is v w(x) w(y) w(z). An orthographic ray along y through
(x, z) sees optical path d(x, z) = N h w(x) w(z).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np


# ---------------------------------------------------------------- VDB files

def write_vdb(path, voxel_size: float, origin, density=None, emission=None) -> Path:
    """Write dense arrays (density (nx,ny,nz); emission (nx,ny,nz,3) or
    (nx,ny,nz)) as leaf voxels; index (0,0,0) is centred at `origin` (km)."""
    import pyopenvdb as vdb

    grids = []
    m = [[voxel_size, 0, 0, 0], [0, voxel_size, 0, 0], [0, 0, voxel_size, 0], [*map(float, origin), 1]]
    for name, arr in (("density", density), ("emission", emission)):
        if arr is None:
            continue
        arr = np.ascontiguousarray(arr, dtype=np.float32)
        vec = arr.ndim == 4
        g = vdb.Vec3SGrid() if vec else vdb.FloatGrid()
        g.name = name
        g.transform = vdb.createLinearTransform(m)
        g.copyFromArray(arr, (0, 0, 0), (0.0, 0.0, 0.0) if vec else 0.0)
        if g.activeLeafVoxelCount() != g.activeVoxelCount():
            # copyFromArray made active tiles of constant blocks. Writing a
            # different value into one voxel of every 8^3 block forces a leaf
            # there; writing the value back leaves the leaf (no pruning).
            acc = g.getAccessor()
            nz = np.any(arr != 0, axis=-1) if vec else arr != 0
            for bi in range(0, nz.shape[0], 8):
                for bj in range(0, nz.shape[1], 8):
                    for bk in range(0, nz.shape[2], 8):
                        blk = np.argwhere(nz[bi:bi + 8, bj:bj + 8, bk:bk + 8])
                        if len(blk) == 0:
                            continue
                        ijk = tuple(int(c) for c in blk[0] + (bi, bj, bk))
                        v = arr[ijk]
                        val = tuple(float(c) for c in v) if vec else float(v)
                        bumped = tuple(c + 1.0 for c in val) if vec else val + 1.0
                        acc.setValueOn(ijk, bumped)
                        acc.setValueOn(ijk, val)
        assert g.activeLeafVoxelCount() == g.activeVoxelCount(), "tiles left in the grid"
        grids.append(g)
    vdb.write(str(path), grids=grids)
    return Path(path)


def box_arrays(n: int, density: float | None, emission):
    """Dense arrays for an n^3 box of constant values."""
    d = None if density is None else np.full((n, n, n), density, np.float32)
    e = None
    if emission is not None:
        e = np.empty((n, n, n, 3), np.float32) if np.ndim(emission) else np.empty((n, n, n), np.float32)
        e[...] = emission
    return d, e


# ---------------------------------------------------------------- TOML

def toml_dumps(doc: dict) -> str:
    """Enough TOML for scene files: nested tables, arrays of tables, numbers,
    strings, booleans and flat lists."""

    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v) if isinstance(v, int) else repr(float(v))
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(x) for x in v) + "]"
        raise TypeError(f"cannot write {v!r} as TOML")

    lines = []
    scalars = {k: v for k, v in doc.items() if not isinstance(v, dict) and not _is_table_array(v)}
    for k, v in scalars.items():
        lines.append(f"{k} = {val(v)}")
    for k, v in doc.items():
        if isinstance(v, dict):
            lines.append(f"\n[{k}]")
            lines += [f"{kk} = {val(vv)}" for kk, vv in v.items()]
        elif _is_table_array(v):
            for t in v:
                lines.append(f"\n[[{k}]]")
                lines += [f"{kk} = {val(vv)}" for kk, vv in t.items()]
    return "\n".join(lines) + "\n"


def _is_table_array(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def write_scene(path, camera: dict, width: int, height: int, spp: int = 16, density_scale=1.0,
                emission_scale=1.0, background=(0.0, 0.0, 0.0), terrain: dict | None = None,
                extinction: bool = False) -> Path:
    """A scene file for the closed forms: no air unless `extinction`, no
    stars, no airglow (the volume's own emission-absorption model alone)."""
    doc = {
        "camera": camera,
        "render": {"width": width, "height": height, "spp": spp, "exposure": 0.0},
        "volume": {"density_scale": float(density_scale), "emission_scale": float(emission_scale)},
        "background": {"radiance": [float(x) for x in background], "stars": False},
        "terrain": terrain or {"kind": "none"},
        "sky": {"extinction": bool(extinction)},
        "airglow": {"on": False},
    }
    Path(path).write_text(toml_dumps(doc))
    return Path(path)


# ---------------------------------------------------------------- closed forms

def ramp_profile(x, lo_centre: float, hi_centre: float, h: float):
    """w(x): 1 between the first and last voxel centres, linear to 0 one voxel beyond."""
    x = np.asarray(x, dtype=np.float64)
    return np.clip(np.minimum((x - (lo_centre - h)) / h, ((hi_centre + h) - x) / h), 0.0, 1.0)


def ramp_pixel_mean(a, b, lo_centre: float, hi_centre: float, h: float):
    """Exact mean of w over [a, b] (w is piecewise linear: integrate its antiderivative)."""

    def W(x):  # antiderivative of w, W(-inf) = 0
        x = np.asarray(x, dtype=np.float64)
        l0, l1, r0, r1 = lo_centre - h, lo_centre, hi_centre, hi_centre + h
        up = np.clip(x, l0, l1) - l0
        flat = np.clip(x, l1, r0) - l1
        down = np.clip(x, r0, r1) - r0
        return up * up / (2 * h) + flat + (down - down * down / (2 * h))

    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return (W(b) - W(a)) / (b - a)


def ortho_pixel_edges(center_u: float, center_v: float, ortho_height: float, width: int, height: int):
    """Pixel edge coordinates along the image's right (u) and up (v) axes for
    an orthographic camera: column c spans u in [u_c, u_c+1]; row r (row 0 at
    the top) spans v from v_edges[r+1] to v_edges[r]."""
    p = ortho_height / height
    u = center_u + (np.arange(width + 1) - width / 2) * p
    v = center_v + (height / 2 - np.arange(height + 1)) * p
    return u, v


def gauss_legendre_pixel_mean(f, u_edges, v_edges, order: int = 4, sub: int = 16):
    """Mean of f(u, v) over every pixel (rows from the top): each pixel is cut
    into sub x sub cells with `order`-point Gauss-Legendre rules on each axis.
    The box fields are smooth except on the kinks of the ramps; a kink inside
    a cell of width c costs O(c^2) of that cell's share, so 16 cells per pixel
    keep the error far below 1e-4 of the value."""
    x, w = np.polynomial.legendre.leggauss(order)
    x = ((np.arange(sub)[:, None] + (x[None, :] + 1) / 2) / sub).ravel()  # composite nodes in [0, 1]
    w = np.tile(w / 2 / sub, sub)
    ua, ub = u_edges[:-1], u_edges[1:]
    vt, vb = v_edges[:-1], v_edges[1:]  # top and bottom of each row
    uu = ua[:, None] + (ub - ua)[:, None] * x[None, :]  # (W, q)
    vv = vb[:, None] + (vt - vb)[:, None] * x[None, :]  # (H, q)
    out = np.empty((len(vt), len(ua)) + np.shape(f(uu[:1, :1], vv[:1, :1]))[2:])
    for r in range(len(vt)):  # row by row: bounded memory
        vals = f(uu[None, :, None, :], vv[r][None, None, :, None])  # (1, W, q, q, ...)
        out[r] = np.einsum("owij...,i,j->w...", vals, w, w)
    return out


# ---------------------------------------------------------------- brute-force oracle

def trilinear(arr, ijk):
    """Trilinear sample of a dense array (zero outside) at fractional index points (..., 3)."""
    ijk = np.asarray(ijk, dtype=np.float64)
    base = np.floor(ijk).astype(np.int64)
    t = ijk - base
    shape = np.array(arr.shape[:3])
    out = np.zeros(ijk.shape[:-1] + arr.shape[3:], dtype=np.float64)
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                idx = base + np.array([dx, dy, dz])
                ok = np.all((idx >= 0) & (idx < shape), axis=-1)
                wgt = (np.where(dx, t[..., 0], 1 - t[..., 0]) * np.where(dy, t[..., 1], 1 - t[..., 1])
                       * np.where(dz, t[..., 2], 1 - t[..., 2]))
                ic = np.clip(idx, 0, shape - 1)
                v = arr[ic[..., 0], ic[..., 1], ic[..., 2]]
                v = np.where(ok[..., None] if arr.ndim == 4 else ok, v, 0.0)
                out += (wgt[..., None] if arr.ndim == 4 else wgt) * v
    return out


def ray_box(origins, dirs, lo, hi):
    """Slab test: entry and exit distances (t0 <= t1; t1 < t0 where missed), t0 >= 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs
        a = (np.asarray(lo)[None, :] - origins) * inv
        b = (np.asarray(hi)[None, :] - origins) * inv
    t0 = np.nanmax(np.minimum(a, b), axis=1)
    t1 = np.nanmin(np.maximum(a, b), axis=1)
    return np.maximum(t0, 0.0), t1


def march(origins, dirs, voxel_size, origin, density, emission, background, n_steps: int = 2000):
    """Oracle: L and T along rays (origins, dirs: (R, 3)) through the
    trilinear field of dense arrays whose index (0,0,0) is centred at
    `origin`, clipped to the field's support and cut into `n_steps` midpoint
    steps: L = sum e_k T_k ds, T_k = exp(-tau) at the step midpoint, plus
    T L_bg. The field is piecewise linear, so the midpoint rule is exact on
    each linear piece and errs by O(ds^2) only where a step crosses a kink."""
    origins = np.asarray(origins, np.float64)
    dirs = np.asarray(dirs, np.float64)
    o = np.asarray(origin, np.float64)
    shape = np.array((density if density is not None else emission).shape[:3])
    lo = o - voxel_size
    hi = o + (shape) * voxel_size  # last centre + one voxel
    t0, t1 = ray_box(origins, dirs, lo, hi)
    ds = np.where(t1 > t0, (t1 - t0) / n_steps, 0.0)
    L = np.zeros((len(origins), 3))
    tau = np.zeros(len(origins))
    for k in range(n_steps):
        p = origins + dirs * (t0 + (k + 0.5) * ds)[:, None]
        ijk = (p - o) / voxel_size
        sig = trilinear(density, ijk) if density is not None else np.zeros(len(p))
        tau_mid = tau + 0.5 * sig * ds
        if emission is not None:
            e = trilinear(emission, ijk)
            if e.ndim == 1:
                e = np.repeat(e[:, None], 3, axis=1)
            L += e * (np.exp(-tau_mid) * ds)[:, None]
        tau += sig * ds
    T = np.exp(-tau)
    L += T[:, None] * np.asarray(background, np.float64)[None, :]
    return L, T


def curtain_arrays(voxel_size: float = 0.5, length: float = 60.0, z_range=(90.0, 160.0), sigma_y: float = 0.35,
                   bend: float = 3.0, density_peak: float = 0.05):
    """An aurora-like sheet, about one voxel thick: a Gaussian of sigma_y km
    across y around y = bend sin(2 pi x / 40), emission peaking at 105 km
    with a green-to-red colour ramp with height, extinction
    density_peak * exp(-0.02 (h - 90)) inside the sheet. Returns
    (origin, density, emission) for write_vdb / march."""
    h = voxel_size
    nx = int(round(length / h)) + 1
    ny = int(round((2 * bend + 8 * sigma_y + 2) / h)) + 1
    nz = int(round((z_range[1] - z_range[0]) / h)) + 1
    origin = np.array([-length / 2, -(ny - 1) * h / 2, z_range[0]])
    x = origin[0] + h * np.arange(nx)
    y = origin[1] + h * np.arange(ny)
    z = origin[2] + h * np.arange(nz)
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    yc = bend * np.sin(2 * np.pi * X / 40.0)
    sheet = np.exp(-0.5 * ((Y - yc) / sigma_y) ** 2)
    along = 0.6 + 0.4 * np.cos(2 * np.pi * X / 17.0) ** 2
    alt = np.exp(-0.5 * ((Z - 105.0) / 6.0) ** 2) + 0.25 * np.exp(-0.5 * ((Z - 140.0) / 12.0) ** 2)
    prof = sheet * along * alt
    prof[prof < 1e-4] = 0.0  # sparse: leaves only near the sheet
    red = np.clip((Z - 100.0) / 50.0, 0.0, 1.0)
    emission = np.stack([0.1 + 0.9 * red, 1.0 - 0.7 * red, 0.3 + 0.0 * red], axis=-1) * prof[..., None]
    density = density_peak * np.exp(-0.02 * (Z - 90.0)) * (prof > 0) * sheet
    return origin, density.astype(np.float32), emission.astype(np.float32)


# ---------------------------------------------------------------- terrain under a slab

def slab_irradiance(e, sigma: float, path: float, z_mid: float, half_width: float, n: int = 64):
    """Irradiance at the ground point under the centre of a square slab
    (half-width `half_width` at height `z_mid`, vertical optical path length
    `path` = N h, emission e per km, extinction sigma per km, sharing one
    profile): a ray at mu = cos(theta) crosses path / mu of it, so its radiance
    is (e / sigma)(1 - exp(-sigma path / mu)) (e path / mu for sigma = 0), and
    E = integral over the directions that meet the square of L mu d omega.
    8-fold symmetry, Gauss-Legendre in phi and in mu; the slab's side faces
    are ignored (they subtend path / half_width of the sky at the edge)."""
    e = np.asarray(e, np.float64)
    xp, wp = np.polynomial.legendre.leggauss(n)
    phi = (xp + 1) / 2 * (np.pi / 4)
    wphi = wp / 2 * (np.pi / 4)
    total = 0.0
    for p, wpp in zip(phi, wphi):
        mu_min = np.cos(np.arctan(half_width / (z_mid * np.cos(p))))
        xm, wm = np.polynomial.legendre.leggauss(n)
        mu = mu_min + (xm + 1) / 2 * (1 - mu_min)
        wmu = wm / 2 * (1 - mu_min)
        if sigma > 0:
            g = (1 - np.exp(-sigma * path / mu)) / sigma  # L / e, times mu below
        else:
            g = path / mu
        total += wpp * np.sum(wmu * g * mu)
    return 8 * total * e


def slab_arrays(n_xy: int, n_z: int, density: float, emission):
    """A slab of n_xy x n_xy x n_z voxels of constant density and emission."""
    d = np.full((n_xy, n_xy, n_z), density, np.float32)
    e = np.empty((n_xy, n_xy, n_z, 3), np.float32)
    e[...] = emission
    return d, e
