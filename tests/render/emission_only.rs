//! The emission-only path (`src/render/emission_only.rs`): taken exactly
//! when the medium has no extinction, and then equal to the general walk.
//!
//! Tolerance: both paths integrate the same cubic exactly on the same dual
//! cells (the general one by its coefficients, the emission-only one by
//! Simpson's rule on the corner weights), so they differ by rounding only:
//! a few ulps per cell, some 1e-15 relative over the tens of cells a ray
//! crosses here. 1e-12 relative (plus 1e-15 absolute for values that
//! vanish) leaves three orders of magnitude of margin and is still far
//! below anything a picture shows.

use aurora::grid::{Grid, Transform};
use aurora::render::{
    primary_path, radiance_along_ray, radiance_general, render, Integration, Medium, PrimaryPath, RenderSettings, Volume,
};
use aurora::util::progress::NoProgress;
use glam::{DVec3, IVec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A sparse cluster of random voxels (about 40 % of a box) around `centre`,
/// straddling leaf boundaries; `empty_density` leaves the density grid
/// without a voxel.
fn grids(seed: u64, centre: IVec3, tr: Transform, empty_density: bool) -> (Grid<f32>, Grid<[f32; 3]>) {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut d = Grid::new("density", 0.0f32, tr);
    let mut e = Grid::new("emission", [0.0f32; 3], tr);
    for x in -6..=6 {
        for y in -6..=6 {
            for z in -6..=6 {
                let p = centre + IVec3::new(x, y, z);
                if rng.random::<f64>() < 0.4 {
                    e.set(p, [rng.random::<f32>(), rng.random::<f32>() * 2.0, rng.random::<f32>() * 0.5]);
                }
                if !empty_density && rng.random::<f64>() < 0.4 {
                    d.set(p, rng.random::<f32>() * 3.0);
                }
            }
        }
    }
    (d, e)
}

/// Rays through (near) the cluster from outside and from inside, with a
/// finite or an infinite end.
fn rays(seed: u64, centre: DVec3, n: usize) -> Vec<(DVec3, DVec3, f64)> {
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let dir = loop {
                let v = DVec3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
                if v.length() > 0.05 {
                    break v.normalize();
                }
            };
            let target = centre + DVec3::new(rng.random(), rng.random(), rng.random()) * 5.0 - 2.5;
            let inside = rng.random::<f64>() < 0.3;
            let origin = if inside { target } else { target - dir * 20.0 };
            let t_max = if rng.random::<f64>() < 0.5 { f64::INFINITY } else { 25.0 * rng.random::<f64>() };
            (origin, dir, t_max)
        })
        .collect()
}

#[test]
fn emission_only_path_matches_the_general_path_without_extinction() {
    let tr = Transform::new(0.4, DVec3::new(0.3, -0.2, 0.1));
    let other = Transform::new(0.55, DVec3::new(-0.1, 0.2, 0.0));
    let centre = IVec3::new(7, -1, 15);
    let world = tr.index_to_world(centre.as_dvec3());
    let (d, e) = grids(1, centre, tr, false);
    let (empty, _) = grids(1, centre, tr, true);
    let (d_other, _) = grids(2, IVec3::new(5, -1, 11), other, false);
    // No density grid; an empty one; a full one at density_scale 0, on the
    // emission's transform (one four-channel field) and on another.
    let cases: [(&str, Option<&Grid<f32>>, f64); 4] = [
        ("no density", None, 1.0),
        ("empty density", Some(&empty), 1.0),
        ("scale 0", Some(&d), 0.0),
        ("scale 0, own transform", Some(&d_other), 0.0),
    ];
    for (name, density, ds) in cases {
        let m = Medium::new(density, Some(&e), ds, 1.7).unwrap();
        assert_eq!(primary_path(&m), PrimaryPath::EmissionOnly, "{name}");
        let mut lit = 0;
        for (o, dir, t_max) in rays(3, world, 400) {
            let fast = radiance_along_ray(&m, o, dir, t_max, Integration::Exact, 0.5);
            let general = radiance_general(&m, o, dir, t_max);
            assert_eq!((fast.tau, general.tau), (0.0, 0.0), "{name}");
            for c in 0..3 {
                let (a, b) = (fast.l[c], general.l[c]);
                assert!((a - b).abs() <= 1e-12 * b + 1e-15, "{name}: L[{c}] {a} vs general {b} (ray {o} {dir} {t_max})");
            }
            lit += (general.l[1] > 0.0) as usize;
        }
        assert!(lit > 200, "{name}: only {lit} rays met the emission");
    }
}

#[test]
fn emission_only_path_is_not_taken_with_extinction() {
    let tr = Transform::new(0.4, DVec3::ZERO);
    let centre = IVec3::new(-3, 4, 9);
    let (d, e) = grids(4, centre, tr, false);
    let m = Medium::new(Some(&d), Some(&e), 0.8, 1.0).unwrap();
    assert_eq!(primary_path(&m), PrimaryPath::General);
    // The primary ray is the general walk's, bit for bit, with its optical
    // depth: on these rays the extinction takes a visible part of the light,
    // which the emission-only integral would have missed.
    let unlit = Medium::new(None, Some(&e), 1.0, 1.0).unwrap();
    let mut dimmed = 0;
    for (o, dir, t_max) in rays(5, tr.index_to_world(centre.as_dvec3()), 300) {
        let got = radiance_along_ray(&m, o, dir, t_max, Integration::Exact, 0.5);
        assert_eq!(got, radiance_general(&m, o, dir, t_max));
        let bare = radiance_along_ray(&unlit, o, dir, t_max, Integration::Exact, 0.5);
        if got.tau > 0.1 && got.l[1] < 0.95 * bare.l[1] {
            dimmed += 1;
        }
    }
    assert!(dimmed > 100, "only {dimmed} rays dimmed by the density");
}

/// A whole picture (the pixel loop, the air, the background behind): with
/// the density at scale 0 the emission-only path, with a density scale so
/// small that the transmittance differs from 1 by under 1e-9 the general
/// walk; the pixels agree to that 1e-9 plus rounding.
#[test]
fn emission_only_picture_matches_the_general_walk() {
    let tr = Transform::new(0.5, DVec3::ZERO);
    let (d, e) = grids(6, IVec3::new(2, 0, 8), tr, false);
    let mut scene = aurora::scene::Scene::default();
    scene.terrain.kind = aurora::scene::TerrainKind::None;
    (scene.render.width, scene.render.height, scene.render.spp) = (24, 16, 2);
    scene.camera.position = [1.0, -20.0, 4.0];
    scene.camera.look_at = [1.0, 0.0, 4.0];
    let image = |ds: f64| {
        let mut s = RenderSettings::from_scene(&scene);
        s.volume.density_scale = ds;
        render(&s, &Volume { density: Some(&d), emission: Some(&e) }, &NoProgress).unwrap()
    };
    assert_eq!(primary_path(&Medium::new(Some(&d), Some(&e), 1e-12, 1.0).unwrap()), PrimaryPath::General);
    let (fast, general) = (image(0.0), image(1e-12));
    let peak = general.pixels.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    assert!(peak > 0.0);
    for (a, b) in fast.pixels.iter().zip(&general.pixels) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 1e-6 * b[c].abs() + 1e-9 * peak, "{a:?} vs {b:?}");
        }
    }
}
