"""The render-relevant part of an aurora scene file, read without bpy.

`aurora render` and the Blender side must agree on the camera, the film,
the volume scales, the background, the terrain and the sky's air. This module reads those
six tables of the scene TOML into plain dataclasses. `src/scene/` is the
authority: the defaults and ranges below come from its schema
(`aurora scene --schema`, committed as scene_schema.json next to this file
and checked against the binary by tests/cli/schema.rs), not restated here. The bake tables
(`curtain`, `beams`, ...) are ignored here: the baker validates them.

Units are kilometres, z up (Blender units = km in this add-on).
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field, make_dataclass
from pathlib import Path


#: `aurora scene --schema`: {table: {key: {"default", "min", "max", ...}}}.
SCHEMA = json.loads((Path(__file__).resolve().parent / "scene_schema.json").read_text())


def _default(table: str, key: str):
    v = SCHEMA[table][key]["default"]
    return tuple(v) if isinstance(v, list) else v


def _bound(x):
    return {"inf": math.inf, "-inf": -math.inf}.get(x, x) if isinstance(x, str) else float(x)


#: `camera.projection` values (src/scene/types.rs, `Projection`).
PROJECTIONS = tuple(SCHEMA["camera"]["projection"]["values"])


class SceneFileError(ValueError):
    """A scene file that cannot be read or has a value out of range."""


def _table_class(name: str, table: str, keys: str, doc: str):
    """A frozen dataclass of the schema's `keys` of `table`, each defaulting
    to the schema's default (lists as tuples)."""
    fields = []
    for key in keys.split():
        d = _default(table, key)
        fields.append((key, str | None if d is None else type(d), field(default=d)))
    return make_dataclass(name, fields, frozen=True, namespace={"__doc__": doc, "__module__": __name__})


Camera = _table_class("Camera", "camera", "position look_at up projection fov_deg ortho_height", """`[camera]`.

    fov_deg: the vertical field of view, degrees (perspective); the angle
    across the image circle (fisheye, up to 360). ortho_height: the vertical
    extent of the view in km (orthographic).""")
Render = _table_class("Render", "render", "width height spp shadow_samples exposure view_transform shutter_s png_bits", """`[render]`.

    view_transform: the PNG view transform of `aurora render` ("agx" or
    "standard"; the EXR it writes and Cycles' EXR are linear either way).
    shutter_s: seconds of shutter centred on the frame (0: sharp); Cycles
    blurs along the VDB's velocity grid. png_bits: 8 or 16, for the PNGs
    `aurora render` writes. shadow_samples: `aurora render`'s shadow rays
    per terrain hit (Cycles lights the terrain by its own sampling).""")
Volume = _table_class("Volume", "volume", "density_scale emission_scale", """`[volume]`.

    Extinction sigma_t = density_scale * density grid (per km); emitted
    radiance per km = emission_scale * emission grid.""")
Background = _table_class("Background", "background", "radiance image stars limiting_magnitude star_brightness",
                          """`[background]`.

    radiance: seen by camera rays that escape; lights nothing. image: an
    equirectangular linear EXR of sky radiance (relative to the scene file).
    The procedural stars are drawn by `aurora render` only.""")
Sky = _table_class("Sky", "sky", "extinction ozone_du aerosol_optical_depth angstrom aerosol_scale_height_km scattering",
                   """`[sky]`: the air between the aurora and the camera (air.py), on by default.

    scattering: the air scatters the sky's light into the sight lines (in
    the map `aurora sky` writes) and the sky lights the ground: the world
    shows that map to every ray, not only the camera's (world.py).""")
Earth = _table_class("Earth", "earth", "radius_km", """`[earth]`.

    radius_km: the sphere the camera stands on, centre (0, 0, -radius_km);
    0 is flat ground. The air's altitude and local up at the camera follow it.""")
Terrain = _table_class("Terrain", "terrain", "kind height albedo", """`[terrain]`.

    A scene file without [terrain] gets aurora's default scene terrain.""")


@dataclass(frozen=True)
class SceneSpec:
    """What a renderer needs from a scene file."""

    camera: Camera = field(default_factory=Camera)
    render: Render = field(default_factory=Render)
    volume: Volume = field(default_factory=Volume)
    background: Background = field(default_factory=Background)
    terrain: Terrain = field(default_factory=Terrain)
    sky: Sky = field(default_factory=Sky)
    earth: Earth = field(default_factory=Earth)
    #: The file it came from (None for a scene built in code).
    path: Path | None = None
    #: `[colour] observer`: whose colours the bake wrote ("camera" or "eye");
    #: the air's channel weights follow it (air.py).
    observer: str = _default("colour", "observer")
    #: `[colour] white_balance_k`: the camera's white balance, K (display.py).
    white_balance_k: float = _default("colour", "white_balance_k")


_TABLES = {
    "camera": Camera,
    "render": Render,
    "volume": Volume,
    "background": Background,
    # `terrain` has more keys (mountains, heightmap) that only the terrain
    # generator uses; they are accepted and ignored here.
    "terrain": Terrain,
    "sky": Sky,
    # `earth.magnetic_pole` shapes the bake only; accepted and ignored here.
    "earth": Earth,
}
_TERRAIN_GENERATOR_KEYS = {"mountain_height", "mountain_scale", "heightmap", "extent", "seed"}


def _vec3(where: str, value) -> tuple[float, float, float]:
    if not (isinstance(value, list) and len(value) == 3 and all(isinstance(x, (int, float)) for x in value)):
        raise SceneFileError(f"{where} must be a list of 3 numbers, got {value!r}")
    v = tuple(float(x) for x in value)
    if not all(math.isfinite(x) for x in v):
        raise SceneFileError(f"{where} must be finite, got {value!r}")
    return v  # type: ignore[return-value]


def _checked(src: str, table: str, key: str, t: dict) -> float:
    """`t[key]` (or the default) checked against the schema's range."""
    k = SCHEMA[table][key]
    return _number(f"{src}: {table}.{key}", t.get(key, k["default"]), _bound(k["min"]), _bound(k["max"]),
                   lo_open=not k["min_inclusive"], hi_open=not k["max_inclusive"])


#: `render.exposure`'s stops (its schema states them as a rule beside "auto").
EXPOSURE_STOPS = (-50.0, 50.0)


def _exposure(src: str, r: dict):
    """`render.exposure`: stops in EXPOSURE_STOPS, or "auto" (metered)."""
    value = r.get("exposure", SCHEMA["render"]["exposure"]["default"])
    if value == "auto":
        return "auto"
    if isinstance(value, str):
        raise SceneFileError(f"{src}: render.exposure = {value!r} must be a number of stops in "
                             f"[{EXPOSURE_STOPS[0]:g}, {EXPOSURE_STOPS[1]:g}], or \"auto\"")
    return _number(f"{src}: render.exposure", value, *EXPOSURE_STOPS)


def _number(where: str, value, lo: float, hi: float, lo_open: bool = False, hi_open: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneFileError(f"{where} must be a number, got {value!r}")
    x = float(value)
    ok = (math.isfinite(x) and (x > lo if lo_open else x >= lo) and (x < hi if hi_open else x <= hi))
    if not ok:
        bracket = "(" if lo_open else "["
        close = ")" if hi_open else "]"
        raise SceneFileError(f"{where} = {value!r} must be in {bracket}{lo}, {hi}{close}")
    return x


def _table(doc: dict, name: str, src: str) -> dict:
    t = doc.get(name, {})
    if not isinstance(t, dict):
        raise SceneFileError(f"{src}: [{name}] must be a table")
    cls = _TABLES[name]
    known = set(cls.__dataclass_fields__)
    if name == "terrain":
        known |= _TERRAIN_GENERATOR_KEYS
    if name == "earth":
        known |= {"magnetic_pole"}
    unknown = sorted(set(t) - known)
    if unknown:
        raise SceneFileError(f"{src}: unknown key(s) in [{name}]: {', '.join(unknown)}")
    return t


def scene_from_dict(doc: dict, src: str = "<scene>", path: Path | None = None) -> SceneSpec:
    """Validate the render tables of a parsed TOML document (ranges as in
    `Scene::validate` in src/scene/validation.rs)."""
    c = _table(doc, "camera", src)
    d = Camera()
    cam = Camera(
        position=_vec3(f"{src}: camera.position", c.get("position", list(d.position))),
        look_at=_vec3(f"{src}: camera.look_at", c.get("look_at", list(d.look_at))),
        up=_vec3(f"{src}: camera.up", c.get("up", list(d.up))),
        projection=c.get("projection", d.projection),
        fov_deg=_number(f"{src}: camera.fov_deg", c.get("fov_deg", d.fov_deg), 0.0,
                        360.0 if c.get("projection") == "fisheye" else 180.0, lo_open=True),
        ortho_height=_checked(src, "camera", "ortho_height", c),
    )
    if cam.projection not in PROJECTIONS:
        raise SceneFileError(f"{src}: camera.projection = {cam.projection!r} must be one of {', '.join(PROJECTIONS)}")
    if cam.projection != "fisheye" and cam.fov_deg >= 180.0:
        raise SceneFileError(f"{src}: camera.fov_deg = {cam.fov_deg} must be in (0, 180)")
    fwd = [b - a for a, b in zip(cam.position, cam.look_at)]
    if all(x == 0.0 for x in fwd):
        raise SceneFileError(f"{src}: camera.look_at must differ from camera.position")
    if sum(x * x for x in _cross(fwd, cam.up)) < 1e-18:
        raise SceneFileError(f"{src}: camera.up must not be parallel to the view direction")

    r = _table(doc, "render", src)
    ren = Render(
        width=int(_checked(src, "render", "width", r)),
        height=int(_checked(src, "render", "height", r)),
        spp=int(_checked(src, "render", "spp", r)),
        shadow_samples=int(_checked(src, "render", "shadow_samples", r)),
        exposure=_exposure(src, r),
        view_transform=r.get("view_transform", Render().view_transform),
        shutter_s=_checked(src, "render", "shutter_s", r),
        png_bits=r.get("png_bits", Render().png_bits),
    )
    if isinstance(ren.png_bits, bool) or ren.png_bits not in (8, 16):
        raise SceneFileError(f"{src}: render.png_bits = {ren.png_bits!r} must be 8 or 16")
    views = SCHEMA["render"]["view_transform"]["values"]
    if ren.view_transform not in views:
        raise SceneFileError(f"{src}: render.view_transform = {ren.view_transform!r} must be one of {', '.join(views)}")
    for k in ("width", "height", "spp", "shadow_samples"):
        if k in r and (isinstance(r[k], float) and r[k] != int(r[k])):
            raise SceneFileError(f"{src}: render.{k} must be an integer, got {r[k]!r}")

    v = _table(doc, "volume", src)
    vol = Volume(
        density_scale=_checked(src, "volume", "density_scale", v),
        emission_scale=_checked(src, "volume", "emission_scale", v),
    )

    b = _table(doc, "background", src)
    rad = _vec3(f"{src}: background.radiance", b.get("radiance", list(Background().radiance)))
    if any(x < 0.0 for x in rad):
        raise SceneFileError(f"{src}: background.radiance components must be >= 0, got {list(rad)}")
    db = Background()
    img = b.get("image", db.image)
    if img is not None and not isinstance(img, str):
        raise SceneFileError(f"{src}: background.image must be a path string, got {img!r}")
    stars = b.get("stars", db.stars)
    if not isinstance(stars, bool):
        raise SceneFileError(f"{src}: background.stars must be true or false, got {stars!r}")
    bg = Background(rad, img, stars,
                    _checked(src, "background", "limiting_magnitude", b), _checked(src, "background", "star_brightness", b))

    t = _table(doc, "terrain", src)
    d = Terrain()
    ter = Terrain(
        # A [terrain] table without `kind` takes Terrain::default()'s kind
        # (the schema's default_in_table), a file without [terrain] the
        # default scene's.
        kind=t.get("kind", SCHEMA["terrain"]["kind"].get("default_in_table", d.kind) if "terrain" in doc else d.kind),
        height=_number(f"{src}: terrain.height", t.get("height", d.height), -math.inf, math.inf),
        albedo=_vec3(f"{src}: terrain.albedo", t.get("albedo", list(d.albedo))),
    )
    if ter.kind not in ("none", "plane", "heightfield"):
        raise SceneFileError(f"{src}: terrain.kind = {ter.kind!r} must be \"none\", \"plane\" or \"heightfield\"")
    if any(not 0.0 <= a <= 1.0 for a in ter.albedo):
        raise SceneFileError(f"{src}: terrain.albedo components must be in [0, 1], got {list(ter.albedo)}")

    k = _table(doc, "sky", src)
    ext = k.get("extinction", Sky().extinction)
    if not isinstance(ext, bool):
        raise SceneFileError(f"{src}: sky.extinction must be true or false, got {ext!r}")
    scattering = k.get("scattering", Sky().scattering)
    if not isinstance(scattering, bool):
        raise SceneFileError(f"{src}: sky.scattering must be true or false, got {scattering!r}")
    sky = Sky(ext, *(_checked(src, "sky", key, k) for key in ("ozone_du", "aerosol_optical_depth", "angstrom",
                                                              "aerosol_scale_height_km")), scattering)

    e = _table(doc, "earth", src)
    # The schema states this range as a rule (0, or 1000 to 100000 km):
    # aurora checks it; here a number >= 0 is enough.
    earth = Earth(_number(f"{src}: earth.radius_km", e.get("radius_km", Earth().radius_km), 0.0, math.inf))

    # [colour] shapes the bake; only its observer and white balance matter
    # here (the rest of the table is aurora's to check).
    colour = doc.get("colour", {})
    if not isinstance(colour, dict):
        raise SceneFileError(f"{src}: [colour] must be a table")
    observer = colour.get("observer", _default("colour", "observer"))
    observers = SCHEMA["colour"]["observer"]["values"]
    if observer not in observers:
        raise SceneFileError(f"{src}: colour.observer = {observer!r} must be one of {', '.join(observers)}")

    white = _checked(src, "colour", "white_balance_k", colour)
    return SceneSpec(cam, ren, vol, bg, ter, sky, earth, path, observer, white)


def load_scene(path: str | Path) -> SceneSpec:
    """Read and validate the render tables of a scene TOML file."""
    p = Path(path)
    try:
        with open(p, "rb") as f:
            doc = tomllib.load(f)
    except OSError as e:
        raise SceneFileError(f"{p}: cannot read: {e}") from e
    except tomllib.TOMLDecodeError as e:
        raise SceneFileError(f"{p}: not valid TOML: {e}") from e
    return scene_from_dict(doc, str(p), p.resolve())


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _normalize(a):
    n = math.sqrt(sum(x * x for x in a))
    return [x / n for x in a]


def camera_basis(cam: Camera):
    """(right, up', forward) unit vectors, `aurora render`'s convention:
    forward = normalize(look_at - position), right = normalize(forward x up),
    up' = right x forward."""
    forward = _normalize([b - a for a, b in zip(cam.position, cam.look_at)])
    right = _normalize(_cross(forward, cam.up))
    up = _cross(right, forward)
    return tuple(right), tuple(up), tuple(forward)


def pixel_ray(cam: Camera, width: int, height: int, px: float, py: float):
    """Origin and unit direction of the camera ray through raster point
    (px, py), measured in pixels from the top-left corner (pixel centres at
    half-integers, row 0 at the top). Used by tests to predict images.
    None outside a fisheye's image circle (src/geometry/camera.rs)."""
    right, up, forward = camera_basis(cam)
    if cam.projection in ("fisheye", "equirectangular"):
        u, v = 2.0 * px / width - 1.0, 1.0 - 2.0 * py / height
        if cam.projection == "fisheye":
            r = math.hypot(u, v)
            if r > 1.0:
                return None
            th = r * math.radians(cam.fov_deg) / 2.0
            a, b = (math.sin(th) / r if r > 0 else 0.0), math.cos(th)
            d = [b * f + a * (u * x + v * y) for f, x, y in zip(forward, right, up)]
        else:
            lam, beta = math.pi * u, math.pi / 2.0 * v
            d = [math.cos(beta) * (math.cos(lam) * f + math.sin(lam) * x) + math.sin(beta) * y
                 for f, x, y in zip(forward, right, up)]
        return tuple(cam.position), tuple(_normalize(d))
    # Screen coordinates in [-1, 1] vertically, [-aspect, aspect] horizontally.
    sx = (2.0 * px - width) / height
    sy = (height - 2.0 * py) / height
    if cam.projection == "perspective":
        t = math.tan(math.radians(cam.fov_deg) / 2.0)
        d = _normalize([f + t * (sx * r + sy * u) for f, r, u in zip(forward, right, up)])
        return tuple(cam.position), tuple(d)
    h = cam.ortho_height / 2.0
    o = tuple(p + h * (sx * r + sy * u) for p, r, u in zip(cam.position, right, up))
    return o, forward
