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

use super::classic::{default_scene, oval};
use crate::scene::{root::Scene, site::SiteParams};

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

/// The default's three arcs over Tromso (module doc), 1.5 stops darker
/// than the default: the moonlit snow (albedo 0.85 at 0.02 lux, about 0.006
/// cd/m^2, 29 in the volume's unit) is brighter than the arcs' sides, and a photographer shortens
/// the exposure under a bright Moon.
pub fn tromso() -> Scene {
    let mut s = Scene { site: Some(tromso_site()), ..default_scene() };
    s.render.exposure -= 1.5;
    s
}

/// The oval's arc over Tromso as a dome master (module doc), 2.5 stops
/// darker than `oval`: the moonlit sky is 2.0 kR at the zenith and 17 kR
/// low in the south under the Moon (V 20.9 and 18.6 mag/arcsec^2), against
/// the dark sky's 0.3 of airglow.
pub fn tromso_dome() -> Scene {
    let mut s = Scene { site: Some(tromso_site()), ..oval() };
    s.render.exposure -= 2.5;
    s
}
