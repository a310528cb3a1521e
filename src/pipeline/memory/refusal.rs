//! A bake that would not fit, refused with the changes that would.
//!
//! [`check`] compares the bake's estimate from its plan
//! ([`super::budget::estimate`]) with the share
//! [`USABLE_FRACTION`] of what this process may use
//! ([`crate::util::memory::available`]), the rest being kept for what does
//! not scale with the scene. Over it, the bake is refused ([`TooLarge`])
//! naming the term and key that drive it, the memory needed, the share that
//! counts, and the suggestions: for each key in [`CANDIDATES`], the nearest
//! value in the direction that shrinks its terms (more beams.dt, fewer
//! beams, larger voxels, ...) at which the estimate, recomputed with that
//! one key changed, fits; a key no valid value of which fits is left out.
//! The message rounds the need up and the usable share down, so a bake it
//! refuses never reads as one that fits.
//!
//! The search asks for many estimates: it walks and bisects on the grid
//! term's closed-form bound ([`LeafCount::Bound`], never below the count),
//! then narrows the last step on the counted bands, which the bake's own
//! check uses, each distinct set counted once ([`LeafCount::Memo`]); a
//! changed footprint is simulated once per value and kept for the search.

use super::budget::{estimate, Estimate, LeafCount, LeafMemo, USABLE_FRACTION};
use crate::pipeline::plan::BakePlan;
use crate::scene::{Scene, VoxelSize};
use crate::util::fmath;
use crate::util::memory::MemoryLimit;
use crate::util::progress::NoProgress;
use std::cell::RefCell;

/// One change that alone brings the estimate under the usable share.
#[derive(Clone, Debug, PartialEq)]
pub struct Suggestion {
    /// The key, as the user writes it (e.g. "beams.count").
    pub key: String,
    /// Its value now and the suggested one, as written in a scene file.
    pub from: String,
    pub to: String,
    /// The estimate with the change, bytes.
    pub bytes: f64,
}

/// A bake that would not fit.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "the bake needs about {} GiB (its {what}: {} GiB, from {key} = {value}), more than the {} GiB it may use: {:.0} % of the {limit} this process may use, the other {:.0} % being kept for the program, its threads, the allocator's slack and the files' write buffers; {}",
    gib_up(*total),
    gib_up(*needed),
    gib_down(*usable),
    100.0 * USABLE_FRACTION,
    100.0 * (1.0 - USABLE_FRACTION),
    advice(suggestions)
)]
pub struct TooLarge {
    /// The key of the largest term, its value and what it is.
    pub key: String,
    pub value: String,
    pub what: &'static str,
    /// The largest term, the whole estimate and the usable share, bytes.
    pub needed: f64,
    pub total: f64,
    pub usable: f64,
    pub limit: MemoryLimit,
    pub suggestions: Vec<Suggestion>,
}

impl TooLarge {
    /// Always the user's input: the scene asks for too much memory (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// Bytes as GiB rounded up, two decimals.
fn gib_up(bytes: f64) -> String {
    format!("{:.2}", (bytes / (1u64 << 30) as f64 * 100.0).ceil() / 100.0)
}

/// Bytes as GiB rounded down, two decimals.
fn gib_down(bytes: f64) -> String {
    format!("{:.2}", (bytes / (1u64 << 30) as f64 * 100.0).floor() / 100.0)
}

/// The message's advice: the suggestions, or that no single change fits.
fn advice(suggestions: &[Suggestion]) -> String {
    if suggestions.is_empty() {
        let keys: Vec<&str> = CANDIDATES.iter().map(|c| c.key).collect();
        return format!("no single change of {} brings it under: change several, or run where more memory is free", keys.join(", "));
    }
    let each: Vec<String> =
        suggestions.iter().map(|s| format!("{} = {} (now {}; about {} GiB)", s.key, s.to, s.from, gib_up(s.bytes))).collect();
    format!("each of these changes alone brings it under: {}", each.join("; "))
}

/// Refuses the bake of `plan` when its estimate exceeds
/// [`USABLE_FRACTION`] of `limit`, with the suggestions that fit (each
/// the estimate of the plan reusing its footprints where the key leaves
/// them); returns the estimate.
pub fn check(plan: &BakePlan, limit: &MemoryLimit) -> Result<Estimate, Box<TooLarge>> {
    let memo = LeafMemo::default();
    let e = estimate(plan, LeafCount::Memo(&memo));
    let usable = USABLE_FRACTION * limit.bytes;
    let total = e.total();
    if total <= usable {
        return Ok(e);
    }
    let d = e.dominant();
    Err(Box::new(TooLarge {
        key: d.key.clone(),
        value: d.value.clone(),
        what: d.what,
        needed: d.bytes,
        total,
        usable,
        limit: limit.clone(),
        suggestions: suggestions(plan, usable, memo),
    }))
}

/// A key the refusal may suggest changing, and how.
pub struct Candidate {
    pub key: &'static str,
    /// The key's value in `scene` as a number, if the key applies (a
    /// per-line grid list, a trail, ... only when present).
    value: fn(&Scene) -> Option<f64>,
    /// Sets the key to a number.
    set: fn(&mut Scene, f64),
    /// The key's value in a scene, as written in a scene file.
    written: fn(&Scene) -> String,
    /// Values tried, from the current one outward in the direction that
    /// shrinks the estimate, each a factor 1.25 farther; the farthest allowed.
    toward: Toward,
}

/// Where a candidate's values go, and how far.
#[derive(Clone, Copy)]
enum Toward {
    /// Up, at most this value.
    Up(f64),
    /// Down, at least this value.
    Down(f64),
    /// Down through the integers, at least this one.
    DownInt(f64),
}

/// The keys the refusal tries, one at a time.
pub const CANDIDATES: &[Candidate] = &[
    Candidate {
        key: "beams.count",
        value: |s| Some(s.beams.count as f64),
        set: |s, x| s.beams.count = x as usize,
        written: |s| s.beams.count.to_string(),
        toward: Toward::DownInt(1.0),
    },
    Candidate {
        key: "beams.dt",
        value: |s| Some(s.beams.dt),
        set: |s, x| s.beams.dt = x,
        written: |s| s.beams.dt.to_string(),
        toward: Toward::Up(1.0),
    },
    Candidate {
        key: "grid.voxel_size",
        value: |s| match s.grid.voxel_size {
            VoxelSize::Km(v) => Some(v),
            VoxelSize::Auto(_) => Some(crate::scene::KernelRadius::of(&s.photons).auto_voxel_floor_km()),
        },
        set: |s, x| s.grid.voxel_size = VoxelSize::Km(x),
        written: |s| match s.grid.voxel_size {
            VoxelSize::Km(v) => v.to_string(),
            VoxelSize::Auto(_) => "\"auto\"".to_string(),
        },
        toward: Toward::Up(1e3),
    },
    Candidate {
        key: "photons.radius_km",
        value: |s| Some(s.photons.radius_km),
        set: |s, x| s.photons.radius_km = x,
        written: |s| s.photons.radius_km.to_string(),
        toward: Toward::Down(1e-3),
    },
    Candidate {
        key: "footprint.resolution",
        value: |s| Some(s.footprint.resolution[0] as f64),
        set: |s, x| {
            let [nx, ny] = s.footprint.resolution;
            let f = x / nx as f64;
            s.footprint.resolution = [(x as usize).max(8), ((ny as f64 * f).round() as usize).max(8)];
        },
        written: |s| format!("{:?}", s.footprint.resolution),
        toward: Toward::DownInt(8.0),
    },
    Candidate {
        key: "grid.lines",
        value: |s| (!s.grid.lines.is_empty()).then_some(s.grid.lines.len() as f64),
        set: |s, x| s.grid.lines.truncate(x as usize),
        written: |s| format!("{:?}", s.grid.lines),
        toward: Toward::DownInt(0.0),
    },
    Candidate {
        key: "animation.trail_samples",
        value: |s| (s.animation.trail_samples > 0).then_some(s.animation.trail_samples as f64),
        set: |s, x| s.animation.trail_samples = x as u32,
        written: |s| s.animation.trail_samples.to_string(),
        toward: Toward::DownInt(0.0),
    },
];

/// For each of [`CANDIDATES`], the value nearest the plan's scene's at which the
/// estimate with that key alone changed is at most `usable` bytes and the
/// scene still valid: values a factor 1.25 apart outward until one fits,
/// then 16 halvings between it and the last that did not (on the closed-form
/// leaf bound), then 5 more on the counted bands between the scene's value
/// and it, then rounded outward to two significant digits when that still
/// fits. A key no value of which fits is left out.
pub fn suggestions(plan: &BakePlan, usable: f64, memo: LeafMemo) -> Vec<Suggestion> {
    let search = Search { scene: &plan.scene, plan, usable, plans: RefCell::new(Vec::new()), memo };
    CANDIDATES.iter().filter_map(|c| search.suggest(c)).collect()
}

/// One refusal's search: the scene, its plan, the plans of the changed
/// footprints met so far.
struct Search<'a> {
    scene: &'a Scene,
    plan: &'a BakePlan,
    usable: f64,
    plans: RefCell<Vec<BakePlan>>,
    /// The bands counted so far.
    memo: LeafMemo,
}

impl Search<'_> {
    /// The scene with `c` set to `x`, if valid.
    fn changed(&self, c: &Candidate, x: f64) -> Option<Scene> {
        let mut s = self.scene.clone();
        (c.set)(&mut s, x);
        s.validate("suggestion", None).is_ok().then_some(s)
    }

    /// The estimate of `s` by `count`, its plan reusing the scene's or an
    /// earlier changed one's footprints where they are `s`'s.
    fn bytes(&self, s: &Scene, count: LeafCount) -> f64 {
        if self.plan.has_footprints_of(s) {
            return estimate(&BakePlan::reusing(s, self.plan, &NoProgress), count).total();
        }
        let mut plans = self.plans.borrow_mut();
        let k = match plans.iter().position(|p| p.has_footprints_of(s)) {
            Some(k) => k,
            None => {
                plans.push(BakePlan::reusing(s, self.plan, &NoProgress));
                plans.len() - 1
            }
        };
        estimate(&BakePlan::reusing(s, &plans[k], &NoProgress), count).total()
    }

    /// The estimate with `c` set to `x`, if that scene is valid and fits.
    fn fits(&self, c: &Candidate, x: f64, count: LeafCount) -> Option<f64> {
        let s = self.changed(c, x)?;
        let bytes = self.bytes(&s, count);
        (bytes <= self.usable).then_some(bytes)
    }

    fn suggest(&self, c: &Candidate) -> Option<Suggestion> {
        let x0 = (c.value)(self.scene)?;
        let (up, limit, integer) = match c.toward {
            Toward::Up(m) => (true, m, false),
            Toward::Down(m) => (false, m, false),
            Toward::DownInt(m) => (false, m, true),
        };
        let past = |x: f64| if up { x >= limit } else { x <= limit };
        let step = |x: f64| {
            let y = if up { x * 1.25 } else { x / 1.25 };
            let y = if integer { y.floor().min(x - 1.0) } else { y };
            if up {
                y.min(limit)
            } else {
                y.max(limit)
            }
        };
        // Outward on the bound until one fits; the farthest on the count
        // when none does.
        let (mut bad, mut good) = (x0, None);
        let mut x = x0;
        while !past(x) {
            x = step(x);
            if self.fits(c, x, LeafCount::Bound).is_some() {
                good = Some(x);
                break;
            }
            bad = x;
        }
        let mut good = match good {
            Some(g) => g,
            None => {
                self.fits(c, x, LeafCount::Memo(&self.memo))?;
                x
            }
        };
        let bisect = |bad: &mut f64, good: &mut f64, halvings: usize, count: LeafCount<'_>| {
            for _ in 0..halvings {
                let mid = if integer { ((*bad + *good) / 2.0).floor() } else { 0.5 * (*bad + *good) };
                if (integer && (*good - *bad).abs() <= 1.0) || mid == *bad || mid == *good {
                    break;
                }
                if self.fits(c, mid, count).is_some() {
                    *good = mid;
                } else {
                    *bad = mid;
                }
            }
        };
        bisect(&mut bad, &mut good, 16, LeafCount::Bound);
        // The count lies at or under the bound: the change that fits on the
        // count lies between the scene's value and the bound's.
        let mut bad = x0;
        bisect(&mut bad, &mut good, 5, LeafCount::Memo(&self.memo));
        // Two significant digits, outward, if that still fits.
        let round = |x: f64| {
            if x <= 0.0 {
                return x;
            }
            let p = fmath::powf(10f64, fmath::log10(x).floor() - 1.0);
            let r = if up { (x / p).ceil() * p } else { (x / p).floor() * p };
            // Clear the binary noise of the product.
            format!("{r:.12e}").parse::<f64>().unwrap_or(r)
        };
        let nice = round(good);
        let x = if !past(nice) || nice == limit { nice } else { good };
        let (x, bytes) = match self.fits(c, x, LeafCount::Memo(&self.memo)) {
            Some(b) => (x, b),
            None => (good, self.fits(c, good, LeafCount::Memo(&self.memo))?),
        };
        let changed = self.changed(c, x)?;
        Some(Suggestion { key: c.key.to_string(), from: (c.written)(self.scene), to: (c.written)(&changed), bytes })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan_of(s: &Scene) -> BakePlan {
        BakePlan::new(s, &NoProgress)
    }

    fn limit(g: f64) -> MemoryLimit {
        MemoryLimit { bytes: g * (1u64 << 30) as f64, source: "test" }
    }

    #[test]
    fn huge_scenes_are_refused_naming_the_key_that_drives_them() {
        // In chunks the photons are a chunk's; with the automatic voxel
        // size every photon's distance from the camera is kept.
        let mut s = Scene::default();
        s.beams.count = 100_000_000;
        s.grid.voxel_size = VoxelSize::Auto(crate::scene::AutoTag::Auto);
        let e = check(&plan_of(&s), &limit(8.0)).unwrap_err();
        assert_eq!(e.key, "beams.count", "{e}");

        let mut s = Scene::default();
        s.beams.dt = 1e-6;
        assert_eq!(check(&plan_of(&s), &limit(8.0)).unwrap_err().key, "beams.dt");

        let mut s = Scene::default();
        s.photons.radius_km = 50.0;
        let e = check(&plan_of(&s), &limit(8.0)).unwrap_err();
        assert_eq!(e.key, "photons.radius_km", "{e}");

        let mut s = Scene::default();
        s.grid.voxel_size = VoxelSize::Km(0.005);
        let e = check(&plan_of(&s), &limit(8.0)).unwrap_err();
        assert_eq!(e.key, "grid.voxel_size", "{e}");
        assert!(e.to_string().contains("GiB") && e.to_string().contains("test"), "{e}");
    }

    #[test]
    fn the_message_never_reads_as_fitting() {
        // A limit a hair under what the estimate needs over the usable
        // share: the need is printed above the usable share, and the share
        // and what it is for are said.
        let s = Scene::default();
        let total = super::super::budget::estimate(&plan_of(&s), LeafCount::Bands).total();
        let l = MemoryLimit { bytes: total / USABLE_FRACTION * (1.0 - 1e-9), source: "test" };
        let e = check(&plan_of(&s), &l).unwrap_err();
        let m = e.to_string();
        let need: f64 = gib_up(e.total).parse().unwrap();
        let usable: f64 = gib_down(e.usable).parse().unwrap();
        assert!(need > usable, "{m}");
        assert!(m.contains("80 %") && m.contains("kept for the program"), "{m}");
        // Exactly at the usable share: accepted.
        check(&plan_of(&s), &MemoryLimit { bytes: total / USABLE_FRACTION * (1.0 + 1e-12), source: "test" }).unwrap();
    }
}
