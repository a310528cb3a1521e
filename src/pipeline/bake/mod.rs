//! The bake: scene -> footprints -> beams -> photons -> grids.
//!
//! [`bake`] composes the stages for a scene: the field's check, a
//! [`BakePlan`] (`crate::pipeline::plan`: footprints, atmosphere, colour
//! table, field, kernel radius field, chunks), the memory check on that
//! plan before any beam is traced (`crate::pipeline::memory`), the beam
//! count ([`beam_count`]: from `beams.count`, or from the [`pilot`] when
//! `beams.target_noise > 0`), then [`trace`] and [`gather`] a chunk of
//! beams at a time (so the memory does not grow with the beams) and
//! [`finish`]. [`bake_plan`] does the same from a plan already built
//! (frame sequences reuse one, [`bake_reusing`]).
//!
//! The rooms: [`trace`] the beams a chunk at a time; [`gather`] the grids
//! from their photons (the one trace-and-gather); [`finish`] the checks,
//! pruning, density, velocity, shell and stats; [`density`] the density
//! grid and the air extinction; [`velocity`] the velocity grid; [`stats`]
//! the numbers written as bake.json; [`pilot`] the beam count from a target
//! noise and the deposition check; [`result`] what a bake returns, [`Bake`]
//! or [`BakeError`]; [`identity`] what makes two bakes the same. Here: the
//! composition. `aurora preview` and the bench call the stages one by one.
//!
//! Grid transform: translation 0, so voxel (i, j, k) is centred at
//! `voxel_size * (i, j, k)` km (`crate::pipeline::voxel::grid_transform`).

pub mod density;
pub mod finish;
pub mod gather;
pub mod identity;
pub mod pilot;
pub mod result;
pub mod stats;
pub mod trace;
pub mod velocity;

pub use result::{empty_reason, Bake, BakeError};

use crate::pipeline::memory;
use crate::pipeline::plan::BakePlan;
use crate::scene::Scene;
use crate::util::progress::Progress;
use stats::{NoiseEstimate, StageTimes};
use std::time::Instant;

/// Refuses a bake whose beams cannot go down (a field within their
/// deflection cone of the horizontal, [`crate::pipeline::beams::dip`]: its
/// memory has no bound) or whose plan would need more memory than this
/// process may use (`crate::pipeline::memory::refusal`). Runs after the
/// plan is built (its footprints cost some MB) and before any beam is
/// traced.
pub fn check_memory(plan: &BakePlan) -> Result<(), BakeError> {
    let s = &plan.scene;
    crate::pipeline::beams::dip::check_field(&s.curtains, &s.beams, &s.earth, plan.site_field.as_ref())?;
    memory::refusal::check(plan, &crate::util::memory::available())?;
    Ok(())
}

/// Runs every stage of the bake for a validated scene: the field's check,
/// the plan (the footprints), the memory check on that plan, the rest.
pub fn bake(scene: &Scene, progress: &dyn Progress) -> Result<Bake, BakeError> {
    bake_reusing(scene, None, progress).map(|(b, _)| b)
}

/// [`bake`] reusing what it can of a previous plan ([`BakePlan::reusing`]:
/// a frame sequence, where only the time changes, keeps the atmosphere and
/// colour table); returns the bake and its plan, for the next call.
pub fn bake_reusing(scene: &Scene, prev: Option<&BakePlan>, progress: &dyn Progress) -> Result<(Bake, BakePlan), BakeError> {
    let t_all = Instant::now();
    crate::pipeline::beams::dip::check_scene_field(scene)?;
    let plan = match prev {
        Some(p) => BakePlan::reusing(scene, p, progress),
        None => BakePlan::new(scene, progress),
    };
    check_memory(&plan)?;
    Ok((bake_plan(&plan, t_all, progress)?, plan))
}

/// Runs the pilot (when `beams.target_noise > 0`), trace, gather and finish
/// on a plan; the stats' total time runs from `t_all`, the footprints' is
/// the plan's.
pub fn bake_plan(plan: &BakePlan, t_all: Instant, progress: &dyn Progress) -> Result<Bake, BakeError> {
    let mut times = StageTimes { footprints: plan.footprint_seconds, ..StageTimes::default() };
    let (count, noise, warnings) = beam_count(plan, &mut times, progress)?;
    let (emission, gathered) = gather::trace_and_gather(plan, count, noise, warnings, &mut times, progress)?;
    if progress.cancelled() {
        return Err(crate::pipeline::beams::BeamError::Cancelled.into());
    }
    finish::finish(plan, emission, gathered, times, t_all, progress)
}

/// The beam count: `beams.count`, or the pilot's when `beams.target_noise >
/// 0` (with its estimate, and a warning when `beams.count` capped it);
/// first the deposition pilot refuses a curtain whose beams would not
/// deposit ([`pilot::check_deposition`]). `times.pilot` is filled in.
pub fn beam_count(
    plan: &BakePlan,
    times: &mut StageTimes,
    progress: &dyn Progress,
) -> Result<(usize, Option<NoiseEstimate>, Vec<String>), BakeError> {
    let t = Instant::now();
    pilot::check_deposition(plan)?;
    times.pilot = t.elapsed().as_secs_f64();
    let target = plan.scene.beams.target_noise;
    if target <= 0.0 {
        return Ok((plan.scene.beams.count, None, Vec::new()));
    }
    let mut warnings = Vec::new();
    let t = Instant::now();
    progress.start("pilot (beams.target_noise)", 1);
    let est = pilot::beams_for_noise(plan, target)?;
    progress.inc(1);
    progress.finish();
    times.pilot += t.elapsed().as_secs_f64();
    if est.capped {
        warnings.push(format!(
            "beams.target_noise = {} needs {:.0} beams (pilot: {:.3} relative RMS noise at {} beams); capped at beams.count = {}, expected noise {:.3}: raise beams.count to reach the target",
            est.target, est.beams_needed, est.pilot_noise, est.pilot_beams, est.beams, est.expected_noise
        ));
    }
    Ok((est.beams, Some(est), warnings))
}

#[cfg(test)]
mod tests {
    use super::density::{extinction, extinction_warning, MAX_EXTINCTION_PER_KM};
    use super::*;
    use crate::grid::Grid;
    use crate::scene::{ColourMode, GatherMethod, GridParams};
    use crate::util::fmath;
    use crate::util::progress::NoProgress;

    /// A small, fast scene: one short curtain, few beams, coarse voxels.
    fn small_scene() -> Scene {
        crate::scene::presets::small_test_scene()
    }

    #[test]
    fn bake_is_deterministic_across_thread_counts() {
        let s = small_scene();
        let run =
            |threads| rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| bake(&s, &NoProgress).unwrap());
        let (a, b) = (run(1), run(2));
        assert_eq!(a.photons, b.photons);
        assert_eq!(a.emission, b.emission);
        assert_eq!(a.density, b.density);
        assert!(a.stats.photons > 10_000, "{}", a.stats.photons);
    }

    #[test]
    fn emission_integrates_to_the_photon_power() {
        // With a constant radius the kernel integrates to 1, so
        // sum(emission) voxel^3 = sum(Phi) / 1e19. The voxel sum of a Gaussian
        // of sd = 1 voxel matches its integral to ~1e-8 (Poisson summation);
        // the truncation sphere cuts voxels, an error of order
        // K(c r) * (surface * voxel) ~ 1e-3 per photon, averaging out: 0.5 %.
        let mut s = small_scene();
        s.photons.radius_noise = 0.0;
        // Pruning drops the faintest leaves and their power (0.5 % of the
        // blue with the default atmosphere): off, the sum is the kernel's.
        s.grid.prune = 0.0;
        let b = bake(&s, &NoProgress).unwrap();
        let v3 = fmath::powi(b.stats.voxel_size_km, 3);
        let mut sum = [0.0f64; 3];
        for (_, v) in b.emission.iter_active() {
            for (t, &c) in sum.iter_mut().zip(&v) {
                *t += c as f64 * v3;
            }
        }
        for (k, (&got, &power)) in sum.iter().zip(&b.stats.total_emitted_power).enumerate() {
            let want = power / 1e19;
            assert!((got / want - 1.0).abs() < 5e-3, "component {k}: {got} vs {want}");
        }
    }

    #[test]
    fn density_lives_on_the_emission_voxels_and_stats_are_consistent() {
        // The default, physical air: optically thin, an empty density grid.
        let b = bake(&small_scene(), &NoProgress).unwrap();
        assert_eq!(b.density.leaf_count(), 0);
        assert!(b.emission.leaf_count() > 0);
        // The artistic air: density on every emission voxel.
        let mut s = small_scene();
        s.grid.density_a = 0.02;
        let b = bake(&s, &NoProgress).unwrap();
        assert_eq!(b.density.active_voxel_count(), b.emission.active_voxel_count());
        for (ijk, d) in b.density.iter_active() {
            assert!(b.emission.is_active(ijk));
            assert!(d.is_finite() && d >= 0.0);
        }
        assert!(b.emission.first_non_finite().is_none());
        // The aurora's voxels (non-zero emission) plus the Cycles shell (zeros).
        let nonzero = b.emission.iter_active().filter(|(_, v)| *v != [0.0; 3]).count() as u64;
        assert_eq!(b.stats.active_voxels, nonzero);
        assert_eq!(b.stats.active_voxels + b.stats.shell_voxels, b.emission.active_voxel_count());
        assert_eq!(b.stats.file_voxels, b.emission.active_voxel_count());
        assert_eq!(b.stats.file_leaves, b.emission.leaf_count());
        // The shell is exactly the 26-neighbourhood of the non-zero voxels.
        for (ijk, v) in b.emission.iter_active() {
            let near =
                (-1..=1).any(|dx| (-1..=1).any(|dy| (-1..=1).any(|dz| b.emission.get(ijk + glam::IVec3::new(dx, dy, dz)) != [0.0; 3])));
            assert!(near, "active voxel {ijk} = {v:?} is not next to the aurora");
        }
        assert_eq!(b.stats.photons, b.photons.len());
        // Energy bookkeeping: deposited <= electron power.
        assert!(b.stats.deposited_power_w <= b.stats.electron_power_w * (1.0 + 1e-9));
        let json = serde_json::to_string(&b.stats).unwrap();
        assert!(json.contains("\"units\":\"km\""));
        // Voxel centres on the lattice voxel_size * ijk.
        let (lo, _) = b.emission.index_bbox().unwrap();
        assert_eq!(b.emission.transform.index_to_world(lo.as_dvec3()), lo.as_dvec3() * b.stats.voxel_size_km);
    }

    #[test]
    fn gather_methods_and_colour_map_mode_bake() {
        // splat (sample-point radius) and kdtree (balloon radius) estimate the
        // same density: with radius noise their totals agree to the noise's
        // effect on normalisation (a few percent), and both conserve power.
        let mut s = small_scene();
        let a = bake(&s, &NoProgress).unwrap();
        s.photons.gather = GatherMethod::Splat;
        let b = bake(&s, &NoProgress).unwrap();
        let total = |g: &Grid<[f32; 3]>| g.iter_active().map(|(_, v)| v[1] as f64).sum::<f64>();
        let (ta, tb) = (total(&a.emission), total(&b.emission));
        assert!((ta / tb - 1.0).abs() < 0.05, "{ta} vs {tb}");
        // report2014 averages colours: its values are photon powers / 1e19,
        // bounded by the largest photon's.
        s.photons.gather = GatherMethod::Report2014;
        let c = bake(&s, &NoProgress).unwrap();
        let max_photon = c.photons.iter().map(|p| p.power[1]).fold(0.0f32, f32::max) as f64 / 1e19;
        assert!(c.emission.iter_active().all(|(_, v)| (v[1] as f64) <= max_photon * (1.0 + 1e-5)));
        // Artist colour map: a constant blue map gives blue everywhere.
        s.photons.gather = GatherMethod::Kdtree;
        s.colour.mode = ColourMode::Colormap;
        s.colour.colormap = vec![[80.0, 0.0, 0.0, 1.0], [400.0, 0.0, 0.0, 1.0]];
        s.grid.cycles_shell = false;
        let d = bake(&s, &NoProgress).unwrap();
        assert!(d.emission.iter_active().all(|(_, v)| v[0] == 0.0 && v[1] == 0.0 && v[2] > 0.0));
    }

    #[test]
    fn a_resolved_bake_has_no_warnings() {
        // small_scene: r_min = 1.0 * 0.7 = 0.7 km >= half of the 1 km voxel,
        // and the band (band_fraction 0.08 of 16 km, spread by the fluid) is
        // wider than a voxel.
        let b = bake(&small_scene(), &NoProgress).unwrap();
        assert!(b.stats.warnings.is_empty(), "{:?}", b.stats.warnings);
    }

    #[test]
    fn steep_air_density_is_clamped_and_warned_never_infinite() {
        // exp(-10 (h - 10^6)) overflows f64 for any altitude of the grid.
        let mut s = small_scene();
        s.grid.density_a = 0.02;
        s.grid.density_b = 10.0;
        s.grid.density_base_km = 1e6;
        let b = bake(&s, &NoProgress).unwrap();
        assert!(b.density.first_non_finite().is_none());
        let max = b.density.iter_active().map(|(_, d)| d).fold(0.0f32, f32::max);
        assert_eq!(max, MAX_EXTINCTION_PER_KM as f32, "the peak voxel's indicator is 1 - e^-100 = 1 in f64");
        assert!(b.stats.warnings.iter().any(|w| w.starts_with("air extinction clamped")), "{:?}", b.stats.warnings);
        // density_a = 0 gives 0, not 0 * inf = NaN.
        s.grid.density_a = 0.0;
        let b = bake(&s, &NoProgress).unwrap();
        assert!(b.density.iter_active().all(|(_, d)| d == 0.0));
        assert!(b.stats.warnings.is_empty(), "{:?}", b.stats.warnings);
        assert_eq!(extinction(&s.grid, 100.0), 0.0);
        // The artistic profile is far below the clamp: no warning, the formula.
        let p = GridParams { density_a: 0.02, ..GridParams::default() };
        assert_eq!(extinction(&p, 100.0), p.density_a * fmath::exp(-p.density_b * (100.0 - p.density_base_km)));
        assert!(extinction_warning(&p, 60.0).is_none());
    }

    #[test]
    fn power_accounting_closes_and_deposits_match_electron_power_less_backscatter() {
        // Expected deposition: every beam finishes (no undeposited power),
        // each curtain's electron power splits exactly into deposited +
        // backscattered (Fang's 1 - G(inf)) + above the beams' top, and the
        // deposit matches electron power less those within 1 % (it is exact
        // up to rounding: telescoping sums).
        let s = small_scene();
        let b = bake(&s, &NoProgress).unwrap();
        let st = &b.stats.beam_stats;
        assert_eq!(st.curtains.len(), 1);
        assert_eq!((st.ended_left_footprint, st.ended_max_steps, st.ended_bottom), (0, 0, 0));
        for c in &st.curtains {
            let sum = c.deposited_power_w + c.backscattered_power_w + c.above_top_power_w + c.undeposited_power_w;
            assert!((sum / c.electron_power_w - 1.0).abs() < 1e-9, "{c:?}");
            assert_eq!(c.undeposited_power_w, 0.0);
            let g = crate::physics::deposition::curtain_spectrum::deposition(
                &s.curtains[0],
                crate::physics::deposition::curtain_spectrum::Population::Body,
            );
            assert!((c.backscattered_power_w / c.electron_power_w - (1.0 - g.total())).abs() < 1e-9, "{c:?}");
            let expect = c.electron_power_w - c.backscattered_power_w - c.above_top_power_w;
            assert!((c.deposited_power_w / expect - 1.0).abs() < 0.01, "{c:?}");
            // Soft electrons above 260 km: a few percent at most.
            assert!(c.above_top_power_w < 0.05 * c.electron_power_w, "{c:?}");
        }
        assert!((b.stats.deposited_power_w - st.power.deposited_power_w).abs() < 1e-9 * st.power.deposited_power_w);
        // The photons carry the deposited energy: total luminance > 0 and the
        // stats agree with the per-curtain sums.
        assert!((st.power.electron_power_w - st.curtains[0].electron_power_w).abs() < 1e-9 * st.power.electron_power_w);
        // CSDA stops by its own rules, and reports what they leave.
        let mut c = small_scene();
        c.beams.deposition = crate::scene::Deposition::Csda;
        let st = bake(&c, &NoProgress).unwrap().stats.beam_stats;
        let cp = &st.curtains[0];
        assert!(st.ended_left_footprint > 0 && cp.undeposited_power_w > 0.0, "{st:?}");
        let sum = cp.deposited_power_w + cp.undeposited_power_w;
        assert!((sum / cp.electron_power_w - 1.0).abs() < 1e-9, "{cp:?}");
    }

    #[test]
    fn hard_spectrum_shows_the_pink_n2_first_positive_lower_border() {
        // 30 keV Maxwellian, no soft part, no colour noise: with the simple
        // line model, below 84 km the grid is red and violet over green (N2 1P and N2+ 1N stay with N2,
        // 557.7 nm fades with O), while the green layer is green.
        // With the chemistry, O2+ recombination under a bright hard arc's
        // electron density (1e5-1e6 cm^-3) keeps some 557.7 nm down there
        // (GLOW's rule too): the border is red over green and over blue,
        // and still redder than the green layer.
        let mut s = small_scene();
        s.curtains[0].char_energy_kev = 30.0;
        s.curtains[0].soft_fraction = 0.0;
        s.colour.noise_km = 0.0;
        s.beams.count = 600;
        for lines in [crate::scene::LineModel::Simple, crate::scene::LineModel::Chemistry] {
            s.colour.lines = lines;
            let b = bake(&s, &NoProgress).unwrap();
            let band = |lo: f64, hi: f64| emission_between(&b, lo, hi);
            let green = band(100.0, 120.0);
            assert!(green[1] > green[0] && green[1] > green[2], "{lines:?} 100-120 km {green:?}");
            let border = band(76.0, 84.0);
            assert!(border[0] > border[1], "{lines:?} 76-84 km {border:?}");
            if lines == crate::scene::LineModel::Simple {
                assert!(border[2] > border[1], "76-84 km {border:?}");
            }
            assert!(border[0] / border[1] > 2.0 * green[0] / green[1], "{lines:?}: {border:?} {green:?}");
            assert!(border.iter().sum::<f64>() > 1e-3 * green.iter().sum::<f64>(), "a 30 keV spectrum lights 76-84 km: {border:?}");
        }
    }

    /// The emission grid's RGB summed over voxels whose centre altitude lies
    /// in `[lo, hi)` km.
    fn emission_between(b: &Bake, lo: f64, hi: f64) -> [f64; 3] {
        let mut c = [0.0f64; 3];
        for (ijk, v) in b.emission.iter_active() {
            let z = ijk.z as f64 * b.stats.voxel_size_km;
            if (lo..hi).contains(&z) {
                for k in 0..3 {
                    c[k] += v[k] as f64;
                }
            }
        }
        c
    }

    #[test]
    fn aurora_is_green_in_the_middle_and_red_on_top() {
        // Luminance-weighted colour of the emission by altitude band.
        let mut s = small_scene();
        s.beams.count = 1500;
        let b = bake(&s, &NoProgress).unwrap();
        let band = |lo: f64, hi: f64| emission_between(&b, lo, hi);
        let mid = band(105.0, 130.0);
        assert!(mid[1] > mid[0] && mid[1] > mid[2], "105-130 km {mid:?}");
        let top = band(230.0, 300.0);
        assert!(top[0] > top[1] && top[0] > top[2], "230-300 km {top:?}");
    }
}
