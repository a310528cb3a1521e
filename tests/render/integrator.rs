//! The volume walker and integrators against brute force.
//!
//! The oracle (`common::oracle::oracle`) shares no code with the renderer: it
//! finds every index-plane crossing of the ray directly, integrates sigma_t
//! between crossings with 3-point Gauss (exact for the cubic the trilinear
//! field is there) and `int T e` with 8-point Gauss on many sub-parts, all
//! through `Grid::sample_world`.

#![allow(clippy::needless_range_loop)]

use crate::common::oracle::*;
use aurora::grid::{Grid, Transform};
use aurora::render::dda::{segments, CellFilter, LeafWalker};
use aurora::render::segment::{Accum, Cubic, Piece, TAU_CUTOFF};
use aurora::render::{optical_depth_along_ray, radiance_along_ray, render, Integration, Medium, Volume};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;
use glam::{DVec3, IVec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A sparse random grid: clusters of voxels (about 40% of each cluster box
/// active) around the given index centres, values in [0, vmax).
fn random_grids(rng: &mut Pcg64, centres: &[IVec3], radius: i32, vmax: f32, tr: Transform) -> (Grid<f32>, Grid<[f32; 3]>) {
    let mut d = Grid::new("density", 0.0f32, tr);
    let mut e = Grid::new("emission", [0.0f32; 3], tr);
    for &c in centres {
        for x in -radius..=radius {
            for y in -radius..=radius {
                for z in -radius..=radius {
                    let p = c + IVec3::new(x, y, z);
                    if rng.random::<f64>() < 0.4 {
                        d.set(p, rng.random::<f32>() * vmax);
                    }
                    if rng.random::<f64>() < 0.4 {
                        e.set(p, [rng.random::<f32>(), rng.random::<f32>() * 2.0, rng.random::<f32>() * 0.5]);
                    }
                }
            }
        }
    }
    (d, e)
}

fn random_dir(rng: &mut Pcg64) -> DVec3 {
    loop {
        let v = DVec3::new(rng.random::<f64>() * 2.0 - 1.0, rng.random::<f64>() * 2.0 - 1.0, rng.random::<f64>() * 2.0 - 1.0);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// A ray through (near) a random active voxel, from outside or from inside,
/// with a finite or infinite end.
fn random_ray<T: aurora::grid::VoxelValue>(rng: &mut Pcg64, g: &Grid<T>) -> (DVec3, DVec3, f64) {
    let n = g.active_voxel_count() as usize;
    let (v, _) = g.iter_active().nth(rng.random_range(0..n)).unwrap();
    let jitter = DVec3::new(rng.random(), rng.random(), rng.random()) * 3.0 - 1.5;
    let target = g.transform.index_to_world(v.as_dvec3() + jitter);
    let d = random_dir(rng);
    let span = 30.0 * g.transform.voxel_size;
    if rng.random::<f64>() < 0.5 {
        (target - d * span, d, if rng.random::<f64>() < 0.5 { f64::INFINITY } else { span * rng.random::<f64>() * 1.5 })
    } else {
        (target, d, if rng.random::<f64>() < 0.5 { f64::INFINITY } else { span * rng.random::<f64>() })
    }
}

/// Compares the exact integrator with the oracle on random rays.
/// Tolerance: the renderer stores `scale * value` as f32 (relative rounding
/// 6e-8 per voxel) while the oracle multiplies in f64, and the emission
/// quadrature errs below 1e-9 relative: 3e-7 relative (plus 1e-12 absolute
/// for values that vanish).
fn compare(density: Option<&Grid<f32>>, emission: Option<&Grid<[f32; 3]>>, ds: f64, es: f64, rays: usize, seed: u64) -> usize {
    let medium = Medium::new(density, emission, ds, es).unwrap();
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut nonzero = 0;
    for _ in 0..rays {
        let (o, d, t_max) = match (density, emission) {
            (Some(g), _) => random_ray(&mut rng, g),
            (None, Some(g)) => random_ray(&mut rng, g),
            _ => unreachable!(),
        };
        let got = radiance_along_ray(&medium, o, d, t_max, Integration::Exact, 0.5);
        let (tau, l) = oracle(density, emission, ds, es, RaySpan { o, d, t_max }, 16);
        if tau > TAU_CUTOFF {
            // The renderer stops once tau passes TAU_CUTOFF (T < 4e-18): what
            // is left of L is below exp(-40) times the rest of the emission.
            assert!(got.tau > TAU_CUTOFF && got.tau <= tau * (1.0 + 3e-7), "tau {} vs oracle {tau}", got.tau);
        } else {
            assert!((got.tau - tau).abs() <= 3e-7 * tau + 1e-12, "tau {} vs oracle {tau} (ray {o} {d} {t_max})", got.tau);
        }
        for c in 0..3 {
            assert!((got.l[c] - l[c]).abs() <= 3e-7 * l[c] + 1e-12, "L[{c}] {} vs oracle {} (ray {o} {d} {t_max})", got.l[c], l[c]);
        }
        // Shadow rays use the same walker; with density and emission on
        // different transforms the radiance walk splits pieces further, so
        // the sums agree to rounding only.
        let shadow = optical_depth_along_ray(&medium, o, d, t_max, Integration::Exact, 0.5);
        assert!((shadow.tau - got.tau).abs() <= 1e-12 * got.tau, "shadow tau {} vs {}", shadow.tau, got.tau);
        if tau > 0.0 || l[1] > 0.0 {
            nonzero += 1;
        }
    }
    nonzero
}

#[test]
fn exact_matches_brute_force_on_random_sparse_grids() {
    let mut rng = Pcg64::seed_from_u64(11);
    let tr = Transform::new(0.37, DVec3::new(-1.3, 0.4, 2.2));
    // Clusters straddling leaf (8), block (128) and negative-index boundaries.
    let centres = [IVec3::new(0, -1, 3), IVec3::new(127, 6, -8), IVec3::new(-9, 130, 1)];
    let (d, e) = random_grids(&mut rng, &centres, 5, 3.0, tr);
    let n = compare(Some(&d), Some(&e), 0.7, 1.3, 300, 1);
    assert!(n > 100, "only {n} rays met the volume");
    compare(Some(&d), None, 1.0, 1.0, 100, 2);
    compare(None, Some(&e), 1.0, 2.0, 100, 3);
}

#[test]
fn exact_matches_brute_force_with_density_and_emission_on_different_transforms() {
    let mut rng = Pcg64::seed_from_u64(12);
    let (d, _) = random_grids(&mut rng, &[IVec3::new(2, 3, -4)], 6, 2.0, Transform::new(0.5, DVec3::new(0.1, 0.0, -0.3)));
    let (_, e) = random_grids(&mut rng, &[IVec3::new(4, 2, -3)], 5, 1.0, Transform::new(0.61, DVec3::new(-0.2, 0.35, 0.0)));
    let medium = Medium::new(Some(&d), Some(&e), 1.0, 1.0).unwrap();
    assert_eq!(medium.fields.len(), 2, "different transforms need two fields");
    let n = compare(Some(&d), Some(&e), 1.0, 1.0, 300, 4);
    assert!(n > 100, "{n}");
}

#[test]
fn exact_matches_brute_force_in_optically_thick_cells() {
    // Voxel values up to 60 per km at h = 0.5: up to 30 optical depths per
    // cell, so the emission quadrature must subdivide.
    let mut rng = Pcg64::seed_from_u64(13);
    let (d, e) = random_grids(&mut rng, &[IVec3::ZERO], 3, 60.0, Transform::new(0.5, DVec3::ZERO));
    compare(Some(&d), Some(&e), 1.0, 1.0, 200, 5);
}

#[test]
fn gauss_legendre_emission_error_is_below_the_documented_bound() {
    // segment.rs documents a measured worst relative error of 3.5e-12 for
    // 6-point Gauss-Legendre on parts whose optical-depth quartic has
    // absolute coefficient sum <= 1/2. Reference: the same piece split 64
    // times finer (each part's quartic coefficients shrink by 64^-k).
    // Random cubics, optical depths up to 40.
    let mut rng = Pcg64::seed_from_u64(14);
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        let sig: [f64; 8] = std::array::from_fn(|_| rng.random::<f64>() * 20.0);
        let em: [[f64; 8]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| rng.random::<f64>()));
        let ua = [rng.random(), rng.random(), rng.random()];
        let ub = [rng.random(), rng.random(), rng.random()];
        let len = rng.random::<f64>() * 2.0;
        let piece = Piece { t0: 0.0, t1: len, sigma_t: Cubic::along(sig, ua, ub), e: em.map(|v| Cubic::along(v, ua, ub)) };
        let mut a = Accum::default();
        a.add(&piece, true);
        // Reference: 64 sub-pieces, each re-parametrised to its own [0, 1].
        let mut r = Accum::default();
        for k in 0..64 {
            let (s0, s1) = (k as f64 / 64.0, (k + 1) as f64 / 64.0);
            let at = |s: f64| std::array::from_fn::<f64, 3, _>(|i| ua[i] + (ub[i] - ua[i]) * s);
            let sub = Piece {
                t0: len * s0,
                t1: len * s1,
                sigma_t: Cubic::along(sig, at(s0), at(s1)),
                e: em.map(|v| Cubic::along(v, at(s0), at(s1))),
            };
            r.add(&sub, true);
        }
        assert!((a.tau - r.tau).abs() <= 1e-12 * r.tau.max(1.0), "optical depth is exact");
        for c in 0..3 {
            if r.l[c] > 1e-300 {
                worst = worst.max((a.l[c] - r.l[c]).abs() / r.l[c]);
            }
        }
    }
    eprintln!("worst relative emission quadrature error: {worst:.2e}");
    assert!(worst < 1e-11, "worst relative emission error {worst:.2e}");
}

/// A smooth, optically thick blob: rho = 4 exp(-|u - c|^2 / 36) per km on a
/// 25^3 grid (h = 0.4 km): optical depth about 11 through the centre.
fn blob() -> Grid<f32> {
    let c = DVec3::splat(12.0);
    box_f32(
        IVec3::ZERO,
        IVec3::splat(24),
        |p| (4.0 * fmath::exp(-(p.as_dvec3() - c).length_squared() / 36.0)) as f32,
        Transform::new(0.4, DVec3::ZERO),
    )
}

#[test]
fn fixed_step_error_grows_with_step_size_while_exact_stays_exact() {
    // Emission uniform over the box (not proportional to density, whose
    // L = e/sigma (1 - T) would saturate and hide errors in thick media).
    let d = blob();
    let e = box_vec3(IVec3::ZERO, IVec3::splat(24), |_| [0.5, 0.35, 0.1], d.transform);
    let medium = Medium::new(Some(&d), Some(&e), 1.0, 1.0).unwrap();
    let mut rng = Pcg64::seed_from_u64(15);
    let steps = [0.05, 0.2, 0.8, 3.2]; // km; the voxel is 0.4 km
    let mut err_t = [0.0; 4];
    let mut err_l = [0.0; 4];
    let rays = 60;
    let mut thick = 0;
    for _ in 0..rays {
        // Rays through the blob's core, in random directions.
        let dir = random_dir(&mut rng);
        let through = DVec3::splat(4.8) + DVec3::new(rng.random(), rng.random(), rng.random()) * 1.6 - 0.8;
        let o = through - dir * 20.0;
        let (tau, l) = oracle(Some(&d), Some(&e), 1.0, 1.0, RaySpan { o, d: dir, t_max: f64::INFINITY }, 32);
        if tau > 5.0 {
            thick += 1;
        }
        let exact = radiance_along_ray(&medium, o, dir, f64::INFINITY, Integration::Exact, 0.5);
        assert!(rel(exact.transmittance(), fmath::exp(-tau), 0.0) < 1e-4, "exact T {} vs {}", exact.transmittance(), fmath::exp(-tau));
        assert!(rel(exact.l[0], l[0], 0.0) < 1e-4, "exact L {} vs {}", exact.l[0], l[0]);
        for (k, &h) in steps.iter().enumerate() {
            let off: f64 = rng.random();
            let f = radiance_along_ray(&medium, o, dir, f64::INFINITY, Integration::FixedStep(h), off);
            err_t[k] += rel(f.transmittance(), fmath::exp(-tau), 0.0) / rays as f64;
            err_l[k] += rel(f.l[0], l[0], 0.0) / rays as f64;
        }
    }
    assert!(thick > rays / 2, "the test needs optically thick rays ({thick})");
    for k in 1..4 {
        assert!(err_t[k] > err_t[k - 1], "mean T error must grow with the step: {err_t:?}");
        assert!(err_l[k] > err_l[k - 1], "mean L error must grow with the step: {err_l:?}");
    }
    // The coarsest step is badly wrong in transmittance, the exact one is not.
    assert!(err_t[3] > 0.05, "{err_t:?}");
    eprintln!("fixed-step mean relative error, steps {steps:?} km: T {err_t:?}, L {err_l:?}");
}

#[test]
fn fixed_step_converges_to_exact_on_pixels() {
    // The same scene rendered with both integrators: the fixed-step image
    // approaches the exact one as h shrinks (midpoint rule, O(h^2)).
    let d = blob();
    let c = d.transform.index_to_world(DVec3::splat(12.0));
    let mut s = settings(persp((c + DVec3::new(0.0, -15.0, 2.0)).to_array(), c.to_array(), [0.0, 0.0, 1.0], 40.0), 16, 16, 1);
    s.background.radiance = [1.0; 3];
    let vol = Volume { density: Some(&d), emission: None };
    let exact = render(&s, &vol, &NoProgress).unwrap();
    let mut last = f64::INFINITY;
    for h in [0.8, 0.2, 0.05] {
        s.integration = Integration::FixedStep(h);
        let img = render(&s, &vol, &NoProgress).unwrap();
        let err: f64 = img.pixels.iter().zip(&exact.pixels).map(|(a, b)| (a[0] as f64 - b[0] as f64).abs()).sum::<f64>() / 256.0;
        assert!(err < last, "h = {h}: mean error {err} did not decrease");
        last = err;
    }
    assert!(last < 1e-3, "{last}");
}

/// Brute-force list of dual cells `(corner, t0, t1)` crossed by a ray with a
/// non-zero corner: every index-plane crossing, cell from the midpoint.
fn brute_cells(g: &Grid<f32>, o: DVec3, d: DVec3) -> Vec<(IVec3, f64, f64)> {
    let Some((lo, hi)) = support(g) else { return vec![] };
    let Some((a, b)) = clip(o, d, lo, hi) else { return vec![] };
    let tr = g.transform;
    let mut ts = vec![a, b];
    for k in 0..3 {
        if d[k] == 0.0 {
            continue;
        }
        let ua = (o[k] + d[k] * a - tr.translation[k]) / tr.voxel_size;
        let ub = (o[k] + d[k] * b - tr.translation[k]) / tr.voxel_size;
        for p in (ua.min(ub).ceil() as i64)..=(ua.max(ub).floor() as i64) {
            let t = (p as f64 * tr.voxel_size + tr.translation[k] - o[k]) / d[k];
            if t > a && t < b {
                ts.push(t);
            }
        }
    }
    ts.sort_by(f64::total_cmp);
    let mut out = vec![];
    for w in ts.windows(2) {
        if w[1] - w[0] < 1e-9 {
            continue;
        }
        let c = tr.world_to_index(o + d * (0.5 * (w[0] + w[1]))).floor().as_ivec3();
        let any = (0..8).any(|k| g.get(c + IVec3::new(k >> 2 & 1, k >> 1 & 1, k & 1)) != 0.0);
        if any {
            out.push((c, w[0], w[1]));
        }
    }
    out
}

#[test]
fn dda_visits_exactly_the_non_empty_cells_in_order() {
    let mut rng = Pcg64::seed_from_u64(16);
    let tr = Transform::new(1.0, DVec3::new(0.25, -0.5, 0.125));
    // 24 small clusters spread over +-9000 voxels: more root nodes than the
    // root list handles, so the root-level DDA runs too; plus clusters across
    // leaf, block and super-node boundaries.
    let mut centres = vec![IVec3::new(0, 0, 0), IVec3::new(128, -1, 4095), IVec3::new(-4097, 127, -129)];
    for _ in 0..24 {
        centres.push(IVec3::new(rng.random_range(-9000..9000), rng.random_range(-9000..9000), rng.random_range(-9000..9000)));
    }
    let (g, _) = random_grids(&mut rng, &centres, 2, 1.0, tr);
    let medium = Medium::new(Some(&g), None, 1.0, 1.0).unwrap();
    let field = &medium.fields[0];
    assert!(field.keys.len() > 24);
    let mut checked = 0;
    for i in 0..400 {
        // Rays aimed at one cluster from another (crossing lots of empty space).
        let a = centres[i % centres.len()].as_dvec3() + DVec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
        let b = centres[(i * 7 + 3) % centres.len()].as_dvec3() + DVec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
        let (pa, pb) = (tr.index_to_world(a), tr.index_to_world(b));
        if (pb - pa).length() < 1e-6 {
            continue;
        }
        let d = (pb - pa).normalize();
        let o = pa - d * 10.0;
        let want = brute_cells(&g, o, d);
        let got: Vec<_> = segments(field, o, d, 0.0, f64::INFINITY, CellFilter::Any).collect();
        assert_eq!(got.len(), want.len(), "ray {i}: cell count");
        for (x, y) in got.iter().zip(&want) {
            assert_eq!(x.corner, y.0, "ray {i}: cell order");
            let scale = 1.0 + x.t1.abs();
            assert!((x.t0 - y.1).abs() < 1e-9 * scale && (x.t1 - y.2).abs() < 1e-9 * scale, "ray {i}: span {x:?} vs {y:?}");
        }
        checked += want.len();
    }
    assert!(checked > 2000, "{checked}");
}

#[test]
fn cost_does_not_grow_with_an_empty_bounding_box() {
    // The same few leaves, alone and with one far-away leaf that blows the
    // bounding box up to 800,000 voxels on a side (~1e17 voxels of volume;
    // 0.4e6 km, inside the 1e6 km the renderer places): the image is bit-identical, the accelerator barely grows, and
    // a ray through empty space does the same work however far the far leaf is.
    let tr = Transform::new(0.5, DVec3::ZERO);
    let mut rng = Pcg64::seed_from_u64(17);
    let (near, near_e) = random_grids(&mut rng, &[IVec3::new(4, 4, 4)], 6, 1.0, tr);
    let with_far = |k: i32| {
        let (mut d, mut e) = (near.clone(), near_e.clone());
        let p = IVec3::new(400_000 * k, -400_000 * k, 200_000 * k);
        d.set(p, 1.0);
        e.set(p, [1.0; 3]);
        (d, e, p)
    };
    let c = tr.index_to_world(DVec3::splat(4.0));
    let s = settings(persp((c + DVec3::new(3.0, -20.0, 5.0)).to_array(), c.to_array(), [0.0, 0.0, 1.0], 30.0), 32, 32, 1);
    let a = render(&s, &Volume { density: Some(&near), emission: Some(&near_e) }, &NoProgress).unwrap();
    let (fd, fe, _) = with_far(2);
    let b = render(&s, &Volume { density: Some(&fd), emission: Some(&fe) }, &NoProgress).unwrap();
    assert_eq!(a.pixels, b.pixels);
    assert_eq!(a.stats.volume_work, b.stats.volume_work);
    let ma = Medium::new(Some(&near), Some(&near_e), 1.0, 1.0).unwrap();
    let mb = Medium::new(Some(&fd), Some(&fe), 1.0, 1.0).unwrap();
    // One far voxel adds at most 8 dual leaves (4 channels of 9^3 f32 plus
    // masks) and 8 blocks and super nodes.
    let added = mb.memory_bytes() - ma.memory_bytes();
    assert!(added <= 8 * (4 * 729 * 4 + 140) + 8 * (16 * 16 * 16 + 32 * 32 * 32) * 4, "{added} bytes");
    // Walker steps of rays through the cluster, away from and towards the far voxel.
    let steps = |m: &Medium, far: IVec3| -> [u64; 2] {
        let mut n = [0u64; 2];
        for i in 0..50 {
            let o = c + DVec3::new(-10.0, i as f64 * 0.1 - 2.5, 0.3);
            for (k, dir) in [DVec3::X, (tr.index_to_world(far.as_dvec3()) - o).normalize()].into_iter().enumerate() {
                let mut w = LeafWalker::new(&m.fields[0], o, dir, 0.0, f64::INFINITY);
                for _ in w.by_ref() {}
                n[k] += w.steps;
            }
        }
        n
    };
    let (d1, e1, p1) = with_far(1);
    let (d2, e2, p2) = with_far(2);
    let m1 = Medium::new(Some(&d1), Some(&e1), 1.0, 1.0).unwrap();
    let m2 = Medium::new(Some(&d2), Some(&e2), 1.0, 1.0).unwrap();
    let (s0, s1, s2) = (steps(&ma, p1), steps(&m1, p1), steps(&m2, p2));
    // Away from the far voxel: exactly the work without it (super nodes are
    // clipped to what they hold).
    assert!(s1[0] == s0[0] && s2[0] == s1[0], "{s0:?} {s1:?} {s2:?}");
    // Towards it: the near cluster plus one descent into the far voxel's
    // nodes (<= 3 per level), independent of the distance. (The two
    // directions differ by 1e-5 rad, which may change a step in the cluster.)
    assert!(s1[1] <= s0[0] + s0[1] + 50 * 12 && s2[1].abs_diff(s1[1]) <= 50, "{s0:?} {s1:?} {s2:?}");
}
