"""Import an aurora bake (.vdb, or the .usda that points at it) as a Volume object.

The VDB's own transform places the voxels in km. Units (`units`): "km"
(the default) makes the scene's unit 1 Blender unit = 1 km and puts the
Volume at identity; "scene" keeps the scene's unit settings and scales the
Volume to them (1000 / `unit_settings.scale_length` Blender units per km: a
shot in metres gets 1000); a number is Blender units per km, the scene
untouched. A USD stage is imported with Blender's USD importer, which
scales root prims by the stage's metersPerUnit (aurora writes 1000: km) and
turns Y-up stages to Z-up; its roots are then scaled from metres to the
chosen units. Path lengths are measured in the grid's own units
(`volume.render.space` OBJECT), the units of the bake's per-km density and
emission, so the picture is the same at any scale.

Sequences (`aurora bake --frames`): importing any `aurora.NNNN.vdb` of a
folder, or the folder's time-sampled `aurora.usda`, sets the Volume up as
Blender's own sequence (is_sequence, frame_start, frame_duration,
frame_offset: Blender loads file number scene frame - frame_start + 1 +
frame_offset, digits before the extension replaced at the same width), and
with `set_frame_range` (the default) the scene's frame range and fps to the
sequence's (fps from the frame's `aurora.NNNN.json`, or the stage's
timeCodesPerSecond), and the current frame to the imported file's (a
stage: its first frame); without it the shot's range, fps and current frame
stay, and the Volume still plays its frames at their own numbers.

Render accuracy (docs/guide.md, "How Cycles reads the VDB"): precision FULL (HALF
is off by up to 0.34%), clipping 0 (the default 0.001 drops faint emission).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import bpy
from mathutils import Matrix

from .material import volume_material
from .render_settings import set_scene_units
from .vdb_pad import has_cycles_shell, pad_vdb

VDB_SUFFIXES = {".vdb"}
USD_SUFFIXES = {".usd", ".usda", ".usdc", ".usdz"}
# The bake's velocity grid (`grid.velocity`), km/s: Blender's and Houdini's name.
VELOCITY_GRID = "v"
#: Blender units per metre (1 BU = 1 km).
BU_PER_METRE = 1.0e-3


class AuroraImportError(RuntimeError):
    """The file is missing, unreadable or holds no aurora grids."""


def import_aurora(
    filepath,
    density_scale: float = 1.0,
    emission_scale: float = 1.0,
    scattering_albedo=0.0,
    anisotropy: float = 0.0,
    scene: bpy.types.Scene | None = None,
    name: str | None = None,
    units: str | float = "km",
    pad_dir=None,
    air=None,
    set_frame_range: bool = True,
) -> list[bpy.types.Object]:
    """Import `filepath` (.vdb or .usd[a|c|z]) into `scene` (default: the
    context scene) and give every imported Volume the aurora material.

    extinction = density_scale * `density`, emitted radiance per km =
    emission_scale * `emission`; scattering only if `scattering_albedo` > 0.
    pad_dir: if given, each VDB is first copied there with a shell of active
    zero voxels around its non-zero voxels (vdb_pad.py: makes Cycles' biased
    volume mode exact at the edges of the active region) and the Volume
    reads the copy; the original path is kept in the object's
    `aurora_source` property. Files that already carry the shell (`aurora
    bake` writes it: metadata `aurora_cycles_shell = true` on every grid)
    are read as they are.
    units: "km", "scene" or Blender units per km (the module doc).
    set_frame_range: a sequence sets the scene's frame range and fps.
    Returns the Volume objects (one for a .vdb).
    """
    path = Path(filepath).expanduser().resolve()
    if not path.is_file():
        raise AuroraImportError(f"{path}: no such file")
    scene = scene or bpy.context.scene
    per_km = units_per_km(scene, units)
    suffix = path.suffix.lower()
    if suffix in VDB_SUFFIXES:
        objects = [_import_vdb(scene, path, name or path.stem, per_km)]
    elif suffix in USD_SUFFIXES:
        objects = _import_usd(scene, path, per_km)
    else:
        raise AuroraImportError(f"{path}: expected .vdb or .usd/.usda/.usdc/.usdz")
    for obj in objects:
        vol = obj.data
        source = Path(bpy.path.abspath(vol.filepath))
        if pad_dir is not None and not has_cycles_shell(source):
            padded = Path(pad_dir) / f"{source.stem}.cycles-padded.vdb"
            try:
                pad_vdb(source, padded)
            except (OSError, RuntimeError, ValueError) as e:
                raise AuroraImportError(f"{source}: cannot write the padded copy {padded}: {e}") from e
            vol.filepath = str(padded)
        grids = _load_grids(vol, source)
        has_density = grids.get("density") == "FLOAT"
        if "density" in grids and not has_density:
            raise AuroraImportError(f"{path}: grid `density` is {grids['density']}, expected FLOAT")
        has_emission = grids.get("emission") in ("VECTOR_FLOAT", "FLOAT")
        if "emission" in grids and not has_emission:
            raise AuroraImportError(f"{path}: grid `emission` is {grids['emission']}, expected VECTOR_FLOAT or FLOAT")
        if not (has_density or has_emission):
            raise AuroraImportError(f"{path}: no `density` or `emission` grid (found: {sorted(grids) or 'none'})")
        has_high = _high_column(path, grids, has_density, has_emission)
        set_velocity_grid(vol, grids)
        vol.render.precision = "FULL"
        vol.render.clipping = 0.0
        vol.render.space = "OBJECT"
        vol.render.step_size = 0.0  # auto: the voxel size, times the scene's step rate
        mat = volume_material(
            f"{obj.name}Material",
            density_scale,
            emission_scale,
            has_density=has_density,
            has_emission=has_emission,
            scattering_albedo=scattering_albedo,
            anisotropy=anisotropy,
            air=air,
            has_high=has_high,
        )
        vol.materials.clear()
        vol.materials.append(mat)
        obj["aurora_source"] = str(source)
    if units == "km":
        set_scene_units(scene)
    seq = sequence_of(path)
    if seq is not None:
        first, last, fps = seq
        for obj in objects:
            set_volume_sequence(obj.data, first, last)
        if not set_frame_range:
            return objects
        scene.frame_start, scene.frame_end = first, last
        if fps:
            set_scene_fps(scene, fps)
        # The scene shows the frame that was imported (a frame file's own
        # number; a stage's first frame), so rendering it renders that file.
        m = FRAME_RE.match(path.name)
        scene.frame_current = int(m["digits"]) if m and path.suffix.lower() == ".vdb" else first
    return objects


def units_per_km(scene: bpy.types.Scene, units: str | float) -> float:
    """Blender units per km of the volume for `units` (the module doc)."""
    if units == "km":
        return 1.0
    if units == "scene":
        u = scene.unit_settings
        if u.system == "NONE" or u.scale_length <= 0:
            return 1000.0  # unitless: 1 Blender unit reads as 1 m
        return 1000.0 / u.scale_length
    if isinstance(units, (int, float)) and not isinstance(units, bool) and 0 < units < float("inf"):
        return float(units)
    raise AuroraImportError(f"units = {units!r}: expected \"km\", \"scene\" or Blender units per km, a number > 0")


#: `stem.NNNN.vdb`: the digits just before the extension (Blender's rule).
FRAME_RE = re.compile(r"^(?P<stem>.*?)(?P<digits>\d+)(?P<ext>\.vdb)$", re.IGNORECASE)


def sequence_of(path: Path) -> tuple[int, int, float | None] | None:
    """(first frame, last frame, fps or None) of the sequence `path` belongs
    to: a frame file `stem.NNNN.vdb` with sibling frames, or a stage whose
    filePath is time-sampled. None for a single file."""
    if path.suffix.lower() == ".usda":
        text = path.read_text(errors="replace")
        if "filePath.timeSamples" not in text:
            return None
        num = lambda key: re.search(rf"^\s*{key}\s*=\s*([-0-9.eE+]+)", text, re.MULTILINE)
        start, end, tcps = num("startTimeCode"), num("endTimeCode"), num("timeCodesPerSecond")
        if not (start and end):
            return None
        return int(float(start.group(1))), int(float(end.group(1))), float(tcps.group(1)) if tcps else None
    m = FRAME_RE.match(path.name)
    if not m:
        return None
    stem, width = m["stem"], len(m["digits"])
    frames = []
    for p in path.parent.iterdir():
        q = FRAME_RE.match(p.name)
        if q and q["stem"] == stem and len(q["digits"]) >= width and p.is_file():
            frames.append(int(q["digits"]))
    if len(frames) < 2:
        return None
    fps = None
    report = path.with_suffix(".json")
    try:
        fps = float(json.loads(report.read_text())["fps"])
    except (OSError, ValueError, KeyError, TypeError):
        pass
    return min(frames), max(frames), fps


def set_volume_sequence(vol: bpy.types.Volume, first: int, last: int) -> None:
    """Scene frame F loads file number F for F in [first, last] (CLIP
    outside): Blender's file number is F - frame_start + 1 + frame_offset."""
    vol.is_sequence = True
    vol.frame_start = first
    vol.frame_duration = last - first + 1
    vol.frame_offset = first - 1
    vol.sequence_mode = "CLIP"


def set_scene_fps(scene: bpy.types.Scene, fps: float) -> None:
    """fps = render.fps / render.fps_base, fps an integer where it can be."""
    whole = max(1, round(fps))
    scene.render.fps = whole
    scene.render.fps_base = whole / fps


def set_velocity_grid(vol: bpy.types.Volume, grids: dict[str, str]) -> bool:
    """Motion blur from the bake's velocity grid `v` (`grid.velocity = true`),
    when the file holds it: km/s in the VDB's own units (1 unit = 1 km), which
    are the Volume's object space whatever the import's units (the object's
    scale maps km to the scene), so Blender reads it per second at scale 1.
    True when set."""
    if grids.get(VELOCITY_GRID) != "VECTOR_FLOAT":
        return False
    vol.velocity_grid = VELOCITY_GRID
    vol.velocity_unit = "SECOND"
    vol.velocity_scale = 1.0
    return True


def _high_column(path, grids: dict[str, str], has_density: bool, has_emission: bool) -> bool:
    """Whether the file holds the high column (`density_high` and
    `emission_high`, beside the grids they add to); a half column is an error."""
    high = {n: grids[n] for n in ("density_high", "emission_high") if n in grids}
    if not high:
        return False
    want = {"density_high": ("FLOAT",), "emission_high": ("VECTOR_FLOAT",)}
    for n, t in high.items():
        if t not in want[n]:
            raise AuroraImportError(f"{path}: grid `{n}` is {t}, expected {want[n][0]}")
    if len(high) != 2 or not (has_density and has_emission):
        raise AuroraImportError(
            f"{path}: the high column needs `density`, `emission`, `density_high` and `emission_high` (found: {sorted(grids)})"
        )
    return True


def _load_grids(vol: bpy.types.Volume, path: Path) -> dict[str, str]:
    if not vol.grids.load():
        raise AuroraImportError(f"{path}: Blender cannot read the VDB: {vol.grids.error_message}")
    return {g.name: g.data_type for g in vol.grids}


def _import_vdb(scene, path: Path, name: str, per_km: float) -> bpy.types.Object:
    vol = bpy.data.volumes.new(name)
    vol.filepath = str(path)
    vol.sequence_mode = "CLIP"
    obj = bpy.data.objects.new(name, vol)
    scene.collection.objects.link(obj)
    obj.matrix_world = Matrix.Scale(per_km, 4)
    return obj


def _import_usd(scene, path: Path, per_km: float) -> list[bpy.types.Object]:
    before = set(bpy.data.objects)
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
        result = bpy.ops.wm.usd_import(filepath=str(path), import_volumes=True, import_cameras=False, import_lights=False,
                                       import_materials=False, apply_unit_conversion_scale=True,
                                       create_world_material=False)
    if "FINISHED" not in result:
        raise AuroraImportError(f"{path}: Blender's USD importer failed")
    new = [o for o in bpy.data.objects if o not in before]
    # The importer scaled the roots to metres; bring them to the chosen units.
    for obj in new:
        if obj.parent is None or obj.parent not in new:
            obj.matrix_world = Matrix.Scale(BU_PER_METRE * per_km, 4) @ obj.matrix_world
    volumes = [o for o in new if o.type == "VOLUME"]
    if not volumes:
        raise AuroraImportError(f"{path}: the stage holds no UsdVol.Volume")
    return volumes
