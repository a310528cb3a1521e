"""A baked frame sequence in Blender and USD: Blender's own volume sequence
logic loads frame 3 from frame 1's name; the add-on sets the sequence up
(is_sequence, frame_start, frame_duration, frame_offset, scene range and fps)
from a frame file or from the stage; usd-core reads the stage with one time
sample per frame and field.

The scene is the suite's small one (scenes.py), the binary
target/release/aurora (AURORA_BIN overrides).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from scenes import aurora_bin, write_small_scene

#: The small scene's `[animation]` for the sequence: 30 fps, rays along the
#: curtain and a drift, so that the frames differ.
ANIMATION = {"fps": 30.0, "ray_speed_kms": 20.0, "drift_km": 4.0, "drift_period_s": 1.0}


@pytest.fixture(scope="module")
def sequence(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("seq")
    write_small_scene(d / "scene.toml", animation=ANIMATION)
    subprocess.run([str(aurora_bin()), "bake", str(d / "scene.toml"), "--frames", "1-4", "--out", str(d / "out"), "-q"], check=True)
    return d / "out"


def evaluated_file(bpy, obj, frame: int) -> str:
    bpy.context.scene.frame_set(frame)
    dg = bpy.context.evaluated_depsgraph_get()
    vol = obj.evaluated_get(dg).data
    assert vol.grids.load(), vol.grids.error_message
    return Path(bpy.path.abspath(vol.grids.frame_filepath)).name


def bounds(obj) -> list[tuple[float, ...]]:
    return sorted(tuple(round(c, 4) for c in v) for v in obj.bound_box)


def test_blenders_own_sequence_logic_loads_frame_3_from_frame_1s_name(bpy, fresh, sequence):
    scene = bpy.context.scene
    vol = bpy.data.volumes.new("seq")
    vol.filepath = str(sequence / "aurora.0001.vdb")
    vol.is_sequence = True
    vol.frame_start = 1
    vol.frame_duration = 4
    obj = bpy.data.objects.new("seq", vol)
    scene.collection.objects.link(obj)
    assert evaluated_file(bpy, obj, 3) == "aurora.0003.vdb"
    # And the grids are frame 3's: the same bounds as frame 3 opened alone.
    dg = bpy.context.evaluated_depsgraph_get()
    seq_bounds = bounds(obj.evaluated_get(dg))
    single = bpy.data.volumes.new("single")
    single.filepath = str(sequence / "aurora.0003.vdb")
    one = bpy.data.objects.new("single", single)
    scene.collection.objects.link(one)
    dg = bpy.context.evaluated_depsgraph_get()
    assert seq_bounds == bounds(one.evaluated_get(dg))
    assert evaluated_file(bpy, obj, 1) == "aurora.0001.vdb"


def test_addon_sets_up_the_sequence_from_a_frame_file(addon, fresh, bpy, sequence, tmp_path):
    obj = addon.import_aurora(sequence / "aurora.0001.vdb")[0]
    vol = obj.data
    assert (vol.is_sequence, vol.frame_start, vol.frame_duration, vol.frame_offset) == (True, 1, 4, 0)
    scene = bpy.context.scene
    assert (scene.frame_start, scene.frame_end) == (1, 4)
    assert scene.render.fps / scene.render.fps_base == pytest.approx(30.0)
    assert evaluated_file(bpy, obj, 3) == "aurora.0003.vdb"
    # A sequence starting at frame 5: scene frame F still loads file F.
    later = tmp_path / "later"
    later.mkdir()
    for f in range(1, 5):
        shutil.copy(sequence / f"aurora.{f:04d}.vdb", later / f"aurora.{f + 4:04d}.vdb")
    obj = addon.import_aurora(later / "aurora.0006.vdb")[0]
    assert scene.frame_current == 6, "the scene should show the imported frame"
    assert (obj.data.frame_start, obj.data.frame_duration, obj.data.frame_offset) == (5, 4, 4)
    assert (scene.frame_start, scene.frame_end) == (5, 8)
    assert evaluated_file(bpy, obj, 6) == "aurora.0006.vdb"


def test_a_sequence_imported_into_a_shot_keeps_its_range_when_asked(addon, fresh, bpy, sequence):
    """set_frame_range=False: the shot's range, fps and current frame stay;
    the Volume still loads file F at scene frame F."""
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end, scene.frame_current, scene.render.fps = 1, 240, 17, 25
    obj = addon.import_aurora(sequence / "aurora.0002.vdb", set_frame_range=False)[0]
    assert (scene.frame_start, scene.frame_end, scene.frame_current, scene.render.fps) == (1, 240, 17, 25)
    assert (obj.data.is_sequence, obj.data.frame_start, obj.data.frame_duration) == (True, 1, 4)
    assert evaluated_file(bpy, obj, 3) == "aurora.0003.vdb"
    # The operator's default sets the range, visibly (its option's name).
    addon.register()
    try:
        op = bpy.ops.aurora.import_vdb.get_rna_type().properties["set_frame_range"]
        assert op.default is True and op.name == "Set Frame Range and fps"
    finally:
        addon.unregister()


def test_stage_has_a_time_sample_per_frame_and_imports_as_a_sequence(addon, fresh, bpy, sequence):
    usda = sequence / "aurora.usda"
    check = (
        "from pxr import Usd, UsdVol; s = Usd.Stage.Open(%r);"
        "assert (s.GetStartTimeCode(), s.GetEndTimeCode(), s.GetTimeCodesPerSecond()) == (1, 4, 30), s;"
        "import os\n"
        "for n in ('density', 'emission'):\n"
        "    a = UsdVol.OpenVDBAsset(s.GetPrimAtPath('/aurora/' + n)).GetFilePathAttr()\n"
        "    assert a.GetTimeSamples() == [1, 2, 3, 4], a.GetTimeSamples()\n"
        "    assert os.path.basename(a.Get(3).resolvedPath) == 'aurora.0003.vdb', a.Get(3)\n" % str(usda)
    )
    subprocess.run([sys.executable, "-c", check], check=True)
    objs = addon.import_aurora(usda)
    assert len(objs) == 1
    vol = objs[0].data
    assert vol.is_sequence and vol.frame_start == 1 and vol.frame_duration == 4
    scene = bpy.context.scene
    assert (scene.frame_start, scene.frame_end) == (1, 4)
    assert scene.render.fps / scene.render.fps_base == pytest.approx(30.0)
    assert evaluated_file(bpy, objs[0], 3) == "aurora.0003.vdb"
