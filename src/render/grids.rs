//! The renderer's grid choice: which grids of a file it reads and what it
//! makes of them. A float `density` grid is extinction per unit length; an
//! `emission` grid is vec3 emission, or a float one counted as grey (the
//! same value in all three channels). Either may be absent, not both. A grid
//! the renderer would use but cannot (a vec3 or bool `density`, say) is
//! refused rather than silently ignored.
//!
//! The choice is made over a plain listing of the file's grids ([`Listed`])
//! and the decoded grids, so the renderer knows nothing of file formats:
//! `crate::app::vdb_for_render::render_grids` lists a VDB file and calls [`choose`].

use crate::grid::{Grid, Leaf};

/// A grid's value type, as far as the choice is concerned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridType {
    Float,
    Vec3,
    /// Any other type (bool, double, int, ...): never read.
    Other,
}

/// One grid of a file, as its header lists it.
#[derive(Clone, Copy, Debug)]
pub struct Listed<'a> {
    pub name: &'a str,
    /// The type as stored, e.g. `Tree_vec3s_5_4_3` (for messages).
    pub type_name: &'a str,
    pub kind: GridType,
}

/// Why a file cannot be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderGridsError {
    #[error("holds neither a `density` nor an `emission` grid (grids: {0})")]
    NoAuroraGrids(String),
    /// A grid the renderer would use has a type it cannot (a vec3 or bool
    /// `density`, say): refused rather than silently ignored.
    #[error("grid `{name}` is {type_name}; the renderer needs {expected}")]
    WrongType { name: String, type_name: String, expected: &'static str },
    /// A high-column grid (`density_high`, `emission_high`) that cannot be
    /// added to its fine grid, or one without its fine grid.
    #[error("{0}")]
    High(String),
    /// The emission cannot be re-coloured for the observer asked
    /// ([`super::recolour`]).
    #[error(transparent)]
    Recolour(#[from] super::recolour::RecolourError),
}

impl RenderGridsError {
    /// Always the user's input: the file given to render (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// Refuses a grid the renderer would use but cannot (a vec3 or bool
/// `density`, a bool `emission`): the type check of [`choose`], on the
/// listing alone.
pub fn check_types(listing: &[Listed<'_>]) -> Result<(), RenderGridsError> {
    for g in listing {
        let expected = match g.name {
            "density" if g.kind != GridType::Float => "a float grid (extinction per unit length)",
            "emission" if !matches!(g.kind, GridType::Float | GridType::Vec3) => "a vec3 grid (or a float grid, taken as grey)",
            "density_high" if g.kind != GridType::Float => "a float grid (the density's high column, crate::grid::high_column)",
            "emission_high" if g.kind != GridType::Vec3 => "a vec3 grid (the emission's high column, crate::grid::high_column)",
            _ => continue,
        };
        return Err(RenderGridsError::WrongType { name: g.name.to_string(), type_name: g.type_name.to_string(), expected });
    }
    Ok(())
}

/// The density and emission grids [`choose`] takes from a file; either may
/// be absent, not both.
pub type ChosenGrids = (Option<Grid<f32>>, Option<Grid<[f32; 3]>>);

/// The grids a renderer needs: from `listing` (every grid of the file, in
/// file order) and the file's decoded `float_grids` and `vec3_grids` (each
/// in file order), the first float `density` and the first `emission`
/// (vec3, else float taken as grey). A `density_high` or `emission_high`
/// grid (the high column at a resolution of its own, `crate::grid::high_column`) is
/// added to its fine grid ([`crate::grid::high_column::merge`]), as a renderer
/// sampling both grids sees them.
pub fn choose(
    listing: &[Listed<'_>],
    float_grids: Vec<Grid<f32>>,
    vec3_grids: Vec<Grid<[f32; 3]>>,
) -> Result<ChosenGrids, RenderGridsError> {
    check_types(listing)?;
    let names: Vec<&str> = listing.iter().map(|g| g.name).collect();
    let [density, density_high, float_emission] = first_named(float_grids, ["density", "density_high", "emission"]);
    let [emission, emission_high] = first_named(vec3_grids, ["emission", "emission_high"]);
    let emission = emission.or_else(|| float_emission.as_ref().map(grey));
    let density = with_high(density, density_high, "density")?;
    let emission = with_high(emission, emission_high, "emission")?;
    if density.is_none() && emission.is_none() {
        return Err(RenderGridsError::NoAuroraGrids(if names.is_empty() { "none".into() } else { names.join(", ") }));
    }
    Ok((density, emission))
}

/// The first of `grids` (in file order) named each of `names`.
fn first_named<T, const N: usize>(grids: Vec<Grid<T>>, names: [&str; N]) -> [Option<Grid<T>>; N] {
    let mut found = [(); N].map(|_| None);
    for g in grids {
        if let Some(k) = names.iter().position(|n| *n == g.name) {
            found[k].get_or_insert(g);
        }
    }
    found
}

/// `fine` plus its high column, when the file has one.
fn with_high<T: crate::grid::VoxelValue>(
    fine: Option<Grid<T>>,
    high: Option<Grid<T>>,
    name: &str,
) -> Result<Option<Grid<T>>, RenderGridsError> {
    match (fine, high) {
        (Some(f), Some(h)) => crate::grid::high_column::merge(&f, &h).map(Some).map_err(|e| RenderGridsError::High(e.to_string())),
        (None, Some(_)) => Err(RenderGridsError::High(format!("grid `{name}_high` has no `{name}` grid to add to"))),
        (f, None) => Ok(f),
    }
}

/// A float grid as a grey `emission` grid: its value in all three
/// channels, the same leaves and masks.
pub fn grey(f: &Grid<f32>) -> Grid<[f32; 3]> {
    let mut grey = Grid::new("emission", [f.background; 3], f.transform);
    for leaf in f.leaves() {
        let mut l = Leaf::new(leaf.origin, [f.background; 3]);
        l.mask = leaf.mask;
        for (dst, src) in l.values.iter_mut().zip(leaf.values.iter()) {
            *dst = [*src; 3];
        }
        grey.insert_leaf(l);
    }
    grey
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use glam::{DVec3, IVec3};

    fn float_grid(name: &str, at: IVec3, v: f32) -> Grid<f32> {
        let mut g = Grid::new(name, 0.0f32, Transform::new(0.5, DVec3::ZERO));
        g.set(at, v);
        g
    }

    fn listed<'a>(name: &'a str, kind: GridType) -> Listed<'a> {
        Listed { name, type_name: "Tree_x_5_4_3", kind }
    }

    #[test]
    fn float_emission_is_grey_and_density_is_kept() {
        let at = IVec3::new(3, -9, 17);
        let grids = vec![float_grid("density", at, 2.0), float_grid("emission", at, 0.25)];
        let list = [listed("density", GridType::Float), listed("emission", GridType::Float)];
        let (d, e) = choose(&list, grids, Vec::new()).unwrap();
        assert_eq!(d.unwrap().get(at), 2.0);
        let e = e.unwrap();
        assert_eq!(e.name, "emission");
        assert_eq!(e.get(at), [0.25; 3]);
        assert_eq!(e.get(at + IVec3::X), [0.0; 3], "inactive voxels stay at the background");
    }

    #[test]
    fn vec3_emission_wins_over_a_float_one() {
        let at = IVec3::new(1, 2, 3);
        let mut v = Grid::new("emission", [0.0f32; 3], Transform::new(0.5, DVec3::ZERO));
        v.set(at, [1.0, 2.0, 3.0]);
        let list = [listed("emission", GridType::Float), listed("emission", GridType::Vec3)];
        let (d, e) = choose(&list, vec![float_grid("emission", at, 9.0)], vec![v]).unwrap();
        assert!(d.is_none());
        assert_eq!(e.unwrap().get(at), [1.0, 2.0, 3.0]);
    }

    #[test]
    fn wrong_types_and_missing_grids_are_refused_by_name() {
        let m = choose(&[listed("density", GridType::Vec3)], Vec::new(), Vec::new()).unwrap_err().to_string();
        assert!(m.contains("`density`") && m.contains("float grid"), "{m}");
        let m = choose(&[listed("emission", GridType::Other)], Vec::new(), Vec::new()).unwrap_err().to_string();
        assert!(m.contains("`emission`") && m.contains("vec3 grid"), "{m}");
        let m = choose(&[listed("temperature", GridType::Float)], vec![float_grid("temperature", IVec3::ZERO, 1.0)], Vec::new())
            .unwrap_err()
            .to_string();
        assert!(m.contains("neither") && m.contains("temperature"), "{m}");
        let m = choose(&[], Vec::new(), Vec::new()).unwrap_err().to_string();
        assert!(m.contains("grids: none"), "{m}");
    }
}
