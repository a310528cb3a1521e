//! A VDB file into the renderer: the adapter between the file layer
//! (`vdb`) and the renderer (`render`), which know nothing of each other.
//!
//! Two paths, one verdict on a file:
//! - the grid path: [`render_grids`] lists a file read into grids
//!   (`vdb::read::read_vdb_for_render`) for the renderer's grid choice
//!   (`render::grids::choose`);
//! - the records path: [`read_render_medium`] parses the file once, locating
//!   each leaf's record (`vdb::parse::Decode::Locate`), and builds the
//!   renderer's medium straight from the records (`Medium::from_sources`
//!   over `vdb::records::FileLeaves`, each a `leaf_source::LeafSource`): no
//!   grid in between. It applies the grid reader's checks (the tile limit
//!   of every grid, every record of the unused grids decompressed once), so
//!   both paths accept and refuse the same files (`vdb::read`'s module doc).
//!
//! Re-colouring: a render whose `[colour] observer` is not the one the file
//! records (`aurora_observer`, [`baked_observer`]) takes the emission from
//! the file's line grids ([`render_grids_as`],
//! `render::recolour::emission_from_lines`) on the grid path, or is refused
//! when a line grid is missing; the file's listing alone decides
//! ([`emission_source_of`]), so the check costs no decoding.

use crate::grid::leaf_source::{GreySource, LeafSource};
use crate::grid::Transform;
use crate::io::vdb::parse::RawMeta;
use crate::io::vdb::parse::{self, AnyTree, ParseError, ValueKind};
use crate::io::vdb::read::{check_file_tile_voxels, check_tile_voxels, VdbFile, VdbReadError};
use crate::io::vdb::records::{FileBytes, FileLeaves};
use crate::physics::emission::line_table::{grid_name, LINE_KEYS};
use crate::render::grids::{check_types, choose, ChosenGrids, GridType, Listed, RenderGridsError};
use crate::render::medium::Medium;
use crate::render::recolour::{emission_from_lines, emission_source, observer_named, EmissionSource, RecolourError};
use crate::render::{Prepared, RenderError, RenderSettings, Volume};
use crate::scene::ColourParams;
use crate::util::observer::Observer;
use glam::DVec3;
use std::path::Path;

/// The grids a renderer needs from a file: the file's grids listed for the
/// renderer's grid choice ([`crate::render::grids::choose`]: a float
/// `density` grid, an `emission` grid, vec3 or float counted as grey; either
/// may be absent, not both).
pub fn render_grids(file: VdbFile) -> Result<ChosenGrids, RenderGridsError> {
    let listing: Vec<Listed<'_>> =
        file.grids.iter().map(|g| Listed { name: &g.name, type_name: &g.type_name, kind: grid_type(g.kind) }).collect();
    choose(&listing, file.float_grids, file.vec3_grids)
}

/// [`render_grids`] for a render of `colour`: the emission as baked, or
/// rebuilt from the line grids for `colour.observer` where the file was
/// baked for another ([`emission_source_of`]'s verdict, on the file read).
pub fn render_grids_as(file: VdbFile, colour: &ColourParams) -> Result<ChosenGrids, RenderGridsError> {
    let listing = file.grids.iter().map(|g| (g.name.as_str(), g.kind, g.metadata.as_slice()));
    if source_of(listing, colour)? == EmissionSource::AsBaked {
        return render_grids(file);
    }
    let found = LINE_KEYS.map(|k| file.float(&grid_name(k)));
    let missing: Vec<String> = LINE_KEYS.iter().zip(&found).filter(|(_, g)| g.is_none()).map(|(k, _)| grid_name(k)).collect();
    let lines = match found {
        [Some(a), Some(b), Some(c), Some(d), Some(e)] => [a, b, c, d, e],
        _ => {
            let baked = baked_observer(file.grids.iter().map(|g| g.metadata.as_slice()))?.unwrap_or_default();
            return Err(RecolourError::MissingLines { asked: colour.observer, baked, missing }.into());
        }
    };
    let emission = emission_from_lines(lines, colour.observer)?;
    let (density, _) = render_grids(file)?;
    Ok((density, Some(emission)))
}

/// The observer a file's `emission` was coloured for, from its grids'
/// metadata: `aurora_observer` (`crate::io::bake_folder::OBSERVER_KEY`)
/// where a grid has it; the default observer for a bake of ours without it
/// (its grids carry `aurora_scene_hash`; the key is written only for
/// another observer); None for a file from elsewhere, whose colours are
/// taken as the scene's.
pub fn baked_observer<'a>(metadata: impl IntoIterator<Item = &'a [(String, RawMeta)]>) -> Result<Option<Observer>, RecolourError> {
    let key = crate::io::bake_folder::OBSERVER_KEY;
    let mut ours = false;
    for m in metadata {
        for (k, v) in m {
            if k == key {
                return match v {
                    RawMeta::String(s) => observer_named(key, s).map(Some),
                    other => Err(RecolourError::UnknownObserver { key: key.to_string(), value: format!("{other:?}") }),
                };
            }
            ours |= k == "aurora_scene_hash";
        }
    }
    Ok(ours.then(Observer::default))
}

/// [`emission_source`] of a file's grids, each its name, value type and
/// metadata.
fn source_of<'a>(
    grids: impl Iterator<Item = (&'a str, Option<ValueKind>, &'a [(String, RawMeta)])>,
    colour: &ColourParams,
) -> Result<EmissionSource, RecolourError> {
    let grids: Vec<_> = grids.collect();
    let baked = baked_observer(grids.iter().map(|g| g.2))?;
    let floats: Vec<&str> = grids.iter().filter(|g| g.1 == Some(ValueKind::Float)).map(|g| g.0).collect();
    emission_source(colour, baked, &floats)
}

/// Where a render of `colour` takes the emission of the VDB file at `path`
/// from (`crate::render::recolour::emission_source`): decided from the
/// file's listing (`vdb::parse::list_grids`: names, types, metadata), no
/// grid decoded. A missing line grid for another observer than the bake's
/// is refused (an input error naming the grids).
pub fn emission_source_of(path: &Path, colour: &ColourParams) -> Result<EmissionSource, RenderReadError> {
    let file = path.display().to_string();
    let bytes = FileBytes::open(path).map_err(|source| VdbReadError::Io { path: path.to_path_buf(), source })?;
    let headers = parse::list_grids(bytes.bytes()).map_err(|source| VdbReadError::Invalid { file: file.clone(), source })?;
    let names: Vec<String> = headers.iter().map(|h| h.name()).collect();
    let listing = headers.iter().zip(&names).map(|(h, n)| (n.as_str(), h.kind, h.metadata.as_slice()));
    source_of(listing, colour).map_err(|e| RenderReadError::Grids { file, source: e.into() })
}

/// The renderer's name for a grid's value type, as listed for
/// [`crate::render::grids`] (both the grid and the records path).
fn grid_type(kind: Option<ValueKind>) -> GridType {
    match kind {
        Some(ValueKind::Float) => GridType::Float,
        Some(ValueKind::Vec3) => GridType::Vec3,
        None => GridType::Other,
    }
}

/// Why a VDB file's medium could not be built: the grid choice
/// ([`crate::render::grids`]) or the renderer's checks on the values.
#[derive(Debug, thiserror::Error)]
pub enum RenderReadError {
    #[error(transparent)]
    Read(#[from] VdbReadError),
    #[error("{file}: {source}")]
    Grids { file: String, source: RenderGridsError },
    #[error("{file}: {source}")]
    Render { file: String, source: RenderError },
}

impl RenderReadError {
    /// True when the file, or a grid the renderer refuses, is at fault (exit status 2).
    pub fn is_input(&self) -> bool {
        match self {
            RenderReadError::Read(e) => e.is_input(),
            RenderReadError::Grids { source, .. } => source.is_input(),
            RenderReadError::Render { source, .. } => source.is_input(),
        }
    }
}

/// The renderer's medium read straight from a VDB file, and the split of
/// the time it took.
pub struct RenderMedium {
    pub medium: Medium,
    /// Reading the file and validating every record (its leaves located).
    pub open_seconds: f64,
    /// Decoding the records into the medium (`Medium::from_sources`).
    pub build_seconds: f64,
}

/// The renderer prepared from a VDB file for a scene of `colour`, as
/// `aurora render --vdb` does: the records path ([`read_render_medium`])
/// where it applies and the emission is taken as baked, else the grid path
/// (re-coloured from the line grids for another observer than the bake's:
/// [`render_grids_as`]); with the seconds spent opening the file and
/// building the medium.
pub fn prepare_from_vdb(settings: &RenderSettings, path: &Path, colour: &ColourParams) -> Result<(Prepared, f64, f64), RenderReadError> {
    let file = path.display().to_string();
    let render_err = |source: RenderError| RenderReadError::Render { file: file.clone(), source };
    let (ds, es) = (settings.volume.density_scale, settings.volume.emission_scale);
    if emission_source_of(path, colour)? == EmissionSource::AsBaked {
        if let Some(read) = read_render_medium(path, ds, es)? {
            let prepared = Prepared::with_medium(settings, read.medium, None).map_err(render_err)?;
            return Ok((prepared, read.open_seconds, read.build_seconds));
        }
    }
    let open = std::time::Instant::now();
    let vdb = crate::io::vdb::read::read_vdb_for_render(path)?;
    let (density, emission) = render_grids_as(vdb, colour).map_err(|source| RenderReadError::Grids { file: file.clone(), source })?;
    let open_seconds = open.elapsed().as_secs_f64();
    let build = std::time::Instant::now();
    let volume = Volume { density: density.as_ref(), emission: emission.as_ref() };
    let prepared = Prepared::new(settings, &volume).map_err(render_err)?;
    Ok((prepared, open_seconds, build.elapsed().as_secs_f64()))
}

/// Reads a VDB file straight into the renderer's medium (the `render`
/// command's path): the file is parsed once, validating every record and
/// locating each leaf's, then [`Medium::from_sources`] decodes the records
/// in parallel, each into a per-thread buffer, checks them and copies them
/// into the medium's blocks: no [`crate::grid::Grid`] in between. The grids are the ones
/// [`render_grids`] would choose and the medium equals `Medium::new` of
/// those grids (read by [`read_vdb`]), field for field. The other grids'
/// records are checked, not kept (module docs), so this path refuses
/// exactly the files the grid path refuses.
///
/// `Ok(None)` where this path does not apply and the caller should read
/// grids instead ([`read_vdb_for_render`], [`render_grids`]): a float
/// `emission` grid (read as grey), active tiles in a chosen grid, or no
/// grid to render (the grid path reports it), a high-column grid
/// (`density_high`, `emission_high`: the grid path adds it to its fine grid).
pub fn read_render_medium(path: &Path, density_scale: f64, emission_scale: f64) -> Result<Option<RenderMedium>, RenderReadError> {
    let start = std::time::Instant::now();
    let bytes = FileBytes::open(path).map_err(|source| VdbReadError::Io { path: path.to_path_buf(), source })?;
    render_medium_named(bytes.bytes(), &path.display().to_string(), start, density_scale, emission_scale, EmissionGrid::Baked)
}

/// [`read_render_medium`] of a file held in memory.
pub fn read_render_medium_bytes(bytes: &[u8], density_scale: f64, emission_scale: f64) -> Result<Option<RenderMedium>, RenderReadError> {
    render_medium_named(bytes, "<memory>", std::time::Instant::now(), density_scale, emission_scale, EmissionGrid::Baked)
}

/// [`read_render_medium`] with the float grid `grid` (a line's, `line_5577`)
/// as a grey emission ([`GreySource`]) beside the density: the medium
/// `Medium::new(density, grey(grid))` of the grids read whole, which the
/// keogram traced from grids read whole. `Ok(None)` where that path does
/// not apply (no such float grid, active tiles, a high column): the caller
/// reads grids instead.
pub fn read_line_medium(path: &Path, grid: &str, density_scale: f64, emission_scale: f64) -> Result<Option<RenderMedium>, RenderReadError> {
    let start = std::time::Instant::now();
    let bytes = FileBytes::open(path).map_err(|source| VdbReadError::Io { path: path.to_path_buf(), source })?;
    render_medium_named(bytes.bytes(), &path.display().to_string(), start, density_scale, emission_scale, EmissionGrid::Grey(grid))
}

/// Which grid the medium's emission comes from.
#[derive(Clone, Copy)]
enum EmissionGrid<'a> {
    /// The vec3 `emission` grid, as baked.
    Baked,
    /// This float grid, grey.
    Grey(&'a str),
}

fn render_medium_named(
    bytes: &[u8],
    file: &str,
    start: std::time::Instant,
    density_scale: f64,
    emission_scale: f64,
    pick: EmissionGrid<'_>,
) -> Result<Option<RenderMedium>, RenderReadError> {
    let file = file.to_string();
    let invalid = |source: ParseError| VdbReadError::Invalid { file: file.clone(), source };
    let parsed = parse::parse_file_with(bytes, &|gh| {
        if gh.kind.is_some() {
            parse::Decode::Locate
        } else {
            parse::Decode::Skip
        }
    })
    .map_err(invalid)?;
    let names: Vec<String> = parsed.grids.iter().map(|g| g.header.name()).collect();
    let listing: Vec<Listed<'_>> = parsed
        .grids
        .iter()
        .zip(&names)
        .map(|(g, name)| Listed { name, type_name: &g.header.type_name, kind: grid_type(g.header.kind) })
        .collect();
    check_types(&listing).map_err(|source| RenderReadError::Grids { file: file.clone(), source })?;
    let transform_of = |g: &parse::ParsedGrid| g.header.transform.unwrap_or(Transform::new(1.0, DVec3::ZERO));
    let mut density = None;
    let mut emission = None;
    let mut grey = None;
    let mut float_emission = false;
    let mut used = [None, None];
    for (i, (g, name)) in parsed.grids.iter().zip(&names).enumerate() {
        match (&g.tree, name.as_str()) {
            (Some(AnyTree::Float(t)), "density") if density.is_none() => {
                used[0] = Some(i);
                density = Some(FileLeaves { name: name.clone(), transform: transform_of(g), tree: t, data: bytes })
            }
            (Some(AnyTree::Vec3(t)), "emission") if emission.is_none() && matches!(pick, EmissionGrid::Baked) => {
                used[1] = Some(i);
                emission = Some(FileLeaves { name: name.clone(), transform: transform_of(g), tree: t, data: bytes })
            }
            (Some(AnyTree::Float(_)), "emission") if matches!(pick, EmissionGrid::Baked) => float_emission = true,
            (Some(AnyTree::Float(t)), n) if grey.is_none() && matches!(pick, EmissionGrid::Grey(want) if want == n) => {
                used[1] = Some(i);
                grey = Some(FileLeaves { name: name.clone(), transform: transform_of(g), tree: t, data: bytes })
            }
            _ => {}
        }
    }
    if matches!(pick, EmissionGrid::Grey(_)) && grey.is_none() {
        return Ok(None);
    }
    let tiles = density.as_ref().is_some_and(|d| d.tree.active_tile_count > 0)
        || emission.as_ref().is_some_and(|e| e.tree.active_tile_count > 0)
        || grey.as_ref().is_some_and(|e| e.tree.active_tile_count > 0);
    // The high column (`crate::grid::high_column`) is added to its fine grid in memory:
    // the grid path does it.
    let high = names.iter().any(|n| n.ends_with(crate::grid::high_column::HIGH_SUFFIX));
    if (emission.is_none() && float_emission) || (density.is_none() && emission.is_none() && grey.is_none()) || tiles || high {
        return Ok(None);
    }
    // What the grid reader refuses is refused here too: its tile limit on
    // every grid, and the records of the grids the medium does not use
    // checked as decoding them would (`parse::check_located`); the builder
    // checks the used grids' records as it decodes them.
    let (mut tile_voxels, mut trees) = (0u128, 0usize);
    for (i, (g, name)) in parsed.grids.iter().zip(&names).enumerate() {
        let Some(tree) = &g.tree else { continue };
        check_tile_voxels(tree.tile_voxels(), name, &file)?;
        (tile_voxels, trees) = (tile_voxels + tree.tile_voxels(), trees + 1);
        if !used.contains(&Some(i)) {
            tree.check_located(bytes, &g.header.unique_name).map_err(invalid)?;
        }
    }
    check_file_tile_voxels(tile_voxels, trees, &file)?;
    let open_seconds = start.elapsed().as_secs_f64();
    let build = std::time::Instant::now();
    let grey = grey.as_ref().map(|g| GreySource(g));
    let medium = Medium::from_sources(
        density.as_ref().map(|s| s as &dyn LeafSource),
        emission.as_ref().map(|s| s as &dyn LeafSource).or(grey.as_ref().map(|s| s as &dyn LeafSource)),
        density_scale,
        emission_scale,
    )
    .map_err(|source| RenderReadError::Render { file: file.clone(), source })?;
    Ok(Some(RenderMedium { medium, open_seconds, build_seconds: build.elapsed().as_secs_f64() }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use crate::io::vdb::read::read_vdb_bytes;
    use glam::IVec3;

    /// Density and emission grids with dense, sparse, all-zero (a Cycles
    /// shell) and single-voxel leaves, negative coordinates, inactive
    /// voxels holding garbage-free background, on transform `tr` (emission
    /// on `tr_e`).
    fn medium_grids(tr: Transform, tr_e: Transform) -> (Grid<f32>, Grid<[f32; 3]>) {
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr_e);
        let mut h = 17u32;
        let mut next = || {
            h ^= h << 13;
            h ^= h >> 17;
            h ^= h << 5;
            h
        };
        for x in -12..20 {
            for y in -4..9 {
                for z in 0..11 {
                    let r = next();
                    if r % 3 == 0 {
                        continue;
                    }
                    let v = (r % 1000) as f32 * 1e-3;
                    d.set(IVec3::new(x, y, z), if r % 7 == 0 { 0.0 } else { v });
                    if r % 5 != 0 {
                        e.set(IVec3::new(x, y, z), [v, 0.5 * v, if r % 11 == 0 { 0.0 } else { 2.0 * v }]);
                    }
                }
            }
        }
        // A shell leaf of active zeros in both, one only in emission, a
        // lone voxel on a leaf's upper face.
        for ijk in [IVec3::new(40, 0, 0), IVec3::new(41, 3, 7)] {
            d.set(ijk, 0.0);
            e.set(ijk, [0.0; 3]);
        }
        e.set(IVec3::new(-40, 8, 0), [0.0; 3]);
        d.set(IVec3::new(7, 63, -9), 3.5);
        (d, e)
    }

    /// The medium built straight from a file's records equals the one built
    /// from the same file read into grids, field for field (block numbers
    /// included), for every compression, half emission, shared and
    /// separate transforms, any scales and the thread count; the scales set
    /// afterwards equal the scales built in.
    #[test]
    fn medium_from_file_equals_medium_from_grids() {
        use crate::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        use crate::render::medium::Medium;
        use crate::scene::Compression;
        let tr = Transform::new(0.5, DVec3::new(1.0, -2.0, 3.0));
        for tr_e in [tr, Transform::new(0.25, DVec3::ZERO)] {
            let (d, e) = medium_grids(tr, tr_e);
            for c in [
                Compression::None,
                Compression::Zip,
                Compression::ActiveMask,
                Compression::ZipActiveMask,
                Compression::Blosc,
                Compression::BloscActiveMask,
            ] {
                for half in [false, true] {
                    let opts = WriteOptions {
                        compression: c,
                        half: if half { vec!["emission".into()] } else { Vec::new() },
                        ..WriteOptions::default()
                    };
                    let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
                    let file = read_vdb_bytes(&bytes).unwrap();
                    let (gd, ge) = render_grids(file).unwrap();
                    for (ds, es) in [(1.0, 1.0), (2.5, 0.0), (0.0, 3.0)] {
                        let want = Medium::new(gd.as_ref(), ge.as_ref(), ds, es).unwrap();
                        for threads in [1, 2] {
                            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                            let got = pool.install(|| read_render_medium_bytes(&bytes, ds, es)).unwrap().unwrap().medium;
                            assert!(got == want, "{c:?} half {half} scales {ds} {es} threads {threads}");
                        }
                        let mut rescaled = Medium::new(gd.as_ref(), ge.as_ref(), 1.0, 1.0).unwrap();
                        rescaled.set_scales(ds, es).unwrap();
                        assert!(rescaled == want, "set_scales({ds}, {es})");
                    }
                    let m = Medium::new(gd.as_ref(), ge.as_ref(), 1.0, 1.0).unwrap();
                    assert_eq!(m.fields.len(), if tr_e == tr { 1 } else { 2 });
                }
            }
        }
    }

    /// A line's grid read from the file's records as a grey emission
    /// ([`read_line_medium`]) builds the medium the keogram built from the
    /// grids read whole (`Medium::new(density, grey(line))`), for every
    /// compression, the line stored in half floats or not, and the thread
    /// count; a file without that grid takes the grid path (`None`).
    #[test]
    fn line_medium_from_file_equals_the_grey_grid_medium() {
        use crate::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        use crate::scene::Compression;
        let tr = Transform::new(0.5, DVec3::new(1.0, -2.0, 3.0));
        let (d, e) = medium_grids(tr, tr);
        let mut line = Grid::new("line_5577", 0.0f32, tr);
        for leaf in e.leaves() {
            for n in 0..crate::grid::LEAF_NUM_VALUES {
                if leaf.is_active(n) {
                    let ijk = leaf.origin + crate::grid::offset_to_local(n);
                    line.set(ijk, leaf.values[n][1] * 3.0);
                }
            }
        }
        let dir = crate::util::scratch::folder("vdb_for_render", "line_medium");
        for c in [Compression::None, Compression::ZipActiveMask, Compression::BloscActiveMask] {
            for half in [false, true] {
                let opts = WriteOptions {
                    compression: c,
                    half: if half { vec!["emission".into(), "line_5577".into()] } else { Vec::new() },
                    ..WriteOptions::default()
                };
                let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e), GridRef::Float(&line)], &opts).unwrap();
                let path = dir.join("f.vdb");
                std::fs::write(&path, &bytes).unwrap();
                let file = read_vdb_bytes(&bytes).unwrap();
                let grey = crate::render::grids::grey(file.float("line_5577").unwrap());
                let want = Medium::new(file.float("density"), Some(&grey), 1.5, 2.0).unwrap();
                for threads in [1, 2] {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                    let got = pool.install(|| read_line_medium(&path, "line_5577", 1.5, 2.0)).unwrap().unwrap().medium;
                    assert!(got == want, "{c:?} half {half} threads {threads}");
                    assert!(!got.fields[0].values.is_half(), "the density is full floats: one shared 32-bit field");
                }
                assert!(read_line_medium(&path, "line_6300", 1.0, 1.0).unwrap().is_none());
                // Without a density the line alone: kept as half floats
                // when the file stores them so.
                std::fs::write(&path, write_vdb_bytes(&[GridRef::Vec3(&e), GridRef::Float(&line)], &opts).unwrap()).unwrap();
                let alone = Medium::new(None, Some(&grey), 1.5, 2.0).unwrap();
                let got = read_line_medium(&path, "line_5577", 1.5, 2.0).unwrap().unwrap().medium;
                assert!(got == alone, "{c:?} half {half} alone");
                assert_eq!(got.fields[0].values.is_half(), half);
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A render of the medium read straight from the file is byte-identical
    /// to the render of the grids in memory.
    #[test]
    fn render_from_file_equals_render_in_memory() {
        use crate::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        use crate::render::{render, render_prepared, Prepared, RenderSettings, Volume};
        let tr = Transform::new(0.5, DVec3::ZERO);
        let (d, e) = medium_grids(tr, tr);
        let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
        let mut scene = crate::scene::Scene::default();
        scene.terrain.kind = crate::scene::TerrainKind::None;
        scene.render.width = 24;
        scene.render.height = 16;
        scene.render.spp = 4;
        scene.camera.position = [4.0, -30.0, 2.0];
        scene.camera.look_at = [4.0, 0.0, 2.0];
        scene.volume.emission_scale = 40.0;
        let settings = RenderSettings::from_scene(&scene);
        let volume = Volume { density: Some(&d), emission: Some(&e) };
        let want = render(&settings, &volume, &crate::util::progress::NoProgress).unwrap();
        let m = read_render_medium_bytes(&bytes, 1.0, 1.0).unwrap().unwrap().medium;
        let p = Prepared::with_medium(&settings, m.clone(), None).unwrap();
        let got = render_prepared(&p, &crate::util::progress::NoProgress).unwrap();
        let bits = |img: &crate::render::Image| img.pixels.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert!(bits(&want).iter().any(|&b| b != 0), "the camera sees the volume");
        assert_eq!(bits(&got), bits(&want));
        // With a terrain lit by the volume: the emission sampler built from
        // the medium equals the one built from the grid.
        let mut lit = settings.clone();
        lit.terrain.kind = crate::scene::TerrainKind::Plane;
        lit.terrain.height = -1.0;
        let want = render(&lit, &volume, &crate::util::progress::NoProgress).unwrap();
        let p = Prepared::with_medium(&lit, m, None).unwrap();
        assert!(p.sampler().is_some(), "the terrain's sampler is exercised");
        assert_eq!(bits(&render_prepared(&p, &crate::util::progress::NoProgress).unwrap()), bits(&want));
        assert!(want.stats.shadow_samples > 0, "shadow rays were traced");
    }

    /// The listing (`parse::list_grids`) names, types and metadata every
    /// grid as the whole parse does; the recorded observer is the key's,
    /// the default for a bake of ours without it, none for a file from
    /// elsewhere, and an unknown one is refused by name.
    #[test]
    fn the_listing_gives_the_grids_and_the_observer_they_record() {
        use crate::io::vdb::write::{write_vdb_bytes, GridRef, MetaValue, WriteOptions};
        let tr = Transform::new(0.5, DVec3::ZERO);
        let (d, e) = medium_grids(tr, tr);
        let mut line = Grid::new("line_5577", 0.0f32, tr);
        line.set(IVec3::new(1, 2, 3), 4.0);
        let file = |meta: Vec<(&str, MetaValue)>| {
            let metadata = meta.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
            let opts = WriteOptions { metadata, ..WriteOptions::default() };
            write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e), GridRef::Float(&line)], &opts).unwrap()
        };
        let hash = ("aurora_scene_hash", MetaValue::String("0123".into()));
        let observer = |bytes: &[u8]| {
            let listed = parse::list_grids(bytes).unwrap();
            let whole = parse::parse_file(bytes, &|_| false).unwrap();
            assert_eq!(listed.len(), whole.grids.len());
            for (l, w) in listed.iter().zip(&whole.grids) {
                assert_eq!(
                    (l.name(), l.kind, &l.metadata, l.end_pos),
                    (w.header.name(), w.header.kind, &w.header.metadata, w.header.end_pos)
                );
            }
            baked_observer(listed.iter().map(|h| h.metadata.as_slice()))
        };
        let eye = file(vec![hash.clone(), (crate::io::bake_folder::OBSERVER_KEY, MetaValue::String("eye".into()))]);
        assert_eq!(observer(&eye).unwrap(), Some(Observer::Eye));
        assert_eq!(observer(&file(vec![hash.clone()])).unwrap(), Some(Observer::Camera));
        assert_eq!(observer(&file(Vec::new())).unwrap(), None);
        let owl = file(vec![hash, (crate::io::bake_folder::OBSERVER_KEY, MetaValue::String("owl".into()))]);
        let m = observer(&owl).unwrap_err().to_string();
        assert!(m.contains("aurora_observer = \"owl\"") && m.contains("\"camera\", \"eye\""), "{m}");
        // A damaged listing is an error, never a panic.
        for cut in [0, 8, 40, eye.len() / 3] {
            assert!(parse::list_grids(&eye[..cut]).is_err(), "cut at {cut}");
        }
    }

    /// Bad files give typed errors, never a panic: every 7th byte of a
    /// small file's last two thirds damaged in turn, a truncated file,
    /// negative voxels (named with their coordinates; the writer refuses
    /// NaN, `render_read_drops_only_zero_leaves` covers the rest).
    #[test]
    fn bad_files_give_errors_on_the_medium_path() {
        use crate::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        for i in 0..40 {
            d.set(IVec3::new(i, i % 5, 2 * i), 1.0 + i as f32);
            e.set(IVec3::new(i, 1, 0), [i as f32, 0.0, 1.0]);
        }
        let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
        for cut in [0, 8, bytes.len() / 2, bytes.len() - 1] {
            assert!(read_render_medium_bytes(&bytes[..cut], 1.0, 1.0).is_err(), "cut at {cut}");
        }
        let start = bytes.len() / 3;
        for at in (start..bytes.len()).step_by(7) {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut b = bytes.clone();
                b[at] ^= flip;
                // Either an error or a medium (a flipped float bit can be a
                // valid value): never a panic.
                let _ = read_render_medium_bytes(&b, 1.0, 1.0);
            }
        }
        for (v, want) in [(-1.0f32, "-1.0"), (-1e-30, "-1e-30")] {
            let mut bad = d.clone();
            bad.set(IVec3::new(3, 4, 5), v);
            let bytes = write_vdb_bytes(&[GridRef::Float(&bad), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
            let err = read_render_medium_bytes(&bytes, 1.0, 1.0).err().expect("refused").to_string();
            assert!(err.contains("[3, 4, 5]") && err.contains(want) && err.contains("density"), "{err}");
        }
    }
}
