//! Frames and projections: the round Earth's local frame and the camera.

pub mod astronomy;
pub mod camera;
pub mod earth;
