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
//!
//! **On a round Earth** (`crate::geometry::earth`) the angles are relative to the
//! local vertical and north: the beams walk in the curved frame (ground
//! coordinates and altitude, where the local frame is the frame's axes) and
//! their deposits are mapped onto the sphere, so a curtain 2000 km long
//! keeps its inclination along its length. **With a dipole pole**
//! (`earth.magnetic_pole`) the field at a point is the centred dipole's
//! about that pole (e.g. Kivelson & Russell 1995, "Introduction to Space
//! Physics", section 6.2): at magnetic latitude `lambda` (90 degrees less
//! the central angle to the pole) the dip is `tan I = 2 tan(lambda)`, and the
//! horizontal part points toward the pole, `D` the pole's azimuth
//! ([`MagneticField::dipole`]). Beyond the dipole's equator (more than a
//! quarter of the globe from the pole, `lambda < 0`) B points up: the
//! electrons still go down the field line into the atmosphere, along -B,
//! so there `b` is -B, dipping `|I|` toward the pole's antipode (the other
//! pole). Where `|I|` is no more than the beams' deflection `alpha_D` a
//! step may go up or sideways for ever; such a curtain is refused
//! (`crate::pipeline::beams::dip`). **With a site** the field is the
//! Earth's, IGRF-14 (`crate::physics::site_field`), read into the same
//! two angles.

use crate::geometry::earth::Earth;
use crate::util::fmath;
use glam::DVec3;

/// The geomagnetic frame: `b` the unit direction of the field line the way
/// precipitating electrons move (down: B in the northern hemisphere, -B in
/// the southern), `u`, `v` completing an orthonormal, right-handed basis
/// (u x v = b).
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
        let (si, ci) = fmath::sin_cos(inclination_deg.to_radians());
        let (sd, cd) = fmath::sin_cos(declination_deg.to_radians());
        let b = DVec3::new(ci * sd, ci * cd, -si).normalize();
        // Any unit vector orthogonal to b; pick the one from the axis least
        // aligned with b.
        let a = if b.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let u = (a - b * a.dot(b)).normalize();
        let v = b.cross(u);
        Self { b, u, v }
    }

    /// The dipole's field line at ground point `at` for the pole at ground
    /// point `pole` (module doc), the way electrons precipitate: inclination
    /// `atan(2 tan(lambda))`, declination the pole's azimuth; beyond the
    /// dipole's equator (negative inclination, B pointing up) -B, dipping
    /// `|I|` the other way. Within 1e-9 rad of the pole the field is
    /// vertical.
    pub fn dipole(earth: &Earth, pole: [f64; 2], at: [f64; 2]) -> Self {
        let (inc, dec) = dipole_angles_deg(earth, pole, at);
        if inc < 0.0 {
            Self::new(-inc, dec + 180.0)
        } else {
            Self::new(inc, dec)
        }
    }

    /// The dip of `b` below the horizon, degrees (in [0, 90] for every field
    /// [`MagneticField::new`] and [`MagneticField::dipole`] make).
    pub fn dip_deg(&self) -> f64 {
        fmath::asin((-self.b.z).clamp(-1.0, 1.0)).to_degrees()
    }

    /// The point where the field line through `p` crosses altitude `z`
    /// (traced back up along -B for z above p).
    #[inline]
    pub fn foot(&self, p: DVec3, z: f64) -> DVec3 {
        // p + b * t has altitude z when t = (z - p.z) / b.z.
        p + self.b * ((z - p.z) / self.b.z)
    }
}

/// The dipole's inclination and declination, degrees, at ground point `at`
/// for the pole at `pole` ([`MagneticField::dipole`]): the inclination of B
/// itself, negative beyond the dipole's equator where B points up.
pub fn dipole_angles_deg(earth: &Earth, pole: [f64; 2], at: [f64; 2]) -> (f64, f64) {
    let colat = earth.central_angle(at, pole);
    if colat < 1e-9 {
        return (90.0, 0.0);
    }
    let lat = std::f64::consts::FRAC_PI_2 - colat;
    let inc = fmath::atan(2.0 * fmath::tan(lat)).to_degrees();
    (inc, earth.azimuth_deg(at, pole))
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
            assert!((fmath::asin(-f.b.z).to_degrees() - inc).abs() < 1e-9);
        }
        // Declination 0: the horizontal part points north (+y).
        let f = MagneticField::new(78.0, 0.0);
        assert!(f.b.y > 0.0 && f.b.x.abs() < 1e-12);
        let p = DVec3::new(1.0, 2.0, 150.0);
        let foot = f.foot(p, 260.0);
        assert!((foot.z - 260.0).abs() < 1e-9 && (foot - p).normalize().dot(-f.b) > 1.0 - 1e-12);
    }

    #[test]
    fn dipole_dip_follows_tan_i_equals_two_tan_latitude() {
        let e = Earth::new(crate::geometry::earth::MEAN_RADIUS_KM);
        // The pole 2000 km north: magnetic latitude 90 - 2000 / R rad =
        // 72.01 degrees; tan I = 2 tan(72.01 deg) = 6.160, I = 80.78
        // degrees, the horizontal part due north.
        let (i, d) = dipole_angles_deg(&e, [0.0, 2000.0], [0.0, 0.0]);
        let lat = 90.0 - (2000.0 / e.radius_km).to_degrees();
        assert!((fmath::tan(i.to_radians()) - 2.0 * fmath::tan(lat.to_radians())).abs() < 1e-9, "{i}");
        assert!((i - 80.78).abs() < 0.005 && d.abs() < 1e-9, "{i} {d}");
        // East of the pole's meridian the field points back toward it.
        let (_, d) = dipole_angles_deg(&e, [0.0, 2000.0], [1000.0, 0.0]);
        assert!(d < -20.0 && d > -90.0, "{d}");
        // At the pole, vertical.
        assert_eq!(dipole_angles_deg(&e, [0.0, 2000.0], [0.0, 2000.0]), (90.0, 0.0));
    }

    #[test]
    fn beyond_the_dipole_equator_electrons_go_down_along_minus_b() {
        // The pole 14000 km north: magnetic latitude 90 - 14000 / R rad =
        // -35.9 degrees, B points up at 55.3 degrees; the electrons' line
        // dips 55.3 degrees toward the south (away from the pole, toward
        // its antipode).
        let e = Earth::new(crate::geometry::earth::MEAN_RADIUS_KM);
        let (i, d) = dipole_angles_deg(&e, [0.0, 14000.0], [0.0, 0.0]);
        assert!(i < -55.0 && i > -56.0 && d.abs() < 1e-9, "{i} {d}");
        let f = MagneticField::dipole(&e, [0.0, 14000.0], [0.0, 0.0]);
        assert!(f.b.z < 0.0 && f.b.y < 0.0 && f.b.x.abs() < 1e-12, "{:?}", f.b);
        assert!((f.dip_deg() + i).abs() < 1e-9, "{} vs {i}", f.dip_deg());
        // The mirror by the dipole's symmetry: the pole d north and the pole
        // pi R - d south (its antipode d north) give the same line.
        let d = 3000.0;
        let far = std::f64::consts::PI * e.radius_km - d;
        for at in [[0.0, 0.0], [40.0, -25.0], [-300.0, 120.0]] {
            let n = MagneticField::dipole(&e, [0.0, d], at);
            let s = MagneticField::dipole(&e, [0.0, -far], at);
            assert!((n.b - s.b).length() < 1e-9, "{at:?}: {:?} vs {:?}", n.b, s.b);
        }
    }
}
