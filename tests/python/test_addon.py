"""The Blender add-on in ../../blender: install, enable, import, scene set-up.

Headless, through bpy 5.0.1. Two ways in are tested: the Blender 4.2+
extension route (zip + `bpy.ops.extensions.package_install_files`, what a
user does from Preferences) and the legacy add-on route (the folder on a
script directory + `addon_utils.enable`). Blender's user folders point at a
temporary directory (conftest.py).
"""

from __future__ import annotations

import math
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest

import synth
from scenes import aurora_bin, write_small_scene

ROOT = Path(__file__).resolve().parent.parent.parent
ADDON = ROOT / "blender"


@pytest.fixture(scope="module")
def aurora_vdb(tmp_path_factory):
    """Both grids, 12^3 voxels of 0.5 km, index 0 at (10, -3, 100) km."""
    d = tmp_path_factory.mktemp("vdb")
    dens = np.full((12, 12, 12), 0.02, np.float32)
    em = np.zeros((12, 12, 12, 3), np.float32)
    em[..., 1] = np.linspace(0.1, 1.0, 12)[None, None, :]
    return synth.write_vdb(d / "aurora.vdb", 0.5, (10.0, -3.0, 100.0), dens, em)


def write_usda(path: Path, vdb_name: str, meters_per_unit: float, up_axis: str) -> Path:
    """A stage like `aurora bake` writes: one UsdVol.Volume, two OpenVDBAsset
    fields in one VDB file, relative asset paths."""
    path.write_text(f"""#usda 1.0
(
    defaultPrim = "aurora"
    metersPerUnit = {meters_per_unit}
    upAxis = "{up_axis}"
)

def Volume "aurora"
{{
    rel field:density = </aurora/density>
    rel field:emission = </aurora/emission>

    def OpenVDBAsset "density"
    {{
        asset filePath = @./{vdb_name}@
        token fieldName = "density"
    }}

    def OpenVDBAsset "emission"
    {{
        asset filePath = @./{vdb_name}@
        token fieldName = "emission"
    }}
}}
""")
    return path


def principled(mat):
    nodes = [n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeVolumePrincipled"]
    assert len(nodes) == 1
    return nodes[0]


def assert_aurora_volume(obj, density_scale, emission_scale):
    """The Volume object and its material are wired as the add-on promises."""
    assert obj.type == "VOLUME"
    vol = obj.data
    assert vol.grids.load(), vol.grids.error_message
    grids = {g.name: g.data_type for g in vol.grids}
    assert grids == {"density": "FLOAT", "emission": "VECTOR_FLOAT"}
    assert vol.render.precision == "FULL"
    assert vol.render.clipping == 0.0
    assert vol.render.space == "OBJECT"
    mat = vol.materials[0]
    pv = principled(mat)
    assert tuple(pv.inputs["Color"].default_value)[:3] == (0.0, 0.0, 0.0)  # no scattering
    assert tuple(pv.inputs["Absorption Color"].default_value)[:3] == (0.0, 0.0, 0.0)  # sigma_a = density
    assert pv.inputs["Blackbody Intensity"].default_value == 0.0
    assert pv.inputs["Density"].default_value == pytest.approx(density_scale)
    assert pv.inputs["Density Attribute"].default_value == "density"
    assert pv.inputs["Emission Strength"].default_value == pytest.approx(emission_scale)
    assert not pv.inputs["Temperature"].is_linked
    links = pv.inputs["Emission Color"].links
    assert len(links) == 1
    attr, sock = links[0].from_node, links[0].from_socket
    if attr.bl_idname == "ShaderNodeVectorMath":
        # A scene file's `[sky] extinction` (on by default): the emission
        # times the air's transmittance (blender/air.py).
        assert attr.operation == "MULTIPLY"
        first = attr.inputs[0].links[0]
        attr, sock = first.from_node, first.from_socket
    assert attr.bl_idname == "ShaderNodeAttribute"
    assert (attr.attribute_type, attr.attribute_name, sock.name) == ("GEOMETRY", "emission", "Color")
    out = [n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    assert len(out) == 1 and out[0].inputs["Volume"].links[0].from_node == pv
    assert not out[0].inputs["Surface"].is_linked
    assert mat.cycles.volume_interpolation == "LINEAR"


def test_installs_and_enables_as_extension_imports_and_bakes(bpy, fresh, tmp_path, aurora_vdb, blender_user_dir, monkeypatch):
    """The zip tools/build_extension writes, installed into the throw-away
    user folder (conftest.py), enabled, importing, and baking from the
    panel's operator with the baker the zip brought: no preference, no
    $AURORA_BIN, no aurora on PATH."""
    binary = aurora_bin()
    build = [sys.executable, str(ROOT / "tools" / "build_extension"), "--binary", str(binary)]
    out = subprocess.run(build + ["--out", str(tmp_path / "dist")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    z = Path(out.stdout.strip())
    assert z.name == "aurora_importer-0.1.0-linux_x64.zip" and z.is_file()  # Blender's --split-platforms name
    zf = zipfile.ZipFile(z)
    names = zf.namelist()
    assert "blender_manifest.toml" in names and "scene_schema.json" in names and "scene_keys.json" in names
    assert {"__init__.py", "preferences.py", "operators/__init__.py", "operators/bake.py", "ui/__init__.py",
            "ui/panels.py"} <= set(names)  # the subpackages too
    assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)
    baker = zf.getinfo("bin/linux-x64/aurora")
    assert zf.read(baker) == binary.read_bytes() and (baker.external_attr >> 16) & 0o111
    assert tomllib.loads(zf.read("blender_manifest.toml").decode())["platforms"] == ["linux-x64"]
    again = subprocess.run(build + ["--out", str(tmp_path / "dist2")], capture_output=True, text=True, check=True)
    assert Path(again.stdout.strip()).read_bytes() == z.read_bytes()  # reproducible
    plain = subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension"), "--no-binary", "--out", str(tmp_path / "dist3")],
                           capture_output=True, text=True, check=True)
    plain_zip = zipfile.ZipFile(Path(plain.stdout.strip()))
    assert Path(plain.stdout.strip()).name == "aurora_importer-0.1.0.zip"
    assert not any(n.startswith("bin/") for n in plain_zip.namelist())
    assert "platforms" not in tomllib.loads(plain_zip.read("blender_manifest.toml").decode())
    result = bpy.ops.extensions.package_install_files(filepath=str(z), repo="user_default", enable_on_install=True)
    assert result == {"FINISHED"}
    module = "bl_ext.user_default.aurora_importer"
    try:
        assert module in bpy.context.preferences.addons
        installed = Path(bpy.utils.user_resource("EXTENSIONS")) / "user_default" / "aurora_importer"
        manifest = tomllib.loads((installed / "blender_manifest.toml").read_text())
        assert (manifest["id"], manifest["name"]) == ("aurora_importer", "Aurora")
        assert str(installed).startswith(str(blender_user_dir))  # never the real user folder
        assert hasattr(bpy.ops.aurora, "import_vdb")
        result = bpy.ops.aurora.import_vdb(filepath=str(aurora_vdb), density_scale=2.0, emission_scale=3.0)
        assert result == {"FINISHED"}
        vols = [o for o in bpy.data.objects if o.type == "VOLUME"]
        assert len(vols) == 1
        assert_aurora_volume(vols[0], 2.0, 3.0)
        assert np.allclose(np.array(vols[0].matrix_world), np.eye(4))
        assert bpy.context.scene.unit_settings.scale_length == 1000.0  # 1 BU = 1 km
        # A bake from the panel's operator with nothing but the extension:
        # the baker comes from the installed zip.
        monkeypatch.delenv("AURORA_BIN", raising=False)
        monkeypatch.setenv("PATH", str(tmp_path))  # no aurora on PATH either
        prefs = bpy.context.preferences.addons[module].preferences
        assert type(prefs).bl_idname == module  # the preferences are keyed by the package
        assert prefs.binary == ""
        found = sys.modules[module + ".preferences"].aurora_binary(bpy.context)
        assert Path(found) == installed / "bin" / "linux-x64" / "aurora"
        s = bpy.context.scene.aurora
        s.output_dir = str(tmp_path / "bake")
        s.beams.count, s.footprint.resolution, s.grid.voxel_size = 300, (64, 16), 2.0
        assert bpy.ops.aurora.bake() == {"FINISHED"}
        baked = [o for o in bpy.data.objects if o.get("aurora_bake_dir") == str(tmp_path / "bake")]
        assert len(baked) == 1 and baked[0].data.grids.load()
        assert (tmp_path / "bake" / "aurora.vdb").is_file() and (tmp_path / "bake" / "scene.toml").is_file()
        # A path in the preferences is the user's explicit choice and wins
        # over the bundled baker.
        prefs.binary = str(binary)
        assert sys.modules[module + ".preferences"].aurora_binary(bpy.context) == str(binary)
    finally:
        bpy.ops.preferences.addon_disable(module=module)
    assert module not in bpy.context.preferences.addons


def test_enables_as_legacy_addon(bpy, fresh, tmp_path, aurora_vdb):
    import addon_utils

    # A name of its own, so this is not the copy conftest already imported.
    name = "aurora_importer_legacy"
    (tmp_path / "scripts" / "addons").mkdir(parents=True)
    (tmp_path / "scripts" / "addons" / name).symlink_to(ADDON, target_is_directory=True)
    d = bpy.context.preferences.filepaths.script_directories.new()
    d.directory = str(tmp_path / "scripts")
    bpy.utils.refresh_script_paths()
    try:
        mod = addon_utils.enable(name, default_set=True, handle_error=None)
        assert mod is not None and name in bpy.context.preferences.addons
        assert mod.bl_info["blender"] <= (5, 0, 0) and mod.bl_info["name"] == "Aurora"
        assert bpy.ops.aurora.import_vdb(filepath=str(aurora_vdb)) == {"FINISHED"}
        assert_aurora_volume([o for o in bpy.data.objects if o.type == "VOLUME"][0], 1.0, 1.0)
        # With a scene file: camera, world and the file's scales come too.
        cam = {"position": [0, -50, 5], "look_at": [10, 0, 103], "up": [0, 0, 1], "projection": "perspective",
               "fov_deg": 30.0}
        toml = synth.write_scene(tmp_path / "op.toml", cam, 64, 36, density_scale=0.25, emission_scale=2.0)
        before = set(bpy.data.objects)
        assert bpy.ops.aurora.import_vdb(filepath=str(aurora_vdb), scene_file=str(toml)) == {"FINISHED"}
        sc = bpy.context.scene
        assert sc.camera is not None and sc.camera.data.angle_y == pytest.approx(math.radians(30.0))
        assert not sc.render.film_transparent  # interactive default: opaque film, background visible
        new_vols = [o for o in bpy.data.objects if o not in before and o.type == "VOLUME"]
        assert len(new_vols) == 1
        assert_aurora_volume(new_vols[0], 0.25, 2.0)
        # Errors are reported (an ERROR report, which bpy.ops turns into a
        # RuntimeError for a script), not a Python traceback from the add-on.
        with pytest.raises(RuntimeError, match="missing.vdb: no such file"):
            bpy.ops.aurora.import_vdb(filepath=str(tmp_path / "missing.vdb"))
    finally:
        addon_utils.disable(name, default_set=True)
        bpy.context.preferences.filepaths.script_directories.remove(d)
        sys.modules.pop(name, None)


def test_import_function_vdb(addon, fresh, aurora_vdb, bpy):
    objs = addon.import_aurora(aurora_vdb, density_scale=0.5, emission_scale=4.0)
    assert len(objs) == 1
    obj = objs[0]
    assert_aurora_volume(obj, 0.5, 4.0)
    assert np.allclose(np.array(obj.matrix_world), np.eye(4))  # the VDB's transform places it
    # Bounds in km straight from the VDB transform: index 0..11 at 0.5 km from (10, -3, 100).
    corners = np.array([obj.matrix_world @ __import__("mathutils").Vector(c) for c in obj.bound_box])
    assert corners.min(0)[2] <= 100.0 + 1e-6 and corners.max(0)[2] >= 105.5 - 1e-6
    assert obj["aurora_source"] == str(Path(aurora_vdb).resolve())


def _render_mean(bpy, scene, cam_pos, look, scale_clip: float) -> np.ndarray:
    """Mean linear RGB of a 24x16 Cycles picture from a camera at `cam_pos`
    looking at `look` (Blender units), fixed seed."""
    from mathutils import Vector

    data = bpy.data.cameras.new("c")
    data.clip_start, data.clip_end = 0.01 * scale_clip, 1000.0 * scale_clip
    cam = bpy.data.objects.new("c", data)
    scene.collection.objects.link(cam)
    cam.location = cam_pos
    cam.rotation_euler = (Vector(look) - Vector(cam_pos)).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam
    scene.render.engine = "CYCLES"
    scene.cycles.samples, scene.cycles.seed, scene.cycles.device = 16, 5, "CPU"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 24, 16, 100
    scene.render.filepath = str(Path(bpy.app.tempdir) / "shot.exr")
    scene.render.image_settings.file_format = "OPEN_EXR"
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(scene.render.filepath)
    px = np.array(img.pixels[:], dtype=np.float64).reshape(-1, 4)[:, :3]
    bpy.data.images.remove(img)
    return px.mean(axis=0)


def test_import_into_a_shot_in_metres_keeps_the_shot_and_the_picture(addon, fresh, bpy, aurora_vdb):
    """A shot in metres (1 Blender unit = 1 m) keeps its unit settings, frame
    range and fps; the Volume comes in 1000 units per km, and Cycles draws
    the same picture as the km import seen from the same place."""
    sc = bpy.context.scene
    sc.unit_settings.system, sc.unit_settings.scale_length, sc.unit_settings.length_unit = "METRIC", 1.0, "METERS"
    sc.frame_start, sc.frame_end, sc.render.fps = 1001, 1240, 24
    obj = addon.import_aurora(aurora_vdb, units="scene")[0]
    assert (sc.unit_settings.scale_length, sc.unit_settings.length_unit) == (1.0, "METERS")
    assert (sc.frame_start, sc.frame_end, sc.render.fps) == (1001, 1240, 24)
    assert np.allclose(np.array(obj.matrix_world), np.diag([1000.0, 1000.0, 1000.0, 1.0]))
    assert obj.data.render.space == "OBJECT"  # path lengths in the grid's km
    look_km, cam_km = (13.0, 0.0, 102.5), (13.0, -30.0, 102.5)
    metres = _render_mean(bpy, sc, tuple(1000.0 * c for c in cam_km), tuple(1000.0 * c for c in look_km), 1000.0)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    addon.import_aurora(aurora_vdb)
    assert sc.unit_settings.scale_length == 1000.0
    km = _render_mean(bpy, sc, cam_km, look_km, 1.0)
    assert km.max() > 0.0
    # Same seed and the same geometry up to a scale: equal but for float
    # rounding in the ray setup, far below Cycles' 16-sample noise.
    assert metres == pytest.approx(km, rel=0.02)
    # Any scale, by number; a bad one is refused.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    obj = addon.import_aurora(aurora_vdb, units=100.0)[0]
    assert np.allclose(np.array(obj.matrix_world), np.diag([100.0, 100.0, 100.0, 1.0]))
    assert bpy.context.scene.unit_settings.scale_length == 1.0  # untouched
    with pytest.raises(addon.AuroraImportError, match="units = -1"):
        addon.import_aurora(aurora_vdb, units=-1.0)
    # The operator's options say what they change.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        assert bpy.ops.aurora.import_vdb(filepath=str(aurora_vdb), units="CUSTOM", units_per_km=10.0) == {"FINISHED"}
        vol = [o for o in bpy.data.objects if o.type == "VOLUME"][0]
        assert np.allclose(np.array(vol.matrix_world), np.diag([10.0, 10.0, 10.0, 1.0]))
        assert bpy.context.scene.unit_settings.scale_length == 1.0
        units = bpy.ops.aurora.import_vdb.get_rna_type().properties["units"]
        assert units.default == "KM" and units.enum_items["KM"].name == "Set Scene to km"
    finally:
        addon.unregister()


def test_import_with_scattering_keeps_extinction(addon, fresh, aurora_vdb):
    obj = addon.import_aurora(aurora_vdb, 1.5, 1.0, scattering_albedo=0.6)[0]
    pv = principled(obj.data.materials[0])
    # sigma_s = 0.6 sigma_t, sigma_a = 0.4 sigma_t: Density (sigma_t) unchanged.
    assert tuple(pv.inputs["Color"].default_value)[:3] == pytest.approx((0.6, 0.6, 0.6))
    assert pv.inputs["Density"].default_value == pytest.approx(1.5)


def test_float_emission_grid_reads_as_grey(addon, fresh, tmp_path):
    v = synth.write_vdb(tmp_path / "grey.vdb", 1.0, (0, 0, 0), None, np.ones((4, 4, 4), np.float32))
    obj = addon.import_aurora(v)[0]
    grids = {g.name: g.data_type for g in obj.data.grids}
    assert grids == {"emission": "FLOAT"}
    pv = principled(obj.data.materials[0])
    # No density grid: Density 0, or Principled would fill the bounds with it.
    assert pv.inputs["Density"].default_value == 0.0
    assert pv.inputs["Emission Color"].links[0].from_node.attribute_name == "emission"


@pytest.mark.parametrize("mpu, up, scale, rot_x_deg", [(1000, "Z", 1.0, 0.0), (1, "Y", 1e-3, 90.0)])
def test_import_usda(addon, fresh, bpy, tmp_path, aurora_vdb, mpu, up, scale, rot_x_deg):
    """aurora's stage (km: metersPerUnit 1000, Z up) lands at identity; a
    stage in metres with Y up is scaled to km and turned Z-up."""
    import shutil

    shutil.copy(aurora_vdb, tmp_path / "aurora.vdb")
    usda = write_usda(tmp_path / "aurora.usda", "aurora.vdb", mpu, up)
    # The file is a valid UsdVol stage for the USD library itself (its own
    # process: usd-core and Blender's bundled USD stay apart).
    check = ("from pxr import Usd, UsdVol, UsdGeom; s = Usd.Stage.Open(%r); v = UsdVol.Volume(s.GetPrimAtPath('/aurora'));"
             "f = v.GetFieldPaths(); assert sorted(str(k) for k in f) == ['density', 'emission'], f;"
             "assert UsdGeom.GetStageMetersPerUnit(s) == %r" % (str(usda), float(mpu)))
    subprocess.run([sys.executable, "-c", check], check=True)
    objs = addon.import_aurora(usda, 1.0, 2.0)
    assert len(objs) == 1
    assert_aurora_volume(objs[0], 1.0, 2.0)
    from mathutils import Matrix

    expected = Matrix.Scale(scale, 4) @ Matrix.Rotation(math.radians(rot_x_deg), 4, "X")
    assert np.allclose(np.array(objs[0].matrix_world), np.array(expected), atol=1e-9)


def test_import_errors(addon, fresh, bpy, tmp_path):
    with pytest.raises(addon.AuroraImportError, match="no such file"):
        addon.import_aurora(tmp_path / "missing.vdb")
    other = tmp_path / "other.vdb"
    import pyopenvdb as vdb

    g = vdb.FloatGrid()
    g.name = "temperature"
    g.getAccessor().setValueOn((0, 0, 0), 1.0)
    vdb.write(str(other), grids=[g])
    with pytest.raises(addon.AuroraImportError, match="no `density` or `emission`"):
        addon.import_aurora(other)
    bad = tmp_path / "notes.txt"
    bad.write_text("x")
    with pytest.raises(addon.AuroraImportError, match="expected .vdb"):
        addon.import_aurora(bad)


def test_setup_scene_from_toml_perspective(addon, fresh, bpy, tmp_path, aurora_vdb):
    cam = {"position": [0.0, -260.0, 1.5], "look_at": [0.0, 0.0, 110.0], "up": [0, 0, 1],
           "projection": "perspective", "fov_deg": 50.0}
    scene_path = synth.write_scene(tmp_path / "s.toml", cam, 160, 90, spp=16, density_scale=0.7,
                                   emission_scale=1.3, background=(0.01, 0.02, 0.03),
                                   terrain={"kind": "plane", "height": 0.25, "albedo": [0.2, 0.3, 0.4]})
    built = addon.setup_scene_from_toml(scene_path, vdb=aurora_vdb,
                                        settings=addon.CyclesSettings(samples=32, seed=3))
    sc = bpy.context.scene
    # Camera: columns right, up', -forward (the reference renderer's basis).
    f = np.array([0.0, 260.0, 108.5]) / np.linalg.norm([0.0, 260.0, 108.5])
    r = np.cross(f, [0, 0, 1])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    m = np.array(built.camera.matrix_world)
    assert np.allclose(m[:3, 0], r) and np.allclose(m[:3, 1], u) and np.allclose(m[:3, 2], -f)
    assert np.allclose(m[:3, 3], [0.0, -260.0, 1.5])
    c = built.camera.data
    assert (c.type, c.sensor_fit) == ("PERSP", "VERTICAL")
    assert c.angle_y == pytest.approx(math.radians(50.0))
    assert sc.camera == built.camera
    # Film and sampling.
    assert (sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage) == (160, 90, 100)
    assert sc.render.film_transparent and sc.view_layers[0].use_pass_environment
    assert sc.cycles.pixel_filter_type == "BOX"
    assert (sc.cycles.samples, sc.cycles.seed) == (32, 3)
    assert not sc.cycles.use_denoising and not sc.cycles.use_adaptive_sampling
    assert sc.cycles.sample_clamp_direct == 0 and sc.cycles.sample_clamp_indirect == 0
    assert sc.cycles.volume_biased and sc.cycles.volume_step_rate == pytest.approx(0.1)
    # The scene file's view (the default AgX, no look); the EXR is linear whatever it is.
    assert (sc.view_settings.view_transform, sc.view_settings.look, sc.view_settings.exposure) == ("AgX", "None", 0)
    assert sc.unit_settings.scale_length == 1000.0
    # Background only for camera rays, not a light.
    w = sc.world
    assert w.cycles.sampling_method == "NONE"
    bg = [n for n in w.node_tree.nodes if n.bl_idname == "ShaderNodeBackground"][0]
    assert tuple(bg.inputs["Color"].default_value)[:3] == pytest.approx((0.01, 0.02, 0.03))
    mix = [n for n in w.node_tree.nodes if n.bl_idname == "ShaderNodeMixShader"][0]
    assert mix.inputs["Fac"].links[0].from_socket.name == "Is Camera Ray"
    # Volume scales from [volume]; terrain plane with the albedo; lights for the terrain.
    assert_aurora_volume(built.volumes[0], 0.7, 1.3)
    # The scene's Earth is the default sphere: the plane at 0.25 km is its
    # cap, every vertex 0.25 km above it (float32 coordinates: 1e-6 km).
    ter = built.terrain
    R = 6371.0
    radii = [math.dist(ter.matrix_world @ v.co, (0.0, 0.0, -R)) for v in ter.data.vertices]
    assert max(abs(r - (R + 0.25)) for r in radii) < 1e-5
    diffuse = [n for n in ter.data.materials[0].node_tree.nodes if n.bl_idname == "ShaderNodeBsdfDiffuse"][0]
    assert tuple(diffuse.inputs["Color"].default_value)[:3] == pytest.approx((0.2, 0.3, 0.4))
    assert len(built.lights) > 0 and not built.volumes[0].visible_diffuse
    total = sum(o.data.energy * np.array(o.data.color) for o in built.lights)
    # P = 4 pi I, I = emission_scale * h^3 * sum(emission): 1.3 * 0.125 * 144 * sum(linspace(0.1, 1, 12)).
    assert total[1] == pytest.approx(4 * math.pi * 1.3 * 0.125 * 144 * 6.6, rel=1e-5)


def horizon_fan(bpy, obj, camera, radius, centre, offsets_deg):
    """Rays from `camera` in the vertical plane of the cap's nadir at the
    given angles from the sphere's horizon (negative: below it), against the
    cap's mesh: whether each hits it and the hit's distance from `centre`."""
    from mathutils import Vector
    from mathutils.bvhtree import BVHTree

    tree = BVHTree.FromObject(obj, bpy.context.evaluated_depsgraph_get())
    cam, c = np.array(camera, float), np.array(centre, float)
    rho = np.linalg.norm(cam - c)
    down = (c - cam) / rho
    side = np.cross(down, [1.0, 0.0, 0.0] if abs(down[0]) < 0.9 else [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    out = np.cross(side, down)  # horizontal, in the plane of the fan
    tangent = math.asin(radius / rho)  # the horizon ray's angle from the nadir
    rows = []
    for off in offsets_deg:
        psi = tangent + math.radians(off)  # more than the tangent: above the horizon
        d = math.cos(psi) * down + math.sin(psi) * out
        loc, _, _, _ = tree.ray_cast(Vector(cam), Vector(d))
        rows.append((off, loc is not None, None if loc is None else float(np.linalg.norm(np.array(loc) - c))))
    return rows


@pytest.mark.parametrize("camera", [(0.0, -260.0, 1.5), (300.0, 200.0, 40.0), (0.0, 0.0, 0.3)])
def test_plane_on_a_round_earth_is_the_sphere_to_its_horizon(addon, fresh, bpy, tmp_path, camera):
    """On a round Earth the "plane" terrain is the cap of the sphere of
    radius R + height that `aurora render` intersects: a fan of rays across
    the horizon meets the cap exactly when it meets the sphere, to within
    the cap's bound (the horizon at most 1e-3 of its dip low, terrain.py)
    and 0.001 degrees of the ray tracer's rounding, and the hits lie on the
    sphere within 2e-3 of the camera's altitude. A flat plane fails it: its
    horizon is off by about the dip, 0.2 to 7 degrees here."""
    R, h = 6371.0, 0.25
    cam = {"position": list(camera), "look_at": [camera[0], camera[1] + 100.0, camera[2]], "up": [0, 0, 1],
           "projection": "perspective", "fov_deg": 50.0}
    scene_path = synth.write_scene(tmp_path / "r.toml", cam, 16, 9,
                                   terrain={"kind": "plane", "height": h, "albedo": [0.2, 0.3, 0.4]})
    built = addon.setup_scene_from_toml(scene_path)
    ter = built.terrain
    centre, radius = (0.0, 0.0, -R), R + h
    a = math.dist(camera, centre) - radius
    dip = math.degrees(math.acos(radius / (radius + a)))
    tol = 1e-3 * dip + 1e-3
    offsets = [-3 * tol, -1.5 * tol, 1.5 * tol, 3 * tol, -0.5 * dip, -0.9 * dip, 0.5, 5.0]
    for off, hit, r in horizon_fan(bpy, ter, camera, radius, centre, offsets):
        assert hit == (off < 0), f"camera {camera}: ray {off:+.4f} deg from the horizon (dip {dip:.3f}) hit={hit}"
        if hit:
            assert abs(r - radius) <= 2e-3 * a + 5e-5, f"camera {camera}: hit {r - radius:+.6f} km off the sphere"
    assert len(ter.data.polygons) <= 200_000
    assert all(p.use_smooth for p in ter.data.polygons)


def test_plane_on_flat_ground_is_a_square(addon, fresh, tmp_path):
    cam = {"position": [3.0, -40.0, 1.5], "look_at": [3.0, 0.0, 1.5], "up": [0, 0, 1],
           "projection": "perspective", "fov_deg": 50.0}
    scene_path = synth.write_scene(tmp_path / "f.toml", cam, 16, 9,
                                   terrain={"kind": "plane", "height": 0.25, "albedo": [0.2, 0.3, 0.4]})
    text = scene_path.read_text() + "\n[earth]\nradius_km = 0.0\n"
    scene_path.write_text(text)
    ter = addon.setup_scene_from_toml(scene_path).terrain
    verts = sorted((round(v.co.x, 3), round(v.co.y, 3), round(v.co.z, 6)) for v in ter.data.vertices)
    r = 1.0e4
    assert verts == sorted([(3 - r, -40 - r, 0.25), (3 + r, -40 - r, 0.25), (3 + r, -40 + r, 0.25), (3 - r, -40 + r, 0.25)])


def test_setup_scene_orthographic_point_sampled_heightfield(addon, fresh, bpy, tmp_path):
    cam = {"position": [1.0, 2.0, 30.0], "look_at": [1.0, 2.0, 0.0], "up": [0, 1, 0],
           "projection": "orthographic", "ortho_height": 12.0}
    scene_path = synth.write_scene(tmp_path / "o.toml", cam, 40, 30, spp=1,
                                   terrain={"kind": "heightfield", "height": 0.0, "albedo": [0.5, 0.5, 0.5]})
    obj = tmp_path / "terrain.obj"
    # Two triangles rising along +x to z = 3 km; with normals, as a mesher may write them.
    obj.write_text("v 0 0 0\nv 10 0 3\nv 10 10 3\nv 0 10 0\nvn -0.287 0 0.958\n"
                   "f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n")
    with pytest.raises(ValueError, match="aurora terrain"):
        addon.setup_scene_from_toml(scene_path)
    built = addon.setup_scene_from_toml(scene_path, terrain_obj=obj)
    sc = bpy.context.scene
    c = built.camera.data
    assert (c.type, c.sensor_fit, c.ortho_scale) == ("ORTHO", "VERTICAL", 12.0)
    assert sc.cycles.pixel_filter_type == "GAUSSIAN" and sc.cycles.filter_width == pytest.approx(0.01)
    verts = sorted(tuple(round(x, 6) for x in built.terrain.matrix_world @ v.co) for v in built.terrain.data.vertices)
    assert verts == [(0, 0, 0), (0, 10, 0), (10, 0, 3), (10, 10, 3)]  # z stayed up
    # Smooth, with Blender's own vertex normals (the OBJ's are dropped), as
    # `aurora render` shades: on this plane each is the plane's normal.
    mesh = built.terrain.data
    assert all(p.use_smooth for p in mesh.polygons)
    assert not getattr(mesh, "has_custom_normals", False)
    n = (-3.0 / 109.0 ** 0.5, 0.0, 10.0 / 109.0 ** 0.5)  # the plane z = 0.3 x
    for v in mesh.vertices:
        assert tuple(v.normal) == pytest.approx(n, abs=1e-5)


def test_scene_file_errors(addon, tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[camera]\nprojection = \"mirrorball\"\n")
    with pytest.raises(addon.SceneFileError, match="mirrorball"):
        addon.load_scene(p)
    p.write_text("[render]\nwidht = 3\n")
    with pytest.raises(addon.SceneFileError, match="widht"):
        addon.load_scene(p)
    p.write_text("[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 5]\nup = [0, 0, 1]\n")
    with pytest.raises(addon.SceneFileError, match="parallel"):
        addon.load_scene(p)
    # The bake's own tables are the baker's business: accepted here.
    p.write_text("seed = 3\n[[curtain]]\nlength = 100.0\n[grid]\nvoxel_size = \"auto\"\n[render]\nwidth = 8\nheight = 4\n")
    s = addon.load_scene(p)
    # Left-out keys take aurora's defaults (fov 75, see test_scene_defaults_match_the_baker).
    assert (s.render.width, s.render.height, s.camera.fov_deg) == (8, 4, 75.0)


def test_blender_minimum_resolution_is_refused(addon, fresh, tmp_path):
    """Blender silently raises a 2-pixel-high render to 4 pixels (changing the
    pixel size, measured): refused instead."""
    cam = {"position": [0, -5, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "projection": "orthographic",
           "ortho_height": 1.0}
    with pytest.raises(ValueError, match="at least 4x4"):
        addon.setup_scene_from_toml(synth.write_scene(tmp_path / "t.toml", cam, 64, 2))


@pytest.mark.parametrize("shell", [True, False])
def test_bake_writes_the_cycles_shell_the_addon_would_add(addon, tmp_path, shell):
    # `aurora bake` dilates both grids by one voxel of active zeros (the
    # 26-neighbourhood) and marks them; the add-on then reads the file as it
    # is. Proof that the bake's shell is the add-on's: padding the baked file
    # switches on no voxel at all. Without the shell, padding adds voxels and
    # the file is not marked.
    scene = write_small_scene(tmp_path / "s.toml", grid={"cycles_shell": shell})
    out = tmp_path / "out"
    r = subprocess.run([str(aurora_bin()), "bake", str(scene), "--out", str(out), "-q"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    vdb = out / "aurora.vdb"
    from aurora_importer.vdb_pad import has_cycles_shell, pad_vdb
    assert has_cycles_shell(vdb) is shell
    report = pad_vdb(vdb, tmp_path / "padded.vdb")
    added = sum(report.grids.values())
    if shell:
        assert report.grids == {"density": 0, "emission": 0}, report.grids
    else:
        assert added > 0, report.grids


def test_scene_defaults_match_the_baker(addon, tmp_path):
    # A scene file that leaves out [camera], [render], [volume], [background]
    # and [terrain] must frame and expose the same picture in Blender as in
    # `aurora render`: the add-on's defaults are aurora's. `aurora scene FILE`
    # prints the file with every default filled in by aurora itself.
    from aurora_importer.scene_toml import load_scene
    minimal = tmp_path / "minimal.toml"
    minimal.write_text("seed = 3\n")
    r = subprocess.run([str(aurora_bin()), "scene", str(minimal)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    full = tmp_path / "full.toml"
    full.write_text(r.stdout)
    ours, theirs = load_scene(minimal), load_scene(full)
    for table in ("camera", "render", "volume", "background", "terrain"):
        assert getattr(ours, table) == getattr(theirs, table), table


def test_scene_schema_copy_is_the_binarys(addon):
    # The add-on's defaults and ranges come from blender/scene_schema.json;
    # it must be what `aurora scene --schema` prints (tests/cli/schema.rs checks
    # the same from Rust), and a [terrain] table without `kind` means no
    # terrain there as in aurora (Terrain::default), unlike a missing table.
    from aurora_importer import scene_toml
    r = subprocess.run([str(aurora_bin()), "scene", "--schema"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    committed = (ADDON / "scene_schema.json").read_text()
    assert r.stdout == committed, "run: aurora scene --schema > blender/scene_schema.json"
    assert scene_toml.Camera().fov_deg == scene_toml.SCHEMA["camera"]["fov_deg"]["default"]
    assert scene_toml.scene_from_dict({"terrain": {"height": 1.0}}).terrain.kind == "none"
    assert scene_toml.scene_from_dict({}).terrain.kind == "heightfield"
    with pytest.raises(scene_toml.SceneFileError, match="render.width"):
        scene_toml.scene_from_dict({"render": {"width": scene_toml.SCHEMA["render"]["width"]["max"] + 1}})


def test_panoramic_cameras(addon, fresh, tmp_path):
    import bpy
    for proj, fov, kind in [("fisheye", 180.0, "FISHEYE_EQUIDISTANT"), ("equirectangular", 75.0, "EQUIRECTANGULAR")]:
        cam = {"position": [0.0, 0.0, 1.0], "look_at": [0.0, 0.0, 10.0], "up": [0.0, 1.0, 0.0],
               "projection": proj, "fov_deg": fov}
        scene_path = synth.write_scene(tmp_path / f"{proj}.toml", cam, 64, 64, spp=1)
        built = addon.setup_scene_from_toml(scene_path)
        c = built.camera.data
        assert (c.type, c.panorama_type) == ("PANO", kind)
        if proj == "fisheye":
            assert c.fisheye_fov == pytest.approx(math.radians(fov))
        else:
            assert (c.longitude_min, c.longitude_max) == pytest.approx((-math.pi, math.pi))
        # The image centre looks down the object's -Z = forward (straight up).
        assert tuple(built.camera.matrix_world.col[2][:3]) == pytest.approx((0.0, 0.0, -1.0), abs=1e-9)
        bpy.ops.wm.read_factory_settings(use_empty=True)
