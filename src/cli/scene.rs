//! The commands that show one part of a scene: `aurora scene` (the scene as
//! TOML, or the schema of every key), `aurora footprint` (each curtain's
//! footprint as a PNG) and `aurora terrain` (the heightfield as OBJ).

use super::args::{FootprintArgs, SceneArgs, TerrainArgs};
use super::exit::InputError;
use super::{load_scene, load_scene_as_given, scene_dir};
use anyhow::{Context, Result};

/// `aurora scene`: a preset or file with every default filled in, or
/// `--list` (the presets) or `--schema`.
pub fn print(a: SceneArgs) -> Result<()> {
    if a.list {
        print!("{}", aurora::scene::presets::list());
        return Ok(());
    }
    if a.schema {
        print!("{}", aurora::scene::schema::schema_json());
        return Ok(());
    }
    // As written: `[oval]` and magnetic paths stay keys, not placed paths.
    let s = load_scene_as_given(&a.name, &a.overrides)?;
    print!("{}", scene_header(&a.name));
    print!("{}", s.to_toml());
    Ok(())
}

fn scene_header(name: &str) -> String {
    format!(
        "# aurora scene `{name}`. Units: kilometres, z up (x east, y north).\n\
         # Bake: aurora bake FILE.toml --out DIR    Render: aurora render FILE.toml --out image.exr\n\
         # Every key is optional; unknown keys are errors. docs/scene.md gives each key's meaning,\n\
         # unit, default and range.\n\n"
    )
}

/// `aurora footprint`: DIR/footprint-N.png per curtain.
pub fn footprint(a: FootprintArgs) -> Result<()> {
    let scene = load_scene(&a.scene, &a.overrides)?;
    aurora::util::atomic_write::prepare_folder(&a.out)?;
    for (i, fp) in aurora::pipeline::plan::footprints(&scene).iter().enumerate() {
        let path = a.out.join(format!("footprint-{i}.png"));
        fp.write_png(&path).with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// `aurora terrain`: the triangles `aurora render` traces, as a Wavefront OBJ.
pub fn terrain(a: TerrainArgs) -> Result<()> {
    let TerrainArgs { scene: scene_arg, out, overrides } = a;
    let scene = load_scene(&scene_arg, &overrides)?;
    if out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("obj") {
        return Err(
            InputError(format!("--out {}: the terrain is written as a Wavefront OBJ; give a name ending in .obj", out.display())).into()
        );
    }
    aurora::util::atomic_write::check_replaceable(&out)?;
    if scene.terrain.kind != aurora::scene::TerrainKind::Heightfield {
        return Err(InputError(format!(
            "terrain.kind = {:?}: only a heightfield has a mesh to write (a plane is z = terrain.height)",
            scene.terrain.kind
        ))
        .into());
    }
    // On a round Earth the mesh lies on the sphere, as the renderer traces it.
    let mut hf = aurora::render::terrain::Heightfield::from_terrain(&scene.terrain, Some(&scene_dir(&scene_arg)))
        .map_err(|e| InputError(e.to_string()))?;
    if scene.earth.radius_km > 0.0 {
        hf = hf.on_sphere(scene.earth.radius_km).map_err(|e| InputError(e.to_string()))?;
    }
    aurora::render::terrain::write_obj(&out, &hf).with_context(|| format!("cannot write {}", out.display()))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
