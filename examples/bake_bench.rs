//! Bake timing: bakes each scene given (preset name or TOML path; default
//! `default`) once and prints per-stage wall times and the bake's counts.
//! Speed is measured here, never in a unit test.
//!
//! cargo run --release --example bake_bench -- default seed2014
fn main() {
    let mut names: Vec<String> = std::env::args().skip(1).collect();
    if names.is_empty() {
        names.push("default".into());
    }
    println!("threads: {}", rayon::current_num_threads());
    for name in names {
        let scene = match aurora::scene::Scene::load(&name) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        let b = match aurora::pipeline::bake::bake(&scene, &aurora::util::progress::NoProgress) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(1);
            }
        };
        let s = &b.stats;
        let t = &s.times_s;
        println!(
            "{name}: total {:.2} s (footprints {:.2}, beams {:.2}, gather {:.2}, density {:.2}); {} beams, {} photons, {} active voxels, {} leaves, voxel {} km; peak emission {:?} kR/km (Y {:.3}); electron power {:.3e} W, deposited {:.3e} W",
            t.total, t.footprints, t.beams, t.gather, t.density, s.beams, s.photons, s.active_voxels, s.leaves,
            s.voxel_size_km, s.peak_emission, s.peak_luminance, s.electron_power_w, s.deposited_power_w
        );
    }
}
