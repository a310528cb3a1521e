//! The bake's last stage, [`finish`]: the emission's checks (every value
//! finite, the f32 and half-float ranges), then with `grid.prune > 0` the
//! leaves faintest at the camera dropped within that error budget
//! ([`crate::pipeline::prune`]; the per-line grids keep the leaves the
//! emission kept); the density grid on the (kept) active voxels
//! ([`super::density::density_grid`]); the velocity grid on them
//! ([`super::velocity::velocity_grid`]); with `grid.cycles_shell`, every
//! grid dilated by one voxel of active zeros
//! ([`crate::grid::Grid::dilate_active`]); and the stats. Emission that
//! overflows f32 is an error, never a file.

use super::density::{density_grid, extinction_warning};
use super::gather::{sum_power, Gathered};
use super::result::{empty_reason, Bake, BakeError};
use super::stats::{BakeStats, StageTimes};
use crate::grid::{Grid, Leaf};
use crate::pipeline::plan::BakePlan;
use crate::pipeline::prune;
use crate::util::colour::luminance;
use crate::util::progress::Progress;
use rayon::prelude::*;
use std::time::Instant;

/// The emission's checks and peaks, the first step of [`finish`]: every
/// active value finite (else [`BakeError::NonFinite`] at the first bad voxel
/// in leaf order), and the largest component and luminance. Per leaf in parallel; the first error in
/// leaf order wins and maxima do not depend on the order, so the outcome is
/// the same whatever the thread count.
pub fn scan_emission(emission: &Grid<[f32; 3]>, radius_km: f64) -> Result<([f32; 3], f64), BakeError> {
    let per_leaf: Vec<Result<([f32; 3], f64), BakeError>> = emission
        .leaves()
        .par_iter()
        .map(|l| {
            let mut peak = [0.0f32; 3];
            let mut peak_y = 0.0f64;
            for (ijk, v) in l.iter_active() {
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(BakeError::NonFinite { ijk: ijk.to_array(), value: format!("{v:?}"), radius_km });
                }
                for k in 0..3 {
                    peak[k] = peak[k].max(v[k]);
                }
                peak_y = peak_y.max(luminance([v[0] as f64, v[1] as f64, v[2] as f64]));
            }
            Ok((peak, peak_y))
        })
        .collect();
    let mut peak = [0.0f32; 3];
    let mut peak_y = 0.0f64;
    for r in per_leaf {
        let (p, y) = r?;
        for k in 0..3 {
            peak[k] = peak[k].max(p[k]);
        }
        peak_y = peak_y.max(y);
    }
    Ok((peak, peak_y))
}

/// Where `grid.half_emission` or `grid.half_density` asks for half floats
/// a grid's values exceed (|x| > 65504, the largest half): that grid is
/// written as full floats ([`crate::io::bake_folder::fit_half`]) and the bake says so.
fn half_warnings(grid: &crate::scene::GridParams, peak: [f32; 3], density: &Grid<f32>) -> Vec<String> {
    let max = half::f16::MAX.to_f32();
    let mut w = Vec::new();
    let e = peak.iter().fold(0.0f32, |m, x| m.max(*x));
    if grid.half_emission && e > max {
        w.push(format!("the emission reaches {e} (beyond the half-float range, |x| <= 65504): `emission` is stored as full floats although grid.half_emission = true"));
    }
    if grid.half_density {
        let d = density.iter_active().fold(0.0f32, |m, (_, x)| m.max(x.abs()));
        if d > max {
            w.push(format!("the density reaches {d} (beyond the half-float range, |x| <= 65504): `density` is stored as full floats although grid.half_density = true"));
        }
    }
    w
}

/// Stage 4: checks the emission, prunes it, builds the density grid and the
/// Cycles shell, and the stats. `times.prune`, `times.density` are filled
/// in; `times.total` is the time since `t_all`.
pub fn finish(
    plan: &BakePlan,
    emission: Grid<[f32; 3]>,
    g: Gathered,
    times: StageTimes,
    t_all: Instant,
    progress: &dyn Progress,
) -> Result<Bake, BakeError> {
    finish_keeping(plan, emission, g, times, t_all, progress).map(|(b, _)| b)
}

/// The leaves pruning dropped, in leaf order ([`finish_keeping`]).
pub type DroppedLeaves = Vec<Leaf<[f32; 3]>>;

/// [`finish`], also returning the leaves pruning dropped (leaf order; none
/// when `grid.prune` is 0). Without the Cycles shell the bake's emission
/// and these leaves are the gathered grid, so a caller that refinishes
/// (the preview, after a camera or grid edit) keeps them instead of a copy
/// of the gathered grid ([`Grid::restore_leaves`]).
pub fn finish_keeping(
    plan: &BakePlan,
    emission: Grid<[f32; 3]>,
    g: Gathered,
    mut times: StageTimes,
    t_all: Instant,
    progress: &dyn Progress,
) -> Result<(Bake, DroppedLeaves), BakeError> {
    let Gathered { photons, mut lines, beam_stats, voxel_km: vs, voxel_source: vs_source, mut warnings, noise, velocity, photon_totals } =
        g;
    if emission.leaf_count() == 0 {
        return Err(BakeError::Empty(empty_reason(&beam_stats, &plan.scene.beams)));
    }
    let transform = emission.transform;

    let t = Instant::now();
    let (peak, peak_y) = scan_emission(&emission, plan.kernel.base_km)?;
    if let Some((lo, hi)) = emission.index_bbox() {
        // The lowest altitude in the grid's box: at the box's point nearest
        // the Earth's centre (the lowest z when flat).
        let (lo, hi) = (transform.index_to_world(lo.as_dvec3()), transform.index_to_world(hi.as_dvec3()));
        let earth = plan.earth();
        let h_min = if earth.is_flat() { lo.z } else { earth.altitude(earth.centre().clamp(lo, hi)) };
        warnings.extend(extinction_warning(&plan.scene.grid, h_min));
    }
    let scan_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut emission = emission;
    let (prune_stats, dropped) = if plan.scene.grid.prune > 0.0 {
        let camera = plan.camera_model()?;
        let (st, dropped) = prune::prune_keeping(&mut emission, &camera, plan.scene.grid.prune);
        // The per-line grids keep the leaves the emission kept (crate::pipeline::prune).
        for g in &mut lines {
            prune::prune_like(g, &emission);
        }
        (Some(st), dropped)
    } else {
        (None, Vec::new())
    };
    times.prune = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.start("density", emission.leaf_count() as u64);
    let mut density = density_grid(&emission, &plan.scene.grid, peak_y, &plan.earth());
    progress.inc(emission.leaf_count() as u64);
    progress.finish();
    warnings.extend(half_warnings(&plan.scene.grid, peak, &density));
    let (aurora_voxels, aurora_leaves) = (emission.active_voxel_count(), emission.leaf_count());
    // On the kept voxels, before the shell (whose zeros are at rest).
    let mut velocity = velocity.map(|num| super::velocity::velocity_grid(&emission, &num));
    let shell_voxels = if plan.scene.grid.cycles_shell {
        // Both grids live on the same voxels: the density takes the
        // emission's dilation rather than computing it again.
        let n = emission.dilate_active();
        let m = density.activate_like(&emission);
        debug_assert_eq!(n, m, "both grids live on the same voxels");
        if let Some(v) = velocity.as_mut() {
            v.activate_like(&emission);
        }
        n
    } else {
        0
    };
    times.density = scan_s + t.elapsed().as_secs_f64();
    times.total = t_all.elapsed().as_secs_f64();

    let (photon_count, total) = photon_totals.unwrap_or_else(|| (photons.len(), sum_power(&photons, [0.0; 3])));
    let bbox = emission.index_bbox();
    let stats = BakeStats {
        units: "km",
        seed: plan.scene.seed,
        scene_hash: plan.scene_hash.clone(),
        voxel_size_km: vs,
        voxel_size_source: vs_source,
        gather: plan.scene.photons.gather,
        beams: beam_stats.beams,
        photons: photon_count,
        active_voxels: aurora_voxels,
        leaves: aurora_leaves,
        shell_voxels,
        file_voxels: emission.active_voxel_count(),
        file_leaves: emission.leaf_count(),
        index_bbox: bbox.map(|(a, b)| [a.to_array(), b.to_array()]),
        world_bbox: bbox
            .map(|(a, b)| [transform.index_to_world(a.as_dvec3()).to_array(), transform.index_to_world(b.as_dvec3()).to_array()]),
        peak_emission: peak,
        peak_luminance: peak_y,
        total_emitted_power: total,
        total_emitted_luminance: luminance(total),
        electron_power_w: beam_stats.power.electron_power_w,
        deposited_power_w: beam_stats.power.deposited_power_w,
        deposited_fraction: beam_stats.power.deposited_fraction,
        beam_stats,
        times_s: times,
        noise,
        prune: prune_stats,
        warnings,
    };
    Ok((Bake { emission, density, lines, velocity, photons, stats }, dropped))
}
