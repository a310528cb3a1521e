"""The Blender add-on in ../blender, loaded once per process under one name,
`aurora_importer` (what an installed extension's code imports as its own
package). Every tool and test goes through `load_addon`, so the add-on's
modules and classes exist once: loading it a second time under another name
(`blender`) would make two copies of every class, and `isinstance` checks
across them fail."""

from __future__ import annotations

import importlib.util
import sys

from . import ROOT

#: The one name the add-on is loaded under.
NAME = "aurora_importer"


def load_addon(name: str = NAME):
    """Import ../blender as a package (relative imports inside it work under any name)."""
    if name in sys.modules:
        return sys.modules[name]
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
