"""The Blender add-on in ../blender, loaded once per process under one name,
`aurora_importer` (what an installed extension's code imports as its own
package). Every tool and test goes through `load_addon`, so the add-on's
modules and classes exist once: loading it a second time under another name
(`blender`) would make two copies of every class, and `isinstance` checks
across them fail."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from . import ROOT

#: The one name the add-on is loaded under.
NAME = "aurora_importer"


def blender_openvdb_on_path() -> None:
    """Lets the add-on's `import openvdb` find Blender's own module outside
    Blender: the bpy wheel ships it in a site-packages folder of its own,
    which is appended to sys.path (at the end, so that usd-core's `pxr`
    stays ahead of Blender's). Inside Blender, or where `openvdb` is
    already importable, nothing changes."""
    if importlib.util.find_spec("openvdb") is not None:
        return
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        return
    found = sorted(Path(spec.submodule_search_locations[0]).glob("*/python/lib/python3*/site-packages"))
    if found and str(found[-1]) not in sys.path:
        sys.path.append(str(found[-1]))


def load_addon(name: str = NAME):
    """Import ../blender as a package (relative imports inside it work under
    any name), with Blender's `openvdb` reachable as inside Blender."""
    if name in sys.modules:
        return sys.modules[name]
    blender_openvdb_on_path()
    init = ROOT / "blender" / "__init__.py"
    spec = importlib.util.spec_from_file_location(name, init, submodule_search_locations=[str(init.parent)])
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def scene_toml():
    """The add-on's scene reader (`blender/scene_toml.py`: load_scene,
    pixel_ray), from the one loaded add-on."""
    load_addon()
    return importlib.import_module(f"{NAME}.scene_toml")
