//! The round Earth under a scene: a sphere of radius R (`earth.radius_km`,
//! 6371 km by default, the mean radius; 0 is flat ground, where
//! altitude is z), and the closed forms of its geometry.
//!
//! **Frames.** The scene frame is Cartesian, km, x east, y north, z up *at
//! the scene's origin*, which lies on the ground; the Earth's centre is at
//! `(0, 0, -R)`. Everything written (VDB, USD, the camera) is in this one
//! frame. The **altitude** of a point p is its distance from the centre less
//! the radius, `h(p) = |p - c| - R`; with R = 0 it is `z`.
//!
//! **Ground coordinates.** Curtain centres and `path`s are ground
//! distances from the origin, mapped onto the sphere by the azimuthal
//! equidistant projection about the origin (Snyder 1987, "Map projections: a
//! working manual", USGS Professional Paper 1395, section 25): the ground
//! point `(x, y)` at distance `d = |(x, y)|` and azimuth `atan2(x, y)` from
//! north is the sphere's point at central angle `theta = d / R` from the
//! origin along that azimuth. A point `(x, y, h)` of the **curved frame**
//! (ground coordinates and altitude) is, in the scene frame,
//!
//! ```text
//! p = c + (R + h) (sin(theta) (x, y, 0) / d + cos(theta) (0, 0, 1))
//! ```
//!
//! ([`Earth::to_scene`]; [`Earth::to_curved`] inverts it). Distances from the
//! origin along the ground are exact; across them the projection stretches
//! by `theta / sin(theta)` (0.4 % at d = 1000 km).
//!
//! **Local frame.** At a point, `up` is the radial direction; `north` the
//! projection's +y (the image of the curved frame's y axis, made orthogonal
//! to up); `east = north x up`. At the origin they are the scene's axes; for
//! a scene without a pole they are the directions the field's angles are
//! measured from (`crate::physics::geomagnetic_field`).
//!
//! **Closed forms.** With the observer at altitude `h0` and a point at
//! altitude `h` a ground distance `d` away (central angle `theta = d / R`),
//! in the plane of the two and the centre:
//!
//! - the point's elevation above the observer's horizon is
//!   `atan2((R + h) cos(theta) - (R + h0), (R + h) sin(theta))`
//!   ([`Earth::elevation_deg`]; flat: `atan2(h - h0, d)`): 105 km at 1000 km
//!   is 1.44 degrees up on the sphere, 5.99 on a flat ground;
//! - a layer at altitude h is on the observer's horizon at the ground
//!   distance `R (acos(R / (R + h0)) + acos(R / (R + h)))`
//!   ([`Earth::horizon_distance_km`]): 1149 km for h = 105 km from the
//!   ground; on a flat ground never;
//! - a ray `o + t u` (u unit) comes closest to the centre at
//!   `t* = -(o - c) . u`; its lowest altitude is `|o - c + t* u| - R` if
//!   `t* > 0`, else the altitude of o ([`Earth::lowest_altitude`]; flat:
//!   `o.z` for a ray not going down, minus infinity otherwise);
//! - the drop of the sphere below the origin's tangent plane at ground
//!   distance d is `R (1 - cos(d / R))`, about `d^2 / 2R` (78 km at 1000 km).

use crate::util::fmath;
use glam::DVec3;

/// The mean radius of the Earth, km (IUGG: the radius of the sphere of the
/// same volume, 6371.0 km).
pub const MEAN_RADIUS_KM: f64 = 6371.0;

/// The Earth of a scene: a sphere of `radius_km` about `(0, 0, -radius_km)`,
/// or the flat ground `z = 0` when `radius_km` is 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Earth {
    pub radius_km: f64,
}

impl Earth {
    /// Flat ground: altitude is z, and every map is the identity.
    pub const FLAT: Earth = Earth { radius_km: 0.0 };

    pub fn new(radius_km: f64) -> Self {
        Earth { radius_km }
    }

    /// No curvature: every function is the flat ground's.
    #[inline]
    pub fn is_flat(&self) -> bool {
        self.radius_km == 0.0
    }

    /// The centre, `(0, 0, -R)`.
    #[inline]
    pub fn centre(&self) -> DVec3 {
        DVec3::new(0.0, 0.0, -self.radius_km)
    }

    /// The altitude of a scene-frame point, km.
    #[inline]
    pub fn altitude(&self, p: DVec3) -> f64 {
        if self.is_flat() {
            p.z
        } else {
            (p - self.centre()).length() - self.radius_km
        }
    }

    /// The unit vertical at a scene-frame point (+z when flat).
    #[inline]
    pub fn local_up(&self, p: DVec3) -> DVec3 {
        if self.is_flat() {
            DVec3::Z
        } else {
            (p - self.centre()).normalize()
        }
    }

    /// The local (east, north, up) frame at the point of ground coordinates
    /// `(x, y)` (module doc): north is the projection's +y made orthogonal
    /// to up.
    pub fn local_frame(&self, x: f64, y: f64) -> [DVec3; 3] {
        if self.is_flat() {
            return [DVec3::X, DVec3::Y, DVec3::Z];
        }
        let up = self.local_up(self.to_scene(DVec3::new(x, y, 0.0)));
        // The image of +y by a centred difference of the projection (1 m:
        // the projection is smooth on the scale of R).
        let e = 1e-3;
        let dy = self.to_scene(DVec3::new(x, y + e, 0.0)) - self.to_scene(DVec3::new(x, y - e, 0.0));
        let north = (dy - up * dy.dot(up)).normalize();
        [north.cross(up), north, up]
    }

    /// The scene-frame point of the curved frame's `(x, y, h)`: ground
    /// coordinates and altitude (module doc). The identity when flat.
    #[inline]
    pub fn to_scene(&self, q: DVec3) -> DVec3 {
        if self.is_flat() {
            return q;
        }
        let r = self.radius_km;
        let d = (q.x * q.x + q.y * q.y).sqrt();
        let rh = r + q.z;
        if d == 0.0 {
            return DVec3::new(0.0, 0.0, q.z);
        }
        let (s, c) = fmath::sin_cos(d / r);
        DVec3::new(rh * s * q.x / d, rh * s * q.y / d, rh * c - r)
    }

    /// The curved frame's `(x, y, h)` of a scene-frame point: the inverse of
    /// [`Earth::to_scene`] (the identity when flat).
    #[inline]
    pub fn to_curved(&self, p: DVec3) -> DVec3 {
        if self.is_flat() {
            return p;
        }
        let v = p - self.centre();
        let rho = (v.x * v.x + v.y * v.y).sqrt();
        let h = v.length() - self.radius_km;
        if rho == 0.0 {
            return DVec3::new(0.0, 0.0, h);
        }
        let d = self.radius_km * fmath::atan2(rho, v.z);
        DVec3::new(d * v.x / rho, d * v.y / rho, h)
    }

    /// The scene-frame ground point of ground coordinates `(x, y)`.
    pub fn ground_point(&self, x: f64, y: f64) -> DVec3 {
        self.to_scene(DVec3::new(x, y, 0.0))
    }

    /// The lowest altitude along the ray `o + t u`, `t >= 0` (u need not be
    /// unit): module doc. Minus infinity for a ray going down over a flat
    /// ground.
    pub fn lowest_altitude(&self, o: DVec3, u: DVec3) -> f64 {
        let u = u.normalize();
        if self.is_flat() {
            return if u.z >= 0.0 { o.z } else { f64::NEG_INFINITY };
        }
        let oc = o - self.centre();
        let t = -oc.dot(u);
        if t <= 0.0 {
            self.altitude(o)
        } else {
            (oc + u * t).length() - self.radius_km
        }
    }

    /// The ground distance at which a layer at altitude `h` km lies on the
    /// horizon of an observer at altitude `h0` km (module doc); infinite on
    /// a flat ground.
    pub fn horizon_distance_km(&self, h0: f64, h: f64) -> f64 {
        if self.is_flat() {
            return f64::INFINITY;
        }
        let r = self.radius_km;
        r * (fmath::acos(r / (r + h0)) + fmath::acos(r / (r + h)))
    }

    /// The elevation, degrees, of a point at altitude `h` a ground distance
    /// `d` km from an observer at altitude `h0` (module doc).
    pub fn elevation_deg(&self, h0: f64, h: f64, d: f64) -> f64 {
        if self.is_flat() {
            return fmath::atan2(h - h0, d).to_degrees();
        }
        let r = self.radius_km;
        let (s, c) = fmath::sin_cos(d / r);
        fmath::atan2((r + h) * c - (r + h0), (r + h) * s).to_degrees()
    }

    /// The drop of the ground below the origin's tangent plane at ground
    /// distance `d` km, `R (1 - cos(d / R))` (0 when flat).
    pub fn drop_km(&self, d: f64) -> f64 {
        if self.is_flat() {
            0.0
        } else {
            self.radius_km * (1.0 - fmath::cos(d / self.radius_km))
        }
    }

    /// The central angle between two ground points, radians (0 when flat).
    pub fn central_angle(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        if self.is_flat() {
            return 0.0;
        }
        let (pa, pb) = (self.ground_point(a[0], a[1]) - self.centre(), self.ground_point(b[0], b[1]) - self.centre());
        fmath::atan2(pa.cross(pb).length(), pa.dot(pb))
    }

    /// The great-circle distance between two ground points, km (the plane
    /// distance when flat).
    pub fn ground_distance_km(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        if self.is_flat() {
            return fmath::hypot(a[0] - b[0], a[1] - b[1]);
        }
        self.radius_km * self.central_angle(a, b)
    }

    /// The azimuth, degrees from the local north toward the local east, of
    /// the great circle from ground point `a` toward `b` (the plane's
    /// bearing when flat).
    pub fn azimuth_deg(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        if self.is_flat() {
            return fmath::atan2(b[0] - a[0], b[1] - a[1]).to_degrees();
        }
        let [east, north, up] = self.local_frame(a[0], a[1]);
        let d = self.ground_point(b[0], b[1]) - self.ground_point(a[0], a[1]);
        let t = d - up * d.dot(up);
        fmath::atan2(t.dot(east), t.dot(north)).to_degrees()
    }

    /// The ground point a great-circle distance `dist` km from `a` at
    /// azimuth `az_deg` (from the local north toward east), in ground
    /// coordinates.
    pub fn destination(&self, a: [f64; 2], az_deg: f64, dist: f64) -> [f64; 2] {
        let (s, c) = fmath::sin_cos(az_deg.to_radians());
        if self.is_flat() {
            return [a[0] + dist * s, a[1] + dist * c];
        }
        let [east, north, up] = self.local_frame(a[0], a[1]);
        let dir = east * s + north * c;
        let (sa, ca) = fmath::sin_cos(dist / self.radius_km);
        let p = self.centre() + (up * ca + dir * sa) * self.radius_km;
        let q = self.to_curved(p);
        [q.x, q.y]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const E: Earth = Earth { radius_km: MEAN_RADIUS_KM };

    #[test]
    fn flat_earth_is_the_old_frame_bit_for_bit() {
        let f = Earth::FLAT;
        for p in [DVec3::new(1.5, -2.25, 105.0), DVec3::new(-1e3, 7e2, 0.1)] {
            assert_eq!(f.altitude(p), p.z);
            assert_eq!(f.to_scene(p), p);
            assert_eq!(f.to_curved(p), p);
            assert_eq!(f.local_up(p), DVec3::Z);
        }
        assert_eq!(f.local_frame(300.0, -20.0), [DVec3::X, DVec3::Y, DVec3::Z]);
        assert_eq!(f.horizon_distance_km(0.0, 105.0), f64::INFINITY);
        // atan(105 / 1000) = 5.994 degrees.
        assert!((f.elevation_deg(0.0, 105.0, 1000.0) - 5.9941).abs() < 1e-3);
    }

    #[test]
    fn altitude_of_mapped_points_and_the_inverse() {
        // (x, y, h) -> scene -> altitude is h, and the inverse returns
        // (x, y, h), to rounding of a few ulps of R (1e-9 km).
        for q in
            [DVec3::new(0.0, 0.0, 110.0), DVec3::new(1000.0, 0.0, 105.0), DVec3::new(-700.0, 1200.0, 250.0), DVec3::new(3.0, -4.0, 0.0)]
        {
            let p = E.to_scene(q);
            assert!((E.altitude(p) - q.z).abs() < 1e-9, "{q}");
            assert!((E.to_curved(p) - q).length() < 1e-8, "{q} {}", E.to_curved(p));
        }
        // The ground point 1000 km east drops R (1 - cos(d / R)) = 78.3 km
        // below the origin's tangent plane (about d^2 / 2R = 78.5 km) and
        // sits R sin(d / R) = 995.9 km east.
        let g = E.ground_point(1000.0, 0.0);
        assert!((-g.z - E.drop_km(1000.0)).abs() < 1e-9 && (E.drop_km(1000.0) - 78.32).abs() < 0.005, "{g}");
        assert!((g.x - MEAN_RADIUS_KM * fmath::sin(1000.0 / MEAN_RADIUS_KM)).abs() < 1e-9);
        // A point 10 km above the origin: altitude 10 (closed form, exact).
        assert_eq!(E.altitude(DVec3::new(0.0, 0.0, 10.0)), 10.0);
        // Ground distance along a radial line is exact.
        assert!((E.ground_distance_km([0.0, 0.0], [600.0, 800.0]) - 1000.0).abs() < 1e-9);
    }

    #[test]
    fn elevation_and_horizon_match_the_curvature_figures() {
        // 105 km at 1000 km: 1.44 degrees on the sphere, 5.99 flat.
        let e = E.elevation_deg(0.0, 105.0, 1000.0);
        assert!((e - 1.437).abs() < 0.005, "{e}");
        // The 105 km layer reaches the horizon at R acos(R / (R + 105)) =
        // 1148.8 km from the ground.
        let d = E.horizon_distance_km(0.0, 105.0);
        assert!((d - 1148.8).abs() < 0.1, "{d}");
        assert!(E.elevation_deg(0.0, 105.0, d).abs() < 1e-9);
        // The elevation from the mapped points agrees with the closed form.
        let p = E.to_scene(DVec3::new(0.0, 1000.0, 105.0));
        let el = fmath::atan(p.z / fmath::hypot(p.y, p.x)).to_degrees();
        assert!((el - e).abs() < 1e-9, "{el} vs {e}");
    }

    #[test]
    fn lowest_altitude_of_a_ray_is_the_closest_approach() {
        // A horizontal ray from altitude 0 at the origin: at ground distance
        // d the ray is sqrt(R^2 + t^2) - R above the sphere; it never comes
        // lower than 0 (t* = 0).
        assert!(E.lowest_altitude(DVec3::ZERO, DVec3::Y).abs() < 1e-12);
        // A ray from 300 km up, 2 degrees down: closest approach (R + 300)
        // cos(2 deg) - R = 300 - 6671 (1 - cos 2deg) = 295.94 km.
        let o = DVec3::new(0.0, 0.0, 300.0);
        let u = DVec3::new(0.0, fmath::cos(2f64.to_radians()), -fmath::sin(2f64.to_radians()));
        let want = (MEAN_RADIUS_KM + 300.0) * fmath::cos(2f64.to_radians()) - MEAN_RADIUS_KM;
        assert!((E.lowest_altitude(o, u) - want).abs() < 1e-9);
        assert!((want - 295.936).abs() < 1e-3);
        // Brute force along the ray.
        let brute = (0..200_000).map(|i| E.altitude(o + u * (i as f64 * 0.05))).fold(f64::INFINITY, f64::min);
        assert!((brute - want).abs() < 1e-6, "{brute} vs {want}");
        // A ray going up: its start.
        assert_eq!(E.lowest_altitude(o, DVec3::new(0.0, 1.0, 0.5)), E.altitude(o));
        assert_eq!(Earth::FLAT.lowest_altitude(o, u), f64::NEG_INFINITY);
    }

    #[test]
    fn local_frame_is_orthonormal_and_north_points_along_the_meridian_of_the_projection() {
        for (x, y) in [(0.0, 0.0), (1000.0, 0.0), (-800.0, 1500.0)] {
            let [e, n, u] = E.local_frame(x, y);
            assert!(e.dot(n).abs() < 1e-12 && e.dot(u).abs() < 1e-12 && n.dot(u).abs() < 1e-9);
            assert!((e.cross(n) - u).length() < 1e-9);
            assert!((u - E.local_up(E.ground_point(x, y))).length() < 1e-12);
        }
        // On the y axis north is the radial direction of the projection:
        // along the chord between the points 1 km either side on the axis
        // (parallel to the tangent at its middle).
        let [_, n, _] = E.local_frame(0.0, 1000.0);
        let d = (E.ground_point(0.0, 1001.0) - E.ground_point(0.0, 999.0)).normalize();
        assert!(n.dot(d) > 1.0 - 1e-9, "{}", 1.0 - n.dot(d));
        // The destination 500 km from (0, 1000) toward azimuth 90 is 500 km
        // away along a great circle, at that azimuth.
        let b = E.destination([0.0, 1000.0], 90.0, 500.0);
        assert!((E.ground_distance_km([0.0, 1000.0], b) - 500.0).abs() < 1e-6);
        assert!((E.azimuth_deg([0.0, 1000.0], b) - 90.0).abs() < 1e-6);
    }
}
