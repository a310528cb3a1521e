"""The add-on's layout and names: one register loop over every module's
`classes`, operator class names that follow their `bl_idname`, the name
shown ("Aurora") against the id kept (`aurora_importer`), and no file of the
add-on that edits sys.path (it imports Blender's own `openvdb`)."""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import tomllib
from pathlib import Path

import pytest

ADDON = Path(__file__).resolve().parents[2] / "blender"

#: What sys.path edits look like, each of which the check must catch.
EDITS = [
    "import sys\nsys.path.append('x')",
    "import sys\nsys.path.insert(0, 'x')",
    "import sys\nsys.path.extend(['x'])",
    "import sys\nsys.path = ['x']",
    "import sys\nsys.path += ['x']",
    "import sys\nsys.path[:0] = ['x']",
    "import sys\ndel sys.path[0]",
    "import sys as s\ns.path.remove('x')",
    "from sys import path\npath.append('x')",
    "import site\nsite.addsitedir('x')",
]
#: Reading sys.path is fine.
READS = ["import sys\nprint(sys.path)", "import sys\nfound = [p for p in sys.path if p]\nfound.append('x')"]


def sys_path_edits(source: str) -> list[int]:
    """Line numbers in `source` that assign to sys.path, call a method on it,
    import it by name, or add a site directory."""
    tree = ast.parse(source)
    sys_names = {a.asname or a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names if a.name == "sys"}

    def is_sys_path(node) -> bool:
        while isinstance(node, ast.Subscript):
            node = node.value
        return (isinstance(node, ast.Attribute) and node.attr == "path" and isinstance(node.value, ast.Name)
                and node.value.id in sys_names)

    hits = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.Delete)):
            targets = node.targets
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        else:
            targets = []
        if any(is_sys_path(t) for t in targets):
            hits.append(node.lineno)
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and (
                is_sys_path(node.func.value) or node.func.attr == "addsitedir"):
            hits.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and node.module == "sys" and any(a.name == "path" for a in node.names):
            hits.append(node.lineno)
    return hits


@pytest.mark.parametrize("source", EDITS)
def test_the_sys_path_check_catches_an_edit(source):
    assert sys_path_edits(source)


@pytest.mark.parametrize("source", READS)
def test_the_sys_path_check_lets_a_read_pass(source):
    assert sys_path_edits(source) == []


def test_no_file_of_the_addon_edits_sys_path():
    files = sorted(p for p in ADDON.rglob("*.py") if "__pycache__" not in p.parts)
    assert len(files) > 10 and ADDON / "operators" / "bake.py" in files
    found = {str(p.relative_to(ADDON)): lines for p in files if (lines := sys_path_edits(p.read_text()))}
    assert found == {}, f"files of the add-on that edit sys.path (file: lines): {found}"


def submodules(addon):
    """Every module of the add-on, imported."""
    return [importlib.import_module(m.name)
            for m in pkgutil.walk_packages(addon.__path__, prefix=f"{addon.__name__}.")]


def blender_classes(module):
    """The Blender classes a module defines (operators, panels, menus,
    lists, property groups, preferences)."""
    import bpy

    kinds = (bpy.types.Operator, bpy.types.Panel, bpy.types.Menu, bpy.types.UIList, bpy.types.PropertyGroup,
             bpy.types.AddonPreferences)
    return {c for c in vars(module).values()
            if inspect.isclass(c) and issubclass(c, kinds) and c not in kinds and c.__module__ == module.__name__}


def test_every_class_is_in_its_modules_classes_and_registers_in_one_loop(addon, bpy):
    defined = set()
    for module in submodules(addon):
        mine = blender_classes(module)
        assert mine <= set(getattr(module, "classes", ())), f"{module.__name__}: classes lacks {mine}"
        defined |= mine
    # The panel's sub-panels are made by a function, so they are listed, not defined by name.
    assert defined <= set(addon.classes) and len(addon.classes) == len(set(addon.classes))
    assert not any(c.is_registered for c in addon.classes)
    addon.register()
    try:
        assert all(c.is_registered for c in addon.classes)
        assert "aurora" in bpy.types.Scene.bl_rna.properties
        entries = bpy.types.TOPBAR_MT_file_import._dyn_ui_initialize()
        assert addon.ui.menus.file_import_entry in entries
    finally:
        addon.unregister()
    assert not any(c.is_registered for c in addon.classes)
    assert "aurora" not in bpy.types.Scene.bl_rna.properties
    assert addon.ui.menus.file_import_entry not in bpy.types.TOPBAR_MT_file_import._dyn_ui_initialize()


def test_class_names_follow_their_bl_idname(addon, bpy):
    """Blender's convention: `aurora.import_vdb` is AURORA_OT_import_vdb; a
    menu's, panel's or list's bl_idname is its class name."""
    operators = [c for c in addon.classes if issubclass(c, bpy.types.Operator)]
    assert {c.bl_idname for c in operators} >= {"aurora.import_vdb", "aurora.bake", "aurora.load_preset"}
    for c in operators:
        prefix, name = c.bl_idname.split(".")
        assert c.__name__ == f"{prefix.upper()}_OT_{name}", c
    for c in addon.classes:
        if issubclass(c, (bpy.types.Menu, bpy.types.Panel, bpy.types.UIList)):
            assert getattr(c, "bl_idname", c.__name__) == c.__name__, c


def test_shown_as_aurora_with_the_id_aurora_importer(addon):
    manifest = tomllib.loads((ADDON / "blender_manifest.toml").read_text())
    assert (manifest["name"], manifest["id"]) == ("Aurora", "aurora_importer")
    assert addon.bl_info["name"] == "Aurora"
    assert addon.__name__ == "aurora_importer"
    # Preferences are stored under the package name; not enabled here, so none.
    assert addon.preferences.AuroraPreferences.bl_idname == "aurora_importer"
    assert addon.preferences.addon_preferences() is None
