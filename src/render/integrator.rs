//! The pixel loop: each pixel's samples traced through a [`Prepared`]
//! scene, in bands of [`TILE`] rows, `TILE x TILE` pixels at a time, in
//! parallel, collected in row order; then the stars. Per sample: the
//! sample's position in the pixel (`sampler.rs`), the camera ray, the
//! terrain hit, the volume's radiance and transmittance up to it
//! (`march.rs`), and behind it the terrain lit by emissive shadow rays
//! (`shadow.rs`) or the background and sky; the pixel value is the mean of
//! its samples (the model is the renderer's module doc). Each pixel depends
//! only on (seed, pixel index), never on the thread count or the order.

use super::image::{Image, RenderStats};
use super::march::{optical_depth_along_ray, radiance_advected, radiance_along_ray, RaySpan};
use super::prepared::Prepared;
use super::sampler::{pixel_position, pixel_rng};
use super::settings::Integration;
use super::settings::{RenderError, RenderSettings, Volume};
use super::shadow::estimate_irradiance;
use super::stars::planck;
use crate::physics::night_sky::star_extinction::StarAir;
use crate::util::progress::Progress;
use rand::Rng;
use rand_pcg::Pcg32;
use rayon::prelude::*;
use std::time::Instant;

/// Per-row work counters (summed in row order).
#[derive(Clone, Copy, Default)]
pub(super) struct Counters {
    pub(super) primary: u64,
    pub(super) shadow_samples: u64,
    pub(super) shadow_rays: u64,
    pub(super) hits: u64,
    pub(super) work: u64,
    pub(super) shadow_nanos: u64,
}

impl Prepared {
    /// The value of pixel (px, py) (row 0 at the top).
    pub fn pixel(&self, px: usize, py: usize) -> [f32; 4] {
        self.pixel_counted(px, py, &mut Counters::default())
    }

    pub(super) fn pixel_counted(&self, px: usize, py: usize, n: &mut Counters) -> [f32; 4] {
        let spp = self.settings.render.spp;
        let mut st = self.pixel_start(px, py);
        self.trace_samples(px, py, &mut st, spp, n);
        st.sum.map(|v| (v / spp as f64) as f32)
    }

    /// The motion blur's march step: half the finest voxel (the advected
    /// lookups leave the dual cells, so the exact walk does not apply).
    fn blur_step(&self) -> f64 {
        0.5 * self.medium.fields.iter().map(|f| f.transform.voxel_size).fold(f64::INFINITY, f64::min)
    }

    /// A pixel's random stream and sample shift, nothing traced yet.
    pub(super) fn pixel_start(&self, px: usize, py: usize) -> PixelState {
        let index = (py * self.camera.width + px) as u64;
        let mut rng = pixel_rng(self.settings.seed, index);
        let shift = if self.settings.render.spp == 1 { [0.0; 2] } else { [rng.random::<f64>(), rng.random::<f64>()] };
        PixelState { rng, shift, sum: [0.0; 4], n: 0, pairs: 0, pair_sum: 0.0, pair_sum2: 0.0, pending: 0.0 }
    }

    /// Traces samples `st.n .. until` of the pixel and adds them to `st`
    /// (the sample positions continue the pixel's sample sequence, the random
    /// numbers its stream, so tracing in two calls equals tracing in one).
    pub(super) fn trace_samples(&self, px: usize, py: usize, st: &mut PixelState, until: usize, n: &mut Counters) {
        let s = &self.settings;
        let spp = s.render.spp;
        let albedo = s.terrain.albedo;
        let background = s.background.radiance;
        for i in st.n..until {
            st.n = i + 1;
            let (jx, jy, offset) = if spp == 1 {
                (0.5, 0.5, 0.5)
            } else {
                let (jx, jy) = pixel_position(st.shift, i);
                (jx, jy, st.rng.random::<f64>())
            };
            // Outside a fisheye's image circle the sample sees nothing
            // (RGBA 0, as Cycles leaves it).
            let Some(ray) = self.camera.ray_at(px as f64 + jx, py as f64 + jy) else {
                n.primary += 1;
                st.add_luminance(i, 0.0);
                continue;
            };
            let hit = self.terrain.intersect(ray.origin, ray.dir, 0.0, f64::INFINITY);
            let t_end = hit.map_or(f64::INFINITY, |h| h.t);
            let vol = match (&self.velocity, s.render.shutter_s > 0.0) {
                (Some(v), true) => {
                    // The sample's shutter time: a golden-ratio sequence over the
                    // pixel's samples from its own shift, uniform on the shutter.
                    let u = (0.5 + st.shift[0] + st.shift[1] + i as f64 * GOLDEN).fract();
                    let tau = (u - 0.5) * s.render.shutter_s;
                    let h = match s.integration {
                        Integration::FixedStep(h) => h,
                        Integration::Exact => self.blur_step(),
                    };
                    radiance_advected(&self.medium, v, RaySpan { origin: ray.origin, dir: ray.dir, t_max: t_end }, h, offset, tau)
                }
                _ => radiance_along_ray(&self.medium, ray.origin, ray.dir, t_end, s.integration, offset),
            };
            let t = vol.transmittance();
            n.primary += 1;
            n.work += vol.work;
            let behind = match hit {
                Some(h) => {
                    n.hits += 1;
                    // The first hit of the render builds the emission sampler
                    // (`Prepared::sampler`), outside the shadow rays' time.
                    let shadow = self.shadow_scene();
                    let start = Instant::now();
                    let (e, rays) = estimate_irradiance(&shadow, h.p, h.n, s.render.shadow_samples, &mut st.rng);
                    n.shadow_nanos += start.elapsed().as_nanos() as u64;
                    n.shadow_samples += s.render.shadow_samples as u64;
                    n.shadow_rays += rays;
                    let m = self.moonlight_on(h.p, h.n);
                    let g = self.airglow.as_ref().map_or([0.0; 3], |a| a.ground_irradiance(h.n));
                    let l = [0, 1, 2].map(|c| albedo[c] / std::f64::consts::PI * (e[c] + m[c] + g[c]));
                    match &self.air {
                        // The terrain's light crosses the air to the camera.
                        Some(a) => {
                            let ta = a.along(ray.origin, h.p);
                            [0, 1, 2].map(|c| l[c] * ta[c])
                        }
                        None => l,
                    }
                }
                None => {
                    let s = self.sky.radiance(ray.dir);
                    let g = self.airglow.as_ref().map_or([0.0; 3], |a| a.radiance(ray.dir));
                    [0, 1, 2].map(|c| background[c] + s[c] + g[c])
                }
            };
            // The volume's emission lies above the air: its transmittance
            // towards the ray's direction (`crate::physics::air_extinction`).
            let l_vol = match &self.air {
                Some(a) => {
                    let ta = a.towards(ray.dir);
                    [0, 1, 2].map(|c| vol.l[c] * ta[c])
                }
                None => vol.l,
            };
            let mut lum = 0.0;
            for c in 0..3 {
                let v = l_vol[c] + t * behind[c];
                st.sum[c] += v;
                lum += v;
            }
            st.sum[3] += 1.0 - t;
            st.add_luminance(i, lum);
        }
    }
}

/// The golden ratio's fractional part: the shutter times of a pixel's
/// samples, `frac(c + i GOLDEN)`, fill the shutter evenly for any count.
const GOLDEN: f64 = 0.618_033_988_749_894_9;

/// One pixel's samples so far: its random stream, the sum of its samples
/// and the statistics of its antithetic pairs' means (R + G + B).
#[derive(Clone)]
pub(super) struct PixelState {
    pub(super) rng: Pcg32,
    pub(super) shift: [f64; 2],
    pub(super) sum: [f64; 4],
    /// Samples traced.
    pub(super) n: usize,
    pub(super) pairs: u32,
    pub(super) pair_sum: f64,
    pub(super) pair_sum2: f64,
    /// R + G + B of the pair's first sample, while its partner is pending.
    pub(super) pending: f64,
}

impl PixelState {
    #[inline]
    pub(super) fn add_luminance(&mut self, i: usize, lum: f64) {
        if i.is_multiple_of(2) {
            self.pending = lum;
        } else {
            let m = 0.5 * (self.pending + lum);
            self.pairs += 1;
            self.pair_sum += m;
            self.pair_sum2 += m * m;
        }
    }
}

/// Renders the volume (and terrain) with `settings`. Multithreaded with rayon
/// (the caller sets the thread count); reports one progress unit per row.
pub fn render(settings: &RenderSettings, volume: &Volume<'_>, progress: &dyn Progress) -> Result<Image, RenderError> {
    let build = Instant::now();
    let prepared = Prepared::new(settings, volume)?;
    let build_seconds = build.elapsed().as_secs_f64();
    let mut img = render_prepared(&prepared, progress)?;
    img.stats.build_seconds = build_seconds;
    Ok(img)
}

/// [`render`] from an already built [`Prepared`] at its settings (size
/// from its camera, `settings.render.spp`): a caller that keeps the medium
/// between renders (`crate::app::preview`) pays the build once. The same image
/// as `render` with those settings; `stats.build_seconds` is 0.
pub fn render_prepared(prepared: &Prepared, progress: &dyn Progress) -> Result<Image, RenderError> {
    if prepared.settings.render.spp == 0 {
        return Err(RenderError::Settings("render.spp must be at least 1".into()));
    }
    let shutter = prepared.settings.render.shutter_s;
    if shutter > 0.0 && prepared.velocity.is_none() {
        return Err(RenderError::Settings(format!(
            "render.shutter_s = {shutter} blurs along the velocity grid `v`, which the volume does not hold: bake it with grid.velocity = true, or set render.shutter_s = 0"
        )));
    }
    let build_seconds = 0.0;
    let (w, h) = (prepared.camera.width, prepared.camera.height);
    progress.start("render", h as u64);
    let start = Instant::now();
    let bands: Vec<(Vec<[f32; 4]>, Counters, f64, usize)> = (0..h.div_ceil(TILE))
        .into_par_iter()
        .map(|b| {
            let t0 = Instant::now();
            let mut n = Counters::default();
            let (y0, y1) = (b * TILE, ((b + 1) * TILE).min(h));
            let mut band = vec![[0.0f32; 4]; (y1 - y0) * w];
            for x0 in (0..w).step_by(TILE) {
                for py in y0..y1 {
                    for px in x0..(x0 + TILE).min(w) {
                        band[(py - y0) * w + px] = prepared.pixel_counted(px, py, &mut n);
                    }
                }
            }
            progress.inc((y1 - y0) as u64);
            (band, n, t0.elapsed().as_secs_f64(), y1 - y0)
        })
        .collect();
    let rows: Vec<(Vec<[f32; 4]>, Counters, f64)> = bands.into_iter().map(|(b, n, s, _)| (b, n, s)).collect();
    let render_seconds = start.elapsed().as_secs_f64();
    progress.finish();
    let mut pixels = Vec::with_capacity(w * h);
    let mut counts = Vec::with_capacity(h);
    for (row, n, secs) in rows {
        pixels.extend(row);
        counts.push((n, secs));
    }
    Ok(prepared.finish(pixels, &counts, build_seconds, render_seconds))
}

/// The pixel loops trace bands of `TILE` rows, `TILE x TILE` pixels at a
/// time, so that rays traced one after the other cross neighbouring cells
/// (cache reuse: 8 % less CPU than whole rows at 160x90, 8 spp; 8 x 8 tiles
/// measured no better). Each pixel depends on (seed, pixel) only, so the
/// order changes nothing in the image.
pub(super) const TILE: usize = 4;

impl Prepared {
    /// The image from its pixels and the per-row work counters: stats, then stars.
    pub(super) fn finish(&self, mut pixels: Vec<[f32; 4]>, counts: &[(Counters, f64)], build_seconds: f64, render_seconds: f64) -> Image {
        let mut stats = RenderStats {
            leaves: self.medium.leaf_count() as u64,
            accel_bytes: self.medium.memory_bytes() as u64,
            build_seconds,
            render_seconds,
            threads: rayon::current_num_threads(),
            ..RenderStats::default()
        };
        for (n, secs) in counts {
            stats.primary_rays += n.primary;
            stats.shadow_samples += n.shadow_samples;
            stats.shadow_rays += n.shadow_rays;
            stats.terrain_hits += n.hits;
            stats.volume_work += n.work;
            stats.thread_seconds += secs;
            stats.shadow_thread_seconds += n.shadow_nanos as f64 * 1e-9;
        }
        self.add_stars(&mut pixels);
        self.add_moon(&mut pixels);
        Image { width: self.camera.width, height: self.camera.height, pixels, stats }
    }
}

impl Prepared {
    /// The Moon's irradiance on the terrain at `p` of normal `n`
    /// (`moon.rs`): through the air toward the Moon, none where the terrain
    /// hides it; the volume's transmittance toward the Moon is taken as 1
    /// (an aurora's optical depth is below 1e-3).
    fn moonlight_on(&self, p: glam::DVec3, n: glam::DVec3) -> [f64; 3] {
        let Some(m) = &self.sky.moon else { return [0.0; 3] };
        if n.dot(m.dir) <= 0.0 || self.terrain.intersect(p + n * 1e-6, m.dir, 0.0, f64::INFINITY).is_some() {
            return [0.0; 3];
        }
        let e = m.irradiance_on(n);
        match &self.air {
            Some(a) => {
                let t = a.towards(m.dir);
                [0, 1, 2].map(|c| e[c] * t[c])
            }
            None => e,
        }
    }

    /// The Moon's disc (`moon.rs`), seen as a star is.
    fn add_moon(&self, pixels: &mut [[f32; 4]]) {
        if let Some(m) = &self.sky.moon {
            m.draw(pixels, &self.camera, |dir| self.star_transmittance(dir));
        }
    }

    /// The star field's points (`sky.rs`), seen through the volume's
    /// transmittance and the air's for each star's own spectrum
    /// (`crate::physics::night_sky::star_extinction`), hidden by the terrain
    /// and by the solid Earth (a ray that goes below the ground: below the
    /// horizontal on a flat ground, below the horizon's dip on a round one),
    /// as the airglow is.
    fn add_stars(&self, pixels: &mut [[f32; 4]]) {
        let air = self.air.as_ref().map(|a| (StarAir::new(&a.air, a.observer_km, self.settings.observer), a));
        self.sky.add_stars(pixels, &self.camera, |star| {
            let t = self.volume_transmittance_to_sky(star.dir)?;
            Some(match &air {
                Some((sa, ext)) => sa.transmittance(|l| planck(l, star.temperature_k), ext.elevation_deg(star.dir)).map(|ta| t * ta),
                None => [t; 3],
            })
        });
    }

    /// The volume's transmittance toward a point of the sky at infinity
    /// from the camera; None where the terrain or the solid Earth hides it.
    fn volume_transmittance_to_sky(&self, dir: glam::DVec3) -> Option<f64> {
        let s = &self.settings;
        let o = self.camera.position;
        let earth = crate::geometry::earth::Earth::new(s.earth_radius_km);
        if earth.lowest_altitude(o, dir) < 0.0 || self.terrain.intersect(o, dir, 0.0, f64::INFINITY).is_some() {
            return None;
        }
        Some(optical_depth_along_ray(&self.medium, o, dir, f64::INFINITY, s.integration, 0.5).transmittance())
    }

    /// The transmittance toward a point of the sky at infinity from the
    /// camera: the volume's times the air's per channel (the aurora's line
    /// mix, for the Moon); None where the terrain or the solid Earth hides it.
    fn star_transmittance(&self, dir: glam::DVec3) -> Option<[f64; 3]> {
        let t = self.volume_transmittance_to_sky(dir)?;
        Some(match &self.air {
            Some(a) => a.towards(dir).map(|ta| t * ta),
            None => [t; 3],
        })
    }
}
