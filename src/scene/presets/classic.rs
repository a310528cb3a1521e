//! The three scenes the rest are built on: the default (three curtains
//! seen from the ground), the 2014 report's own scene, and an arc of the
//! auroral oval for a planetarium dome.

use crate::scene::{
    animation::*, atmosphere::*, background::*, beams::*, camera::*, colour::*, curtain::*, earth::*, footprint::*, grid::*, photons::*,
    render::*, root::Scene, sky::*, terrain::*, volume::*,
};
use crate::util::fmath;

impl Default for Scene {
    fn default() -> Self {
        default_scene()
    }
}

/// Three arcs one behind the other, seen from the ground to the north
/// with a photographer's wide lens (75 x 107 degrees, tilted 25 degrees up
/// so the horizon sits in the lower quarter): 400, 620 and 880 km long at
/// 70, 130 and 220 km from the camera, each along a circle about a point
/// [`DEFAULT_ARC_CENTRE_KM`] north of the camera (a stretch of the auroral
/// oval, whose arcs follow circles of magnetic latitude), so every arc runs
/// off both sides of the frame and its lower border bows down toward the
/// horizon at both ends, as photographs show arcs.
/// An active display, IBC III (`crate::pipeline::columns`: the brightest
/// 557.7 nm column along B is 137 kR): each arc an inverted-V
/// (Evans 1974), a source of 0.8, 0.6 and 0.5 keV electrons accelerated
/// through 5, 3.5 and 2 kV, so that its lower border is sharp (a
/// monoenergetic-like spectrum stops within 2-3 km, a Maxwellian needs
/// 4-9: Fang et al. 2010), in a body 5 km wide at half maximum
/// (`footprint.sheet_thickness_km`; Knudsen et al. 2001: 5-20 km) of 60,
/// 36 and 24 mW/m^2 at its peak, with six filaments 0.15 km wide inside it
/// (Maggs & Davis 1968; Dahlgren et al. 2012: 0.05-0.2 km) of the same
/// electrons accelerated through 4, 3 and 2 kV more, 170, 140 and 90
/// mW/m^2 (peaks: the rays along the sheet vary 8x): 0.25, 0.17 and 0.11
/// MW per km of arc in all (`bake.json`'s electron power over each arc's
/// length; IBC III arcs carry 0.2-0.5). The sheet rolls
/// up 8 km (`footprint.sheet_rollup_km`): curls along one unbroken band;
/// each band bends by 14 km over 0.35 of its length, so folds are seen
/// edge-on here and there as bright slanting streaks; rays 0.9 km wide,
/// 5 km apart on average (irregularly) and within 8x of each other. The beams
/// follow the field (a 5 keV electron's gyroradius is metres); 30,000 of
/// them, so that neighbouring columns overlap at the half-kilometre voxel
/// instead of standing apart as hairs. The aurora's light on the ground is
/// estimated from 8 shadow rays a sample (`render.shadow_samples`), so the
/// lit mountains are smooth. Exposed as a camera's highlight meter exposes
/// a bright display (`render.exposure = "auto"` meters about -6 EV here):
/// -6 stops keeps the arcs' cores out of the view transform's shoulder and
/// leaves the sky dark, as photographers expose.
pub fn default_scene() -> Scene {
    let arc = |distance_km: f64, length_km: f64, shift_km: f64, flux: f64, (t, kv): (f64, f64), filament: (f64, f64), seed: u64| Curtain {
        path: Some(arc_about(DEFAULT_CAMERA_XY, DEFAULT_ARC_CENTRE_KM, distance_km, length_km, shift_km)),
        energy_flux: flux,
        char_energy_kev: t,
        spectrum: SpectrumShape::Accelerated,
        potential_kv: kv,
        filament_energy_flux: filament.0,
        filament_potential_kv: filament.1,
        bend_km: 14.0,
        seed,
        ..Curtain::default()
    };
    Scene {
        seed: 2014,
        curtains: vec![
            arc(70.0, 400.0, -20.0, 60.0, (0.8, 5.0), (170.0, 4.0), 1),
            arc(130.0, 620.0, 25.0, 36.0, (0.6, 3.5), (140.0, 3.0), 2),
            arc(220.0, 880.0, -5.0, 24.0, (0.5, 2.0), (90.0, 2.0), 3),
        ],
        footprint: FootprintParams {
            sheet_rollup_km: 8.0,
            sheet_thickness_km: 5.0,
            filament_count: 6,
            filament_width_km: 0.15,
            bend_wavelength: 0.35,
            ray_spacing_km: 5.0,
            ray_width_km: 0.9,
            ray_contrast: 8.0,
            ..FootprintParams::default()
        },
        beams: BeamParams { count: 30_000, ..BeamParams::default() },
        colour: ColourParams::default(),
        photons: PhotonParams::default(),
        grid: GridParams::default(),
        camera: Camera {
            position: [DEFAULT_CAMERA_XY[0], DEFAULT_CAMERA_XY[1], 1.0],
            // 25 degrees up: 110 km ahead, 51.3 km higher.
            look_at: [DEFAULT_CAMERA_XY[0], DEFAULT_CAMERA_XY[1] + 110.0, 52.3],
            ..Camera::default()
        },
        render: RenderParams { exposure: -6.0, shadow_samples: 8, ..RenderParams::default() },
        volume: VolumeParams::default(),
        background: Background::default(),
        terrain: Terrain { kind: TerrainKind::Heightfield, ..Terrain::default() },
        animation: AnimationParams::default(),
        atmosphere: AtmosphereParams::default(),
        earth: EarthParams::default(),
        site: None,
        oval: None,
        sky: SkyParams::default(),
        airglow: crate::scene::airglow::AirglowParams::default(),
        overrides: Vec::new(),
    }
}

/// Where the default's camera stands on the ground, km.
pub const DEFAULT_CAMERA_XY: [f64; 2] = [0.0, -90.0];
/// The default's arcs follow circles about a point this far north of its
/// camera, km: about the distance from a station under the oval's night
/// side to the magnetic pole's (the `oval` preset's arc is 2200 km from
/// its pole).
pub const DEFAULT_ARC_CENTRE_KM: f64 = 1800.0;

/// A curtain's path, 17 points along the circle about the point
/// `centre_km` north of `camera`, passing `distance_km` north of it, `length_km`
/// long, its middle moved `shift_km` east along the circle; rounded to
/// metres so the scene file stays readable.
pub fn arc_about(camera: [f64; 2], centre_km: f64, distance_km: f64, length_km: f64, shift_km: f64) -> Vec<[f64; 2]> {
    let rho = centre_km - distance_km;
    let (half, mid) = (length_km / 2.0 / rho, shift_km / rho);
    let n = 17;
    (0..n)
        .map(|k| {
            let phi = mid - half + 2.0 * half * k as f64 / (n - 1) as f64;
            let (x, y) = (camera[0] + rho * fmath::sin(phi), camera[1] + centre_km - rho * fmath::cos(phi));
            [(x * 1e3).round() / 1e3, (y * 1e3).round() / 1e3]
        })
        .collect()
}

/// The 2014 report's final scene: 500,000 beams, alpha_D = 25 deg,
/// delta alpha = 12 deg, beam length 70, dt = 0.004 (at most 250
/// deflections), photon radius 0.2, air density 0.9 exp(-0.02 h), three
/// sheets. Report units are taken as km.
pub fn seed2014() -> Scene {
    let mut s = default_scene();
    // The report's footprint: its fluid, three 160 km sheets with
    // straight ends where the default's stood before they spanned the sky.
    // Its fluxes, 6, 4 and 3 erg cm^-2 s^-1, under its dense air at an
    // exposure of +3 stops.
    // Straight sheets where the default stood before its arcs followed the
    // oval, seen from its camera of then.
    // Its electrons: Maxwellians of E0 4, 2.5 and 1.5 keV.
    for (((c, [x, y, rot]), flux), e0) in
        s.curtains.iter_mut().zip([[-20.0, 0.0, 4.0], [25.0, 45.0, -6.0], [-5.0, 95.0, 2.0]]).zip([6.0, 4.0, 3.0]).zip([4.0, 2.5, 1.5])
    {
        c.spectrum = SpectrumShape::Maxwellian;
        c.char_energy_kev = e0;
        c.potential_kv = 0.0;
        c.bend_km = Curtain::default().bend_km;
        c.path = None;
        c.length = 160.0;
        c.center = [x, y];
        c.rotation_deg = rot;
        c.energy_flux = flux;
        c.filament_energy_flux = 0.0;
        c.filament_potential_kv = 0.0;
    }
    s.camera = Camera::default();
    s.footprint = FootprintParams { model: FootprintModel::Fluid2014, ..FootprintParams::default() };
    s.footprint.end_fade_km = 0.0;
    s.beams.count = 500_000;
    s.beams.alpha_d_deg = 25.0;
    s.beams.delta_alpha_deg = 12.0;
    s.beams.length_km = 70.0;
    s.beams.dt = 0.004;
    // With s = L dt xi (mean L dt / 2 = 0.14 km) and at most 250 steps a
    // beam travels 35 km on average: starting at 140 km it reaches the
    // green layer (100-120 km), as the report's curtains do.
    s.beams.top_km = 140.0;
    // The report's beams end after 1/dt steps wherever they are: its look
    // needs the straight-line model and its stopping rules.
    s.beams.deposition = Deposition::Csda;
    s.photons.radius_km = 0.2;
    s.photons.radius_noise = 0.3;
    s.grid.voxel_size = VoxelSize::Km(0.2);
    s.grid.density_a = 0.9;
    s.grid.density_b = 0.02;
    s.grid.density_base_km = 90.0;
    s.colour.mode = ColourMode::Colormap;
    s.render.width = 640;
    s.render.height = 438;
    s.render.spp = 8;
    s.render.shadow_samples = 1;
    s.render.exposure = 3.0;
    s
}

/// Ground distance from the oval's dipole pole to its arc, km: magnetic
/// latitude 90 deg - 2200 / 6371 rad = 70.2 deg, the auroral oval's night
/// side.
pub const OVAL_POLE_DISTANCE_KM: f64 = 2200.0;
/// Length of the oval's arc along its circle of magnetic latitude, km.
pub const OVAL_LENGTH_KM: f64 = 2500.0;

/// An arc of the auroral oval for a planetarium dome: the lower border
/// (the path, at 110 km) runs 2500 km along the small circle of magnetic
/// latitude 70.2 deg about a dipole pole 2200 km north
/// (`earth.magnetic_pole`), its middle overhead; seen by a 180-degree
/// fisheye looking at the zenith, north up, with stars. On the round
/// Earth its ends go down behind the horizon, some 1250 km away.
///
/// Under the arc's middle the camera looks up its field lines (dip 79.8
/// deg at magnetic latitude 70.2 deg, `tan I = 2 tan(lat)`): the gaps
/// between the footprint's rays within some 20 km of the zenith are seen
/// nearly edge-on, as dark lanes converging on the magnetic zenith 10 deg
/// south of it (the corona's perspective, `tests/physics/corona.rs`);
/// farther along, the sight lines cross the gaps and fill them in.
pub fn oval() -> Scene {
    let earth = crate::geometry::earth::Earth::new(crate::geometry::earth::MEAN_RADIUS_KM);
    let pole = [0.0, OVAL_POLE_DISTANCE_KM];
    // The small circle's radius in space, R sin(rho / R): its azimuths from
    // the pole span the arc's length; 33 points, 78 km apart.
    let rho = OVAL_POLE_DISTANCE_KM;
    let span_deg = (OVAL_LENGTH_KM / (earth.radius_km * fmath::sin(rho / earth.radius_km))).to_degrees();
    let south = earth.azimuth_deg(pole, [0.0, 0.0]);
    let n = 33;
    let path: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let az = south + span_deg * (0.5 - k as f64 / (n - 1) as f64);
            let [x, y] = earth.destination(pole, az, rho);
            // Rounded to metres: the TOML stays readable.
            [(x * 1e3).round() / 1e3, (y * 1e3).round() / 1e3]
        })
        .collect();
    let mut s = Scene {
        curtains: vec![Curtain {
            path: Some(path),
            width: 40.0,
            energy_flux: 60.0,
            char_energy_kev: 4.0,
            filament_energy_flux: 100.0,
            filament_potential_kv: 4.0,
            bend_km: 8.0,
            seed: 1,
            ..Curtain::default()
        }],
        ..default_scene()
    };
    s.earth.magnetic_pole = Some(pole);
    s.beams.count = 50_000;
    s.photons.radius_km = 1.5;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s.camera = Camera {
        position: [0.0, 0.0, 0.002],
        look_at: [0.0, 0.0, 1.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Fisheye,
        fov_deg: 180.0,
        ..Camera::default()
    };
    s.render.width = 1024;
    s.render.height = 1024;
    // A bright arc (IBC III) straight overhead: -6.5 stops, as the
    // highlight meter (`render.exposure = "auto"`: -6.4 EV) exposes it; the
    // sky stays dark.
    s.render.exposure = -6.5;
    s.background.stars = true;
    s.terrain = Terrain { kind: TerrainKind::Plane, ..Terrain::default() };
    s
}
