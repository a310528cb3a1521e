//! The geomagnetic field over a scene, as the beams see it: one direction,
//! the same everywhere, so field lines are straight (the model of Baranoski,
//! Rokne, Shirley, Trondsen & Bastos 2000, whose electrons are deflected
//! about a fixed B; a scene spans some hundreds of km, small beside the
//! dipole's scale, the Earth's radius).
//!
//! The direction is given by the field's two angles as geomagnetism defines
//! them (e.g. the IGRF's elements, Alken et al. 2021, "International
//! Geomagnetic Reference Field: the thirteenth generation", Earth Planets
//! Space 73, 49): the **inclination** or dip I, the angle of B below the
//! horizon (`beams.b_inclination_deg`, 90 = vertical), and the
//! **declination** D, the azimuth of its horizontal part
//! (`beams.b_declination_deg`, degrees from north, +y, toward east, +x). In
//! the scene's frame (x east, y north, z up):
//!
//! ```text
//! b = (cos I sin D, cos I cos D, -sin I)
//! ```
//!
//! pointing down, the way precipitating electrons move. [`MagneticField`]
//! completes it to an orthonormal frame for the beams' deflections and
//! traces a point's field line to an altitude ([`MagneticField::foot`]).

use glam::DVec3;

/// The geomagnetic frame: `b` the unit field direction (pointing down, the
/// way precipitating electrons move), `u`, `v` completing an orthonormal,
/// right-handed basis (u x v = b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MagneticField {
    pub b: DVec3,
    pub u: DVec3,
    pub v: DVec3,
}

impl MagneticField {
    /// B dipping `inclination_deg` below the horizon, its horizontal part
    /// toward azimuth `declination_deg` (degrees from +y, north, toward +x, east).
    pub fn new(inclination_deg: f64, declination_deg: f64) -> Self {
        let (si, ci) = inclination_deg.to_radians().sin_cos();
        let (sd, cd) = declination_deg.to_radians().sin_cos();
        let b = DVec3::new(ci * sd, ci * cd, -si).normalize();
        // Any unit vector orthogonal to b; pick the one from the axis least
        // aligned with b.
        let a = if b.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let u = (a - b * a.dot(b)).normalize();
        let v = b.cross(u);
        Self { b, u, v }
    }

    /// The point where the field line through `p` crosses altitude `z`
    /// (traced back up along -B for z above p).
    #[inline]
    pub fn foot(&self, p: DVec3, z: f64) -> DVec3 {
        // p + b * t has altitude z when t = (z - p.z) / b.z.
        p + self.b * ((z - p.z) / self.b.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_frame_is_orthonormal_and_points_down() {
        for (inc, dec) in [(78.0, 0.0), (90.0, 0.0), (45.0, 30.0), (10.0, -120.0)] {
            let f = MagneticField::new(inc, dec);
            assert!((f.b.length() - 1.0).abs() < 1e-12 && (f.u.length() - 1.0).abs() < 1e-12);
            assert!(f.b.dot(f.u).abs() < 1e-12 && f.b.dot(f.v).abs() < 1e-12 && f.u.dot(f.v).abs() < 1e-12);
            assert!(f.b.z < 0.0);
            // Dip angle below the horizon.
            assert!(((-f.b.z).asin().to_degrees() - inc).abs() < 1e-9);
        }
        // Declination 0: the horizontal part points north (+y).
        let f = MagneticField::new(78.0, 0.0);
        assert!(f.b.y > 0.0 && f.b.x.abs() < 1e-12);
        let p = DVec3::new(1.0, 2.0, 150.0);
        let foot = f.foot(p, 260.0);
        assert!((foot.z - 260.0).abs() < 1e-9 && (foot - p).normalize().dot(-f.b) > 1.0 - 1e-12);
    }
}
