//! A step's deposit becomes a photon: its colour from the emission lines
//! at the step's end altitude and the local ionization rate, its per-line
//! powers, and its segment mapped from the walk's curved frame to the scene
//! frame ([`deposit`]; the identity on a flat ground).

use super::beam::{BeamContext, BeamStart, BeamTrace};
use crate::geometry::earth::Earth;
use crate::physics::emission::line_table::{O1D_LINES, R_PER_KM_SCALE};
use crate::pipeline::deposit::{Photon, StepDeposit};
use crate::pipeline::motion::Wave;
use crate::pipeline::red_trail::TrailSample;
use glam::DVec3;

/// The photon of one beam step: `power` spread along the step from `start`
/// to `end` (km, the curved frame of `earth`, mapped to the scene frame:
/// a step of at most a few km is a chord of the mapped curve, off it by
/// its sagitta, under a metre on the scale of R). The gather's segment
/// kernel smooths it along the step; `photons.kernel = "point"` collapses
/// it to a point at `end`.
#[inline]
pub fn deposit(earth: &Earth, start: DVec3, end: DVec3, power: [f32; 3]) -> Photon {
    Photon::segment(scene_f32(earth, start), scene_f32(earth, end), power)
}

/// A walk-frame point mapped to the scene frame, in f32 (a photon's end).
#[inline]
fn scene_f32(earth: &Earth, q: DVec3) -> [f32; 3] {
    let p = earth.to_scene(q);
    [p.x as f32, p.y as f32, p.z as f32]
}

/// [`deposit`] for the next photon of `out`: a step starting where the
/// last one ended (the same bits) takes that end's mapping rather than
/// mapping it again (on a round Earth a square root and a sine and cosine).
#[inline]
fn deposit_next(earth: &Earth, out: &mut BeamTrace, start: DVec3, end: DVec3, power: [f32; 3]) -> Photon {
    let same = |a: DVec3, b: DVec3| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits);
    let s = match out.last_end {
        Some((q, s)) if same(q, start) => s,
        _ => scene_f32(earth, start),
    };
    let e = scene_f32(earth, end);
    out.last_end = Some((end, e));
    Photon::segment(s, e, power)
}

/// Pushes the photon and deposit record of one step: `kev_s` deposited at
/// the frame's time, `base_kev_s` the same without the pulsation. The
/// step's colour is that of its end altitude at the local ionization rate
/// `q = flux * q_per_flux(end)` (ion pairs cm^-3 s^-1), which the deposit
/// record keeps for `aurora profile`. Under a pulsation each line's photons
/// are its yield times the unmodulated deposit times the modulation a line
/// of its lifetime shows (`crate::physics::emission::line_table`); otherwise the colour table's
/// colour times the deposit. Per-line powers take each line's yield at the
/// step's midpoint (the altitude a step spread along its length averages to
/// second order, as `aurora profile` bins it), with no colour noise. In a
/// sample of the red trail (`ctx.trail`) each line's photons are the
/// unmodulated deposit times [`trail_factor`].
#[inline]
pub(super) fn emit(ctx: &BeamContext, start: &BeamStart, out: &mut BeamTrace, from: DVec3, to: DVec3, kev_s: f64, base_kev_s: f64) {
    let q_at = |z: f64| match ctx.ionization {
        Some(p) => start.flux_kev_cm2_s * p.per_flux(z),
        None => 0.0,
    };
    let q = q_at(to.z);
    let h_colour = to.z + start.colour_offset_km;
    let rgb = match (ctx.trail, start.wave, ctx.lines) {
        (Some(tr), wave, Some(t)) => {
            let factor = |i: usize, tau: f64| trail_factor(&tr, wave.as_ref(), i, tau);
            t.rgb_trail(|z| t.at_q(ctx.colour, z, q), to.z, h_colour, factor).map(|c| c * base_kev_s)
        }
        (None, Some(w), Some(t)) => {
            t.rgb_in_motion(|z| t.at_q(ctx.colour, z, q), to.z, h_colour, |tau| w.at_lifetime(tau)).map(|c| c * base_kev_s)
        }
        _ => ctx.colour.rgb_with_colour_altitude(to.z, h_colour, q).map(|c| c * kev_s),
    };
    let photon = deposit_next(&ctx.earth, out, from, to, [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32]);
    out.photons.push(photon);
    out.deposits.push(StepDeposit { z_start: from.z, z_end: to.z, power_kev_s: kev_s, q });
    if let (Some(t), false) = (ctx.lines, ctx.line_outputs.is_empty()) {
        let zm = 0.5 * (from.z + to.z);
        let l = t.at_q(ctx.colour, zm, q_at(zm));
        for &i in ctx.line_outputs {
            let n = match (ctx.trail, start.wave) {
                (Some(tr), wave) => base_kev_s * trail_factor(&tr, wave.as_ref(), i, l.tau_s[i]),
                (None, Some(w)) => base_kev_s * w.at_lifetime(l.tau_s[i]),
                (None, None) => kev_s,
            };
            out.line_power.push((l.yields[i] * n * R_PER_KM_SCALE) as f32);
        }
    }
}

/// What line i of lifetime `tau` keeps of a deposit in the red trail's
/// sample `tr` (`crate::pipeline::red_trail`): the O(1D) lines the sample's weight, the
/// others their value at the bake's time (under a pulsation, what a line of
/// their lifetime shows) in sample 0 and nothing in the earlier ones.
#[inline]
fn trail_factor(tr: &TrailSample, wave: Option<&Wave>, i: usize, tau: f64) -> f64 {
    if O1D_LINES[i] {
        tr.weight(tau, wave)
    } else if tr.is_now() {
        wave.map_or(1.0, |w| w.at_lifetime(tau))
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::beams::beam::BeamBuffers;

    #[test]
    fn chained_deposits_are_the_mapped_ends() {
        // Steps that start where the last one ended reuse its mapping; a
        // step that does not (a new start) maps its own; on a round Earth
        // and a flat one, every photon is `deposit`'s.
        for earth in [Earth::new(crate::geometry::earth::MEAN_RADIUS_KM), Earth::new(0.0)] {
            let mut out = BeamTrace::begin(DVec3::ZERO, 0.0, false, BeamBuffers::default());
            let pts = [DVec3::new(10.0, -3.0, 200.0), DVec3::new(10.2, -3.1, 198.5), DVec3::new(10.3, -3.0, 197.0)];
            let steps = [(pts[0], pts[1]), (pts[1], pts[2]), (pts[0], pts[2]), (pts[2], DVec3::new(-0.0, 0.0, 120.0))];
            for (a, b) in steps {
                let got = deposit_next(&earth, &mut out, a, b, [1.0, 2.0, 3.0]);
                assert_eq!(got, deposit(&earth, a, b, [1.0, 2.0, 3.0]), "{a} {b}");
            }
        }
    }
}
