//! Electron transport in the continuous slowing-down approximation (CSDA),
//! the deposition model before Fang's fits (`beams.deposition = "csda"`):
//! an electron loses energy continuously along its path, at a rate set by
//! the air it crosses, until it stops.
//!
//! **Range-energy relation.** In the CSDA an electron of energy E (keV)
//! stops after a fixed column mass of air, its range R(E) (g cm^-2),
//! whatever the path's shape. For precipitating electrons in air, from
//! Barrett & Hays (1976, "Spatial distribution of energy deposited in
//! nitrogen by electrons", J. Chem. Phys. 64, 743) as given by Rees (1989,
//! "Physics and Chemistry of the Upper Atmosphere", Cambridge University
//! Press):
//!
//! ```text
//! R(E) = 4.30e-7 + 5.36e-6 E^1.67      (g cm^-2, E in keV)
//! ```
//!
//! ([`range_g_cm2`]) and its inverse ([`energy_from_range`]), 0 where the
//! residual range does not exceed R(0).
//!
//! **Slowing down along a path.** An electron that has crossed a column X
//! has the energy whose range is what is left: `E' = R^-1(R(E) - X)`, and it
//! deposited `E - E'` on the way. The beams keep the residual range
//! `r = R(E0) - sum X` and subtract each step's column.
//!
//! **Column of a straight step.** In a plane-parallel atmosphere with
//! vertical column mass C(z) above altitude z (`crate::physics::atmosphere`), a
//! straight step of length s between altitudes z0 and z1 crosses
//!
//! ```text
//! X = (s / |z1 - z0|) |C(z1) - C(z0)|        (rho s when level)
//! ```
//!
//! ([`step_column`]; the level case is `Atmosphere::slant_column`'s).
//!
//! The model puts an electron's energy at the end of its range (a Bragg-like
//! peak at the stopping depth), where Fang's transport fits spread it
//! (`crate::physics::deposition::fang`); it is kept for comparison.

use crate::physics::atmosphere::Atmosphere;
use crate::util::fmath;

/// Range-energy relation of precipitating electrons in air (Barrett & Hays
/// 1976 / Rees 1989): the column mass, g cm^-2, that stops an electron of
/// energy `e_kev` keV.
#[inline]
pub fn range_g_cm2(e_kev: f64) -> f64 {
    4.30e-7 + 5.36e-6 * fmath::powf(e_kev.max(0.0), 1.67)
}

/// Inverse of [`range_g_cm2`]: the energy whose range is `r`; 0 when `r`
/// does not exceed the relation's offset R(0).
#[inline]
pub fn energy_from_range(r: f64) -> f64 {
    let x = r - 4.30e-7;
    if x <= 0.0 {
        0.0
    } else {
        fmath::powf(x / 5.36e-6, 1.0 / 1.67)
    }
}

/// The column mass, g cm^-2, along a straight step of length `len` km from
/// altitude `z0` to `z1`, whose vertical column masses are `col0` and `col1`
/// (the caller has them): `(len / |dz|) |col1 - col0|`, or
/// `Atmosphere::slant_column` (rho times length at the mid-point) when the
/// step is level to within 1e-6 of its length.
#[inline]
pub fn step_column(atm: &Atmosphere, z0: f64, z1: f64, len: f64, col0: f64, col1: f64) -> f64 {
    let dz = (z1 - z0).abs();
    if dz > 1e-6 * len && dz > 1e-9 {
        (len / dz) * (col1 - col0).abs()
    } else {
        atm.slant_column(z0, z1, len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_energy_inverse_round_trips() {
        for e in [0.05, 0.3, 1.0, 3.7, 10.0, 55.0] {
            let back = energy_from_range(range_g_cm2(e));
            assert!((back / e - 1.0).abs() < 1e-12, "{e} -> {back}");
        }
        assert_eq!(energy_from_range(4.0e-7), 0.0);
    }

    #[test]
    fn a_step_crosses_the_column_between_its_ends_scaled_by_its_slant() {
        let a = Atmosphere::us1976();
        let (c0, c1) = (a.column_mass(120.0), a.column_mass(110.0));
        // Vertical: the column between the altitudes; 60 degrees from the
        // vertical: twice that (rounding only).
        assert!((step_column(&a, 120.0, 110.0, 10.0, c0, c1) / (c1 - c0) - 1.0).abs() < 1e-12);
        assert!((step_column(&a, 120.0, 110.0, 20.0, c0, c1) / (2.0 * (c1 - c0)) - 1.0).abs() < 1e-12);
        // Level: rho times length, as slant_column.
        assert_eq!(step_column(&a, 110.0, 110.0, 3.0, c1, c1), a.slant_column(110.0, 110.0, 3.0));
    }
}
