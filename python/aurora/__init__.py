"""aurora from Python: scenes, altitude profiles, bakes, renders and
keograms as NumPy arrays, and synthetic all-sky frames that asilib reads.

The work is the library's (the same code as the `aurora` command line);
this package only shapes its answers into arrays. Long calls take
``progress=callable(stage, done, total)``; Ctrl-C (or a notebook's
interrupt) stops them: a bake stops at its next chunk of beams, writes
nothing, keeps the folder's previous bake and raises KeyboardInterrupt.

    import aurora
    s = aurora.Scene("default")            # a preset or a TOML file
    s.set("curtain[0].energy_flux", 20)     # as --set, checked as the CLI checks it
    p = aurora.profile(s)                   # p.columns["oi_5577"], p.units["oi_5577"]
    aurora.bake(s, "out")                   # out/aurora.vdb, aurora.usda, bake.json
    img = aurora.render(s, "out/aurora.vdb", grid="line_5577")   # rayleigh, img.units
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional, Sequence

import numpy as np

from ._aurora import InputError, Scene, frame_range, frame_vdb, presets
from . import _aurora

__all__ = [
    "InputError", "Scene", "Array", "Profile", "Keogram", "profile", "bake", "render", "keogram", "meridian",
    "skymap", "frame_range", "frame_vdb", "presets", "write_frame", "read_frame", "asilib_imager",
]

Progress = Optional[Callable[[str, int, int], object]]


class Array(np.ndarray):
    """A NumPy array with its unit in ``.units`` (and, for a line's image,
    whether the air's extinction is in it, ``.air``)."""

    def __new__(cls, values, units: str = "", air: str = ""):
        a = np.asarray(values).view(cls)
        a.units, a.air = units, air
        return a

    def __array_finalize__(self, obj):
        self.units = getattr(obj, "units", "")
        self.air = getattr(obj, "air", "")


@dataclass
class Profile:
    """`aurora profile`'s CSV as arrays: ``columns[name]`` one value per
    curtain and 0.5 km bin, in the CSV's order (``curtain``,
    ``altitude_km``, ``ionization``, ``oi_5577``, ..., ``*_ver_cm3_s``),
    ``units[name]``; ``column_brightness[name]`` one value per curtain
    (the ``.columns.csv``: ``*_r`` rayleigh, ``*_r_per_erg``);
    ``area_km2`` the footprints' areas; ``power_w`` where the electron
    power went."""

    columns: dict
    units: dict
    column_brightness: dict
    area_km2: np.ndarray
    power_w: dict

    def curtain(self, i: int) -> dict:
        """The columns of curtain ``i``'s bins alone."""
        keep = self.columns["curtain"] == i
        return {k: v[keep] for k, v in self.columns.items()}


@dataclass
class Keogram:
    """`aurora keogram` as arrays: ``values[row, frame]`` (``.units``: R
    for a line's grid), rows every 0.5 degrees of scan angle from the
    magnetic north horizon through the zenith to the south one."""

    values: Array
    scan_deg: np.ndarray
    elevation_deg: np.ndarray
    azimuth_deg: np.ndarray
    frames: np.ndarray
    times_s: np.ndarray
    grid: str


def profile(scene: Scene, progress: Progress = None) -> Profile:
    """The altitude profiles of the scene's beam deposits (`aurora profile`)."""
    d = _aurora.profile(scene, progress)
    header, n = d["header"], d["row_count"]
    rows = np.frombuffer(d["rows"], "<f8").reshape(n, len(header))
    columns = {h: rows[:, i].copy() for i, h in enumerate(header)}
    columns["curtain"] = columns["curtain"].astype(int)
    ch = d["columns_header"]
    crow = np.frombuffer(d["columns_rows"], "<f8").reshape(-1, len(ch))
    bright = {h: crow[:, i].copy() for i, h in enumerate(ch)}
    bright["curtain"] = bright["curtain"].astype(int)
    return Profile(columns, dict(zip(header, d["units"])), bright, np.array(d["area_km2"]), d["power_w"])


def bake(scene: Scene, out, frames=None, progress: Progress = None) -> str:
    """Bakes the scene into the folder ``out`` (aurora.vdb, aurora.usda,
    bake.json, replaced as a unit when the bake ends); with ``frames`` (a
    list of frame numbers or a range such as ``"1-10"``) a sequence folder,
    as ``aurora bake --frames``: frames already complete are kept. Returns
    its summary."""
    if isinstance(frames, str):
        frames = frame_range(frames)
    frames = None if frames is None else [int(f) for f in frames]
    summary, warnings = _aurora.bake(scene, Path(out), frames, progress)
    _warn(warnings)
    return summary


def render(scene: Scene, vdb=None, grid: Optional[str] = None, frame: Optional[int] = None, progress: Progress = None) -> Array:
    """One image as `aurora render` makes it: linear Rec.709 RGBA
    (height, width, 4) float32, or with ``grid`` (``line_5577``, ...) the
    narrow-band image (height, width) in rayleigh (``.units``, ``.air``).
    ``vdb`` a baked file, or with ``frame`` a sequence folder; none bakes
    the scene in memory."""
    data, w, h, meta, warnings = _aurora.render(scene, None if vdb is None else Path(vdb), grid, frame, progress)
    _warn(warnings)
    rgba = np.frombuffer(data, "<f4").reshape(h, w, 4)
    if meta is None:
        return Array(rgba.copy(), "linear Rec.709 radiance (RGB) and coverage (A)")
    return Array(rgba[..., 0].copy(), meta[0], meta[1])


def keogram(scene: Scene, seq, frames, grid: str = "line_5577", progress: Progress = None) -> Keogram:
    """The keogram of a baked sequence folder ``seq`` (`aurora keogram`);
    ``frames`` a list of frame numbers or a range such as ``"1-10"``."""
    if isinstance(frames, str):
        frames = frame_range(frames)
    d = _aurora.keogram(scene, Path(seq), [int(f) for f in frames], grid, progress)
    rows = len(d["scan_deg"])
    values = np.frombuffer(d["values"], "<f4").reshape(rows, len(d["frames"])).copy()
    return Keogram(Array(values, d["units"], d["air"]), np.array(d["scan_deg"]), np.array(d["elevation_deg"]),
                   np.array(d["azimuth_deg"]), np.array(d["frames"]), np.array(d["times_s"]), d["grid"])


def meridian(scene: Scene) -> dict:
    """The keogram's rows for the scene's camera: ``scan_deg``,
    ``elevation_deg``, ``azimuth_deg`` and ``dir`` (unit vectors, scene frame)."""
    r = _aurora.meridian(scene)
    return {"scan_deg": np.array([x[0] for x in r]), "elevation_deg": np.array([x[1] for x in r]),
            "azimuth_deg": np.array([x[2] for x in r]), "dir": np.array([x[3] for x in r])}


def skymap(scene: Scene, altitude_km: float = 110.0, origin: Optional[Sequence[float]] = None) -> dict:
    """The skymap of the scene's (fisheye) camera, as asilib's imagers take
    it: ``az``, ``el`` (degrees) of each pixel centre and ``lat``, ``lon``
    (degrees) where its ray crosses ``altitude_km`` on the round Earth,
    (height, width) arrays, NaN outside the image circle (and below the
    horizon for lat/lon); ``alt`` the altitude. The scene's origin is its
    ``[site]``, or ``origin=(lat, lon)``."""
    d = _aurora.skymap(scene, float(altitude_km), None if origin is None else (float(origin[0]), float(origin[1])))
    shape = (d["height"], d["width"])
    out = {k: np.frombuffer(d[k], "<f8").reshape(shape).copy() for k in ("az", "el", "lat", "lon")}
    out["alt"] = d["alt"]
    out["origin"] = d["origin"]
    return out


def write_frame(path, image, time: _dt.datetime, skymap: dict) -> Path:
    """Writes one all-sky frame with its skymap as ``path`` (.npz):
    ``image`` (height, width), ``time`` (UTC, ISO 8601) and the skymap's
    ``az``, ``el``, ``lat``, ``lon`` and ``alt``."""
    path = Path(path)
    np.savez(path, image=np.asarray(image), time=np.array(time.isoformat()),
             origin=np.asarray(skymap["origin"], float), **{k: np.asarray(skymap[k]) for k in ("az", "el", "lat", "lon", "alt")})
    return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")


def read_frame(path) -> tuple:
    """A frame :func:`write_frame` wrote: (time, image, skymap)."""
    with np.load(path) as f:
        sky = {k: f[k] for k in ("az", "el", "lat", "lon")}
        sky["alt"] = float(f["alt"])
        sky["origin"] = tuple(float(x) for x in f["origin"])
        return _dt.datetime.fromisoformat(str(f["time"])), f["image"], sky


def asilib_imager(paths: Sequence, location: str = "AURO", site_alt_km: float = 0.0, cadence_s: Optional[float] = None):
    """An ``asilib.Imager`` over frames :func:`write_frame` wrote (one
    image a file, in time order): asilib's imager plug-in dictionaries
    (``file_info`` with a loader, ``meta``, ``skymap``), as its
    ``fake_asi`` example builds them. The imager's latitude and longitude
    in ``meta`` are the skymap's origin (the scene's)."""
    import asilib

    paths = [Path(p) for p in paths]
    times = [read_frame(p)[0] for p in paths]
    _, first, sky = read_frame(paths[0])
    origin = sky["origin"]
    if cadence_s is None:
        cadence_s = (times[1] - times[0]).total_seconds() if len(times) > 1 else 1.0

    def loader(path):
        t, img, _ = read_frame(path)
        return np.array([t]), img[np.newaxis, ...]

    file_info = {"path": paths, "start_time": times, "end_time": [t + _dt.timedelta(seconds=cadence_s / 2) for t in times],
                 "loader": loader, "time_range": [times[0], times[-1] + _dt.timedelta(seconds=cadence_s / 2)]}
    meta = {"array": "AURORA", "location": location, "lat": origin[0], "lon": origin[1], "alt": site_alt_km,
            "cadence": cadence_s, "resolution": first.shape}
    return asilib.Imager(file_info, meta, sky, plot_settings={"color_norm": "lin"})


def _warn(warnings):
    import warnings as w

    for m in warnings:
        w.warn(m, stacklevel=3)
