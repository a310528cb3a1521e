"""Presets: the binary's built-in scenes, read into `scene.aurora`.

`aurora scene --list` names them, `aurora scene NAME` prints one, which
`AURORA_OT_load_preset` reads into the panel's properties (its camera,
resolution and frame rate are the shot's, not the preset's, and are left
alone: properties.load_document).
"""

from __future__ import annotations

import subprocess
import tomllib

import bpy
from bpy.props import StringProperty

from .. import properties as P
from ..bake_job import BakeError
from ..preferences import aurora_binary

#: Presets when the binary predates `aurora scene --list`.
FALLBACK_PRESETS = ("default", "seed2014")

_preset_cache: dict[str, list[str]] = {}


def list_presets(binary: str) -> list[str]:
    """`aurora scene --list`: one preset per line, its name first; the
    fallback names when the binary cannot be run or predates `--list`."""
    try:
        out = subprocess.run([binary, "scene", "--list"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return list(FALLBACK_PRESETS)
    if out.returncode != 0:
        return list(FALLBACK_PRESETS)
    names = [line.split()[0] for line in out.stdout.splitlines() if line.strip()]
    return names or list(FALLBACK_PRESETS)


def cached_presets(binary: str) -> list[str]:
    """`list_presets`, run once per binary (a menu is drawn often)."""
    if binary not in _preset_cache:
        _preset_cache[binary] = list_presets(binary)
    return _preset_cache[binary]


def preset_document(binary: str, name: str) -> dict:
    out = subprocess.run([binary, "scene", name], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise BakeError(f"aurora scene {name}: {out.stderr.strip() or f'exit status {out.returncode}'}")
    return tomllib.loads(out.stdout)


class AURORA_OT_load_preset(bpy.types.Operator):
    """Set the Aurora panel from one of the binary's built-in scenes"""

    bl_idname = "aurora.load_preset"
    bl_label = "Load Aurora Preset"
    bl_options = {"REGISTER", "UNDO"}

    name: StringProperty(name="Preset", default="default")

    def execute(self, context):
        try:
            doc = preset_document(aurora_binary(context), self.name)
        except (BakeError, OSError, subprocess.SubprocessError, tomllib.TOMLDecodeError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        P.load_document(context.scene.aurora, doc)
        context.scene.aurora.preset = self.name
        return {"FINISHED"}


classes = (AURORA_OT_load_preset,)
