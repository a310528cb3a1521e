//! The renderer's oracles, written independently of `aurora::render`
//! (camera formula, ray-box clipping, brute-force integration through
//! `Grid::sample_world`), and the grid builders and render settings the
//! tests feed both.
#![allow(dead_code, clippy::excessive_precision, clippy::needless_range_loop)]
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use aurora::grid::{Grid, Transform};
use aurora::render::{Integration, RenderSettings};
use aurora::scene::{AirglowParams, Background, Camera, Projection, RenderParams, SkyParams, Terrain, TerrainKind, VolumeParams};
use aurora::util::fmath;
use glam::{DVec3, IVec3};

/// A float grid with every voxel of the inclusive index box `[lo, hi]` set.
pub fn box_f32(lo: IVec3, hi: IVec3, value: impl Fn(IVec3) -> f32, tr: Transform) -> Grid<f32> {
    let mut g = Grid::new("density", 0.0f32, tr);
    for x in lo.x..=hi.x {
        for y in lo.y..=hi.y {
            for z in lo.z..=hi.z {
                let p = IVec3::new(x, y, z);
                g.set(p, value(p));
            }
        }
    }
    g
}

/// A vec3 grid with every voxel of the inclusive index box `[lo, hi]` set.
pub fn box_vec3(lo: IVec3, hi: IVec3, value: impl Fn(IVec3) -> [f32; 3], tr: Transform) -> Grid<[f32; 3]> {
    let mut g = Grid::new("emission", [0.0f32; 3], tr);
    for x in lo.x..=hi.x {
        for y in lo.y..=hi.y {
            for z in lo.z..=hi.z {
                let p = IVec3::new(x, y, z);
                g.set(p, value(p));
            }
        }
    }
    g
}

pub fn ortho(position: [f64; 3], look_at: [f64; 3], up: [f64; 3], ortho_height: f64) -> Camera {
    Camera { position, look_at, up, projection: Projection::Orthographic, fov_deg: 40.0, ortho_height }
}

pub fn persp(position: [f64; 3], look_at: [f64; 3], up: [f64; 3], fov_deg: f64) -> Camera {
    Camera { position, look_at, up, projection: Projection::Perspective, fov_deg, ortho_height: 1.0 }
}

/// Settings with unit scales, no terrain, black background (no stars, no
/// airglow), no air
/// (`sky.extinction = false`: the volume's closed forms), exact integration.
pub fn settings(camera: Camera, width: usize, height: usize, spp: usize) -> RenderSettings {
    RenderSettings {
        camera,
        render: RenderParams { width, height, spp, exposure: 0.0, ..Default::default() },
        volume: VolumeParams { density_scale: 1.0, emission_scale: 1.0 },
        background: Background { radiance: [0.0; 3], stars: false, ..Background::default() },
        terrain: Terrain { kind: TerrainKind::None, ..Terrain::default() },
        earth_radius_km: 0.0,
        sky: SkyParams { extinction: false, ..SkyParams::default() },
        airglow: AirglowParams { on: false, ..AirglowParams::default() },
        line: None,
        observer: aurora::util::observer::Observer::default(),
        seed: 7,
        integration: Integration::Exact,
        base_dir: None,
        site: None,
        time_s: 0.0,
    }
}

/// The camera ray through film point (fx, fy), written from Cycles'
/// formulas (independent of `aurora::geometry::camera`).
pub fn camera_ray(cam: &Camera, w: usize, h: usize, fx: f64, fy: f64) -> (DVec3, DVec3) {
    let pos = DVec3::from_array(cam.position);
    let fwd = (DVec3::from_array(cam.look_at) - pos).normalize();
    let right = fwd.cross(DVec3::from_array(cam.up)).normalize();
    let up = right.cross(fwd);
    let (wf, hf) = (w as f64, h as f64);
    match cam.projection {
        Projection::Perspective => {
            let t = fmath::tan(cam.fov_deg.to_radians() / 2.0);
            let x = (2.0 * fx / wf - 1.0) * t * wf / hf;
            let y = (1.0 - 2.0 * fy / hf) * t;
            (pos, (fwd + x * right + y * up).normalize())
        }
        Projection::Orthographic => {
            let y = (1.0 - 2.0 * fy / hf) * cam.ortho_height / 2.0;
            let x = (2.0 * fx / wf - 1.0) * cam.ortho_height / 2.0 * wf / hf;
            (pos + x * right + y * up, fwd)
        }
        // Panoramas as Cycles writes them (kernel/camera/projection.h):
        // a direction (x, y, z) in Cycles' panoramic camera space (looking
        // along +x) is `x fwd - y right + z up` in the world
        // (blender_camera_matrix). Outside the fisheye's circle: no ray (0).
        Projection::Fisheye => {
            let (u, v) = (2.0 * fx / wf - 1.0, 1.0 - 2.0 * fy / hf);
            let r = (u * u + v * v).sqrt();
            if r > 1.0 {
                return (pos, DVec3::ZERO);
            }
            let theta = r * cam.fov_deg.to_radians() * 0.5;
            let mut phi = if r > 0.0 { fmath::acos((u / r).clamp(-1.0, 1.0)) } else { 0.0 };
            if v < 0.0 {
                phi = -phi;
            }
            let l = DVec3::new(fmath::cos(theta), -fmath::cos(phi) * fmath::sin(theta), fmath::sin(phi) * fmath::sin(theta));
            (pos, l.x * fwd - l.y * right + l.z * up)
        }
        Projection::Equirectangular => {
            let (u, v) = (fx / wf, 1.0 - fy / hf);
            let pi = std::f64::consts::PI;
            let (phi, theta) = (-2.0 * pi * u + pi, -pi * v + pi);
            let l = DVec3::new(fmath::sin(theta) * fmath::cos(phi), fmath::sin(theta) * fmath::sin(phi), fmath::cos(theta));
            (pos, l.x * fwd - l.y * right + l.z * up)
        }
    }
}

/// Slab test: the parameter range of `o + t d` inside `[lo, hi]`, t >= 0.
pub fn clip(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let (mut a, mut b) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
        } else {
            let (p, q) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
            a = a.max(p.min(q));
            b = b.min(p.max(q));
        }
    }
    (a < b).then_some((a, b))
}

/// Gauss-Legendre nodes and weights on [0, 1], n = 3 or 8.
pub fn gauss(n: usize) -> Vec<(f64, f64)> {
    let (x, w): (Vec<f64>, Vec<f64>) = match n {
        3 => (vec![-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4], vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]),
        8 => (
            vec![
                -0.960_289_856_497_536_3,
                -0.796_666_477_413_626_7,
                -0.525_532_409_916_329_0,
                -0.183_434_642_495_649_8,
                0.183_434_642_495_649_8,
                0.525_532_409_916_329_0,
                0.796_666_477_413_626_7,
                0.960_289_856_497_536_3,
            ],
            vec![
                0.101_228_536_290_376_3,
                0.222_381_034_453_374_5,
                0.313_706_645_877_887_3,
                0.362_683_783_378_362_0,
                0.362_683_783_378_362_0,
                0.313_706_645_877_887_3,
                0.222_381_034_453_374_5,
                0.101_228_536_290_376_3,
            ],
        ),
        _ => panic!("no rule for n = {n}"),
    };
    x.into_iter().zip(w).map(|(x, w)| (0.5 + 0.5 * x, 0.5 * w)).collect()
}

/// Parameters where `o + t d` crosses an integer index plane of `tr`, for t
/// in `(t0, t1)`.
fn plane_crossings(tr: &Transform, o: DVec3, d: DVec3, t0: f64, t1: f64, out: &mut Vec<f64>) {
    for k in 0..3 {
        if d[k] == 0.0 {
            continue;
        }
        let ua = (o[k] + d[k] * t0 - tr.translation[k]) / tr.voxel_size;
        let ub = (o[k] + d[k] * t1 - tr.translation[k]) / tr.voxel_size;
        let (lo, hi) = (ua.min(ub).ceil() as i64, ua.max(ub).floor() as i64);
        for p in lo..=hi {
            let t = (p as f64 * tr.voxel_size + tr.translation[k] - o[k]) / d[k];
            if t > t0 && t < t1 {
                out.push(t);
            }
        }
    }
}

/// World box of a grid's support (active bbox widened by one voxel).
pub fn support<T: aurora::grid::VoxelValue>(g: &Grid<T>) -> Option<(DVec3, DVec3)> {
    let (lo, hi) = g.index_bbox()?;
    Some((g.transform.index_to_world(lo.as_dvec3() - DVec3::ONE), g.transform.index_to_world(hi.as_dvec3() + DVec3::ONE)))
}

/// The part `t` in `[0, t_max]` of the ray `o + t d` that [`oracle`]
/// integrates over.
#[derive(Clone, Copy, Debug)]
pub struct RaySpan {
    pub o: DVec3,
    pub d: DVec3,
    pub t_max: f64,
}

/// Brute-force `(tau, L)` along `seg`: breakpoints at every index-plane
/// crossing of both grids (so sigma_t and e are cubic between them),
/// sigma_t (`ds` times the density) integrated with 3-point Gauss (exact
/// for cubics), `int T e` (`es` times the emission) with `parts` x 8-point
/// Gauss per interval, sampling with `Grid::sample_world`.
pub fn oracle(
    density: Option<&Grid<f32>>,
    emission: Option<&Grid<[f32; 3]>>,
    ds: f64,
    es: f64,
    seg: RaySpan,
    parts: usize,
) -> (f64, [f64; 3]) {
    let RaySpan { o, d, t_max } = seg;
    let mut lo = DVec3::INFINITY;
    let mut hi = DVec3::NEG_INFINITY;
    for b in [density.and_then(support), emission.and_then(support)].into_iter().flatten() {
        lo = lo.min(b.0);
        hi = hi.max(b.1);
    }
    let Some((a, b)) = clip(o, d, lo, hi) else { return (0.0, [0.0; 3]) };
    let b = b.min(t_max);
    if !(a < b) {
        return (0.0, [0.0; 3]);
    }
    let mut ts = vec![a, b];
    if let Some(g) = density {
        plane_crossings(&g.transform, o, d, a, b, &mut ts);
    }
    if let Some(g) = emission {
        plane_crossings(&g.transform, o, d, a, b, &mut ts);
    }
    ts.sort_by(f64::total_cmp);
    ts.dedup();
    let sigma = |t: f64| density.map_or(0.0, |g| ds * g.sample_world(o + d * t) as f64);
    let emit = |t: f64| emission.map_or([0.0; 3], |g| g.sample_world(o + d * t).map(|v| es * v as f64));
    let g3 = gauss(3);
    let g8 = gauss(8);
    let tau_over = |x: f64, y: f64| -> f64 { g3.iter().map(|(s, w)| w * sigma(x + (y - x) * s)).sum::<f64>() * (y - x) };
    let mut tau = 0.0;
    let mut l = [0.0; 3];
    for w2 in ts.windows(2) {
        let (x, y) = (w2[0], w2[1]);
        if emission.is_some() {
            let h = (y - x) / parts as f64;
            for p in 0..parts {
                let pa = x + p as f64 * h;
                for (s, w) in &g8 {
                    let t = pa + h * s;
                    let tr = fmath::exp(-(tau + tau_over(x, t)));
                    let e = emit(t);
                    for c in 0..3 {
                        l[c] += w * h * tr * e[c];
                    }
                }
            }
        }
        tau += tau_over(x, y);
    }
    (tau, l)
}

/// Relative difference |a - b| / max(|b|, floor).
pub fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}
