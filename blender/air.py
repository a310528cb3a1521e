"""The air between the aurora and the camera (`[sky]`), as `aurora render`
applies it (src/physics/air_extinction.rs is the model and its derivation; this is a
port of its few formulas, checked against the library's own numbers by
tests/python/test_air.py).

Emission above the extinction layer reaches the observer with, per Rec.709
channel c,

    T_c(e) = sum_i w_ic exp(-tau_i X(e)),
    X(e) = 1 / (sin e + 0.50572 (e + 6.07995 deg)^-1.6364)   (Kasten & Young 1989),

e the elevation of the viewing direction above the horizon (clamped at 0
below it), tau_i line i's zenith depth above the observer: Rayleigh times
the U.S. Standard Atmosphere 1976 pressure ratio, the ozone column's share
above the observer (a triangle from 10 to 40 km peaking at 25 km: all of it
below 10 km) and the aerosol's `tau_550 (lambda / 550)^-angstrom` times
exp(-altitude / scale height). The per-line sea-level depths and the
channel weights w_ic come from blender/extinction.json, which tests/render/extinction.rs
writes from the library and checks.

In Cycles the volume material multiplies its emission by T_c of the camera
ray's direction (material.py: the Geometry node's Incoming vector), which
is exact for camera rays: every point of a primary ray shares its direction,
so the whole emission integral is scaled as `aurora render` scales it. The
terrain's own light is not dimmed in Cycles (docs/guide.md).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

TABLE = json.loads((Path(__file__).resolve().parent / "extinction.json").read_text())

#: U.S. Standard Atmosphere 1976: base geopotential height (km), base
#: temperature (K), lapse rate (K/km); g0 M / R* in K/km; r0 in km.
_LAYERS = [(0.0, 288.15, -6.5), (11.0, 216.65, 0.0), (20.0, 216.65, 1.0), (32.0, 228.65, 2.8),
           (47.0, 270.65, 0.0), (51.0, 270.65, -2.8), (71.0, 214.65, -2.0)]
_TOP = 84.852
_GMR = 34.163195
_R0 = 6356.766
_O3 = (10.0, 25.0, 40.0)


def pressure_ratio(z_km: float) -> float:
    """p / p0 of the standard atmosphere at geometric altitude z (km)."""
    z = max(z_km, 0.0)
    h = _R0 * z / (_R0 + z)
    p = 1.0
    for i, (hb, tb, lapse) in enumerate(_LAYERS):
        top = _LAYERS[i + 1][0] if i + 1 < len(_LAYERS) else _TOP
        dh = min(h, top) - hb
        t = tb + lapse * dh
        p *= math.exp(-_GMR * dh / tb) if lapse == 0.0 else (tb / t) ** (_GMR / lapse)
        if h <= top:
            return p
    return p * math.exp(-_GMR * (h - _TOP) / t)


def ozone_fraction_above(z_km: float) -> float:
    a, m, b = _O3
    if z_km <= a:
        return 1.0
    if z_km <= m:
        return 1.0 - (z_km - a) ** 2 / ((b - a) * (m - a))
    if z_km < b:
        return (b - z_km) ** 2 / ((b - a) * (b - m))
    return 0.0


def air_mass(e_deg: float) -> float:
    """Kasten & Young (1989); below the horizon, the horizon's."""
    e = min(max(e_deg, 0.0), 90.0)
    return 1.0 / (math.sin(math.radians(e)) + 0.50572 * (e + 6.07995) ** -1.6364)


def line_depths(sky, observer_km: float) -> list[float]:
    """Zenith optical depth above the observer of each line (`Extinction::tau_zenith`)."""
    out = []
    for line in TABLE["lines"]:
        wl = line["aerosol_wavelengths_nm"]
        aerosol = sky.aerosol_optical_depth * sum((w / 550.0) ** -sky.angstrom for w in wl) / len(wl)
        out.append(line["rayleigh"] * pressure_ratio(observer_km)
                   + line["ozone_per_du"] * sky.ozone_du * ozone_fraction_above(observer_km)
                   + aerosol * math.exp(-max(observer_km, 0.0) / sky.aerosol_scale_height_km))
    return out


def weights(observer: str = "camera") -> list[list[float]]:
    """Each channel's weights over the lines (rows: R, G, B) for the scene's
    `[colour] observer` ("camera" or "eye"): the lines' colours, and so
    their shares of each channel, are that observer's."""
    return TABLE["weights"][observer]


def transmittance(sky, observer_km: float, e_deg: float, observer: str = "camera") -> tuple[float, float, float]:
    """T_c towards elevation e (degrees) for emission above the layer."""
    x = air_mass(e_deg)
    t = [math.exp(-tau * x) for tau in line_depths(sky, observer_km)]
    return tuple(sum(w * ti for w, ti in zip(row, t)) for row in weights(observer))
