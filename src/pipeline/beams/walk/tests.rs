use super::*;
use crate::geometry::earth::Earth;
use crate::physics::deposition::fang::{MonoDeposition, SpectrumDeposition};
use crate::physics::emission::line_colour::{ColourTable, EmissionModel};
use crate::physics::geomagnetic_field::MagneticField;
use crate::pipeline::deposit::pos;
use crate::pipeline::footprint::Footprint;
use crate::scene::BeamParams;
use crate::util::fmath;
use crate::util::rng;

/// The US Standard Atmosphere 1976 and the default emission model's
/// colours.
fn us1976() -> (Atmosphere, ColourTable) {
    (Atmosphere::us1976(), ColourTable::physical(&EmissionModel::default()))
}

/// NRLMSIS 2.1 and its emission model's colours.
fn nrlmsis21() -> (Atmosphere, ColourTable) {
    let atm = Atmosphere::nrlmsis21();
    let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
    (atm, colour)
}

/// A beam's surroundings: the atmosphere and its colours, the footprint
/// and the beam parameters.
struct Setup {
    atm: Atmosphere,
    colour: ColourTable,
    fp: Footprint,
    p: BeamParams,
}

impl Setup {
    /// `atm_colour` over a footprint beams never leave, with [`params`].
    fn flat((atm, colour): (Atmosphere, ColourTable)) -> Setup {
        Setup { atm, colour, fp: flat_footprint(1e5), p: params() }
    }

    /// The beam context of `model` ([`context`]).
    fn ctx<'a>(&'a self, model: DepositModel<'a>) -> BeamContext<'a> {
        context(&self.atm, &self.colour, &self.fp, &self.p, model)
    }
}

/// A footprint that is 1 everywhere in a huge box: beams never leave it.
/// One cell of density 1, `length` x `width` km, about the origin.
fn one_cell(length: f64, width: f64) -> Footprint {
    Footprint {
        nx: 1,
        ny: 1,
        data: vec![1.0],
        center: [0.0, 0.0],
        rotation_rad: 0.0,
        length,
        width,
        path: None,
        flux_scale: 1.0,
        filament_share: None,
    }
}

fn flat_footprint(size: f64) -> Footprint {
    Footprint {
        nx: 4,
        ny: 4,
        data: vec![1.0; 16],
        center: [0.0, 0.0],
        rotation_rad: 0.0,
        length: size,
        width: size,
        path: None,
        flux_scale: 1.0,
        filament_share: None,
    }
}

fn params() -> BeamParams {
    BeamParams { length_km: 400.0, dt: 0.0025, ..BeamParams::default() }
}

/// A curtain's spectrum table of a hard Maxwellian and a soft part.
fn curtain_g(e0: f64, soft: f64, e_soft: f64) -> std::sync::Arc<SpectrumDeposition> {
    use crate::physics::deposition::fang::maxwellian;
    SpectrumDeposition::cached(&[maxwellian(1.0 - soft, e0), maxwellian(soft, e_soft)])
}

fn start(e: f64) -> BeamStart {
    BeamStart {
        position: DVec3::new(0.0, 0.0, 260.0),
        energy_kev: e,
        power_kev_s: 1.0,
        base_power_kev_s: 1.0,
        wave: None,
        colour_offset_km: 0.0,
        flux_kev_cm2_s: 0.0,
        population: Default::default(),
    }
}

#[test]
fn deflection_angle_to_b_lies_in_the_sampled_range() {
    let (atm, colour) = us1976();
    let fp = flat_footprint(1e5);
    let p = BeamParams { alpha_d_deg: 25.0, delta_alpha_deg: 12.0, b_inclination_deg: 70.0, b_declination_deg: 20.0, ..params() };
    let ctx = BeamContext { record_path: true, ..context(&atm, &colour, &fp, &p, DepositModel::Csda) };
    let (lo, hi) = ((25.0f64 - 12.0).to_radians(), 25.0f64.to_radians());
    let mut r = rng::rng(&[1]);
    let mut n = 0;
    for k in 0..20 {
        let t = trace_beam(&ctx, &start(2.0 + k as f64), &mut r);
        for w in t.path.windows(2) {
            let d = w[1] - w[0];
            let len = d.length();
            if len < 1e-6 {
                continue; // a step with xi ~ 0 has no direction to measure
            }
            let angle = fmath::acos((d.dot(ctx.field.b) / len).clamp(-1.0, 1.0));
            // acos near small angles loses precision ~ sqrt(eps / len);
            // 1e-6 rad covers it for steps above 1 um.
            assert!(angle >= lo - 1e-6 && angle <= hi + 1e-6, "angle {} deg", angle.to_degrees());
            n += 1;
        }
    }
    assert!(n > 1000, "{n} steps checked");
}

#[test]
fn monoenergetic_beam_deposits_exactly_its_energy() {
    let s = Setup::flat(us1976());
    let ctx = s.ctx(DepositModel::Csda);
    let mut r = rng::rng(&[2]);
    for e0 in [0.5, 3.0, 10.0, 30.0] {
        let t = trace_beam(&ctx, &start(e0), &mut r);
        assert_eq!(t.end, EndReason::EnergySpent, "{e0} keV");
        // power_kev_s = 1: the deposits are the fractions E_lost / E0.
        let sum: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
        // The deposits telescope: sum = (E0 - 0) / E0, up to one rounding
        // per step (a few hundred steps x 1 ulp).
        assert!((sum - 1.0).abs() < 1e-12 * t.deposits.len() as f64, "{e0}: {sum}");
        assert_eq!(t.photons.len(), t.deposits.len());
        assert_eq!(t.undeposited_kev_s, 0.0);
    }
}

#[test]
fn harder_electrons_penetrate_deeper() {
    let s = Setup::flat(us1976());
    let ctx = s.ctx(DepositModel::Csda);
    let mut r = rng::rng(&[3]);
    let mut mean_end = |e0: f64| {
        let n = 50;
        (0..n).map(|_| trace_beam(&ctx, &start(e0), &mut r).end_position.z).sum::<f64>() / n as f64
    };
    let (z1, z3, z10) = (mean_end(1.0), mean_end(3.0), mean_end(10.0));
    // Range-energy with USSA 1976 columns: 10 keV (2.5e-4 g/cm^2) stops
    // near 102 km, 1 keV (5.8e-6 g/cm^2) near 148 km; slant paths and
    // deflections add a few percent of column (a fraction of a km).
    assert!((97.0..106.0).contains(&z10), "10 keV ends at {z10}");
    assert!((140.0..160.0).contains(&z1), "1 keV ends at {z1}");
    assert!(z10 < z3 && z3 < z1);
}

/// A beam context for the tests: `p`'s field, no per-line output, no
/// ionization profile (q = 0 at every deposit).
fn context<'a>(
    atm: &'a Atmosphere,
    colour: &'a ColourTable,
    fp: &'a Footprint,
    p: &'a BeamParams,
    model: DepositModel<'a>,
) -> BeamContext<'a> {
    BeamContext {
        atmosphere: atm,
        model,
        colour,
        field: MagneticField::new(p.b_inclination_deg, p.b_declination_deg),
        params: p,
        footprint: fp,
        threshold: 0.03,
        record_path: false,
        lines: None,
        trail: None,
        line_outputs: &[],
        ionization: None,
        earth: Earth::FLAT,
    }
}

#[test]
fn expected_beam_deposits_the_spectrum_total_below_its_start_and_accounts_for_the_rest() {
    let s = Setup::flat(nrlmsis21());
    let atm = &s.atm;
    for (e0, soft) in [(1.0, 0.0), (3.0, 0.1), (30.0, 0.0)] {
        let g = curtain_g(e0, soft, 0.2);
        let ctx = s.ctx(DepositModel::Expected(&g));
        let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(e0) }, &mut rng::rng(&[7]));
        assert_eq!(t.end, EndReason::EnergySpent, "{e0} keV");
        let dep: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
        // Above the start it lays its share up to z_up (where at most
        // ABOVE_START_TOL of the total lies higher, or the table's top; no
        // column where that is below the start) and reports the rest above
        // z_up: a finished beam deposits exactly G(inf) less what it
        // reports above (sums of telescoping differences, rounding only).
        let z_up = above_start_column_top(atm, &|m| g.fraction_above(m), g.total(), 260.0);
        let above = g.fraction_above(atm.column_mass(z_up));
        assert!(z_up <= atm.top_km() && z_up >= 260.0, "{e0}: {z_up} km");
        assert!(above <= ABOVE_START_TOL * g.total() || z_up >= atm.top_km(), "{e0}: {z_up} km, {above}");
        assert!((dep + t.above_top_kev_s - g.total()).abs() < 1e-12, "{e0}: {dep} + {} vs {}", t.above_top_kev_s, g.total());
        assert!((t.above_top_kev_s - above.min(g.fraction_above(atm.column_mass(260.0)))).abs() < 1e-12, "{e0}: {}", t.above_top_kev_s);
        assert!(t.undeposited_kev_s == 0.0);
        // What lies above the start is on the field line above it, and
        // holds what lies above the start less what is reported above z_up.
        let up: f64 = t.deposits.iter().filter(|d| d.z_end >= 260.0 - 1e-9).map(|d| d.power_kev_s).sum();
        let want = if z_up > 260.0 { g.fraction_above(atm.column_mass(260.0)) - t.above_top_kev_s } else { 0.0 };
        assert!((up - want).abs() < 1e-12, "{e0}: above the start {up} vs {want}");
        let top = t.deposits.iter().map(|d| d.z_start.max(d.z_end)).fold(0.0, f64::max);
        assert!((top - z_up).abs() < 1e-6, "{e0}: highest deposit {top} km, column top {z_up} km");
        assert!((dep + t.backscatter_kev_s + t.above_top_kev_s - 1.0).abs() < 1e-12);
        assert!(t.deposits.iter().all(|d| d.power_kev_s > 0.0));
    }
}

#[test]
fn fang_beams_keep_going_when_their_foot_leaves_the_footprint() {
    let (atm, colour) = nrlmsis21();
    // A 2 km strip of density (the kind that stops CSDA beams, test
    // below) in the middle of an 18 km box.
    let mut data = vec![0.0; 9];
    data[4] = 1.0;
    let fp = Footprint {
        nx: 1,
        ny: 9,
        data,
        center: [0.0, 0.0],
        rotation_rad: 0.0,
        length: 1e4,
        width: 18.0,
        path: None,
        flux_scale: 1.0,
        filament_share: None,
    };
    let p = BeamParams { alpha_d_deg: 20.0, delta_alpha_deg: 10.0, ..params() };
    let g = curtain_g(30.0, 0.0, 0.2);
    let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
    let mut r = rng::rng(&[6]);
    let mut outside = 0;
    for _ in 0..20 {
        let t = trace_beam(&ctx, &start(30.0), &mut r);
        assert_eq!(t.end, EndReason::EnergySpent);
        assert_eq!(t.undeposited_kev_s, 0.0);
        outside += t
            .photons
            .iter()
            .filter(|ph| {
                let q = pos(ph);
                let foot = ctx.field.foot(q, 260.0);
                fp.cell_value_world(foot.x, foot.y) <= 0.03
            })
            .count();
    }
    assert!(outside > 100, "only {outside} photons beyond the strip: the test does not test");
}

#[test]
fn runaway_fang_steps_end_at_the_bottom_or_the_enlarged_box() {
    let (atm, colour) = nrlmsis21();
    let fp = one_cell(10.0, 4.0);
    let g = curtain_g(3.0, 0.0, 0.2);
    // Straight down in steps of up to 2.5e6 km: the first step is cut at
    // the atmosphere's bottom (where a 3 keV spectrum is complete).
    let p = BeamParams { length_km: 1e9, alpha_d_deg: 0.0, delta_alpha_deg: 0.0, b_inclination_deg: 90.0, ..params() };
    let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
    let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(3.0) }, &mut rng::rng(&[9]));
    assert!(matches!(t.end, EndReason::Bottom | EndReason::EnergySpent), "{:?}", t.end);
    assert!(t.photons.iter().all(|ph| ph.position[2] >= 50.0 - 1e-4), "{:?}", t.photons);
    let dep: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
    assert!((dep + t.backscatter_kev_s + t.above_top_kev_s + t.undeposited_kev_s - 1.0).abs() < 1e-12);
    // Near-horizontal steps of 1e11 km: stopped at the box enlarged by
    // its size (|u| <= 10, |v| <= 4 at the start altitude), never placing
    // a photon whose foot is further out.
    let p = BeamParams { length_km: 1e9, alpha_d_deg: 89.999, delta_alpha_deg: 0.0, b_inclination_deg: 10.0, ..params() };
    let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
    let mut r = rng::rng(&[10]);
    for _ in 0..20 {
        let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(3.0) }, &mut r);
        assert_ne!(t.end, EndReason::MaxSteps);
        for ph in &t.photons {
            let q = pos(ph);
            let foot = ctx.field.foot(q, 260.0);
            assert!(foot.x.abs() <= 10.0 + 1e-3 && foot.y.abs() <= 4.0 + 1e-3, "{foot}");
        }
    }
}

#[test]
fn sampled_deposition_converges_to_the_expected_one_step_by_step() {
    // Same random stream => same path in both models (the energy is
    // drawn before the path and the path does not depend on it), so per
    // altitude bin the sampled deposits' mean over beams must converge
    // to the expected model's (Rao-Blackwellisation: E[D_E] = G). Test
    // each 2 km bin at 5 standard errors of the sampled mean (sample
    // variance over N = 4000 beams; 80 bins, so a false alarm at
    // 5 sigma has probability ~ 80 x 6e-7).
    let s = Setup::flat(nrlmsis21());
    let (e0, soft, e_soft) = (3.0, 0.2, 0.3);
    let g = curtain_g(e0, soft, e_soft);
    let (ce, cs) = (s.ctx(DepositModel::Expected(&g)), s.ctx(DepositModel::Sampled(MonoDeposition::get())));
    let n = 4000;
    let nb = 80;
    let bin = |z: f64| (((z - 80.0) / 2.0).floor() as isize).clamp(0, nb as isize - 1) as usize;
    let (mut sum_e, mut sum_s, mut sum_s2) = (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
    for i in 0..n {
        let mut r = rng::rng(&[8, i as u64]);
        let e0_i = if r.random::<f64>() < soft { e_soft } else { e0 };
        let st = BeamStart {
            energy_kev: crate::physics::deposition::spectrum::Spectrum::Maxwellian { e0_kev: e0_i }.sample_energy(&mut r),
            ..start(0.0)
        };
        let mut r2 = r.clone();
        let (te, ts) = (trace_beam(&ce, &st, &mut r), trace_beam(&cs, &st, &mut r2));
        let mut per = vec![0.0; nb];
        for d in &ts.deposits {
            per[bin(d.z_end)] += d.power_kev_s;
        }
        for d in &te.deposits {
            sum_e[bin(d.z_end)] += d.power_kev_s;
        }
        // Above the start: both models account for it, not deposit it.
        sum_e[nb - 1] += te.above_top_kev_s;
        per[nb - 1] += ts.above_top_kev_s;
        for b in 0..nb {
            sum_s[b] += per[b];
            sum_s2[b] += per[b] * per[b];
        }
    }
    let nf = n as f64;
    let mut checked = 0;
    for b in 0..nb {
        let (me, ms) = (sum_e[b] / nf, sum_s[b] / nf);
        let se = ((sum_s2[b] / nf - ms * ms).max(0.0) / nf).sqrt();
        assert!((me - ms).abs() <= 5.0 * se + 1e-9, "bin {} km: expected {me:.5} sampled {ms:.5} +- {se:.5}", 80 + 2 * b);
        if me > 1e-3 {
            checked += 1;
        }
    }
    assert!(checked > 15, "{checked} bins with deposits");
}

#[test]
fn beams_leave_when_their_foot_leaves_the_footprint() {
    let (atm, colour) = us1976();
    // A 2 km wide strip: a random walk of 10-20 degree steps leaves it.
    let fp = one_cell(1e4, 2.0);
    let p = BeamParams { alpha_d_deg: 20.0, delta_alpha_deg: 10.0, ..params() };
    let ctx = context(&atm, &colour, &fp, &p, DepositModel::Csda);
    let mut r = rng::rng(&[6]);
    let mut left = 0;
    for _ in 0..50 {
        let t = trace_beam(&ctx, &start(30.0), &mut r);
        if t.end == EndReason::LeftFootprint {
            left += 1;
            let foot = ctx.field.foot(t.end_position, 260.0);
            assert!(fp.cell_value_world(foot.x, foot.y) > 0.03, "the last accepted point is inside");
        }
        for ph in &t.photons {
            let q = pos(ph);
            let foot = ctx.field.foot(q, 260.0);
            // f32 positions: allow 1e-4 km of rounding at the strip edge.
            assert!(foot.y.abs() < 1.0 + 1e-4, "photon outside the strip: {foot}");
        }
    }
    assert!(left > 10, "only {left} of 50 left a 2 km strip");
}

/// The deposit of `t` above `z0` in bins of `dz` km, each deposit spread
/// evenly over its altitude span (as the photon segment lays it).
fn binned_above(t: &BeamTrace, z0: f64, dz: f64, n: usize) -> Vec<f64> {
    let mut bins = vec![0.0; n];
    for d in &t.deposits {
        let (a, b) = (d.z_start.min(d.z_end), d.z_start.max(d.z_end));
        if a < z0 - 1e-9 {
            continue;
        }
        for (i, bin) in bins.iter_mut().enumerate() {
            let (lo, hi) = (z0 + i as f64 * dz, z0 + (i + 1) as f64 * dz);
            let overlap = (b.min(hi) - a.max(lo)).max(0.0);
            if b > a {
                *bin += d.power_kev_s * overlap / (b - a);
            }
        }
    }
    bins
}

#[test]
fn the_deposit_above_the_start_follows_fang_without_a_lump() {
    // A vertical field: the column above the start is the altitude axis.
    // Per 2 km bin from the start up, the beam's deposit against Fang 2010
    // over the spectrum, G(m(z_lo)) - G(m(z_hi)): within 10 % in every bin
    // holding at least 1e-3 of the share above the start (a span's deposit
    // is spread evenly, within exp(+-0.075) of the profile at its ends;
    // the top span, which also holds the last 0.2 % of the total, is left
    // out), and the share above each bin's top within 5 %
    // where it is at least 1e-3 of it and 10 times that last share. The old column (everything above
    // its 10 km top span laid in that span) put 5 keV's share in a lump
    // and nothing above 276 km.
    let (atm, colour) = nrlmsis21();
    let s = Setup {
        p: BeamParams { b_inclination_deg: 90.0, alpha_d_deg: 0.0, delta_alpha_deg: 0.0, ..params() },
        ..Setup::flat((atm, colour))
    };
    let atm = &s.atm;
    let mut checked = 0;
    for e0 in [0.1, 0.3, 1.0, 3.0, 5.0, 10.0, 30.0] {
        let g = curtain_g(e0, 0.0, 0.2);
        let ctx = s.ctx(DepositModel::Expected(&g));
        let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(e0) }, &mut rng::rng(&[11]));
        let share = g.fraction_above(atm.column_mass(260.0));
        let n = 200;
        let bins = binned_above(&t, 260.0, 2.0, n);
        let f = |z: f64| g.fraction_above(atm.column_mass(z));
        let spans = above_start_spans(atm, &|m| g.fraction_above(m), g.total(), 260.0);
        let top_span = if spans.len() >= 2 { spans[spans.len() - 2] } else { 260.0 };
        let mut above_got = share;
        for (i, got) in bins.iter().enumerate() {
            let (lo, hi) = (260.0 + 2.0 * i as f64, 262.0 + 2.0 * i as f64);
            let want = f(lo) - f(hi);
            above_got -= got;
            if want >= 1e-3 * share && hi <= top_span {
                assert!((got / want - 1.0).abs() < 0.10, "{e0} keV, {lo}-{hi} km: {got:e} vs Fang {want:e}");
                checked += 1;
            }
            if f(hi) >= (1e-3 * share).max(10.0 * ABOVE_START_TOL * g.total()) {
                assert!((above_got / f(hi) - 1.0).abs() < 0.05, "{e0} keV, above {hi} km: {above_got:e} vs Fang {:e}", f(hi));
            }
        }
    }
    assert!(checked > 50, "{checked} bins checked");
}
