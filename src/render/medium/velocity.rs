//! The velocity grid `v` the renderer's motion blur reads
//! (`render.shutter_s`), as Cycles reads a volume's velocity grid: a sample
//! at shutter time tau (uniform over [-shutter / 2, shutter / 2]) reads the
//! density and emission at `p - v(p) tau` (first-order advection of the
//! lookups, `crate::render::march::radiance_advected`). `v` is trilinear
//! like every grid, 0 where inactive, in world units per second (km/s for
//! the bake's files, `crate::pipeline::bake::velocity` upstream).

use crate::grid::Grid;
use crate::render::settings::RenderError;
use glam::DVec3;

/// A velocity grid checked for the renderer: finite components, and its
/// largest speed (how far a lookup can move, per second of shutter).
#[derive(Clone, Debug)]
pub struct Velocity {
    grid: Grid<[f32; 3]>,
    max_speed: f64,
}

impl Velocity {
    /// Refuses a non-finite component, naming the grid and the voxel.
    pub fn new(grid: Grid<[f32; 3]>) -> Result<Velocity, RenderError> {
        if let Some((ijk, v)) = grid.first_non_finite() {
            return Err(RenderError::Grid { grid: grid.name.clone(), message: format!("velocity {v:?} at voxel {ijk} is not finite") });
        }
        let max_speed = grid.iter_active().map(|(_, v)| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64).length()).fold(0.0, f64::max);
        Ok(Velocity { grid, max_speed })
    }

    /// The velocity at a world point (trilinear, 0 outside the active voxels).
    #[inline]
    pub fn at(&self, p: DVec3) -> DVec3 {
        let v = self.grid.sample_world(p);
        DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
    }

    /// The largest speed of any voxel, world units per second.
    pub fn max_speed(&self) -> f64 {
        self.max_speed
    }
}
