//! VDB reader (to be written)
