//! Where the auroral oval is: its boundaries in corrected geomagnetic
//! latitude (`crate::physics::magnetic_coordinates`) at a magnetic local
//! time, from the AL index, by Starkov (1994, "Mathematical model of the
//! auroral boundaries", Geomagnetism and Aeronomy 34(3), 331-336).
//!
//! **The model.** Each boundary's corrected geomagnetic colatitude, degrees,
//! at magnetic local time `t` (hours) is a sum of three harmonics,
//!
//! ```text
//! theta = A0 + A1 cos(15 (t + a1)) + A2 cos(15 (2t + a2)) + A3 cos(15 (3t + a3))
//! ```
//!
//! (the cosines' arguments in degrees), and each coefficient is a cubic in
//! `x = log10 |AL|` (AL in nT): `A = b0 + b1 x + b2 x^2 + b3 x^3`, with
//! Starkov's table of `b` for three boundaries: the oval's poleward edge,
//! its equatorward edge, and the diffuse aurora's equatorward edge
//! ([`STARKOV`]; the same numbers as ocbpy 0.7.0's
//! `ocbpy.boundaries.models`). A colatitude below 0 is taken as 0.
//!
//! **From Kp.** Where only Kp is known, AL comes from Starkov's (1994b)
//! regression as Sigernes et al. (2011, "Two methods to forecast auroral
//! displays", J. Space Weather Space Clim. 1, A03) used it:
//!
//! ```text
//! AL = -(18 - 12.3 Kp + 27.2 Kp^2 - 2 Kp^3) nT
//! ```
//!
//! (-18 nT at Kp 0, -386.5 nT at Kp 5, -652.5 nT at Kp 9; it rises
//! monotonically over 0-9). The boundaries are the same in both
//! hemispheres (in corrected geomagnetic latitude, with its sign).
//!
//! **Checked** against ocbpy 0.7.0's `starkov_auroral_boundary`
//! (`tests/data/starkov_oracle.csv`, made by
//! `tools/reference/aacgm_oval_table.py`).

use crate::util::fmath;

/// One of Starkov's boundaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// The auroral oval's poleward edge.
    Poleward,
    /// The auroral oval's equatorward edge.
    Equatorward,
    /// The diffuse aurora's equatorward edge.
    DiffuseEquatorward,
}

/// Starkov's coefficients `[b0, b1, b2, b3]` for `A0, A1, a1, A2, a2, A3,
/// a3` (degrees for A, hours for a), per boundary in [`Boundary`] order.
pub const STARKOV: [[[f64; 4]; 7]; 3] = [
    [
        [-0.07, 24.54, -12.53, 2.15],
        [-10.06, 19.83, -9.33, 1.24],
        [-6.61, 10.17, -5.80, 1.19],
        [-4.44, 7.47, -3.01, 0.25],
        [6.37, -1.10, 0.34, -0.38],
        [-3.77, 7.90, -4.73, 0.91],
        [-4.48, 10.16, -5.87, 0.98],
    ],
    [
        [1.16, 23.21, -10.97, 2.03],
        [-9.59, 17.78, -7.20, 0.96],
        [-2.22, 1.50, -0.58, 0.08],
        [-12.07, 17.49, -7.96, 1.15],
        [-23.98, 42.79, -26.96, 5.56],
        [-6.56, 11.44, -6.73, 1.31],
        [-20.07, 36.67, -24.20, 5.11],
    ],
    [
        [3.44, 29.77, -16.38, 3.35],
        [-2.41, 7.89, -4.32, 0.87],
        [-1.68, -2.48, 1.58, -0.28],
        [-0.74, 3.94, -3.09, 0.72],
        [8.69, -20.73, 13.03, -2.14],
        [-2.12, 3.24, -1.67, 0.31],
        [8.61, -5.34, -1.36, 0.76],
    ],
];

/// AL, nT (negative), from Kp (module doc: Starkov 1994b as Sigernes et al.
/// 2011 used it).
pub fn al_from_kp_nt(kp: f64) -> f64 {
    -(18.0 - 12.3 * kp + 27.2 * kp * kp - 2.0 * kp * kp * kp)
}

/// The boundary's corrected geomagnetic colatitude, degrees, at magnetic
/// local time `mlt_h` and AL index `al_nt` (module doc).
pub fn colatitude_deg(boundary: Boundary, mlt_h: f64, al_nt: f64) -> f64 {
    let b = &STARKOV[boundary as usize];
    let x = fmath::log10(al_nt.abs());
    let c: Vec<f64> = b.iter().map(|k| k[0] + x * (k[1] + x * (k[2] + x * k[3]))).collect();
    let cos = |n: f64, a: f64| fmath::cos((15.0 * (n * mlt_h + a)).to_radians());
    (c[0] + c[1] * cos(1.0, c[2]) + c[3] * cos(2.0, c[4]) + c[5] * cos(3.0, c[6])).max(0.0)
}

/// The oval at one magnetic local time: its equatorward and poleward
/// edges' corrected geomagnetic latitudes, degrees (north).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OvalEdges {
    pub equatorward_deg: f64,
    pub poleward_deg: f64,
}

/// The oval's edges at `mlt_h` for AL `al_nt`.
pub fn edges(mlt_h: f64, al_nt: f64) -> OvalEdges {
    OvalEdges {
        equatorward_deg: 90.0 - colatitude_deg(Boundary::Equatorward, mlt_h, al_nt),
        poleward_deg: 90.0 - colatitude_deg(Boundary::Poleward, mlt_h, al_nt),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ORACLE: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/starkov_oracle.csv"));

    /// The largest difference from ocbpy over the oracle's 36 rows and 3
    /// boundaries, degrees, of `model(boundary, mlt_h, al_nt)`.
    fn worst(model: impl Fn(Boundary, f64, f64) -> f64) -> f64 {
        let mut w = 0.0_f64;
        let mut n = 0;
        for row in ORACLE.lines().filter(|l| !l.starts_with('#')).skip(1) {
            let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
            for (b, want) in [Boundary::Poleward, Boundary::Equatorward, Boundary::DiffuseEquatorward].into_iter().zip(&v[2..]) {
                w = w.max((model(b, v[1], v[0]) - want).abs());
                n += 1;
            }
        }
        assert_eq!(n, 108);
        w
    }

    #[test]
    fn starkov_matches_ocbpy_at_four_activities_and_nine_hours() {
        // The same closed form: the oracle's six printed decimals.
        let w = worst(colatitude_deg);
        assert!(w < 1e-5, "{w} deg");
    }

    #[test]
    fn a_model_without_the_activity_fails_the_same_check() {
        // The boundaries of a quiet oval (AL -18 nT) whatever AL is: off by
        // degrees (the equatorward edge at midnight moves 5.5 degrees from
        // AL -18 to -386 nT).
        let w = worst(|b, t, _| colatitude_deg(b, t, -18.0));
        assert!(w > 1.0, "{w}");
    }

    #[test]
    fn kp_to_al_as_sigernes_et_al_and_the_oval_widens_equatorward_with_it() {
        assert!((al_from_kp_nt(0.0) + 18.0).abs() < 1e-12);
        assert!((al_from_kp_nt(5.0) + 386.5).abs() < 1e-9);
        assert!((al_from_kp_nt(9.0) + 652.5).abs() < 1e-9);
        let mut last = f64::INFINITY;
        for kp in 1..=9 {
            let e = edges(0.0, al_from_kp_nt(kp as f64));
            assert!(e.equatorward_deg < e.poleward_deg && e.equatorward_deg < last, "{kp}: {e:?}");
            last = e.equatorward_deg;
        }
        // Kp 5 at magnetic midnight: the oval from 61.85 to 73.12 degrees
        // (ocbpy's colatitudes 28.15 and 16.88 at AL -386.5 nT, the oracle).
        let e = edges(0.0, al_from_kp_nt(5.0));
        assert!((e.equatorward_deg - 61.85).abs() < 0.01 && (e.poleward_deg - 73.12).abs() < 0.01, "{e:?}");
    }
}
