//! The reference raymarcher: the ground truth users compare Cycles and other
//! renderers against. It reads grids only (never the bake).
//!
//! Model (emission-absorption, no scattering), per primary ray:
//! `L = int_0^d T(0,s) e(s) ds + T(0,d) L_behind`, `T = exp(-int sigma_t)`,
//! with `sigma_t = density_scale * density` and `e = emission_scale * emission`
//! sampled as Cycles samples the same VDB: voxel (i,j,k) centred at index point
//! (i,j,k), trilinear, inactive voxels 0 (docs/guide.md, "How Cycles reads the VDB").
//! `L_behind` is the background radiance, or, where the ray hits the terrain,
//! `albedo / pi * E` with `E` the irradiance the volume's emission delivers
//! through the volume's transmittance, estimated with emissive shadow rays
//! (`shadow.rs`; the 2014 report's `L = T * Li + Lvi`). **Background
//! radiance does not light the terrain**: it is only what camera rays see
//! behind everything.
//!
//! **The air** (`[sky] extinction`, `crate::physics::air_extinction`): the volume's
//! emission lies above the lower atmosphere, so `L` is multiplied per channel
//! by the air's transmittance towards the ray's direction, the terrain's
//! light by the transmittance of its straight path to the camera, and the
//! stars like the emission; the background radiance and the sky image are
//! not dimmed (they are the sky as seen).
//!
//! Stages (each a function of plain data):
//! `settings.rs` (what is asked, [`RenderError`]) -> `prepared.rs` (built
//! once per scene, camera and medium: [`Prepared`]) with `crate::geometry::camera`
//! (rays), `medium/` (ghosted dual leaves + tree), `terrain.rs`, `sky.rs`
//! and the emission sampler of `shadow.rs` -> `integrator.rs` (the pixel
//! loop, tiles; `adaptive.rs` shares the samples by pixel variance), its
//! sample positions from `sampler.rs` -> per ray `dda.rs` (hierarchical
//! DDA: occupied leaves, then dual cells) -> `segment.rs` (exact optical
//! depth, Gauss-Legendre emission per cell) -> `march.rs` (integrators,
//! one walker for primary and shadow rays) -> `shadow.rs` (terrain
//! irradiance) -> `film.rs` (EXR / PNG).
//!
//! Pixels: row 0 at the top. With `spp = 1` a pixel is sampled at its centre;
//! with more samples the pixel value is the average over its square (Cycles'
//! BOX filter), at stratified antithetic positions ([`pixel_position`]):
//! `spp / 2` points of a digitally shifted Sobol (0, 2)-sequence in one half
//! of the pixel, each paired with its reflection through the pixel centre
//! `(x, y) -> (1 - x, 1 - y)` in the other (an odd `spp` ends with one
//! unpaired sample). Every position is uniform in the pixel, so the mean of
//! the samples is an unbiased estimate of the pixel mean. If the radiance is
//! linear across the pixel, `L(c + u) = L(c) + g.u`, each pair sums to
//! `2 L(c)`, the exact pixel mean, whatever the shift: the estimator is
//! exact on linear fields (the first-order antithetic variate, Hammersley &
//! Morton 1956), and on a smooth field its error is second order in the
//! pixel size. At every power of two the set is stratified (4 samples: one
//! per quadrant; 16: one per cell of a 4 x 4 grid's worth of boxes): on
//! sub-pixel streaks the error falls about as `spp^-1` instead of
//! `spp^-1/2`, as Cycles' does. Each pixel's random
//! stream is seeded from `(seed, pixel index)`, so the image does not depend
//! on the thread count. Output alpha is `1 - T` along the primary ray up to the
//! terrain or infinity (volume coverage); RGB already contains the terrain or

// `!(x > 0.0)` is used on purpose throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Loops over the three colour channels index several arrays at once.
#![allow(clippy::needless_range_loop)]

pub use crate::geometry::camera;
pub mod adaptive;
pub mod agx;
pub mod dda;
pub mod grids;
pub mod image_file;
pub mod integrator;
pub mod march;
pub mod medium;
pub mod prepared;
pub mod sampler;
pub mod segment;
pub mod settings;
pub mod shadow;
pub mod sky;
pub mod terrain;

pub use crate::geometry::camera::{CameraModel, Ray};
pub use adaptive::{render_adaptive, render_adaptive_prepared, ADAPTIVE_FLOOR, ADAPTIVE_MIN_SPP};
pub use integrator::{render, render_prepared, Image, RenderStats};
pub use march::{optical_depth_along_ray, radiance_along_ray, RayIntegral};
pub use medium::Medium;
pub use prepared::Prepared;
pub use sampler::{pixel_position, pixel_rng, sobol2};
pub use settings::{Integration, RenderError, RenderSettings, Volume};
pub use terrain::{write_obj, Heightfield, TerrainModel};
