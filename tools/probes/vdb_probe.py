#!/usr/bin/python3
"""What OpenVDB itself sees in VDB files, as JSON (the reference for aurora's writer).

Runs under Debian's /usr/bin/python3 with pyopenvdb (OpenVDB 10.0.1); see
tools/setup. Used by tests/vdb/openvdb.rs.

  vdb_probe.py [--dump] [--samples SAMPLES.json] FILE...
      For each file: file metadata and, per grid, name, value type, class,
      transform (map type, voxel size, index->world of a few points),
      background, half flag, active voxel count, bounding box, leaf count, all
      metadata; with --samples ({"grid": [[i,j,k], ...]}) the value and
      active state OpenVDB reads at each coordinate; with --dump every active
      value (voxels and tiles).

  vdb_probe.py --write-reference OUT.vdb
      Writes a file with pyopenvdb (its defaults: Blosc + active mask) holding
      float and vec3s grids with negative coordinates, several root children,
      a constant region stored as tiles, a half-float grid, and prints the
      same JSON as above (with --dump) for it.
"""
import json
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.probe import require  # noqa: E402

vdb = require("pyopenvdb")


def jsonable(v):
    """Metadata and values as JSON (tuples to lists, non-finite floats to strings)."""
    if isinstance(v, float):
        return v if math.isfinite(v) else repr(v)
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, (int, str, bool)) or v is None:
        return v
    return repr(v)


def grid_info(grid, samples, dump):
    t = grid.transform
    meta = {k: jsonable(grid[k]) for k in grid.metadata.keys()}
    bbox = grid.evalActiveVoxelBoundingBox()
    info = {
        "name": grid.name,
        "value_type": grid.valueTypeName,
        "class": str(grid.gridClass),
        "background": jsonable(grid.background),
        "half": bool(grid.saveFloatAsHalf),
        "active_voxels": grid.activeVoxelCount(),
        "leaf_count": grid.leafCount(),
        "bbox": [list(bbox[0]), list(bbox[1])],
        "empty": grid.empty(),
        "transform": {
            "type": t.typeName,
            "voxel_size": list(t.voxelSize()),
            "index_to_world": {
                "0,0,0": list(t.indexToWorld((0, 0, 0))),
                "1,2,3": list(t.indexToWorld((1, 2, 3))),
                "-7,100,-1000": list(t.indexToWorld((-7, 100, -1000))),
            },
        },
        "metadata": meta,
    }
    acc = grid.getConstAccessor()
    if samples and grid.name in samples:
        info["samples"] = [
            [list(c), jsonable(acc.getValue(tuple(c))), bool(acc.isValueOn(tuple(c)))] for c in samples[grid.name]
        ]
    if dump:
        voxels, tiles = [], []
        for item in grid.citerOnValues():
            lo, hi = list(item.min), list(item.max)
            if lo == hi:
                voxels.append([lo, jsonable(item.value)])
            else:
                tiles.append([lo, hi, jsonable(item.value)])
        info["voxels"] = voxels
        info["tiles"] = tiles
    return info


def probe(path, samples, dump):
    grids, file_meta = vdb.readAll(path)
    return {
        "path": path,
        "file_metadata": {k: jsonable(v) for k, v in file_meta.items()},
        "grids": [grid_info(g, samples, dump) for g in grids],
    }


def fog_grid(kind, name, voxel_size, offset=(10.0, -20.0, 2.5)):
    """An empty fog-volume grid of `kind` (vdb.FloatGrid, vdb.Vec3SGrid)
    named `name`, its linear transform of `voxel_size` moved by `offset`."""
    grid = kind()
    grid.name = name
    grid.gridClass = vdb.GridClass.FOG_VOLUME
    grid.transform = vdb.createLinearTransform(voxelSize=voxel_size)
    if offset is not None:
        grid.transform.translate(offset)
    return grid


def write_reference(path):
    """Grids covering the cases our reader must handle in OpenVDB's own bytes:
    tiles, vec3s, half floats, a plain float grid, an unsupported type."""
    density = fog_grid(vdb.FloatGrid, "density", 0.25)
    acc = density.getAccessor()
    n = 0
    for i in range(-40, 40, 3):
        for j in range(-5000, 5000, 617):
            for k in range(-9, 9, 4):
                acc.setValueOn((i, j, k), 0.001 * n - 0.3)
                n += 1
    # A constant 16^3 block aligned to an Internal16 child: pyopenvdb's fill
    # stores it as two 8^3 ... tiles at the Internal16 level.
    density.fill((64, 64, 64), (79, 79, 79), 1.5, True)

    emission = fog_grid(vdb.Vec3SGrid, "emission", 0.25)
    acc = emission.getAccessor()
    for i in range(-20, 20, 1):
        for j in range(-3, 3):
            for k in (-4097, 0, 4100):
                acc.setValueOn((i, j, k), (0.5 * i, 0.25 * j + 0.125, k / 8.0))

    half = fog_grid(vdb.Vec3SGrid, "emission_half", 0.5, offset=None)
    half.saveFloatAsHalf = True
    acc = half.getAccessor()
    for i in range(0, 30, 2):
        acc.setValueOn((i, -i, 3 * i), (i / 3.0, 1.0 / (i + 1), -2.0 * i))

    # No tiles: the tests' vdb-rs oracle reads this one too (with Blosc).
    plain = fog_grid(vdb.FloatGrid, "density_plain", 0.25)
    acc = plain.getAccessor()
    for i in range(-300, 300, 7):
        for k in range(-20, 20):
            acc.setValueOn((i, i // 3, k), math.sin(0.01 * i) * math.exp(-0.1 * abs(k)))

    # A type aurora does not read: skipped, the others still load.
    mask = vdb.BoolGrid()
    mask.name = "mask"
    mask.getAccessor().setValueOn((1, 2, 3), True)

    vdb.write(path, grids=[density, emission, half, plain, mask])
    return probe(path, None, True)


def main(argv):
    if len(argv) == 2 and argv[0] == "--write-reference":
        print(json.dumps(write_reference(argv[1])))
        return 0
    dump, samples, files = False, None, []
    it = iter(argv)
    for a in it:
        if a == "--dump":
            dump = True
        elif a == "--samples":
            with open(next(it)) as f:
                samples = json.load(f)
        else:
            files.append(a)
    out = []
    for path in files:
        try:
            out.append(probe(path, samples, dump))
        except Exception as e:  # report, the test asserts on it
            out.append({"path": path, "error": f"{type(e).__name__}: {e}"})
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
