//! Frames and projections: the round Earth's local frame and the camera.

pub mod camera;
pub mod earth;
