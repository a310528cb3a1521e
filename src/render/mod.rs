//! The reference raymarcher: the ground truth users compare Cycles and other
//! renderers against. It reads grids only (never the bake).
//!
//! Model (emission-absorption, no scattering), per primary ray:
//! `L = int_0^d T(0,s) e(s) ds + T(0,d) L_behind`, `T = exp(-int sigma_t)`,
//! with `sigma_t = density_scale * density` and `e = emission_scale * emission`
//! sampled as Cycles samples the same VDB: voxel (i,j,k) centred at index point
//! (i,j,k), trilinear, inactive voxels 0 (docs/guide.md, "How Cycles reads the VDB").
//! `L_behind` is the background radiance plus the sky (`sky.rs`: image and
//! stars, drawn as a reference lens draws them by `star_psf.rs`) and the airglow (`airglow.rs`, dimmed by the air), or, where the ray hits the terrain,
//! `albedo / pi * E` with `E` the irradiance the volume's emission delivers
//! through the volume's transmittance, estimated with emissive shadow rays
//! (`shadow.rs`; the 2014 report's `L = T * Li + Lvi`). **Background
//! radiance does not light the terrain**: it is only what camera rays see
//! behind everything. **The air** (`[sky] extinction`,
//! `crate::physics::air_extinction`) dims `L` per channel by its
//! transmittance towards the ray's direction, each star by that of its own
//! spectrum (`crate::physics::night_sky::star_extinction`), and the terrain's light by
//! that of its path to the camera; the background radiance and the sky image
//! are the sky as seen, not dimmed.
//!
//! Pixels: row 0 at the top. With `spp = 1` a pixel is sampled at its centre;
//! with more, the pixel value is the mean over its square (Cycles' BOX
//! filter) at stratified antithetic positions ([`pixel_position`]): points
//! of a digitally shifted Sobol (0, 2)-sequence in one half of the pixel,
//! each paired with its reflection through the centre. Every position is
//! uniform in the pixel (unbiased); each pair sums to `2 L(c)` on a linear
//! field (exact there: the first-order antithetic variate, Hammersley &
//! Morton 1956); at every power of two the set is stratified, so on
//! sub-pixel streaks the error falls about as `spp^-1`, as Cycles' does.
//! Each pixel's random stream is seeded from `(seed, pixel index)`: the
//! image does not depend on the thread count. Output alpha is `1 - T` along
//! the primary ray up to the terrain or infinity (the volume's coverage);
//! RGB already contains the terrain or the background behind it.
//!
//! Files, in the order of the stages: `settings.rs` (what is asked,
//! [`RenderError`]) -> `prepared.rs` ([`Prepared`], built once per scene,
//! camera and medium: `crate::geometry::camera`'s rays, `medium/` (dual
//! leaves and their tree), `terrain.rs`, `sky.rs`, `airglow.rs`, the emission sampler of
//! `shadow.rs`) -> `integrator.rs` (the pixel loop, tiles; `adaptive.rs`
//! shares the samples by pixel variance; positions from `sampler.rs`) ->
//! per ray `dda.rs` (hierarchical DDA: occupied leaves, then dual cells) ->
//! `segment.rs` (exact optical depth, Gauss-Legendre emission per cell), or
//! without extinction `emission_only.rs` (the plain line integral) ->
//! `march.rs` (one walker for primary and shadow rays) -> `shadow.rs`
//! (terrain irradiance) -> `image.rs` ([`Image`]) -> `image_file.rs` (EXR,
//! PNG) through `view_transform.rs` (standard, `agx.rs`, or AgX after a
//! look of `agx_look.rs`). `grids.rs`
//! picks a file's grids, `recolour.rs` rebuilds the emission from the line
//! grids for another observer; `sky_map.rs` renders the sky alone as a map for
//! Blender's world.

// Loops over the three colour channels index several arrays at once.
#![allow(clippy::needless_range_loop)]

pub mod adaptive;
pub mod agx;
pub mod agx_look;
pub mod airglow;
pub mod dda;
pub mod develop;
pub mod emission_only;
pub mod grids;
pub mod image;
pub mod image_file;
pub mod integrator;
pub mod march;
pub mod medium;
pub mod moon;
pub mod prepared;
pub mod recolour;
pub mod sampler;
pub mod segment;
pub mod settings;
pub mod shadow;
pub mod site_sky;
pub mod sky;
pub mod sky_map;
pub mod star_psf;
pub mod stars;
pub mod terrain;
pub mod view_transform;

pub use crate::geometry::camera::{CameraModel, Ray};
pub use adaptive::{render_adaptive, render_adaptive_prepared, ADAPTIVE_FLOOR, ADAPTIVE_MIN_SPP};
pub use image::{Image, RenderStats};
pub use integrator::{render, render_prepared};
pub use march::{optical_depth_along_ray, primary_path, radiance_along_ray, radiance_general, PrimaryPath, RayIntegral};
pub use medium::Medium;
pub use prepared::Prepared;
pub use sampler::{pixel_position, pixel_rng, sobol2};
pub use settings::{Integration, RenderError, RenderSettings, Volume};
pub use terrain::{write_obj, Heightfield, TerrainModel};
