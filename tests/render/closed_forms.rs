//! Rendered pixels against closed forms (spp = 1, no terrain: deterministic).
//!
//! Tolerance: 1e-4 relative, the bound the renderer states. Its own error is
//! far smaller: optical depth is integrated exactly in f64 from the same f32
//! voxel values, emission with Gauss-Legendre of relative error < 1e-9 (see
//! `segment.rs`), and pixels are stored as f32 (relative rounding 6e-8).
//!
//! Box geometry used throughout (derivation). A box of N^3 voxels of value v
//! at indices 0..N-1 has, along an index axis u, the profile
//! `r(u) = clamp(min(u + 1, N - u), 0, 1)`: 1 between the planes through the
//! outer voxel centres (u = 0 and u = N-1) and a linear ramp over one voxel
//! beyond each (the trilinear interpolant falls to the inactive neighbour's
//! 0). The field is `v r(x) r(y) r(z)`. Along an axis-aligned ray at lateral
//! index position (x, y): `int r(z) dz = (N - 1) + 1/2 + 1/2 = N` voxels, so the
//! optical depth is `v N h r(x) r(y)` (h the voxel size). Along an oblique
//! ray that crosses each face ramp while its other two coordinates are in
//! [0, N-1], the field in the ramp is `v r(u_face)`, whose integral over the
//! ramp equals `v` times the length of the ray in the half of the ramp
//! inside the plane at u = -1/2 (resp. N - 1/2): the optical depth is
//! `v` times the ray's length in the box `[-1/2, N - 1/2]^3` (index), scaled by h.

use crate::common::oracle::*;
use aurora::grid::{Grid, Transform};
use aurora::render::{radiance_along_ray, render, Integration, Medium, RenderSettings, Volume};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;
use glam::{DVec3, IVec3};

const N: i32 = 16;
const H: f64 = 0.5;

fn tr() -> Transform {
    Transform::new(H, DVec3::new(1.0, -2.0, 0.5))
}

fn idx(p: DVec3) -> DVec3 {
    tr().world_to_index(p)
}

/// The ray's index-space path length in `[-1/2, N-1/2]^3`, times h, if the
/// ray meets the box's ramps only where one coordinate at a time is outside
/// `[0, N-1]` (the condition of the module doc); `Some(0)` if it misses the
/// support `[-1, N]^3` entirely; None otherwise (edge or corner ramps).
fn box_path(o: DVec3, d: DVec3) -> Option<f64> {
    let (oi, di) = (idx(o), d / H);
    let n = N as f64;
    let Some((t_in, t_out)) = clip(oi, di, DVec3::splat(-1.0), DVec3::splat(n)) else { return Some(0.0) };
    // Interval of t where each axis is inside [0, N-1].
    let mut j = [(0.0, 0.0); 3];
    for k in 0..3 {
        if di[k] == 0.0 {
            if oi[k] < 0.0 || oi[k] > n - 1.0 {
                return None;
            }
            j[k] = (t_in, t_out);
        } else {
            let (p, q) = ((0.0 - oi[k]) / di[k], (n - 1.0 - oi[k]) / di[k]);
            j[k] = (p.min(q).max(t_in), p.max(q).min(t_out));
            if j[k].0 > j[k].1 {
                return None;
            }
        }
    }
    let eps = 1e-9;
    for a in 0..3 {
        for b in 0..3 {
            if a == b {
                continue;
            }
            let before_both = j[a].0.min(j[b].0) > t_in + eps;
            let after_both = j[a].1.max(j[b].1) < t_out - eps;
            let a_before_b_after = j[b].1 < j[a].0 - eps;
            if before_both || after_both || a_before_b_after {
                return None;
            }
        }
    }
    let (a, b) = clip(oi, di, DVec3::splat(-0.5), DVec3::splat(n - 0.5)).expect("inside the support");
    // t is the world parameter (d is unit), so b - a is a world length.
    Some(b - a)
}

fn ramp(u: f64) -> f64 {
    (u + 1.0).min(N as f64 - u).clamp(0.0, 1.0)
}

fn check(what: &str, got: f32, want: f64, tol: f64) {
    let err = rel(got as f64, want, 1e-300);
    assert!(err <= tol, "{what}: got {got}, want {want} (relative error {err:.2e})");
}

/// Alpha must be 1 - T: to 1e-4 relative on whichever of T and 1 - T is
/// smaller (so neither a faint nor a nearly opaque pixel hides an error),
/// plus the f32 rounding of a value near 1 (2^-24).
fn check_alpha(what: &str, alpha: f32, t: f64) {
    let err = (alpha as f64 - (1.0 - t)).abs();
    let tol = 1e-4 * t.min(1.0 - t) + fmath::powi(2f64, -24);
    assert!(err <= tol, "{what}: alpha {alpha}, T {t}: |alpha - (1 - T)| = {err:.2e} > {tol:.2e}");
}

const SIGMA: f32 = 0.25;
const E: [f32; 3] = [1.0, 0.5, 0.25];

fn density_box(v: f32) -> Grid<f32> {
    box_f32(IVec3::ZERO, IVec3::splat(N - 1), |_| v, tr())
}
fn emission_box(e: [f32; 3]) -> Grid<[f32; 3]> {
    box_vec3(IVec3::ZERO, IVec3::splat(N - 1), |_| e, tr())
}

fn centre() -> DVec3 {
    tr().index_to_world(DVec3::splat((N as f64 - 1.0) / 2.0))
}

/// Perspective, oblique view of the box: most pixels cross it obliquely.
fn oblique_persp() -> RenderSettings {
    let c = centre();
    let pos = c + DVec3::new(-9.0, -14.0, 6.0);
    settings(persp(pos.to_array(), c.to_array(), [0.0, 0.0, 1.0], 45.0), 48, 36, 1)
}

/// Orthographic, looking straight down -z over the box and its margins.
fn axis_ortho() -> RenderSettings {
    let c = centre();
    let pos = c + DVec3::new(0.0, 0.0, 20.0);
    settings(ortho(pos.to_array(), c.to_array(), [0.0, 1.0, 0.0], 10.0), 40, 40, 1)
}

/// Orthographic, oblique direction.
fn oblique_ortho() -> RenderSettings {
    let c = centre();
    let pos = c - DVec3::new(0.3, 0.2, -1.0).normalize() * 20.0;
    settings(ortho(pos.to_array(), c.to_array(), [0.0, 1.0, 0.0], 9.0), 36, 36, 1)
}

/// For every pixel with a closed form, checks `f(D)` against the pixel, where
/// `D` is the ray's effective path length through the box; returns the number
/// of pixels checked inside the box.
fn check_image(s: &RenderSettings, vol: &Volume, f: impl Fn(f64) -> ([f64; 3], f64), what: &str) -> usize {
    let img = render(s, vol, &NoProgress).unwrap();
    let (w, h) = (s.render.width, s.render.height);
    let axis_aligned = s.camera.projection == aurora::scene::Projection::Orthographic
        && DVec3::from_array(s.camera.look_at) - DVec3::from_array(s.camera.position) == DVec3::new(0.0, 0.0, -20.0);
    let mut inside = 0;
    for py in 0..h {
        for px in 0..w {
            let (o, d) = camera_ray(&s.camera, w, h, px as f64 + 0.5, py as f64 + 0.5);
            let path = if axis_aligned {
                let u = idx(o);
                Some(N as f64 * H * ramp(u.x) * ramp(u.y))
            } else {
                box_path(o, d)
            };
            let Some(path) = path else { continue };
            if path > 0.0 {
                inside += 1;
            }
            let (l, t) = f(path);
            let p = img.pixel(px, py);
            for c in 0..3 {
                check(&format!("{what} pixel ({px},{py}) channel {c}"), p[c], l[c], 1e-4);
            }
            check_alpha(&format!("{what} pixel ({px},{py})"), p[3], t);
        }
    }
    inside
}

#[test]
fn homogeneous_box_transmittance_is_exp_of_optical_depth() {
    let d = density_box(SIGMA);
    let vol = Volume { density: Some(&d), emission: None };
    for (name, mut s) in [("persp", oblique_persp()), ("ortho-axis", axis_ortho()), ("ortho-oblique", oblique_ortho())] {
        s.background.radiance = [1.0; 3];
        let n = check_image(
            &s,
            &vol,
            |path| {
                let t = fmath::exp(-(SIGMA as f64) * path);
                ([t; 3], t)
            },
            name,
        );
        assert!(n >= 200, "{name}: only {n} pixels crossed the box with a closed form");
    }
}

#[test]
fn emission_only_box_gives_e_times_path() {
    let e = emission_box(E);
    let vol = Volume { density: None, emission: Some(&e) };
    for (name, s) in [("persp", oblique_persp()), ("ortho-axis", axis_ortho()), ("ortho-oblique", oblique_ortho())] {
        let n = check_image(&s, &vol, |path| (E.map(|e| e as f64 * path), 1.0), name);
        assert!(n >= 200, "{name}: {n}");
    }
}

#[test]
fn emission_with_absorption_same_shape_closed_form() {
    // density = sigma s(x), emission = e s(x) for the same shape s: along any
    // ray L = e/sigma (1 - exp(-sigma D)), D = int s, plus background * exp(-sigma D).
    let sigma = 0.8f32;
    let d = density_box(sigma);
    let e = emission_box(E);
    let vol = Volume { density: Some(&d), emission: Some(&e) };
    let b = 0.3;
    for (name, mut s) in [("persp", oblique_persp()), ("ortho-axis", axis_ortho()), ("ortho-oblique", oblique_ortho())] {
        s.background.radiance = [b; 3];
        s.volume.density_scale = 1.25; // sigma_t = 1.25 * 0.8 = 1.0 per km
        s.volume.emission_scale = 2.0;
        let st = 1.25 * sigma as f64;
        let n = check_image(
            &s,
            &vol,
            |path| {
                let t = fmath::exp(-st * path);
                (E.map(|e| 2.0 * e as f64 / st * (1.0 - t) + b * t), t)
            },
            name,
        );
        assert!(n >= 200, "{name}: {n}");
    }
}

/// Slanted orthographic view of a slab that varies along z only: voxels
/// x in 0..64, y in 0..5, z in 0..80, h = 0.1 km, looking along
/// (0.5, 0, -1). Every ray crosses the full z range with x, y in the interior.
fn slab_scene(rho: impl Fn(i32) -> f32) -> (Grid<f32>, RenderSettings, f64) {
    let h = 0.1;
    let t = Transform::new(h, DVec3::new(-3.0, 2.0, 0.0));
    let g = box_f32(IVec3::ZERO, IVec3::new(63, 4, 79), |p| rho(p.z), t);
    let fwd = DVec3::new(0.5, 0.0, -1.0).normalize();
    let mid = t.index_to_world(DVec3::new(30.0, 2.0, 40.0));
    let pos = mid - fwd * 20.0;
    let mut s = settings(ortho(pos.to_array(), mid.to_array(), [0.0, 1.0, 0.0], 0.4), 8, 2, 1);
    s.background.radiance = [1.0; 3];
    (g, s, fwd.z.abs())
}

#[test]
fn linear_density_ramp_along_a_slanted_ray() {
    // rho_k = g k: the trilinear interpolant is exactly linear in z inside
    // and ramps from g (N-1) to 0 above the top voxel; below k = 0 it is 0.
    // int over z (index) = g (N-1)^2 / 2 + g (N-1) / 2 = g N (N-1) / 2, and the
    // slanted path multiplies by h / |cos|.
    let g = 0.005;
    let n = 80.0;
    let (grid, s, cos) = slab_scene(|k| (g * k as f64) as f32);
    let tau = 0.1 * g * n * (n - 1.0) / 2.0 / cos;
    let img = render(&s, &Volume { density: Some(&grid), emission: None }, &NoProgress).unwrap();
    for p in &img.pixels {
        check("ramp T", p[0], fmath::exp(-tau), 1e-4);
        check_alpha("ramp", p[3], fmath::exp(-tau));
    }
}

#[test]
fn exponential_atmosphere_along_a_slanted_ray() {
    // rho_k = rho0 exp(-k h / Hs). The piecewise-linear interpolant
    // integrates exactly to h sum_k rho_k along z (every tent has area h),
    // so tau = h sum rho_k / |cos|: checked to 1e-4.
    // Against the continuous exponential: h sum rho_k = trapezoid + end ramps,
    // and Euler-Maclaurin gives trapezoid - int_0^Z rho = h^2 / (12 Hs) (rho0 - rho_top)
    // + O(h^4 / Hs^3), so the difference from the closed form
    // int_0^Z rho0 exp(-z/Hs) dz + (rho0 + rho_top) h / 2 is predicted to 1e-3.
    let (h, hs, rho0, n) = (0.1, 1.0, 0.3, 80);
    let rho = |k: i32| rho0 * fmath::exp(-(k as f64) * h / hs);
    let (grid, s, cos) = slab_scene(|k| rho(k) as f32);
    let sum: f64 = (0..n).map(|k| rho(k) as f32 as f64).sum();
    let tau = h * sum / cos;
    let img = render(&s, &Volume { density: Some(&grid), emission: None }, &NoProgress).unwrap();
    for p in &img.pixels {
        check("atmosphere T", p[0], fmath::exp(-tau), 1e-4);
        check_alpha("atmosphere", p[3], fmath::exp(-tau));
    }
    let z = (n - 1) as f64 * h;
    let rho_top = rho(n - 1);
    let continuous = rho0 * hs * (1.0 - fmath::exp(-z / hs)) + (rho0 + rho_top) * h / 2.0;
    let predicted = h * h / (12.0 * hs) * (rho0 - rho_top);
    let rendered_tau = -fmath::ln(img.pixels[0][0] as f64) * cos;
    let diff = rendered_tau - continuous;
    assert!((diff - predicted).abs() <= 1e-3 * predicted + 1e-6, "trapezoid error {diff:.3e} vs Euler-Maclaurin {predicted:.3e}");
}

#[test]
fn single_voxel_footprint_is_exactly_one_voxel() {
    // One active voxel of value 3 at index (4,4,4), h = 0.5: tau along z at
    // lateral index offsets (dx, dy) is 3 h (1-|dx|)(1-|dy|) for |dx|,|dy| < 1,
    // and exactly 0 (T = 1 bit for bit) outside.
    let t = Transform::new(0.5, DVec3::ZERO);
    let mut g = Grid::new("density", 0.0f32, t);
    g.set(IVec3::splat(4), 3.0);
    let c = t.index_to_world(DVec3::splat(4.0));
    let pos = c + DVec3::new(0.0, 0.0, 10.0);
    // 11 x 11 pixels, 0.25 voxel apart, centred on the voxel: offsets -1.25 ..= 1.25.
    let mut s = settings(ortho(pos.to_array(), c.to_array(), [0.0, 1.0, 0.0], 11.0 * 0.125), 11, 11, 1);
    s.background.radiance = [1.0; 3];
    let vol = Volume { density: Some(&g), emission: None };
    let img = render(&s, &vol, &NoProgress).unwrap();
    let mut outside = 0;
    for py in 0..11 {
        for px in 0..11 {
            let (o, _) = camera_ray(&s.camera, 11, 11, px as f64 + 0.5, py as f64 + 0.5);
            let u = t.world_to_index(o) - DVec3::splat(4.0);
            let p = img.pixel(px, py);
            if u.x.abs() > 1.0 + 1e-9 || u.y.abs() > 1.0 + 1e-9 {
                assert_eq!(p, [1.0, 1.0, 1.0, 0.0], "pixel ({px},{py}) at offset {u:?} must see nothing");
                outside += 1;
            } else {
                let tau = 3.0 * 0.5 * (1.0 - u.x.abs()).max(0.0) * (1.0 - u.y.abs()).max(0.0);
                check("single voxel", p[0], fmath::exp(-tau), 1e-4);
                check_alpha("single voxel", p[3], fmath::exp(-tau));
            }
        }
    }
    assert_eq!(outside, 11 * 11 - 9 * 9);
    // Rays a hair outside the footprint, in every direction around the voxel.
    let medium = Medium::new(Some(&g), None, 1.0, 1.0).unwrap();
    for (off, dir) in [
        (DVec3::new(0.5 * (1.0 + 1e-9), 0.0, -3.0), DVec3::Z),
        (DVec3::new(0.0, -0.5 * (1.0 + 1e-9), -3.0), DVec3::Z),
        (DVec3::new(-3.0, 0.0, 0.5 * (1.0 + 1e-9)), DVec3::X),
        (DVec3::new(-3.0, -3.0, 0.5 * (1.0 + 1e-9)), DVec3::new(1.0, 1.0, 0.0).normalize()),
    ] {
        let r = radiance_along_ray(&medium, c + off, dir, f64::INFINITY, Integration::Exact, 0.5);
        assert_eq!(r.transmittance(), 1.0, "offset {off:?}");
    }
    // ... and a hair inside: tau = 3 h * 1e-3.
    let r = radiance_along_ray(&medium, c + DVec3::new(0.5 * (1.0 - 1e-3), 0.0, -3.0), DVec3::Z, f64::INFINITY, Integration::Exact, 0.5);
    assert!(rel(r.tau, 3.0 * 0.5 * 1e-3, 0.0) < 1e-9, "{}", r.tau);
}

#[test]
fn rays_in_planes_shared_by_leaves_and_nodes_count_once() {
    // A voxel at a corner shared by 8 leaves, blocks and super nodes (index
    // (0,0,0) and (4096,-4096,128)), seen along z through its centre and
    // along lines in its voxel-centre planes: tau = v h (1-|dx|)(1-|dy|)
    // exactly as for an interior voxel, never counted twice. Tolerance 1e-10:
    // local coordinates are differences of index coordinates up to 4096,
    // each rounded to 4096 * 2^-52 = 9e-13.
    for centre in [IVec3::ZERO, IVec3::new(4096, -4096, 128)] {
        let t = Transform::new(0.5, DVec3::new(0.3, -0.2, 0.1));
        let mut g = Grid::new("density", 0.0f32, t);
        g.set(centre, 2.0);
        let medium = Medium::new(Some(&g), None, 1.0, 1.0).unwrap();
        let c = t.index_to_world(centre.as_dvec3());
        for (dx, dy) in [(0.0, 0.0), (0.5, 0.0), (0.0, -0.25), (0.75, 0.5)] {
            let o = c + DVec3::new(dx, dy, -3.0) * 0.5;
            let r = radiance_along_ray(&medium, o, DVec3::Z, f64::INFINITY, Integration::Exact, 0.5);
            let want = 2.0 * 0.5 * (1.0 - f64::abs(dx)) * (1.0 - f64::abs(dy));
            assert!(rel(r.tau, want, 0.0) < 1e-10, "centre {centre} offset ({dx},{dy}): tau {} vs {want}", r.tau);
            // The same along x and y.
            let o = c + DVec3::new(-3.0, dx, dy) * 0.5;
            let r = radiance_along_ray(&medium, o, DVec3::X, f64::INFINITY, Integration::Exact, 0.5);
            assert!(rel(r.tau, want, 0.0) < 1e-10, "centre {centre} along x offset ({dx},{dy}): tau {}", r.tau);
            let o = c + DVec3::new(dy, 3.0, dx) * 0.5;
            let r = radiance_along_ray(&medium, o, -DVec3::Y, f64::INFINITY, Integration::Exact, 0.5);
            assert!(rel(r.tau, want, 0.0) < 1e-10, "centre {centre} along -y offset ({dx},{dy}): tau {}", r.tau);
        }
    }
}
