//! bake (to be written)
