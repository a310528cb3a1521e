"""What Blender (bpy 5.0.1) sees in a VDB file or a USD stage, as JSON.

Runs under the project venv's Python (.venv/bin/python; see tools/setup).
Used by tests/vdb/blender.rs.

  blender_probe.py FILE...      per file, in a fresh empty scene:
                                FILE.vdb: load it as a Volume datablock on an object;
                                FILE.usda: import it with bpy.ops.wm.usd_import

Prints one JSON line, a list with one entry per file: per Volume object, its name, location/scale/dimensions,
world matrix, the volume's file path, load error, and per grid its name,
data type, channels, index-to-object matrix and whether grid.load() succeeded.
The object's bounds are Blender's: the union of the grids' leaf-node boxes,
half a voxel beyond the outermost voxel centres.
"""
import json
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.probe import require  # noqa: E402

bpy = require("bpy")


def matrix(m):
    return [list(row) for row in m]


def describe(obj):
    vol = obj.data
    grids_ok = vol.grids.load()
    grids = []
    for g in vol.grids:
        load_ok = g.load()
        grids.append({
            "name": g.name,
            "data_type": g.data_type,
            "channels": g.channels,
            "matrix_object": matrix(g.matrix_object),
            "load_ok": bool(load_ok),
        })
    bpy.context.view_layer.update()
    return {
        "object": obj.name,
        "filepath": vol.filepath,
        "abs_filepath": bpy.path.abspath(vol.filepath),
        "grids_loaded": bool(grids_ok),
        "error": vol.grids.error_message,
        "grids": grids,
        "location": list(obj.location),
        "scale": list(obj.scale),
        "rotation_euler": list(obj.rotation_euler),
        "dimensions": list(obj.dimensions),
        "bound_box": [list(c) for c in obj.bound_box],
        "matrix_world": matrix(obj.matrix_world),
    }


def probe(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    path = os.path.abspath(path)
    if path.endswith(".vdb"):
        vol = bpy.data.volumes.new("probe")
        vol.filepath = path
        obj = bpy.data.objects.new("probe", vol)
        bpy.context.scene.collection.objects.link(obj)
        objects = [obj]
        result = {"mode": "vdb"}
    else:
        status = bpy.ops.wm.usd_import(filepath=path)
        objects = [o for o in bpy.data.objects if o.type == "VOLUME"]
        result = {"mode": "usd", "import_status": sorted(status)}
    result["volumes"] = [describe(o) for o in objects]
    result["object_types"] = sorted(o.type for o in bpy.data.objects)
    return result


if __name__ == "__main__":
    print(json.dumps([probe(p) for p in sys.argv[1:]]))
