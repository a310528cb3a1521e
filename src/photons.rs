//! photons (to be written)
