"""Baking from Blender: `scene.aurora`, `bpy.ops.aurora.bake()`, the bake job
and `aurora bake --progress json`.

Scenes are reduced (a few hundred to a few thousand beams, coarse
footprints and voxels) so that each bake takes a second or two; the
physics checked (where the emission lies) does not depend on the noise
level. The binary is $AURORA_BIN or target/release/aurora (a missing binary
fails the test).
"""

from __future__ import annotations

import hashlib
import importlib
import json
import math
import subprocess
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scenes import aurora_bin

#: A reduced scene: ~1 s per bake on two cores.
SMALL = {"beams": {"count": 400}, "footprint": {"resolution": (64, 16), "steps": 2},
         "grid": {"voxel_size": 2.0}, "photons": {"radius_km": 1.5}}


@pytest.fixture(scope="module")
def panel(addon, bpy):
    """The add-on registered (panel, operators, scene.aurora) for this module."""
    addon.register()
    yield addon
    addon.unregister()


@pytest.fixture()
def sc(panel, fresh, bpy, monkeypatch):
    monkeypatch.setenv("AURORA_BIN", str(aurora_bin()))
    fresh.render.resolution_x, fresh.render.resolution_y, fresh.render.resolution_percentage = 64, 36, 100
    return fresh


def sub(addon, name):
    return importlib.import_module(f"{addon.__name__}.{name}")


def set_small(s, **extra):
    for table, keys in {**SMALL, **extra}.items():
        for k, v in keys.items():
            setattr(getattr(s, table), k, v)


def add_camera(bpy, sc, position, look_at):
    from mathutils import Vector

    data = bpy.data.cameras.new("Shot")
    obj = bpy.data.objects.new("Shot", data)
    sc.collection.objects.link(obj)
    d = Vector(look_at) - Vector(position)
    obj.matrix_world = d.to_track_quat("-Z", "Y").to_matrix().to_4x4()
    obj.matrix_world.translation = position
    sc.camera = obj
    return obj


def bezier(bpy, sc, points, name="Path"):
    cu = bpy.data.curves.new(name, "CURVE")
    cu.dimensions = "3D"
    sp = cu.splines.new("BEZIER")
    sp.bezier_points.add(len(points) - 1)
    for bp, (x, y) in zip(sp.bezier_points, points):
        bp.co = (x, y, 0.0)
        bp.handle_left_type = bp.handle_right_type = "AUTO"
    obj = bpy.data.objects.new(name, cu)
    sc.collection.objects.link(obj)
    return obj


def digest(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


def emission_voxels(vdb: Path):
    """World centres (N, 3) and summed RGB emission (N,) of the active voxels."""
    import pyopenvdb as openvdb

    grid = openvdb.read(str(vdb), "emission")
    (i0, j0, k0), (i1, j1, k1) = grid.evalActiveVoxelBoundingBox()
    arr = np.zeros((i1 - i0 + 1, j1 - j0 + 1, k1 - k0 + 1, 3), np.float32)
    grid.copyToArray(arr, ijk=(i0, j0, k0))
    e = arr.sum(-1)
    idx = np.argwhere(e > 0)
    vs = grid.transform.voxelSize()[0]
    origin = np.array(grid.transform.indexToWorld((i0, j0, k0)))
    return origin + idx * vs, e[e > 0].astype(np.float64)


def polyline_distance(p: np.ndarray, line: np.ndarray):
    """Distance of points p (N, 2) to the polyline and their arc length along it."""
    a, b = line[:-1], line[1:]
    ab = b - a
    seg = np.linalg.norm(ab, axis=1)
    s0 = np.concatenate([[0.0], np.cumsum(seg)])[:-1]
    t = np.clip(((p[:, None, :] - a[None]) * ab[None]).sum(-1) / (seg ** 2)[None], 0.0, 1.0)
    q = a[None] + t[..., None] * ab[None]
    d = np.linalg.norm(p[:, None, :] - q, axis=-1)
    k = d.argmin(1)
    return d[np.arange(len(p)), k], s0[k] + t[np.arange(len(p)), k] * seg[k], seg.sum()


# --- the scene file the panel writes ------------------------------------------------


def test_an_untouched_panel_bakes_the_clis_default_scene(sc, panel, tmp_path):
    sw = sub(panel, "scene_write")
    doc = sw.scene_document(sc)
    # Only what the shot decides: no camera (none is active), the size, the fps.
    assert doc == {"render": {"width": 64, "height": 36}, "animation": {"fps": 24.0}}
    f = tmp_path / "scene.toml"
    f.write_text(sw.to_toml(doc))
    out = subprocess.run([aurora_bin(), "scene", f], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    full = tomllib.loads(out.stdout)
    default = tomllib.loads(subprocess.run([aurora_bin(), "scene", "default"], capture_output=True, text=True).stdout)
    for t in ("beams", "footprint", "photons", "grid", "colour", "curtain", "atmosphere"):
        assert full[t] == default[t], t


def test_every_schema_key_is_a_property_with_its_default_range_and_unit(sc, panel):
    P = sub(panel, "properties")
    s = sc.aurora
    n = left_to_files = 0
    for table, keys in P.SCHEMA.items():
        if table in P.TABLES_FROM_BLENDER:
            continue
        for key, entry in keys.items():
            if (table, key) in P.FROM_BLENDER:
                continue
            if table in P.OPTIONAL_TABLES and key not in P.panel_keys(table):
                # No default and no example (site.pressure_hpa, oval.al_nt, oval.mlt_h): scene files only.
                left_to_files += 1
                continue
            group = s if table == "" else (s.curtains.add() if table == "curtain" else getattr(s, table))
            prop = group.bl_rna.properties[key]
            n += 1
            if "min" in entry and isinstance(entry["default"], (int, float)) and prop.type in ("INT", "FLOAT"):
                lo = P._bound(entry["min"])
                if math.isfinite(lo):
                    assert prop.hard_min == pytest.approx(lo, rel=1e-6), f"{table}.{key} min"
            unit = P.KEYS[table][key]["unit"]
            if unit:
                assert f"({unit})" in prop.name, f"{table}.{key}: unit {unit} not in {prop.name!r}"
            assert P.KEYS[table][key]["description"].replace("`", "")[:20] in prop.description
            if table not in P.OPTIONAL_TABLES:
                assert P.read_key(group, table, key) is None, f"{table}.{key} differs from its default"
    # An optional table is written only when switched on.
    for table in P.OPTIONAL_TABLES:
        assert not getattr(s, table).enabled and P.table_values(getattr(s, table), table, P.panel_keys(table)) == {}
    every = sum(len(k) for k in P.SCHEMA.values())
    assert n == every - len(P.SCHEMA["camera"]) - len(P.FROM_BLENDER) - left_to_files and n > 80
    # site.pressure_hpa, oval.al_nt and oval.mlt_h.
    assert left_to_files == 3


def test_the_site_and_hour_load_from_a_preset_and_write_back_only_when_on(sc, panel, tmp_path, bpy):
    """`[site]` in the panel: the `tromso` preset switches it on with its
    values, the scene file the panel writes holds the same site (and the
    binary takes it), and switched off the file has no `[site]`."""
    P, sw = sub(panel, "properties"), sub(panel, "scene_write")
    assert bpy.ops.aurora.load_preset(name="tromso") == {"FINISHED"}
    preset = tomllib.loads(subprocess.run([aurora_bin(), "scene", "tromso"], capture_output=True, text=True, check=True).stdout)
    assert sc.aurora.site.enabled
    doc = sw.scene_document(sc)
    for key, v in preset["site"].items():
        assert doc["site"][key] == pytest.approx(v) if isinstance(v, float) else doc["site"][key] == v, key
    f = tmp_path / "s.toml"
    f.write_text(sw.to_toml(doc))
    mine = tomllib.loads(subprocess.run([aurora_bin(), "scene", f], capture_output=True, text=True, check=True).stdout)
    assert mine["site"] == preset["site"]
    sc.aurora.site.enabled = False
    assert "site" not in sw.scene_document(sc)
    assert bpy.ops.aurora.load_preset(name="default") == {"FINISHED"}
    assert not sc.aurora.site.enabled


def test_the_ovals_activity_loads_from_a_preset_and_writes_back_only_when_on(sc, panel, tmp_path, bpy):
    """`[oval]` in the panel: `tromso_kp5` switches it on at Kp 5, the file
    the panel writes holds the same `[oval]` (and the binary takes it), and
    switched off the file has none."""
    sw = sub(panel, "scene_write")
    assert bpy.ops.aurora.load_preset(name="tromso_kp5") == {"FINISHED"}
    preset = tomllib.loads(subprocess.run([aurora_bin(), "scene", "tromso_kp5"], capture_output=True, text=True, check=True).stdout)
    assert preset["oval"] == {"kp": 5.0}
    assert sc.aurora.oval.enabled and sc.aurora.oval.kp == pytest.approx(5.0)
    sc.aurora.oval.kp = 6.5
    doc = sw.scene_document(sc)
    assert doc["oval"] == {"kp": pytest.approx(6.5)}
    f = tmp_path / "s.toml"
    f.write_text(sw.to_toml(doc))
    mine = tomllib.loads(subprocess.run([aurora_bin(), "scene", f], capture_output=True, text=True, check=True).stdout)
    assert mine["oval"] == {"kp": 6.5} and mine["site"] == preset["site"]
    sc.aurora.oval.enabled = False
    assert "oval" not in sw.scene_document(sc)


def test_a_preset_loads_into_the_panel_and_writes_back_the_same_bake(sc, panel, tmp_path, bpy):
    P, sw = sub(panel, "properties"), sub(panel, "scene_write")
    assert bpy.ops.aurora.load_preset(name="seed2014") == {"FINISHED"}
    assert sc.aurora.preset == "seed2014"
    f = tmp_path / "s.toml"
    f.write_text(sw.to_toml(sw.scene_document(sc)))
    mine = tomllib.loads(subprocess.run([aurora_bin(), "scene", f], capture_output=True, text=True, check=True).stdout)
    preset = tomllib.loads(subprocess.run([aurora_bin(), "scene", "seed2014"], capture_output=True, text=True, check=True).stdout)
    for t in ("", "beams", "footprint", "photons", "grid", "colour", "curtain", "atmosphere"):
        if t == "":
            assert mine["seed"] == preset["seed"]
        else:
            assert mine[t] == preset[t], t
    assert len(sc.aurora.curtains) == len(preset["curtain"])


def test_the_preset_menu_lists_the_binarys_presets_and_falls_back_without_it(sc, panel, tmp_path, bpy):
    pm = sub(panel, "operators.presets")
    out = subprocess.run([aurora_bin(), "scene", "--list"], capture_output=True, text=True, check=True).stdout
    names = [line.split()[0] for line in out.splitlines()]
    assert pm.list_presets(str(aurora_bin())) == names
    forms = {"quiet_arc", "rayed_band", "corona", "pulsating_patches", "type_a_red", "type_b_pink", "surge"}
    assert forms <= set(names), names
    # Every listed preset loads into the panel.
    for name in names:
        assert bpy.ops.aurora.load_preset(name=name) == {"FINISHED"}, name
        assert sc.aurora.preset == name
    # A binary that predates --list (an error exit) or one that cannot run: the fixed names.
    old = tmp_path / "old-aurora"
    old.write_text("#!/bin/sh\necho 'unexpected argument --list' >&2\nexit 2\n")
    old.chmod(0o755)
    assert pm.list_presets(str(old)) == list(pm.FALLBACK_PRESETS)
    assert pm.list_presets(str(tmp_path / "missing")) == list(pm.FALLBACK_PRESETS)


def test_camera_export_inverts_the_importer_and_honours_sensor_fit(sc, panel, bpy):
    cam_mod, ce, st = sub(panel, "camera"), sub(panel, "camera_export"), sub(panel, "scene_toml")
    c = st.Camera(position=(5.0, -80.0, 2.0), look_at=(0.0, 30.0, 110.0), up=(0.0, 0.0, 1.0), fov_deg=40.0)
    obj = cam_mod.build_camera(sc, c)
    t = ce.camera_table(obj, sc)
    assert t["projection"] == "perspective" and t["fov_deg"] == pytest.approx(40.0, abs=1e-4)
    assert np.allclose(t["position"], c.position, atol=1e-4)
    fwd = np.subtract(t["look_at"], t["position"])
    want = np.subtract(c.look_at, c.position)
    assert np.allclose(fwd / np.linalg.norm(fwd), want / np.linalg.norm(want), atol=1e-6)
    # AUTO on a 16:9 frame: the 36 mm sensor spans the width at 50 mm.
    obj.data.sensor_fit, obj.data.lens, obj.data.sensor_width = "AUTO", 50.0, 36.0
    want_v = math.degrees(2 * math.atan(math.tan(math.atan(18.0 / 50.0)) * 36 / 64))
    assert ce.camera_table(obj, sc)["fov_deg"] == pytest.approx(want_v, abs=1e-4)
    # Portrait: AUTO's sensor width spans the (longer) height.
    sc.render.resolution_x, sc.render.resolution_y = 36, 64
    assert ce.camera_table(obj, sc)["fov_deg"] == pytest.approx(math.degrees(2 * math.atan(18.0 / 50.0)), abs=1e-4)
    obj.data.type, obj.data.ortho_scale, obj.data.sensor_fit = "ORTHO", 20.0, "HORIZONTAL"
    assert ce.camera_table(obj, sc)["ortho_height"] == pytest.approx(20.0 * 64 / 36)
    obj.data.type, obj.data.shift_x = "PERSP", 0.1
    with pytest.raises(ce.CameraExportError, match="shift"):
        ce.camera_table(obj, sc)


def test_a_curve_becomes_the_curtains_path_in_world_km(sc, panel, bpy):
    sw = sub(panel, "scene_write")
    P = sub(panel, "properties")
    c = P.add_curtain(sc.aurora)
    c.length = 99.0  # replaced by the path
    obj = bezier(bpy, sc, [(-150.0, 0.0), (0.0, 25.0), (150.0, 0.0)])
    obj.location = (10.0, -5.0, 7.0)
    c.path_object = obj
    t = sw.curtain_table(c, bpy.context.evaluated_depsgraph_get())
    assert "length" not in t and "center" not in t
    path = np.array(t["path"])
    assert np.allclose(path[0], (-140.0, -5.0)) and np.allclose(path[-1], (160.0, -5.0))
    assert path[:, 1].max() == pytest.approx(20.0, abs=0.01)  # the bend at the middle point
    # A poly spline: its points; a NURBS one: a smooth curve inside its hull.
    cu = obj.data
    cu.splines.clear()
    sp = cu.splines.new("POLY")
    sp.points.add(2)
    for p, (x, y) in zip(sp.points, [(0, 0), (50, 10), (100, 0)]):
        p.co = (x, y, 3.0, 1.0)
    t = sw.curtain_table(c, bpy.context.evaluated_depsgraph_get())
    assert np.allclose(t["path"], [[10, -5], [60, 5], [110, -5]])
    sp.type = "NURBS"
    sp.use_endpoint_u = True
    t = np.array(sw.curtain_table(c, bpy.context.evaluated_depsgraph_get())["path"])
    assert len(t) > 3 and np.allclose(t[0], (10, -5), atol=1e-4) and t[:, 1].max() < 5.0


# --- bpy.ops.aurora.bake() ---------------------------------------------------------


def test_bake_with_a_bezier_path_loads_a_volume_whose_emission_follows_the_curve(sc, panel, bpy, tmp_path):
    """Needs a binary with the `[[curtain]] path` key: against one without
    it the bake is refused (`unknown field path`) and this fails."""
    s = sc.aurora
    s.output_dir = str(tmp_path / "bake")
    set_small(s)
    s.beams.count = 1500
    P = sub(panel, "properties")
    c = P.add_curtain(s)
    c.width, c.bend_km = 30.0, 5.0
    # 300 km long, one bend: an arc of 30 km sagitta through three points.
    curve = bezier(bpy, sc, [(-148.0, 0.0), (0.0, 30.0), (148.0, 0.0)])
    c.path_object = curve
    add_camera(bpy, sc, (0.0, -250.0, 1.0), (0.0, 0.0, 105.0))
    assert bpy.ops.aurora.bake() == {"FINISHED"}
    vols = [o for o in sc.objects if o.type == "VOLUME"]
    assert len(vols) == 1 and vols[0].data.grids.load()
    assert {g.name for g in vols[0].data.grids} == {"density", "emission"}
    line = np.array(sub(panel, "curve_path").curve_path(curve))
    length = np.linalg.norm(np.diff(line, axis=0), axis=1).sum()
    assert 295.0 < length < 320.0, length
    xyz, e = emission_voxels(Path(s.output_dir) / "aurora.vdb")
    band = (xyz[:, 2] >= 95.0) & (xyz[:, 2] <= 125.0)
    d, along, total = polyline_distance(xyz[band, :2], line)
    w = e[band]
    tol = c.width / 2 + c.bend_km
    near = w[d <= tol].sum() / w.sum()
    assert near >= 0.9, f"{near:.1%} of the 95-125 km emission within {tol} km of the curve"
    # Over its whole length: every tenth of the curve carries emission.
    share = np.histogram(along, bins=10, range=(0, total), weights=w)[0] / w.sum()
    assert share.min() > 0.02, f"emission per tenth of the curve: {np.round(share, 3)}"


def test_bake_frames_gives_a_sequence_blender_plays(sc, panel, bpy, tmp_path):
    s = sc.aurora
    s.output_dir = str(tmp_path / "seq")
    set_small(s)
    sc.frame_start, sc.frame_end = 1, 3
    assert bpy.ops.aurora.bake(frames=True) == {"FINISHED"}
    out = Path(s.output_dir)
    assert sorted(p.name for p in out.glob("aurora.*.vdb")) == ["aurora.0001.vdb", "aurora.0002.vdb", "aurora.0003.vdb"]
    (obj,) = [o for o in sc.objects if o.type == "VOLUME"]
    vol = obj.data
    assert vol.is_sequence and vol.frame_duration == 3
    for f in (1, 2, 3):
        sc.frame_set(f)
        ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        assert Path(ev.data.grids.frame_filepath).name == f"aurora.{f:04d}.vdb"
        assert ev.data.grids.load(), ev.data.grids.error_message
    # Baking again refreshes the same object, not a second one.
    obj.name = "Northern lights"
    obj.location.z = 0.0  # still where the VDB puts it
    assert bpy.ops.aurora.bake(frames=True) == {"FINISHED"}
    assert [o for o in sc.objects if o.type == "VOLUME"] == [obj]
    assert obj.name == "Northern lights" and obj.data.is_sequence and obj.data.users == 1
    assert len(bpy.data.volumes) == 1


def test_bake_errors_are_reported_and_leave_nothing(sc, panel, bpy, tmp_path, monkeypatch):
    s = sc.aurora
    s.output_dir = str(tmp_path / "x")
    monkeypatch.setenv("AURORA_BIN", str(tmp_path / "nope"))
    with pytest.raises(RuntimeError, match="AURORA_BIN"):
        bpy.ops.aurora.bake()
    monkeypatch.delenv("AURORA_BIN")
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(RuntimeError, match="no aurora binary"):
        bpy.ops.aurora.bake()
    monkeypatch.setenv("AURORA_BIN", str(aurora_bin()))
    s.footprint.resolution = (4, 4)  # below the schema's minimum of 8: the property holds it there
    assert tuple(s.footprint.resolution) == (8, 8)
    # A rule between keys the properties cannot hold alone: the binary names the key.
    s.beams.delta_alpha_deg = s.beams.alpha_d_deg + 1.0
    with pytest.raises(RuntimeError, match="delta_alpha_deg"):
        bpy.ops.aurora.bake()
    assert list(tmp_path.iterdir()) == []  # no output folder, no staging left
    # A folder of other work is never replaced.
    s.beams.delta_alpha_deg = 3.0
    s.footprint.resolution = (64, 16)
    set_small(s)
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "thesis.tex").write_text("mine")
    with pytest.raises(RuntimeError, match="not a bake"):
        bpy.ops.aurora.bake()
    assert (tmp_path / "x" / "thesis.tex").read_text() == "mine"


def test_a_refused_bake_names_the_curve_not_the_previous_bakes_scene_file(sc, panel, bpy, tmp_path):
    s = sc.aurora
    s.output_dir = str(tmp_path / "bake")
    set_small(s)
    assert bpy.ops.aurora.bake() == {"FINISHED"}  # a previous bake, with its scene.toml
    P = sub(panel, "properties")
    P.add_curtain(s)
    c = P.add_curtain(s)
    # Longer than the 1e4 km a path may be: the binary refuses curtain[1].path.
    c.path_object = bezier(bpy, sc, [(-6000.0, 0.0), (0.0, 10.0), (6000.0, 0.0)], name="Oval edge")
    before = digest(Path(s.output_dir))
    with pytest.raises(RuntimeError) as e:
        bpy.ops.aurora.bake()
    msg = str(e.value)
    assert "curtain[1].path" in msg and "curtain[1] is the curve 'Oval edge'" in msg, msg
    assert "the Aurora panel's scene" in msg and str(Path(s.output_dir) / "scene.toml") not in msg, msg
    assert digest(Path(s.output_dir)) == before


# --- the modal path: progress and cancel ---------------------------------------------


def make_job(panel, bpy, sc, frames):
    return sub(panel, "operators.bake").make_job(bpy.context, frames)


def test_a_bake_reports_progress_often_and_a_cancel_leaves_the_previous_bake_untouched(sc, panel, bpy, tmp_path):
    ops = sub(panel, "operators.bake")
    s = sc.aurora
    s.output_dir = str(tmp_path / "out")
    set_small(s)
    s.beams.count = 3000
    s.footprint.resolution = (128, 32)
    s.grid.voxel_size = 1.0
    job = make_job(panel, bpy, sc, False)
    job.start()
    # What the modal operator does on each timer tick.
    texts, deadline = [], time.monotonic() + 300
    while job.running and time.monotonic() < deadline:
        ev = ops.latest_progress(job.poll())
        if ev is not None:
            texts.append(ops.status_text(ev, None))
        time.sleep(ops.TICK_S)
    ev = ops.latest_progress(job.poll())
    if ev is not None:
        texts.append(ops.status_text(ev, None))
    job.finish()
    ops.load_result(sc, job)
    assert len(texts) >= 5, texts
    assert len(set(texts)) >= 5, texts
    assert any("beams" in t for t in texts) and all("Esc to cancel" in t for t in texts)
    assert not job.errors
    first = digest(Path(s.output_dir))
    assert "aurora.vdb" in first

    # Another scene, cancelled half-way: the first bake stays, byte for byte.
    s.seed = 7
    s.beams.count = 20000
    job = make_job(panel, bpy, sc, False)
    job.start()
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not any(e.stage == "beams" and e.done > 0 for e in job.events):
        job.poll()
        time.sleep(0.02)
    assert job.running, "the second bake ended before it could be cancelled"
    job.cancel()
    assert job.returncode == 130  # it stopped at the cancel file (`--cancel-file`), not by a signal
    assert digest(Path(s.output_dir)) == first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging folder left


def test_a_cancelled_sequence_never_mixes_two_scenes_frames(sc, panel, bpy, tmp_path):
    s = sc.aurora
    s.output_dir = str(tmp_path / "seq")
    set_small(s)
    sc.frame_start, sc.frame_end = 1, 3
    job = make_job(panel, bpy, sc, True)
    job.run()
    first = digest(Path(s.output_dir))
    s.seed = 99
    s.beams.count = 4000
    sc.frame_end = 6
    job = make_job(panel, bpy, sc, True)
    job.start()
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not any(e.stage == "frame" and e.done >= 1 for e in job.events):
        job.poll()
        time.sleep(0.02)
    assert job.running, "the second sequence ended before it could be cancelled"
    assert any(p.name.startswith("aurora.0001") for p in job.staging.iterdir())  # frame 1 of the new scene existed
    job.cancel()
    assert job.returncode == 130
    assert digest(Path(s.output_dir)) == first


def test_status_text_and_latest_progress(panel):
    ops = sub(panel, "operators.bake")
    E = sub(panel, "bake_job").Event
    assert ops.status_text(None, (1, 3)) == "Aurora frames 1-3: starting (Esc to cancel)"
    assert ops.status_text(E("gather", 50, 200, 3.25), None) == "Aurora bake: gather 25%, 3.2 s (Esc to cancel)"
    evs = [E("beams", 1, 10), E(warning="w"), E(error="x")]
    assert ops.latest_progress(evs).stage == "beams"
    assert ops.latest_progress([E(error="x")]) is None


# --- aurora bake --progress json -----------------------------------------------------


def test_progress_json_lines(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text("[beams]\ncount = 500\n[footprint]\nresolution = [64, 16]\n[grid]\nvoxel_size = 2.0\n")
    r = subprocess.run([aurora_bin(), "bake", scene, "--out", tmp_path / "o", "--progress", "json", "--frames", "1-2"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    objs = [json.loads(line) for line in r.stderr.splitlines()]  # every line is JSON
    assert all(isinstance(o, dict) for o in objs)
    stages = [o for o in objs if "stage" in o]
    assert {"footprints", "beams", "frame"} <= {o["stage"] for o in stages}
    for o in stages:
        assert set(o) == {"stage", "done", "total", "seconds"}
        assert 0 <= o["done"] <= max(o["total"], o["done"]) and o["seconds"] >= 0
        if o["total"]:
            assert o["done"] <= o["total"]
    assert [o["done"] for o in stages if o["stage"] == "frame"] == [0, 1, 2]
    secs = [o["seconds"] for o in objs]
    assert secs == sorted(secs)
    assert all(set(o) == {"warning", "seconds"} for o in objs if "warning" in o)
    # An error is an object with the exit status, and the only line.
    bad = tmp_path / "bad.toml"
    bad.write_text("[beams]\ncount = 0\n")
    r = subprocess.run([aurora_bin(), "bake", bad, "--out", tmp_path / "b", "--progress", "json"], capture_output=True, text=True)
    assert r.returncode == 2
    (err,) = [json.loads(line) for line in r.stderr.splitlines()]
    assert err["status"] == 2 and "beams.count" in err["error"]
