"""A one-voxel shell of active zero voxels around a VDB's non-zero voxels.

Why (measured with bpy 5.0.1, tests/python/test_cycles_closed_forms.py):
trilinear interpolation spreads a voxel's value one voxel in every direction,
so the field is non-zero up to one voxel beyond the last non-zero voxel,
also diagonally. Cycles' biased (ray-marching) volume mode only marches
inside bounds built from the active voxels grown by one voxel across faces,
not across edges and corners: where two or three axes leave the active set
at once, on the low-index side, part of the ramp is cut. A 16-voxel box then
loses half a voxel of path (3%) along its low edges and a lone voxel renders
as a lopsided blob. The unbiased mode is not affected. With every voxel of
the 26-neighbourhood of the non-zero set active (value 0: the field is
unchanged) the biased mode matches trilinear interpolation exactly.

`pad_vdb(src, dst)` writes such a copy (all grids, file metadata kept); it
uses Blender's own OpenVDB module, `openvdb`.
`has_cycles_shell(path)` tells whether a file already carries the shell:
`aurora bake` writes it with `grid.cycles_shell = true` (off by default) and marks
every grid with the metadata `aurora_cycles_shell = true`, so the add-on
need not copy it.
"""

from __future__ import annotations

import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class PadReport:
    grids: dict  # name -> number of voxels switched on
    seconds: float


def shell_mask(nonzero: np.ndarray) -> np.ndarray:
    """Voxels in the 26-neighbourhood of `nonzero` but not in it (3D bool array;
    the outermost layer of the result is not reliable: callers keep a margin)."""
    grown = nonzero.copy()
    for axis in range(3):  # separable dilation: a 3x3x3 cube = three 3-wide lines
        g = grown.copy()
        sl_lo = [slice(None)] * 3
        sl_hi = [slice(None)] * 3
        sl_lo[axis] = slice(0, -1)
        sl_hi[axis] = slice(1, None)
        g[tuple(sl_lo)] |= grown[tuple(sl_hi)]
        g[tuple(sl_hi)] |= grown[tuple(sl_lo)]
        grown = g
    return grown & ~nonzero


def pad_grid(grid, slab: int = 32) -> int:
    """Switch on (value 0) every inactive voxel next to a non-zero voxel."""
    if grid.activeVoxelCount() == 0:
        return 0
    (i0, j0, k0), (i1, j1, k1) = grid.evalActiveVoxelBoundingBox()
    lo = np.array([i0, j0, k0]) - 1
    hi = np.array([i1, j1, k1]) + 1
    ny, nz = int(hi[1] - lo[1] + 3), int(hi[2] - lo[2] + 3)
    vec = grid.valueTypeName in ("vec3s", "vec3f", "vec3d")
    acc = grid.getAccessor()
    switched = 0
    for x0 in range(int(lo[0]), int(hi[0]) + 1, slab):
        # One voxel of margin on every side so the dilation sees its neighbours.
        shape = (slab + 2, ny, nz) + ((3,) if vec else ())
        arr = np.zeros(shape, np.float32)
        grid.copyToArray(arr, ijk=(x0 - 1, int(lo[1]) - 1, int(lo[2]) - 1))
        nonzero = np.any(arr != 0, axis=-1) if vec else arr != 0
        if not nonzero.any():
            continue
        shell = shell_mask(nonzero)
        shell[0] = shell[-1] = False  # margins belong to the neighbouring slabs
        for i, j, k in np.argwhere(shell):
            ijk = (int(x0 - 1 + i), int(lo[1] - 1 + j), int(lo[2] - 1 + k))
            if not acc.isValueOn(ijk):
                acc.setActiveState(ijk, True)
                switched += 1
    return switched


def has_cycles_shell(path) -> bool:
    """True when every grid of the file says `aurora_cycles_shell = true`
    (reads the grids' metadata only, not their voxels)."""
    import openvdb

    grids = openvdb.readAllGridMetadata(str(path))
    if not grids:
        return False
    for g in grids:
        try:
            flag = g["aurora_cycles_shell"]
        except (KeyError, TypeError):
            return False
        if flag is not True:
            return False
    return True


def pad_vdb(src, dst) -> PadReport:
    """Copy `src` to `dst` with every grid padded (see the module doc)."""
    import openvdb

    t0 = time.perf_counter()
    grids, meta = openvdb.readAll(str(src))
    report = {}
    for g in grids:
        report[g.name] = pad_grid(g)
    dst = Path(dst)
    dst.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{dst.name}.", suffix=".tmp.vdb", dir=dst.parent)
    os.close(fd)
    try:
        openvdb.write(tmp, grids=grids, metadata=meta)
        os.replace(tmp, dst)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return PadReport(report, time.perf_counter() - t0)
