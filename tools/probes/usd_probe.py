"""What usd-core (pxr) sees in a USD stage, as JSON.

Runs under the project venv's Python (.venv/bin/python; see tools/setup).
Used by tests/vdb/blender.rs.

  usd_probe.py STAGE.usda

Prints one JSON line: stage metadata (defaultPrim, metersPerUnit, upAxis),
every prim's path and type, and for each UsdVol.Volume its field
relationships and, per OpenVDBAsset field, the authored and resolved file
path, fieldName, fieldClass (and whether it is one of the schema's allowed
tokens), fieldDataType, plus the Volume's local transform.
"""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.probe import require  # noqa: E402

Sdf, Usd, UsdGeom, UsdVol = (require(f"pxr.{m}", "pxr (usd-core)") for m in ("Sdf", "Usd", "UsdGeom", "UsdVol"))


def main(path):
    stage = Usd.Stage.Open(path)
    out = {
        "default_prim": str(stage.GetDefaultPrim().GetPath()) if stage.GetDefaultPrim() else None,
        "meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
        "up_axis": str(UsdGeom.GetStageUpAxis(stage)),
        "prims": [[str(p.GetPath()), str(p.GetTypeName())] for p in stage.Traverse()],
        "volumes": [],
    }
    for prim in stage.Traverse():
        if not prim.IsA(UsdVol.Volume):
            continue
        vol = UsdVol.Volume(prim)
        xf = UsdGeom.Xformable(prim).GetLocalTransformation()
        fields = {}
        for name, target in vol.GetFieldPaths().items():
            asset = UsdVol.OpenVDBAsset(stage.GetPrimAtPath(target))
            fp = asset.GetFilePathAttr().Get()
            fclass = asset.GetFieldClassAttr()
            allowed = list(fclass.GetMetadata("allowedTokens") or [])
            fields[name] = {
                "prim": str(target),
                "is_openvdb_asset": bool(asset),
                "file_path": fp.path,
                "resolved_path": fp.resolvedPath,
                "field_name": asset.GetFieldNameAttr().Get(),
                "field_class": fclass.Get(),
                "field_class_allowed": allowed,
                "field_data_type": asset.GetFieldDataTypeAttr().Get(),
            }
        out["volumes"].append({
            "path": str(prim.GetPath()),
            "fields": fields,
            "local_transform": [list(r) for r in xf],
        })
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1])
