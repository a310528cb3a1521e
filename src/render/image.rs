//! The renderer's result: a linear image ([`Image`]) and the work and time
//! that made it ([`RenderStats`]), and the memory an image of a given size
//! takes ([`image_memory_bytes`]).

/// Bytes a render holds per pixel: the image (`[f32; 4]`), the bands the
/// threads fill before it is assembled (as much again), the 16-bit PNG's
/// samples and the EXR writer's copy.
pub const RENDER_BYTES_PER_PIXEL: u64 = 48;

/// Bytes an adaptive render holds per pixel: each pixel's state (its
/// random stream, sums and pair statistics, about 104 bytes), its
/// statistics and weights for the second pass, and the image as above.
pub const ADAPTIVE_BYTES_PER_PIXEL: u64 = 192;

/// The memory a `width` x `height` render holds for its pixels (adaptive or
/// not), in bytes: what the render checks against the process's limit
/// before any pixel is allocated.
pub fn image_memory_bytes(width: usize, height: usize, adaptive: bool) -> u128 {
    let per_pixel = if adaptive { ADAPTIVE_BYTES_PER_PIXEL } else { RENDER_BYTES_PER_PIXEL };
    width as u128 * height as u128 * per_pixel as u128
}

/// Work and time of one render. Counts are exact and deterministic; times are
/// measured (wall clock, and per-thread time summed over threads).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera rays (pixels x spp).
    pub primary_rays: u64,
    /// Emission samples drawn at terrain hits (hits x shadow_samples).
    pub shadow_samples: u64,
    /// Shadow rays actually traced (samples facing the surface).
    pub shadow_rays: u64,
    /// Primary rays that hit the terrain.
    pub terrain_hits: u64,
    /// Dual-cell pieces / quadrature parts (exact) or steps (fixed step)
    /// integrated along primary rays.
    pub volume_work: u64,
    /// Dual leaves in the acceleration structure, and its size in bytes.
    pub leaves: u64,
    pub accel_bytes: u64,
    /// Building the acceleration structure, emission sampler and terrain.
    pub build_seconds: f64,
    /// Wall-clock time of the pixel loop.
    pub render_seconds: f64,
    /// Thread time of the pixel loop summed over threads.
    pub thread_seconds: f64,
    /// Of `thread_seconds`, the time spent estimating terrain irradiance.
    pub shadow_thread_seconds: f64,
    pub threads: usize,
}

impl RenderStats {
    /// Primary rays per second of wall-clock time (all threads, including
    /// the shadow rays they spawn).
    pub fn primary_rays_per_second(&self) -> f64 {
        self.primary_rays as f64 / self.render_seconds.max(1e-12)
    }
    /// Primary rays per thread-second, shadow work excluded.
    pub fn primary_rays_per_thread_second(&self) -> f64 {
        self.primary_rays as f64 / (self.thread_seconds - self.shadow_thread_seconds).max(1e-12)
    }
    /// Shadow-ray samples per thread-second.
    pub fn shadow_samples_per_thread_second(&self) -> f64 {
        self.shadow_samples as f64 / self.shadow_thread_seconds.max(1e-12)
    }
}

/// A rendered image: linear Rec.709 RGBA, row 0 at the top, A = 1 - T.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 4]>,
    pub stats: RenderStats,
}

impl Image {
    pub fn pixel(&self, x: usize, y: usize) -> [f32; 4] {
        self.pixels[y * self.width + x]
    }
}
