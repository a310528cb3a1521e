//! The aurora's colours: the emission lines ([`LINES`]), the colour of one
//! photon of each ([`line_rgb`], [`n2_1p_rgb`]), their yields per keV of
//! deposited electron energy as a function of altitude ([`EmissionModel`]),
//! and the colour per keV tabulated for the beams ([`ColourTable`]: the
//! simple model, the chemistry's table, or an artist colour map).
//!
//! A photon "power" in this crate is a linear Rec.709 triple in units where
//! one photon per second of OI 557.7 nm has luminance Y = 1; the emission
//! grid then reads 1 = 1 kR of 557.7 nm per km of path
//! (`crate::pipeline::photons`). A line's colour is its wavelength through
//! the scene's observer (`[colour] observer`, [`Observer`]: a camera at
//! daylight white balance by default, or the CIE 1931 eye), gamut mapped
//! into Rec.709, weighted by the photon energy (`crate::util::colour`,
//! `crate::util::observer`). The functions take any wavelength the observer
//! covers (380-780 nm for the camera), so every line and band has a colour.
//!
//! Sources: the yields and quenching rates are cited on [`EmissionModel`];
//! the N2 1P band heads on [`N2_1P`].

use crate::physics::atmosphere::Atmosphere;
use crate::physics::chemistry::table::ChemistryTable;
use crate::util::colour::luminance;
pub use crate::util::observer::Observer;
use std::sync::Arc;

/// An emission line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub name: &'static str,
    pub lambda_nm: f64,
}

pub const OI_5577: Line = Line { name: "OI 557.7 nm", lambda_nm: 557.7 };
pub const OI_6300: Line = Line { name: "OI 630.0 nm", lambda_nm: 630.0 };
pub const OI_6364: Line = Line { name: "OI 636.4 nm", lambda_nm: 636.4 };
pub const N2P_4278: Line = Line { name: "N2+ 427.8 nm", lambda_nm: 427.8 };
/// The N2 first positive (B3Pi_g -> A3Sigma_u+) bands of the visible red,
/// the Delta v = 3 sequence: band heads (3,0) 687.5 ... (8,5) 646.9 nm
/// (Lofthus & Krupenie 1977, J. Phys. Chem. Ref. Data 6, 113). Its colour
/// is the band-averaged one, [`n2_1p_rgb`]; `lambda_nm` is the mean.
pub const N2_1P: Line = Line { name: "N2 1P 647-688 nm", lambda_nm: 666.8 };
/// Band heads of the N2 1P Delta v = 3 sequence, nm, taken with equal weight.
pub const N2_1P_BANDS_NM: [f64; 6] = [646.9, 654.5, 662.4, 670.5, 678.9, 687.5];
/// The lines of the physical colour model, in [`LineYields`] order.
pub const LINES: [Line; 5] = [OI_5577, OI_6300, OI_6364, N2P_4278, N2_1P];

/// Linear Rec.709 colour of one photon per second at `lambda_nm` seen by
/// `observer`, brought into Rec.709 as that observer does it
/// ([`Observer::in_gamut`]), in units where one 557.7 nm photon has Y = 1
/// for that observer. Photon counts become radiometric weights through the
/// photon energy ratio `557.7 / lambda` (the observers weigh radiant power,
/// not photon number).
pub fn line_rgb(lambda_nm: f64, observer: Observer) -> [f64; 3] {
    let c = observer.in_gamut(observer.rgb(lambda_nm));
    let w = OI_5577.lambda_nm / lambda_nm / y_ref(observer);
    c.map(|x| x * w)
}

/// Linear Rec.709 colour of one photon per second at `lambda_nm` seen by
/// `observer` in the units of [`line_rgb`], not yet brought into the
/// gamut: the term of a spectrum's sum, whose total is brought in once.
pub fn photon_rgb_unclipped(lambda_nm: f64, observer: Observer) -> [f64; 3] {
    let w = OI_5577.lambda_nm / lambda_nm / y_ref(observer);
    observer.rgb(lambda_nm).map(|x| x * w)
}

/// Luminance of one 557.7 nm photon's gamut-mapped colour for `observer`:
/// the unit of photon power.
fn y_ref(observer: Observer) -> f64 {
    luminance(observer.in_gamut(observer.rgb(OI_5577.lambda_nm)))
}

/// Linear Rec.709 colour of one photon per second spread with equal photon
/// weights over the wavelengths `bands_nm` (a band system), seen by
/// `observer`: the mean of each wavelength's colour weighted by its photon
/// energy (`557.7 / lambda`), brought into the gamut once (the mixture is
/// what is seen), in the units of [`line_rgb`].
pub fn bands_rgb(bands_nm: &[f64], observer: Observer) -> [f64; 3] {
    let n = bands_nm.len() as f64;
    let rgb = bands_nm.iter().fold([0.0; 3], |acc, &l| {
        let c = observer.rgb(l);
        let w = OI_5577.lambda_nm / l / n;
        [acc[0] + w * c[0], acc[1] + w * c[1], acc[2] + w * c[2]]
    });
    observer.in_gamut(rgb).map(|x| x / y_ref(observer))
}

/// Linear Rec.709 colour of one photon per second of the N2 1P visible
/// bands seen by `observer`: [`bands_rgb`] over [`N2_1P_BANDS_NM`].
pub fn n2_1p_rgb(observer: Observer) -> [f64; 3] {
    bands_rgb(&N2_1P_BANDS_NM, observer)
}

/// The colour of one photon per second of `line` seen by `observer`: the
/// band mixture for the N2 1P bands, the line's wavelength otherwise.
pub fn colour_of(line: &Line, observer: Observer) -> [f64; 3] {
    if *line == N2_1P {
        n2_1p_rgb(observer)
    } else {
        line_rgb(line.lambda_nm, observer)
    }
}

/// Photons emitted per keV of electron energy deposited, per line.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LineYields {
    pub oi_5577: f64,
    pub oi_6300: f64,
    pub oi_6364: f64,
    pub n2p_4278: f64,
    /// N2 first positive, visible red bands (Delta v = 3), all together.
    pub n2_1p: f64,
}

impl LineYields {
    pub fn as_array(&self) -> [f64; 5] {
        [self.oi_5577, self.oi_6300, self.oi_6364, self.n2p_4278, self.n2_1p]
    }
}

/// The emission yields per keV deposited at altitude h: a deliberately simple,
/// documented parameterisation (not a chemistry model), calibrated to the
/// standard rules of thumb. With x_s = n_s / (n_N2 + n_O2 + n_O) the mole
/// fraction of species s (ionisation and excitation shared by mole fraction):
///
/// - **N2+ 427.8 nm**: `eps_4278 = 0.34 x_N2 / 0.781`. 0.34 photons/keV is
///   Rees & Luckey (1974): about 210 R of 427.8 nm per erg cm^-2 s^-1
///   (1 erg = 6.24e8 keV), for the mixed lower thermosphere (x_N2 = 0.781).
/// - **OI 557.7 nm**: O(1S) comes mostly from energy transfer
///   N2(A) + O -> O(1S) near 100-120 km, and from electron impact on O higher
///   up: `eps_5577 = Q_1S (Y_A x_N2 T_A + Y_O x_O)`, where
///   `T_A = k_AO [O] / (k_AO [O] + k_AO2 [O2] + A_A)` is the fraction of
///   N2(A) that gives its energy to O (k_AO = 3e-11, k_AO2 = 2.5e-12 cm^3/s,
///   A_A = 0.5 /s; laboratory orders of magnitude, e.g. Piper 1982), and
///   `Q_1S = A_1S / (A_1S + k_1S [O2])` the O(1S) survival against quenching
///   by O2 (A_1S = 1/0.7 s, k_1S = 5e-14 cm^3/s, the Slanger & Black rate
///   4e-12 exp(-865/T) at T = 200 K). Together they put the green lower border
///   near 95-100 km, where O falls away and O2 takes N2(A). Y_A = 1.33 and
///   Y_O = 2.0 photons/keV give about 1.1 photons/keV at 110 km: about 3 times
///   427.8, i.e. the usual ~1 kR of 557.7 per erg cm^-2 s^-1.
/// - **OI 630.0 + 636.4 nm**: O(1D) production `Y_D x_O` (Y_D = 20 per keV in
///   pure O, about 0.7 per 35 eV ion pair, counting secondary electrons and
///   dissociative recombination), rising with altitude with the O fraction,
///   times the survival against quenching by N2
///   `q_D = A_D / (A_D + k_D [N2])`, k_D = 3e-11 cm^3/s and lifetime
///   1/A_D = 110 s (half-quenched where `[N2]` = 3e8 cm^-3, near 260 km); the
///   emitted photons split 3:1 between 630.0 and 636.4 nm.
/// - **N2 1P, 647-688 nm** (the red of the pink lower border of hard
///   aurora): `eps_1P = R_1P eps_4278`, proportional to N2 like 427.8 nm.
///   N2(B) is excited by electron impact on N2 (directly and by cascade from
///   N2(C) and higher states) and radiates in microseconds, so neither O
///   thinning nor quenching removes it above 60 km (`k_N2 [N2]` ~ 1e3 /s
///   against A ~ 1.5e5 /s at 80 km), while 557.7 nm fades below 100 km with
///   O and under O2 quenching: the lower border turns from green to the
///   violet of N2+ 1N plus the red of N2 1P, pink, without anyone placing it.
///   R_1P = 1 (photons of the Delta v = 3 sequence per 427.8 nm photon) is
///   our round reading of auroral spectra (Vallance Jones 1974, "Aurora",
///   ch. 4; Gattinger & Vallance Jones 1974, Can. J. Phys. 52, 2343, the
///   1P vibrational development): the bands are of the order of the 427.8 nm
///   band in photon count. An approximate, documented choice, not a fit.
#[derive(Clone, Debug, Default)]
pub struct EmissionModel {
    pub atmosphere: Atmosphere,
    /// Whose colours [`EmissionModel::rgb_per_kev`] gives.
    pub observer: Observer,
}

/// 427.8 nm photons per keV at the reference N2 fraction (Rees & Luckey 1974).
pub const EPS_4278: f64 = 0.34;
/// N2 mole fraction of the well-mixed atmosphere.
pub const X_N2_MIXED: f64 = 0.781;
/// O(1S) yield through N2(A) energy transfer, photons per keV into N2.
pub const Y_A: f64 = 1.33;
/// O(1S) yield by direct impact on O, photons per keV into O.
pub const Y_O: f64 = 2.0;
/// N2 1P (Delta v = 3) photons per 427.8 nm photon (see [`EmissionModel`]).
pub const R_1P: f64 = 1.0;
/// N2(A) + O rate, cm^3/s.
pub const K_A_O: f64 = 3e-11;
/// N2(A) + O2 quenching rate, cm^3/s.
pub const K_A_O2: f64 = 2.5e-12;
/// N2(A) radiative rate, 1/s.
pub const A_A: f64 = 0.5;
/// O(1S) radiative rate, 1/s (lifetime about 0.7 s).
pub const A_1S: f64 = 1.0 / 0.7;
/// O(1S) + O2 quenching at about 200 K, cm^3/s.
pub const K_1S_O2: f64 = 5e-14;
/// O(1D) production per keV into O.
pub const Y_D: f64 = 20.0;
/// O(1D) radiative rate, 1/s (lifetime 110 s).
pub const A_D: f64 = 1.0 / 110.0;
/// O(1D) + N2 quenching, cm^3/s.
pub const K_D_N2: f64 = 3e-11;

impl EmissionModel {
    /// The model on `atmosphere`, coloured for the default observer.
    pub fn new(atmosphere: Atmosphere) -> Self {
        Self { atmosphere, observer: Observer::default() }
    }

    /// The model coloured for `observer`.
    pub fn with_observer(self, observer: Observer) -> Self {
        Self { observer, ..self }
    }

    /// Photons per keV deposited at altitude `h_km`, per line.
    pub fn yields(&self, h_km: f64) -> LineYields {
        let c = self.atmosphere.composition(h_km);
        let total = c.total();
        let (x_n2, x_o) = (c.n2 / total, c.o / total);
        let t_a = K_A_O * c.o / (K_A_O * c.o + K_A_O2 * c.o2 + A_A);
        let q_1s = A_1S / (A_1S + K_1S_O2 * c.o2);
        let q_d = A_D / (A_D + K_D_N2 * c.n2);
        let o1d = Y_D * x_o * q_d;
        LineYields {
            oi_5577: q_1s * (Y_A * x_n2 * t_a + Y_O * x_o),
            oi_6300: 0.75 * o1d,
            oi_6364: 0.25 * o1d,
            n2p_4278: EPS_4278 * x_n2 / X_N2_MIXED,
            n2_1p: R_1P * EPS_4278 * x_n2 / X_N2_MIXED,
        }
    }

    /// Linear Rec.709 colour emitted per keV deposited at `h_km`.
    pub fn rgb_per_kev(&self, h_km: f64) -> [f64; 3] {
        lines_rgb(self.yields(h_km).as_array(), self.observer)
    }
}

/// Colour per keV tabulated for fast lookup along beams: over altitude from
/// the simple physical model or an artist colour map, or over altitude and
/// ionization rate from the chemistry ([`ColourTable::chemistry`]).
#[derive(Clone, Debug)]
pub struct ColourTable {
    h0: f64,
    dh: f64,
    rgb: Vec<[f64; 3]>,
    chem: Option<Arc<ChemColour>>,
}

/// The chemistry's line table and the colour per keV at each of its nodes.
#[derive(Debug)]
struct ChemColour {
    lines: ChemistryTable,
    rgb: Vec<[f64; 3]>,
}

/// Linear Rec.709 colour of `y` photons of each line of [`LINES`] seen by
/// `observer`.
pub fn lines_rgb(y: [f64; 5], observer: Observer) -> [f64; 3] {
    let mut rgb = [0.0; 3];
    for (line, n) in LINES.iter().zip(y) {
        let c = colour_of(line, observer);
        for k in 0..3 {
            rgb[k] += n * c[k];
        }
    }
    rgb
}

/// Altitude range of the physical table, km (clamped outside).
pub const TABLE_H: (f64, f64) = (50.0, 700.0);

impl ColourTable {
    /// The physical model tabulated every 0.05 km over [`TABLE_H`]: linear
    /// interpolation of the smooth yields is then exact to about 1e-5.
    pub fn physical(model: &EmissionModel) -> Self {
        let dh = 0.05;
        let n = ((TABLE_H.1 - TABLE_H.0) / dh).round() as usize + 1;
        let rgb = (0..n).map(|i| model.rgb_per_kev(TABLE_H.0 + i as f64 * dh)).collect();
        Self { h0: TABLE_H.0, dh, rgb, chem: None }
    }

    /// The chemistry (`crate::physics::chemistry`) on `atmosphere`, over altitude and
    /// ionization rate ([`crate::physics::chemistry::table`]: its grid, error and
    /// cost), with each node's colour per keV seen by `observer`. Its
    /// altitude-only lookups ([`ColourTable::rgb`]) read the simple model's
    /// table, built beside it.
    pub fn chemistry(atmosphere: &Atmosphere, observer: Observer) -> Self {
        let lines = ChemistryTable::build(atmosphere);
        let rgb = lines.nodes().iter().map(|n| lines_rgb(n.per_kev, observer)).collect();
        let simple = Self::physical(&EmissionModel::new(atmosphere.clone()).with_observer(observer));
        Self { chem: Some(Arc::new(ChemColour { lines, rgb })), ..simple }
    }

    /// Whether colours depend on the ionization rate (the chemistry).
    #[inline]
    pub fn needs_q(&self) -> bool {
        self.chem.is_some()
    }

    /// Photons per keV deposited of each line at `h_km` and ionization rate
    /// `q` (ion pairs cm^-3 s^-1) from the chemistry table; `None` for the
    /// simple model and colour maps (whose yields are [`EmissionModel`]'s).
    /// The one function every per-line consumer calls at a deposit.
    #[inline]
    pub fn line_yields(&self, h_km: f64, q: f64) -> Option<LineYields> {
        let c = self.chem.as_ref()?;
        let y = c.lines.at(h_km, q).per_kev;
        Some(LineYields { oi_5577: y[0], oi_6300: y[1], oi_6364: y[2], n2p_4278: y[3], n2_1p: y[4] })
    }

    /// The chemistry's whole interpolated node (yields, channels, lifetimes)
    /// at (`h_km`, `q`); `None` without the chemistry.
    pub fn line_node(&self, h_km: f64, q: f64) -> Option<crate::physics::chemistry::table::Node> {
        self.chem.as_ref().map(|c| c.lines.at(h_km, q))
    }

    /// Colour per keV at `h_km` and ionization rate `q`: the chemistry's
    /// bilinear lookup, or [`ColourTable::rgb`] (q unused) without it.
    #[inline]
    pub fn rgb_q(&self, h_km: f64, q: f64) -> [f64; 3] {
        self.rgb_lq(h_km, crate::physics::chemistry::table::ChemistryTable::log_q(q))
    }

    /// [`Self::rgb_q`] at `lq`, the chemistry table's log of `q`.
    #[inline]
    fn rgb_lq(&self, h_km: f64, lq: f64) -> [f64; 3] {
        match &self.chem {
            Some(c) => {
                let cell = c.lines.cell_log(h_km, lq);
                let mut out = [0.0; 3];
                for (&i, &w) in cell.i.iter().zip(&cell.w) {
                    for (o, x) in out.iter_mut().zip(c.rgb[i]) {
                        *o += w * x;
                    }
                }
                out
            }
            None => self.rgb(h_km),
        }
    }

    /// An artist colour map: rows of [altitude_km, r, g, b] with ascending
    /// altitudes (validated by the scene), colour per keV deposited. Linear
    /// interpolation between rows, clamped to the first and last row.
    pub fn colormap(rows: &[[f64; 4]]) -> Self {
        let (lo, hi) = match (rows.first(), rows.last()) {
            (Some(a), Some(b)) => (a[0], b[0]),
            _ => return Self { h0: 0.0, dh: 1.0, rgb: vec![[0.0; 3]], chem: None },
        };
        let dh = 0.05;
        let n = (((hi - lo) / dh).ceil() as usize).max(1) + 1;
        let rgb = (0..n).map(|i| colormap_rgb(rows, lo + i as f64 * dh)).collect();
        Self { h0: lo, dh, rgb, chem: None }
    }

    /// Colour per keV at `h_km` (linear between samples, clamped at the ends).
    #[inline]
    pub fn rgb(&self, h_km: f64) -> [f64; 3] {
        let u = ((h_km - self.h0) / self.dh).max(0.0);
        let i = (u as usize).min(self.rgb.len() - 1);
        if i + 1 >= self.rgb.len() {
            return self.rgb[self.rgb.len() - 1];
        }
        let f = u - i as f64;
        let (a, b) = (self.rgb[i], self.rgb[i + 1]);
        std::array::from_fn(|k| a[k] + (b[k] - a[k]) * f)
    }

    /// Colour of energy deposited at the true altitude `h_km` and
    /// ionization rate `q`, with the chromaticity taken at `h_colour_km` (the
    /// report's colour noise perturbs the colour, not the intensity):
    /// luminance of `rgb_q(h, q)`, hue and saturation of
    /// `rgb_q(h_colour, q)`.
    #[inline]
    pub fn rgb_with_colour_altitude(&self, h_km: f64, h_colour_km: f64, q: f64) -> [f64; 3] {
        let lq = crate::physics::chemistry::table::ChemistryTable::log_q(q);
        let c = self.rgb_lq(h_colour_km, lq);
        let own = self.rgb_lq(h_km, lq);
        let y = luminance(own);
        let yc = luminance(c);
        if yc > 0.0 {
            c.map(|x| x * y / yc)
        } else {
            own
        }
    }
}

/// Artist colour map lookup: linear interpolation in altitude, clamped.
pub fn colormap_rgb(rows: &[[f64; 4]], h_km: f64) -> [f64; 3] {
    let Some(first) = rows.first() else { return [0.0; 3] };
    if h_km <= first[0] {
        return [first[1], first[2], first[3]];
    }
    for w in rows.windows(2) {
        if h_km <= w[1][0] {
            let t = (h_km - w[0][0]) / (w[1][0] - w[0][0]);
            return std::array::from_fn(|k| w[0][k + 1] + (w[1][k + 1] - w[0][k + 1]) * t);
        }
    }
    let last = rows[rows.len() - 1];
    [last[1], last[2], last[3]]
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::util::colour::{cie1931_xyz, gamut_map, xyz_to_rec709};

    const EYE: Observer = Observer::Eye;

    #[test]
    fn one_557_7_photon_has_unit_luminance_and_lines_have_their_hues() {
        for o in Observer::ALL {
            assert!((luminance(line_rgb(557.7, o)) - 1.0).abs() < 1e-12);
            let g = line_rgb(557.7, o);
            assert!(g[1] > g[0] && g[1] > g[2], "{o:?} green {g:?}");
            let r = line_rgb(630.0, o);
            assert!(r[0] > 5.0 * r[1] && r[0] > 5.0 * r[2], "{o:?} red {r:?}");
            let b = line_rgb(427.8, o);
            assert!(b[2] > b[0] && b[2] > b[1], "{o:?} violet {b:?}");
        }
        // The camera's green line has almost no red (a saturated green); the
        // eye's gamut-mapped one keeps 0.37 of its green in red (yellowish).
        let (cam, eye) = (line_rgb(557.7, Observer::Camera), line_rgb(557.7, EYE));
        assert!(cam[0] < 0.05 * cam[1] && eye[0] > 0.3 * eye[1], "camera {cam:?} eye {eye:?}");
    }

    #[test]
    fn every_wavelength_of_the_visible_has_a_colour_for_every_observer() {
        // Any line or band the line model adds is covered: finite, >= 0.
        for o in Observer::ALL {
            for l in 380..=780 {
                let c = line_rgb(l as f64 + 0.3, o);
                assert!(c.iter().all(|x| x.is_finite() && *x >= 0.0), "{o:?} {l}: {c:?}");
            }
        }
        assert_eq!(bands_rgb(&[557.7], EYE), line_rgb(557.7, EYE));
    }

    #[test]
    fn yields_match_the_rules_of_thumb() {
        let m = EmissionModel::default();
        let y110 = m.yields(110.0);
        // 427.8 nm: 0.34 photons/keV scaled by x_N2 (0.76 at 110 km).
        assert!((y110.n2p_4278 - 0.34 * 0.763 / 0.781).abs() < 0.01, "{y110:?}");
        // Green about 3 times the 427.8 yield at 110 km ("a few times").
        let ratio = y110.oi_5577 / y110.n2p_4278;
        assert!((2.0..5.0).contains(&ratio), "green/blue {ratio}");
        // Lower border: green at 90 km below a third of its 110 km yield.
        assert!(m.yields(90.0).oi_5577 < y110.oi_5577 / 3.0);
        // Red: negligible at 110 km, quenched half way near 260 km, 630:636.4 = 3.
        assert!(y110.oi_6300 < 0.01 * y110.oi_5577);
        let y = m.yields(300.0);
        assert!((y.oi_6300 / y.oi_6364 - 3.0).abs() < 1e-12);
        assert!(m.yields(300.0).oi_6300 > m.yields(200.0).oi_6300);
    }

    #[test]
    fn colour_is_green_at_110_km_and_red_at_250_km() {
        let m = EmissionModel::default();
        let c = m.rgb_per_kev(110.0);
        assert!(c[1] > c[0] && c[1] > c[2], "110 km {c:?}");
        let c = m.rgb_per_kev(250.0);
        assert!(c[0] > c[1] && c[0] > c[2], "250 km {c:?}");
        // The lower border is bluer than the green layer (violet N2+ shows).
        let (lo, mid) = (m.rgb_per_kev(88.0), m.rgb_per_kev(110.0));
        assert!(lo[2] / lo[1] > mid[2] / mid[1].max(1e-30), "{lo:?} {mid:?}");
    }

    #[test]
    fn n2_1p_is_red_and_makes_the_lower_border_of_hard_aurora_pink() {
        let c = n2_1p_rgb(EYE);
        assert!(c[0] > 5.0 * c[1] && c[0] > 5.0 * c[2], "1P colour {c:?}");
        // Its mean wavelength lies inside its bands.
        assert!((N2_1P_BANDS_NM.iter().sum::<f64>() / 6.0 - N2_1P.lambda_nm).abs() < 0.1);
        // The eye's colours (the ratios below are the CIE observer's).
        let m = EmissionModel::default().with_observer(EYE);
        // 1P follows N2 like 427.8 nm at every altitude.
        for h in [80.0, 100.0, 150.0, 250.0] {
            let y = m.yields(h);
            assert!((y.n2_1p / y.n2p_4278 - R_1P).abs() < 1e-12);
        }
        // Green layer: green dominates. Lower border: red over green grows
        // steadily downward (R = G near 86 km on NRLMSIS, 5 times the green
        // layer's ratio by 84 km), and below 84 km red and blue both exceed
        // green: pink/magenta. (557.7 nm holds 0.37 of its red/green at
        // 110 km: the gamut-mapped green line is yellowish.)
        let mid = m.rgb_per_kev(110.0);
        assert!(mid[1] > mid[0] && mid[1] > mid[2], "110 km {mid:?}");
        let rg = |h: f64| m.rgb_per_kev(h)[0] / m.rgb_per_kev(h)[1];
        assert!(rg(84.0) > 5.0 * rg(110.0), "{} vs {}", rg(84.0), rg(110.0));
        for h in [78.0, 81.0, 83.5] {
            let lo = m.rgb_per_kev(h);
            assert!(lo[0] > lo[1] && lo[2] > lo[1], "{h} km {lo:?}");
        }
        for k in 0..16 {
            let h = 78.0 + 2.0 * k as f64;
            assert!(rg(h) > rg(h + 2.0), "red/green not growing downward at {h} km");
        }
    }

    #[test]
    fn table_interpolates_the_model_and_clamps() {
        let m = EmissionModel::default();
        let t = ColourTable::physical(&m);
        for h in [95.3, 110.01, 151.77, 247.5] {
            let (a, b) = (t.rgb(h), m.rgb_per_kev(h));
            for k in 0..3 {
                // Linear interpolation error h^2/8 |f''| relative: ~1e-4 here.
                assert!((a[k] - b[k]).abs() <= 1e-3 * (b[k].abs() + 1e-3), "{h}: {a:?} vs {b:?}");
            }
        }
        assert_eq!(t.rgb(10.0), t.rgb(TABLE_H.0));
        assert_eq!(t.rgb(5000.0), t.rgb(TABLE_H.1));
        // Colour altitude changes chromaticity only.
        let c = t.rgb_with_colour_altitude(110.0, 250.0, 0.0);
        assert!((luminance(c) - luminance(t.rgb(110.0))).abs() < 1e-12);
        assert!(c[0] > c[1]);
    }

    #[test]
    fn colormap_interpolates_linearly_and_clamps_at_the_ends() {
        let rows = [[100.0, 0.0, 1.0, 0.0], [200.0, 1.0, 0.0, 0.5]];
        assert_eq!(colormap_rgb(&rows, 50.0), [0.0, 1.0, 0.0]);
        assert_eq!(colormap_rgb(&rows, 300.0), [1.0, 0.0, 0.5]);
        let c = colormap_rgb(&rows, 125.0);
        assert!((c[0] - 0.25).abs() < 1e-12 && (c[1] - 0.75).abs() < 1e-12 && (c[2] - 0.125).abs() < 1e-12);
        let t = ColourTable::colormap(&rows);
        let c2 = t.rgb(125.0);
        for k in 0..3 {
            assert!((c2[k] - c[k]).abs() < 1e-12);
        }
        assert_eq!(t.rgb(0.0), [0.0, 1.0, 0.0]);
        assert_eq!(t.rgb(1e4), [1.0, 0.0, 0.5]);
    }

    // ---- Oracles (docs/mutants/REPORT.md): closed forms, literature
    // numbers and conservation, not the code's constants read back.

    #[test]
    fn a_line_photon_weighs_its_energy_times_ybar() {
        // Gamut mapping keeps Y, so one photon of wavelength l has luminance
        // (557.7 / l) Y(l) / Y(557.7): photon energy h c / l times the
        // luminous efficiency, relative to the 557.7 nm unit. Y is the
        // luminance of the Rec.709 colour of the CMFs, i.e. ybar to the
        // matrix's 4 digits (1e-3 at 427.8 nm), taken exactly here.
        let y = |l: f64| luminance(xyz_to_rec709(cie1931_xyz(l)));
        for l in [427.8, 557.7, 630.0, 636.4, 666.8] {
            let want = 557.7 / l * y(l) / y(557.7);
            assert!((luminance(line_rgb(l, EYE)) / want - 1.0).abs() < 1e-12, "{l}");
        }
        // The N2 1P colour is the gamut-mapped mixture of its bands, equal
        // photon counts, each weighted by its photon energy.
        let mut xyz = [0.0; 3];
        for l in N2_1P_BANDS_NM {
            let c = cie1931_xyz(l);
            for k in 0..3 {
                xyz[k] += 557.7 / l * c[k] / 6.0;
            }
        }
        let want = gamut_map(xyz_to_rec709(xyz)).map(|c| c / y(557.7));
        let got = n2_1p_rgb(EYE);
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-12 * want[0], "{got:?} vs {want:?}");
        }
        assert!((luminance(got) - luminance(xyz_to_rec709(xyz)) / y(557.7)).abs() < 1e-12);
    }

    #[test]
    fn chemistry_shares_the_simple_models_1p_ratio_and_its_table_has_its_colours() {
        assert_eq!(crate::physics::chemistry::R_1P, R_1P);
        let atm = Atmosphere::nrlmsis21();
        let t = ColourTable::chemistry(&atm, Observer::default());
        assert!(t.needs_q() && !ColourTable::physical(&EmissionModel::default()).needs_q());
        // rgb_q is the colour of line_yields (bilinear on both: the same
        // weights), green at 110 km, red at 250 km.
        for (h, q) in [(110.3, 2e3), (251.1, 1.5)] {
            let y = t.line_yields(h, q).unwrap().as_array();
            let (a, b) = (t.rgb_q(h, q), lines_rgb(y, Observer::default()));
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() <= 1e-9 * (b[k].abs() + 1e-9), "{h}: {a:?} {b:?}");
            }
        }
        let g = t.rgb_q(110.0, 2e3);
        assert!(g[1] > g[0] && g[1] > g[2], "{g:?}");
        let r = t.rgb_q(250.0, 1.5);
        assert!(r[0] > r[1] && r[0] > r[2], "{r:?}");
    }

    #[test]
    fn line_yields_as_array_follow_the_lines_order() {
        let y = LineYields { oi_5577: 1.0, oi_6300: 2.0, oi_6364: 3.0, n2p_4278: 4.0, n2_1p: 5.0 };
        assert_eq!(y.as_array(), [1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(LINES.map(|l| l.name), ["OI 557.7 nm", "OI 630.0 nm", "OI 636.4 nm", "N2+ 427.8 nm", "N2 1P 647-688 nm"]);
    }

    /// The emission model as documented on [`EmissionModel`], with the rates
    /// as the doc cites them (lifetimes, not rates), on the composition of
    /// the atmosphere at `h`.
    fn documented_yields(c: Composition) -> [f64; 5] {
        let total = c.n2 + c.o2 + c.o;
        let (x_n2, x_o) = (c.n2 / total, c.o / total);
        // Competition kinetics: fraction of N2(A) quenched by O.
        let t_a = 3e-11 * c.o / (3e-11 * c.o + 2.5e-12 * c.o2 + 0.5);
        // Stern-Volmer survival against quenching, lifetime tau, rate k, density n.
        let stern_volmer = |tau: f64, k: f64, n: f64| 1.0 / (1.0 + tau * k * n);
        let green = stern_volmer(0.7, 5e-14, c.o2) * (1.33 * x_n2 * t_a + 2.0 * x_o);
        let red = 20.0 * x_o * stern_volmer(110.0, 3e-11, c.n2);
        let blue = 0.34 * x_n2 / 0.781;
        [green, 0.75 * red, 0.25 * red, blue, blue]
    }

    use crate::physics::atmosphere::Composition;

    #[test]
    fn yields_are_the_documented_kinetics_at_every_altitude() {
        for atmosphere in [Atmosphere::nrlmsis21(), Atmosphere::us1976()] {
            let m = EmissionModel::new(atmosphere.clone());
            for i in 0..=130 {
                let h = 50.0 + 5.0 * i as f64;
                let got = m.yields(h).as_array();
                let want = documented_yields(atmosphere.composition(h));
                for k in 0..5 {
                    // Same arithmetic in a different order: rounding only.
                    assert!((got[k] - want[k]).abs() <= 1e-12 * want[k].abs(), "{h} km line {k}: {} vs {}", got[k], want[k]);
                }
            }
        }
    }

    #[test]
    fn yields_reach_their_physical_limits_and_conserve_energy() {
        let m = EmissionModel::default();
        // The default model's own atmosphere (U.S. Standard Atmosphere 1976).
        let a = Atmosphere::default();
        // Well-mixed 50-80 km: N2 is 78.08 % of the air, 78.85 % of N2+O2
        // (Ar not counted), so 427.8 nm is Rees & Luckey's 0.34 photons/keV
        // to 1 %.
        for h in [50.0, 65.0, 80.0] {
            let y = m.yields(h).n2p_4278;
            assert!((y / 0.34 - 1.0).abs() < 0.015, "{h} km: {y}");
        }
        // Top of the table (700 km), nearly pure O: 557.7 tends to the direct
        // impact yield 2.0 per keV into O (O2 and N2(A) transfer gone) and
        // 630.0 + 636.4 nm to the unquenched O(1D) yield 20 per keV into O
        // ([N2] / 3.03e8 cm^-3 quenches a fraction of it: Stern-Volmer).
        let c = a.composition(700.0);
        let x_o = c.o / c.total();
        let y = m.yields(700.0);
        assert!((y.oi_5577 / (2.0 * x_o) - 1.0).abs() < 1e-3, "{y:?}");
        let q = 1.0 / (1.0 + c.n2 / (1.0 / (110.0 * 3e-11)));
        assert!(((y.oi_6300 + y.oi_6364) / (20.0 * x_o * q) - 1.0).abs() < 1e-12);
        // O(1D) half-quenched where [N2] = 1 / (110 s * 3e-11 cm^3/s).
        let n_half = 1.0 / (110.0 * 3e-11);
        let h_half = (0..65000).map(|i| 50.0 + 0.01 * i as f64).find(|&h| a.composition(h).n2 < n_half).unwrap();
        let c = a.composition(h_half);
        let y = m.yields(h_half);
        let q = (y.oi_6300 + y.oi_6364) / (20.0 * c.o / c.total());
        assert!((q - 0.5).abs() < 1e-3, "{h_half} km: {q}");
        // Energy: photons per keV times photon energy (1239.84 eV nm / l)
        // stays below the keV deposited, at every altitude (a few % at most).
        for i in 0..=650 {
            let h = 50.0 + i as f64;
            let radiated: f64 = m.yields(h).as_array().iter().zip(LINES).map(|(n, l)| n * 1.23984 / l.lambda_nm).sum();
            assert!((0.0..0.1).contains(&radiated), "{h} km: {radiated} keV per keV");
        }
    }

    #[test]
    fn colour_per_kev_is_the_sum_of_the_line_colours() {
        // Light adds: rgb = sum over lines of yield times one photon's colour
        // (the 1P bands through their mixture colour).
        let m = EmissionModel::default();
        let o = m.observer;
        let colours = [line_rgb(557.7, o), line_rgb(630.0, o), line_rgb(636.4, o), line_rgb(427.8, o), n2_1p_rgb(o)];
        for h in [70.0, 95.0, 110.0, 180.0, 300.0] {
            let y = m.yields(h).as_array();
            let got = m.rgb_per_kev(h);
            for k in 0..3 {
                let want: f64 = (0..5).map(|i| y[i] * colours[i][k]).sum();
                assert!((got[k] - want).abs() < 1e-12 * (want.abs() + 1e-3), "{h} km {k}: {} vs {want}", got[k]);
            }
        }
    }

    #[test]
    fn tables_end_at_their_last_row_and_black_colour_altitude_keeps_the_colour() {
        let m = EmissionModel::default();
        let t = ColourTable::physical(&m);
        let (a, b) = (t.rgb(TABLE_H.1), m.rgb_per_kev(TABLE_H.1));
        let (c, d) = (t.rgb(TABLE_H.0), m.rgb_per_kev(TABLE_H.0));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-12 * b[k].abs() && (c[k] - d[k]).abs() <= 1e-12 * d[k].abs());
        }
        // A black colour-map row has no chromaticity: the colour of the true
        // altitude is kept.
        let rows = [[100.0, 0.0, 0.0, 0.0], [200.0, 1.0, 0.5, 0.25], [250.0, 0.2, 0.3, 0.4]];
        let t = ColourTable::colormap(&rows);
        assert_eq!(t.rgb_with_colour_altitude(150.0, 100.0, 0.0), t.rgb(150.0));
        let (end, mid) = (t.rgb(250.0), t.rgb(225.0));
        for k in 0..3 {
            assert!((end[k] - rows[2][k + 1]).abs() < 1e-12, "{end:?}");
            assert!((mid[k] - 0.5 * (rows[1][k + 1] + rows[2][k + 1])).abs() < 1e-12);
        }
        assert_eq!(ColourTable::colormap(&[]).rgb(120.0), [0.0; 3]);
        assert_eq!(colormap_rgb(&[], 120.0), [0.0; 3]);
    }

    #[test]
    fn colormap_table_spans_rows_below_sea_level() {
        // The scene allows any strictly ascending finite altitudes; a map
        // from -50 to 100 km is linear in between, and its table covers all
        // of it (grey ramp: value (h + 50) / 150 per channel).
        let rows = [[-50.0, 0.0, 0.0, 0.0], [100.0, 1.0, 1.0, 1.0]];
        let t = ColourTable::colormap(&rows);
        for h in [-50.0, 0.0, 37.5, 90.0, 100.0] {
            let c = t.rgb(h);
            assert!((c[0] - (h + 50.0) / 150.0).abs() < 1e-12, "{h} km: {c:?}");
        }
    }
}
