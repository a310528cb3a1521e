//! The bake pipeline (`aurora::pipeline::plan`, `aurora::pipeline::bake`): a beam is the same beam whatever
//! the chunking, and a bake composed from the plan's stages is `aurora
//! bake`'s.

use crate::common::small::small_scene;
use aurora::pipeline::bake;
use aurora::pipeline::bake::stats::StageTimes;
use aurora::pipeline::plan::BakePlan;
use aurora::scene::{BeamStarts, Deposition};
use aurora::util::progress::NoProgress;
use std::time::Instant;

#[test]
fn chunked_tracing_equals_one_call_byte_for_byte() {
    for (starts, deposition) in [(BeamStarts::Stratified, Deposition::Expected), (BeamStarts::Random, Deposition::Sampled)] {
        let mut s = small_scene();
        s.beams.starts = starts;
        s.beams.deposition = deposition;
        let plan = BakePlan::new(&s, &NoProgress);
        let n = s.beams.count;
        let whole = aurora::pipeline::bake::trace::trace(&plan, n, 0, 0..n, &NoProgress).unwrap();
        assert!(whole.photons.len() > 1000, "{}", whole.photons.len());
        // Cuts inside the first curtain, at the curtain boundary (201 of
        // 301 beams go to the first, weight 1 : 0.5), inside the second.
        for cuts in [vec![0, 1, n], vec![0, 100, 201, 250, n], vec![0, 201, n], vec![0, 7, 8, 300, n]] {
            let mut photons = Vec::new();
            let (mut beams, mut electron, mut deposited) = (0, 0.0, 0.0);
            for w in cuts.windows(2) {
                let part = aurora::pipeline::bake::trace::trace(&plan, n, 0, w[0]..w[1], &NoProgress).unwrap();
                beams += part.stats.beams;
                electron += part.stats.power.electron_power_w;
                deposited += part.stats.power.deposited_power_w;
                photons.extend(part.photons);
            }
            assert_eq!(photons.len(), whole.photons.len(), "{starts:?} {cuts:?}");
            let bytes = |p: &[aurora::pipeline::deposit::Photon]| {
                p.iter()
                    .flat_map(|p| {
                        p.position.iter().chain(&p.end).chain(&p.power).flat_map(|x| x.to_bits().to_le_bytes()).collect::<Vec<_>>()
                    })
                    .collect::<Vec<u8>>()
            };
            assert!(bytes(&photons) == bytes(&whole.photons), "{starts:?} {cuts:?}: photons differ");
            assert_eq!(beams, n);
            // The power sums only differ by the order of f64 additions.
            assert!((electron / whole.stats.power.electron_power_w - 1.0).abs() < 1e-12, "{electron}");
            assert!((deposited / whole.stats.power.deposited_power_w - 1.0).abs() < 1e-12, "{deposited}");
        }
        // An empty range traces nothing.
        assert!(aurora::pipeline::bake::trace::trace(&plan, n, 0, 5..5, &NoProgress).unwrap().photons.is_empty());
    }
}

#[test]
fn a_bake_through_the_plan_equals_aurora_bake() {
    let s = small_scene();
    let want = bake::bake(&s, &NoProgress).unwrap();
    // The stages by hand: plan, trace in two chunks, voxel size, gather,
    // finish.
    let plan = BakePlan::new(&s, &NoProgress);
    let n = plan.scene.beams.count;
    let mut photons = aurora::pipeline::bake::trace::trace(&plan, n, 0, 0..150, &NoProgress).unwrap().photons;
    let rest = aurora::pipeline::bake::trace::trace(&plan, n, 0, 150..n, &NoProgress).unwrap();
    photons.extend(rest.photons);
    let (v, source) = plan.voxel_size(&photons);
    assert_eq!((v, source.as_str()), (want.stats.voxel_size_km, want.stats.voxel_size_source.as_str()));
    let emission = aurora::pipeline::bake::gather::gather(&plan, &photons, v, &NoProgress);
    let whole = aurora::pipeline::bake::trace::trace(&plan, n, 0, 0..n, &NoProgress).unwrap();
    assert_eq!(photons, whole.photons);
    let g = aurora::pipeline::bake::gather::Gathered {
        photons,
        lines: Vec::new(),
        beam_stats: whole.stats,
        voxel_km: v,
        voxel_source: source,
        warnings: Vec::new(),
        noise: None,
        velocity: None,
        photon_totals: None,
    };
    let got = aurora::pipeline::bake::finish::finish(&plan, emission, g, StageTimes::default(), Instant::now(), &NoProgress).unwrap();
    assert_eq!(got.emission, want.emission);
    assert_eq!(got.density, want.density);
    assert_eq!(got.photons, want.photons);
    let mut a = got.stats.clone();
    a.times_s = want.stats.times_s.clone();
    assert_eq!(a, want.stats);
    // And the written file's bytes: the same VDB as `aurora bake` writes.
    let opts = aurora::io::bake_folder::write_options(&s);
    let file = |b: &bake::Bake| {
        aurora::io::vdb::write::write_vdb_bytes(
            &[aurora::io::vdb::write::GridRef::Float(&b.density), aurora::io::vdb::write::GridRef::Vec3(&b.emission)],
            &opts,
        )
        .unwrap()
    };
    assert!(file(&got) == file(&want));
}

#[test]
fn a_reused_plan_is_the_fresh_plan() {
    // Frames reuse the plan: only the time changes, so the atmosphere and
    // colour table are kept and the footprints recomputed; a beams edit
    // keeps the footprints. Either way the bake is the fresh plan's.
    let s = small_scene();
    let plan = BakePlan::new(&s, &NoProgress);
    let mut later = s.clone();
    later.animation.time_s += 0.5;
    let mut more = s.clone();
    more.beams.count = 400;
    for t in [later, more] {
        let reused = BakePlan::reusing(&t, &plan, &NoProgress);
        let fresh = BakePlan::new(&t, &NoProgress);
        let (a, _) = bake::bake_reusing(&t, Some(&plan), &NoProgress).unwrap();
        let b = bake::bake_plan(&fresh, Instant::now(), &NoProgress).unwrap();
        assert_eq!(a.emission, b.emission);
        assert_eq!(a.density, b.density);
        assert_eq!(
            reused.footprints.iter().map(|f| f.data.clone()).collect::<Vec<_>>(),
            fresh.footprints.iter().map(|f| f.data.clone()).collect::<Vec<_>>()
        );
    }
}
