//! A curtain's path: the smooth curve through the artist's points and the
//! curvilinear frame (arc length u, signed distance v to the left) the
//! footprint lives in.
//!
//! **The curve.** A centripetal Catmull-Rom spline through the points
//! (Catmull & Rom 1974; knots `t_{i+1} = t_i + |P_{i+1} - P_i|^(1/2)`,
//! evaluated by the pyramid of linear interpolations of Barry & Goldman
//! 1988). It passes through every point (the artist's points lie on the
//! curtain, unlike a B-spline's control points), and the centripetal knots
//! are the ones for which no span forms a cusp or a loop and the curve
//! stays close to its points (Yuksel, Schaefer & Keyser 2011,
//! "Parameterization and applications of Catmull-Rom curves",
//! Computer-Aided Design 43(7)). The end spans use phantom points reflected
//! through the ends (`P_-1 = 2 P_0 - P_1`), so two points give the straight
//! segment between them, at uniform speed.
//!
//! **The frame.** The curve is sampled at vertices at most
//! [`MAX_SPACING_KM`] apart (at least [`MIN_SAMPLES_PER_SPAN`] a span; the
//! chord's sagitta h^2 / 8R is 12 m at h = 1 km on a bend of radius 10 km);
//! each vertex gets the left normal of the centred difference of its
//! neighbours. Within a chord, `x(u, v) = p_k + t d_k + v (n_k + t (n_{k+1} -
//! n_k))` with u the arc length along the chords: continuous in u and v
//! (neighbouring chords share their edge), and a rigid rotation when the path
//! is straight. [`PathFrame::to_local`] inverts it exactly (a quadratic in
//! v per chord), starting from the chord a raster of the plane names and
//! stepping to a neighbour while t leaves [0, 1]. Both ends are continued
//! straight by `reach` km; points farther than `reach` from the continued
//! curve are outside (`(inf, inf)`).
//!
//! **Where the path lies.** The path is the ground track of the curtain's
//! lower border at [`PATH_ALTITUDE_KM`]; the beams start at `beams.top_km`,
//! up the field line, [`lift_km`] away horizontally; with a dipole pole
//! (`earth.magnetic_pole`) each point is lifted along the dipole's field
//! there, and with a `[site]` along IGRF-14's ([`Lift`]).

use crate::geometry::earth::Earth;
use crate::physics::geomagnetic_field::MagneticField;
use crate::physics::site_field::SiteField;
use crate::scene::root::Scene;
use crate::scene::{BeamParams, EarthParams};
use glam::DVec3;
use std::sync::Arc;

/// The altitude of a path, km: the lower border of the green curtain, where
/// its emission peaks (100-120 km; 557.7 nm peaks near 110-115 km).
pub const PATH_ALTITUDE_KM: f64 = 110.0;
/// Largest spacing of the frame's vertices along the curve, km.
pub const MAX_SPACING_KM: f64 = 1.0;
/// Fewest vertices per span between two points.
pub const MIN_SAMPLES_PER_SPAN: usize = 8;
/// Most cells of the raster that names a chord for a point.
const MAX_RASTER_CELLS: f64 = 2.0e6;

/// The horizontal offset, km, from a point at [`PATH_ALTITUDE_KM`] to the
/// point of its field line at the beams' start altitude: `cot(I) (top - 110)`
/// against the field's horizontal direction (31.9 km at I = 78 deg, top 260 km).
pub fn lift_km(beams: &BeamParams) -> [f64; 2] {
    let f = MagneticField::new(beams.b_inclination_deg, beams.b_declination_deg);
    let p = f.foot(DVec3::new(0.0, 0.0, PATH_ALTITUDE_KM), beams.top_km);
    [p.x, p.y]
}

/// How a path's points move from [`PATH_ALTITUDE_KM`] to the beams' start
/// altitude: one offset ([`lift_km`]) for a uniform field, or, with a
/// dipole pole, the offset of the dipole's field at each point (on the
/// scale of an oval the field turns with the arc), or with a `[site]`
/// (`field = "igrf"`) the offset of IGRF-14's field over each point at
/// [`PATH_ALTITUDE_KM`] (`crate::physics::site_field`), as the beams follow it.
#[derive(Clone, Debug, PartialEq)]
pub enum Lift {
    Constant([f64; 2]),
    Dipole { earth: Earth, pole: [f64; 2], top_km: f64 },
    Site { field: Arc<SiteField>, top_km: f64 },
}

impl From<[f64; 2]> for Lift {
    fn from(d: [f64; 2]) -> Self {
        Lift::Constant(d)
    }
}

impl From<&Lift> for Lift {
    fn from(l: &Lift) -> Self {
        l.clone()
    }
}

impl Lift {
    /// The lift of a scene's own field keys: the dipole's with
    /// `earth.magnetic_pole`, else [`lift_km`].
    pub fn of(beams: &BeamParams, earth: &EarthParams) -> Lift {
        match earth.magnetic_pole {
            Some(pole) if earth.radius_km > 0.0 => Lift::Dipole { earth: Earth::new(earth.radius_km), pole, top_km: beams.top_km },
            _ => Lift::Constant(lift_km(beams)),
        }
    }

    /// The scene's lift: IGRF-14's over a `[site]` whose field is IGRF
    /// (the field its beams follow), else [`Lift::of`].
    pub fn of_scene(scene: &Scene) -> Lift {
        Lift::over(&scene.beams, &scene.earth, SiteField::of_scene(scene))
    }

    /// IGRF-14's lift when the beams follow `site`'s field, else
    /// [`Lift::of`].
    pub fn over(beams: &BeamParams, earth: &EarthParams, site: Option<SiteField>) -> Lift {
        match site {
            Some(field) => Lift::Site { field: Arc::new(field), top_km: beams.top_km },
            None => Lift::of(beams, earth),
        }
    }

    /// The point `q` lifted.
    pub fn apply(&self, q: [f64; 2]) -> [f64; 2] {
        let d = match self {
            Lift::Constant(d) => *d,
            Lift::Dipole { earth, pole, top_km } => {
                let f = MagneticField::dipole(earth, *pole, q);
                let p = f.foot(DVec3::new(0.0, 0.0, PATH_ALTITUDE_KM), *top_km);
                [p.x, p.y]
            }
            Lift::Site { field, top_km } => {
                let p = field.field(q, PATH_ALTITUDE_KM).foot(DVec3::new(0.0, 0.0, PATH_ALTITUDE_KM), *top_km);
                [p.x, p.y]
            }
        };
        [q[0] + d[0], q[1] + d[1]]
    }

    /// A path's points lifted.
    pub fn path(&self, p: &[[f64; 2]]) -> Vec<[f64; 2]> {
        p.iter().map(|&q| self.apply(q)).collect()
    }
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn norm(a: [f64; 2]) -> f64 {
    dot(a, a).sqrt()
}
fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

/// The centripetal Catmull-Rom point of the span P1-P2 at fraction `f` in
/// [0, 1] (Barry & Goldman's pyramid).
fn catmull_rom(p: [[f64; 2]; 4], f: f64) -> [f64; 2] {
    let t0 = 0.0;
    let t1 = t0 + norm(sub(p[1], p[0])).sqrt();
    let t2 = t1 + norm(sub(p[2], p[1])).sqrt();
    let t3 = t2 + norm(sub(p[3], p[2])).sqrt();
    let t = t1 + (t2 - t1) * f;
    let l = |a: [f64; 2], b: [f64; 2], ta: f64, tb: f64| lerp(a, b, (t - ta) / (tb - ta));
    let a1 = l(p[0], p[1], t0, t1);
    let a2 = l(p[1], p[2], t1, t2);
    let a3 = l(p[2], p[3], t2, t3);
    let b1 = l(a1, a2, t0, t2);
    let b2 = l(a2, a3, t1, t3);
    l(b1, b2, t1, t2)
}

/// The curve through `points` (at least 2, consecutive ones distinct) as
/// vertices at most [`MAX_SPACING_KM`] apart, the points among them.
pub fn vertices(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let n = points.len();
    let at = |i: isize| -> [f64; 2] {
        if i < 0 {
            sub(lerp(points[0], points[1], 0.0), sub(points[1], points[0]))
        } else if i as usize >= n {
            let (a, b) = (points[n - 1], points[n - 2]);
            [2.0 * a[0] - b[0], 2.0 * a[1] - b[1]]
        } else {
            points[i as usize]
        }
    };
    let mut out = vec![points[0]];
    for k in 0..n - 1 {
        let span = [at(k as isize - 1), at(k as isize), at(k as isize + 1), at(k as isize + 2)];
        let m = ((norm(sub(span[2], span[1])) / MAX_SPACING_KM).ceil() as usize).max(MIN_SAMPLES_PER_SPAN);
        for j in 1..m {
            out.push(catmull_rom(span, j as f64 / m as f64));
        }
        out.push(points[k + 1]);
    }
    out
}

/// The length of a polyline, km.
pub fn polyline_length(v: &[[f64; 2]]) -> f64 {
    v.windows(2).map(|w| norm(sub(w[1], w[0]))).sum()
}

/// The curvilinear frame of a path (module documentation). u runs from
/// `-length / 2` at the first point to `length / 2` at the last, like a
/// straight curtain's, v to the left.
#[derive(Clone, Debug, PartialEq)]
pub struct PathFrame {
    /// Vertices, the straight continuations' ends first and last.
    pts: Vec<[f64; 2]>,
    normals: Vec<[f64; 2]>,
    /// Arc length at each vertex from the first point (negative before it).
    s: Vec<f64>,
    /// The curve's length, km.
    pub length: f64,
    /// Distance from the continued curve beyond which a point is outside, km.
    pub reach: f64,
    origin: [f64; 2],
    cell: f64,
    cols: usize,
    rows: usize,
    /// Per raster cell, the chord nearest its centre (u32::MAX: none within reach).
    chord: Vec<u32>,
}

impl PathFrame {
    /// The frame of the curve through `points`, continued by `reach` km at
    /// both ends.
    pub fn new(points: &[[f64; 2]], reach: f64) -> Self {
        let v = vertices(points);
        let m = v.len();
        let unit = |a: [f64; 2]| {
            let l = norm(a);
            [a[0] / l, a[1] / l]
        };
        let mut tangents: Vec<[f64; 2]> = (0..m).map(|i| unit(sub(v[(i + 1).min(m - 1)], v[i.saturating_sub(1)]))).collect();
        tangents[0] = unit(sub(v[1], v[0]));
        tangents[m - 1] = unit(sub(v[m - 1], v[m - 2]));
        let (t0, t1) = (tangents[0], tangents[m - 1]);
        let mut pts = vec![[v[0][0] - reach * t0[0], v[0][1] - reach * t0[1]]];
        pts.extend_from_slice(&v);
        pts.push([v[m - 1][0] + reach * t1[0], v[m - 1][1] + reach * t1[1]]);
        let mut tan = vec![t0];
        tan.extend_from_slice(&tangents);
        tan.push(t1);
        let normals: Vec<[f64; 2]> = tan.iter().map(|t| [-t[1], t[0]]).collect();
        let mut s = vec![-reach, 0.0];
        for w in v.windows(2) {
            let last = *s.last().expect("non-empty");
            s.push(last + norm(sub(w[1], w[0])));
        }
        let length = *s.last().expect("non-empty");
        s.push(length + reach);

        // The raster: every cell within reach of a chord names the chord
        // nearest its centre.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &pts {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a] - reach);
                hi[a] = hi[a].max(p[a] + reach);
            }
        }
        let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let cell = (2.0 * MAX_SPACING_KM).max((area / MAX_RASTER_CELLS).sqrt());
        let cols = ((hi[0] - lo[0]) / cell).ceil() as usize + 1;
        let rows = ((hi[1] - lo[1]) / cell).ceil() as usize + 1;
        let mut best = vec![f64::INFINITY; cols * rows];
        let mut chord = vec![u32::MAX; cols * rows];
        let limit = reach + cell;
        for k in 0..pts.len() - 1 {
            let (a, b) = (pts[k], pts[k + 1]);
            let i0 = (((a[0].min(b[0]) - limit - lo[0]) / cell).floor().max(0.0)) as usize;
            let i1 = ((((a[0].max(b[0]) + limit - lo[0]) / cell).ceil()) as usize).min(cols - 1);
            let j0 = (((a[1].min(b[1]) - limit - lo[1]) / cell).floor().max(0.0)) as usize;
            let j1 = ((((a[1].max(b[1]) + limit - lo[1]) / cell).ceil()) as usize).min(rows - 1);
            let d = sub(b, a);
            let dd = dot(d, d);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = [lo[0] + (i as f64 + 0.5) * cell, lo[1] + (j as f64 + 0.5) * cell];
                    let w = sub(c, a);
                    let t = (dot(w, d) / dd).clamp(0.0, 1.0);
                    let dist = norm(sub(w, [d[0] * t, d[1] * t]));
                    let idx = j * cols + i;
                    if dist <= limit && dist < best[idx] {
                        best[idx] = dist;
                        chord[idx] = k as u32;
                    }
                }
            }
        }
        Self { pts, normals, s, length, reach, origin: lo, cell, cols, rows, chord }
    }

    fn chords(&self) -> usize {
        self.pts.len() - 1
    }

    /// Frame (u, v) to world (x, y), km.
    pub fn to_world(&self, u: f64, v: f64) -> (f64, f64) {
        let s = u + 0.5 * self.length;
        let k = (self.s.partition_point(|&x| x <= s).max(1) - 1).min(self.chords() - 1);
        let t = (s - self.s[k]) / (self.s[k + 1] - self.s[k]);
        let p = lerp(self.pts[k], self.pts[k + 1], t);
        let n = lerp(self.normals[k], self.normals[k + 1], t);
        (p[0] + v * n[0], p[1] + v * n[1])
    }

    /// (t, v) of `q` in chord k: `q = p_k + t d + v (n_k + t dn)`.
    fn solve(&self, k: usize, q: [f64; 2]) -> (f64, f64) {
        let (p0, n0) = (self.pts[k], self.normals[k]);
        let d = sub(self.pts[k + 1], p0);
        let dn = sub(self.normals[k + 1], n0);
        let w = sub(q, p0);
        // cross(w - v n0, d + v dn) = 0: a v^2 + b v + c = 0.
        let a = -cross(n0, dn);
        let b = cross(w, dn) - cross(n0, d);
        let c = cross(w, d);
        let disc = b * b - 4.0 * a * c;
        let v = if a.abs() < 1e-14 * b.abs() || disc < 0.0 { -c / b } else { 2.0 * c / (-b - b.signum() * disc.sqrt()) };
        let e = [d[0] + v * dn[0], d[1] + v * dn[1]];
        let t = dot(sub(w, [v * n0[0], v * n0[1]]), e) / dot(e, e);
        (t, v)
    }

    /// World (x, y) to frame (u, v), km; `(inf, inf)` farther than `reach`
    /// from the continued curve.
    pub fn to_local(&self, x: f64, y: f64) -> (f64, f64) {
        const OUT: (f64, f64) = (f64::INFINITY, f64::INFINITY);
        let gi = (x - self.origin[0]) / self.cell;
        let gj = (y - self.origin[1]) / self.cell;
        if !(gi >= 0.0 && gj >= 0.0 && gi < self.cols as f64 && gj < self.rows as f64) {
            return OUT;
        }
        let mut k = self.chord[gj as usize * self.cols + gi as usize];
        if k == u32::MAX {
            return OUT;
        }
        let q = [x, y];
        let last = self.chords() - 1;
        let mut prev = usize::MAX;
        let (mut t, mut v) = self.solve(k as usize, q);
        for _ in 0..self.chords() {
            let kk = k as usize;
            let next = if t < 0.0 && kk > 0 {
                kk - 1
            } else if t > 1.0 && kk < last {
                kk + 1
            } else {
                break;
            };
            if next == prev {
                break;
            }
            prev = kk;
            k = next as u32;
            (t, v) = self.solve(next, q);
        }
        let kk = k as usize;
        let s = self.s[kk] + t * (self.s[kk + 1] - self.s[kk]);
        if !(v.abs() <= self.reach && s >= -self.reach && s <= self.length + self.reach) {
            return OUT;
        }
        (s - 0.5 * self.length, v)
    }
}

/// One stretch of a path that bends tighter than a radius: its tightest
/// vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct TightBend {
    /// Where, km.
    pub at: [f64; 2],
    /// Arc length from the first point, km.
    pub along_km: f64,
    /// The radius of curvature there, km.
    pub radius_km: f64,
}

/// The stretches of the curve through `points` whose radius of curvature
/// falls below `min_radius_km`, the tightest vertex of each. The radius at
/// a vertex is that of the circle through it and its two neighbours,
/// `R = |a| |b| |c| / (2 |a x b|)` with a, b, c the triangle's sides (the
/// circumradius: exact on a circle, within `O(h^2 / R^2)` of the curve's
/// own for vertices h apart, at most [`MAX_SPACING_KM`]).
pub fn tight_bends(points: &[[f64; 2]], min_radius_km: f64) -> Vec<TightBend> {
    let v = vertices(points);
    let mut s = vec![0.0];
    for w in v.windows(2) {
        s.push(s[s.len() - 1] + norm(sub(w[1], w[0])));
    }
    let mut out: Vec<TightBend> = Vec::new();
    let mut in_run = false;
    for i in 1..v.len().saturating_sub(1) {
        let (a, b) = (sub(v[i], v[i - 1]), sub(v[i + 1], v[i]));
        let twice_area = cross(a, b).abs();
        let r = if twice_area > 0.0 {
            norm(a) * norm(b) * norm(sub(v[i + 1], v[i - 1])) / (2.0 * twice_area)
        } else if dot(a, b) < 0.0 {
            // Collinear and going back: the path turns on itself, radius 0.
            0.0
        } else {
            f64::INFINITY
        };
        if r < min_radius_km {
            let here = TightBend { at: v[i], along_km: s[i], radius_km: r };
            match out.last_mut() {
                Some(last) if in_run => {
                    if r < last.radius_km {
                        *last = here;
                    }
                }
                _ => out.push(here),
            }
            in_run = true;
        } else {
            in_run = false;
        }
    }
    out
}

/// Warnings for curtains whose path bends tighter than half their width:
/// there the inner edge of the footprint's frame (v = -width / 2 on the
/// inside of the bend) passes the bend's centre and the band overlaps
/// itself. A warning, not an error: the bake is still defined, the overlap
/// is only brighter than intended. Each names the curtain, the place and the
/// radius (at most three places a curtain, then how many more).
pub fn bend_warnings(curtains: &[crate::scene::Curtain]) -> Vec<String> {
    let mut w = Vec::new();
    for (i, c) in curtains.iter().enumerate() {
        let Some(points) = &c.path else { continue };
        let half = 0.5 * c.width;
        let bends = tight_bends(points, half);
        for b in bends.iter().take(3) {
            if b.radius_km == 0.0 {
                w.push(format!(
                    "tight bend: curtain[{i}].path turns back on itself at ({:.1}, {:.1}) km, {:.1} km along it: the band folds over itself there; remove the point that goes back or move it aside",
                    b.at[0], b.at[1], b.along_km
                ));
                continue;
            }
            w.push(format!(
                "tight bend: curtain[{i}].path bends with a radius of curvature of {:.1} km at ({:.1}, {:.1}) km, {:.1} km along it, below half its width (curtain[{i}].width / 2 = {half} km): the band overlaps itself on the inside of the bend; space the points wider there or narrow the curtain",
                b.radius_km, b.at[0], b.at[1], b.along_km
            ));
        }
        if bends.len() > 3 {
            w.push(format!("tight bend: curtain[{i}].path has {} more bends tighter than {half} km", bends.len() - 3));
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::fmath;

    #[test]
    fn with_a_site_a_path_is_lifted_along_igrfs_field_over_it() {
        // Tromso's dome: IGRF-14 at 110 km over the site dips 78.6 degrees
        // toward declination 11 degrees east (`crate::physics::site_field`'s
        // test): the lift runs cot(I) (top - 110) against the field's
        // horizontal part, not the scene keys' dipole's.
        let s = crate::scene::presets::by_name("tromso_dome").unwrap();
        let lift = Lift::of_scene(&s);
        let field = SiteField::of_scene(&s).unwrap();
        let (inc, dec) = field.angles_deg([0.0, 0.0], PATH_ALTITUDE_KM);
        let d = lift.apply([0.0, 0.0]);
        let want = (s.beams.top_km - PATH_ALTITUDE_KM) / fmath::tan(inc.to_radians());
        let az = fmath::atan2(d[0], d[1]).to_degrees();
        assert!(matches!(lift, Lift::Site { .. }));
        assert!((fmath::hypot(d[0], d[1]) - want).abs() < 0.5, "{d:?} {want}");
        assert!(((az - dec - 180.0).rem_euclid(360.0) + 0.5).rem_euclid(360.0) < 1.0, "{az} {dec}");
        assert_ne!(Lift::of(&s.beams, &s.earth).apply([0.0, 0.0]), d);
        // `field = "scene"` keeps the scene keys' lift.
        let mut own = s.clone();
        own.site.as_mut().unwrap().field = crate::scene::SiteField::Scene;
        assert_eq!(Lift::of_scene(&own), Lift::of(&s.beams, &s.earth));
    }

    /// Points 30 degrees apart on a circle of radius 20 km (chords of
    /// 10.35 km, so centripetal is uniform Catmull-Rom here).
    fn circle() -> Vec<[f64; 2]> {
        (0..10).map(|k| (k as f64 * 30.0).to_radians()).map(|a| [20.0 * fmath::cos(a), 20.0 * fmath::sin(a)]).collect()
    }

    #[test]
    fn tight_bends_find_the_radius_and_the_place() {
        let pts = circle();
        let chord = 40.0 * fmath::sin(15f64.to_radians());
        let length = polyline_length(&vertices(&pts));
        // Inside, the cubic spans stay near the circle (tightest at the
        // points: 17.0 km there): below a 16 km limit only the end spans are
        // tight. There the phantom end points (reflections through the
        // ends) start the curve along the chord, so it turns the span's 30
        // degrees in about half the distance: a radius near R / 2.
        let ends = tight_bends(&pts, 16.0);
        assert_eq!(ends.len(), 2, "{ends:?}");
        assert!(ends[0].along_km < chord && ends[1].along_km > length - chord, "{ends:?}");
        assert!(ends.iter().all(|b| b.radius_km > 0.4 * 20.0 && b.radius_km < 0.75 * 20.0), "{ends:?}");
        // Above 25 km every vertex is tight: one stretch, the whole curve.
        assert_eq!(tight_bends(&pts, 25.0).len(), 1);
        // A straight path never bends.
        assert!(tight_bends(&[[0.0, 0.0], [50.0, 0.0], [100.0, 0.0]], 1e6).is_empty());
        // One that goes back along itself turns with radius 0, at the
        // turning point (50 km out, 50 km along).
        let back = tight_bends(&[[0.0, 0.0], [50.0, 0.0], [20.0, 0.0]], 1e-3);
        assert_eq!(back.len(), 1, "{back:?}");
        assert_eq!(back[0].radius_km, 0.0);
        assert!((back[0].at[0] - 50.0).abs() < 1e-9 && back[0].at[1] == 0.0 && (back[0].along_km - 50.0).abs() < 1e-9, "{back:?}");
        // A right-angle corner at (100, 0) between two long legs: the
        // tightest place is at the corner.
        let b = tight_bends(&[[0.0, 0.0], [100.0, 0.0], [100.0, 100.0]], 30.0);
        assert_eq!(b.len(), 1, "{b:?}");
        let d = norm(sub(b[0].at, [100.0, 0.0]));
        assert!(d < 5.0 && b[0].radius_km < 30.0 && (b[0].along_km - 100.0).abs() < 5.0, "{b:?}");
    }

    #[test]
    fn bend_warnings_name_the_curtain_and_the_place() {
        use crate::scene::Curtain;
        let tightest = tight_bends(&circle(), 1e3)[0].clone();
        let narrow = Curtain { path: Some(circle()), width: 1.9 * tightest.radius_km, bend_km: 2.0, ..Curtain::default() };
        let wide = Curtain { path: Some(circle()), width: 50.0, bend_km: 2.0, ..Curtain::default() };
        let w = bend_warnings(&[Curtain::default(), narrow, wide]);
        assert_eq!(w.len(), 1, "{w:?}");
        let place = format!("{:.1} km at ({:.1}, {:.1}) km", tightest.radius_km, tightest.at[0], tightest.at[1]);
        assert!(w[0].starts_with("tight bend: curtain[2].path") && w[0].contains("curtain[2].width / 2 = 25 km"), "{}", w[0]);
        assert!(w[0].contains(&place), "{} lacks {place}", w[0]);
        // Three collinear points going back: any width folds the band.
        let back = Curtain { path: Some(vec![[0.0, 0.0], [50.0, 0.0], [20.0, 0.0]]), width: 2.0, ..Curtain::default() };
        let w = bend_warnings(&[back]);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("tight bend: curtain[0].path turns back on itself at (50.0, 0.0) km, 50.0 km along it"), "{}", w[0]);
    }

    #[test]
    fn two_points_give_the_straight_segment_and_a_rigid_frame() {
        let f = PathFrame::new(&[[-30.0, 5.0], [50.0, 65.0]], 20.0);
        assert!((f.length - 100.0).abs() < 1e-9);
        // Rotation by atan2(60, 80): u along (0.8, 0.6), v along (-0.6, 0.8), centre (10, 35).
        let (x, y) = f.to_world(12.0, -7.0);
        let (ex, ey) = (10.0 + 12.0 * 0.8 + 7.0 * 0.6, 35.0 + 12.0 * 0.6 - 7.0 * 0.8);
        assert!((x - ex).abs() < 1e-9 && (y - ey).abs() < 1e-9, "{x} {y}");
        let (u, v) = f.to_local(x, y);
        assert!((u - 12.0).abs() < 1e-9 && (v + 7.0).abs() < 1e-9);
        assert_eq!(f.to_local(10.0 + 100.0, 35.0 - 200.0), (f64::INFINITY, f64::INFINITY));
    }

    #[test]
    fn a_curved_frame_inverts_exactly_and_passes_through_its_points() {
        let pts = [[0.0, 0.0], [100.0, 40.0], [200.0, 0.0], [260.0, -80.0]];
        let f = PathFrame::new(&pts, 30.0);
        let v = vertices(&pts);
        for p in pts {
            assert!(v.iter().any(|q| q == &p));
        }
        // Curve length: above the chords' 355 km.
        assert!(f.length > polyline_length(&pts) && f.length < 1.2 * polyline_length(&pts), "{}", f.length);
        for i in 0..200 {
            let u = -0.5 * f.length + f.length * (i as f64 + 0.5) / 200.0;
            for v in [-14.0, -3.0, 0.0, 6.5, 14.0] {
                let (x, y) = f.to_world(u, v);
                let (u2, v2) = f.to_local(x, y);
                assert!((u2 - u).abs() < 1e-7 && (v2 - v).abs() < 1e-7, "{u} {v} -> {u2} {v2}");
            }
        }
    }

    #[test]
    fn lift_is_cot_dip_times_the_height() {
        let b = BeamParams::default();
        let l = lift_km(&b);
        let expect = (b.top_km - PATH_ALTITUDE_KM) / fmath::tan(b.b_inclination_deg.to_radians());
        // Declination 0: the field points north and down, so its line rises to the south.
        assert!(l[0].abs() < 1e-9 && (l[1] + expect).abs() < 1e-9, "{l:?} {expect}");
        assert!((expect - 31.9).abs() < 0.1);
    }
}
