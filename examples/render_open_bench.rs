//! The `render --vdb` command's two VDB phases, timed to the microsecond
//! (the command prints them to 10 ms): *open* (map the file, validate every
//! record, locate the leaves: `RenderMedium::open_seconds`) and *build*
//! (decode the chosen grids' records into the medium: `build_seconds`), as
//! `aurora::app::vdb_for_render::read_render_medium` reports them, the wall time of
//! the whole call, and the CPU time of the calling thread over the call
//! (`CLOCK_THREAD_CPUTIME_ID`): the open phase runs on it, the build's
//! parallel loops on rayon's workers, so on a loaded machine it tracks the
//! open phase's work better than its wall time does (it also holds the
//! build's serial steps, the same code before and after a change to the
//! open phase).
//!
//! `cargo run --release --example render_open_bench -- FILE.vdb [RUNS]`
//! prints one line per run (`open_s build_s total_s thread_cpu_s`), then
//! the medians and the load average. Run it twice on a warm page cache
//! (the first run of a freshly written file may read from disk).
//!
//! `... -- --with-unused-copies IN.vdb OUT.vdb` writes OUT: IN's
//! `density` and `emission` plus copies of them named `temperature` and
//! `velocity` (Blosc + active mask, as a bake), a file whose records the
//! renderer checks without using half of them.

mod common;

use std::time::Instant;

/// CPU time of the calling thread, seconds.
fn thread_cpu() -> f64 {
    let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: writes one timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

fn write_copies(input: &str, output: &str) {
    use aurora::io::vdb::write::{write_vdb, GridRef, WriteOptions};
    let f = aurora::io::vdb::read::read_vdb(std::path::Path::new(input)).expect("a readable VDB");
    let d = f.float("density").expect("a density grid").clone();
    let e = f.vec3("emission").expect("an emission grid").clone();
    let mut t = d.clone();
    t.name = "temperature".into();
    let mut v = e.clone();
    v.name = "velocity".into();
    let opts = WriteOptions { compression: aurora::scene::Compression::BloscActiveMask, ..WriteOptions::default() };
    let grids = [GridRef::Float(&d), GridRef::Vec3(&e), GridRef::Float(&t), GridRef::Vec3(&v)];
    write_vdb(std::path::Path::new(output), &grids, &opts).expect("written");
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() == 4 && args[1] == "--with-unused-copies" {
        return write_copies(&args[2], &args[3]);
    }
    let Some(path) = args.get(1) else {
        eprintln!("usage: render_open_bench FILE.vdb [RUNS]");
        std::process::exit(2);
    };
    let runs: usize = args.get(2).map_or(5, |s| s.parse().expect("RUNS is a count"));
    let (mut open, mut build, mut total, mut cpu) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..runs {
        let c = thread_cpu();
        let t = Instant::now();
        let m = aurora::app::vdb_for_render::read_render_medium(std::path::Path::new(path), 1.0, 1.0)
            .expect("the file renders")
            .expect("the records path applies to this file");
        let wall = t.elapsed().as_secs_f64();
        let c = thread_cpu() - c;
        drop(m.medium);
        println!("{:.6} {:.6} {:.6} {:.6}", m.open_seconds, m.build_seconds, wall, c);
        open.push(m.open_seconds);
        build.push(m.build_seconds);
        total.push(wall);
        cpu.push(c);
    }
    println!(
        "median open {:.6} s, build {:.6} s, total {:.6} s, thread CPU {:.6} s over {runs} runs; load average {}",
        median(&mut open),
        median(&mut build),
        median(&mut total),
        median(&mut cpu),
        common::loadavg()
    );
}
