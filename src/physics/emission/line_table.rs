//! The emission lines one at a time: each line's photons per keV deposited
//! and its upper state's lifetime by altitude, tabulated once per bake
//! ([`LineTable`]), for the two things the summed colour of
//! `crate::physics::emission::line_colour::ColourTable` cannot do:
//! - **lifetimes in motion**: a line of lifetime tau keeps the fraction
//!   `1 / sqrt(1 + (omega tau)^2)` of a sinusoidal modulation of its source,
//!   lagging by `atan(omega tau)` ([`crate::physics::emission::lifetime::response`]); so under a
//!   pulsating patch each line's photons are its unmodulated yield times its
//!   own filtered modulation ([`LineTable::rgb_in_motion`], with
//!   `crate::pipeline::motion::Wave::at_lifetime`);
//! - **per-line grids** (`grid.lines`): each line's volume emission rate on
//!   its own float grid, in rayleigh per km ([`R_PER_KM_SCALE`]).
//!
//! Each line's yield comes from ONE function, [`line_yields`]
//! (`line_colour::EmissionModel::yields`), and its lifetime from ONE function,
//! [`line_lifetimes`] (`crate::physics::emission::lifetime::lifetimes`): a line model that
//! gives both replaces these two bodies.
//!
//! Units. The gather turns a photon power Phi (per second) into
//! `Phi K / 1e19` with K the kernel (km^-3): kR per km when Phi is in
//! photons per second (`crate::pipeline::photons`). A per-line photon carries
//! `1e3` times its photons per second, so its grid reads rayleigh per km:
//! 1 R/km = 1e6 photons cm^-2 s^-1 per 1e5 cm = 10 photons cm^-3 s^-1, and a
//! ray's integral of the grid in km is the line's brightness in rayleigh.

use crate::physics::atmosphere::Atmosphere;
use crate::physics::emission::line_colour::{colour_of, EmissionModel, Observer, LINES, TABLE_H};

/// Number of lines ([`LINES`]).
pub const N_LINES: usize = LINES.len();

/// The names `grid.lines` takes, in [`LINES`] order: 557.7, 630.0, 636.4,
/// 427.8 nm and the N2 1P visible bands (the scene's list, checked there).
pub const LINE_KEYS: [&str; N_LINES] = crate::scene::validation::LINE_KEYS;

/// A per-line photon's power per photon per second: its grid is then in
/// rayleigh per km (module doc).
pub const R_PER_KM_SCALE: f64 = 1e3;

/// The index of line `key` in [`LINES`], if it is one of [`LINE_KEYS`].
pub fn line_index(key: &str) -> Option<usize> {
    LINE_KEYS.iter().position(|k| *k == key)
}

/// The VDB grid name of line `key`: `line_5577`, ...
pub fn grid_name(key: &str) -> String {
    format!("line_{key}")
}

/// Photons per keV deposited at `h_km`, per line in [`LINES`] order: the one
/// place a line's yield is read.
pub fn line_yields(model: &EmissionModel, h_km: f64) -> [f64; N_LINES] {
    model.yields(h_km).as_array()
}

/// The lifetime of each line's upper state at `h_km`, s, in [`LINES`]
/// order: O(1S) for 557.7 nm, O(1D) for 630.0 and 636.4 nm, 0 for the
/// prompt N2+ and N2 bands. The one place a line's lifetime is read.
pub fn line_lifetimes(atm: &Atmosphere, h_km: f64) -> [f64; N_LINES] {
    let l = crate::physics::emission::lifetime::lifetimes(atm, h_km);
    [l.o1s_s, l.o1d_s, l.o1d_s, 0.0, 0.0]
}

/// Which lines come from O(1D) (630.0 and 636.4 nm), in [`LINES`] order:
/// the ones the red trail sums over earlier times (`crate::pipeline::red_trail`).
pub const O1D_LINES: [bool; N_LINES] = [false, true, true, false, false];

/// The linear Rec.709 colour of one photon per second of each line seen by
/// `observer` (`crate::physics::emission::line_colour`'s units).
pub fn line_colours(observer: Observer) -> [[f64; 3]; N_LINES] {
    std::array::from_fn(|i| colour_of(&LINES[i], observer))
}

/// Per-line yields and lifetimes every 0.05 km over [`TABLE_H`] (as the
/// colour table), linear between samples, clamped at the ends.
#[derive(Clone, Debug)]
pub struct LineTable {
    h0: f64,
    dh: f64,
    yields: Vec<[f64; N_LINES]>,
    tau: Vec<[f64; N_LINES]>,
    colours: [[f64; 3]; N_LINES],
}

/// What a beam step leaves in each line at one altitude: photons per keV
/// and lifetime, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinesAt {
    pub yields: [f64; N_LINES],
    pub tau_s: [f64; N_LINES],
}

impl LineTable {
    /// The table of `model` (its atmosphere gives the lifetimes): 13,001
    /// evaluations of each function, built once per bake.
    pub fn new(model: &EmissionModel) -> Self {
        let dh = 0.05;
        let n = ((TABLE_H.1 - TABLE_H.0) / dh).round() as usize + 1;
        let h = |i: usize| TABLE_H.0 + i as f64 * dh;
        let yields = (0..n).map(|i| line_yields(model, h(i))).collect();
        let tau = (0..n).map(|i| line_lifetimes(&model.atmosphere, h(i))).collect();
        Self { h0: TABLE_H.0, dh, yields, tau, colours: line_colours(model.observer) }
    }

    /// Yields and lifetimes at `h_km`.
    #[inline]
    pub fn at(&self, h_km: f64) -> LinesAt {
        let u = ((h_km - self.h0) / self.dh).max(0.0);
        let last = self.yields.len() - 1;
        let i = (u as usize).min(last);
        if i >= last {
            return LinesAt { yields: self.yields[last], tau_s: self.tau[last] };
        }
        let f = u - i as f64;
        let lerp = |a: &[f64; N_LINES], b: &[f64; N_LINES]| std::array::from_fn(|k| a[k] + (b[k] - a[k]) * f);
        LinesAt { yields: lerp(&self.yields[i], &self.yields[i + 1]), tau_s: lerp(&self.tau[i], &self.tau[i + 1]) }
    }

    /// Yields and lifetimes at `h_km` and ionization rate `q` (ion pairs
    /// cm^-3 s^-1): the chemistry's node when `colour` carries the chemistry
    /// (`crate::physics::emission::line_colour::ColourTable::line_node`: its yields per keV and
    /// its O(1S) and O(1D) lifetimes with quenching), else this table's
    /// simple-model values at `h_km` (q unused).
    #[inline]
    pub fn at_q(&self, colour: &crate::physics::emission::line_colour::ColourTable, h_km: f64, q: f64) -> LinesAt {
        match colour.line_node(h_km, q) {
            Some(n) => {
                let (t1d, t1s) = (n.tau[0] as f64, n.tau[1] as f64);
                LinesAt { yields: n.per_kev, tau_s: [t1s, t1d, t1d, 0.0, 0.0] }
            }
            None => self.at(h_km),
        }
    }

    /// Colour per keV of the lines `l` with each line's photons times
    /// `factor(tau)` of its lifetime tau.
    #[inline]
    pub fn rgb_of(&self, l: &LinesAt, factor: impl Fn(f64) -> f64) -> [f64; 3] {
        self.rgb_of_each(l, |_, tau| factor(tau))
    }

    /// Colour per keV of the lines `l` with line i's photons times
    /// `factor(i, tau)` of its index and lifetime.
    #[inline]
    pub fn rgb_of_each(&self, l: &LinesAt, factor: impl Fn(usize, f64) -> f64) -> [f64; 3] {
        let mut rgb = [0.0; 3];
        for i in 0..N_LINES {
            let n = l.yields[i] * factor(i, l.tau_s[i]);
            for (c, line) in rgb.iter_mut().zip(self.colours[i]) {
                *c += n * line;
            }
        }
        rgb
    }

    /// Colour per keV at `h_km` with each line's photons times `factor(tau)`
    /// of its lifetime tau (this table's values).
    #[inline]
    pub fn rgb_filtered(&self, h_km: f64, factor: impl Fn(f64) -> f64) -> [f64; 3] {
        self.rgb_of(&self.at(h_km), factor)
    }

    /// The colour per keV of *unmodulated* deposit at `h_km` under a
    /// modulation that a line of lifetime tau shows as `factor(tau)`
    /// (module doc), with the lines of each altitude from `at`, the
    /// chromaticity of `h_colour_km` and the luminance of `h_km` (the colour
    /// noise, as `ColourTable::rgb_with_colour_altitude`).
    pub fn rgb_in_motion(&self, at: impl Fn(f64) -> LinesAt, h_km: f64, h_colour_km: f64, factor: impl Fn(f64) -> f64 + Copy) -> [f64; 3] {
        let rgb = self.rgb_of(&at(h_km), factor);
        if h_colour_km == h_km {
            return rgb;
        }
        let c = self.rgb_of(&at(h_colour_km), factor);
        let (y, yc) = (crate::util::colour::luminance(rgb), crate::util::colour::luminance(c));
        if yc > 0.0 {
            c.map(|x| x * y / yc)
        } else {
            rgb
        }
    }

    /// The colour per keV of one sample of the red trail (`crate::pipeline::red_trail`):
    /// line i's photons times `factor(i, tau)`, with the lines of each
    /// altitude from `at`, the chromaticity of `h_colour_km` and the colour
    /// noise's luminance ratio taken from the *unweighted* lines (the
    /// steady state's `Y(h) / Y(h_colour)`, as
    /// `ColourTable::rgb_with_colour_altitude`). The result is linear in the
    /// factors, so the samples of a still scene, whose factors sum to 1,
    /// add up to the colour without the trail.
    pub fn rgb_trail(
        &self,
        at: impl Fn(f64) -> LinesAt,
        h_km: f64,
        h_colour_km: f64,
        factor: impl Fn(usize, f64) -> f64 + Copy,
    ) -> [f64; 3] {
        let own = at(h_km);
        if h_colour_km == h_km {
            return self.rgb_of_each(&own, factor);
        }
        let c = at(h_colour_km);
        let (y, yc) =
            (crate::util::colour::luminance(self.rgb_of(&own, |_| 1.0)), crate::util::colour::luminance(self.rgb_of(&c, |_| 1.0)));
        if yc > 0.0 {
            self.rgb_of_each(&c, factor).map(|x| x * y / yc)
        } else {
            self.rgb_of_each(&own, factor)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::emission::line_colour::ColourTable;

    #[test]
    fn unfiltered_table_is_the_colour_table() {
        // With every factor 1 the lines sum to the physical colour table's
        // colour (same yields, same line colours; both tables linear in
        // altitude between the same nodes: rounding only).
        let m = EmissionModel::default();
        let (lines, colour) = (LineTable::new(&m), ColourTable::physical(&m));
        for h in [80.0, 97.31, 110.0, 151.77, 250.0, 699.0, 10.0, 800.0] {
            let (a, b) = (lines.rgb_filtered(h, |_| 1.0), colour.rgb(h));
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() <= 1e-12 * (b[k].abs() + 1e-12), "{h}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn keys_name_the_lines_in_order() {
        assert_eq!(line_index("6300"), Some(1));
        assert_eq!(line_index("6364"), Some(2));
        assert_eq!(line_index("630"), None);
        assert_eq!(grid_name("4278"), "line_4278");
        let atm = Atmosphere::nrlmsis21();
        let tau = line_lifetimes(&atm, 200.0);
        assert!(tau[0] < 1.0 && tau[1] > 5.0 && tau[1] == tau[2] && tau[3] == 0.0 && tau[4] == 0.0, "{tau:?}");
    }
}
