//! Every preset reaches the International Brightness Coefficient class its
//! documentation states (`Preset::ibc_class`): its brightest 557.7 nm
//! column along B, the baked `line_5577` grid summed along the field
//! through each voxel-sized bin (`aurora::pipeline::columns`), within 1.5x
//! of the class's 1, 10, 100 or 1000 kR (Chamberlain 1961). The presets
//! bake as they are (their own beams, footprints and voxels): the column
//! is what a user's bake holds.

use aurora::pipeline::bake::bake;
use aurora::pipeline::columns::{brightest_column, ibc_column_r};
use aurora::pipeline::plan::BakePlan;
use aurora::scene::presets::PRESETS;
use aurora::util::progress::NoProgress;

/// The brightest 557.7 nm column of `scene`, R.
pub fn brightest_5577_r(scene: &aurora::scene::Scene) -> f64 {
    let mut s = scene.clone();
    s.grid.lines = vec!["5577".into()];
    let b = bake(&s, &NoProgress).unwrap();
    let plan = BakePlan::new(&s, &NoProgress);
    let g = b.lines.iter().find(|g| g.name == "line_5577").expect("a line_5577 grid");
    brightest_column(g, 100.0, |x, y| plan.field_at([x, y]).b)
}

#[test]
fn every_preset_reaches_its_brightness_class() {
    let mut report = String::new();
    let mut bad = Vec::new();
    for p in PRESETS {
        let Some(class) = p.ibc_class else { continue };
        let column = brightest_5577_r(&(p.build)());
        let want = ibc_column_r(class);
        report += &format!("{:18} IBC {class}: brightest 557.7 nm column {:8.1} kR (class {:6.0} kR)\n", p.name, column / 1e3, want / 1e3);
        if !(column >= want / 1.5 && column <= want * 1.5) {
            bad.push(p.name);
        }
    }
    eprint!("{report}");
    assert!(bad.is_empty(), "outside 1.5x of their class: {bad:?}\n{report}");
}
