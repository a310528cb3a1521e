//! Index space to world space: OpenVDB's `UniformScaleTranslateMap`, a
//! voxel size and a translation, voxel centres at integer coordinates.

use glam::DVec3;

/// Index-to-world map: uniform scale then translation (OpenVDB
/// `UniformScaleTranslateMap`): `world = voxel_size * ijk + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub voxel_size: f64,
    pub translation: DVec3,
}

impl Transform {
    pub fn new(voxel_size: f64, translation: DVec3) -> Self {
        Self { voxel_size, translation }
    }
    #[inline]
    pub fn index_to_world(&self, ijk: DVec3) -> DVec3 {
        ijk * self.voxel_size + self.translation
    }
    #[inline]
    pub fn world_to_index(&self, p: DVec3) -> DVec3 {
        (p - self.translation) / self.voxel_size
    }
}
