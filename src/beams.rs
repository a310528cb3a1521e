//! beams (to be written)
