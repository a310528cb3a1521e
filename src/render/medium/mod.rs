//! The renderer's plain-data view of the volume: sigma_t and emission laid out
//! for fast, exact sampling along rays, built once per render.
//!
//! Model. Cycles (like OpenVDB's `BoxSampler`) samples a grid trilinearly
//! between the eight voxel centres around a point; voxel (i,j,k) sits at
//! index point (i,j,k) and inactive voxels read as 0
//! (docs/guide.md, "How Cycles reads the VDB"). So the field is a trilinear
//! polynomial inside each *dual cell* `[i,i+1] x [j,j+1] x [k,k+1]` of index
//! space. Dual cells are grouped into *dual leaves* of 8^3 cells: dual leaf
//! `D` covers index space `[8D, 8D+8]^3` and needs the 9^3 voxel values
//! `8D .. 8D+8`: its own 8^3 leaf plus the faces, edges and corner of its
//! three upper neighbours. A dual leaf exists iff one of its 9^3 voxels is
//! active and non-zero, so the field is exactly 0 outside the stored dual
//! leaves: a single active voxel creates the 8 dual leaves (or fewer)
//! around it, and its tent-shaped footprint reaches exactly one voxel past
//! its centre. The values are stored once per source leaf (a *block*) and
//! each dual leaf reads its neighbours' blocks in place: copying 9^3
//! "ghost" values per dual leaf instead would store 729 values per dual
//! leaf against 512 per source leaf, on more dual leaves than source
//! leaves, and the copy would dominate the build.
//!
//! One concept per file:
//! - `layout.rs`: the tree's node levels, slot functions and mask bits;
//! - `field.rs`: a [`Field`](field::Field) (blocks, dual leaves, the tree
//!   over them) and its lookup;
//! - `dual.rs`: per source leaf, the dual leaves it feeds and the dual
//!   cells with a non-zero corner;
//! - `check.rs`: what the renderer accepts (finite, >= 0, zero background,
//!   a scaled peak that cannot overflow the film);
//! - `build.rs`: the one parallel pass from [`LeafSource`]s to a field,
//!   with its memory check;
//! - `values.rs`: the stored values, 32-bit or half floats;
//! - `velocity.rs`: the velocity grid the motion blur advects lookups along;
//! - here: the [`Medium`], which channel of which field holds sigma_t and
//!   emission, and the volume scales applied at lookup.
//!
//! The structure is plain data: no references into the source grids.

pub mod build;
pub mod check;
mod dual;
pub mod field;
pub mod layout;
pub mod values;
pub mod velocity;

use crate::grid::leaf_source::{GridSource, LeafSource};
use crate::grid::Grid;
use check::{check_header, check_scaled_peak};
use field::Field;
use glam::DVec3;

use crate::render::settings::RenderError;

/// Where a quantity lives: which field, which channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Channel {
    pub field: usize,
    pub channel: usize,
}

/// The volume as the renderer sees it: sigma_t = density_scale * density and
/// emission e = emission_scale * emission, each on its grid's own transform.
/// When both grids share a transform they share one [`Field`] (channel 0 =
/// density, channels 1..4 = emission), so a ray walks one tree. The fields
/// hold the grids' values as stored (unit scale) and the scales are applied
/// at lookup ([`Field::scale`]), so [`Medium::set_scales`] changes them
/// without a rebuild.
#[derive(Debug, Clone, PartialEq)]
pub struct Medium {
    pub fields: Vec<Field>,
    /// sigma_t, if the volume has any extinction.
    pub sigma_t: Option<Channel>,
    /// First of the three emission channels, if the volume emits.
    pub emission: Option<Channel>,
    /// Density, then emission: where its values are stored, its largest
    /// value and its grid's name; `None` for a missing grid or one with no
    /// non-zero active voxel. Kept whatever the scale, so that a scale
    /// leaving or reaching 0 needs no rebuild either.
    stored: [Option<Stored>; 2],
    pub density_scale: f64,
    pub emission_scale: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct Stored {
    channel: Channel,
    peak: f32,
    grid: String,
}

/// The scene keys of the two scales, density then emission.
const SCALE_KEYS: [&str; 2] = ["density_scale", "emission_scale"];

fn check_scales(scales: [f64; 2]) -> Result<(), RenderError> {
    for (what, s) in SCALE_KEYS.iter().zip(scales) {
        if !(s.is_finite() && s >= 0.0) {
            return Err(RenderError::Settings(format!("volume.{what} = {s} must be finite and >= 0")));
        }
    }
    Ok(())
}

impl Medium {
    /// Builds the medium. A missing grid, a zero scale or a grid with no
    /// non-zero voxel means "no extinction" / "no emission".
    pub fn new(
        density: Option<&Grid<f32>>,
        emission: Option<&Grid<[f32; 3]>>,
        density_scale: f64,
        emission_scale: f64,
    ) -> Result<Medium, RenderError> {
        let d = density.map(GridSource);
        let e = emission.map(GridSource);
        Medium::from_sources(
            d.as_ref().map(|s| s as &dyn LeafSource),
            e.as_ref().map(|s| s as &dyn LeafSource),
            density_scale,
            emission_scale,
        )
    }

    /// [`Medium::new`] from any [`LeafSource`]s (a density source of 1
    /// channel, an emission source of 3): the same medium, field for field,
    /// from a grid in memory or from a file's leaves decoded on the fly.
    /// Errors (in this order): a scale out of range, a bad transform or
    /// background, then per source (density first) its first bad voxel or
    /// unreadable leaf in key order and a scaled peak above
    /// [`check::MAX_SCALED_VALUE`].
    pub fn from_sources(
        density: Option<&dyn LeafSource>,
        emission: Option<&dyn LeafSource>,
        density_scale: f64,
        emission_scale: f64,
    ) -> Result<Medium, RenderError> {
        let scales = [density_scale, emission_scale];
        check_scales(scales)?;
        let srcs = [density, emission];
        for (s, want) in srcs.iter().zip([1, 3]) {
            if let Some(s) = s {
                if s.channels() != want {
                    return Err(RenderError::Grid {
                        grid: s.name().to_string(),
                        message: format!("has {} components a voxel, expected {want}", s.channels()),
                    });
                }
                check_header(*s)?;
            }
        }
        // Each field's value storage is checked against the process's
        // memory limit before it is allocated ([`Field::from_sources`]).
        let limit = crate::util::memory::available();
        let mut reserved = 0.0;
        // Sources sharing a transform share a field. A source without
        // leaves (a bake's density with `density_a` 0) has no non-zero
        // voxel: it feeds no field, and is left out before the pass rather
        // than found out after it (which would build the field twice).
        let fed: [Option<&dyn LeafSource>; 2] = srcs.map(|s| s.filter(|s| s.leaf_count() > 0));
        let groups: Vec<Vec<usize>> = match fed {
            [Some(d), Some(e)] if d.transform() == e.transform() => vec![vec![0, 1]],
            _ => (0..2).filter(|&k| fed[k].is_some()).map(|k| vec![k]).collect(),
        };
        let mut medium = Medium { fields: Vec::new(), sigma_t: None, emission: None, stored: [None, None], density_scale, emission_scale };
        for group in groups {
            let list: Vec<&dyn LeafSource> = group.iter().filter_map(|&k| srcs[k]).collect();
            let (mut field, reports) = Field::from_sources(&list, reserved, &limit)?;
            let mut peaks = [0.0f32; 2];
            for (r, &k) in reports.into_iter().zip(&group) {
                if let Some(e) = r.fail {
                    return Err(e);
                }
                let name = srcs[k].map_or("", |s| s.name());
                check_scaled_peak(name, r.peak, SCALE_KEYS[k], scales[k])?;
                peaks[k] = r.peak;
            }
            // A source feeds the field iff it has a non-zero active voxel:
            // its peak (values are >= 0) is above 0. Rebuilt without a
            // source that has none (rare: an all-zero grid).
            let live: Vec<usize> = group.iter().copied().filter(|&k| peaks[k] > 0.0).collect();
            if live.is_empty() {
                continue;
            }
            if live.len() < group.len() {
                let list: Vec<&dyn LeafSource> = live.iter().filter_map(|&k| srcs[k]).collect();
                drop(field); // never two copies at once
                field = Field::from_sources(&list, reserved, &limit)?.0;
            }
            let fi = medium.fields.len();
            let mut ch = 0;
            for &k in &live {
                let src = srcs[k].expect("live sources exist");
                medium.stored[k] = Some(Stored { channel: Channel { field: fi, channel: ch }, peak: peaks[k], grid: src.name().into() });
                ch += src.channels();
            }
            reserved += field.values.bytes() as f64;
            medium.fields.push(field);
        }
        medium.set_scales(density_scale, emission_scale)?;
        Ok(medium)
    }

    /// Sets `volume.density_scale` and `volume.emission_scale` without
    /// rebuilding anything (the fields hold unit values; the scales are
    /// applied at lookup): the medium then equals `Medium::new` with these
    /// scales, field for field. On error (a scale out of range, or a grid's
    /// largest value times its scale above [`check::MAX_SCALED_VALUE`]) the medium
    /// is unchanged.
    pub fn set_scales(&mut self, density_scale: f64, emission_scale: f64) -> Result<(), RenderError> {
        let scales = [density_scale, emission_scale];
        check_scales(scales)?;
        for (k, st) in self.stored.iter().enumerate() {
            if let Some(st) = st {
                check_scaled_peak(&st.grid, st.peak, SCALE_KEYS[k], scales[k])?;
            }
        }
        for f in &mut self.fields {
            f.scale = [1.0; 4];
        }
        for (k, (st, n)) in self.stored.iter().zip([1, 3]).enumerate() {
            if let Some(st) = st {
                let c = st.channel;
                self.fields[c.field].scale[c.channel..c.channel + n].fill(scales[k]);
            }
        }
        let on = |k: usize| self.stored[k].as_ref().filter(|_| scales[k] > 0.0).map(|s| s.channel);
        self.sigma_t = on(0);
        self.emission = on(1);
        self.density_scale = density_scale;
        self.emission_scale = emission_scale;
        Ok(())
    }

    /// The largest sigma_t anywhere in the medium (0 without extinction):
    /// the density grid's largest stored value times `volume.density_scale`,
    /// a majorant of the trilinear field (a convex combination of stored
    /// values, 0 outside them) for the shadow rays' ratio tracking. O(1):
    /// the build keeps each source's peak, and a scale edit changes only
    /// the factor, so nothing is cached that could go stale.
    pub fn sigma_t_majorant(&self) -> f64 {
        match (self.sigma_t, &self.stored[0]) {
            (Some(c), Some(st)) => st.peak as f64 * self.fields[c.field].scale[c.channel],
            _ => 0.0,
        }
    }

    /// sigma_t at a world point (per unit length).
    pub fn sigma_t_at(&self, p: DVec3) -> f64 {
        let Some(c) = self.sigma_t else { return 0.0 };
        let f = &self.fields[c.field];
        let mut v = [0.0; 4];
        f.sample_index(f.transform.world_to_index(p), &mut v);
        v[c.channel]
    }

    /// Emitted radiance per unit length at a world point.
    pub fn emission_at(&self, p: DVec3) -> [f64; 3] {
        let Some(c) = self.emission else { return [0.0; 3] };
        let f = &self.fields[c.field];
        let mut v = [0.0; 4];
        f.sample_index(f.transform.world_to_index(p), &mut v);
        [v[c.channel], v[c.channel + 1], v[c.channel + 2]]
    }

    /// Total dual leaves stored.
    pub fn leaf_count(&self) -> usize {
        self.fields.iter().map(Field::leaf_count).sum()
    }

    pub fn memory_bytes(&self) -> usize {
        self.fields.iter().map(Field::memory_bytes).sum()
    }

    /// World-space box enclosing every field's support, if any.
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        self.fields.iter().filter(|f| !f.is_empty()).map(Field::world_bounds).reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }
}
