//! The storage study of `aurora bench`: bytes per frame against picture
//! error, one curve per lever (see [`super::sweeps`] for the harness).
//!
//! The reference is the scene baked without pruning and written at full
//! precision, without the Cycles shell, in one grid per field: the most
//! faithful file the bake can write. Each lever writes the same bake another
//! way, the file is read back (so half-float rounding is in the picture),
//! the high column is added back to its fine grid as a renderer does
//! ([`crate::grid::high_column::merge`]), and the picture is compared with the
//! reference's: mean relative luminance error over the pixels above 1 % of
//! the peak, the same metric as the pruning study, with exact integration
//! (no step jitter, so nothing but the fields differ).
//!
//! | lever | swept | file |
//! |---|---|---|
//! | half floats | none, `emission`, both grids | unpruned, every bit |
//! | pruning | `grid.prune` budget | half floats, every bit |
//! | mantissa bits | `grid.mantissa_bits` | half floats, the scene's pruning |
//! | high column | `grid.high_above_km` (factor 2) | half floats, the scene's pruning and bits |
//! | Cycles shell | the scene's settings with `grid.cycles_shell` | as the bake writes it |
//!
//! Every file is compressed as the bake compresses (`grid.compression`,
//! libdeflate for ZIP).
//!
//! Pictures are point-sampled (one sample per pixel, exact integration), or
//! with `aurora bench --storage` rendered as the scene renders them (its
//! spp and integration: a pixel is the mean over its area, as a viewer sees
//! it, and fine-scale differences of the field average out).
//!
//! Pruning follows the camera, so each view is its own study: the scene's
//! camera, and a dome master (a 180-degree fisheye looking up from the
//! scene's camera position). The x axis of the chart is the file's size in
//! MB ([`SIZE_STAGE`], in [`CostUnit::Megabytes`]).

use crate::app::bench::harness::{Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::image_rel_error_masked;
use crate::geometry::earth::Earth;
use crate::grid::high_column::{self, Column};
use crate::grid::Grid;
use crate::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
use crate::pipeline::bake;
use crate::render::{Image, RenderError, RenderSettings, Volume};
use crate::scene::{Camera, Projection, Scene, TerrainKind};
use crate::util::progress::NoProgress;

/// The stage name of the storage studies: their measurements' `seconds`
/// is the file's size in MB, and the chart says so.
pub const SIZE_STAGE: &str = "file size";

/// Which camera a storage study prunes for and renders through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// The scene's own camera and image size (or the plan's volume image
    /// in a quick run).
    Scene,
    /// A dome master: 180-degree fisheye looking up from the scene
    /// camera's position.
    Dome,
}

impl View {
    fn name(self) -> &'static str {
        match self {
            View::Scene => "storage (scene camera)",
            View::Dome => "storage (dome master)",
        }
    }
}

/// The dome master's camera: at the scene camera's position, looking at
/// the zenith, with the scene's +y up in the picture.
pub fn dome_camera(scene: &Scene) -> Camera {
    let p = scene.camera.position;
    Camera {
        position: p,
        look_at: [p[0], p[1], p[2] + 10.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Fisheye,
        fov_deg: 180.0,
        ortho_height: 1.0,
    }
}

impl<'a> Bench<'a> {
    /// The storage study for `view` (module doc), on the bench's scene
    /// with `image` pixels.
    pub fn storage_study(&self, view: View, image: [usize; 2]) -> Result<Study, SweepError> {
        let name = view.name();
        let metric = "mean relative luminance error, pixels > 1% of peak";
        let mut unpruned = self.scene.clone();
        unpruned.grid.prune = 0.0;
        unpruned.grid.cycles_shell = false;
        let base = bake::bake(&unpruned, &NoProgress)?;
        let peak = base.stats.peak_luminance;
        let earth = Earth::new(self.scene.earth.radius_km);
        let mut s = RenderSettings::from_scene(&self.scene);
        if view == View::Dome {
            s.camera = dome_camera(&self.scene);
        }
        (s.render.width, s.render.height) = (image[0], image[1]);
        s.terrain.kind = TerrainKind::None;
        s.background.radiance = [0.0; 3];
        s.background.stars = false;
        // Point-sampled (one sample per pixel, exact integration: no step
        // jitter, so nothing but the fields differ), or the picture as the
        // scene renders it (its spp and integration: each pixel the mean over
        // its area, as a viewer sees it).
        if !self.plan.storage_as_rendered {
            s.render.spp = 1;
            s.integration = crate::render::Integration::Exact;
        }
        let sampling = if self.plan.storage_as_rendered {
            format!("spp {}, the scene's integration", s.render.spp)
        } else {
            "spp 1, exact integration".to_string()
        };
        let camera = crate::geometry::camera::CameraModel::new(&s.camera, s.render.width, s.render.height).map_err(RenderError::from)?;
        // The bake's options with `half` grids and `bits` mantissa bits.
        let options = |half: &[&str], bits: u32| WriteOptions {
            half: half.iter().map(|h| h.to_string()).collect(),
            mantissa_bits: ["density", "emission"].map(|g| (g.to_string(), bits)).to_vec(),
            ..crate::io::bake_folder::write_options(&self.scene)
        };
        let density = |e: &Grid<[f32; 3]>| bake::density::density_grid(e, &self.scene.grid, peak, &earth);
        // Writes `e` (and its density) as one grid each, or split at a high
        // column, with half floats or not, `bits` mantissa bits, optionally
        // with the shell.
        let write = |e: &Grid<[f32; 3]>, half: &[&str], bits: u32, col: Option<Column>, shell: bool| -> Result<Vec<u8>, SweepError> {
            let mut d = density(e);
            let mut e = e.clone();
            if shell {
                e.dilate_active();
                d.dilate_active();
            }
            match col {
                None => write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &options(half, bits)),
                Some(c) => {
                    let (df, dh) = high_column::split(&d, &c, &earth);
                    let (ef, eh) = high_column::split(&e, &c, &earth);
                    let opts = crate::io::bake_folder::with_high_column(options(half, bits));
                    write_vdb_bytes(&[GridRef::Float(&df), GridRef::Vec3(&ef), GridRef::Float(&dh), GridRef::Vec3(&eh)], &opts)
                }
            }
            .map_err(|e| SweepError::Storage(e.to_string()))
        };
        let render = |w: &[u8]| -> Result<Image, SweepError> {
            let f = crate::io::vdb::read::read_vdb_bytes(w).map_err(|e| SweepError::Storage(e.to_string()))?;
            let grid = |n: &str| f.float(n).cloned();
            let vgrid = |n: &str| f.vec3(n).cloned();
            let merged = |fine: Option<Grid<f32>>, high: Option<Grid<f32>>| match (fine, high) {
                (Some(a), Some(b)) => high_column::merge(&a, &b).map(Some).map_err(|e| SweepError::Storage(e.to_string())),
                (a, _) => Ok(a),
            };
            let d = merged(grid("density"), grid("density_high"))?;
            let e = match (vgrid("emission"), vgrid("emission_high")) {
                (Some(a), Some(b)) => Some(high_column::merge(&a, &b).map_err(|e| SweepError::Storage(e.to_string()))?),
                (a, _) => a,
            };
            let (img, _) = self.render_timed(&s, &Volume { density: d.as_ref(), emission: e.as_ref() })?;
            Ok(img)
        };
        let all_bits = crate::io::vdb::mantissa::FLOAT_MANTISSA_BITS;
        let reference_file = write(&base.emission, &[], all_bits, None, false)?;
        let reference = render(&reference_file)?;
        let all = vec![true; reference.pixels.len()];
        let mb = |w: &[u8]| w.len() as f64 / 1e6;
        let mut ms = Vec::new();
        let mut notes = vec![format!(
            "Reference: unpruned, full floats, no shell, one grid per field: {} bytes, {} voxels in {} leaves. Per file: bytes, flux ratio of the picture.",
            reference_file.len(),
            base.emission.active_voxel_count(),
            base.emission.leaf_count()
        )];
        let mut measure = |method: &str, param_name: &str, param: f64, w: &[u8], scene_setting: bool| -> Result<(), SweepError> {
            let img = render(w)?;
            let (err, flux) = image_rel_error_masked(&img.pixels, &reference.pixels, &all, 0.01);
            notes.push(format!("{method}, {param_name} = {param}: {} bytes, error {err:.5}, flux {flux:.5}", w.len()));
            ms.push(self.measure(
                &Series { study: name, method, param_name, stage: SIZE_STAGE, metric },
                param,
                Cost::megabytes(mb(w)),
                err,
                scene_setting,
            ));
            Ok(())
        };
        let g = &self.scene.grid;
        let scene_half: Vec<&str> =
            [(g.half_density, "density"), (g.half_emission, "emission")].into_iter().filter(|x| x.0).map(|x| x.1).collect();
        measure("half floats", "half grids", 0.0, &reference_file, false)?;
        if !self.plan.storage_as_rendered {
            measure("half floats", "half grids", 1.0, &write(&base.emission, &["emission"], all_bits, None, false)?, false)?;
        }
        measure("half floats", "half grids", 2.0, &write(&base.emission, &["density", "emission"], all_bits, None, false)?, false)?;
        let pruned = |b: f64| {
            let mut e = base.emission.clone();
            if b > 0.0 {
                crate::pipeline::prune::prune(&mut e, &camera, b);
            }
            e
        };
        for &b in &self.plan.prune_budgets {
            measure("pruning (half floats)", "budget", b, &write(&pruned(b), &["density", "emission"], all_bits, None, false)?, false)?;
        }
        let scene_pruned = pruned(g.prune);
        let col =
            (g.high_voxel_factor > 1).then(|| Column::new(g.high_above_km, g.high_voxel_factor as i32, base.emission.transform.voxel_size));
        for &bits in &self.plan.storage_mantissa_bits {
            let on = bits == g.mantissa_bits && !g.cycles_shell && scene_half.len() == 2;
            let method = format!("mantissa bits (half floats, pruned {}{})", g.prune, if col.is_some() { ", high column" } else { "" });
            measure(&method, "bits", bits as f64, &write(&scene_pruned, &["density", "emission"], bits, col, false)?, on)?;
        }
        let f = g.high_voxel_factor.max(2) as i32;
        for &h in &self.plan.storage_high_km {
            let col = Column::new(h, f, base.emission.transform.voxel_size);
            let on = g.high_voxel_factor > 1 && h == g.high_above_km && !g.cycles_shell && scene_half.len() == 2;
            measure(
                &format!("high column x{f} (half floats, {} mantissa bits, pruned {})", g.mantissa_bits, g.prune),
                "above km",
                h,
                &write(&scene_pruned, &["density", "emission"], g.mantissa_bits, Some(col), false)?,
                on,
            )?;
        }
        for shell in [false, true] {
            let on = shell == g.cycles_shell;
            if !shell && self.plan.storage_mantissa_bits.contains(&g.mantissa_bits) {
                continue; // the scene's own file, measured with the bits
            }
            measure(
                "Cycles shell (scene's other settings)",
                "shell",
                shell as u8 as f64,
                &write(&scene_pruned, &scene_half, g.mantissa_bits, col, shell)?,
                on,
            )?;
        }
        Ok(Study {
            name: name.into(),
            stage: SIZE_STAGE.into(),
            metric: metric.into(),
            reference: format!(
                "the unpruned full-float file's image ({}x{} px, {sampling}, {})",
                image[0],
                image[1],
                if view == View::Dome { "180-degree fisheye up" } else { "the scene's camera" }
            ),
            reference_cost: mb(&reference_file),
            unit: CostUnit::Megabytes,
            expected_trend: vec![],
            notes,
            measurements: ms,
        })
    }
}
