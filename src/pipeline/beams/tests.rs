use super::*;
use crate::util::fmath;

/// A small scene: one short curtain, few beams.
fn small_scene(count: usize) -> Scene {
    let mut s = crate::scene::presets::small_test_scene();
    s.beams.count = count;
    s
}

#[test]
fn stratified_beam_i_is_the_same_whatever_the_count_and_threads() {
    // Beam i's start, energy and path depend on (seed, curtain, i) only:
    // its photons are the same in a bake of N and of 2N beams (their
    // power scales by N / 2N: each beam carries P / N), and the whole
    // photon list is the same for 1 and 3 threads.
    let s1 = small_scene(300);
    let s2 = small_scene(600);
    let fps = crate::pipeline::plan::footprints(&s1);
    let atm = Atmosphere::us1976();
    let colour = crate::pipeline::plan::colour_table(&s1, &atm);
    let run = |s: &Scene, threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| trace_all(s, &fps, &atm, &colour, &crate::util::progress::NoProgress).unwrap().0)
    };
    let (a, b) = (run(&s1, 1), run(&s2, 3));
    assert_eq!(a, run(&s1, 3));
    // The first 300 beams of the 600 come first in the list.
    assert!(b.len() > a.len());
    for (p, q) in a.iter().zip(&b) {
        assert_eq!((p.position, p.end), (q.position, q.end));
        for k in 0..3 {
            // P/N halves exactly in binary, up to the f32 rounding of
            // the product.
            assert!((p.power[k] - 2.0 * q.power[k]).abs() <= 2e-7 * p.power[k].abs(), "{p:?} {q:?}");
        }
    }
}

#[test]
fn the_drawn_starts_are_where_the_traced_beams_begin() {
    // CSDA beams (no column above the start) on a flat ground (scene
    // frame = footprint frame): each beam's first photon begins at its
    // drawn start, to the photons' f32 precision.
    let mut s = small_scene(300);
    s.beams.deposition = Deposition::Csda;
    s.earth.radius_km = 0.0;
    let fps = crate::pipeline::plan::footprints(&s);
    let atm = Atmosphere::us1976();
    let colour = crate::pipeline::plan::colour_table(&s, &atm);
    let params = TraceParams::of(&s, &fps, &atm, &colour, None);
    let t = trace_range(&params, 300, 0, 0..300, false, &crate::util::progress::NoProgress).unwrap();
    let starts: Vec<DVec3> = start_positions(&params, 300).concat();
    assert_eq!(starts.len(), t.beam_photons.len());
    let mut first = 0usize;
    let mut checked = 0;
    for (start, &n) in starts.iter().zip(&t.beam_photons) {
        if n > 0 {
            let p = crate::pipeline::deposit::pos(&t.photons[first]);
            assert!((p - *start).length() < 1e-3 * start.length().max(1.0) * 1e-2, "{p} against {start}");
            checked += 1;
        }
        first += n as usize;
    }
    assert!(checked > 250, "{checked} beams with photons");
}

#[test]
fn steps_are_segments_and_the_point_kernel_collapses_them() {
    let mut s = small_scene(50);
    let fps = crate::pipeline::plan::footprints(&s);
    let atm = Atmosphere::us1976();
    let colour = crate::pipeline::plan::colour_table(&s, &atm);
    let (seg, _) = trace_all(&s, &fps, &atm, &colour, &crate::util::progress::NoProgress).unwrap();
    assert!(seg.iter().filter(|p| !p.is_point()).count() > seg.len() / 2);
    // Consecutive steps of a beam chain: one ends where the next starts
    // (except across beams, and after a step that deposited nothing).
    let chained = seg.windows(2).filter(|w| w[0].end == w[1].position).count();
    assert!(chained as f64 > 0.9 * seg.len() as f64, "{chained} of {}", seg.len());
    s.photons.kernel = KernelShape::Point;
    let (pts, _) = trace_all(&s, &fps, &atm, &colour, &crate::util::progress::NoProgress).unwrap();
    assert_eq!(pts.len(), seg.len());
    for (p, q) in pts.iter().zip(&seg) {
        assert!(p.is_point() && p.position == q.end && p.power == q.power);
    }
}

#[test]
fn gamma3_has_the_right_mean_and_variance() {
    // Gamma(3, E0): mean 3 E0, variance 3 E0^2. Sample mean of N = 1e5 has
    // sigma = sqrt(3) E0 / sqrt(N); allow 5 sigma.
    let mut r = rng::rng(&[5]);
    let n = 100_000;
    let maxwellian = crate::physics::deposition::spectrum::Spectrum::Maxwellian { e0_kev: 2.0 };
    let xs: Vec<f64> = (0..n).map(|_| maxwellian.sample_energy(&mut r)).collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    assert!((mean - 6.0).abs() < 5.0 * 3f64.sqrt() * 2.0 / (n as f64).sqrt(), "{mean}");
    // Sample variance: relative sigma sqrt((kurtosis - 1) / N) with
    // kurtosis 3 + 6/3 = 5 for Gamma(3): 0.0063; 5 sigma = 3.2 %.
    let var = xs.iter().map(|x| fmath::powi(x - mean, 2)).sum::<f64>() / n as f64;
    assert!((var / 12.0 - 1.0).abs() < 0.032, "{var}");
}

#[test]
fn apportion_is_exact_and_proportional() {
    assert_eq!(apportion(10, &[1.0, 1.0, 1.0]), vec![4, 3, 3]);
    assert_eq!(apportion(7, &[0.0, 2.0, 1.0]).iter().sum::<usize>(), 7);
    assert_eq!(apportion(7, &[0.0, 2.0, 1.0])[0], 0);
    assert_eq!(apportion(100, &[3.0, 1.0]), vec![75, 25]);
}
