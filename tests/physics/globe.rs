//! The southern hemisphere: beyond the dipole's equator B points up, and
//! the electrons still go down the field line into the atmosphere (along
//! -B), as they go along B in the north.

use crate::common::small::small_scene;
use aurora::pipeline::beams::trace_deposits;
use aurora::pipeline::deposit::StepDeposit;
use aurora::scene::Scene;
use aurora::util::progress::NoProgress;

/// Deposited power per 1 km altitude bin from 0 to 800 km, each step's
/// power spread evenly over the altitudes it spans.
fn profile(deposits: &[Vec<StepDeposit>]) -> Vec<f64> {
    let mut bins = vec![0.0; 800];
    for d in deposits.iter().flatten() {
        let (lo, hi) = (d.z_start.min(d.z_end), d.z_start.max(d.z_end));
        if hi - lo < 1e-9 {
            bins[(lo.max(0.0) as usize).min(799)] += d.power_kev_s;
            continue;
        }
        for (k, b) in bins.iter_mut().enumerate() {
            let overlap = (hi.min(k as f64 + 1.0) - lo.max(k as f64)).max(0.0);
            *b += d.power_kev_s * overlap / (hi - lo);
        }
    }
    bins
}

#[test]
fn a_southern_curtain_deposits_downward_as_its_northern_mirror() {
    // The mirror by the dipole's symmetry: the pole 3000 km north of the
    // scene (magnetic latitude 63.0 degrees, B dipping 75.7 degrees
    // north-down), and the pole pi R - 3000 km south, so that its
    // antipode, the other pole, lies 3000 km north (latitude -63.0
    // degrees, B pointing 75.7 degrees up toward the south). Along -B the
    // southern electrons follow the same line as the northern ones along
    // B, on the same random streams: the same deposits up to the rounding
    // of the field's angles. Both deposit at least 95 % of the power
    // entering the atmosphere, every step going down, and their altitude
    // profiles peak within 1 km and differ by under 1 % of their power.
    // (Before, the southern beams climbed out of the atmosphere with 97 %
    // of their power.)
    let run = |pole: [f64; 2]| {
        let mut s: Scene = small_scene();
        s.earth.magnetic_pole = Some(pole);
        // The pole is one a scene file accepts.
        Scene { earth: s.earth.clone(), ..Scene::default() }.validate("globe", None).unwrap();
        let fps = aurora::pipeline::plan::footprints(&s);
        let atm = aurora::pipeline::plan::atmosphere(&s);
        let colour = aurora::pipeline::plan::colour_table(&s, &atm);
        trace_deposits(&s, &fps, &atm, &colour, &NoProgress).unwrap()
    };
    let r = aurora::geometry::earth::MEAN_RADIUS_KM;
    let (north, ns) = run([0.0, 3000.0]);
    let (south, ss) = run([0.0, -(std::f64::consts::PI * r - 3000.0)]);
    for (name, st, deps) in [("north", &ns, &north), ("south", &ss, &south)] {
        assert!(st.power.deposited_fraction >= 0.95, "{name}: {st:?}");
        for c in &st.curtains {
            assert!(c.deposited_fraction >= 0.95, "{name}: {c:?}");
        }
        assert!(deps.iter().flatten().all(|d| d.z_end <= d.z_start), "{name}: a step went up");
    }
    let (pn, ps) = (profile(&north), profile(&south));
    let peak = |p: &[f64]| p.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0 as f64 + 0.5;
    let (zn, zs) = (peak(&pn), peak(&ps));
    eprintln!("peaks: north {zn} km, south {zs} km");
    assert!((zn - zs).abs() <= 1.0, "peaks at {zn} and {zs} km");
    assert!(zn > 90.0 && zn < 150.0, "{zn}");
    let total: f64 = pn.iter().sum();
    let diff: f64 = pn.iter().zip(&ps).map(|(a, b)| (a - b).abs()).sum();
    assert!(diff < 0.01 * total, "profiles differ by {:.3} of the power", diff / total);
}
