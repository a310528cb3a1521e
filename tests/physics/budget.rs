//! The memory budget (`aurora::pipeline::memory_budget`) bounds what a real bake makes: the
//! leaves below the beams' highest start lie in its world box, the leaves
//! above (the columns over the starts, which reach far above `beams.top_km`
//! with Fang's depositions) are no more than its column bound, and its
//! photon term counts at least the photons the bake holds.

use crate::common::small::small_scene;
use aurora::pipeline::bake;
use aurora::pipeline::deposit::Photon;
use aurora::pipeline::memory_budget;
use aurora::scene::{Deposition, KernelRadius};
use aurora::util::progress::NoProgress;

#[test]
fn a_bake_stays_inside_the_budget_bounds() {
    for deposition in [Deposition::Expected, Deposition::Sampled, Deposition::Csda] {
        let mut s = small_scene();
        s.beams.deposition = deposition;
        let b = bake::bake(&s, &NoProgress).unwrap();
        let g = &b.emission;
        let t = g.transform;
        let reach = KernelRadius::of(&s.photons).max_reach_km(s.photons.cutoff);
        let slack = reach + t.voxel_size;
        let (lo, hi) = memory_budget::world_bounds(&s);
        let start_top = s.beams.top_km + s.beams.top_noise_km;
        let top = s.curtains.iter().map(|c| memory_budget::deposit_top_km(&s, c)).fold(0.0, f64::max);
        let mut above = std::collections::BTreeSet::new();
        let mut highest = f64::NEG_INFINITY;
        for (ijk, _) in g.iter_active() {
            let p = t.index_to_world(ijk.as_dvec3());
            highest = highest.max(p.z);
            assert!(p.z <= top + slack, "{deposition:?}: a voxel at {:.1} km, the deposits' top {top:.1} km", p.z);
            if p.z <= start_top + slack {
                for i in 0..2 {
                    assert!(
                        p[i] >= lo[i] - slack && p[i] <= hi[i] + slack,
                        "{deposition:?}: voxel {p:?} outside the world box {lo:?}..{hi:?}"
                    );
                }
            } else {
                above.insert(ijk.to_array().map(|c| c.div_euclid(8)));
            }
        }
        let leaf_km = 8.0 * t.voxel_size;
        let bound = memory_budget::column_leaves(&s, leaf_km, reach);
        assert!(above.len() as f64 <= bound, "{deposition:?}: {} leaves above the starts, bound {bound}", above.len());
        if deposition == Deposition::Csda {
            assert!(above.is_empty(), "csda deposits nothing above the starts: highest voxel {highest:.1} km");
        } else {
            // The columns are really there, so the bounds above were tested.
            assert!(highest > start_top + 50.0, "{deposition:?}: highest voxel {highest:.1} km, starts at most {start_top} km");
            assert!(!above.is_empty());
        }
        let e = memory_budget::estimate(&s);
        let term = e.terms.iter().find(|t| t.what == "photons").unwrap();
        let held = 3.0 * (b.photons.len() * std::mem::size_of::<Photon>()) as f64;
        assert!(
            held <= term.bytes,
            "{deposition:?}: {} photons held, the budget counts {}",
            b.photons.len(),
            term.bytes / 3.0 / std::mem::size_of::<Photon>() as f64
        );
    }
}

/// The pole's ground distance north of the origin that gives the dipole's
/// field a dip of `dip_deg` there: magnetic latitude `atan(tan(I) / 2)`,
/// 90 degrees less the central angle to the pole.
fn pole_for_dip(dip_deg: f64, radius_km: f64) -> [f64; 2] {
    let lat = (dip_deg.to_radians().tan() / 2.0).atan();
    [0.0, (std::f64::consts::FRAC_PI_2 - lat) * radius_km]
}

#[test]
fn the_photon_estimate_follows_the_field_dip() {
    // With a shallower field each beam takes more steps to descend: at a
    // dip of 12 degrees some 4.5 times the 78 degrees' (sin 78 / sin 12),
    // where the estimate once counted 1 / beams.dt steps whatever the dip.
    // The estimate is Wald's bound on the expected steps to descend from
    // the highest start (top_km + top_noise_km) to where the spectrum's
    // deposition is complete, plus four standard deviations of the sum,
    // and the columns above the starts: above the count by the start
    // noise (at most 12 km of some 180 km descent, 7 %), the last step's
    // overshoot and the margin, so within 15 % of it at every dip (measured:
    // 4.9 % at 78 degrees, 6.7 % at 12); and the
    // grid's leaves stay within its bound.
    for dip in [78.0, 45.0, 25.0, 12.0] {
        let mut s = small_scene();
        s.atmosphere.model = aurora::scene::AtmosphereModel::Us1976;
        if dip < 78.0 {
            s.earth.magnetic_pole = Some(pole_for_dip(dip, s.earth.radius_km));
        }
        let b = bake::bake(&s, &NoProgress).unwrap();
        let e = memory_budget::estimate(&s);
        let term = e.terms.iter().find(|t| t.what == "photons").unwrap();
        let counted = term.bytes / 3.0 / std::mem::size_of::<Photon>() as f64;
        let held = b.photons.len() as f64;
        let grids = e.terms.iter().find(|t| t.what == "grids").unwrap();
        let leaves = b.emission.leaf_count() as f64;
        let bound = grids.bytes / 1.3 / (512.0 * 16.0 + 192.0);
        eprintln!("dip {dip}: {held} photons, estimate {counted:.0} ({:.3}); {leaves} leaves, bound {bound:.0}", counted / held);
        assert!(counted >= held && counted <= 1.15 * held, "dip {dip}: {held} photons, the estimate counts {counted:.0}");
        assert!(leaves <= bound, "dip {dip}: {leaves} leaves, bound {bound:.0}");
    }
}
