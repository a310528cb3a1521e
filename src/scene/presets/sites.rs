//! Scenes over a real place at a real hour (`[site]`): the catalogue's
//! stars where they were, the Moon with its phase and its light.
//!
//! Tromso (69.65 N, 18.96 E) on 2026-12-18 at 18:00 UTC, an hour after
//! dark in the polar night (the Sun 29 degrees down): the Moon, two-thirds
//! lit, stands 29 degrees up in the south (azimuth 185), behind a camera
//! that looks north at the default's arcs, and lights the ground; the Big
//! Dipper is low in the north-east, Cassiopeia high in the north-west.
//! Positions from skyfield 1.55 with de421, as `tests/data/sky_positions.csv`'s
//! tool computes them.
//!
//! Tromso at Kp 5 (`tromso_kp5`, `tromso_kp5_dome`): the same night at
//! 22:30 UTC, magnetic midnight at Tromso (its AACGM-v2 magnetic local
//! time 0.03 h at 110 km, aacgmv2 2.7.1; `crate::physics::magnetic_coordinates`). `[oval]
//! kp = 5` lays the arcs across Starkov's oval for AL -386.5 nT, which at
//! midnight spans corrected geomagnetic latitudes 61.9-73.1 degrees
//! (`crate::physics::auroral_oval`): Tromso, at 67.3 degrees, lies in
//! its middle, so the middle arc passes 30 km north of the zenith, the
//! equatorward one 380 km south and the poleward one 430 km north (at
//! 110 km; aacgmv2 2.7.1's inverse trace puts them 384, 32 and 435 km
//! from Tromso).

use super::classic::{default_scene, oval};
use crate::scene::{
    camera::Camera,
    grid::VoxelSize,
    oval::OvalParams,
    root::Scene,
    site::SiteParams,
    terrain::{Terrain, TerrainKind},
};
use crate::util::fmath;

/// The site and hour of both scenes.
pub fn tromso_site() -> SiteParams {
    SiteParams {
        latitude_deg: 69.65,
        longitude_deg: 18.96,
        height_km: 0.0,
        utc: "2026-12-18T18:00:00Z".into(),
        temperature_c: -10.0,
        pressure_hpa: None,
        field: Default::default(),
    }
}

/// What `aurora scene --list` says of [`tromso`].
pub const TROMSO: &str =
    "the default's arcs over Tromso on 2026-12-18 at 18:00 UTC: the real stars, the Moon behind the camera lighting the ground";
/// What `aurora scene --list` says of [`tromso_dome`].
pub const TROMSO_DOME: &str = "the oval's arc over Tromso at the same hour as a dome master: the real constellations and the Moon";

/// The default's three arcs over Tromso (module doc), half a stop darker
/// than the default, as a camera's highlight meter exposes it (-6.2 EV
/// metered: the moonlit snow, albedo 0.85 at 0.02 lux, about 0.006 cd/m^2,
/// brightens the frame's lower part; the arcs still set the exposure).
pub fn tromso() -> Scene {
    let mut s = Scene { site: Some(tromso_site()), ..default_scene() };
    s.render.exposure -= 0.5;
    s
}

/// The oval's arc over Tromso as a dome master (module doc), a stop under
/// `oval`: the arc sets what the highlight meter gives (-6.45 EV metered,
/// `oval` -6.4), and a photographer shortens the exposure a stop more
/// under the moonlit sky (2.0 kR at the zenith and 17 kR low in the south
/// under the Moon, V 20.9 and 18.6 mag/arcsec^2), which the meter's
/// highlights do not see.
pub fn tromso_dome() -> Scene {
    let mut s = Scene { site: Some(tromso_site()), ..oval() };
    s.render.exposure -= 1.0;
    s
}

/// The hour of the Kp 5 scenes: magnetic midnight at Tromso (module doc).
pub const TROMSO_MIDNIGHT_UTC: &str = "2026-12-18T22:30:00Z";

/// What `aurora scene --list` says of [`tromso_kp5`].
pub const TROMSO_KP5: &str =
    "Tromso at magnetic midnight at Kp 5: three 1200 km arcs laid across Starkov's oval by [oval], seen by a photographer looking north";
/// What `aurora scene --list` says of [`tromso_kp5_dome`].
pub const TROMSO_KP5_DOME: &str = "Tromso at magnetic midnight at Kp 5 as a dome master: the oval's three arcs from horizon to horizon";

/// The Kp 5 night: Tromso at [`TROMSO_MIDNIGHT_UTC`] with `[oval] kp = 5`,
/// the arcs of `base` left straight so that the oval places them.
fn kp5(base: Scene, length_km: f64) -> Scene {
    let mut s = Scene {
        site: Some(SiteParams { utc: TROMSO_MIDNIGHT_UTC.into(), ..tromso_site() }),
        oval: Some(OvalParams { kp: 5.0, ..OvalParams::default() }),
        ..base
    };
    for c in &mut s.curtains {
        c.path = None;
        c.length = length_km;
    }
    s
}

/// Tromso at Kp 5, as a photographer sees it (module doc): the default's
/// three arcs (their electrons and filaments), each 1200 km long, placed by
/// `[oval]`; a 100-degree camera 2 m up at the site looking north, 35
/// degrees up, over a snow plain; 1 km voxels (a voxel at the poleward
/// arc, 430 km away, is 0.13 degree, about a pixel of the 1280-pixel
/// frame); 60,000 beams.
pub fn tromso_kp5() -> Scene {
    let mut s = kp5(default_scene(), 1200.0);
    s.beams.count = 60_000;
    s.photons.radius_km = 1.5;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    let up = 35.0_f64.to_radians();
    s.camera = Camera {
        position: [0.0, 0.0, 0.002],
        look_at: [0.0, 100.0 * fmath::cos(up), 0.002 + 100.0 * fmath::sin(up)],
        fov_deg: 100.0,
        ..Camera::default()
    };
    s.render.width = 1280;
    s.render.height = 720;
    // 2.5 stops under the default: the Moon, low in the west, lights the sky.
    s.render.exposure = -5.5;
    // The snow of the plain around the site (the default's mountains stand over the origin).
    s.terrain = Terrain { kind: TerrainKind::Plane, ..Terrain::default() };
    s
}

/// Tromso at Kp 5 as a dome master (module doc): the `tromso_dome`
/// settings (a 180-degree fisheye at the zenith, north up, 1 km voxels),
/// the default's three arcs each 2000 km long, placed by `[oval]`, 60,000
/// beams.
pub fn tromso_kp5_dome() -> Scene {
    let mut base = oval();
    base.curtains = default_scene().curtains;
    base.earth.magnetic_pole = None;
    let mut s = kp5(base, 2000.0);
    // `oval`'s camera: the 180-degree fisheye at the zenith, north up.
    s.beams.count = 60_000;
    s.render.exposure = -4.5;
    s
}
