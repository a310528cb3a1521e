//! The red trail (`animation.trail_samples`, `aurora::pipeline::red_trail`): a scene that
//! does not move keeps its red; a drifting curtain's 630.0 nm trails its
//! 557.7 nm by about speed x lifetime; the bake is the same whatever the
//! thread count. And the per-line grids after pruning keep exactly the
//! leaves the emission kept (`aurora::pipeline::prune::prune_like`).

use super::lines::{bake_with_one_and, hold_still, line_grid, patch_scene};
use aurora::grid::Grid;
use aurora::pipeline::bake;
use aurora::scene::{AnimationParams, Scene};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;
use std::collections::BTreeSet;

/// The lines' patch scene (one 40 x 16 km curtain, 400 beams, 1 km voxels,
/// nothing pruned) with the green and red lines on grids of their own;
/// nothing moves.
fn still_scene() -> Scene {
    let mut s = patch_scene();
    s.grid.lines = vec!["6300".into(), "5577".into()];
    hold_still(&mut s.animation);
    s
}

/// Largest difference of two grids' values over both active sets, relative
/// to the larger grid's peak.
fn max_rel_diff(a: &Grid<f32>, b: &Grid<f32>) -> f64 {
    let peak = a.iter_active().chain(b.iter_active()).map(|(_, v)| v.abs() as f64).fold(0.0, f64::max);
    let d = a.iter_active().chain(b.iter_active()).map(|(ijk, _)| (a.get(ijk) as f64 - b.get(ijk) as f64).abs()).fold(0.0, f64::max);
    d / peak
}

/// The grid's centroid along y (world km), weighted by its values.
fn centroid_y(g: &Grid<f32>) -> f64 {
    let (mut w, mut wy) = (0.0, 0.0);
    for (ijk, v) in g.iter_active() {
        let p = g.transform.index_to_world(ijk.as_dvec3());
        w += v as f64;
        wy += v as f64 * p.y;
    }
    wy / w
}

#[test]
fn a_still_scene_keeps_its_red_with_the_trail() {
    // Nothing moves: every sample traces the same beams through the same
    // footprints, and the weights sum to 1 (`aurora::pipeline::red_trail`), so each
    // line's photons per second (its grid summed times the voxel volume:
    // the kernel has unit mass whatever the photons) are the steady
    // state's to the f32 rounding of adding 9 photon sets in place of one
    // (1e-5 leaves room). Voxel by voxel the gather's merged runs
    // (`photons::merge`) join the samples' red-only steps into runs other
    // than the one set's, each within its stated bound of the steps' own
    // kernels: measured 4.6e-4 of the peak (the green, one set either
    // way, is identical); 2e-3 holds.
    let s = still_scene();
    let off = bake::bake(&s, &NoProgress).unwrap();
    let mut t = s.clone();
    t.animation.trail_samples = 8;
    let on = bake::bake(&t, &NoProgress).unwrap();
    assert_eq!(on.stats.photons, 9 * off.stats.photons, "one photon set per sample");
    let total = |g: &Grid<f32>| g.iter_active().map(|(_, v)| v as f64).sum::<f64>();
    for key in ["6300", "5577"] {
        let (a, b) = (line_grid(&off, key), line_grid(&on, key));
        let r = total(b) / total(a) - 1.0;
        assert!(r.abs() < 1e-5, "{key}: total {r:+e}");
        let d = max_rel_diff(a, b);
        eprintln!("{key}: total {r:+e}, largest voxel difference {d:e} of the peak");
        assert!(d < 2e-3, "{key}: {d}");
    }
    // The colour grid too: the line table's colour is the colour table's
    // (same yields per node), its red from 9 photon sets.
    let (a, b) = (&off.emission, &on.emission);
    let sum = |g: &Grid<[f32; 3]>, k: usize| g.iter_active().map(|(_, v)| v[k] as f64).sum::<f64>();
    let peak = a.iter_active().map(|(_, v)| v[0].max(v[1]).max(v[2]) as f64).fold(0.0, f64::max);
    for k in 0..3 {
        let r = sum(b, k) / sum(a, k) - 1.0;
        assert!(r.abs() < 1e-5, "channel {k}: total {r:+e}");
    }
    for (ijk, v) in a.iter_active() {
        let w = b.get(ijk);
        for k in 0..3 {
            assert!(((v[k] - w[k]) as f64).abs() < 2e-3 * peak, "{ijk}: {v:?} vs {w:?}");
        }
    }
}

#[test]
fn a_drifting_curtain_leaves_its_red_behind() {
    // Only the drift moves the curtain: y(t) = D sin(2 pi t / T) across its
    // axis, D = 100 km, T = 6000 s, baked at t = 0 where it moves at
    // v = 2 pi D / T = 0.105 km/s towards +y and its path is straight to
    // third order ((omega s)^2 / 6 = 2.7 % at the last lag, 387 s). The
    // green stays at t (0.9 s: 0.1 km); the red sums the curtain's earlier
    // places: its centroid lies behind the same bake's red without the
    // trail (the inclined field already puts the high red elsewhere than
    // the green) by v times the emission-weighted O(1D) lifetime, tau_bar = sum E_z tau_z / sum E_z over the still red's
    // layers. Two checks:
    // - against the samples' own closed form, sum_z E_z sum_k w_k(tau_z)
    //   D sin(omega s_k) / sum E_z: the same deposits, so only the lifetimes'
    //   source differs (the chemistry's per ionization rate against the
    //   neutral-only `line_lifetimes`, which weighs the same deposits) and
    //   the deposits' noise, which both bakes share (same beams): measured
    //   1 %, 10 % allowed;
    // - against the physics, v tau_bar: besides that, the discrete mean lag
    //   is within 10 % of tau from 10 s up and 0.54 of it at 1.5 s
    //   (`aurora::pipeline::red_trail` tests), with the red's weighted lifetime 46 s:
    //   measured 5 % short, 15 % allowed.
    let mut s = still_scene();
    let (d, period) = (100.0, 6000.0);
    s.animation.drift_km = d;
    s.animation.drift_period_s = period;
    s.animation.trail_samples = 8;
    let on = bake::bake(&s, &NoProgress).unwrap();
    let mut still = s.clone();
    still.animation.trail_samples = 0;
    let off = bake::bake(&still, &NoProgress).unwrap();

    let lag = centroid_y(line_grid(&off, "6300")) - centroid_y(line_grid(&on, "6300"));
    let green_shift = centroid_y(line_grid(&on, "5577")) - centroid_y(line_grid(&off, "5577"));
    assert!(green_shift.abs() < 0.05, "the green stays at t: {green_shift} km");

    let atm = aurora::pipeline::plan::atmosphere(&s);
    let omega = std::f64::consts::TAU / period;
    let v = omega * d;
    let samples = aurora::pipeline::red_trail::samples(8);
    let (mut e_sum, mut tau_sum, mut lag_sum) = (0.0, 0.0, 0.0);
    let red = line_grid(&off, "6300");
    for (ijk, e) in red.iter_active() {
        let z = red.transform.index_to_world(ijk.as_dvec3()).z;
        let tau = aurora::physics::emission::line_table::line_lifetimes(&atm, z)[1];
        let e = e as f64;
        e_sum += e;
        tau_sum += e * tau;
        lag_sum += e * samples.iter().map(|k| k.weight(tau, None) * d * fmath::sin(omega * k.lag_s)).sum::<f64>();
    }
    let (tau_bar, want) = (tau_sum / e_sum, lag_sum / e_sum);
    eprintln!("red lag {lag:.3} km; the samples' closed form {want:.3} km; v tau_bar {:.3} km (tau_bar {tau_bar:.1} s)", v * tau_bar);
    assert!(lag > 0.0, "the red lies behind (towards -y): {lag} km");
    assert!((lag / want - 1.0).abs() < 0.10, "lag {lag:.3} km vs the samples' {want:.3} km");
    assert!((lag / (v * tau_bar) - 1.0).abs() < 0.15, "lag {lag:.3} km vs v tau_bar = {v:.4} x {tau_bar:.1} s");
}

#[test]
fn the_trail_is_the_same_whatever_the_thread_count() {
    let mut s = still_scene();
    s.animation = AnimationParams { drift_km: 20.0, fold_speed_kms: 3.0, trail_samples: 3, ..s.animation };
    s.beams.count = 200;
    let (a, b) = bake_with_one_and(2, &s);
    assert!(a.emission == b.emission, "emission differs with the thread count");
}

#[test]
fn pruned_per_line_grids_keep_the_leaves_the_emission_kept() {
    // The rule (`aurora::pipeline::prune`): a line grid keeps exactly its own leaves
    // whose origin the pruned emission kept. With the trail the green lacks
    // leaves the red has, so the line grids' leaf sets differ; each must be
    // its unpruned set intersected with the emission's kept set.
    let mut s = still_scene();
    s.animation = AnimationParams { drift_km: 30.0, drift_period_s: 600.0, trail_samples: 4, ..s.animation };
    // The Cycles shell dilates the emission after pruning: without it the
    // file's emission leaves are the kept ones.
    s.grid.cycles_shell = false;
    let full = bake::bake(&s, &NoProgress).unwrap();
    s.grid.prune = 0.05;
    let pruned = bake::bake(&s, &NoProgress).unwrap();
    let st = pruned.stats.prune.as_ref().expect("pruned");
    assert!(st.leaves_removed > 0, "the budget drops leaves: {st:?}");
    let origins = |g: &Grid<f32>| g.leaves().iter().map(|l| l.origin.to_array()).collect::<BTreeSet<_>>();
    let kept: BTreeSet<[i32; 3]> = pruned.emission.leaves().iter().map(|l| l.origin.to_array()).collect();
    for key in ["6300", "5577"] {
        let before = origins(line_grid(&full, key));
        let after = origins(line_grid(&pruned, key));
        let want: BTreeSet<[i32; 3]> = before.intersection(&kept).cloned().collect();
        assert_eq!(after, want, "{key}");
        assert!(after.len() < before.len(), "{key}: pruning dropped some of its leaves");
        // The kept leaves hold the unpruned values.
        for l in line_grid(&pruned, key).leaves() {
            assert!(line_grid(&full, key).leaf(l.origin) == Some(l), "{key}: leaf {} changed", l.origin);
        }
    }
    assert!(origins(line_grid(&full, "5577")) != origins(line_grid(&full, "6300")), "the trail's red reaches leaves the green does not");
}
