//! Who looks at the aurora: the colour an observer records of one unit of
//! radiant power at a wavelength, in linear Rec.709 (D65 white) on the
//! photometric scale of CIE 1931's ybar ([`Observer::rgb`]).
//!
//! - [`Observer::Eye`]: the CIE 1931 2-degree observer
//!   ([`crate::util::colour::cie1931_xyz`], Wyman, Sloan & Shirley 2013)
//!   through IEC 61966-2-1's XYZ to Rec.709 matrix. Monochromatic lines fall
//!   outside Rec.709: 557.7 nm is a yellow-green (x 0.34, y 0.66).
//! - [`Observer::Camera`] (the default): a digital camera as photographs
//!   record the sky, the Nikon D5100's measured spectral sensitivities
//!   (Darrodi, Finlayson, Goodman & Mackiewicz 2015, "Reference data set
//!   for camera spectral sensitivity estimation", J. Opt. Soc. Am. A 32, 381;
//!   National Physical Laboratory monochromator measurements) white
//!   balanced for daylight D55 and taken to Rec.709 by a 3x3 matrix fitted by
//!   least squares on the 24 ColorChecker patches under D55 (rms residual
//!   0.009). The camera records 557.7 nm as a saturated green (hue about
//!   120 degrees) and 630.0 nm as crimson, as auroral photographs show them.
//!   The table, `data/observer_camera.csv` (per nm, 380-780 nm; 0
//!   outside), is made by `tools/observer_table` with colour-science and
//!   compiled in; its header holds the inputs' hash, the matrix and the
//!   residual. Linear between the nm rows.
//!
//! Both observers give D55 light the same luminance: the camera's table is
//! scaled so (docs/colour.md). Terms of the camera data: docs/data.md.
//!
//! **Into the gamut** ([`Observer::in_gamut`]): the eye's colour of a line
//! is moved toward the grey of equal luminance
//! ([`crate::util::colour::gamut_map`]); the camera's, as a raw converter
//! does after its matrix, has its negative channels clipped to 0 (427.8 nm
//! comes out of the matrix with a negative luminance, which the grey
//! mapping would turn black; clipped it is the violet-blue photographs
//! show).

use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// The observer whose colours the bake writes and the renderer shows.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "lowercase")]
pub enum Observer {
    /// A digital camera at daylight white balance (module doc).
    #[default]
    Camera,
    /// The CIE 1931 2-degree standard observer.
    Eye,
}

/// The committed camera table (module doc).
const CAMERA_CSV: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/observer_camera.csv"));
/// First and last wavelength of the camera table, nm (1 nm rows).
pub const CAMERA_RANGE_NM: (f64, f64) = (380.0, 780.0);

/// The camera's Rec.709 per nm from [`CAMERA_CSV`], parsed once.
fn camera_table() -> &'static [[f64; 3]] {
    static TABLE: OnceLock<Vec<[f64; 3]>> = OnceLock::new();
    TABLE.get_or_init(|| parse_camera(CAMERA_CSV))
}

/// The rows of the camera table: `wavelength_nm, camera_r, camera_g,
/// camera_b, ...` after `#` comments and the column names, one per nm from
/// [`CAMERA_RANGE_NM`]'s start. The file is ours and compiled in: a bad row
/// is a build fault, caught by the tests.
fn parse_camera(text: &str) -> Vec<[f64; 3]> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("wavelength"))
        .enumerate()
        .map(|(i, l)| {
            let f: Vec<f64> = l.split(',').map(|x| x.trim().parse().expect("camera table: a number")).collect();
            assert_eq!(f[0], CAMERA_RANGE_NM.0 + i as f64, "camera table: one row per nm");
            [f[1], f[2], f[3]]
        })
        .collect()
}

/// The camera's 3x3 matrix from its white-balanced raw RGB to linear
/// Rec.709, rows, as the table's header records it (`# matrix ...: 9
/// numbers`): the matrix the table's rows went through.
pub fn camera_matrix() -> [[f64; 3]; 3] {
    static M: OnceLock<[[f64; 3]; 3]> = OnceLock::new();
    *M.get_or_init(|| {
        let line = CAMERA_CSV.lines().find(|l| l.starts_with("# matrix")).expect("camera table: a matrix line");
        let v: Vec<f64> =
            line.rsplit(':').next().unwrap_or_default().split_whitespace().map(|x| x.parse().expect("camera table: a number")).collect();
        assert_eq!(v.len(), 9, "camera table: a 3x3 matrix");
        [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]]
    })
}

impl Observer {
    /// Every observer, in the order the scene lists them.
    pub const ALL: [Observer; 2] = [Observer::Camera, Observer::Eye];

    /// The scene's name of the observer.
    pub fn name(self) -> &'static str {
        match self {
            Observer::Camera => "camera",
            Observer::Eye => "eye",
        }
    }

    /// `rgb` brought into Rec.709 the way this observer's pipeline does it
    /// (module doc): the eye's gamut map, the camera's clip.
    pub fn in_gamut(self, rgb: [f64; 3]) -> [f64; 3] {
        match self {
            Observer::Eye => crate::util::colour::gamut_map(rgb),
            Observer::Camera => rgb.map(|x| x.max(0.0)),
        }
    }

    /// Linear Rec.709 (not gamut mapped) of one unit of radiant power at
    /// `lambda_nm`, on ybar's scale (module doc); 0 outside the camera
    /// table's range for the camera.
    pub fn rgb(self, lambda_nm: f64) -> [f64; 3] {
        match self {
            Observer::Eye => crate::util::colour::xyz_to_rec709(crate::util::colour::cie1931_xyz(lambda_nm)),
            Observer::Camera => {
                let t = camera_table();
                let u = lambda_nm - CAMERA_RANGE_NM.0;
                if !(0.0..=(t.len() - 1) as f64).contains(&u) {
                    return [0.0; 3];
                }
                let i = (u as usize).min(t.len() - 2);
                let f = u - i as f64;
                std::array::from_fn(|k| t[i][k] + (t[i + 1][k] - t[i][k]) * f)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::colour::{gamut_map, luminance};

    /// Hue in degrees of a linear RGB colour (HSV hexcone).
    fn hue(c: [f64; 3]) -> f64 {
        crate::util::colour::hsv_hue_saturation(c).0
    }

    #[test]
    fn the_table_has_a_row_per_nm_and_reads_linearly_between_rows() {
        assert_eq!(camera_table().len(), 401);
        let (a, b) = (Observer::Camera.rgb(557.0), Observer::Camera.rgb(558.0));
        let m = Observer::Camera.rgb(557.5);
        for k in 0..3 {
            assert!((m[k] - 0.5 * (a[k] + b[k])).abs() < 1e-12);
        }
        assert_eq!(Observer::Camera.rgb(379.9), [0.0; 3]);
        assert_eq!(Observer::Camera.rgb(780.1), [0.0; 3]);
        assert_ne!(Observer::Camera.rgb(780.0), [0.0; 3]);
    }

    #[test]
    fn the_camera_sees_the_green_line_green_and_the_eye_yellow_green() {
        // Photographs: 557.7 nm a saturated green, hue 120-140 degrees
        // after gamut mapping; the CIE observer's is yellow-green, about 101
        // in linear RGB (more yellow once encoded).
        let cam = Observer::Camera.in_gamut(Observer::Camera.rgb(557.7));
        let eye = Observer::Eye.in_gamut(Observer::Eye.rgb(557.7));
        assert!((110.0..150.0).contains(&hue(cam)), "camera {cam:?}: {}", hue(cam));
        assert!(hue(eye) < 105.0, "eye {eye:?}: {}", hue(eye));
        // 630.0 nm: red for both; the camera's crimson has almost no green.
        let red = Observer::Camera.in_gamut(Observer::Camera.rgb(630.0));
        assert!(red[0] > 10.0 * red[1] && red[0] > 10.0 * red[2], "{red:?}");
        // 427.8 nm: a negative luminance out of the matrix; clipped, blue
        // with a little red (violet), never black.
        let blue = Observer::Camera.in_gamut(Observer::Camera.rgb(427.8));
        assert!(luminance(Observer::Camera.rgb(427.8)) < 0.0 && gamut_map(Observer::Camera.rgb(427.8)) == [0.0; 3]);
        assert!(blue[2] > 10.0 * blue[1] && blue[0] > 0.0, "{blue:?}");
    }

    #[test]
    fn both_observers_give_daylight_the_same_luminance() {
        // The table is scaled so that D55 gives ybar's Y; an equal-energy
        // spectrum (close to daylight's flat middle) agrees to a few %.
        let y = |o: Observer| (380..=780).map(|l| luminance(o.rgb(l as f64))).sum::<f64>();
        let (c, e) = (y(Observer::Camera), y(Observer::Eye));
        assert!((c / e - 1.0).abs() < 0.1, "camera {c} eye {e}");
    }
}
