//! An all-sky imager's skymap for a rendered frame: for each pixel centre,
//! the azimuth and elevation of its ray seen from the camera, and the
//! latitude and longitude where that ray crosses a mapping altitude, the
//! calibration an all-sky camera network ships with its images (asilib's
//! `Imager` skymap, Shumko et al. 2023, "asilib: a Python library for
//! all-sky imager data", Frontiers in Astronomy and Space Sciences 10,
//! 1275186; THEMIS ASI skymaps, Mende et al. 2008, Space Sci. Rev. 141,
//! 357, map at 110 km).
//!
//! Azimuth is measured from the local north toward east and elevation from
//! the local horizon, in the camera's local frame on the round Earth
//! (`crate::geometry::earth::Earth::local_frame`). The mapping point is the
//! ray's exit through the sphere of radius `R + alt` about the Earth's
//! centre `c` (the ray starts below it): `t = -b + sqrt(b^2 - (|o - c|^2 -
//! (R + alt)^2))` with `b = (o - c) . u`. Its latitude and longitude are
//! those of the direction `v = (p - c) / |p - c|` on the sphere tangent to
//! the Earth at the scene's origin, whose own latitude and longitude
//! (`origin`, the `[site]`'s) fix the frame: the origin's east, north and
//! up axes are `E = (-sin l, cos l, 0)`, `N = (-sin f cos l, -sin f sin l,
//! cos f)`, `U = (cos f cos l, cos f sin l, sin f)` in Earth-centred
//! coordinates (f, l: the origin's latitude and longitude), so
//! `w = v_x E + v_y N + v_z U`, latitude `asin(w_z)` (computed as
//! `atan2(w_z, |(w_x, w_y)|)`), longitude `atan2(w_y, w_x)`. The ground being a sphere, the site's geodetic
//! latitude stands for the sphere's (WGS 84's flattening, a few tenths of a
//! degree, is left out). Pixels outside a fisheye's image circle are NaN in
//! every array; latitude and longitude are NaN below the horizon (the
//! ground hides the layer).

use crate::geometry::camera::CameraModel;
use crate::geometry::earth::Earth;
use crate::util::fmath;
use glam::DVec3;

/// A skymap: row-major arrays of `height x width` pixels, row 0 at the top
/// of the image (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Skymap {
    pub width: usize,
    pub height: usize,
    /// Degrees from north toward east, in [0, 360).
    pub azimuth_deg: Vec<f64>,
    /// Degrees above the horizon.
    pub elevation_deg: Vec<f64>,
    /// Degrees north, at `altitude_km`.
    pub latitude_deg: Vec<f64>,
    /// Degrees east, in (-180, 180], at `altitude_km`.
    pub longitude_deg: Vec<f64>,
    /// The mapping altitude, km.
    pub altitude_km: f64,
}

/// Why a skymap cannot be made; each names the key and its allowed values.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkymapError {
    #[error("earth.radius_km = 0: a skymap's latitudes and longitudes are on the round Earth; set earth.radius_km > 0")]
    FlatEarth,
    #[error("mapping altitude {0} km: must be a finite number above the camera's altitude ({1:.3} km) and at most 1000 km")]
    Altitude(f64, f64),
    #[error("origin latitude {0}, longitude {1}: the latitude must be in [-90, 90] and the longitude in [-180, 360] degrees")]
    Origin(f64, f64),
}

/// The latitude and longitude, degrees, of a scene-frame direction from
/// the Earth's centre `v` (unit), for an origin at `origin` = (latitude,
/// longitude) degrees (module doc).
pub fn lat_lon_deg(v: DVec3, origin: [f64; 2]) -> [f64; 2] {
    let (sf, cf) = fmath::sin_cos(origin[0].to_radians());
    let (sl, cl) = fmath::sin_cos(origin[1].to_radians());
    let e = DVec3::new(-sl, cl, 0.0);
    let n = DVec3::new(-sf * cl, -sf * sl, cf);
    let u = DVec3::new(cf * cl, cf * sl, sf);
    let w = (e * v.x + n * v.y + u * v.z).normalize();
    [fmath::atan2(w.z, fmath::hypot(w.x, w.y)).to_degrees(), fmath::atan2(w.y, w.x).to_degrees()]
}

/// Where a ray from `o` along unit `u` leaves the sphere of altitude
/// `alt_km` (module doc); `o` below it.
pub fn exit_point(earth: &Earth, o: DVec3, u: DVec3, alt_km: f64) -> DVec3 {
    let oc = o - earth.centre();
    let b = oc.dot(u);
    let r = earth.radius_km + alt_km;
    let t = -b + (b * b - (oc.length_squared() - r * r)).max(0.0).sqrt();
    o + u * t
}

/// The skymap of `camera`'s pixel centres (module doc) on the Earth of
/// `radius_km`, mapped at `alt_km`, the scene's origin at `origin`
/// (latitude, longitude in degrees).
pub fn skymap(camera: &CameraModel, radius_km: f64, origin: [f64; 2], alt_km: f64) -> Result<Skymap, SkymapError> {
    if radius_km <= 0.0 {
        return Err(SkymapError::FlatEarth);
    }
    let earth = Earth::new(radius_km);
    let cam_alt = earth.altitude(camera.position);
    if !(alt_km.is_finite() && alt_km > cam_alt && alt_km <= 1000.0) {
        return Err(SkymapError::Altitude(alt_km, cam_alt));
    }
    if !((-90.0..=90.0).contains(&origin[0]) && (-180.0..=360.0).contains(&origin[1])) {
        return Err(SkymapError::Origin(origin[0], origin[1]));
    }
    let g = earth.to_curved(camera.position);
    let [east, north, up] = earth.local_frame(g.x, g.y);
    let (w, h) = (camera.width, camera.height);
    let n = w * h;
    let mut m = Skymap {
        width: w,
        height: h,
        azimuth_deg: vec![f64::NAN; n],
        elevation_deg: vec![f64::NAN; n],
        latitude_deg: vec![f64::NAN; n],
        longitude_deg: vec![f64::NAN; n],
        altitude_km: alt_km,
    };
    for py in 0..h {
        for px in 0..w {
            let Some(ray) = camera.ray_at(px as f64 + 0.5, py as f64 + 0.5) else { continue };
            let d = ray.dir;
            let i = py * w + px;
            // atan2 of the vertical and horizontal parts: exact near the
            // zenith, where asin of a dot product loses half its digits.
            let (e, n) = (d.dot(east), d.dot(north));
            let el = fmath::atan2(d.dot(up), fmath::hypot(e, n)).to_degrees();
            m.elevation_deg[i] = el;
            m.azimuth_deg[i] = fmath::atan2(e, n).to_degrees().rem_euclid(360.0);
            if el >= 0.0 {
                let p = exit_point(&earth, ray.origin, d, alt_km);
                let [lat, lon] = lat_lon_deg((p - earth.centre()).normalize(), origin);
                m.latitude_deg[i] = lat;
                m.longitude_deg[i] = lon;
            }
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Projection};

    fn zenith_camera(size: usize) -> CameraModel {
        let cam = Camera {
            position: [0.0, 0.0, 0.0],
            look_at: [0.0, 0.0, 1.0],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Fisheye,
            fov_deg: 180.0,
            ..Camera::default()
        };
        CameraModel::new(&cam, size, size).unwrap()
    }

    #[test]
    fn the_centre_pixel_looks_up_and_maps_onto_the_origin() {
        let m = skymap(&zenith_camera(5), 6371.0, [67.0, 20.0], 110.0).unwrap();
        let c = 2 * 5 + 2;
        assert!((m.elevation_deg[c] - 90.0).abs() < 1e-9);
        assert!((m.latitude_deg[c] - 67.0).abs() < 1e-9 && (m.longitude_deg[c] - 20.0).abs() < 1e-9);
        // The corners lie outside the image circle.
        assert!(m.elevation_deg[0].is_nan() && m.latitude_deg[0].is_nan());
    }

    #[test]
    fn a_pixel_north_of_the_zenith_maps_north_by_the_closed_form() {
        // Equidistant fisheye, fov 180 across 41 pixels: the pixel centre k
        // rows above the centre is k * 180/41 degrees from the zenith, at
        // azimuth 0 (the camera's up is north). On the sphere, a ray of
        // elevation el from the ground reaches altitude h at the central
        // angle theta = acos(R cos(el) / (R + h)) - el: its latitude is the
        // origin's plus theta.
        let (r, h) = (6371.0, 110.0);
        let m = skymap(&zenith_camera(41), r, [60.0, -100.0], h).unwrap();
        for k in [1usize, 5, 12, 19] {
            let i = (20 - k) * 41 + 20;
            let el = 90.0 - k as f64 * 180.0 / 41.0;
            assert!((m.elevation_deg[i] - el).abs() < 1e-9, "{k}: {}", m.elevation_deg[i]);
            assert!(m.azimuth_deg[i].abs() < 1e-9 || (m.azimuth_deg[i] - 360.0).abs() < 1e-9);
            let e = el.to_radians();
            let theta = fmath::acos(r * fmath::cos(e) / (r + h)) - e;
            assert!((m.latitude_deg[i] - (60.0 + theta.to_degrees())).abs() < 1e-9, "{k}: {}", m.latitude_deg[i]);
            assert!((m.longitude_deg[i] + 100.0).abs() < 1e-9);
        }
        // Looking up with north at the top, east is on the image's left (the
        // camera's right is forward x up = z x y = -x), as an all-sky
        // imager's picture is shown from below.
        let east = 20 * 41 + 10;
        assert!((m.azimuth_deg[east] - 90.0).abs() < 1e-9 && m.longitude_deg[east] > -100.0);
    }

    #[test]
    fn refusals_name_the_key() {
        assert_eq!(skymap(&zenith_camera(5), 0.0, [0.0, 0.0], 110.0), Err(SkymapError::FlatEarth));
        assert!(matches!(skymap(&zenith_camera(5), 6371.0, [0.0, 0.0], -1.0), Err(SkymapError::Altitude(..))));
        assert!(matches!(skymap(&zenith_camera(5), 6371.0, [91.0, 0.0], 110.0), Err(SkymapError::Origin(..))));
    }
}
