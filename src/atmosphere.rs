//! atmosphere (to be written)
