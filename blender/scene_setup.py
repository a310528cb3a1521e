"""Build a whole Blender scene from an aurora scene TOML.

`setup_scene_from_toml(path, vdb=...)` gives the same picture as
`aurora render path --vdb ...`: camera, resolution and pixel footprint,
volume material with the file's density/emission scales and the sky's air
(air.py: the emission dimmed towards each camera ray), background seen only
by camera rays, the airglow and the stars as the world's background (the
map `aurora sky` writes, see sky_map), terrain (plane or heightfield OBJ),
the Cycles settings of render_settings.py, and the picture developed as
`aurora render` develops its PNG (display.py: white balance, exposure). The pixel footprint follows the scene's `render.spp`
(1: pixel centres; more: the pixel square); the number of Cycles samples is
separate (Cycles needs many more than the reference raymarcher).
"""

from __future__ import annotations

import math
import shutil
import subprocess
import tempfile
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import bpy

from .air import line_depths, weights
from .camera import build_camera
from .display import develop as develop_display
from .display import metered_ev
from .emission_lights import build_emission_lights, emission_clusters
from .render_settings import CyclesSettings, configure_cycles, set_scene_units, set_view
from .scene_toml import SCHEMA, SceneSpec, load_scene
from .terrain import heightfield_terrain, plane_terrain
from .volume_import import import_aurora
from .world import background_world


@dataclass
class AuroraScene:
    spec: SceneSpec
    camera: bpy.types.Object | None
    volumes: list
    terrain: bpy.types.Object | None
    world: bpy.types.World | None
    settings: CyclesSettings
    #: Point lights standing in for the emission (terrain_lighting "lights").
    lights: list


def camera_air(spec: SceneSpec):
    """The air as the camera sees it (air.py), or None with `sky.extinction`
    off: each line's zenith depth above the camera, the channel weights of
    the scene's observer (`[colour] observer`, the colours the bake wrote) and
    the camera's local up. On a round Earth (`earth.radius_km` > 0, centre
    (0, 0, -R)) the camera's altitude is its distance from the centre minus
    R and its up the radial direction; on flat ground its z and +z, as in
    `aurora render` (`Extinction::for_observer_at`)."""
    if not spec.sky.extinction:
        return None
    x, y, z = spec.camera.position
    r = spec.earth.radius_km
    if r > 0.0:
        d = math.sqrt(x * x + y * y + (z + r) ** 2)
        altitude, up = d - r, (x / d, y / d, (z + r) / d)
    else:
        altitude, up = z, (0.0, 0.0, 1.0)
    return line_depths(spec.sky, altitude), weights(spec.observer), up


def sky_wanted(path, spec: SceneSpec) -> bool:
    """Whether `aurora render` draws a sky of its own for this scene: the
    airglow (`[airglow] on`) or the stars (`background.stars`)."""
    with open(path, "rb") as f:
        glow = tomllib.load(f).get("airglow", {})
    on = glow.get("on", SCHEMA["airglow"]["on"]["default"])
    return bool(on) or bool(spec.background.stars)


def sky_map_width(spec: SceneSpec) -> int:
    """The sky map's width: one map pixel per camera pixel at the image
    centre (the stars, a Gaussian of one pixel in both renderers, then have
    about the same size), even, in [512, 16384]."""
    c, w, h = spec.camera, spec.render.width, spec.render.height
    if c.projection == "perspective":
        angle = 2.0 * math.tan(math.radians(c.fov_deg) / 2.0) / h
    elif c.projection == "fisheye":
        angle = math.radians(c.fov_deg) / max(w, h)
    elif c.projection == "equirectangular":
        angle = 2.0 * math.pi / w
    else:
        return 2048
    return min(16384, max(512, 2 * round(math.pi / angle)))


def sky_map(path, out, spec: SceneSpec, binary: str | None = None) -> Path:
    """Runs `aurora sky` on the scene file `path`, writing `out` (an
    equirectangular linear EXR of the airglow and stars seen from the
    camera, src/render/sky_map.rs); binary: the aurora binary (default:
    $AURORA_BIN or `aurora` on PATH, as the bake finds it)."""
    from .bake_job import find_binary

    cmd = [binary or find_binary(), "sky", str(path), "--out", str(out), "--width", str(sky_map_width(spec)), "--quiet"]
    r = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    if r.returncode != 0:
        raise ValueError(f"{path}: `aurora sky` failed ({r.returncode}): {r.stderr.strip()}")
    return Path(out)


def setup_scene_from_toml(
    path,
    vdb=None,
    terrain_obj=None,
    scene: bpy.types.Scene | None = None,
    settings: CyclesSettings | None = None,
    camera: bool = True,
    world: bool = True,
    terrain: bool = True,
    volume_alpha: bool = True,
    pad_dir=None,
    sky_exr=None,
    develop: bool = True,
) -> AuroraScene:
    """Set up `scene` (default: the context scene) from the scene file `path`.

    vdb: the bake to import (.vdb or .usda); None builds everything else.
    terrain_obj: the OBJ from `aurora terrain` (needed for kind = "heightfield").
    settings: Cycles settings; its point_sample is overridden by render.spp.
    volume_alpha: terrain pixels get alpha = 1 - T_volume (else 1).
    pad_dir: where to write the Cycles-padded copy of the VDB (see
    volume_import.import_aurora); None renders the file as it is.
    sky_exr: the airglow and stars map (`aurora sky`) for the world; None
    makes it with the aurora binary when the scene has airglow or stars
    (sky_map; packed into the .blend); False: none.
    develop: the picture developed as `aurora render`'s PNG (display.py: the
    camera's white balance in the compositor, the view's exposure; for
    `render.exposure = "auto"` the EV the binary meters on `vdb`). The render
    passes stay linear either way.
    """
    spec = load_scene(path)
    scene = scene or bpy.context.scene
    settings = replace(settings or CyclesSettings(), point_sample=spec.render.spp == 1)
    set_scene_units(scene)
    configure_cycles(scene, spec.render.width, spec.render.height, settings)
    set_view(scene, spec.render.view_transform)
    cam = build_camera(scene, spec.camera) if camera else None
    wld = None
    if world:
        image = spec.background.image
        if image is not None and spec.path is not None and not Path(image).is_absolute():
            image = spec.path.parent / image
        sky = sky_exr
        made = None
        if sky is None and sky_wanted(path, spec):
            from .bake_job import BakeError, find_binary

            try:
                binary = find_binary()
            except BakeError as e:
                print(f"aurora: {e}; the world has no airglow or stars")
            else:
                made = Path(tempfile.mkdtemp(prefix="aurora-sky-"))
                sky = sky_map(path, made / "sky.exr", spec, binary)
        try:
            # The sky lights the ground only (`aurora render` lights nothing
            # else with it): without a terrain the world stays a backdrop,
            # and Cycles samples no light for it.
            lights = spec.sky.extinction and spec.sky.scattering and terrain and spec.terrain.kind != "none"
            wld = background_world("AuroraBackground", spec.background.radiance, image, sky or None, lights=lights)
        finally:
            if made is not None:
                shutil.rmtree(made, ignore_errors=True)
        scene.world = wld
    ter = None
    if terrain and spec.terrain.kind == "plane":
        ter = plane_terrain(scene, spec.terrain.height, spec.terrain.albedo, spec.camera.position,
                            spec.earth.radius_km, volume_alpha)
    elif terrain and spec.terrain.kind == "heightfield":
        if terrain_obj is None:
            raise ValueError(f"{path}: terrain.kind = \"heightfield\" needs the OBJ from `aurora terrain`")
        ter = heightfield_terrain(scene, Path(terrain_obj), spec.terrain.albedo, volume_alpha)
    vols = []
    lights = []
    if vdb is not None:
        vols = import_aurora(vdb, spec.volume.density_scale, spec.volume.emission_scale, scene=scene,
                             pad_dir=pad_dir, air=camera_air(spec))
    if ter is not None and settings.terrain_lighting == "lights":
        for obj in vols:
            if "emission" not in {g.name for g in obj.data.grids}:
                continue
            clusters = emission_clusters(bpy.path.abspath(obj.data.filepath), spec.volume.emission_scale,
                                         settings.max_lights)
            _, objs = build_emission_lights(scene, clusters, obj.matrix_world)
            lights += objs
            # The lights carry the emission to the terrain; a diffuse ray
            # meeting the volume would count it twice. Shadow rays still
            # cross the volume and are attenuated by it.
            obj.visible_diffuse = False
    if develop:
        ev = None
        if spec.render.exposure == "auto":
            if vdb is None:
                raise ValueError(f"{path}: render.exposure = \"auto\" is metered on the bake: give its VDB")
            ev = metered_ev(path, vdb)
        develop_display(scene, spec, ev)
    return AuroraScene(spec, cam, vols, ter, wld, settings, lights)
