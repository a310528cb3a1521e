//! The airglow behind the volume (`aurora::physics::airglow`,
//! `aurora::render::airglow`, `[airglow]`): the slant column through a
//! spherical shell against van Rhijn's factor and its thick-layer
//! correction, the zenith's radiance per line against the keys, the
//! terrain hiding it, the sky map's layout, the stars and airglow
//! independent of the thread count, and no star below the ground; the
//! broadband light's geometry, and the zenith's total and share of it
//! against a dark site's measured sky; the air's scattering of the sky's
//! light against a brute-force integral over the sky, and the sky's light
//! on the ground.

// Channel loops index several arrays at once.
#![allow(clippy::needless_range_loop)]

use crate::common::oracle::{persp, settings};
use aurora::physics::airglow::{slant_factor, thick_layer_factor, van_rhijn, LAYERS};
use aurora::physics::emission::line_colour::line_rgb;
use aurora::render::airglow::Airglow;
use aurora::render::sky::EnvMap;
use aurora::render::{render, RenderSettings, Volume};
use aurora::scene::{AirglowParams, SkyParams, TerrainKind};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;
use glam::DVec3;
use std::f64::consts::PI;

const R_EARTH: f64 = 6371.0;

/// Only layer `k` of `LAYERS`, at its default brightness.
fn only(k: usize) -> AirglowParams {
    let d = AirglowParams::default();
    let keep = |i: usize, v: f64| if i == k { v } else { 0.0 };
    AirglowParams {
        green_r: keep(0, d.green_r),
        red_r: keep(1, d.red_r),
        sodium_r: keep(2, d.sodium_r),
        hydroxyl_r: keep(3, d.hydroxyl_r),
        continuum_r_per_nm: 0.0,
        zodiacal_light: 0.0,
        starlight: 0.0,
        ..d
    }
}

/// No line, only the broadband keys given.
fn broadband(zodiacal_light: f64, starlight: f64, continuum_r_per_nm: f64) -> AirglowParams {
    AirglowParams { continuum_r_per_nm, zodiacal_light, starlight, ..only(99) }
}

/// One pixel at the centre of a 1 x 1 perspective image looking along
/// `dir` from `at`, round Earth, no air, no volume.
fn pixel(mut s: RenderSettings, at: [f64; 3], dir: DVec3) -> [f32; 4] {
    let up = if dir.z.abs() > 0.9 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
    let look = DVec3::from_array(at) + dir;
    s.camera = persp(at, look.to_array(), up, 10.0);
    let img = render(&s, &Volume::default(), &NoProgress).unwrap();
    img.pixels[0]
}

fn glow_settings(p: AirglowParams) -> RenderSettings {
    let mut s = settings(persp([0.0; 3], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 10.0), 1, 1, 1);
    s.airglow = p;
    s.earth_radius_km = R_EARTH;
    s
}

/// Seen from the ground at zenith angle z, a Gaussian layer's column over
/// its zenith column (the slant factor, by quadrature through the shell)
/// is van Rhijn's thin-layer factor `V = 1 / sqrt(1 - (R sin z / (R +
/// h))^2)` plus the thick-layer correction `sigma^2 / 2 f''(r_h)`,
/// `f(r) = r / sqrt(r^2 - p^2)`, `p = R sin z`; the next term of the
/// expansion, `sigma^4 / 8 f''''`, bounds what is left (2x it, plus 1e-6
/// for the quadrature). For the green layer (sigma 4 km) the correction is
/// 2e-4 of V at 80 degrees; for the red (sigma 30 km) 2.7e-3, ten times
/// the tolerance, so the test tells the thick value from the thin one.
/// V itself is 1.9 at 60 degrees and 3.1-4.1 at 80 (the note's values).
/// The renderer, without air, gives the same factor times the zenith's
/// radiance (its elevation table: within 1e-4).
#[test]
fn a_layer_through_its_shell_gives_van_rhijns_factor_with_the_thick_layer_correction() {
    let mut seen_thick = false;
    for (k, layer) in LAYERS.iter().enumerate().take(2) {
        let zenith = pixel(glow_settings(only(k)), [0.0; 3], DVec3::Z);
        for z_deg in [60.0f64, 80.0] {
            let z = z_deg.to_radians();
            let f = slant_factor(layer, R_EARTH, 0.0, fmath::cos(z));
            let v = van_rhijn(R_EARTH, 0.0, layer.peak_km, z);
            let (thick, next) = thick_layer_factor(layer, R_EARTH, 0.0, z);
            let tol = 2.0 * next.abs() + 1e-6 * thick;
            assert!((f - thick).abs() <= tol, "{} z {z_deg}: quadrature {f}, thick {thick} (next term {next})", layer.name);
            assert!((f - v).abs() <= (thick - v).abs() + tol, "{} z {z_deg}: {f} vs van Rhijn {v}", layer.name);
            if z_deg == 60.0 {
                assert!((v - 1.9).abs() < 0.1, "{v}");
            } else {
                assert!((3.0..4.2).contains(&v), "{v}");
            }
            if (thick - v).abs() > 10.0 * tol {
                seen_thick = true;
            }
            // Through the renderer: the elevation 90 - z, looking north.
            let dir = DVec3::new(0.0, fmath::sin(z), fmath::cos(z));
            let px = pixel(glow_settings(only(k)), [0.0; 3], dir);
            for c in 0..3 {
                let want = zenith[c] as f64 * f;
                assert!(
                    (px[c] as f64 - want).abs() <= 1e-4 * want.abs().max(1e-6),
                    "{} z {z_deg} channel {c}: {} vs {want}",
                    layer.name,
                    px[c]
                );
            }
        }
    }
    assert!(seen_thick, "the red layer's correction is larger than the tolerance");
}

/// At the zenith, without air, each line's radiance is its key: a column
/// of I rayleigh is I 10^6 / (4 pi) photons cm^-2 s^-1 sr^-1, and the
/// volume's unit of radiance is 10^9 / (4 pi) of them (1 kR) times the
/// line's colour per photon (`line_rgb`, luminance 1 for 557.7 nm); within
/// 1 % (the Gaussian's mass below the ground is 1e-9; the f32 pixel 1e-7).
#[test]
fn the_zeniths_radiance_of_each_line_is_its_key() {
    let photons_per_r = 1e6 / (4.0 * PI);
    let unit = 1e9 / (4.0 * PI);
    for (k, layer) in LAYERS.iter().enumerate() {
        let p = only(k);
        let key = aurora::physics::airglow::key_r(&p, layer);
        assert!(key > 0.0);
        let mut want = [0.0; 3];
        for &(lambda, w) in layer.lines {
            let rgb = line_rgb(lambda, aurora::util::observer::Observer::default());
            for c in 0..3 {
                want[c] += rgb[c] * w * key * photons_per_r / unit;
            }
        }
        let got = pixel(glow_settings(p), [0.0; 3], DVec3::Z);
        for c in 0..3 {
            assert!((got[c] as f64 - want[c]).abs() <= 0.01 * want[c].abs().max(1e-9), "{} channel {c}: {got:?} vs {want:?}", layer.name);
        }
        if k == 0 {
            // 250 R of 557.7 nm: luminance 0.25.
            assert!((aurora::util::colour::luminance([got[0] as f64, got[1] as f64, got[2] as f64]) - 0.25).abs() < 0.0025);
        }
    }
    // The air dims the zenith by exp(-tau) of each line above the camera
    // (the air's scattering of the sky's light off: `the_air_scatters_...`).
    let mut s = glow_settings(only(0));
    s.sky = SkyParams { scattering: false, ..SkyParams::default() };
    let air = aurora::physics::air_extinction::Air::from_sky(&s.sky).unwrap();
    let t = fmath::exp(-air.column_above(&air.depths(557.7), 0.0));
    let dimmed = pixel(s, [0.0; 3], DVec3::Z);
    let clear = pixel(glow_settings(only(0)), [0.0; 3], DVec3::Z);
    assert!((dimmed[1] as f64 / clear[1] as f64 - t).abs() < 1e-4, "{} vs {t}", dimmed[1] / clear[1]);
    assert!(t < 0.95);
}

/// A ray half a degree below the horizon from 1 km passes 0.76 km above
/// the ground and crosses every layer twice (bright); the terrain, a
/// sphere 0.9 km up, stops it first: the pixel is the terrain, lit by
/// nothing here, 0. The Earth stops rays below its own horizon.
#[test]
fn the_terrain_and_the_earth_hide_the_airglow() {
    let e = (-0.5f64).to_radians();
    let dir = DVec3::new(0.0, fmath::cos(e), fmath::sin(e));
    let s = glow_settings(AirglowParams::default());
    let open = pixel(s.clone(), [0.0, 0.0, 1.0], dir);
    assert!(open[1] > 1.0, "{open:?}");
    let mut t = s.clone();
    t.terrain.kind = TerrainKind::Plane;
    t.terrain.height = 0.9;
    assert_eq!(pixel(t, [0.0, 0.0, 1.0], dir)[..3], [0.0; 3]);
    let down = (-5.0f64).to_radians();
    assert_eq!(pixel(s, [0.0, 0.0, 1.0], DVec3::new(0.0, fmath::cos(down), fmath::sin(down)))[..3], [0.0; 3]);
}

/// `aurora sky`'s map (`sky_map`) holds at pixel (i, j) the airglow of the
/// direction Blender's Environment Texture reads there (`EnvMap::uv`):
/// within 1e-5 of the airglow's own radiance at pixel centres, which the
/// map then gives back through `EnvMap::radiance`.
#[test]
fn the_sky_map_is_laid_out_as_blenders_world_reads_it() {
    let mut s = glow_settings(AirglowParams::default());
    s.sky = SkyParams::default();
    s.background.stars = false;
    s.camera.position = [3.0, -40.0, 1.0];
    let (w, h) = (64, 32);
    let map = aurora::render::sky_map::sky_map(&s, w, &NoProgress).unwrap();
    assert_eq!((map.width, map.height), (w, h));
    let glow = Airglow::new(&s.airglow, &s.sky, DVec3::from_array(s.camera.position), s.earth_radius_km, s.observer, 0.85).unwrap();
    let env = EnvMap { width: w, height: h, pixels: map.pixels.iter().map(|p| [p[0], p[1], p[2]]).collect() };
    let mut bright = 0;
    for j in 0..h {
        for i in 0..w {
            let (u, v) = ((i as f64 + 0.5) / w as f64, 1.0 - (j as f64 + 0.5) / h as f64);
            let (az, el) = ((0.5 - u) * 2.0 * PI, (v - 0.5) * PI);
            let d = DVec3::new(fmath::cos(el) * fmath::cos(az), fmath::cos(el) * fmath::sin(az), fmath::sin(el));
            let want = glow.radiance(d);
            let got = map.pixels[j * w + i];
            let back = env.radiance(d);
            for c in 0..3 {
                assert!((got[c] as f64 - want[c]).abs() <= 1e-5 * want[c].abs().max(1e-3), "({i}, {j}) channel {c}: {got:?} vs {want:?}");
                assert!((back[c] - got[c] as f64).abs() <= 1e-5 * want[c].abs().max(1e-3));
            }
            bright += (want[1] > 0.1) as usize;
        }
    }
    assert!(bright > w * h / 4, "{bright} bright pixels");
}

/// The stars and the airglow are the same, byte for byte, on 1 and 3
/// threads.
#[test]
fn stars_and_airglow_do_not_depend_on_the_thread_count() {
    let mut s = glow_settings(AirglowParams::default());
    s.sky = SkyParams::default();
    s.background.stars = true;
    s.camera = persp([0.0, 0.0, 1.0], [0.0, 100.0, 30.0], [0.0, 0.0, 1.0], 90.0);
    s.render.width = 96;
    s.render.height = 64;
    let run = |s: &RenderSettings, n: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
        pool.install(|| render(s, &Volume::default(), &NoProgress).unwrap().pixels)
    };
    let (a, b) = (run(&s, 1), run(&s, 3));
    assert!(a.iter().zip(&b).all(|(p, q)| p.iter().zip(q).all(|(x, y)| x.to_bits() == y.to_bits())));
    // Stars are there: pixels brighter than without them, a few per star.
    s.background.stars = false;
    let none = run(&s, 2);
    let lit = a.iter().zip(&none).filter(|(p, q)| p[1] > q[1]).count();
    assert!(lit >= 100, "{lit} pixels hold starlight");
}

/// No star below the ground: from 1 km up, a camera looking 20 degrees
/// below the horizontal (the horizon dips 1 degree) sees none, on a round
/// Earth and on a flat ground; one looking 20 degrees above it sees some.
#[test]
fn no_star_shines_from_below_the_ground() {
    for radius in [R_EARTH, 0.0] {
        let lit = |elevation_deg: f64| {
            let mut s = glow_settings(AirglowParams { on: false, ..AirglowParams::default() });
            s.earth_radius_km = radius;
            s.sky = SkyParams { extinction: false, ..SkyParams::default() };
            s.background.stars = true;
            s.background.limiting_magnitude = 8.0;
            s.terrain.kind = TerrainKind::None;
            let e = elevation_deg.to_radians();
            let at = [0.0, 0.0, 1.0];
            s.camera = persp(at, [0.0, 100.0 * fmath::cos(e), 1.0 + 100.0 * fmath::sin(e)], [0.0, 0.0, 1.0], 30.0);
            s.render.width = 64;
            s.render.height = 64;
            render(&s, &Volume::default(), &NoProgress).unwrap().pixels.iter().filter(|p| p[1] > 0.0).count()
        };
        assert_eq!(lit(-20.0), 0, "radius {radius}");
        assert!(lit(20.0) > 10, "radius {radius}: {} pixels", lit(20.0));
    }
}

/// Each broadband component brightens toward the horizon by its own
/// geometry. Without air: the zodiacal light and the starlight, outside
/// the atmosphere, are the same from every direction above the horizon
/// (to 1e-6); the continuum, a layer at 90 km, by its slant factor (to
/// 1e-4, the table's interpolation), 1.9-2.0 at 60 degrees from the
/// zenith. With the air, the outside light is dimmed toward the horizon
/// between the transmittances of 650 and 450 nm at that air mass.
#[test]
fn the_broadband_light_brightens_by_its_own_geometry() {
    use aurora::physics::air_extinction::{air_mass, Air};
    use aurora::physics::airglow::CONTINUUM_LAYER;
    let clear = SkyParams { extinction: false, ..SkyParams::default() };
    let outside = Airglow::new(&broadband(90.0, 50.0, 0.0), &clear, DVec3::ZERO, R_EARTH, Default::default(), 0.85).unwrap();
    let layer = Airglow::new(&broadband(0.0, 0.0, 1.0), &clear, DVec3::ZERO, R_EARTH, Default::default(), 0.85).unwrap();
    let dir = |e: f64| DVec3::new(0.0, fmath::cos(e.to_radians()), fmath::sin(e.to_radians()));
    let (z_out, z_layer) = (outside.radiance(DVec3::Z), layer.radiance(DVec3::Z));
    assert!(z_out[1] > 0.0 && z_layer[1] > 0.0);
    for e in [60.0, 30.0, 10.0, 2.0] {
        let (o, l) = (outside.radiance(dir(e)), layer.radiance(dir(e)));
        let f = slant_factor(&CONTINUUM_LAYER, R_EARTH, 0.0, fmath::sin(e.to_radians()));
        for c in 0..3 {
            assert!((o[c] / z_out[c] - 1.0).abs() < 1e-6, "outside at {e}: {o:?} vs {z_out:?}");
            assert!((l[c] / (z_layer[c] * f) - 1.0).abs() < 1e-4, "continuum at {e}: {l:?} vs {z_layer:?} x {f}");
        }
        if e == 30.0 {
            assert!((1.9..2.0).contains(&f), "{f}");
        }
    }
    let sky = SkyParams { scattering: false, ..SkyParams::default() };
    let dim = Airglow::new(&broadband(90.0, 50.0, 0.0), &sky, DVec3::ZERO, R_EARTH, Default::default(), 0.85).unwrap();
    let air = Air::from_sky(&sky).unwrap();
    let tau = |l: f64| air.column_above(&air.depths(l), 0.0);
    let (z, low) = (dim.radiance(DVec3::Z), dim.radiance(dir(10.0)));
    let extra = air_mass(10.0) - 1.0;
    let got = low[1] / z[1];
    assert!(got < fmath::exp(-tau(650.0) * extra) && got > fmath::exp(-tau(450.0) * extra), "{got}");
}

/// The default sky at the zenith from the ground, through the eye (CIE
/// 1931 luminance), with the air: as dark as a dark site's moonless sky,
/// V 21.6-22.0 mag arcsec^-2 (Benn & Ellison 1998, La Palma, 21.9 at
/// solar minimum; Patat 2003, A&A 400, 1183, Paranal 21.6-21.9; Falchi et
/// al. 2016, the natural sky 22.0), allowed 21.5-22.2 for the
/// photopic-against-V difference; and about half of it broadband (Leinert
/// et al. 1998, Benn & Ellison 1998): 0.4-0.75. The volume's unit of
/// radiance is 1 kR of 557.7 nm per 4 pi sr: 1.926e-4 cd m^-2
/// (7.958e11 photons m^-2 s^-1 sr^-1 x 3.562e-19 J x 683 lm/W x
/// ybar(557.7) = 0.995), and `m = 12.58 - 2.5 log10(L / cd m^-2)`
/// (Garstang 1986's 10.8e4 cd m^-2 at m = 0). Through the camera at its
/// default white balance the zenith's hue is printed; the photographs'
/// blue is asserted on rendered pictures (`tests/render/sky_colour.rs`).
#[test]
fn the_zenith_sky_is_a_dark_sites_and_half_of_it_broadband() {
    use aurora::util::colour::luminance;
    use aurora::util::observer::Observer;
    let sky = SkyParams::default();
    let zenith = |p: &AirglowParams, o: Observer| Airglow::new(p, &sky, DVec3::ZERO, R_EARTH, o, 0.85).unwrap().radiance(DVec3::Z);
    let all = zenith(&AirglowParams::default(), Observer::Eye);
    let broad = zenith(&broadband(90.0, 50.0, 1.0), Observer::Eye);
    let (y_all, y_broad) = (luminance(all), luminance(broad));
    let cd = y_all * 1.926e-4;
    let mag = 12.58 - 2.5 * fmath::log10(cd);
    let share = y_broad / y_all;
    let cam = zenith(&AirglowParams::default(), Observer::Camera);
    println!(
        "zenith: {y_all:.3} units, {cd:.3e} cd/m^2, V {mag:.2} mag/arcsec^2, broadband {share:.2}; eye {all:?}, camera (daylight) {cam:?}"
    );
    assert!((21.5..22.2).contains(&mag), "V {mag}");
    assert!((0.4..0.75).contains(&share), "broadband share {share}");
}

/// Direction `e` degrees above the horizon at azimuth `az` (radians).
fn toward(e_deg: f64, az: f64) -> DVec3 {
    let (se, ce) = (fmath::sin(e_deg.to_radians()), fmath::cos(e_deg.to_radians()));
    DVec3::new(ce * fmath::cos(az), ce * fmath::sin(az), se)
}

/// The air's scattering of the sky's light (`[sky] scattering`,
/// `aurora::render::airglow`): for one line (557.7 nm, whose depth above
/// the ground is `tau`), what scattering adds at elevation `e` is
/// `J (1 - exp(-tau X(e)))`, the same `J` at every elevation; and `J` is
/// `(Lbar + a E / pi) / 2` of the sky without scattering, found here by
/// brute force: 200,000 directions drawn uniformly over the upper
/// hemisphere (its mean) and as many drawn by the cosine (`E / pi`), read
/// from the sky without scattering, so within 1 % (the draws' standard
/// error is about 0.3 %). Forgetting the ground's light (`a = 0`) in the
/// renderer fails it: J 0.209 against 0.380 (checked once).
/// The sky's irradiance on level ground is pi times the cosine-drawn mean
/// of the sky with scattering (1 %), on a wall half of it.
#[test]
fn the_air_scatters_the_skys_light_as_a_brute_force_integral_gives() {
    use rand::{Rng, SeedableRng};
    let albedo = 0.85;
    let on = SkyParams::default();
    let off = SkyParams { scattering: false, ..on.clone() };
    let p = only(0);
    let glow_on = Airglow::new(&p, &on, DVec3::ZERO, R_EARTH, Default::default(), albedo).unwrap();
    let glow_off = Airglow::new(&p, &off, DVec3::ZERO, R_EARTH, Default::default(), albedo).unwrap();
    let air = aurora::physics::air_extinction::Air::from_sky(&on).unwrap();
    let tau = air.column_above(&air.depths(557.7), 0.0);
    // J from what scattering adds, at several elevations: one value.
    let js: Vec<f64> = [2.0, 10.0, 30.0, 60.0, 89.0]
        .iter()
        .map(|&e| {
            let added = glow_on.radiance(toward(e, 0.3))[1] - glow_off.radiance(toward(e, 0.3))[1];
            added / (1.0 - fmath::exp(-tau * aurora::physics::air_extinction::air_mass(e)))
        })
        .collect();
    for j in &js {
        assert!((j / js[0] - 1.0).abs() < 2e-3, "J by elevation {js:?}");
    }
    // J by brute force over the sky without scattering.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let n = 200_000;
    let (mut mean, mut cos_mean, mut e_on) = (0.0, 0.0, 0.0);
    for _ in 0..n {
        let az = rng.random::<f64>() * 2.0 * PI;
        // Uniform on the hemisphere: sin e uniform.
        let e_uniform = fmath::asin(rng.random::<f64>()).to_degrees();
        mean += glow_off.radiance(toward(e_uniform, az))[1];
        // By the cosine about the zenith: sin^2 e uniform.
        let e_cos = fmath::asin(rng.random::<f64>().sqrt()).to_degrees();
        cos_mean += glow_off.radiance(toward(e_cos, az))[1];
        e_on += glow_on.radiance(toward(e_cos, az))[1];
    }
    let (mean, cos_mean, e_on) = (mean / n as f64, cos_mean / n as f64, PI * e_on / n as f64);
    let j = 0.5 * (mean + albedo * cos_mean);
    println!("J {:.4} (the renderer's {:.4}), sky mean {mean:.4}, E/pi {cos_mean:.4}, tau {tau:.3}", j, js[0]);
    assert!((js[0] / j - 1.0).abs() < 0.01, "J {} against the brute force's {j}", js[0]);
    let ground = glow_on.ground_irradiance(DVec3::Z)[1];
    assert!((ground / e_on - 1.0).abs() < 0.01, "E {ground} against the brute force's {e_on}");
    assert!((glow_on.ground_irradiance(DVec3::X)[1] / ground - 0.5).abs() < 1e-12);
    assert_eq!(glow_off.ground_irradiance(DVec3::Z), [0.0; 3]);
}

/// With the air's scattering the default sky no longer darkens toward the
/// horizon: the green at half a degree is within 10 % of the zenith's
/// (measured 0.98) and at 10 degrees at least 1.5x it (1.70), where without it the air dims the last
/// degrees to a fifth of the zenith and less (measured skies brighten
/// toward the horizon: Garstang 1989, Fig. 4).
#[test]
fn the_sky_brightens_toward_the_horizon_through_the_air() {
    let on = SkyParams::default();
    let off = SkyParams { scattering: false, ..on.clone() };
    let p = AirglowParams::default();
    let g = |sky: &SkyParams, e: f64| {
        Airglow::new(&p, sky, DVec3::new(0.0, 0.0, 1.0), R_EARTH, Default::default(), 0.85).unwrap().radiance(toward(e, 1.0))[1]
    };
    let (zenith, ten, half) = (g(&on, 89.9), g(&on, 10.0), g(&on, 0.5));
    println!(
        "green: zenith {zenith:.3}, 10 deg {ten:.3}, 0.5 deg {half:.3}; without scattering {:.3}, {:.3}, {:.3}",
        g(&off, 89.9),
        g(&off, 10.0),
        g(&off, 0.5)
    );
    assert!(half >= 0.9 * zenith && ten >= 1.5 * zenith, "{zenith} {ten} {half}");
    assert!(g(&off, 0.5) < 0.2 * g(&off, 89.9));
}
