//! Throwaway: writes the default scene's footprints as PNGs to /tmp/aur.
fn main() {
    let s = aurora::scene::Scene::load(&std::env::args().nth(1).unwrap_or("default".into())).unwrap();
    for (i, c) in s.curtains.iter().enumerate() {
        let t = std::time::Instant::now();
        let f = aurora::footprint::simulate(c, &s.footprint, s.seed);
        println!("curtain {i}: {:.3} s, area above threshold {:.1} km2", t.elapsed().as_secs_f64(), f.integral_above(s.footprint.threshold));
        f.write_png(std::path::Path::new(&format!("/tmp/aur/fp{i}.png"))).unwrap();
    }
}
