//! Prints the memory budget's estimate of a bake of a scene file, term by
//! term on stderr and the total in bytes on stdout (the estimate `aurora
//! bake` checks, from the plan it would run:
//! `aurora::pipeline::memory::budget::estimate`). `benchmarks/memory/budget.sh`
//! sets it against the bake's measured peak.
//!
//!     cargo run --release --example memory_estimate -- SCENE.toml

fn main() {
    let path = std::env::args().nth(1).expect("usage: memory_estimate SCENE.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let scene = aurora::scene::Scene::from_toml_str(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    let plan = aurora::pipeline::plan::BakePlan::new(&scene, &aurora::util::progress::NoProgress);
    let e = aurora::pipeline::memory::budget::estimate(&plan, aurora::pipeline::memory::budget::LeafCount::Bands);
    for t in &e.terms {
        eprintln!("{:18} {:9.3} GiB  ({} = {})", t.what, t.bytes / (1u64 << 30) as f64, t.key, t.value);
    }
    println!("{:.0}", e.total());
}
