//! Adaptive sampling by pixel variance ([`render_adaptive`]): a first
//! pass of antithetic pairs in every pixel, then the rest of the ray budget
//! shared by each pixel's relative spread, so that the summed relative
//! error is least for the budget (the model and its bias are stated on
//! [`render_adaptive`]). The image depends only on (seed, pixel), never on
//! the thread count.

use super::image::Image;
use super::integrator::{render, render_prepared, Counters, PixelState, TILE};
use super::prepared::Prepared;
use super::settings::{RenderError, RenderSettings, Volume};
use crate::util::fmath;
use crate::util::progress::Progress;
use rayon::prelude::*;
use std::time::Instant;

/// Least `render.spp` for [`render_adaptive`] to adapt (below it renders
/// uniformly): its first pass needs at least two antithetic pairs a pixel.
pub const ADAPTIVE_MIN_SPP: usize = 8;
/// Pixels dimmer than this fraction of the brightest first-pass pixel count
/// as this bright when their relative error is estimated (a floor: dark sky
/// pixels would otherwise have huge relative errors and draw every sample).
pub const ADAPTIVE_FLOOR: f64 = 0.01;

/// [`render`] with adaptive sampling by pixel variance; `render.spp` is the
/// average number of samples per pixel (the same ray budget as `render`).
///
/// Pass 1 traces `n0 = 2 floor(spp / 4)` samples (at least 4) in every
/// pixel. Each antithetic pair's mean (R + G + B) is one observation; their
/// sample standard deviation `s_i` over the pixel's `n0 / 2` pairs and the
/// pixel mean `m_i` give its relative spread `r_i = s_i / max(m_i, f M)`,
/// `M` the brightest pixel mean, `f` = [`ADAPTIVE_FLOOR`]. Pass 2 shares the
/// remaining `(spp - n0) / 2` pairs per pixel in proportion to
/// `r_i^(2/3)`: the allocation that minimises the summed relative error
/// `sum r_i / sqrt(n_i)` for a fixed total `sum n_i` (Lagrange: `r_i n_i^(-3/2)`
/// equal for all i). Counts are rounded by cumulative sums in pixel order, so
/// the total is exact and the result depends only on pass 1, which depends
/// only on (seed, pixel): the image is identical for any thread count. A
/// pixel's extra samples continue its sample sequence and random stream, and its
/// value is the mean of all its samples. Each sample is unbiased, but the
/// number of samples depends on the first ones, so the pixel mean carries a
/// small bias of order `1 / n0` of its variance (the usual price of adaptive
/// sampling, as in Cycles' own); pixels with no spread in pass 1 (empty
/// sky) get no more samples. If every pixel's spread is 0 the budget is
/// shared evenly.
pub fn render_adaptive(settings: &RenderSettings, volume: &Volume<'_>, progress: &dyn Progress) -> Result<Image, RenderError> {
    let spp = settings.render.spp;
    if spp < ADAPTIVE_MIN_SPP {
        return render(settings, volume, progress);
    }
    let build = Instant::now();
    let prepared = Prepared::new(settings, volume)?;
    render_adaptive_prepared(&prepared, build.elapsed().as_secs_f64(), progress)
}

/// [`render_adaptive`] from an already built [`Prepared`] (for instance
/// one whose medium was read straight from a file,
/// [`Prepared::with_medium`]); `build_seconds` goes into the stats.
pub fn render_adaptive_prepared(prepared: &Prepared, build_seconds: f64, progress: &dyn Progress) -> Result<Image, RenderError> {
    let spp = prepared.settings.render.spp;
    if spp < ADAPTIVE_MIN_SPP {
        let mut img = render_prepared(prepared, progress)?;
        img.stats.build_seconds = build_seconds;
        return Ok(img);
    }
    let (w, h) = (prepared.camera.width, prepared.camera.height);
    let n0 = 2 * (spp / 4);
    progress.start("render", 2 * h as u64);
    let start = Instant::now();
    // Both passes trace bands of TILE rows in TILE x TILE tiles, as render_prepared.
    let rows: Vec<(Vec<PixelState>, Counters, f64)> = (0..h.div_ceil(TILE))
        .into_par_iter()
        .map(|b| {
            let t0 = Instant::now();
            let mut n = Counters::default();
            let (y0, y1) = (b * TILE, ((b + 1) * TILE).min(h));
            let mut band: Vec<PixelState> =
                (y0..y1).flat_map(|py| (0..w).map(move |px| (px, py))).map(|(px, py)| prepared.pixel_start(px, py)).collect();
            for x0 in (0..w).step_by(TILE) {
                for py in y0..y1 {
                    for px in x0..(x0 + TILE).min(w) {
                        prepared.trace_samples(px, py, &mut band[(py - y0) * w + px], n0, &mut n);
                    }
                }
            }
            progress.inc((y1 - y0) as u64);
            (band, n, t0.elapsed().as_secs_f64())
        })
        .collect();
    let mut states = Vec::with_capacity(w * h);
    let mut counts = Vec::with_capacity(2 * h);
    for (row, n, secs) in rows {
        states.extend(row);
        counts.push((n, secs));
    }
    let extra = adaptive_pairs(&states, (spp - n0) / 2);
    let pass2: Vec<(Counters, f64)> = states
        .par_chunks_mut(TILE * w)
        .zip(extra.par_chunks(TILE * w))
        .enumerate()
        .map(|(b, (band, ex))| {
            let t0 = Instant::now();
            let mut n = Counters::default();
            let (y0, rows) = (b * TILE, band.len() / w);
            for x0 in (0..w).step_by(TILE) {
                for py in y0..y0 + rows {
                    for px in x0..(x0 + TILE).min(w) {
                        let i = (py - y0) * w + px;
                        let until = band[i].n + 2 * ex[i];
                        prepared.trace_samples(px, py, &mut band[i], until, &mut n);
                    }
                }
            }
            progress.inc(rows as u64);
            (n, t0.elapsed().as_secs_f64())
        })
        .collect();
    counts.extend(pass2);
    let render_seconds = start.elapsed().as_secs_f64();
    progress.finish();
    let pixels = states.iter().map(|st| st.sum.map(|v| (v / st.n as f64) as f32)).collect();
    Ok(prepared.finish(pixels, &counts, build_seconds, render_seconds))
}

/// Extra antithetic pairs per pixel for pass 2 of [`render_adaptive`]:
/// `pairs_per_pixel * pixels` in all, in proportion to `r_i^(2/3)`.
fn adaptive_pairs(states: &[PixelState], pairs_per_pixel: usize) -> Vec<usize> {
    let stats: Vec<(f64, f64)> = states.iter().map(PixelState::mean_and_pair_sd).collect();
    let peak = stats.iter().fold(0.0f64, |a, s| a.max(s.0));
    let floor = (ADAPTIVE_FLOOR * peak).max(f64::MIN_POSITIVE);
    let mut weights: Vec<f64> = stats.iter().map(|&(m, sd)| fmath::powf(sd / m.max(floor), 2.0 / 3.0)).collect();
    let mut total: f64 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        weights.fill(1.0);
        total = weights.len() as f64;
    }
    let budget = (pairs_per_pixel * states.len()) as f64;
    let mut cum = 0.0f64;
    let mut given = 0usize;
    weights
        .iter()
        .map(|wi| {
            cum += wi;
            let upto = ((budget * cum / total).round() as usize).max(given);
            let e = upto - given;
            given = upto;
            e
        })
        .collect()
}

impl PixelState {
    /// Mean R + G + B and the sample standard deviation of the pair means.
    pub(super) fn mean_and_pair_sd(&self) -> (f64, f64) {
        let mean = (self.sum[0] + self.sum[1] + self.sum[2]) / self.n.max(1) as f64;
        if self.pairs < 2 {
            return (mean, 0.0);
        }
        let k = self.pairs as f64;
        let var = (self.pair_sum2 - self.pair_sum * self.pair_sum / k) / (k - 1.0);
        (mean, var.max(0.0).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::pixel_rng;

    /// A pixel after 4 samples (2 pairs) with mean R + G + B `m` and pair
    /// standard deviation `sd`.
    fn state(m: f64, sd: f64) -> PixelState {
        let (p1, p2) = (m - sd / 2f64.sqrt(), m + sd / 2f64.sqrt());
        PixelState {
            rng: pixel_rng(0, 0),
            shift: [0.0; 2],
            sum: [4.0 * m, 0.0, 0.0, 0.0],
            n: 4,
            pairs: 2,
            pair_sum: p1 + p2,
            pair_sum2: p1 * p1 + p2 * p2,
            pending: 0.0,
        }
    }

    /// The pass-2 budget is shared exactly, in proportion to the relative
    /// spread to the power 2/3 (spreads 0.1 and 0.8: weights 1 and 4), a
    /// pixel with no spread gets nothing, a dim one is floored at 1 % of the
    /// peak (0.001 +- 0.001 counts as 0.01 +- 0.001: relative 0.1), and a
    /// flat image shares the budget evenly.
    #[test]
    fn adaptive_pairs_follow_the_relative_spread() {
        let (m, sd) = state(1.0, 0.8).mean_and_pair_sd();
        assert!((m - 1.0).abs() < 1e-12 && (sd - 0.8).abs() < 1e-12, "{m} {sd}");
        let states = [state(1.0, 0.1), state(1.0, 0.8), state(0.5, 0.0), state(0.001, 0.001)];
        assert_eq!(adaptive_pairs(&states, 3), vec![2, 8, 0, 2]);
        let flat = [state(1.0, 0.0), state(2.0, 0.0), state(0.0, 0.0)];
        assert_eq!(adaptive_pairs(&flat, 2), vec![2, 2, 2]);
    }
}
