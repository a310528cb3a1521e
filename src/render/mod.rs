//! Reference raymarcher (to be written)
