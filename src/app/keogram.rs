//! Keograms: the brightness along the magnetic meridian through the
//! camera, one column per frame of a baked sequence, time left to right,
//! the way all-sky camera networks summarise a night (Eather, Mende &
//! Judge 1976, "Plasma injection at synchronous orbit and spatial and
//! temporal auroral morphology", J. Geophys. Res. 81, 2805).
//!
//! Rows ([`meridian`]): every [`ROW_DEG`] degrees of scan angle from the
//! magnetic north horizon (row 0, the top) through the zenith to the
//! magnetic south horizon, seen from the camera's position. Magnetic north
//! is the azimuth of the field's horizontal part: `beams.b_declination_deg`,
//! or with `earth.magnetic_pole` the dipole's pole azimuth at the camera
//! (`crate::physics::geomagnetic_field`), or with a `[site]` (`field =
//! "igrf"`) IGRF-14's declination at the camera (`crate::physics::site_field`). Row `i` at scan angle `s = i ROW_DEG`
//! looks at elevation `s` toward magnetic north while `s <= 90`, and at
//! elevation `180 - s` toward magnetic south after.
//!
//! Values ([`trace_frame`]): only these rays are traced, through the
//! frame's float grid (a `line_*` grid in rayleigh per km gives the line's
//! column brightness in rayleigh, `4 pi I / 1e6`) and its `density`, up to
//! the terrain, dimmed by the air's transmittance of that line as
//! `[sky] extinction` says (`crate::physics::air_extinction`): the same
//! integral as a pixel of `aurora render --grid` at its centre.
//!
//! Frame `N` is the scene at `animation.time_s + (N - 1) / fps`
//! (`crate::pipeline::motion::frame_time`).

use crate::app::vdb_for_render::{read_line_medium, RenderReadError};
use crate::geometry::earth::Earth;
use crate::io::vdb::read::{read_vdb_for_render, VdbReadError};
use crate::physics::geomagnetic_field::dipole_angles_deg;
use crate::render::image::{Image, RenderStats};
use crate::render::{radiance_along_ray, Integration, Prepared, RenderError, RenderSettings, Volume};
use crate::scene::Scene;
use crate::util::fmath;
use crate::util::progress::Progress;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Rows are this many degrees of scan angle apart.
pub const ROW_DEG: f64 = 0.5;

/// One row of the keogram: a direction in the magnetic meridian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeridianRow {
    /// Degrees from the magnetic north horizon through the zenith (0 to 180).
    pub scan_deg: f64,
    /// Elevation above the horizon, degrees.
    pub elevation_deg: f64,
    /// Azimuth of the ray's horizontal part, degrees from north toward east.
    pub azimuth_deg: f64,
    /// Unit direction in the scene frame.
    pub dir: DVec3,
}

/// Why a keogram could not be made; each variant names the file or grid.
#[derive(Debug, thiserror::Error)]
pub enum KeogramError {
    /// A frame's VDB is not in the sequence folder.
    #[error("frame {frame}: {} is missing (bake the frames first: aurora bake SCENE --frames SPEC --out DIR)", path.display())]
    MissingFrame { frame: i64, path: PathBuf },
    /// The frame's file holds no float grid of that name.
    #[error("--grid {name}: {} has no float grid of that name (float grids: {there}){}", path.display(), rebake_hint(name))]
    NoGrid { name: String, path: PathBuf, there: String },
    #[error(transparent)]
    Read(#[from] VdbReadError),
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// What to add to the bake for a line's grid `line_NAME`: the exact
/// `--set`, and `--rebake` to bake over frames already there.
pub fn rebake_hint(grid: &str) -> String {
    match grid.strip_prefix("line_").filter(|l| crate::scene::validation::LINE_KEYS.contains(l)) {
        Some(line) => format!(
            "; a line's grid is baked when asked for: bake again with --set 'grid.lines=[\"{line}\"]' (and --rebake to replace frames already baked)"
        ),
        None => String::new(),
    }
}

impl KeogramError {
    /// The inputs (frames, grid name, files) are the user's; a render
    /// failure is as the renderer says.
    pub fn is_input(&self) -> bool {
        match self {
            KeogramError::MissingFrame { .. } | KeogramError::NoGrid { .. } => true,
            KeogramError::Read(e) => e.is_input(),
            KeogramError::Render(e) => e.is_input(),
        }
    }
}

/// The azimuth of magnetic north at the camera, degrees from north toward
/// east (module doc).
pub fn magnetic_north_deg(scene: &Scene) -> f64 {
    let earth = Earth::new(scene.earth.radius_km);
    if let Some(site) = crate::physics::site_field::SiteField::of_scene(scene) {
        let g = earth.to_curved(DVec3::from_array(scene.camera.position));
        return site.angles_deg([g.x, g.y], g.z).1;
    }
    match scene.earth.magnetic_pole {
        Some(pole) => {
            let g = earth.to_curved(DVec3::from_array(scene.camera.position));
            dipole_angles_deg(&earth, pole, [g.x, g.y]).1
        }
        None => scene.beams.b_declination_deg,
    }
}

/// The keogram's rows for the scene's camera (module doc), north horizon first.
pub fn meridian(scene: &Scene) -> Vec<MeridianRow> {
    let earth = Earth::new(scene.earth.radius_km);
    let g = earth.to_curved(DVec3::from_array(scene.camera.position));
    let [east, north, up] = earth.local_frame(g.x, g.y);
    let az = magnetic_north_deg(scene);
    let n = (180.0 / ROW_DEG).round() as usize + 1;
    (0..n)
        .map(|i| {
            let scan_deg = i as f64 * ROW_DEG;
            let (elevation_deg, azimuth_deg) = if scan_deg <= 90.0 { (scan_deg, az) } else { (180.0 - scan_deg, az + 180.0) };
            let azimuth_deg = azimuth_deg.rem_euclid(360.0);
            let (sa, ca) = fmath::sin_cos(azimuth_deg.to_radians());
            let (se, ce) = fmath::sin_cos(elevation_deg.to_radians());
            let dir = ((east * sa + north * ca) * ce + up * se).normalize();
            MeridianRow { scan_deg, elevation_deg, azimuth_deg, dir }
        })
        .collect()
}

/// A keogram: `values[row * frames.len() + column]`, in the grid's units
/// integrated along the ray (rayleigh for a `line_*` grid).
#[derive(Clone, Debug, PartialEq)]
pub struct Keogram {
    pub grid: String,
    pub rows: Vec<MeridianRow>,
    pub frames: Vec<i64>,
    /// Each frame's time, s.
    pub times_s: Vec<f64>,
    pub values: Vec<f32>,
    /// Whether the air's extinction is in the values.
    pub air: bool,
}

impl Keogram {
    /// The keogram as a one-channel image: a column per frame, a row per
    /// [`MeridianRow`] (north at the top).
    pub fn image(&self) -> Image {
        let pixels = self.values.iter().map(|&v| [v, v, v, 1.0]).collect();
        Image { width: self.frames.len(), height: self.rows.len(), pixels, stats: RenderStats::default() }
    }

    /// The keogram as CSV: `#` lines (grid, units, air, rows), a header
    /// `scan_deg,elevation_deg,azimuth_deg` then each frame's time in
    /// seconds, then one line per row (module doc).
    pub fn to_csv(&self, units: &str) -> String {
        let mut s = format!(
            "# aurora keogram of {} along the magnetic meridian; units: {units}; air extinction {}\n\
# rows every {ROW_DEG} degrees of scan angle from the magnetic north horizon (scan_deg 0) through the zenith to the south \
horizon (180); columns after the third: frames {}, headed by their times in seconds\n",
            self.grid,
            if self.air { "applied" } else { "not applied" },
            self.frames.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(" ")
        );
        s.push_str("scan_deg,elevation_deg,azimuth_deg");
        for t in &self.times_s {
            s.push_str(&format!(",{t}"));
        }
        s.push('\n');
        let n = self.frames.len();
        for (i, r) in self.rows.iter().enumerate() {
            s.push_str(&format!("{:.1},{:.1},{:.3}", r.scan_deg, r.elevation_deg, r.azimuth_deg));
            for v in &self.values[i * n..(i + 1) * n] {
                s.push_str(&format!(",{v:.6e}"));
            }
            s.push('\n');
        }
        s
    }
}

/// The VDB of each frame, refused as a whole if any is missing.
pub fn frame_files(seq: &Path, frames: &[i64]) -> Result<Vec<PathBuf>, KeogramError> {
    frames
        .iter()
        .map(|&f| {
            let (vdb, _) = crate::farm::frame_files::frame_paths(seq, f);
            if vdb.is_file() {
                Ok(vdb)
            } else {
                Err(KeogramError::MissingFrame { frame: f, path: vdb })
            }
        })
        .collect()
}

/// The renderer's settings for a keogram: the scene's, with the line of a
/// `line_*` grid (its own optical depth in the air) and no sky behind.
fn settings_for(scene: &Scene, grid: &str) -> RenderSettings {
    let mut s = RenderSettings::from_scene(scene);
    s.background.radiance = [0.0; 3];
    s.background.image = None;
    s.background.stars = false;
    s.line = grid.strip_prefix("line_").and_then(crate::physics::emission::line_table::line_index);
    s
}

/// One frame's column: the grid `grid` of `vdb` (and its density) traced
/// along every row's ray from the camera (module doc).
pub fn trace_frame(scene: &Scene, vdb: &Path, grid: &str, rows: &[MeridianRow]) -> Result<Vec<f32>, KeogramError> {
    let settings = settings_for(scene, grid);
    let (ds, es) = (settings.volume.density_scale, settings.volume.emission_scale);
    // The medium straight from the file's records where that path applies
    // (the same medium as from the grids read whole, in less time and
    // memory), else from the grids.
    let read = match read_line_medium(vdb, grid, ds, es) {
        Ok(read) => read,
        Err(RenderReadError::Read(e)) => return Err(e.into()),
        Err(RenderReadError::Render { source, .. }) => return Err(source.into()),
        // The grid path does not choose grids by type: it says what it finds.
        Err(RenderReadError::Grids { .. }) => None,
    };
    let medium = match read {
        Some(read) => read.medium,
        None => {
            let file = read_vdb_for_render(vdb)?;
            let Some(g) = file.float(grid) else {
                let there: Vec<&str> = file.float_grids.iter().map(|g| g.name.as_str()).filter(|n| *n != "density").collect();
                let there = if there.is_empty() { "none".to_string() } else { there.join(", ") };
                return Err(KeogramError::NoGrid { name: grid.to_string(), path: vdb.to_path_buf(), there });
            };
            let emission = crate::render::grids::grey(g);
            let volume = Volume { density: file.float("density"), emission: Some(&emission) };
            crate::render::medium::Medium::new(volume.density, volume.emission, ds, es)?
        }
    };
    // The medium alone, the emission sampler left to be built when a shadow
    // ray needs it (`Prepared::sampler`): a keogram traces none.
    let prepared = Prepared::with_medium(&settings, medium, None)?;
    let origin = DVec3::from_array(scene.camera.position);
    Ok(rows
        .iter()
        .map(|r| {
            let t_end = prepared.terrain().intersect(origin, r.dir, 0.0, f64::INFINITY).map_or(f64::INFINITY, |h| h.t);
            let l = radiance_along_ray(prepared.medium(), origin, r.dir, t_end, Integration::Exact, 0.5).l[0];
            let t = prepared.air().map_or(1.0, |a| a.towards(r.dir)[0]);
            (l * t) as f32
        })
        .collect())
}

/// The keogram of `frames` of the sequence folder `seq` (every frame's VDB
/// checked first), one frame at a time, reporting one unit per frame.
pub fn keogram(scene: &Scene, seq: &Path, frames: &[i64], grid: &str, progress: &dyn Progress) -> Result<Keogram, KeogramError> {
    let files = frame_files(seq, frames)?;
    let rows = meridian(scene);
    let mut columns = Vec::with_capacity(frames.len());
    progress.start("keogram", frames.len() as u64);
    for vdb in &files {
        columns.push(trace_frame(scene, vdb, grid, &rows)?);
        progress.inc(1);
    }
    progress.finish();
    let n = frames.len();
    let mut values = vec![0.0f32; rows.len() * n];
    for (j, c) in columns.iter().enumerate() {
        for (i, v) in c.iter().enumerate() {
            values[i * n + j] = *v;
        }
    }
    let times_s = frames.iter().map(|&f| crate::pipeline::motion::frame_time(&scene.animation, f)).collect();
    Ok(Keogram { grid: grid.to_string(), rows, frames: frames.to_vec(), times_s, values, air: scene.sky.extinction })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn over_a_site_magnetic_north_is_igrfs_declination_at_the_camera() {
        // Tromso, 2026-12-18: IGRF-14's declination about 11 degrees east
        // (`crate::physics::site_field`'s test), not the keys' 0.
        let s = crate::scene::presets::by_name("tromso").unwrap();
        let north = magnetic_north_deg(&s);
        assert!((10.0..12.5).contains(&north), "{north}");
        let mut own = s.clone();
        own.site.as_mut().unwrap().field = crate::scene::SiteField::Scene;
        assert_eq!(magnetic_north_deg(&own), s.beams.b_declination_deg);
    }

    #[test]
    fn meridian_runs_from_the_north_horizon_through_the_zenith_to_the_south() {
        let mut s = Scene::default();
        s.earth.radius_km = 0.0;
        s.earth.magnetic_pole = None;
        s.beams.b_declination_deg = 0.0;
        let rows = meridian(&s);
        assert_eq!(rows.len(), 361);
        assert!((rows[0].dir - DVec3::Y).length() < 1e-12, "{:?}", rows[0]);
        assert!((rows[180].dir - DVec3::Z).length() < 1e-12);
        assert!((rows[360].dir + DVec3::Y).length() < 1e-12);
        assert!((rows[20].elevation_deg - 10.0).abs() < 1e-12 && (rows[340].elevation_deg - 10.0).abs() < 1e-12);
        // A declination turns the meridian: 90 degrees east puts north at +x.
        s.beams.b_declination_deg = 90.0;
        let rows = meridian(&s);
        assert!((rows[0].dir - DVec3::X).length() < 1e-12);
        assert!(rows.iter().all(|r| r.dir.y.abs() < 1e-12));
        // On the round Earth away from the origin the rows turn with the
        // local vertical: the middle row is the camera's zenith, the ends
        // lie on its horizon.
        s.earth.radius_km = crate::geometry::earth::MEAN_RADIUS_KM;
        s.camera.position = [300.0, -500.0, 1.0];
        let up = Earth::new(s.earth.radius_km).local_up(DVec3::from_array(s.camera.position));
        let rows = meridian(&s);
        assert!((rows[180].dir - up).length() < 1e-9);
        assert!(rows[0].dir.dot(up).abs() < 1e-9 && rows[360].dir.dot(up).abs() < 1e-9);
        assert!((rows[0].dir + rows[360].dir).length() < 1e-9);
    }

    #[test]
    fn csv_has_a_row_per_direction_and_a_column_per_frame() {
        let mut s = Scene::default();
        s.earth.radius_km = 0.0;
        let rows = meridian(&s);
        let k = Keogram {
            grid: "line_5577".into(),
            values: (0..rows.len() * 2).map(|i| i as f32).collect(),
            rows,
            frames: vec![3, 4],
            times_s: vec![0.5, 1.0],
            air: true,
        };
        let csv = k.to_csv("R");
        let lines: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(lines[0], "scan_deg,elevation_deg,azimuth_deg,0.5,1");
        assert_eq!(lines.len(), 362);
        assert!(lines[2].starts_with("0.5,0.5,") && lines[2].ends_with(",2.000000e0,3.000000e0"), "{}", lines[2]);
        let img = k.image();
        assert_eq!((img.width, img.height), (2, 361));
        assert_eq!(img.pixels[3][0], 3.0);
    }
}
