//! The grid a footprint is simulated on, before it is bent and placed.

/// The grid a footprint is simulated on: `nx` x `ny` cells over a box of
/// `length` x `width` km (u along the curtain, v across; cell `j * nx + i`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cells {
    pub nx: usize,
    pub ny: usize,
    pub length: f64,
    pub width: f64,
}
