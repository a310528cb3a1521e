//! Terrain under the aurora: an infinite plane or a triangulated heightfield,
//! defined so that Blender can import exactly the same mesh ([`write_obj`]).
//!
//! # Heightfield
//! A regular grid of `nx x ny` height samples over `extent = [x0, y0, x1, y1]`
//! (sample (i, j) at `x = x0 + i (x1 - x0) / (nx - 1)`, `y = y0 + j (y1 - y0) / (ny - 1)`);
//! every cell is split along its diagonal from (i, j) to (i+1, j+1) into the
//! triangles `(p00, p10, p11)` and `(p00, p11, p01)`, both wound
//! counter-clockwise seen from above. Positions are rounded to f32 once, so
//! the mesh we trace and the OBJ Blender reads (in f32) are the same numbers.
//! Outside the extent there is no ground.
//!
//! * Procedural (`kind = "heightfield"`, no `heightmap`): the resolution is 8
//!   samples per `mountain_scale` along each axis, `cells = ceil(8 L /
//!   mountain_scale)` clamped to [1, 1023] (at most 1024^2 samples); heights
//!   are `height + mountain_height * clamp(0.5 + fbm(x / s, y / s), 0, 1)`
//!   with `fbm` = 6 octaves of Perlin noise (`noise` crate, seed from
//!   `terrain.seed`), lacunarity 2, gain 1/2, normalised by the sum of gains.
//! * Heightmap PNG (8- or 16-bit greyscale, at most 4096^2): one sample per
//!   pixel, column 0 at `x0`, **row 0 at `y1`** (north up, as the image is
//!   viewed), height `height + mountain_height * v` with `v` in [0, 1].
//!
//! # On a round Earth
//! With `earth.radius_km = R > 0` (`crate::geometry::earth`: the centre at `(0, 0,
//! -R)`) the plane is the sphere of radius `R + height`
//! ([`TerrainModel::Sphere`], an exact ray-sphere intersection), and a
//! heightfield's sample `(x, y)` of height `z` sits at `z` above the sphere,
//! over the grid point: its height becomes `(R + z) cos(d / R) - R` with
//! `d = |(x, y)|` ([`Heightfield::on_sphere`]), the ground point's drop
//! below the origin's tangent plane taken off. The grid stays regular in x
//! and y (the DDA and the OBJ need it); the sphere's point at ground
//! distance d lies `d - R sin(d / R)`, about `d^3 / 6R^2`, closer to the
//! axis (4 m at 100 km, 0.5 km at 500 km), and a sample of height z sits
//! `z (d / R)^2` low (1 m for 4 km at 110 km): a heightfield is meant for
//! the ground near the camera.
//!
//! Rays are traced with a 2D DDA over the cells the ray's ground projection
//! crosses (cells culled by their height range) and an f64 Moller-Trumbore
//! test of the two triangles of each cell. The shading normal is smooth, as
//! Blender shades the mesh with `use_smooth` (blender/terrain.py): each
//! sample's vertex normal is the normals of the triangles round it
//! weighted by their corner angles there (Blender's vertex normals), and a
//! hit's normal is its triangle's three vertex normals interpolated with
//! the hit's barycentric coordinates and normalised (Cycles' smooth
//! normal), flipped when the ray meets the triangle's back.
//!
//! # Snow
//! The default albedo (`terrain.albedo`, `crate::scene::Terrain`) is
//! fresh snow's in the visible, 0.85: pure snow reflects 0.96-0.99 of
//! visible light and parts per million of soot take 5-15 % off (Warren &
//! Wiscombe 1980, "A model for the spectral albedo of snow II", J. Atmos.
//! Sci. 37, 2734): the auroral zone's winter ground, lit green by the
//! aurora as photographs show it.

use super::settings::RenderError;
use crate::scene::{Terrain, TerrainKind};
use crate::util::fmath;
use glam::DVec3;
use noise::Perlin;
use std::io::Write;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Samples per `mountain_scale` of the procedural heightfield.
pub const SAMPLES_PER_FEATURE: f64 = 8.0;
/// Largest number of cells per axis of the procedural heightfield.
pub const MAX_CELLS: usize = 1023;
/// Largest heightmap side in pixels.
pub const MAX_HEIGHTMAP: usize = 4096;
/// fBm octaves.
pub const OCTAVES: usize = 6;

/// A ray-surface intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub t: f64,
    pub p: DVec3,
    /// Unit normal on the side the ray came from.
    pub n: DVec3,
}

/// The ground, ready for ray tracing.
#[derive(Clone, Debug, PartialEq)]
pub enum TerrainModel {
    None,
    /// The plane z = height.
    Plane {
        height: f64,
    },
    /// Shared: a procedural heightfield is built once per process for its
    /// scene keys ([`TerrainModel::on_earth`]).
    Heightfield(Arc<Heightfield>),
    /// The sphere of `radius` km about `centre`: the plane on a round Earth.
    Sphere {
        centre: DVec3,
        radius: f64,
    },
}

impl TerrainModel {
    /// [`TerrainModel::from_terrain`] on the Earth of radius `earth_radius_km`
    /// (module doc; 0: the flat ground, the same model).
    ///
    /// A procedural heightfield (no `heightmap`: a function of the scene
    /// keys alone) is kept for the process, the last one built, keyed by
    /// those keys and the radius, so the render's checks, the render itself
    /// and each frame of a sequence share one build; a heightmap is read
    /// anew each time (its file may change under a watching preview).
    pub fn on_earth(t: &Terrain, base_dir: Option<&Path>, earth_radius_km: f64) -> Result<TerrainModel, RenderError> {
        if t.kind == TerrainKind::Heightfield && t.heightmap.is_none() {
            return Self::procedural_shared(t, earth_radius_km);
        }
        Self::on_earth_built(t, base_dir, earth_radius_km)
    }

    /// [`TerrainModel::on_earth`] without the shared heightfield.
    fn on_earth_built(t: &Terrain, base_dir: Option<&Path>, earth_radius_km: f64) -> Result<TerrainModel, RenderError> {
        if earth_radius_km == 0.0 || t.kind != TerrainKind::Heightfield {
            let m = Self::from_terrain(t, base_dir)?;
            if earth_radius_km == 0.0 {
                return Ok(m);
            }
            return Ok(match m {
                TerrainModel::Plane { height } => {
                    TerrainModel::Sphere { centre: DVec3::new(0.0, 0.0, -earth_radius_km), radius: earth_radius_km + height }
                }
                other => other,
            });
        }
        // The flat samples without their normals: only the sphere's are used.
        let flat = Heightfield::from_terrain_unshaded(t, base_dir)?;
        Ok(TerrainModel::Heightfield(Arc::new(flat.on_sphere(earth_radius_km)?)))
    }

    /// The procedural heightfield of `t` on the Earth of `earth_radius_km`,
    /// shared with the last call for the same keys (the albedo aside: it is
    /// read per hit, not built in).
    fn procedural_shared(t: &Terrain, earth_radius_km: f64) -> Result<TerrainModel, RenderError> {
        static LAST: Mutex<Option<(String, Arc<Heightfield>)>> = Mutex::new(None);
        // Debug prints every float exactly (-0.0 apart from 0.0), so equal
        // keys are equal inputs.
        let key = format!("{:?} {:?}", Terrain { albedo: [0.0; 3], ..t.clone() }, earth_radius_km.to_bits());
        if let Some((k, h)) = LAST.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            if *k == key {
                return Ok(TerrainModel::Heightfield(Arc::clone(h)));
            }
        }
        let m = Self::on_earth_built(t, None, earth_radius_km)?;
        if let TerrainModel::Heightfield(h) = &m {
            *LAST.lock().unwrap_or_else(|e| e.into_inner()) = Some((key, Arc::clone(h)));
        }
        Ok(m)
    }

    /// Builds the terrain of a scene; a heightmap path is resolved against
    /// `base_dir` (the scene file's folder) when relative.
    pub fn from_terrain(t: &Terrain, base_dir: Option<&Path>) -> Result<TerrainModel, RenderError> {
        Ok(match t.kind {
            TerrainKind::None => TerrainModel::None,
            TerrainKind::Plane => {
                if !t.height.is_finite() {
                    return Err(RenderError::Settings(format!("terrain.height = {} must be finite", t.height)));
                }
                TerrainModel::Plane { height: t.height }
            }
            TerrainKind::Heightfield => TerrainModel::Heightfield(Arc::new(Heightfield::from_terrain(t, base_dir)?)),
        })
    }

    /// The nearest hit with `t` in `(t_min, t_max)`.
    pub fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<SurfaceHit> {
        match self {
            TerrainModel::None => None,
            TerrainModel::Plane { height } => {
                if d.z == 0.0 {
                    return None;
                }
                let t = (height - o.z) / d.z;
                (t > t_min && t < t_max).then(|| SurfaceHit {
                    t,
                    p: DVec3::new(o.x + d.x * t, o.y + d.y * t, *height),
                    n: DVec3::new(0.0, 0.0, -d.z.signum()),
                })
            }
            TerrainModel::Heightfield(h) => h.intersect(o, d, t_min, t_max),
            TerrainModel::Sphere { centre, radius } => intersect_sphere(*centre, *radius, o, d, t_min, t_max),
        }
    }

    pub fn is_none(&self) -> bool {
        matches!(self, TerrainModel::None)
    }

    /// How high the point `p` (km) and the ground under it are, in the same
    /// measure ([`Clearance`]): on the plane and a heightfield, `z` and the
    /// surface's `z` over `(p.x, p.y)`; on the sphere, the altitudes above
    /// the Earth's surface. None without ground under `p` (no terrain, or
    /// outside a heightfield's extent). A camera whose point is below its
    /// ground sees the inside of the terrain: a black picture.
    pub fn clearance(&self, p: DVec3) -> Option<Clearance> {
        match self {
            TerrainModel::None => None,
            TerrainModel::Plane { height } => Some(Clearance { point_km: p.z, ground_km: *height }),
            TerrainModel::Heightfield(h) => h.height_at(p.x, p.y).map(|g| Clearance { point_km: p.z, ground_km: g }),
            TerrainModel::Sphere { centre, radius } => {
                // The Earth's radius: the centre sits at (0, 0, -R).
                let r_earth = -centre.z;
                Some(Clearance { point_km: (p - *centre).length() - r_earth, ground_km: radius - r_earth })
            }
        }
    }
}

/// A point's height and the ground's under it, km ([`TerrainModel::clearance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    pub point_km: f64,
    pub ground_km: f64,
}

impl Clearance {
    /// Whether the point lies below the ground.
    pub fn is_below(&self) -> bool {
        self.point_km < self.ground_km
    }
}

/// The nearest hit of `o + t d` with the sphere, `t` in `(t_min, t_max)`: the
/// roots of `|o - c + t d|^2 = r^2`, the smaller by the numerically stable
/// form (no cancellation between `b` and the root of the discriminant); the
/// normal faces the ray.
pub fn intersect_sphere(c: DVec3, r: f64, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<SurfaceHit> {
    let oc = o - c;
    let a = d.length_squared();
    let half_b = oc.dot(d);
    // |oc|^2 - r^2 as (|oc| - r)(|oc| + r): the altitude times 2R, without
    // the cancellation of two numbers of size R^2.
    let l = oc.length();
    let cc = (l - r) * (l + r);
    let disc = half_b * half_b - a * cc;
    if a == 0.0 || disc < 0.0 {
        return None;
    }
    let q = -(half_b + half_b.signum() * disc.sqrt());
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (cc / q, q / a) };
    let (t0, t1) = (t0.min(t1), t0.max(t1));
    let t = [t0, t1].into_iter().find(|&t| t > t_min && t < t_max)?;
    let p = o + d * t;
    let n = (p - c) / r;
    Some(SurfaceHit { t, p, n: if n.dot(d) > 0.0 { -n } else { n } })
}

/// A triangulated regular grid of heights (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Heightfield {
    /// Sample x coordinates, strictly increasing, f32-exact.
    pub xs: Vec<f64>,
    /// Sample y coordinates, strictly increasing, f32-exact.
    pub ys: Vec<f64>,
    /// Heights, f32-exact, row-major: `z[j * nx + i]` is at `(xs[i], ys[j])`.
    pub z: Vec<f64>,
    pub zmin: f64,
    pub zmax: f64,
    /// Vertex normals, as `z` ([`vertex_normals`]: Blender's for a smooth mesh).
    pub normals: Vec<DVec3>,
}

/// Cells of the procedural heightfield along an axis of length `len`.
pub fn procedural_cells(len: f64, mountain_scale: f64) -> usize {
    let c = (SAMPLES_PER_FEATURE * len / mountain_scale).ceil();
    if c.is_finite() {
        (c as usize).clamp(1, MAX_CELLS)
    } else {
        MAX_CELLS
    }
}

fn f32_exact(x: f64) -> f64 {
    x as f32 as f64
}

/// `n` f32-exact coordinates from `a` to `b`, or an error if f32 rounding
/// would merge two of them.
fn axis(a: f64, b: f64, n: usize, what: &str) -> Result<Vec<f64>, RenderError> {
    let v: Vec<f64> = (0..n).map(|i| f32_exact(a + (b - a) * i as f64 / (n - 1) as f64)).collect();
    if v.windows(2).any(|w| !(w[1] > w[0])) {
        return Err(RenderError::Settings(format!(
            "terrain.extent {what} range [{a}, {b}] is too small for {n} samples in single precision"
        )));
    }
    Ok(v)
}

impl Heightfield {
    /// A heightfield from explicit samples (heights rounded to f32).
    pub fn from_samples(xs: Vec<f64>, ys: Vec<f64>, z: Vec<f64>) -> Result<Heightfield, RenderError> {
        Self::unshaded(xs, ys, z).map(Heightfield::shaded)
    }

    /// [`Heightfield::from_samples`] without the vertex normals (empty):
    /// the same checks and samples, for a field that is only a step to
    /// another ([`Heightfield::on_sphere`] reads the samples alone).
    fn unshaded(xs: Vec<f64>, ys: Vec<f64>, z: Vec<f64>) -> Result<Heightfield, RenderError> {
        let (nx, ny) = (xs.len(), ys.len());
        if nx < 2 || ny < 2 || z.len() != nx * ny {
            return Err(RenderError::Settings(format!(
                "a heightfield needs at least 2x2 samples and nx*ny heights (got {nx}x{ny}, {} heights)",
                z.len()
            )));
        }
        let xs: Vec<f64> = xs.into_iter().map(f32_exact).collect();
        let ys: Vec<f64> = ys.into_iter().map(f32_exact).collect();
        let z: Vec<f64> = z.into_iter().map(f32_exact).collect();
        if xs.windows(2).any(|w| !(w[1] > w[0])) || ys.windows(2).any(|w| !(w[1] > w[0])) {
            return Err(RenderError::Settings("heightfield sample coordinates must increase strictly".into()));
        }
        if z.iter().chain(&xs).chain(&ys).any(|v| !v.is_finite()) {
            return Err(RenderError::Settings("heightfield samples must be finite".into()));
        }
        let zmin = z.iter().copied().fold(f64::INFINITY, f64::min);
        let zmax = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Ok(Heightfield { xs, ys, z, zmin, zmax, normals: Vec::new() })
    }

    /// The heightfield laid on the sphere of radius `r` km about `(0, 0, -r)`
    /// (module doc): each sample's height above the sphere, over its grid
    /// point.
    pub fn on_sphere(self, r: f64) -> Result<Heightfield, RenderError> {
        let nx = self.xs.len();
        let z = self
            .z
            .iter()
            .enumerate()
            .map(|(k, &h)| {
                let (x, y) = (self.xs[k % nx], self.ys[k / nx]);
                (r + h) * fmath::cos(fmath::hypot(x, y) / r) - r
            })
            .collect();
        Self::from_samples(self.xs, self.ys, z)
    }

    /// The heightfield of a scene's `[terrain]` (kind must be "heightfield").
    pub fn from_terrain(t: &Terrain, base_dir: Option<&Path>) -> Result<Heightfield, RenderError> {
        Self::from_terrain_unshaded(t, base_dir).map(Heightfield::shaded)
    }

    /// [`Heightfield::from_terrain`] without the vertex normals
    /// ([`Heightfield::unshaded`]).
    fn from_terrain_unshaded(t: &Terrain, base_dir: Option<&Path>) -> Result<Heightfield, RenderError> {
        let [x0, y0, x1, y1] = t.extent;
        if !(x1 > x0 && y1 > y0 && t.extent.iter().all(|v| v.is_finite())) {
            return Err(RenderError::Settings(format!("terrain.extent {:?} must be [x0, y0, x1, y1] with x1 > x0, y1 > y0", t.extent)));
        }
        if !(t.height.is_finite() && t.mountain_height.is_finite() && t.mountain_height >= 0.0) {
            return Err(RenderError::Settings("terrain.height and mountain_height must be finite, mountain_height >= 0".into()));
        }
        match &t.heightmap {
            Some(p) => Self::heightmap_unshaded(&super::settings::input_path(base_dir, p), t),
            None => Self::procedural_unshaded(t),
        }
    }

    /// Procedural fBm mountains (see the module doc).
    pub fn procedural(t: &Terrain) -> Result<Heightfield, RenderError> {
        Self::procedural_unshaded(t).map(Heightfield::shaded)
    }

    /// The field with its vertex normals.
    fn shaded(mut self) -> Heightfield {
        self.normals = vertex_normals(&self);
        self
    }

    fn procedural_unshaded(t: &Terrain) -> Result<Heightfield, RenderError> {
        if !(t.mountain_scale > 0.0 && t.mountain_scale.is_finite()) {
            return Err(RenderError::Settings(format!("terrain.mountain_scale = {} must be finite and > 0", t.mountain_scale)));
        }
        let [x0, y0, x1, y1] = t.extent;
        let cx = procedural_cells(x1 - x0, t.mountain_scale);
        let cy = procedural_cells(y1 - y0, t.mountain_scale);
        let xs = axis(x0, x1, cx + 1, "x")?;
        let ys = axis(y0, y1, cy + 1, "y")?;
        let perlin = Perlin::new((t.seed ^ (t.seed >> 32)) as u32);
        let mut z = Vec::with_capacity(xs.len() * ys.len());
        for &y in &ys {
            for &x in &xs {
                z.push(t.height + t.mountain_height * mountain(&perlin, x / t.mountain_scale, y / t.mountain_scale));
            }
        }
        Self::unshaded(xs, ys, z)
    }

    /// Heights from an 8- or 16-bit greyscale PNG (see the module doc).
    pub fn from_heightmap(path: &Path, t: &Terrain) -> Result<Heightfield, RenderError> {
        Self::heightmap_unshaded(path, t).map(Heightfield::shaded)
    }

    fn heightmap_unshaded(path: &Path, t: &Terrain) -> Result<Heightfield, RenderError> {
        let err = |message: String| RenderError::Heightmap { path: path.to_path_buf(), message };
        let file = crate::util::input_file::open(path).map_err(|source| RenderError::Input { key: "terrain.heightmap", source })?;
        let mut dec = png::Decoder::new(std::io::BufReader::new(file));
        dec.set_transformations(png::Transformations::EXPAND);
        let mut reader = dec.read_info().map_err(|e| err(e.to_string()))?;
        let (w, h) = (reader.info().width as usize, reader.info().height as usize);
        if w < 2 || h < 2 || w > MAX_HEIGHTMAP || h > MAX_HEIGHTMAP {
            return Err(err(format!("is {w}x{h} pixels; heightmaps must be 2..={MAX_HEIGHTMAP} pixels on each side")));
        }
        let mut buf = vec![0u8; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).map_err(|e| err(e.to_string()))?;
        let (ct, depth) = reader.output_color_type();
        let channels = match ct {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            other => return Err(err(format!("is {other:?}; heightmaps must be greyscale (8 or 16 bit)"))),
        };
        let bytes = match depth {
            png::BitDepth::Eight => 1,
            png::BitDepth::Sixteen => 2,
            other => return Err(err(format!("has bit depth {other:?} after expansion; expected 8 or 16"))),
        };
        let max = if bytes == 1 { 255.0 } else { 65535.0 };
        let [x0, y0, x1, y1] = t.extent;
        let xs = axis(x0, x1, w, "x")?;
        let ys = axis(y0, y1, h, "y")?;
        let mut z = vec![0.0; w * h];
        for row in 0..h {
            let line = &buf[row * info.line_size..][..info.line_size];
            // Row 0 is the north edge (y1): sample j = h - 1 - row.
            let j = h - 1 - row;
            for i in 0..w {
                let at = i * channels * bytes;
                let v = if bytes == 1 { line[at] as f64 } else { u16::from_be_bytes([line[at], line[at + 1]]) as f64 };
                z[j * w + i] = t.height + t.mountain_height * v / max;
            }
        }
        Self::unshaded(xs, ys, z)
    }

    pub fn nx(&self) -> usize {
        self.xs.len()
    }
    pub fn ny(&self) -> usize {
        self.ys.len()
    }

    /// The shading normal at barycentric `(u, v)` of the triangle with
    /// sample `corners`: the vertex normals interpolated and normalised, as
    /// Cycles shades a smooth mesh, turned to the side the ray came from by
    /// the geometric normal (`facing`, already facing the ray): a ray on a
    /// face's back gets the flipped normal, as Cycles' backfacing flip.
    fn smooth_normal(&self, corners: &[(usize, usize); 3], u: f64, v: f64, facing: DVec3, tri: &[DVec3; 3]) -> DVec3 {
        let nx = self.xs.len();
        let vn = corners.map(|(i, j)| self.normals[j * nx + i]);
        let n = ((1.0 - u - v) * vn[0] + u * vn[1] + v * vn[2]).try_normalize().unwrap_or(facing);
        let front = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        if front.dot(facing) >= 0.0 {
            n
        } else {
            -n
        }
    }

    /// The surface's height over `(x, y)`: the triangle of the cell that
    /// holds it (module doc: split along the (i, j)-(i+1, j+1) diagonal),
    /// linear on it; None outside the extent.
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let (nx, ny) = (self.nx(), self.ny());
        if !(x >= self.xs[0] && x <= self.xs[nx - 1] && y >= self.ys[0] && y <= self.ys[ny - 1]) {
            return None;
        }
        let cell = |v: &[f64], x: f64| v.partition_point(|s| *s <= x).saturating_sub(1).min(v.len() - 2);
        let (i, j) = (cell(&self.xs, x), cell(&self.ys, y));
        let u = (x - self.xs[i]) / (self.xs[i + 1] - self.xs[i]);
        let v = (y - self.ys[j]) / (self.ys[j + 1] - self.ys[j]);
        let z = |a: usize, b: usize| self.z[(j + b) * nx + i + a];
        Some(if u >= v {
            // (p00, p10, p11)
            z(0, 0) + u * (z(1, 0) - z(0, 0)) + v * (z(1, 1) - z(1, 0))
        } else {
            // (p00, p11, p01)
            z(0, 0) + u * (z(1, 1) - z(0, 1)) + v * (z(0, 1) - z(0, 0))
        })
    }

    /// Sample (i, j) as a point.
    #[inline]
    pub fn vertex(&self, i: usize, j: usize) -> DVec3 {
        DVec3::new(self.xs[i], self.ys[j], self.z[j * self.xs.len() + i])
    }

    /// The two triangles of cell (i, j), split along the (i,j)-(i+1,j+1) diagonal.
    #[inline]
    pub fn cell_triangles(&self, i: usize, j: usize) -> [[DVec3; 3]; 2] {
        let p00 = self.vertex(i, j);
        let p10 = self.vertex(i + 1, j);
        let p11 = self.vertex(i + 1, j + 1);
        let p01 = self.vertex(i, j + 1);
        [[p00, p10, p11], [p00, p11, p01]]
    }

    /// The nearest hit with `t` in `(t_min, t_max)` (2D DDA over cells).
    pub fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<SurfaceHit> {
        let (nx, ny) = (self.nx(), self.ny());
        let lo = DVec3::new(self.xs[0], self.ys[0], self.zmin);
        let hi = DVec3::new(self.xs[nx - 1], self.ys[ny - 1], self.zmax);
        let (mut ta, mut tb) = (t_min, t_max);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < lo[k] || o[k] > hi[k] {
                    return None;
                }
            } else {
                let (p, q) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
                ta = ta.max(p.min(q));
                tb = tb.min(p.max(q));
            }
        }
        if !(ta <= tb) {
            return None;
        }
        let p = o + d * ta;
        let cell = |v: &[f64], x: f64| v.partition_point(|s| *s <= x).saturating_sub(1).min(v.len() - 2);
        let (mut i, mut j) = (cell(&self.xs, p.x), cell(&self.ys, p.y));
        let next = |v: &[f64], k: usize, o: f64, d: f64| -> f64 {
            if d > 0.0 {
                (v[k + 1] - o) / d
            } else if d < 0.0 {
                (v[k] - o) / d
            } else {
                f64::INFINITY
            }
        };
        let mut tx = next(&self.xs, i, o.x, d.x);
        let mut ty = next(&self.ys, j, o.y, d.y);
        let mut t = ta;
        loop {
            let t_end = tx.min(ty).min(tb);
            // Cull the cell by its height range against the ray's z over the cell.
            let (za, zb) = (o.z + d.z * t, o.z + d.z * t_end);
            let n = nx;
            let hs = [self.z[j * n + i], self.z[j * n + i + 1], self.z[(j + 1) * n + i], self.z[(j + 1) * n + i + 1]];
            let cmin = hs.iter().copied().fold(f64::INFINITY, f64::min);
            let cmax = hs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let margin = 1e-9 * (1.0 + za.abs().max(zb.abs()));
            if za.min(zb) <= cmax + margin && za.max(zb) >= cmin - margin {
                let mut best: Option<SurfaceHit> = None;
                for (tri, corners) in self.cell_triangles(i, j).iter().zip(cell_corners(i, j)) {
                    if let Some((h, u, v)) = intersect_triangle_uv(o, d, tri, t_min, t_max) {
                        if best.is_none_or(|b| h.t < b.t) {
                            best = Some(SurfaceHit { n: self.smooth_normal(&corners, u, v, h.n, tri), ..h });
                        }
                    }
                }
                if best.is_some() {
                    return best;
                }
            }
            if t_end >= tb {
                return None;
            }
            t = t_end;
            if tx <= ty {
                i = step_cell(i, nx - 1, d.x)?;
                tx = next(&self.xs, i, o.x, d.x);
            } else {
                j = step_cell(j, ny - 1, d.y)?;
                ty = next(&self.ys, j, o.y, d.y);
            }
        }
    }
}

/// The cell after cell `k` (of `cells` along one axis) for a ray whose
/// direction along that axis is `d`: the next one up for `d > 0`, else the
/// next one down; `None` past either end.
fn step_cell(k: usize, cells: usize, d: f64) -> Option<usize> {
    if d > 0.0 {
        Some(k + 1).filter(|&next| next < cells)
    } else {
        k.checked_sub(1)
    }
}

/// The samples (i, j) at the corners of cell (i, j)'s two triangles, in
/// [`Heightfield::cell_triangles`]' order.
fn cell_corners(i: usize, j: usize) -> [[(usize, usize); 3]; 2] {
    [[(i, j), (i + 1, j), (i + 1, j + 1)], [(i, j), (i + 1, j + 1), (i, j + 1)]]
}

/// Blender's vertex normals of a triangle mesh: at each vertex the face
/// normals of the triangles round it weighted by their corner angles there,
/// normalised (Blender's `mesh_normals`, as for a mesh shaded smooth).
fn vertex_normals(hf: &Heightfield) -> Vec<DVec3> {
    let (nx, ny) = (hf.xs.len(), hf.ys.len());
    let mut acc = vec![DVec3::ZERO; nx * ny];
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            for corners in cell_corners(i, j) {
                let p = corners.map(|(a, b)| hf.vertex(a, b));
                let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                for k in 0..3 {
                    let (a, b) = ((p[(k + 1) % 3] - p[k]).normalize_or_zero(), (p[(k + 2) % 3] - p[k]).normalize_or_zero());
                    let angle = fmath::acos(a.dot(b).clamp(-1.0, 1.0));
                    let (ci, cj) = corners[k];
                    acc[cj * nx + ci] += n * angle;
                }
            }
        }
    }
    acc.into_iter().map(|n| n.try_normalize().unwrap_or(DVec3::Z)).collect()
}

/// Moller & Trumbore (1997) ray-triangle test in f64; edges are inclusive
/// (with a 1e-12 barycentric tolerance) so the shared diagonal and cell
/// borders leave no cracks.
pub fn intersect_triangle(o: DVec3, d: DVec3, tri: &[DVec3; 3], t_min: f64, t_max: f64) -> Option<SurfaceHit> {
    intersect_triangle_uv(o, d, tri, t_min, t_max).map(|(h, _, _)| h)
}

/// [`intersect_triangle`] with the hit's barycentric coordinates `(u, v)`
/// of `tri[1]` and `tri[2]`.
pub fn intersect_triangle_uv(o: DVec3, d: DVec3, tri: &[DVec3; 3], t_min: f64, t_max: f64) -> Option<(SurfaceHit, f64, f64)> {
    const EPS: f64 = 1e-12;
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - tri[0];
    let u = tv.dot(pv) * inv;
    if !(-EPS..=1.0 + EPS).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv;
    if v < -EPS || u + v > 1.0 + EPS {
        return None;
    }
    let t = e2.dot(qv) * inv;
    if !(t > t_min && t < t_max) {
        return None;
    }
    let mut n = e1.cross(e2).normalize();
    if n.dot(d) > 0.0 {
        n = -n;
    }
    Some((SurfaceHit { t, p: o + d * t, n }, u, v))
}

/// Procedural mountain profile in [0, 1] at `(x, y)` in feature units.
fn mountain(perlin: &Perlin, x: f64, y: f64) -> f64 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
    for o in 0..OCTAVES {
        // Offsets keep the octaves' lattice zeros from lining up at the origin.
        let off = 17.31 * o as f64 + 0.5;
        sum += amp * crate::util::rng::noise2(perlin, x * freq + off, y * freq - off);
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    (0.5 + sum / norm).clamp(0.0, 1.0)
}

/// Writes the heightfield as a Wavefront OBJ (z up, scene units), written to
/// a temporary file and renamed. Vertex `j * nx + i + 1` is sample (i, j);
/// faces are the two triangles of each cell in the order of
/// [`Heightfield::cell_triangles`], smoothing off. Coordinates are printed as
/// the shortest decimal that reads back to the same f32, so Blender's
/// importer gets exactly our vertices. Import in Blender with
/// `bpy.ops.wm.obj_import(filepath=..., forward_axis='Y', up_axis='Z')` (the
/// defaults assume a Y-up file and would rotate the mesh).
pub fn write_obj(path: impl AsRef<Path>, hf: &Heightfield) -> Result<(), RenderError> {
    let path = path.as_ref();
    let io = |e: std::io::Error| RenderError::Io { path: path.to_path_buf(), source: e };
    let mut tmp = crate::util::atomic_write::TempFile::create(path).map_err(|e| RenderError::Output(Box::new(e)))?;
    let result = (|| -> std::io::Result<()> {
        let mut w = std::io::BufWriter::new(tmp.file());
        let (nx, ny) = (hf.nx(), hf.ny());
        writeln!(w, "# aurora terrain: {nx} x {ny} height samples, z up, scene units (km)")?;
        writeln!(w, "# Blender: bpy.ops.wm.obj_import(filepath=..., forward_axis='Y', up_axis='Z')")?;
        writeln!(w, "o terrain")?;
        for j in 0..ny {
            for i in 0..nx {
                let v = hf.vertex(i, j);
                writeln!(w, "v {} {} {}", v.x as f32, v.y as f32, v.z as f32)?;
            }
        }
        writeln!(w, "s off")?;
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let a = j * nx + i + 1;
                let b = a + 1;
                let c = a + nx + 1;
                let d = a + nx;
                writeln!(w, "f {a} {b} {c}")?;
                writeln!(w, "f {a} {c} {d}")?;
            }
        }
        w.into_inner().map_err(|e| e.into_error())?.sync_all()
    })();
    result.map_err(io)?;
    tmp.commit().map_err(|e| RenderError::Output(Box::new(e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_height_under_a_point_is_where_a_vertical_ray_meets_the_mesh() {
        // Procedural mountains; at points inside cells (both triangles), on
        // the diagonal and on samples, the height is the hit of a ray
        // straight down from above the peaks (the mesh's own test).
        let t = Terrain { kind: TerrainKind::Heightfield, extent: [-20.0, -15.0, 25.0, 30.0], ..Terrain::default() };
        let h = Heightfield::from_terrain(&t, None).unwrap();
        for (x, y) in [(-10.0, 4.0), (3.3, -7.1), (h.xs[3], h.ys[5]), (0.5 * (h.xs[4] + h.xs[5]), 0.5 * (h.ys[4] + h.ys[5])), (24.9, 29.9)]
        {
            let z = h.height_at(x, y).unwrap();
            let hit = h.intersect(DVec3::new(x, y, h.zmax + 1.0), DVec3::NEG_Z, 0.0, f64::INFINITY).unwrap();
            // Both are f64 arithmetic on the same f32 vertices: rounding only.
            assert!((hit.p.z - z).abs() < 1e-9, "({x}, {y}): {z} vs {}", hit.p.z);
        }
        assert_eq!(h.height_at(-20.1, 0.0), None);
        let model = TerrainModel::Heightfield(Arc::new(h));
        let c = model.clearance(DVec3::new(-10.0, 4.0, -1.0)).unwrap();
        assert!(c.is_below() && c.point_km == -1.0);
        // On a round Earth the plane is the sphere: altitudes above it.
        let sphere =
            TerrainModel::on_earth(&Terrain { kind: TerrainKind::Plane, height: 0.3, ..Terrain::default() }, None, 6371.0).unwrap();
        let c = sphere.clearance(DVec3::new(100.0, 0.0, 0.5)).unwrap();
        assert!(
            (c.ground_km - 0.3).abs() < 1e-9 && (c.point_km - ((fmath::powi(6371.5f64, 2) + 1e4).sqrt() - 6371.0)).abs() < 1e-9,
            "{c:?}"
        );
        assert_eq!(TerrainModel::None.clearance(DVec3::ZERO), None);
    }

    #[test]
    fn sphere_hits_are_the_closed_form_ones() {
        let r = 6371.0;
        let c = DVec3::new(0.0, 0.0, -r);
        // Straight down from 10 km: the ground at t = 10.
        let h = intersect_sphere(c, r, DVec3::new(0.0, 0.0, 10.0), DVec3::new(0.0, 0.0, -1.0), 0.0, f64::INFINITY).unwrap();
        assert!((h.t - 10.0).abs() < 1e-9 && (h.n - DVec3::Z).length() < 1e-12);
        // From 2 m up, 1 degree down: the chord to the sphere,
        // t = (R + h) sin(a) - sqrt((R + h)^2 sin(a)^2 - (2 R h + h^2)).
        let (h0, a) = (0.002, 1f64.to_radians());
        let d = DVec3::new(0.0, fmath::cos(a), -fmath::sin(a));
        let hit = intersect_sphere(c, r, DVec3::new(0.0, 0.0, h0), d, 0.0, f64::INFINITY).unwrap();
        let rs = (r + h0) * fmath::sin(a);
        let want = rs - (rs * rs - (2.0 * r * h0 + h0 * h0)).sqrt();
        assert!((hit.t - want).abs() < 1e-9 * want.max(1.0), "{} vs {want}", hit.t);
        assert!(((hit.p - c).length() - r).abs() < 1e-9);
        // Horizontal from 2 m up: the ray rises above the sphere everywhere
        // (its lowest altitude is its start), no hit.
        assert!(intersect_sphere(c, r, DVec3::new(0.0, 0.0, h0), DVec3::Y, 0.0, f64::INFINITY).is_none());
        // The flat plane stays the plane.
        let t = Terrain { kind: TerrainKind::Plane, height: 0.5, ..Terrain::default() };
        assert_eq!(TerrainModel::on_earth(&t, None, 0.0).unwrap(), TerrainModel::Plane { height: 0.5 });
        assert_eq!(TerrainModel::on_earth(&t, None, r).unwrap(), TerrainModel::Sphere { centre: c, radius: r + 0.5 });
    }

    #[test]
    fn a_heightfield_on_the_sphere_sits_its_height_above_it() {
        let r = 6371.0;
        let hf = Heightfield::from_samples(vec![0.0, 100.0], vec![0.0, 50.0], vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        let on = hf.clone().on_sphere(r).unwrap();
        for k in 0..4 {
            let (x, y) = (on.xs[k % 2], on.ys[k / 2]);
            // Above the grid point, at altitude z over the sphere: to first
            // order the vertex sits d, not (R + z) sin(d / R), from the axis,
            // which lowers it by z (d / R)^2 (1.2 m for 4 km at 112 km); the
            // f32 heights add under 1e-6 km.
            let p = DVec3::new(x, y, on.z[k]);
            let alt = (p - DVec3::new(0.0, 0.0, -r)).length() - r;
            let theta = fmath::hypot(x, y) / r;
            assert!((alt - hf.z[k]).abs() <= 1.01 * hf.z[k] * theta * theta + 1e-6, "{k}: {alt} vs {}", hf.z[k]);
        }
        // The corner 111.8 km away drops (R + z) (1 - cos(d / R)) = 0.98 km.
        assert!((hf.z[3] - on.z[3] - (r + hf.z[3]) * (1.0 - fmath::cos(fmath::hypot(100f64, 50.0) / r))).abs() < 1e-5);
    }
}
