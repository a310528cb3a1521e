//! Prints the bake's expected peak memory for a scene file and thread
//! count (`aurora::pipeline::memory::expected::expected_peak`, from a traced
//! sample of its beams) beside the memory budget's bound: the terms of the
//! peaking phase on stderr, then `bound expected` in bytes on stdout.
//! `benchmarks/memory/expected.sh` sets both against the bake's measured
//! peak.
//!
//!     cargo run --release --example memory_expected -- SCENE.toml [THREADS]

use aurora::pipeline::bake::{self, stats::StageTimes};
use aurora::pipeline::plan::BakePlan;
use aurora::util::progress::NoProgress;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("usage: memory_expected SCENE.toml [THREADS]");
    let threads: usize = args.next().map_or(2, |t| t.parse().expect("THREADS is a number"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let scene = aurora::scene::Scene::from_toml_str(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
    pool.install(|| {
        let plan = BakePlan::new(&scene, &NoProgress);
        let bound = aurora::pipeline::memory::budget::estimate(&plan, aurora::pipeline::memory::budget::LeafCount::Bands).total();
        let (count, _, _) = bake::beam_count(&plan, &mut StageTimes::default(), &NoProgress).unwrap_or_else(|e| panic!("{e}"));
        let t = std::time::Instant::now();
        let e = aurora::pipeline::memory::expected::expected_peak(&plan, count, threads).unwrap_or_else(|e| panic!("{e}"));
        eprintln!(
            "expected peak {:.3} GiB ({} phase, {} threads, {:.0} leaves, {:.3e} photons, {} of {count} beams traced in {:.2} s{})",
            e.bytes / (1u64 << 30) as f64,
            e.phase,
            e.threads,
            e.leaves,
            e.photons,
            e.sample_beams,
            t.elapsed().as_secs_f64(),
            if e.chunked { ", in chunks" } else { "" }
        );
        for term in &e.terms {
            eprintln!("  {:32} {:9.3} GiB", term.what, term.bytes / (1u64 << 30) as f64);
        }
        println!("{bound:.0} {:.0}", e.bytes);
    });
}
