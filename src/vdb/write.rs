//! VDB writer (to be written)
