//! Frames and projections: the round Earth's local frame, the camera, and
//! an all-sky imager's skymap of a fisheye frame.

pub mod astronomy;
pub mod camera;
pub mod earth;
pub mod imager_skymap;
