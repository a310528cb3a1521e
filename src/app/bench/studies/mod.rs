//! The studies, one lever each, every one a method on the harness's
//! [`crate::app::bench::harness::Bench`] returning a
//! [`crate::app::bench::harness::Study`]: photon count and gather method
//! ([`photon_count`]), gather radius, voxel size, primary-ray integration,
//! pruning, storage (bytes against picture error), shadow rays and animation
//! flicker.

pub mod flicker;
pub mod gather_radius;
pub mod photon_count;
pub mod primary_rays;
pub mod pruning;
pub mod shadow_rays;
pub mod storage;
pub mod voxel_size;
