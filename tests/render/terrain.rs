//! Terrain lit by the aurora (emissive shadow rays), heightfield tracing and
//! the OBJ export, against closed forms, brute force and Blender.

use crate::common::oracle::*;
use crate::common::{python, scratch_file, venv_python};
use aurora::grid::Transform;
use aurora::render::terrain::{intersect_triangle, procedural_cells, write_obj, Heightfield};
use aurora::render::{render, Image, RenderSettings, Volume};
use aurora::scene::{Terrain, TerrainKind};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;
use glam::{DVec3, IVec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::f64::consts::PI;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    scratch_file("terrain", name)
}

// ------------------------------------------------------------ the slab
//
// A slab of voxels x, y in -M..=M, z in Z0..Z0+NZ-1 (h = 1 km, no offset), over
// the ground plane z = 0. Its emission profile is `e s(y)` with
// `s = f(x) f(y) g(z)`: f, g are 1 on the voxel-centre range and ramp linearly
// to 0 one voxel beyond (trilinear interpolation to the inactive neighbours).

const M: i32 = 12;
const Z0: i32 = 3;
const NZ: i32 = 2;
const E: [f32; 3] = [1.0, 0.5, 0.25];
const ALBEDO: f64 = 0.5;

fn slab_settings(spp: usize, shadow: usize) -> RenderSettings {
    // Orthographic, straight down onto a 0.25 km patch around the origin:
    // the irradiance varies across it by ~(0.125 / 12)^2 ~ 1e-4 relative,
    // far below the Monte Carlo error.
    let mut s = settings(ortho([0.0, 0.0, 10.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.25), 16, 16, spp);
    s.terrain = Terrain { kind: TerrainKind::Plane, height: 0.0, albedo: [ALBEDO; 3], ..Terrain::default() };
    s.render.shadow_samples = shadow;
    s
}

/// Signed solid-angle primitive of the rectangle [0,X] x [0,Y] at height z:
/// atan(XY / (z sqrt(X^2 + Y^2 + z^2))) (odd in X and Y).
fn f_rect(x: f64, y: f64, z: f64) -> f64 {
    fmath::atan(x * y / (z * (x * x + y * y + z * z).sqrt()))
}

/// Solid angle of the rectangle [x0,x1] x [y0,y1] at height z above the origin.
fn omega(x0: f64, x1: f64, y0: f64, y1: f64, z: f64) -> f64 {
    f_rect(x1, y1, z) - f_rect(x0, y1, z) - f_rect(x1, y0, z) + f_rect(x0, y0, z)
}

/// Irradiance at the origin per unit emission, from the slab of half-width
/// `m` voxels (non-absorbing), exactly: for a fixed height, the integral of
/// cos / r^2 = z / r^3 over a rectangle is its solid angle, so
/// `J = int dz g(z) int int f(x) f(y) z / r^3 dx dy`. A linear ramp is the
/// average of step functions over the ramp (f(x) = P(X0 < x < X1), X0, X1
/// uniform over the two ramps), so
/// `J = E[int_{Z0'}^{Z1'} omega(X0', X1', Y0', Y1', z) dz]` over six uniform edge
/// positions: 3-point Gauss per edge, 8-point Gauss in z (smooth integrands;
/// accurate to ~1e-7). For m -> infinity, J -> 2 pi H with H = NZ h: an
/// infinite slab, in spherical coordinates around the point, gives
/// `int_hemisphere cos(theta) (H / cos(theta)) dOmega = 2 pi H`.
fn j_exact(m: f64) -> f64 {
    let g3 = gauss(3);
    let g8 = gauss(8);
    let (z0, nz) = (Z0 as f64, NZ as f64);
    let mut j = 0.0;
    for &(a, wa) in &g3 {
        for &(b, wb) in &g3 {
            for &(c, wc) in &g3 {
                for &(d, wd) in &g3 {
                    let (x0, x1, y0, y1) = (-m - a, m + b, -m - c, m + d);
                    for &(p, wp) in &g3 {
                        for &(q, wq) in &g3 {
                            let (za, zb) = (z0 - p, z0 + nz - 1.0 + q);
                            let mut iz = 0.0;
                            for &(s, ws) in &g8 {
                                iz += ws * omega(x0, x1, y0, y1, za + (zb - za) * s);
                            }
                            j += wa * wb * wc * wd * wp * wq * iz * (zb - za);
                        }
                    }
                }
            }
        }
    }
    j
}

fn slab_grids(sigma: Option<f32>) -> (Option<aurora::grid::Grid<f32>>, aurora::grid::Grid<[f32; 3]>) {
    let tr = Transform::new(1.0, DVec3::ZERO);
    let (lo, hi) = (IVec3::new(-M, -M, Z0), IVec3::new(M, M, Z0 + NZ - 1));
    (sigma.map(|s| box_f32(lo, hi, |_| s, tr)), box_vec3(lo, hi, |_| E, tr))
}

/// Mean and standard error of `f(pixel)` over the image.
fn mean_se(img: &Image, f: impl Fn(&[f32; 4]) -> f64) -> (f64, f64) {
    let v: Vec<f64> = img.pixels.iter().map(f).collect();
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

#[test]
fn slab_oracle_tends_to_two_pi_e_h() {
    // The analytic oracle itself: a very wide slab gives 2 pi H (relative
    // finite-width correction ~ (Z0 + NZ/2) / M).
    let h = NZ as f64;
    let wide = j_exact(1e6);
    assert!(rel(wide, 2.0 * PI * h, 0.0) < 1e-5, "{wide} vs {}", 2.0 * PI * h);
    let ours = j_exact(M as f64);
    assert!(ours < wide && ours > 0.5 * wide, "{ours}");
}

#[test]
fn emissive_slab_lights_the_ground_as_the_closed_form() {
    // Non-absorbing slab: L_ground = albedo / pi * e * J (-> 2 albedo e H for
    // an infinite slab), seen through the slab, which adds e * NZ along the
    // vertical primary ray.
    let (_, e) = slab_grids(None);
    let s = slab_settings(16, 16);
    let img = render(&s, &Volume { density: None, emission: Some(&e) }, &NoProgress).unwrap();
    let j = j_exact(M as f64);
    let want = ALBEDO / PI * E[1] as f64 * j;
    let (m, se) = mean_se(&img, |p| p[1] as f64 - E[1] as f64 * NZ as f64);
    // 256 independent pixels, each the mean of 16 x 16 shadow samples:
    // 4 standard errors (estimated from the pixels themselves).
    assert!(se < 0.02 * want, "standard error {se} too large for a meaningful test");
    assert!(
        (m - want).abs() < 4.0 * se,
        "ground radiance {m} +- {se}, closed form {want} (infinite slab: {})",
        2.0 * ALBEDO * E[1] as f64 * NZ as f64
    );
    eprintln!("slab: {m:.5} +- {se:.5} vs {want:.5} (infinite slab {:.5})", 2.0 * ALBEDO * E[1] as f64 * NZ as f64);
    for p in &img.pixels {
        // Grey emission shape: every sample has the same colour, so the
        // channels are exactly proportional to E (to f32 rounding).
        let g = p[1] as f64 - E[1] as f64 * NZ as f64;
        for c in [0, 2] {
            let v = p[c] as f64 - E[c] as f64 * NZ as f64;
            assert!((v - g * E[c] as f64 / E[1] as f64).abs() < 1e-5 * (1.0 + v.abs()), "{p:?}");
        }
        assert_eq!(p[3], 0.0, "no density: alpha is 0");
    }
    assert_eq!(img.stats.terrain_hits, 256 * 16);
    assert_eq!(img.stats.shadow_samples, 256 * 16 * 16);
}

/// `int_hemisphere mu (1 - exp(-sigma D(w))) / sigma dOmega` at the origin,
/// with D the shape integral along w (the profile is cubic between the
/// breakpoints where a coordinate crosses a ramp end, so 3-point Gauss per
/// piece is exact). Hemisphere: composite 8-point Gauss, 40 panels in mu, 16
/// in phi over [0, pi/4] (the square slab is symmetric under the 8
/// reflections of the square). As sigma -> 0 this tends to `J`.
fn j_absorbing(sigma: f64) -> f64 {
    let ramp = |u: f64, lo: f64, hi: f64| (u - lo + 1.0).min(hi + 1.0 - u).clamp(0.0, 1.0);
    let m = M as f64;
    let (z0, z1) = (Z0 as f64, (Z0 + NZ - 1) as f64);
    let shape = |p: DVec3| ramp(p.x, -m, m) * ramp(p.y, -m, m) * ramp(p.z, z0, z1);
    let g3 = gauss(3);
    let g8 = gauss(8);
    let depth = |w: DVec3| -> f64 {
        let mut ts = vec![];
        for (k, planes) in [(0, [-m - 1.0, -m, m, m + 1.0]), (1, [-m - 1.0, -m, m, m + 1.0]), (2, [z0 - 1.0, z0, z1, z1 + 1.0])] {
            if w[k] != 0.0 {
                for p in planes {
                    let t = p / w[k];
                    if t > 0.0 {
                        ts.push(t);
                    }
                }
            }
        }
        ts.push(0.0);
        ts.sort_by(f64::total_cmp);
        let mut d = 0.0;
        for t in ts.windows(2) {
            d += g3.iter().map(|(s, ws)| ws * shape(w * (t[0] + (t[1] - t[0]) * s))).sum::<f64>() * (t[1] - t[0]);
        }
        d
    };
    let (nmu, nphi) = (40, 16);
    let mut total = 0.0;
    for i in 0..nmu {
        for &(a, wa) in &g8 {
            let mu = (i as f64 + a) / nmu as f64;
            let sin = (1.0 - mu * mu).sqrt();
            for k in 0..nphi {
                for &(b, wb) in &g8 {
                    let phi = (k as f64 + b) / nphi as f64 * PI / 4.0;
                    let d = depth(DVec3::new(sin * fmath::cos(phi), sin * fmath::sin(phi), mu));
                    let f = if sigma > 0.0 { (1.0 - fmath::exp(-sigma * d)) / sigma } else { d };
                    total += wa * wb * mu * f;
                }
            }
        }
    }
    // d(Omega) = d(mu) d(phi); the mu and phi panels have widths 1/nmu and (pi/4)/nphi; 8 symmetric copies.
    total * (1.0 / nmu as f64) * (PI / 4.0 / nphi as f64) * 8.0
}

#[test]
fn hemisphere_oracle_agrees_with_the_solid_angle_oracle() {
    let (a, b) = (j_absorbing(0.0), j_exact(M as f64));
    assert!(rel(a, b, 0.0) < 2e-4, "{a} vs {b}");
}

#[test]
fn absorbing_slab_shadow_rays_carry_transmittance() {
    // density sigma s, emission e s (same shape): along any ray from the
    // ground, L(w) = e / sigma (1 - exp(-sigma D(w))), so
    // E = e * j_absorbing(sigma); the camera sees T_p L_ground + e/sigma (1 - T_p)
    // with T_p = exp(-sigma NZ) on its vertical rays.
    let sigma = 0.7f32;
    let (d, e) = slab_grids(Some(sigma));
    let s = slab_settings(16, 16);
    let img = render(&s, &Volume { density: d.as_ref(), emission: Some(&e) }, &NoProgress).unwrap();
    let sg = sigma as f64;
    let tp = fmath::exp(-sg * NZ as f64);
    let front = E[1] as f64 / sg * (1.0 - tp);
    let want = ALBEDO / PI * E[1] as f64 * j_absorbing(sg);
    let (m, se) = mean_se(&img, |p| (p[1] as f64 - front) / tp);
    assert!(se < 0.02 * want, "standard error {se}");
    assert!((m - want).abs() < 4.0 * se, "ground radiance {m} +- {se} vs {want}");
    // Without transmittance on shadow rays the ground would be much brighter.
    let unattenuated = ALBEDO / PI * E[1] as f64 * j_exact(M as f64);
    assert!(unattenuated - want > 10.0 * se, "the test must distinguish {want} from {unattenuated}");
    for p in &img.pixels {
        assert!((p[3] as f64 - (1.0 - tp)).abs() < 1e-4 * (1.0 - tp), "alpha {} vs 1 - T = {}", p[3], 1.0 - tp);
    }
}

// ------------------------------------------------------------ occlusion

/// Writes a 16-bit greyscale PNG (row 0 first).
fn write_png16(path: &std::path::Path, w: usize, h: usize, v: impl Fn(usize, usize) -> u16) {
    let f = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w as u32, h as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut wr = enc.write_header().unwrap();
    let mut data = vec![];
    for row in 0..h {
        for col in 0..w {
            data.extend_from_slice(&v(col, row).to_be_bytes());
        }
    }
    wr.write_image_data(&data).unwrap();
}

#[test]
fn a_ridge_blocks_the_aurora_light_exactly() {
    // Heightmap 41 x 41 over [-20, 20]^2 (1 km spacing): a ridge 30 km high
    // along x = 0 (column 20), flat ground elsewhere. Emissive block at
    // x = 9..11, z = 4..6. Every line from the ground point (-5, 0, 0) to
    // the block passes x = 0 below z = 6 * 5/14 < 2 km, inside the ridge
    // (which is above 15 km for |x| < 0.5): the ground must be exactly black.
    let map = tmp("ridge.png");
    write_png16(&map, 41, 41, |col, _| if col == 20 { 65535 } else { 0 });
    let tr = Transform::new(1.0, DVec3::ZERO);
    let e = box_vec3(IVec3::new(9, -1, 4), IVec3::new(11, 1, 6), |_| [1.0, 1.0, 1.0], tr);
    let mut s = settings(ortho([-5.0, 0.0, 3.0], [-5.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5), 4, 4, 4);
    s.terrain = Terrain {
        kind: TerrainKind::Heightfield,
        height: 0.0,
        mountain_height: 30.0,
        heightmap: Some("ridge.png".into()),
        extent: [-20.0, -20.0, 20.0, 20.0],
        albedo: [0.8; 3],
        ..Terrain::default()
    };
    s.base_dir = map.parent().map(|p| p.to_path_buf());
    s.render.shadow_samples = 8;
    let vol = Volume { density: None, emission: Some(&e) };
    let img = render(&s, &vol, &NoProgress).unwrap();
    assert_eq!(img.stats.terrain_hits, 4 * 4 * 4);
    assert!(img.stats.shadow_rays > 0);
    for p in &img.pixels {
        assert_eq!(*p, [0.0; 4]);
    }
    // Control: without the ridge the same point is lit.
    s.terrain.mountain_height = 0.0;
    let lit = render(&s, &vol, &NoProgress).unwrap();
    assert!(lit.pixels.iter().all(|p| p[0] > 1e-4), "{:?}", lit.pixels[0]);
}

#[test]
fn heightmap_png_orientation_and_scale() {
    // Row 0 of the image is the north edge (y1); column 0 is x0.
    let map = tmp("orient.png");
    write_png16(&map, 3, 2, |col, row| (row * 3 + col) as u16 * 10000);
    let t = Terrain { height: 1.0, mountain_height: 6.5535, extent: [0.0, 0.0, 2.0, 1.0], ..Terrain::default() };
    let hf = Heightfield::from_heightmap(&map, &t).unwrap();
    assert_eq!((hf.nx(), hf.ny()), (3, 2));
    for row in 0..2 {
        for col in 0..3 {
            let v = hf.vertex(col, 1 - row);
            let want = 1.0 + 6.5535 * ((row * 3 + col) as f64 * 10000.0 / 65535.0);
            assert!((v.z - want).abs() < 1e-6, "({col},{row}) {v} vs {want}");
            assert_eq!((v.x, v.y), (col as f64, (1 - row) as f64));
        }
    }
    // Errors are typed, not panics.
    assert!(Heightfield::from_heightmap(&tmp("missing.png"), &t).is_err());
}

// ------------------------------------------------------------ heightfield

fn mountains() -> Heightfield {
    let t = Terrain {
        kind: TerrainKind::Heightfield,
        height: -0.5,
        mountain_height: 1.5,
        mountain_scale: 2.0,
        extent: [-5.0, -4.0, 5.0, 6.0],
        seed: 3,
        ..Terrain::default()
    };
    Heightfield::procedural(&t).unwrap()
}

#[test]
fn procedural_resolution_and_range() {
    assert_eq!(procedural_cells(600.0, 20.0), 240);
    assert_eq!(procedural_cells(1e6, 1.0), 1023);
    assert_eq!(procedural_cells(0.1, 20.0), 1);
    let hf = mountains();
    assert_eq!((hf.nx(), hf.ny()), (41, 41));
    assert!(hf.z.iter().all(|z| (-0.5..=1.0).contains(z)));
    assert!(hf.zmax - hf.zmin > 0.5, "mountains must have relief: {} .. {}", hf.zmin, hf.zmax);
    assert_eq!(hf, mountains(), "deterministic");
}

#[test]
fn heightfield_intersection_matches_brute_force() {
    let hf = mountains();
    let mut rng = Pcg64::seed_from_u64(21);
    let mut hits = 0;
    for i in 0..3000 {
        let o = DVec3::new(rng.random_range(-7.0..7.0), rng.random_range(-6.0..8.0), rng.random_range(-1.0..3.0));
        // Half the rays aimed at a random point of the terrain's box.
        let mut d = if i % 2 == 0 {
            DVec3::new(rng.random_range(-5.0..5.0), rng.random_range(-4.0..6.0), rng.random_range(-0.5..1.0)) - o
        } else {
            DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
        };
        if i % 3 == 0 {
            d.z = d.z.abs() * -0.05; // grazing rays
        }
        if i % 7 == 0 {
            d.x = 0.0; // rays in a grid plane direction
        }
        let d = d.normalize();
        let got = hf.intersect(o, d, 0.0, f64::INFINITY);
        let mut best: Option<(f64, DVec3)> = None;
        for j in 0..hf.ny() - 1 {
            for k in 0..hf.nx() - 1 {
                for tri in hf.cell_triangles(k, j) {
                    if let Some(h) = intersect_triangle(o, d, &tri, 0.0, f64::INFINITY) {
                        if best.is_none_or(|b| h.t < b.0) {
                            best = Some((h.t, h.n));
                        }
                    }
                }
            }
        }
        match (got, best.map(|b| b.0)) {
            (Some(g), Some(b)) => {
                assert!((g.t - b).abs() <= 1e-9 * (1.0 + b), "ray {i}: {} vs {b}", g.t);
                // The smooth shading normal: unit, on the side of the
                // triangle the ray came from (the geometric normal facing it).
                let ng = best.unwrap().1;
                assert!(g.n.dot(ng) > 0.0 && (g.n.length() - 1.0).abs() < 1e-12, "ray {i}: {} vs {ng}", g.n);
                hits += 1;
            }
            (None, None) => {}
            (g, b) => panic!("ray {i} from {o} along {d}: DDA {g:?} vs brute force {b:?}"),
        }
    }
    assert!(hits > 1000, "{hits}");
}

/// Parses an OBJ's `v` and `f` lines.
fn parse_obj(text: &str) -> (Vec<[f32; 3]>, Vec<[usize; 3]>) {
    let mut v = vec![];
    let mut f = vec![];
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => v.push([0, 1, 2].map(|_| it.next().unwrap().parse::<f32>().unwrap())),
            Some("f") => f.push([0, 1, 2].map(|_| it.next().unwrap().parse::<usize>().unwrap())),
            _ => {}
        }
    }
    (v, f)
}

#[test]
fn obj_export_is_the_traced_mesh() {
    let hf = mountains();
    let path = tmp("terrain.obj");
    write_obj(&path, &hf).unwrap();
    let (v, f) = parse_obj(&std::fs::read_to_string(&path).unwrap());
    let (nx, ny) = (hf.nx(), hf.ny());
    assert_eq!(v.len(), nx * ny);
    assert_eq!(f.len(), 2 * (nx - 1) * (ny - 1));
    let vert = |i: usize| DVec3::new(v[i - 1][0] as f64, v[i - 1][1] as f64, v[i - 1][2] as f64);
    let mut k = 0;
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            for tri in hf.cell_triangles(i, j) {
                let got = f[k].map(vert);
                assert_eq!(got, tri, "cell ({i},{j})");
                k += 1;
            }
        }
    }
}

/// [`mountains`], and what Blender prints running `script` after it
/// imported them as the add-on does (written as the OBJ `name`, imported
/// with forward_axis='Y', up_axis='Z'; the script sees the object as `ob`
/// and its mesh as `me`).
fn mountains_through_blender(name: &str, script: &str) -> (Heightfield, String) {
    let hf = mountains();
    let path = tmp(name);
    write_obj(&path, &hf).unwrap();
    let script = format!(
        "import bpy, sys, struct
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=sys.argv[-1], forward_axis='Y', up_axis='Z')
ob = [o for o in bpy.data.objects if o.type == 'MESH'][0]
me = ob.data
{script}"
    );
    let text = python(&venv_python(), &["-c", &script, "--", path.to_str().unwrap()]);
    (hf, text)
}

#[test]
fn blender_imports_exactly_the_same_mesh() {
    // The add-on imports the OBJ with forward_axis='Y', up_axis='Z'; Blender
    // must end up with our vertices bit for bit (f32) and our triangles.
    let script = r#"
assert tuple(ob.matrix_world.row[0]) == (1.0, 0.0, 0.0, 0.0) and tuple(ob.matrix_world.row[2]) == (0.0, 0.0, 1.0, 0.0), ob.matrix_world
out = sys.stdout
out.write("V %d\n" % len(me.vertices))
for v in me.vertices:
    out.write("%s %s %s\n" % tuple(struct.pack('<f', c).hex() for c in v.co))
out.write("F %d\n" % len(me.polygons))
for p in me.polygons:
    out.write(" ".join(str(i) for i in p.vertices) + "\n")
"#;
    let (hf, text) = mountains_through_blender("blender.obj", script);
    let mut lines = text.lines().skip_while(|l| !l.starts_with("V "));
    let nv: usize = lines.next().unwrap()[2..].parse().unwrap();
    assert_eq!(nv, hf.nx() * hf.ny());
    for n in 0..nv {
        let l = lines.next().unwrap();
        let c: Vec<f32> = l
            .split(' ')
            .map(|h| f32::from_le_bytes(std::array::from_fn(|i| u8::from_str_radix(&h[2 * i..2 * i + 2], 16).unwrap())))
            .collect();
        let want = hf.vertex(n % hf.nx(), n / hf.nx());
        assert_eq!(c, vec![want.x as f32, want.y as f32, want.z as f32], "vertex {n}");
    }
    let nf: usize = lines.next().unwrap()[2..].parse().unwrap();
    assert_eq!(nf, 2 * (hf.nx() - 1) * (hf.ny() - 1));
    let mut k = 0;
    for j in 0..hf.ny() - 1 {
        for i in 0..hf.nx() - 1 {
            let a = j * hf.nx() + i;
            for want in [[a, a + 1, a + hf.nx() + 1], [a, a + hf.nx() + 1, a + hf.nx()]] {
                let got: Vec<usize> = lines.next().unwrap().split(' ').map(|x| x.parse().unwrap()).collect();
                assert_eq!(got, want, "face {k}");
                k += 1;
            }
        }
    }
}

#[test]
fn smooth_normals_are_blenders_vertex_normals() {
    // The add-on shades the imported mesh smooth (blender/terrain.py);
    // Cycles interpolates Blender's vertex normals over each triangle, and
    // `aurora render` its own (src/render/terrain.rs). Blender computes them
    // in f32 (corner angles through a single-precision acos, which loses
    // about 1e-4 of a small angle): measured 4.5e-5 at worst, so 1e-4;
    // area-weighted or equal-weighted normals differ from Blender's by
    // 0.3-0.4 on this mesh.
    let script = r#"
for p in me.polygons:
    p.use_smooth = True
me.update()
sys.stdout.write("N %d\n" % len(me.vertices))
for n in me.vertex_normals:
    sys.stdout.write("%r %r %r\n" % tuple(n.vector))
"#;
    let (hf, text) = mountains_through_blender("normals.obj", script);
    let mut lines = text.lines().skip_while(|l| !l.starts_with("N "));
    let nv: usize = lines.next().unwrap()[2..].parse().unwrap();
    assert_eq!(nv, hf.normals.len());
    let mut worst = 0.0f64;
    for want in &hf.normals {
        let c: Vec<f64> = lines.next().unwrap().split(' ').map(|x| x.parse().unwrap()).collect();
        worst = worst.max((DVec3::new(c[0], c[1], c[2]) - *want).length());
    }
    assert!(worst < 1e-4, "largest difference {worst}");
    // Not the flat normals: the mountains' vertex normals differ from
    // their triangles' by much more than that.
    let tri = hf.cell_triangles(3, 3)[0];
    let flat = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
    assert!((hf.normals[3 * hf.nx() + 3] - flat).length() > 1e-3);
}
