//! footprint (to be written)
