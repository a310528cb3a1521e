//! Einstein coefficients of the oxygen lines' upper states, one table for
//! every user: the chemistry's emitting fractions, the lifetimes
//! (`crate::physics::emission::lifetime`) and the air's line mix
//! (`crate::physics::air_extinction`).
//!
//! **O(1D)** radiates at 630.0 nm (1D2 -> 3P2) and 636.4 nm (1D2 -> 3P1),
//! both magnetic dipole with a small electric quadrupole part. Storey &
//! Zeippen (2000, MNRAS 312, 813) added the relativistic corrections to
//! the magnetic dipole operator that lower the ratio of these homologous
//! pairs; their coefficients give a 630.0 / 636.4 nm photon ratio of
//! 2.997, and Sharpee & Slanger (2006, J. Phys. Chem. A 110, 6707)
//! measured 2.997 +- 0.016 in nightglow spectra (Keck HIRES), against 3.10
//! from NIST's recommended coefficients and 3.16 from the older pair GLOW
//! uses (0.00585, 0.00185 s^-1). A(630.0) = 5.63e-3 s^-1; A(636.4) is
//! A(630.0) / 2.997 = 1.879e-3 s^-1, so the photon ratio is S&Z's exactly.
//! The 639.2 nm line (1D2 -> 3P0, A ~ 1e-6 s^-1, 1/1700 of 636.4 nm as
//! Sharpee & Slanger measured it) is left out: a thousandth of the red.
//! The radiative lifetime of O(1D) is `1 / (A_6300 + A_6364)` = 133.2 s
//! (it was 129.9 s with GLOW's pair).
//!
//! **O(1S)**: 557.7 nm (1S0 -> 1D2, A = 1.06 s^-1) and 297.2 nm
//! (1S0 -> 3P1, 0.045 s^-1), GLOW's values (Solomon 2017).

/// One radiative transition: its wavelength in air, nm, and Einstein A, s^-1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    pub lambda_nm: f64,
    pub a_per_s: f64,
}

/// The 630.0 / 636.4 nm photon ratio of Storey & Zeippen's coefficients
/// (module doc), measured 2.997 +- 0.016 by Sharpee & Slanger (2006).
pub const O1D_PHOTON_RATIO: f64 = 2.997;

/// O(1D)'s lines, 630.0 then 636.4 nm (module doc).
pub const O1D: [Transition; 2] =
    [Transition { lambda_nm: 630.0, a_per_s: 5.63e-3 }, Transition { lambda_nm: 636.4, a_per_s: 5.63e-3 / O1D_PHOTON_RATIO }];

/// O(1S)'s lines, 557.7 then 297.2 nm.
pub const O1S: [Transition; 2] = [Transition { lambda_nm: 557.7, a_per_s: 1.06 }, Transition { lambda_nm: 297.2, a_per_s: 0.045 }];

/// Einstein coefficients, s^-1, read from the tables.
pub const A_6300: f64 = O1D[0].a_per_s;
pub const A_6364: f64 = O1D[1].a_per_s;
pub const A_5577: f64 = O1S[0].a_per_s;
pub const A_2972: f64 = O1S[1].a_per_s;
/// O(1D)'s and O(1S)'s total radiative rates, s^-1.
pub const A_1D: f64 = A_6300 + A_6364;
pub const A_1S: f64 = A_5577 + A_2972;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_red_pair_has_storey_and_zeippens_ratio_and_a_133_s_lifetime() {
        // Sharpee & Slanger 2006: 2.997 +- 0.016 measured; within 1 %.
        let r = A_6300 / A_6364;
        assert!((r / 2.997 - 1.0).abs() < 0.01, "{r}");
        // The old pair's 3.16 is outside the measurement's 1 %.
        assert!((0.00585f64 / 0.00185 / 2.997 - 1.0).abs() > 0.05);
        let tau = 1.0 / A_1D;
        assert!((tau - 133.2).abs() < 0.05, "{tau}");
    }
}
