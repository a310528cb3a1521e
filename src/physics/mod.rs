//! The model, as functions of altitude, energy and ionization rate: the
//! neutral atmosphere, the geomagnetic field, the electrons' energy
//! deposition, the chemistry that turns ionization into line emission, the
//! emission lines themselves, the air's extinction of their light, the
//! airglow (the night sky's own light, drawn by the renderer only), and the
//! night sky's other lights: the stars of the Hipparcos catalogue and the
//! Moon's.

pub mod air_extinction;
pub mod airglow;
pub mod atmosphere;
pub mod auroral_oval;
pub mod chemistry;
pub mod data_files;
pub mod deposition;
pub mod emission;
pub mod geomagnetic_field;
pub mod igrf;
pub mod magnetic_coordinates;
pub mod night_sky;
pub mod site_field;
