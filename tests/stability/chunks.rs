//! A bake traced and gathered a chunk of beams at a time
//! (`aurora::pipeline::bake::chunked`) is the bake of all its beams at
//! once, byte for byte: the grids, the stats and the VDB file, for chunk
//! sizes that cut a curtain's beams anywhere, with the per-line grids, the
//! velocity, the red trail and the automatic voxel size (whose distance
//! pass traces the chunks twice), and for both summing gathers.

use crate::common::small::small_scene;
use aurora::pipeline::bake;
use aurora::pipeline::plan::BakePlan;
use aurora::scene::{AutoTag, ColourMode, GatherMethod, Scene, VoxelSize};
use aurora::util::progress::NoProgress;
use std::time::Instant;

fn vdb_bytes(s: &Scene, b: &bake::Bake) -> Vec<u8> {
    use aurora::io::vdb::write::{write_vdb_bytes, GridRef};
    let mut grids = vec![GridRef::Float(&b.density), GridRef::Vec3(&b.emission)];
    // The velocity is compared as a grid: the small scene's overflows the
    // half floats the file would store it in.
    grids.extend(b.lines.iter().map(GridRef::Float));
    let mut without_v = s.clone();
    without_v.grid.velocity = false;
    write_vdb_bytes(&grids, &aurora::io::bake_folder::write_options(&without_v)).unwrap()
}

/// Bakes `s` with `chunk` beams a chunk.
fn bake_in_chunks(s: &Scene, chunk: usize) -> bake::Bake {
    let mut plan = BakePlan::new(s, &NoProgress);
    plan.beam_chunk = chunk;
    bake::bake_plan(&plan, Instant::now(), &NoProgress).unwrap()
}

fn assert_same(s: &Scene, chunks: &[usize]) {
    let whole = bake_in_chunks(s, usize::MAX);
    assert!(whole.stats.photons > 1000, "{}", whole.stats.photons);
    for &c in chunks {
        assert!(c < s.beams.count);
        let got = bake_in_chunks(s, c);
        assert_eq!(got.emission, whole.emission, "chunk {c}");
        assert_eq!(got.density, whole.density, "chunk {c}");
        assert_eq!(got.lines, whole.lines, "chunk {c}");
        assert_eq!(got.velocity, whole.velocity, "chunk {c}");
        let mut stats = got.stats.clone();
        stats.times_s = whole.stats.times_s.clone();
        assert_eq!(stats, whole.stats, "chunk {c}");
        assert!(vdb_bytes(s, &got) == vdb_bytes(s, &whole), "chunk {c}: the files differ");
        // A chunked bake keeps no photons: its memory is the chunk's.
        assert!(got.photons.is_empty());
    }
}

#[test]
fn a_bake_in_chunks_is_the_whole_bake_byte_for_byte() {
    let s = small_scene();
    // 301 beams over two curtains with unequal weights: chunks of 7 cut
    // both curtains mid-way, 150 near their boundary, 299 leaves one beam.
    assert_same(&s, &[7, 150, 299]);
}

#[test]
fn lines_velocity_trail_and_auto_voxels_in_chunks_are_the_whole_bake() {
    let mut s = small_scene();
    s.colour.mode = ColourMode::Physical;
    // Four lines: two gathers of three and one.
    s.grid.lines = aurora::physics::emission::line_table::LINE_KEYS[..4].iter().map(|k| k.to_string()).collect();
    s.grid.velocity = true;
    s.animation.trail_samples = 2;
    s.grid.voxel_size = VoxelSize::Auto(AutoTag::Auto);
    assert_same(&s, &[64]);
}

#[test]
fn a_kdtree_bake_in_chunks_is_the_whole_bake() {
    let mut s = small_scene();
    s.photons.gather = GatherMethod::Kdtree;
    assert_same(&s, &[100]);
}
