//! The classic auroral forms as presets, each a scene whose numbers come
//! from what the form is observed to be, with a camera set for its picture.
//!
//! What sets each form apart is the electrons' spectrum (how deep they
//! reach, and so which lines dominate), the footprint's shape (how thin,
//! how folded, how broken into rays) and where it is seen from:
//!
//! | preset | E0 (keV) | energy flux (mW/m^2) | IBC | footprint | seen from |
//! |---|---|---|---|---|---|
//! | `quiet_arc` | 3 | 9 | II | one 12 km band, 1000 km long, hardly folded | the ground, 300 km south |
//! | `rayed_band` | 5 | 40 | III | folded band, start heights broken into rays | the ground, 150 km south |
//! | `corona` | 4-5 | 50-60 | III | a folded hook and a crossing curtain, rayed, overhead | the ground beneath, looking up the field |
//! | `pulsating_patches` | 10 | 1 | I | a broad diffuse band, 40 km patches blinking | the ground beneath, looking up |
//! | `type_a_red` | 0.15 | 10 | II | a band high up, soft spectrum | the ground, 240 km south |
//! | `type_b_pink` | 25 | 150 | III | a folded band 900 km long, hard spectrum | the ground, 210 km south |
//! | `surge` | 6 | 65 | III | an arc curling into a spiral at its western end | 700 km up, to the south |
//!
//! The IBC column is the class each preset's brightest 557.7 nm column
//! along B reaches (`crate::pipeline::columns`; I-IV: 1, 10, 100, 1000 kR,
//! within 1.5x: `tests/physics/ibc.rs`); the arcs' bodies are the
//! default `footprint.sheet_thickness_km`, 8 km at half maximum.
//!
//! Energies and fluxes: a few eV to 1 keV lights the red above 200 km, about
//! 1 keV the yellow-green, above 10 keV electrons reach below 100 km
//! (Physics Today 61(7):68, 2008); 1 mW/m^2 of 3 keV electrons gives about
//! 1 kR of 557.7 nm (weak aurora), bright displays tens of kR. The fluxes
//! are those of the displays people photograph (IBC I-III), and each
//! preset's exposure is about what a camera's highlight meter gives it
//! (`render.exposure = "auto"`, `crate::render::develop`): its brightest
//! curtain just under the view transform's shoulder, the sky dark (the
//! quiet arc, IBC II low over the horizon, two stops under the meter's
//! -3.8 EV, as photographers keep a faint arc's sky dark: at the meter's
//! EV its sky near the horizon, three to four times the zenith's airglow
//! through the slant, reads as a grey veil). Arcs are 5-20 km wide (Knudsen et al. 2001), with
//! filaments of 0.05-0.2 km inside them (Borovsky 1993, J. Geophys. Res.
//! 98(A4), 6101: the compilation of measured arc thicknesses), and can be
//! over 1000 km long. The field's dip is the default 78 degrees (northern
//! Scandinavia), so the magnetic zenith lies 12 degrees south of the zenith.
//!
//! Every preset bakes in under a minute at its own size on two cores
//! (beam counts of 10,000-20,000, footprints of at most 128 cells across
//! per curtain, voxels of 0.4-1 km); the numbers each form takes are in its
//! function's documentation.

use super::classic::{arc_about, default_scene, DEFAULT_ARC_CENTRE_KM};
use crate::scene::{background::*, camera::*, curtain::*, footprint::*, grid::*, root::Scene, terrain::*};
use crate::util::fmath;

/// A perspective camera at `position` looking at `look_at`, z up.
fn camera(position: [f64; 3], look_at: [f64; 3], fov_deg: f64) -> Camera {
    Camera { position, look_at, up: [0.0, 0.0, 1.0], projection: Projection::Perspective, fov_deg, ortho_height: 10.0 }
}

/// The scene every form starts from: the default's keys but its
/// footprint (each form sets its own from the table's defaults), a star
/// field, a flat dark ground lit by the aurora, and the given curtains.
fn base(seed: u64, curtains: Vec<Curtain>) -> Scene {
    Scene {
        seed,
        curtains,
        footprint: FootprintParams::default(),
        background: Background { stars: true, ..Background::default() },
        terrain: Terrain { kind: TerrainKind::Plane, ..Terrain::default() },
        ..default_scene()
    }
}

pub const QUIET_ARC: &str = "a quiet homogeneous arc: one thin green band 1000 km long, low over the northern horizon";

/// A quiet homogeneous arc. Quiet arcs are the aurora of the evening before
/// a substorm: long (here a 1000 km path with a 1600 km radius of
/// curvature, east-west), 12 km wide at half maximum (Knudsen et al.
/// 2001: 5-20 km), structureless and unrayed (folds, rays and the start-height noise all
/// but off: `sheet_rollup_km` 6, `top_noise_km` 1) and IBC II (9 mW/m^2
/// of E0 = 3 keV electrons: its brightest 557.7 nm column along B about
/// 13 kR, about 80 kW per km of arc; the lower border near 105 km). Its motion is slow: folds at 0.5 km/s, a 2 km
/// drift. Seen from 300 km south, its lower border 20 degrees up.
pub fn quiet_arc() -> Scene {
    let arc = Curtain {
        // Along a circle of 1600 km radius about a point to the north (a
        // circle of magnetic latitude): the arc's middle is nearest the
        // camera and its ends bow down toward the horizon.
        path: Some(vec![[-500.0, 80.0], [-250.0, 20.0], [0.0, 0.0], [250.0, 20.0], [500.0, 80.0]]),
        width: 24.0,
        energy_flux: 9.0,
        char_energy_kev: 3.0,
        soft_fraction: 0.02,
        bend_km: 2.0,
        ..Curtain::default()
    };
    let mut s = base(1, vec![arc]);
    s.footprint.resolution = [512, 64];
    // 12 km wide at half maximum: a broad quiet arc.
    s.footprint.sheet_thickness_km = 12.0;
    // A sheet barely rolled up, rays hardly brighter than the rest.
    s.footprint.sheet_rollup_km = 6.0;
    s.footprint.sheet_amplitude = 0.02;
    // Unrayed: rays 0.3 km apart, 0.6 km wide and within 1.2x of each
    // other merge into a smooth band (the footprint varies along the arc
    // by a coefficient of variation of about 0.1, against 0.4 with the
    // default's rays).
    s.footprint.ray_spacing_km = 0.3;
    s.footprint.ray_width_km = 0.6;
    s.footprint.ray_contrast = 1.2;
    s.footprint.band_fraction = 0.12;
    s.footprint.velocity_amplitude = 0.3;
    s.footprint.velocity_waves = 2.0;
    s.footprint.density_waves = 0.0;
    s.beams.count = 16_000;
    s.beams.top_noise_km = 1.0;
    s.beams.top_noise_freq = 0.05;
    s.photons.radius_km = 0.8;
    s.grid.voxel_size = VoxelSize::Km(0.5);
    s.camera = camera([0.0, -300.0, 0.5], [0.0, 80.0, 75.0], 45.0);
    s.render.exposure = -5.8;
    s.animation.fold_speed_kms = 0.5;
    s.animation.drift_km = 2.0;
    s.animation.ray_speed_kms = 1.0;
    s
}

pub const RAYED_BAND: &str = "a rayed band: a folded active band broken into field-aligned rays, seen from the south";

/// A rayed band: an active arc broken into rays, each a bundle of field
/// lines lit from its own start height. The start heights vary by 30 km
/// over about 1.4 km along the band (`top_noise_km` 30 at 0.7 / km), the
/// beams follow the field (no deflection, as the default), so each ray stays a
/// thin streak along the field; the band folds (`velocity_amplitude` 3,
/// 8 waves) and is bright (40 mW/m^2 of E0 = 5 keV: IBC III, about 100
/// kR along B where a fold stacks the sheet). Rays run
/// along the band at 15 km/s (observed up to about 25 km/s).
pub fn rayed_band() -> Scene {
    let band = Curtain {
        path: Some(vec![[-180.0, 20.0], [-60.0, 50.0], [60.0, 35.0], [180.0, 60.0]]),
        width: 40.0,
        energy_flux: 40.0,
        char_energy_kev: 5.0,
        bend_km: 6.0,
        ..Curtain::default()
    };
    let mut s = base(2, vec![band]);
    s.footprint.velocity_amplitude = 3.0;
    s.footprint.velocity_waves = 8.0;
    s.footprint.density_waves = 14.0;
    s.beams.count = 12_000;
    s.beams.top_noise_km = 30.0;
    s.beams.top_noise_freq = 0.7;
    s.photons.radius_km = 0.4;
    s.grid.voxel_size = VoxelSize::Km(0.4);
    s.camera = camera([0.0, -150.0, 0.5], [0.0, 40.0, 100.0], 60.0);
    s.render.exposure = -2.3;
    s.animation.ray_speed_kms = 15.0;
    s
}

pub const CORONA: &str = "a corona: rayed sheets filling the sky, seen from beneath, the rays converging on the magnetic zenith";

/// A corona: rays are field lines, and parallel lines seen in perspective
/// meet at their vanishing point, the magnetic zenith (the direction -B,
/// here 12 degrees south of the zenith; `tests/physics/corona.rs` finds it in the
/// image). Two rayed curtains over the observer, as at the height of a
/// substorm's breakup: one folded into a hook 300 km across that curls
/// round the magnetic zenith from the south-west through the east to the
/// north, the other crossing the sky from north-west to south-east just
/// east of the observer (60 and 50 mW/m^2 of E0 5 and 4 keV, with filaments
/// accelerated through 4 and 3 kV more: IBC III). Seen from beneath up
/// the field line through a 180-degree fisheye (north at the top of the
/// image) their rays fan out from one point, their lower borders (110 km)
/// coming down to 20-40 degrees elevation on most sides.
pub fn corona() -> Scene {
    let curtain = |path: Vec<[f64; 2]>, flux: f64, e0: f64, filament: (f64, f64), seed: u64| Curtain {
        path: Some(path),
        width: 30.0,
        energy_flux: flux,
        char_energy_kev: e0,
        filament_energy_flux: filament.0,
        filament_potential_kv: filament.1,
        bend_km: 5.0,
        seed,
        ..Curtain::default()
    };
    let hook = vec![
        [-330.0, -300.0],
        [-220.0, -160.0],
        [-60.0, -80.0],
        [110.0, -20.0],
        [150.0, 90.0],
        [60.0, 170.0],
        [-80.0, 150.0],
        [-140.0, 60.0],
    ];
    let crossing = vec![[-420.0, 220.0], [-180.0, 110.0], [0.0, 20.0], [150.0, -100.0], [330.0, -300.0]];
    let mut s = base(3, vec![curtain(hook, 60.0, 5.0, (80.0, 4.0), 3), curtain(crossing, 50.0, 4.0, (60.0, 3.0), 5)]);
    s.footprint.resolution = [512, 96];
    s.footprint.velocity_amplitude = 3.0;
    s.footprint.velocity_waves = 8.0;
    s.footprint.density_waves = 14.0;
    s.beams.count = 20_000;
    s.beams.top_noise_km = 40.0;
    s.beams.top_noise_freq = 0.6;
    // Spread over 650 x 500 km of sky: 0.8 km voxels, about a pixel of the
    // 512-pixel fisheye at 30 degrees elevation (1.3 km there, 0.6 km overhead).
    s.photons.radius_km = 0.8;
    s.grid.voxel_size = VoxelSize::Km(0.8);
    // Up the field line: -B = (0, -cos I, sin I) at declination 0.
    let dip = s.beams.b_inclination_deg.to_radians();
    s.camera = Camera {
        position: [0.0, 0.0, 0.3],
        look_at: [0.0, -100.0 * fmath::cos(dip), 0.3 + 100.0 * fmath::sin(dip)],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Fisheye,
        fov_deg: 180.0,
        ortho_height: 10.0,
    };
    s.render.width = 512;
    s.render.height = 512;
    s.render.exposure = -6.0;
    s.terrain.kind = TerrainKind::None;
    s.animation.ray_speed_kms = 15.0;
    s
}

pub const PULSATING_PATCHES: &str = "pulsating patches: diffuse hard aurora overhead, 40 km patches blinking with 4-12 s periods";

/// Pulsating aurora: diffuse patches tens of km across that switch on and
/// off with periods of 2-20 s, most often 6-10 s (Royrvik & Davis 1977,
/// J. Geophys. Res. 82(29), 4720; Lessard 2012, "A review of pulsating
/// aurora", AGU Monograph 197), in the morning sector after a substorm.
/// Their electrons are hard (10-100 keV: Johnstone 1978) and the energy
/// flux small (a few mW/m^2), so the patches are faint and low (lower
/// border near 95 km). Here: a broad diffuse band (200 km wide, 60 % of it
/// lit, barely folded), 1 mW/m^2 of E0 = 10 keV (IBC I: about 1 kR of
/// 557.7 nm along B), `animation.pulsation` 0.9
/// on 40 km patches with periods drawn in 4-12 s; seen from beneath,
/// looking up through a 100-degree view.
pub fn pulsating_patches() -> Scene {
    let diffuse = Curtain {
        center: [0.0, 60.0],
        length: 300.0,
        width: 200.0,
        energy_flux: 1.0,
        char_energy_kev: 10.0,
        soft_fraction: 0.05,
        bend_km: 10.0,
        ..Curtain::default()
    };
    let mut s = base(4, vec![diffuse]);
    s.footprint.resolution = [256, 128];
    // Diffuse: the report's fluid band, not a thin sheet.
    s.footprint.model = FootprintModel::Fluid2014;
    s.footprint.band_fraction = 0.6;
    s.footprint.velocity_amplitude = 0.5;
    s.footprint.velocity_waves = 3.0;
    s.footprint.density_waves = 4.0;
    s.beams.count = 12_000;
    s.beams.top_noise_km = 0.0;
    s.photons.radius_km = 1.5;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s.camera = Camera { up: [0.0, 1.0, 0.0], ..camera([0.0, 20.0, 0.5], [0.0, 30.0, 100.0], 100.0) };
    s.render.exposure = -2.0;
    s.animation.pulsation = 0.9;
    s.animation.pulsation_patch_km = 40.0;
    s.animation.pulsation_period_s = [4.0, 12.0];
    s.animation.fold_speed_kms = 0.3;
    s.animation.drift_km = 2.0;
    s.animation.ray_speed_kms = 0.0;
    s
}

pub const TYPE_A_RED: &str = "a red type-A aurora: a soft spectrum (E0 0.15 keV) lighting OI 630 nm at 200-400 km";

/// A type-A aurora (the IAGA classification's red upper border): soft
/// electrons, 0.1-0.5 keV, stop above 200 km, where O(1D) lives long
/// enough (110-130 s) to radiate 630.0 / 636.4 nm before a collision
/// quenches it; the display is red, high (250-450 km) and tall. Here:
/// 10 mW/m^2 (IBC II in 557.7 nm, with more 630.0 nm above it), half of
/// it at E0 = 0.05 keV and half at 0.15 keV, beams
/// starting at 500 km (above where the softest deposit), seen from 240 km
/// south.
pub fn type_a_red() -> Scene {
    let band = Curtain {
        path: Some(vec![[-200.0, 60.0], [0.0, 90.0], [200.0, 60.0]]),
        width: 50.0,
        energy_flux: 10.0,
        char_energy_kev: 0.15,
        soft_fraction: 0.5,
        soft_energy_kev: 0.05,
        bend_km: 8.0,
        ..Curtain::default()
    };
    let mut s = base(5, vec![band]);
    // A broad soft band: the report's fluid, not a thin sheet.
    s.footprint.model = FootprintModel::Fluid2014;
    s.footprint.band_fraction = 0.15;
    s.footprint.velocity_amplitude = 1.5;
    s.beams.count = 10_000;
    s.beams.top_km = 500.0;
    s.beams.top_noise_km = 15.0;
    s.beams.top_noise_freq = 0.2;
    s.photons.radius_km = 1.0;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s.camera = camera([0.0, -150.0, 0.5], [0.0, 90.0, 180.0], 70.0);
    s.render.exposure = -3.0;
    s
}

pub const TYPE_B_PINK: &str = "a hard type-B aurora: E0 25 keV electrons reach 85-95 km, a pink N2 lower border under the green";

/// A type-B aurora: hard electrons (tens of keV) reach 85-95 km, where
/// O(1S) is quenched by O2 before it emits 557.7 nm and what is left is
/// the N2 first positive bands (red) and the N2+ first negative (violet):
/// a pink or magenta lower border under the green, in bright active
/// displays. Here: 150 mW/m^2 of E0 = 25 keV (a mean energy of 50 keV;
/// IBC III), a
/// folded band 900 km long seen nearly edge-on from 210 km south, so the
/// lower border shows as a continuous line under the green across the frame.
pub fn type_b_pink() -> Scene {
    let band = Curtain {
        // 900 km along a circle of magnetic latitude (as the default's
        // arcs), 210 km north of the camera: it runs off both sides of the
        // frame, a continuous ribbon bowing toward the horizon.
        path: Some(arc_about([0.0, -160.0], DEFAULT_ARC_CENTRE_KM, 210.0, 900.0, 0.0)),
        width: 40.0,
        energy_flux: 150.0,
        char_energy_kev: 25.0,
        soft_fraction: 0.03,
        bend_km: 6.0,
        ..Curtain::default()
    };
    let mut s = base(6, vec![band]);
    s.footprint.velocity_amplitude = 2.0;
    s.footprint.density_waves = 10.0;
    // The default's sheet: one unbroken band, curled and folded.
    s.footprint.sheet_rollup_km = 8.0;
    s.footprint.sheet_thickness_km = 5.0;
    s.footprint.ray_contrast = 4.0;
    s.beams.count = 30_000;
    s.beams.top_noise_km = 12.0;
    s.beams.top_noise_freq = 0.5;
    s.photons.radius_km = 0.5;
    s.grid.voxel_size = VoxelSize::Km(0.5);
    s.camera = camera([0.0, -160.0, 0.5], [0.0, 60.0, 95.0], 60.0);
    s.render.exposure = -5.0;
    s
}

pub const SURGE: &str = "a westward travelling surge: a bright arc curling into a spiral at its western end, seen from above";

/// A westward travelling surge: at a substorm's onset the arc brightens and
/// its western end rolls up into a bright fold, the surge head, which
/// travels westward at 1-2 km/s (Akasofu 1964, Planet. Space Sci. 12, 273;
/// the surge is the western edge of the substorm's bulge). Here: one arc
/// from 400 km east to a hook 190 km west that curls poleward and back
/// east (radius of curvature about 40 km, above the width's half, 15 km),
/// 65 mW/m^2 of E0 = 6 keV (the inverted-V electrons of a substorm arc;
/// IBC III),
/// folds running westward along it at 2 km/s; seen as an imager in orbit
/// sees it, from 700 km up and 700 km south.
pub fn surge() -> Scene {
    let arc = Curtain {
        path: Some(vec![
            [400.0, -20.0],
            [200.0, -5.0],
            [0.0, 10.0],
            [-120.0, 30.0],
            [-190.0, 80.0],
            [-170.0, 150.0],
            [-100.0, 170.0],
            [-50.0, 130.0],
        ]),
        width: 30.0,
        energy_flux: 65.0,
        char_energy_kev: 6.0,
        bend_km: 4.0,
        ..Curtain::default()
    };
    let mut s = base(7, vec![arc]);
    s.footprint.velocity_amplitude = 2.0;
    s.footprint.velocity_waves = 10.0;
    s.footprint.density_waves = 12.0;
    s.beams.count = 14_000;
    s.beams.top_noise_km = 10.0;
    s.photons.radius_km = 0.8;
    s.grid.voxel_size = VoxelSize::Km(0.8);
    s.camera = camera([0.0, -700.0, 750.0], [30.0, 80.0, 130.0], 40.0);
    s.render.exposure = -1.0;
    s.background.stars = false;
    s.terrain.albedo = [0.15, 0.15, 0.15];
    s.animation.fold_speed_kms = 2.0;
    s.animation.bend_speed_kms = 2.0;
    s
}
