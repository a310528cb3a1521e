//! The N2 triplet states of the chemistry: the metastable N2(A3Sigma_u+),
//! which gives its energy to O and makes O(1S), and N2(B3Pi_g), the upper
//! state of the first positive (1P) bands. Both are local steady states of
//! their production per N2 ionization and their losses, stages a test can
//! call alone ([`n2_a`], [`n2_1p_per_n2_ion`]).
//!
//! **N2(A)**, `n_A = P_A / L_A`, made 0.60 per N2 ionization (GLOW's
//! electron-impact excitation of A, B, C, W and B' with their radiative
//! cascade into A; Cartwright 1978, J. Geophys. Res. 83, 517, for the
//! cascade), lost by
//!
//! - radiation (Vegard-Kaplan), 0.77 s^-1: v = 0 radiates at about 0.5 s^-1
//!   (Shemansky 1969, J. Chem. Phys. 51, 689) and the upper levels faster;
//!   0.77 is GLOW's mean over the auroral vibrational population;
//! - O, k = 3.1e-11 cm^3 s^-1 (GLOW; Piper, Caledonia & Kennealy 1981 and
//!   de Souza et al. 1985 measured 2.8-3.5e-11 for v = 0-2), of which 0.19
//!   makes O(1S) (GLOW's mean over v; Piper 1982, J. Chem. Phys. 77, 2373,
//!   measured a larger yield for v = 0, which falls with v);
//! - O2, 4.1e-12 (GLOW's mean over v; 2.5e-12 for v = 0, Kossyi et al.
//!   1992, Plasma Sources Sci. Technol. 1, 207), and NO, 8.9e-11;
//! - energy pooling N2(A) + N2(A) into N2(B) and N2(C), 7.7e-11 + 1.5e-10
//!   (Piper 1988, as compiled by Kossyi et al. 1992): quadratic in n_A, so
//!   `n_A = 2 P_A / (L_A + sqrt(L_A^2 + 4 k_p P_A))`; at auroral n_A (1e3 to
//!   1e5 cm^-3) it is under 1e-5 of the loss, kept so the balance is whole.
//!
//! At 110-120 km O takes 64-72 % of N2(A) (NRLMSIS 2.1), so the transfer
//! makes O(1S) nearly in proportion to the N2 ionization there, not to
//! N2 ionization x [O]: the N2(A) channel of 557.7 nm peaks 1.6 km below
//! 427.8 nm at E0 = 1 keV and 12.5 km below at 0.5 keV (docs/physics.md,
//! "Green above blue?").
//!
//! **N2(B) and the 1P bands.** N2(B) is made by electron impact on N2,
//! directly and by radiative cascade from N2(C) (the second positive
//! bands) and from the upper levels of W3Delta_u and B'3Sigma_u-; it
//! radiates in 5-8 us (A_B = 1.5e5 s^-1 taken for the v = 3-8 levels of the
//! visible Delta v = 3 bands; Gilmore, Laher & Espy 1992, J. Phys. Chem.
//! Ref. Data 21, 1005) and is quenched by N2 (1e-11 cm^3 s^-1) and O2
//! (3e-10; both from Kossyi et al. 1992): 10 % at 80 km, 2 % at 90 km. That
//! prompt part is the 1P of every altitude, normalised to [`R_1P`] photons of
//! the Delta v = 3 sequence per 427.8 nm photon where nothing quenches
//! (Vallance Jones 1974, "Aurora", ch. 4; Gattinger & Vallance Jones
//! 1974).
//!
//! The low levels of W (v = 0-2, nearly degenerate with B's lowest levels)
//! radiate to B only very slowly, in the far infrared, and live long enough
//! for collisions. Where N2 is dense they are handed to B by N2 collisions
//! (intersystem transfer B <-> W <-> B', Morrill & Benesch 1996, J.
//! Geophys. Res. 101, 261; Kirillov 2008, Ann. Geophys. 26, 1159), higher
//! up O quenches them first. That collisional cascade is
//! `Y_W [N2] / ([N2] + N2_HALF)` per unit of the prompt part: the transfer
//! beats the other losses below about 100 km ([`N2_HALF`] = 1e13 cm^-3,
//! the N2 density there). The 1P so gains relative to 427.8 nm below 100
//! km, as type-B aurora shows: about +50 % in the 1PG over N2+ 1NG (a
//! five-channel photometer in type-B red aurora, Can. J. Phys.; Vallance
//! Jones 1974). [`Y_W`] = 0.9 is fitted to that enhancement for E0 = 10-20
//! keV (tests/physics/published.rs); [`N2_HALF`] is an estimate of where
//! the transfer takes over, not a measured rate.

/// N2(A) made per N2 ionization (with the cascade into A).
pub const Y_N2A: f64 = 0.60;
/// N2(A) loss: radiation, s^-1; O, O2, NO, cm^3 s^-1 (module doc).
pub const A_N2A: f64 = 0.77;
pub const K_N2A_O: f64 = 3.1e-11;
pub const K_N2A_O2: f64 = 4.1e-12;
pub const K_N2A_NO: f64 = 8.9e-11;
/// O(1S) per N2(A) + O reaction.
pub const B_N2A_O1S: f64 = 0.19;
/// N2(A) + N2(A) energy pooling into B and C, cm^3 s^-1 (per pair).
pub const K_N2A_POOL: f64 = 7.7e-11 + 1.5e-10;
/// N2(B) radiative rate, s^-1, and its quenching by N2 and O2, cm^3 s^-1.
pub const A_N2B: f64 = 1.5e5;
pub const K_N2B_N2: f64 = 1e-11;
pub const K_N2B_O2: f64 = 3e-10;
/// N2 1P (Delta v = 3) photons per 427.8 nm photon where nothing quenches
/// and the collisional cascade is off (the high-altitude limit):
/// `crate::physics::emission::line_colour::R_1P`, equal by test.
pub const R_1P: f64 = 1.0;
/// The collisional cascade into N2(B), per unit of the prompt 1P, where N2
/// collisions win outright (fitted, module doc).
pub const Y_W: f64 = 0.9;
/// The N2 density at which the collisional cascade is half on, cm^-3.
pub const N2_HALF: f64 = 1e13;

/// N2(A) in steady state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct N2A {
    /// Density, cm^-3.
    pub density: f64,
    /// O(1S) made by N2(A) + O, cm^-3 s^-1.
    pub o1s_rate: f64,
}

/// N2(A) made by `q_n2` N2 ionizations cm^-3 s^-1 in O2, O and NO
/// densities `o2`, `o`, `no` (cm^-3), with every loss of the module doc.
pub fn n2_a(q_n2: f64, o2: f64, o: f64, no: f64) -> N2A {
    let p = Y_N2A * q_n2.max(0.0);
    let l = A_N2A + K_N2A_O * o + K_N2A_O2 * o2 + K_N2A_NO * no;
    // k_p n^2 + l n - p = 0, the root that stays finite as k_p p -> 0.
    let density = 2.0 * p / (l + (l * l + 4.0 * K_N2A_POOL * p).sqrt());
    N2A { density, o1s_rate: B_N2A_O1S * K_N2A_O * density * o }
}

/// N2 1P (Delta v = 3) photons per N2 ionization, given the 427.8 nm
/// photons per N2 ionization `y_4278`, at N2 and O2 densities `n2`, `o2`
/// (cm^-3): the prompt part (direct impact and radiative cascade) and the
/// collisional cascade from W, both through N2(B)'s quenching (module doc).
pub fn n2_1p_per_n2_ion(y_4278: f64, n2: f64, o2: f64) -> f64 {
    let quench = A_N2B / (A_N2B + K_N2B_N2 * n2 + K_N2B_O2 * o2);
    let cascade = Y_W * n2 / (n2 + N2_HALF);
    R_1P * y_4278 * (1.0 + cascade) * quench
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pooling_is_negligible_at_auroral_densities_and_the_root_is_the_linear_one_without_it() {
        // 1e5 N2 ionizations cm^-3 s^-1 at 100 km (O 4e11, O2 2e12, NO 2e8):
        // the linear balance's n_A and the pooled one agree within 1e-5.
        let (o2, o, no) = (2e12, 4e11, 2e8);
        let l = A_N2A + K_N2A_O * o + K_N2A_O2 * o2 + K_N2A_NO * no;
        let a = n2_a(1e5, o2, o, no);
        let linear = Y_N2A * 1e5 / l;
        assert!((a.density / linear - 1.0).abs() < 1e-5 && a.density < linear, "{} {linear}", a.density);
        // The root solves the quadratic.
        let r = K_N2A_POOL * a.density * a.density + l * a.density - Y_N2A * 1e5;
        assert!(r.abs() < 1e-9 * Y_N2A * 1e5, "{r}");
        // At an absurd rate pooling takes over and n_A grows as sqrt(P).
        let hi = n2_a(1e20, o2, o, no).density;
        assert!((hi / (Y_N2A * 1e20 / K_N2A_POOL).sqrt() - 1.0).abs() < 0.01, "{hi}");
        assert_eq!(n2_a(0.0, o2, o, no).density, 0.0);
    }

    #[test]
    fn the_1p_is_r_1p_times_427_8_high_up_and_gains_the_cascade_low_down() {
        let y = 0.022;
        // 150 km (N2 2.4e10, O2 2.3e9): the prompt part alone, within 0.3 %.
        let hi = n2_1p_per_n2_ion(y, 2.4e10, 2.3e9) / (R_1P * y);
        assert!((hi - 1.0).abs() < 3e-3, "{hi}");
        // 90 km (N2 4.3e13, O2 1.06e13): the cascade is 4.3/5.3 on, N2(B)
        // 2.4 % quenched.
        let lo = n2_1p_per_n2_ion(y, 4.3e13, 1.06e13) / (R_1P * y);
        let want = (1.0 + Y_W * 4.3 / 5.3) * A_N2B / (A_N2B + K_N2B_N2 * 4.3e13 + K_N2B_O2 * 1.06e13);
        assert!((lo - want).abs() < 1e-12 && lo > 1.6, "{lo}");
    }
}
