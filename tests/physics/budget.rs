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
