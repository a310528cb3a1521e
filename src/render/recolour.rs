//! Re-colouring: the `emission` grid rebuilt from the per-line grids
//! (`grid.lines`) for another observer than the one the bake coloured it
//! for (`[colour] observer`, `crate::util::observer`), so one bake renders
//! through the camera or the eye.
//!
//! Model. Light adds: the bake's emission is, voxel by voxel, each line's
//! photons times one photon's colour for the observer, summed over the lines
//! (`crate::physics::emission::line_colour::colour_of`, through
//! `crate::physics::emission::line_table::line_colours`, the colours the bake
//! uses). A line grid holds the line's volume emission rate in rayleigh per
//! km, `R_PER_KM_SCALE` = 1e3 times the emission's unit (1 = 1 kR of OI
//! 557.7 nm per km), so
//!
//! `emission = sum over the lines of line_grid / 1e3 * colour(line, observer)`
//!
//! on the union of the line grids' voxels ([`emission_from_lines`]). It
//! differs from the emission of a bake made for that observer only by what
//! the line grids do not carry: the colour noise (`colour.noise_km`, a
//! chromaticity taken from another altitude), the line yields taken at a
//! step's middle where the photon's colour is taken at its end, and the
//! grids' storage (the emission in half floats with `grid.mantissa_bits`,
//! the lines in floats). The density (with `grid.density_a > 0`) and the
//! pruning follow the baked emission's luminance and are kept as baked.
//!
//! Whether a render re-colours ([`emission_source`]) is decided from the
//! scene's `[colour]` and the file's own record of its observer: the same
//! observer, or an artist colour map (no lines, no observer in its
//! colours), takes the file's emission as it is.

use crate::grid::{Grid, Leaf, OriginMap, LEAF_MASK_WORDS, LEAF_NUM_VALUES};
use crate::physics::emission::line_table::{grid_name, line_colours, LINE_KEYS, N_LINES, R_PER_KM_SCALE};
use crate::scene::{ColourMode, ColourParams};
use crate::util::observer::Observer;
use rayon::prelude::*;

/// Where a render's emission comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmissionSource {
    /// The file's `emission` grid, as baked.
    AsBaked,
    /// Rebuilt from the line grids for the scene's observer ([`emission_from_lines`]).
    FromLines,
}

/// Why a file cannot be re-coloured.
#[derive(Debug, thiserror::Error)]
pub enum RecolourError {
    /// The observer asked is not the bake's and a line grid is missing.
    #[error(
        "colour.observer = \"{asked}\": the file's emission was baked for the {baked} observer (aurora_observer), and \
         re-colouring it for the {asked} needs a float grid per line, but it has no {missing}. Bake the scene with \
         grid.lines = [{all}] to re-colour it, or with colour.observer = \"{asked}\"; or render it with \
         colour.observer = \"{baked}\" (allowed: {allowed})",
        asked = .asked.name(),
        baked = .baked.name(),
        missing = .missing.join(", "),
        all = LINE_KEYS.map(|k| format!("\"{k}\"")).join(", "),
        allowed = Observer::ALL.map(|o| format!("\"{}\"", o.name())).join(", ")
    )]
    MissingLines { asked: Observer, baked: Observer, missing: Vec<String> },
    /// The file's metadata names an observer this renderer does not know.
    #[error(
        "metadata {key} = \"{value}\" names no observer this renderer knows (allowed: {allowed})",
        allowed = Observer::ALL.map(|o| format!("\"{}\"", o.name())).join(", ")
    )]
    UnknownObserver { key: String, value: String },
    /// Line grids that do not share one transform cannot be added voxel by voxel.
    #[error("line grids `{first}` and `{other}` have different transforms: they cannot be added into one emission grid")]
    Transforms { first: String, other: String },
}

impl RecolourError {
    /// Always the user's input: the file given, or the observer asked (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// The observer named `name` (`"camera"`, `"eye"`), as a file's metadata
/// under `key` records it.
pub fn observer_named(key: &str, name: &str) -> Result<Observer, RecolourError> {
    Observer::ALL
        .into_iter()
        .find(|o| o.name() == name)
        .ok_or_else(|| RecolourError::UnknownObserver { key: key.to_string(), value: name.to_string() })
}

/// Whether a render of `colour` takes a file's emission as baked or
/// rebuilds it from its lines: `baked` is the observer the file records
/// (None: a file that does not say, taken as the scene's), `float_grids`
/// the names of its float grids. Another observer than the bake's, with
/// `colour.mode = "physical"`, needs every line's grid (`line_5577`, ...);
/// a missing one is refused, naming them all.
pub fn emission_source(colour: &ColourParams, baked: Option<Observer>, float_grids: &[&str]) -> Result<EmissionSource, RecolourError> {
    let Some(baked) = baked else { return Ok(EmissionSource::AsBaked) };
    if colour.mode != ColourMode::Physical || colour.observer == baked {
        return Ok(EmissionSource::AsBaked);
    }
    let missing: Vec<String> = LINE_KEYS.iter().map(|k| grid_name(k)).filter(|n| !float_grids.contains(&n.as_str())).collect();
    if missing.is_empty() {
        Ok(EmissionSource::FromLines)
    } else {
        Err(RecolourError::MissingLines { asked: colour.observer, baked, missing })
    }
}

/// The emission grid of the line grids `lines` (in `LINES` order, rayleigh
/// per km) seen by `observer` (module doc): active where any line is, the
/// lines added in their order in f64 per voxel, so the same grids give the
/// same bits whatever the thread count.
pub fn emission_from_lines(lines: [&Grid<f32>; N_LINES], observer: Observer) -> Result<Grid<[f32; 3]>, RecolourError> {
    let colours = line_colours(observer).map(|c| c.map(|x| x / R_PER_KM_SCALE));
    let transform = lines[0].transform;
    if let Some(g) = lines.iter().find(|g| g.transform != transform) {
        return Err(RecolourError::Transforms { first: lines[0].name.clone(), other: g.name.clone() });
    }
    let mut seen: OriginMap<()> = OriginMap::default();
    let mut origins = Vec::new();
    for g in &lines {
        for l in g.leaves() {
            if seen.insert(l.origin, ()).is_none() {
                origins.push(l.origin);
            }
        }
    }
    let leaves: Vec<Leaf<[f32; 3]>> = origins
        .par_iter()
        .map(|&origin| {
            let mut sum = vec![[0.0f64; 3]; LEAF_NUM_VALUES];
            let mut out = Leaf::new(origin, [0.0f32; 3]);
            for (g, c) in lines.iter().zip(&colours) {
                let Some(l) = g.leaf(origin) else { continue };
                for w in 0..LEAF_MASK_WORDS {
                    out.mask[w] |= l.mask[w];
                }
                for (n, s) in sum.iter_mut().enumerate() {
                    if l.is_active(n) {
                        let v = l.values[n] as f64;
                        for k in 0..3 {
                            s[k] += v * c[k];
                        }
                    }
                }
            }
            for (dst, s) in out.values.iter_mut().zip(&sum) {
                *dst = s.map(|x| x as f32);
            }
            out
        })
        .collect();
    Ok(Grid::from_leaves("emission", [0.0f32; 3], transform, leaves))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use crate::physics::emission::line_colour::{colour_of, LINES};
    use glam::{DVec3, IVec3};

    fn colour(observer: Observer) -> ColourParams {
        ColourParams { observer, ..ColourParams::default() }
    }

    fn all_lines() -> Vec<String> {
        LINE_KEYS.iter().map(|k| grid_name(k)).collect()
    }

    #[test]
    fn the_same_observer_or_a_colour_map_keeps_the_emission_and_another_needs_every_line() {
        let names = all_lines();
        let all: Vec<&str> = names.iter().map(String::as_str).collect();
        let (cam, eye) = (Observer::Camera, Observer::Eye);
        assert_eq!(emission_source(&colour(eye), Some(eye), &[]).unwrap(), EmissionSource::AsBaked);
        assert_eq!(emission_source(&colour(eye), None, &[]).unwrap(), EmissionSource::AsBaked, "a file that does not say");
        let map = ColourParams { mode: ColourMode::Colormap, ..colour(eye) };
        assert_eq!(emission_source(&map, Some(cam), &[]).unwrap(), EmissionSource::AsBaked, "a colour map has no observer");
        assert_eq!(emission_source(&colour(eye), Some(cam), &all).unwrap(), EmissionSource::FromLines);
        let some = ["density", "line_5577", "line_4278"];
        let m = emission_source(&colour(eye), Some(cam), &some).unwrap_err().to_string();
        for want in ["colour.observer = \"eye\"", "camera observer", "line_6300, line_6364, line_n2_1p", "grid.lines = [\"5577\""] {
            assert!(m.contains(want), "{want}: {m}");
        }
        assert!(!m.contains("line_5577,"), "{m}");
    }

    #[test]
    fn lines_add_with_their_colours_on_the_union_of_their_voxels() {
        // Line i holds (i + 1) R/km at one shared voxel and 10 R/km at a
        // voxel of its own, on a leaf of its own for the last line.
        let tr = Transform::new(0.5, DVec3::new(1.0, 2.0, 3.0));
        let shared = IVec3::new(3, -2, 5);
        let grids: Vec<Grid<f32>> = (0..N_LINES)
            .map(|i| {
                let mut g = Grid::new(grid_name(LINE_KEYS[i]), 0.0f32, tr);
                g.set(shared, (i + 1) as f32);
                g.set(if i + 1 == N_LINES { IVec3::new(40, 0, 0) } else { IVec3::new(i as i32, 0, 0) }, 10.0);
                g
            })
            .collect();
        let refs: [&Grid<f32>; N_LINES] = std::array::from_fn(|i| &grids[i]);
        for observer in Observer::ALL {
            let e = emission_from_lines(refs, observer).unwrap();
            assert_eq!((e.name.as_str(), e.transform), ("emission", tr));
            let c: Vec<[f64; 3]> = LINES.iter().map(|l| colour_of(l, observer)).collect();
            let got = e.get(shared);
            for k in 0..3 {
                let want: f64 = (0..N_LINES).map(|i| (i + 1) as f64 * 1e-3 * c[i][k]).sum();
                assert!((got[k] as f64 - want).abs() <= 1e-6 * want, "{observer:?} {k}: {got:?} vs {want}");
            }
            assert_eq!(e.get(IVec3::new(40, 0, 0)), c[N_LINES - 1].map(|x| (10.0 * 1e-3 * x) as f32));
            assert_eq!(e.active_voxel_count(), 1 + N_LINES as u64);
            assert_eq!(e.get(IVec3::new(9, 9, 9)), [0.0; 3], "inactive stays at the background");
            // The same bits on one thread.
            let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| emission_from_lines(refs, observer));
            assert!(one.unwrap() == e);
        }
        let mut moved = grids[2].clone();
        moved.transform = Transform::new(0.25, DVec3::ZERO);
        let refs: [&Grid<f32>; N_LINES] = std::array::from_fn(|i| if i == 2 { &moved } else { &grids[i] });
        let m = emission_from_lines(refs, Observer::Eye).unwrap_err().to_string();
        assert!(m.contains("line_5577") && m.contains("line_6364") && m.contains("different transforms"), "{m}");
    }
}
