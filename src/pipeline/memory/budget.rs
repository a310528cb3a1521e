//! The bake's memory, known before it is spent.
//!
//! [`estimate`] bounds a bake's peak allocation from the plan it runs
//! ([`BakePlan`]: its footprints, field, kernel and chunk of beams), so the
//! estimate and the bake read the same footprints and constants and cannot
//! drift apart.
//! `super::refusal` compares it with the share
//! [`USABLE_FRACTION`] of what this process may use and refuses with the
//! changes that would fit. Terms in bytes (each an upper bound; measured
//! against the peak resident set by `benchmarks/memory/budget.sh`,
//! docs/benchmarks.md), `leaf` an 8^3-voxel leaf's side, `reach = cutoff *
//! r_max`, `I` the smallest dip of the field where a curtain's beams
//! start ([`crate::pipeline::beams::dip`]; `I <= alpha_D` is refused
//! before this):
//! - **program**: [`PROGRAM_BYTES`], what a bake of a few beams holds.
//! - **photons**: the beams held at once, one chunk of the plan's
//!   `beam_chunk` (`crate::pipeline::plan::BakePlan::chunks`; all of them, every
//!   red-trail sample's, for a bake of one chunk or `report2014`), of
//!   [`steps_per_beam`] steps (csda: `ceil(1 / beams.dt)`; Fang's: by
//!   Wald's identity at most `(H + L dt (sin I + tan alpha_D cos I)) /
//!   (L dt sin(I) / 2)` expected, plus four standard deviations of the sum)
//!   plus the column above each start ([`column_spans`]): for the splat a
//!   [`Photon`] twice (traced, merged), its kernel and its leaf range
//!   each; for the other gathers a photon three times and a kernel.
//! - **candidate leaves**: 12 bytes per leaf within reach of each held
//!   step, bounded per beam by its path's slices of leaves.
//! - **grids**: the leaves the bands of [`super::leaves`]
//!   reach (the plan's beams' own starts, or its start cells, carried
//!   along their field lines, dilated by the reach and the walk's spread), each an
//!   emission leaf (512 x 12 bytes and masks) and, unless the air is
//!   physical (`grid.density_a = 0`), a density leaf (512 x 4), plus
//!   [`GRID_SLACK`]. Above [`COUNTED_LEAVES_MAX`] leaves the world box's
//!   and curtain bands' closed-form bound ([`box_leaves`]) stands.
//! - **footprints**: an f32 per cell of the plan's footprints, which it
//!   keeps; with a red trail, whose samples' footprints are simulated
//!   during the bake, their simulation's 12 f64 per cell.
//! - **per-line grids**: per leaf a float grid per line and the sums of
//!   each three lines; a copy of the held photons and their line powers.
//! - **velocity**: the numerator's sums and the grid, a weighted copy of
//!   the held photons, 12 bytes per beam.
//! - **red trail**: in chunks, an earlier sample's footprints; whole, N
//!   more photon sets and candidate lists.
//! - **photon distances**: `voxel_size = "auto"` in chunks keeps every
//!   photon's distance from the camera, 8 bytes each, every sample's.
//! - **pilots** and the **footprint simulation** (12 f64 per cell): freed
//!   before the bake traces; counted by what the larger exceeds the rest.
//!
//! `voxel_size = "auto"` is taken at its floor ([`KernelRadius::auto_voxel_floor_km`]).

use super::leaves::{band_leaves, start_columns, Band};
use super::reach::{
    band_area_leaves, column_km, column_leaves, column_spans, deposit_top_km, dip_deg, path_curve, photons_of_steps, spread_km,
    steps_per_beam, stop_km, world_bounds,
};
use crate::physics::geomagnetic_field::MagneticField;
use crate::pipeline::beams::{beam_field, start_positions};
use crate::pipeline::deposit::Photon;
use crate::pipeline::photons::kernel::KernelF32;
use crate::pipeline::plan::{BakePlan, DEPOSIT_PILOT_BEAMS, PILOT_HALF_BEAMS};
use crate::scene::{Deposition, GatherMethod, KernelRadius, VoxelSize};
use crate::util::fmath;
use glam::DVec3;
use rayon::prelude::*;

/// Bytes per leaf of both grids: emission values, density values, two masks
/// and bookkeeping.
const LEAF_BYTES: f64 = 512.0 * 12.0 + 512.0 * 4.0 + 2.0 * 64.0 + 64.0;
/// Bytes per leaf of one per-line float grid: values, mask, bookkeeping.
const LINE_LEAF_BYTES: f64 = 512.0 * 4.0 + 64.0 + 64.0;
/// Bytes per leaf of the colour grid a per-line gather makes.
const RGB_LEAF_BYTES: f64 = 512.0 * 12.0 + 64.0 + 64.0;
/// The program before any scene: code, the atmosphere's and colour
/// tables, the thread pool's stacks (measured: some 40 MB resident for a
/// bake of a few beams).
pub const PROGRAM_BYTES: f64 = 64.0 * 1024.0 * 1024.0;
/// The allocator's share beside the grids' leaves: the leaf vectors'
/// doubling and the sums' hash table.
pub const GRID_SLACK: f64 = 1.1;
/// Share of the limit the estimate may use: the rest is kept for what does
/// not scale with the scene (the program's code and stacks, the thread
/// pool, the allocator's slack and fragmentation, the files' write
/// buffers of some hundred KB).
pub const USABLE_FRACTION: f64 = 0.8;

/// One term of the estimate, and the scene key that drives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    pub what: &'static str,
    pub bytes: f64,
    /// The key to change, as the user writes it (e.g. "beams.count").
    pub key: String,
    /// Its value, as written.
    pub value: String,
}

/// The bake's estimated peak memory, term by term.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub terms: Vec<Term>,
}

impl Estimate {
    pub fn total(&self) -> f64 {
        self.terms.iter().map(|t| t.bytes).sum()
    }
    /// The largest term.
    pub fn dominant(&self) -> &Term {
        self.terms.iter().max_by(|a, b| a.bytes.total_cmp(&b.bytes)).expect("an estimate has terms")
    }
}

/// Bytes a held photon costs the gather `method` at its peak (module
/// documentation): for the splat a [`Photon`] traced and merged, its
/// kernel and its leaf range; for the others three photons and a kernel.
pub fn bytes_per_held_photon(method: GatherMethod) -> f64 {
    let (photon, kernel) = (std::mem::size_of::<Photon>() as f64, std::mem::size_of::<KernelF32>() as f64);
    if method == GatherMethod::Splat {
        2.0 * photon + kernel + std::mem::size_of::<(glam::IVec3, glam::IVec3)>() as f64
    } else {
        3.0 * photon + kernel
    }
}

/// The smallest voxel the bake may use, km.
fn min_voxel_km(plan: &BakePlan) -> (f64, String, String) {
    match plan.scene.grid.voxel_size {
        VoxelSize::Km(v) => (v, "grid.voxel_size".into(), format!("{v}")),
        VoxelSize::Auto(_) => {
            let floor = KernelRadius::of(&plan.scene.photons).auto_voxel_floor_km();
            (floor, "grid.voxel_size".into(), format!("\"auto\" (at least photons.radius_km / 2 = {floor} km)"))
        }
    }
}

/// Most beams whose starts the bands draw one by one
/// ([`crate::pipeline::beams::start_positions`]); above it, and for a bake
/// whose beams are not the scene's count from its own footprints (a
/// noise target's, a red trail's), every footprint cell above the
/// threshold is a start.
pub const DRAWN_STARTS_MAX: usize = 4_000_000;

/// Whether the bands take the beams' own starts (module documentation).
pub fn draws_starts(plan: &BakePlan) -> bool {
    let trail = plan.scene.colour.mode == crate::scene::ColourMode::Physical && plan.scene.animation.trail_samples > 0;
    plan.scene.beams.count <= DRAWN_STARTS_MAX && plan.scene.beams.target_noise <= 0.0 && !trail
}

/// The bands of [`super::leaves`] for `plan`'s curtains
/// and footprints at voxel `voxel_km` and kernel reach `reach` km: each
/// line through a beam's own start ([`draws_starts`]: the points the trace
/// draws, carried along their field lines to `beams.top_km` and merged on
/// a grid of a voxel), else through every footprint cell above the
/// threshold and any start height the noise allows.
pub fn bands(plan: &BakePlan, voxel_km: f64, reach: f64) -> Vec<Band> {
    let b = &plan.scene.beams;
    let atm = &plan.atmosphere;
    let leaf = 8.0 * voxel_km;
    let dip = dip_deg(plan).to_radians();
    let spread = spread_km(plan);
    let step = b.length_km * b.dt;
    let lowest_start = b.top_km - b.top_noise_km;
    // The walk's spread after descending d km: 4 standard deviations of
    // d / mu steps' deflections ([`spread_km`]), mu = L dt sin(I) / 2 the
    // mean descent of a step; at most the whole beam's.
    let mu = 0.5 * step * fmath::sin(dip);
    let per_sqrt_km = 4.0 * step * fmath::tan(b.alpha_d_deg.to_radians()) / (3.0 * mu).sqrt();
    // CSDA: 1 / dt steps of L dt xi, xi uniform on [0, 1]: a path of at
    // most L dt (n / 2 + 4 sqrt(n / 12)), four standard deviations.
    let n = (1.0 / b.dt).ceil();
    let csda_path = step * (0.5 * n + 4.0 * (n / 12.0).sqrt());
    let shell = if plan.scene.grid.cycles_shell { voxel_km } else { 0.0 };
    let drawn = draws_starts(plan).then(|| start_positions(&plan.trace_params(), b.count));
    // A start carried to top_km moves by at most top_noise cot(I) (and the
    // merge by half a voxel's diagonal); the dipole's direction at the
    // merged point differs from the start's by at most some 2 d / R rad
    // (its inclination turns by 1-2 times the arc), over lines of at most
    // (top - bottom) / sin(I). IGRF over a site ([`igrf_turn_rad`]) has no
    // such closed form: its angles are taken at each start.
    plan.scene
        .curtains
        .iter()
        .zip(&plan.footprints)
        .enumerate()
        .map(|(k, (c, fp))| {
            let (columns, slack) = match &drawn {
                Some(starts) => {
                    let merge = std::f64::consts::FRAC_1_SQRT_2 * voxel_km;
                    // Each start carried, and with IGRF its turn ([`igrf_turn_rad`]).
                    let (carried, turns): (Vec<[f64; 2]>, Vec<f64>) = starts[k]
                        .par_iter()
                        .map(|p| {
                            let carry = plan.field_at([p.x, p.y]);
                            let q = carry.foot(*p, b.top_km);
                            let turn = if plan.site_field.is_some() { igrf_turn_rad(plan, *p, &carry, q, voxel_km) } else { 0.0 };
                            ([q.x, q.y], turn)
                        })
                        .unzip();
                    let length = (deposit_top_km(plan, c).max(b.top_km + b.top_noise_km) - atm.bottom_km()) / fmath::sin(dip);
                    let turn = match (&plan.site_field, plan.scene.earth.magnetic_pole) {
                        (Some(_), _) => turns.iter().copied().fold(0.0, f64::max) * length,
                        (None, Some(_)) if plan.scene.earth.radius_km > 0.0 => {
                            let d = b.top_noise_km / fmath::tan(dip) + merge;
                            2.0 * d / plan.scene.earth.radius_km * length
                        }
                        _ => 0.0,
                    };
                    (merged_columns(&carried, voxel_km), merge + turn)
                }
                None => {
                    let (columns, slack) = start_columns(fp, plan.scene.footprint.threshold, 0.5 * leaf);
                    (columns, slack + b.top_noise_km / fmath::tan(dip))
                }
            };
            let top = deposit_top_km(plan, c).max(b.top_km + b.top_noise_km);
            let bottom = match b.deposition {
                Deposition::Csda => lowest_start - csda_path,
                _ => stop_km(plan, c) - step,
            }
            .max(atm.bottom_km() - step);
            // The samples' spacing adds its half (`super::leaves`).
            let rho = reach + shell + slack;
            Band {
                columns,
                start_km: b.top_km,
                top_km: top,
                bottom_km: bottom,
                rho_km: rho,
                spread_per_sqrt_km: per_sqrt_km,
                spread_max_km: spread,
            }
        })
        .collect()
}

/// The cell of a grid of `g` km holding `p`.
fn cell(p: [f64; 2], g: f64) -> (i64, i64) {
    ((p[0] / g).floor() as i64, (p[1] / g).floor() as i64)
}

/// The centre of a grid cell of `g` km.
fn cell_centre((a, b): (i64, i64), g: f64) -> [f64; 2] {
    [(a as f64 + 0.5) * g, (b as f64 + 0.5) * g]
}

/// Points merged onto a grid of `g` km: each occupied cell's centre, sorted.
fn merged_columns(points: &[[f64; 2]], g: f64) -> Vec<[f64; 2]> {
    let mut cells: Vec<(i64, i64)> = points.iter().map(|&p| cell(p, g)).collect();
    cells.sort_unstable();
    cells.dedup();
    cells.into_iter().map(|c| cell_centre(c, g)).collect()
}

/// With IGRF over a site, the angle, radians, by which the line of the
/// beam starting at `p` can turn away from its merged column's (module
/// documentation of `super::leaves`): the angle between the field the beam
/// follows (`crate::pipeline::beams::beam_field` at `p`, its own altitude)
/// and the field `carry` it is carried along to `beams.top_km` (at
/// `top_km` over `p`), which moves the line's crossing of `top_km`, to `q`,
/// by that angle over at most the line's length; plus the angle between
/// the beam's field and its merged column's (`BakePlan::field_at` the
/// centre of `q`'s cell of `g` km), by which the line diverges below and
/// above. The bands take the largest over a curtain's starts.
fn igrf_turn_rad(plan: &BakePlan, p: DVec3, carry: &MagneticField, q: DVec3, g: f64) -> f64 {
    let own = beam_field(&plan.earth(), plan.scene.earth.magnetic_pole, plan.site_field.as_ref(), plan.field, p).b;
    let column = plan.field_at(cell_centre(cell([q.x, q.y], g), g)).b;
    own.angle_between(carry.b) + own.angle_between(column)
}

/// Largest leaf count [`super::leaves::band_leaves`] is
/// asked to count (a set of them takes some 40 bytes each); above it the
/// box and band bound ([`box_leaves`]) stands, and such a bake (over 16
/// GiB of grids) is refused anyway on most machines.
pub const COUNTED_LEAVES_MAX: f64 = 2.0e6;

/// Bound on the leaves from the world box and the curtains' bands alone
/// (no footprint), at voxel `voxel_km`, kernel reach `reach`: the
/// smaller of the box's and the curtains' own bounds (module
/// documentation), plus the columns above the starts.
pub fn box_leaves(plan: &BakePlan, leaf_km: f64, reach: f64) -> f64 {
    let dip = dip_deg(plan);
    let (lo, hi) = world_bounds(plan);
    let box_leaves: f64 = (0..3).map(|i| ((hi[i] - lo[i] + 2.0 * reach) / leaf_km).ceil() + 1.0).product();
    let slabs = ((hi[2] - lo[2] + 2.0 * reach) / leaf_km).ceil() + 1.0;
    let shift = leaf_km / fmath::tan(dip.to_radians());
    let spread = spread_km(plan);
    let own: f64 = plan
        .scene
        .curtains
        .iter()
        .map(|c| match path_curve(plan, c) {
            Some((length, _)) => band_area_leaves(length, 0.5 * c.width + reach + spread + leaf_km + shift, leaf_km) * slabs,
            None => {
                let (s, co) = fmath::sin_cos(c.rotation_deg.to_radians());
                let dx = (c.length * co).abs() + (c.width * s).abs() + 2.0 * (reach + spread + leaf_km) + shift;
                let dy = (c.length * s).abs() + (c.width * co).abs() + 2.0 * (reach + spread + leaf_km) + shift;
                ((dx / leaf_km).ceil() + 1.0) * ((dy / leaf_km).ceil() + 1.0) * slabs
            }
        })
        .sum();
    box_leaves.min(own) + column_leaves(plan, leaf_km, reach)
}

/// How the grid term finds its leaves.
#[derive(Clone, Copy, Debug)]
pub enum LeafCount<'a> {
    /// The plan's bands, counted ([`super::leaves`]),
    /// where [`box_leaves`] allows it: the bake's check.
    Bands,
    /// As [`LeafCount::Bands`], each distinct set of bands counted once.
    Memo(&'a LeafMemo),
    /// [`box_leaves`] alone, in closed form: never below [`LeafCount::Bands`]
    /// and cheap, for a search that asks many times.
    Bound,
}

/// Band counts already made, by their bands, voxel, Earth and field: a
/// search that changes keys the bands do not read (beams.count, the lines,
/// ...) counts them once.
#[derive(Debug, Default)]
pub struct LeafMemo(std::cell::RefCell<std::collections::HashMap<u64, Option<usize>>>);

/// A hash of everything [`band_leaves`] reads.
fn bands_key(plan: &BakePlan, bands: &[Band], voxel_km: f64) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    format!("{:?} {:?}", plan.scene.earth, plan.field).hash(&mut h);
    voxel_km.to_bits().hash(&mut h);
    for b in bands {
        for c in &b.columns {
            c.map(f64::to_bits).hash(&mut h);
        }
        [b.start_km, b.top_km, b.bottom_km, b.rho_km, b.spread_per_sqrt_km, b.spread_max_km].map(f64::to_bits).hash(&mut h);
    }
    h.finish()
}

/// The leaves the bake's grids can hold at voxel `voxel_km`, found by
/// `count`: the bands counted from the plan ([`super::leaves`]) when
/// [`box_leaves`] allows it, else that bound.
pub fn grid_leaves(plan: &BakePlan, voxel_km: f64, reach: f64, count: LeafCount) -> f64 {
    let bound = box_leaves(plan, 8.0 * voxel_km, reach + voxel_km);
    if bound > COUNTED_LEAVES_MAX || matches!(count, LeafCount::Bound) {
        return bound;
    }
    let bands = bands(plan, voxel_km, reach);
    let n = match count {
        LeafCount::Memo(m) => {
            let key = bands_key(plan, &bands, voxel_km);
            let known = m.0.borrow().get(&key).copied();
            known.unwrap_or_else(|| {
                let n = band_leaves(plan, &bands, voxel_km);
                m.0.borrow_mut().insert(key, n);
                n
            })
        }
        _ => band_leaves(plan, &bands, voxel_km),
    };
    n.map_or(bound, |n| (n as f64).min(bound))
}

/// The bake's peak memory, term by term, from `plan`: its footprints'
/// cells, its chunk of beams, the leaves its bands touch, found by `count`
/// (the bake's check: [`LeafCount::Bands`]).
pub fn estimate(plan: &BakePlan, count: LeafCount) -> Estimate {
    let b = &plan.scene.beams;
    let (steps, _) = steps_per_beam(plan);
    let dip = dip_deg(plan);
    let chunked = plan.is_chunked(b.count);
    // A chunked bake holds one chunk's photons at a time, of one trail
    // sample; a whole one every beam's, of every sample.
    let held_beams = if chunked { plan.beam_chunk.max(1) } else { b.count } as f64;
    // The tallest curtain's column, for every beam.
    let column = plan.scene.curtains.iter().map(|c| column_km(plan, c)).fold(0.0, f64::max);
    let column_segments = plan.scene.curtains.iter().map(|c| column_spans(plan, c)).fold(0.0, f64::max);
    let step_photons = photons_of_steps(plan, held_beams);
    let photons = step_photons + held_beams * column_segments;
    let photon_bytes = std::mem::size_of::<Photon>() as f64;
    let kernel_bytes = std::mem::size_of::<KernelF32>() as f64;
    let (photon_key, photon_value) = if chunked || steps > 1000.0 {
        ("beams.dt".to_string(), format!("{}", b.dt))
    } else {
        ("beams.count".to_string(), format!("{}", b.count))
    };

    let (voxel, vkey, vvalue) = min_voxel_km(plan);
    let leaf_km = 8.0 * voxel;
    let p = &plan.scene.photons;
    let reach = KernelRadius::of(p).max_reach_km(p.cutoff);
    let per_photon = fmath::powi(2.0 * reach / leaf_km + 2.0, 3);
    let leaves = grid_leaves(plan, voxel, reach, count);
    // The emission's leaves, and the density's on the same voxels unless
    // the air is physical (`grid.density_a = 0`: no density grid).
    let leaf_bytes = if plan.scene.grid.density_a > 0.0 { LEAF_BYTES } else { RGB_LEAF_BYTES };
    // Blame the kernel when its reach, not the voxel or the curtains, makes
    // the grid large: the world box's leaves with the reach over four times
    // those without.
    let (lo, hi) = world_bounds(plan);
    let boxed = |pad: f64| -> f64 { (0..3).map(|i| ((hi[i] - lo[i] + 2.0 * pad) / leaf_km).ceil() + 1.0).product() };
    let (grid_key, grid_value) = if boxed(reach) > 4.0 * boxed(0.0) && reach > leaf_km {
        ("photons.radius_km".to_string(), format!("{}", p.radius_km))
    } else {
        (vkey, vvalue)
    };
    // Candidate entries: each photon's segment box (kernel reach around a
    // step of at most length_km * dt) lists its leaves. Where every step
    // descends (the deflection alpha_D is smaller than the field's dip),
    // a beam's path from its top to the 50 km bottom is at most
    // h / sin(dip - alpha_D) long, so its photons touch at most
    // (path / leaf + 2) slices of cross^2 leaves, which bounds the list
    // (photons of one beam are consecutive and deduplicated) far below
    // photons x leaves per photon.
    let step = b.length_km * b.dt;
    let cross = ((2.0 * reach + step) / leaf_km).ceil() + 1.0;
    let per_photon_seg = fmath::powi(cross, 3);
    let descent = (dip - b.alpha_d_deg).to_radians();
    let per_beam = if descent > 0.05 {
        let path = (b.top_km + b.top_noise_km - 50.0).max(0.0) / fmath::sin(descent);
        (path / leaf_km + 2.0) * cross * cross
    } else {
        f64::INFINITY
    };
    let step_entries = (step_photons * per_photon_seg).min(held_beams * per_beam).min(step_photons * per_photon_seg.min(leaves));
    // A beam's column segments lie end to end along one field line: their
    // boxes list at most (length / leaf + 2) slices each of cross_c^2
    // leaves, cross_c the kernel's width in leaves.
    let sin_dip = fmath::sin(dip.to_radians()).max(0.05);
    let cross_c = (2.0 * reach / leaf_km).ceil() + 2.0;
    let column_entries = held_beams * (column / sin_dip / leaf_km + 2.0 * column_segments) * cross_c * cross_c;
    let candidates = (step_entries + column_entries) * 12.0;
    let (cand_key, cand_value) = if per_photon > 64.0 {
        ("photons.radius_km".to_string(), format!("{}", p.radius_km))
    } else {
        (photon_key.clone(), photon_value.clone())
    };

    // The footprints: the plan keeps an f32 per cell; their simulation
    // works on 12 f64 per cell. It runs before the bake traces, so it
    // counts by what it exceeds the rest, like the pilots; a red trail
    // simulates its samples' footprints during the bake, beside the rest.
    let cells: f64 = plan.footprints.iter().map(|f| (f.nx * f.ny) as f64).sum();
    let simulation = cells * 12.0 * 8.0;
    let kept = 4.0 * cells;
    let [nx, ny] = plan.scene.footprint.resolution;

    // Per held photon: the splat holds the traced one, the merged one (at
    // most one per traced), its kernel and its leaf range (the trace's
    // chunks and their concatenation, two photons, come and go before);
    // the other gathers a third copy (the kd-tree's, the report's bins).
    let held_per_photon = bytes_per_held_photon(p.gather);
    let physical = plan.scene.colour.mode == crate::scene::ColourMode::Physical;
    let trail = if physical { plan.scene.animation.trail_samples as f64 } else { 0.0 };
    let footprint = if trail > 0.0 { simulation } else { kept };
    // Photons held beside the bake's own: every trail sample's when whole.
    let all_photons = photons * if chunked { 1.0 } else { 1.0 + trail };
    let n_lines = if physical { plan.scene.grid.lines.len() as f64 } else { 0.0 };
    let mut terms = vec![
        Term { what: "program", bytes: PROGRAM_BYTES, key: "beams.count".into(), value: format!("{}", b.count) },
        Term { what: "photons", bytes: photons * held_per_photon, key: photon_key, value: photon_value },
        Term { what: "candidate leaves", bytes: candidates, key: cand_key, value: cand_value },
        Term { what: "grids", bytes: GRID_SLACK * leaves * leaf_bytes, key: grid_key, value: grid_value },
        Term { what: "footprints", bytes: footprint, key: "footprint.resolution".into(), value: format!("[{nx}, {ny}]") },
    ];
    if n_lines > 0.0 {
        // Each line's grid, the sums of each three lines (a colour grid
        // each), the lines' photon copy and each photon's line powers.
        let groups = (n_lines / 3.0).ceil();
        let bytes =
            GRID_SLACK * leaves * (n_lines * LINE_LEAF_BYTES + groups * RGB_LEAF_BYTES) + all_photons * (photon_bytes + 4.0 * n_lines);
        terms.push(Term { what: "per-line grids", bytes, key: "grid.lines".into(), value: format!("{:?}", plan.scene.grid.lines) });
    }
    if plan.scene.grid.velocity {
        // The numerator's sums and the velocity grid, the weighted photons'
        // copy and each beam's velocity.
        let bytes = GRID_SLACK * leaves * 2.0 * RGB_LEAF_BYTES + photons * (photon_bytes + kernel_bytes) + 12.0 * b.count as f64;
        terms.push(Term { what: "velocity", bytes, key: "grid.velocity".into(), value: "true".into() });
    }
    if trail > 0.0 {
        // Whole: N more photon sets and candidate lists. In chunks: one
        // earlier sample's footprints at a time (f32 per cell).
        let bytes = if chunked { 4.0 * cells } else { trail * (photons * held_per_photon + candidates) };
        terms.push(Term { what: "red trail", bytes, key: "animation.trail_samples".into(), value: format!("{trail}") });
    }
    if chunked && matches!(plan.scene.grid.voxel_size, VoxelSize::Auto(_)) && plan.camera_model().is_ok_and(|c| c.pixel_angle().is_some()) {
        // Every photon's distance from the camera (8 bytes), of every sample.
        let every = photons_of_steps(plan, b.count as f64) + b.count as f64 * column_segments;
        terms.push(Term {
            what: "photon distances",
            bytes: 8.0 * every * (1.0 + trail),
            key: "beams.count".into(),
            value: format!("{}", b.count),
        });
    }
    // The footprints' simulation and the pilots run before the bake traces
    // and free what they hold: they count by what their peak exceeds the rest.
    let rest: f64 = terms.iter().map(|t| t.bytes).sum();
    let pilot_photons = |beams: f64| photons_of_steps(plan, beams) + beams * column_segments;
    let deposit_pilot = PROGRAM_BYTES + 2.0 * pilot_photons(DEPOSIT_PILOT_BEAMS.min(b.count) as f64) * photon_bytes + footprint;
    let noise_pilot = if b.target_noise > 0.0 {
        let m = PILOT_HALF_BEAMS as f64;
        let grid = leaves.min(photons_of_steps(plan, m) * per_photon);
        PROGRAM_BYTES + 2.0 * GRID_SLACK * grid * RGB_LEAF_BYTES + 6.0 * pilot_photons(m) * photon_bytes + footprint
    } else {
        0.0
    };
    let simulating = PROGRAM_BYTES + simulation;
    let pilots = deposit_pilot.max(noise_pilot) - rest;
    if simulating - rest > pilots.max(0.0) {
        terms.push(Term {
            what: "footprint simulation",
            bytes: simulating - rest,
            key: "footprint.resolution".into(),
            value: format!("[{nx}, {ny}]"),
        });
    } else if pilots > 0.0 {
        let (key, value) = if noise_pilot > deposit_pilot {
            ("beams.target_noise".to_string(), format!("{}", b.target_noise))
        } else {
            ("beams.dt".to_string(), format!("{}", b.dt))
        };
        terms.push(Term { what: "pilots", bytes: pilots, key, value });
    }
    Estimate { terms }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::util::progress::NoProgress;

    /// The bake's check's estimate of a scene, from its plan.
    fn est(s: &Scene) -> Estimate {
        estimate(&BakePlan::new(s, &NoProgress), LeafCount::Bands)
    }

    const GIB: f64 = (1u64 << 30) as f64;

    fn term<'a>(e: &'a Estimate, what: &str) -> &'a Term {
        e.terms.iter().find(|t| t.what == what).unwrap_or_else(|| panic!("no {what} term: {:?}", e.terms))
    }

    #[test]
    fn default_scene_bound_is_above_what_it_uses_and_near_it() {
        let s = Scene::default();
        let e = est(&s);
        // Measured: 2.14 GiB peak resident for the default bake (three
        // arcs 8 km wide, 400-880 km long along the oval) with its VDB
        // write (/usr/bin/time, 2026-12-07; 1.5 GiB for its shorter
        // straight arcs before, 0.66 GiB for the thin sheets before
        // that); the bound is above it and below twice it (the bounding
        // boxes' bound gave 7.1 GiB for the thin sheets: it counted every
        // leaf of boxes the curtains cross).
        assert!(e.total() > 2.14 * GIB && e.total() < 4.28 * GIB, "{} GiB", e.total() / GIB);
    }

    #[test]
    fn per_line_grids_and_the_trail_are_counted() {
        let mut s = Scene::default();
        let plain = est(&s).total();
        s.grid.lines = crate::physics::emission::line_table::LINE_KEYS.iter().map(|k| k.to_string()).collect();
        let e = est(&s);
        let lines = term(&e, "per-line grids");
        let grids = term(&e, "grids");
        // Five float grids and two colour sums on the grids' leaves (the
        // default's physical air has no density grid): (5 x 2176 + 2 x
        // 6272) / 6272 = 3.73 of the grids' term, plus the photons' copy.
        assert!(lines.bytes > 3.73 * grids.bytes, "{} vs {}", lines.bytes, grids.bytes);
        assert!(e.total() > 1.01 * plain);
        // A colour map makes no per-line grids: nothing counted.
        s.colour.mode = crate::scene::ColourMode::Colormap;
        assert_eq!(est(&s).total(), plain);

        // The trail of a bake of one chunk (8,000 beams): N more photon
        // sets and candidate lists.
        let mut s = Scene::default();
        s.beams.count = 8_000;
        s.animation.trail_samples = 8;
        let e = est(&s);
        let t = term(&e, "red trail");
        let (ph, ca) = (term(&e, "photons").bytes, term(&e, "candidate leaves").bytes);
        assert!((t.bytes - 8.0 * (ph + ca)).abs() <= 1e-9 * t.bytes, "{} vs {}", t.bytes, 8.0 * (ph + ca));
        assert_eq!(t.key, "animation.trail_samples");
    }

    #[test]
    fn estimate_shrinks_with_voxel_size_and_a_chunked_bake_does_not_grow_with_beams() {
        let s = Scene::default();
        let plan = BakePlan::new(&s, &NoProgress);
        let a = estimate(&plan, LeafCount::Bands).total();
        let mut t = s.clone();
        t.grid.voxel_size = VoxelSize::Km(2.0);
        assert!(estimate(&BakePlan::reusing(&t, &plan, &NoProgress), LeafCount::Bands).total() < a);
        // Beyond one chunk the photons and candidates are a chunk's: 4 and
        // 40 chunks, the same.
        let at = |count: usize| {
            let mut t = s.clone();
            t.beams.count = count;
            estimate(&BakePlan::reusing(&t, &plan, &NoProgress), LeafCount::Bands)
        };
        let (four, forty) = (at(4 * plan.beam_chunk), at(40 * plan.beam_chunk));
        for what in ["photons", "candidate leaves"] {
            assert_eq!(term(&four, what).bytes, term(&forty, what).bytes, "{what}");
        }
        assert_eq!(term(&four, "photons").key, "beams.dt");
        // The grids follow the starts the beams cover, up to every cell's
        // (the bound where the starts are not drawn).
        let every = at(DRAWN_STARTS_MAX + 1);
        let grids = |e: &Estimate| term(e, "grids").bytes;
        assert!(grids(&four) <= grids(&forty) && grids(&forty) <= grids(&every), "{} {} {}", grids(&four), grids(&forty), grids(&every));
        // Within a chunk, more beams, more photons.
        assert!(at(plan.beam_chunk).total() > at(plan.beam_chunk / 2).total());
    }
}
