//! The memory budget (`aurora::pipeline::memory::budget`) bounds what a real bake makes: the
//! leaves below the beams' highest start lie in its world box, the leaves
//! above (the columns over the starts, which reach far above `beams.top_km`
//! with Fang's depositions) are no more than its column bound, and its
//! photon term counts at least the photons the bake holds.

use crate::common::small::small_scene;
use aurora::pipeline::bake;
use aurora::pipeline::deposit::Photon;
use aurora::pipeline::memory::budget::{self, LeafCount};
use aurora::pipeline::memory::reach;
use aurora::pipeline::plan::BakePlan;
use aurora::scene::{Deposition, KernelRadius};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;

#[test]
fn a_bake_stays_inside_the_budget_bounds() {
    for deposition in [Deposition::Expected, Deposition::Sampled, Deposition::Csda] {
        let mut s = small_scene();
        s.beams.deposition = deposition;
        let b = bake::bake(&s, &NoProgress).unwrap();
        let plan = BakePlan::new(&s, &NoProgress);
        let g = &b.emission;
        let t = g.transform;
        let reach = KernelRadius::of(&s.photons).max_reach_km(s.photons.cutoff);
        let slack = reach + t.voxel_size;
        let (lo, hi) = reach::world_bounds(&plan);
        let start_top = s.beams.top_km + s.beams.top_noise_km;
        let top = s.curtains.iter().map(|c| reach::deposit_top_km(&plan, c)).fold(0.0, f64::max);
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
        let bound = reach::column_leaves(&plan, leaf_km, reach);
        assert!(above.len() as f64 <= bound, "{deposition:?}: {} leaves above the starts, bound {bound}", above.len());
        if deposition == Deposition::Csda {
            assert!(above.is_empty(), "csda deposits nothing above the starts: highest voxel {highest:.1} km");
        } else {
            // The columns are really there, so the bounds above were tested.
            assert!(highest > start_top + 50.0, "{deposition:?}: highest voxel {highest:.1} km, starts at most {start_top} km");
            assert!(!above.is_empty());
        }
        let e = budget::estimate(&plan, LeafCount::Bands);
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

/// The pole's ground distance north of the origin that gives the dipole's
/// field a dip of `dip_deg` there: magnetic latitude `atan(tan(I) / 2)`,
/// 90 degrees less the central angle to the pole.
fn pole_for_dip(dip_deg: f64, radius_km: f64) -> [f64; 2] {
    let lat = fmath::atan(fmath::tan(dip_deg.to_radians()) / 2.0);
    [0.0, (std::f64::consts::FRAC_PI_2 - lat) * radius_km]
}

#[test]
fn the_photon_estimate_follows_the_field_dip() {
    // With a shallower field each beam takes more steps to descend: at a
    // dip of 12 degrees some 4.5 times the 78 degrees' (sin 78 / sin 12),
    // where the estimate once counted 1 / beams.dt steps whatever the dip.
    // The estimate is Wald's bound on the expected steps to descend from
    // the highest start (top_km + top_noise_km) to where the spectrum's
    // deposition is complete, plus four standard deviations of the sum,
    // and the columns above the starts: above the count by the start
    // noise (at most 12 km of some 180 km descent, 7 %), the last step's
    // overshoot and the margin, so within 15 % of it at every dip (measured:
    // 4.9 % at 78 degrees, 6.7 % at 12); and the
    // grid's leaves stay within its bound.
    for dip in [78.0, 45.0, 25.0, 12.0] {
        let mut s = small_scene();
        s.atmosphere.model = aurora::scene::AtmosphereModel::Us1976;
        if dip < 78.0 {
            s.earth.magnetic_pole = Some(pole_for_dip(dip, s.earth.radius_km));
        }
        let b = bake::bake(&s, &NoProgress).unwrap();
        let plan = BakePlan::new(&s, &NoProgress);
        let e = budget::estimate(&plan, LeafCount::Bands);
        let term = e.terms.iter().find(|t| t.what == "photons").unwrap();
        let per_photon = budget::bytes_per_held_photon(s.photons.gather);
        let counted = term.bytes / per_photon;
        let held = b.photons.len() as f64;
        let leaves = b.emission.leaf_count() as f64;
        let reach = KernelRadius::of(&s.photons).max_reach_km(s.photons.cutoff);
        let bound = budget::grid_leaves(&plan, b.stats.voxel_size_km, reach, LeafCount::Bands);
        eprintln!("dip {dip}: {held} photons, estimate {counted:.0} ({:.3}); {leaves} leaves, bound {bound:.0}", counted / held);
        assert!(counted >= held && counted <= 1.15 * held, "dip {dip}: {held} photons, the estimate counts {counted:.0}");
        assert!(leaves <= bound, "dip {dip}: {leaves} leaves, bound {bound:.0}");
    }
}

/// `s` with `key` (a dotted `table.name`) set to `value` as a scene file
/// writes it, read back through TOML.
fn with_key(s: &aurora::scene::Scene, key: &str, value: &str) -> aurora::scene::Scene {
    let mut doc: toml::Table = s.to_toml().parse().unwrap();
    let (table, name) = key.split_once('.').unwrap();
    let v: toml::Table = format!("v = {value}").parse().unwrap_or_else(|e| panic!("{key} = {value}: {e}"));
    doc.get_mut(table).and_then(|t| t.as_table_mut()).unwrap().insert(name.to_string(), v["v"].clone());
    aurora::scene::Scene::from_toml_str(&toml::to_string(&doc).unwrap(), "suggested.toml").unwrap()
}

#[test]
fn each_suggested_change_fits_and_none_goes_the_wrong_way() {
    // Scenes far over an 8 GiB limit, each for a different reason: every
    // change the refusal suggests, written into the scene file alone, gives
    // a scene the budget accepts, and moves its key the way that shrinks
    // the bake (fewer beams, longer steps, larger voxels, a smaller
    // kernel, a coarser footprint, fewer lines or trail samples). A
    // steeper field's longer beams are counted too.
    use aurora::pipeline::memory::refusal::check;
    use aurora::scene::{Scene, VoxelSize};
    let limit = aurora::util::memory::MemoryLimit { bytes: 8.0 * (1u64 << 30) as f64, source: "test" };
    let mut scenes: Vec<(&str, Scene)> = Vec::new();
    // A bake in chunks holds one chunk's photons whatever the count, but
    // with the automatic voxel size every photon's distance from the camera.
    let mut s = Scene::default();
    s.beams.count = 20_000_000;
    s.grid.voxel_size = VoxelSize::Auto(aurora::scene::AutoTag::Auto);
    scenes.push(("many beams", s));
    let mut s = Scene::default();
    s.grid.voxel_size = VoxelSize::Km(0.02);
    scenes.push(("small voxels", s));
    let mut s = Scene::default();
    s.beams.dt = 2e-5;
    s.beams.count = 40_000;
    scenes.push(("short steps", s));
    let mut s = Scene::default();
    s.photons.radius_km = 30.0;
    scenes.push(("wide kernel", s));
    let mut s = Scene::default();
    // 160 km straight curtains: one change alone must be able to bring it under.
    for c in &mut s.curtains {
        c.path = None;
        c.length = 160.0;
    }
    s.beams.count = 400_000;
    s.earth.magnetic_pole = Some(pole_for_dip(12.0, s.earth.radius_km));
    s.grid.lines = aurora::physics::emission::line_table::LINE_KEYS.iter().map(|k| k.to_string()).collect();
    s.animation.trail_samples = 4;
    scenes.push(("shallow field, lines and trail", s));
    for (name, s) in scenes {
        s.validate(name, None).unwrap();
        let e = check(&BakePlan::new(&s, &NoProgress), &limit).expect_err(name);
        let m = e.to_string();
        assert!(!e.suggestions.is_empty(), "{name}: {m}");
        assert!(m.contains("80 %") && m.contains("each of these changes alone brings it under"), "{name}: {m}");
        eprintln!("{name}: {m}");
        for sg in &e.suggestions {
            let t = with_key(&s, &sg.key, &sg.to);
            let fits = check(&BakePlan::new(&t, &NoProgress), &limit);
            assert!(fits.is_ok(), "{name}: {} = {} does not fit: {}", sg.key, sg.to, fits.unwrap_err());
            let ok = match sg.key.as_str() {
                "beams.count" => t.beams.count < s.beams.count,
                "beams.dt" => t.beams.dt > s.beams.dt,
                "grid.voxel_size" => voxel_km(&t) > voxel_km(&s),
                "photons.radius_km" => t.photons.radius_km < s.photons.radius_km,
                "footprint.resolution" => t.footprint.resolution[0] < s.footprint.resolution[0],
                "grid.lines" => t.grid.lines.len() < s.grid.lines.len(),
                "animation.trail_samples" => t.animation.trail_samples < s.animation.trail_samples,
                k => panic!("{name}: an unexpected key {k}"),
            };
            assert!(ok, "{name}: {} goes the wrong way: {} to {}", sg.key, sg.from, sg.to);
        }
    }
}

/// The voxel size the budget takes for `s`: its own, or the automatic
/// one's floor.
fn voxel_km(s: &aurora::scene::Scene) -> f64 {
    s.voxel_size_km().unwrap_or_else(|| KernelRadius::of(&s.photons).auto_voxel_floor_km())
}

#[test]
fn the_grid_term_counts_the_leaves_of_the_bands_near_what_a_bake_holds() {
    // The bands (the beams' own starts along their field lines, dilated
    // by the reach and the walk's spread) hold every leaf the bake makes,
    // and on the small scene's 1 km voxels not many more: the walk's
    // four-standard-deviation spread widens a band by some 4 km each side
    // of curtains 14-16 km wide (measured 2.5x with Fang's depositions,
    // 4.0x with CSDA's shorter beams, whose bound runs to the longest
    // path), under a third of the bounding boxes' bound (8.7x and 14.9x).
    for deposition in [Deposition::Expected, Deposition::Csda] {
        let mut s = small_scene();
        s.beams.deposition = deposition;
        // The thin sheets and the 2014 walk these figures were measured on
        // (an arc's 8 km body fills most of a 14 km box: its bands are
        // near the box, as they should be).
        (s.footprint.sheet_thickness_km, s.footprint.glow) = (0.5, 0.2);
        (s.beams.alpha_d_deg, s.beams.delta_alpha_deg) = (5.0, 3.0);
        let b = bake::bake(&s, &NoProgress).unwrap();
        let plan = BakePlan::new(&s, &NoProgress);
        let reach = KernelRadius::of(&s.photons).max_reach_km(s.photons.cutoff);
        let bound = budget::grid_leaves(&plan, b.stats.voxel_size_km, reach, LeafCount::Bands);
        let leaves = b.emission.leaf_count() as f64;
        let old = budget::box_leaves(&plan, 8.0 * b.stats.voxel_size_km, reach + b.stats.voxel_size_km);
        eprintln!("{deposition:?}: {leaves} leaves, bands {bound}, boxes {old}");
        assert!(leaves <= bound && bound <= 4.5 * leaves, "{deposition:?}: {leaves} leaves, bound {bound}");
        assert!(bound <= 0.33 * old, "{deposition:?}: bands {bound}, boxes {old}");
    }
}

#[test]
fn a_bake_in_chunks_counts_one_chunk_of_photons_and_what_stays_per_beam() {
    let s = small_scene();
    let plan = BakePlan::new(&s, &NoProgress);
    // The plan of a scene like `s`, traced and gathered 50 beams at a time.
    let chunked = |t: &aurora::scene::Scene| {
        let mut p = BakePlan::reusing(t, &plan, &NoProgress);
        p.beam_chunk = 50;
        p
    };
    let term = |s: &aurora::scene::Scene, what: &str| {
        budget::estimate(&chunked(s), LeafCount::Bands).terms.iter().find(|t| t.what == what).map(|t| t.bytes)
    };
    // 301 beams in chunks of 50: the photons and candidates of 50 beams,
    // the same for ten times the beams.
    let mut whole50 = s.clone();
    whole50.beams.count = 50;
    let mut more = s.clone();
    more.beams.count = 3010;
    for what in ["photons", "candidate leaves"] {
        assert_eq!(term(&s, what), term(&whole50, what), "{what}");
        assert_eq!(term(&more, what), term(&s, what), "{what}");
    }
    assert!(chunked(&s).is_chunked(s.beams.count) && !chunked(&whole50).is_chunked(whole50.beams.count));
    // What grows with the beams in chunks: the automatic voxel size's
    // distances (8 bytes a photon) and the velocity's 12 bytes a beam.
    let mut auto = more.clone();
    auto.grid.voxel_size = aurora::scene::VoxelSize::Auto(aurora::scene::AutoTag::Auto);
    let d = term(&auto, "photon distances").expect("a distances term");
    let steps = reach::photons_of_steps(&chunked(&auto), 3010.0);
    assert!(d >= 8.0 * steps, "{d} for {steps} step photons");
    assert_eq!(term(&more, "photon distances"), None);
    let mut v = more.clone();
    v.grid.velocity = true;
    let mut v2 = v.clone();
    v2.beams.count = 2 * 3010;
    // Its grids (two colour grids a leaf, as many leaves as the emission's
    // colour grid under the physical air) follow the leaves, which the
    // beams' own starts widen; the rest grows by 12 bytes a beam.
    assert_eq!(v.grid.density_a, 0.0);
    let grids = |s: &aurora::scene::Scene| term(s, "grids").unwrap();
    let grow = term(&v2, "velocity").unwrap() - term(&v, "velocity").unwrap() - 2.0 * (grids(&v2) - grids(&v));
    assert!((grow - 12.0 * 3010.0).abs() < 1e-3, "{grow}");
}

#[test]
fn over_a_site_the_budget_reads_the_field_the_beams_follow() {
    // The small scene over Tromso, whose own field (20 degrees) IGRF-14
    // replaces: the budget's dip is IGRF's where the beams start (78.5
    // degrees at the site, computed here from the model; the curtains lie
    // within 30 km of it, where it differs by under 0.5 degree), and the
    // bands, which take IGRF's turn between each start and its column,
    // hold every leaf the bake makes.
    let mut s = small_scene();
    s.site = Some(aurora::scene::presets::sites::tromso_site());
    s.earth.radius_km = aurora::geometry::earth::MEAN_RADIUS_KM;
    s.beams.b_inclination_deg = 20.0;
    (s.footprint.sheet_thickness_km, s.footprint.glow) = (0.5, 0.2);
    (s.beams.alpha_d_deg, s.beams.delta_alpha_deg) = (5.0, 3.0);
    let p = s.site.clone().unwrap();
    let site = aurora::geometry::astronomy::site::Site::new(p.latitude_deg, p.longitude_deg, p.height_km).unwrap();
    let igrf = aurora::physics::igrf::Igrf::at(aurora::geometry::astronomy::time::Utc::parse_rfc3339(&p.utc).unwrap()).unwrap();
    let [e, n, u] = site.basis();
    let bf = igrf.field_itrs(site.itrs_km() + s.beams.top_km * u);
    let want = fmath::atan2(-bf.dot(u), fmath::hypot(bf.dot(e), bf.dot(n))).to_degrees();
    let plan = BakePlan::new(&s, &NoProgress);
    let dip = reach::dip_deg(&plan);
    assert!((dip - want).abs() < 0.5, "the budget's dip {dip}, IGRF's {want}");
    let b = bake::bake(&s, &NoProgress).unwrap();
    let r = KernelRadius::of(&s.photons).max_reach_km(s.photons.cutoff);
    let bound = budget::grid_leaves(&plan, b.stats.voxel_size_km, r, LeafCount::Bands);
    let leaves = b.emission.leaf_count() as f64;
    eprintln!("over a site: dip {dip:.3} (IGRF {want:.3}), {leaves} leaves, bands {bound}");
    assert!(leaves <= bound && bound <= 4.5 * leaves, "{leaves} leaves, bound {bound}");
}
