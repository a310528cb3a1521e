//! Validation of a parsed scene: every key's range checked from its table of
//! keys ([`super::keys`]), then the rules between keys, each error naming
//! the file, line, key, value and allowed range ([`RangeError`]); the range
//! limits (`MAX_*`); the shape check that runs before serde. The camera's
//! one set of limits is `Camera::problems` (`super::camera`). Validity is a property of the scene alone,
//! never of the machine: whether a bake fits in memory is decided at bake
//! time (`crate::pipeline::memory::budget`).

use super::keys::KeySpec;
use super::tables::TABLES;
use super::{colour::*, curtain::*, root::Scene};
use crate::util::fmath;
use std::fmt;

/// The line names `grid.lines` takes, in `crate::physics::emission::line_colour::LINES` order
/// (557.7, 630.0, 636.4, 427.8 nm, the N2 1P bands; `crate::physics::emission::line_table` reads
/// them from here).
pub const LINE_KEYS: [&str; 5] = ["5577", "6300", "6364", "4278", "n2_1p"];

/// Largest seed: TOML integers are signed 64-bit, so a scene (and the
/// `--seed` flag, whose bake is written back as TOML) holds at most i64::MAX.
pub const MAX_SEED: u64 = i64::MAX as u64;
/// Largest colour-map component (linear RGB per unit deposited power, about
/// 1 for the report's map): far beyond any look, and small enough that a
/// voxel's emission stays within single precision.
pub const MAX_COLORMAP_VALUE: f64 = 1e6;
/// Largest `--threads`.
pub const MAX_THREADS: u64 = 1_024;

// ---------------------------------------------------------------- errors

/// A scene that could not be read or is out of range.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read (the error is part of the message, not a
    /// `source`, so `{:#}` does not print it twice).
    #[error("{file}: cannot read: {error}")]
    Io { file: String, error: std::io::Error },
    /// Neither a file nor a preset: the message names every preset, and
    /// the nearest (`hint`: "; did you mean `corona`?") when one is near.
    #[error("{name}: no such file, and no preset of that name{hint} (presets: {}; `aurora scene --list` says what each shows)", .presets.join(", "))]
    Unknown { name: String, presets: Vec<&'static str>, hint: String },
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))]
    Invalid(Vec<RangeError>),
    /// An override (`crate::scene::overrides`) that is not a key of the
    /// scene or does not fit it; `given` is how the user gave it.
    #[error("{given}: {message}")]
    Override { given: String, message: String },
}

impl SceneError {
    /// Always the user's input: the scene file or preset named (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// One value outside its allowed range.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeError {
    pub file: String,
    pub line: Option<usize>,
    pub key: String,
    pub value: String,
    pub allowed: String,
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: ", self.file, l)?,
            None => write!(f, "{}: ", self.file)?,
        }
        if self.value.is_empty() {
            // A rule between keys, not one value's range.
            return write!(f, "{}: {}", self.key, self.allowed);
        }
        write!(f, "{} = {} is out of range: {}", self.key, quoted(&self.value), self.allowed)
    }
}

// ---------------------------------------------------------------- checks

impl Scene {
    /// Checks every key's range (from its table of keys, [`super::keys`]),
    /// then the rules between keys; `text` (the TOML source) is used to
    /// find lines.
    pub fn validate(&self, file: &str, text: Option<&str>) -> Result<(), SceneError> {
        let mut v = Validator { file, text, errors: Vec::new() };
        let doc = toml::Table::try_from(self).expect("a scene serialises to a table");
        for table in TABLES {
            match (table.name, doc.get(table.name)) {
                ("", _) => v.table(None, table.keys, &doc),
                // The camera's limits are its own (`Camera::problems`, below).
                ("camera", _) => {}
                ("curtain", Some(toml::Value::Array(curtains))) => {
                    for (i, c) in curtains.iter().enumerate() {
                        if let toml::Value::Table(c) = c {
                            v.table(Some(("curtain", i)), table.keys, c);
                        }
                    }
                }
                (name, Some(toml::Value::Table(t))) => v.table(Some((name, 0)), table.keys, t),
                _ => {}
            }
        }
        self.check_rules(&mut v);
        if v.errors.is_empty() {
            Ok(())
        } else {
            Err(SceneError::Invalid(v.errors))
        }
    }

    /// The rules a key's range alone does not say: between keys, or over a
    /// whole list; each names its key.
    fn check_rules(&self, v: &mut Validator<'_>) {
        if self.curtains.is_empty() {
            v.push(None, "curtain", "[]".into(), "at least one [[curtain]] table is required".into());
        }
        for (i, c) in self.curtains.iter().enumerate() {
            let t = Some(("curtain", i));
            if let Some(p) = &c.path {
                v.path(t, p);
            }
            if let Some(p) = &c.magnetic_path {
                v.magnetic_path(t, p, c.path.is_some(), self.site.as_ref());
            }
            if c.bend_km * 2.0 >= c.width {
                v.push(
                    t,
                    "bend_km",
                    c.bend_km.to_string(),
                    format!("must be less than curtain[{i}].width / 2 = {} (raise width or lower bend_km)", c.width / 2.0),
                );
            }
        }
        if let super::grid::VoxelSize::Km(vs) = self.grid.voxel_size {
            if !(MIN_VOXEL_KM..=MAX_VOXEL_KM).contains(&vs) {
                v.push(
                    Some(("grid", 0)),
                    "voxel_size",
                    vs.to_string(),
                    format!(
                        "must be in [{MIN_VOXEL_KM}, {MAX_VOXEL_KM}] km: a finer voxel puts a scene's few thousand km beyond the grid's \
                         32-bit indices, a coarser one holds the whole aurora in one voxel (or \"auto\")"
                    ),
                );
            }
        }
        if self.curtains.iter().all(|c| c.beam_weight <= 0.0) && !self.curtains.is_empty() {
            v.push(Some(("curtain", 0)), "beam_weight", "0".into(), "at least one curtain needs beam_weight > 0".into());
        }

        let b = &self.beams;
        if !(b.delta_alpha_deg >= 0.0 && b.delta_alpha_deg <= b.alpha_d_deg) {
            v.push(
                Some(("beams", 0)),
                "delta_alpha_deg",
                b.delta_alpha_deg.to_string(),
                format!("must be in [0, alpha_d_deg = {}]", b.alpha_d_deg),
            );
        }

        let e = &self.earth;
        if let Some(pole) = e.magnetic_pole {
            if e.radius_km == 0.0 && !v.names("earth.magnetic_pole") {
                v.push(
                    Some(("earth", 0)),
                    "magnetic_pole",
                    format!("{pole:?}"),
                    "a dipole pole needs a round Earth: set earth.radius_km > 0".into(),
                );
            }
        }

        if self.oval.is_some() && self.site.is_none() {
            v.push(
                Some(("oval", 0)),
                "kp",
                String::new(),
                "[oval] places the arcs over a place at an hour: add a [site] table (latitude_deg, longitude_deg, utc), or remove [oval]"
                    .into(),
            );
        }
        if let Some(site) = &self.site {
            if let Err(e) = crate::geometry::astronomy::time::Utc::parse_rfc3339(&site.utc) {
                v.push(
                    Some(("site", 0)),
                    "utc",
                    format!("\"{}\"", quoted(&site.utc)),
                    format!("must be an RFC 3339 time between 1900 and 2100, such as \"2026-12-07T22:00:00Z\" ({e})"),
                );
            } else if site.field == super::site::SiteField::Igrf {
                // IGRF-14's span (`crate::physics::igrf`, whose table starts
                // in 1900 and ends in 2030).
                use crate::geometry::astronomy::time::Utc;
                let (first, last) = (Utc::parse_rfc3339("1900-01-01T00:00:00Z"), Utc::parse_rfc3339("2030-01-01T00:00:00Z"));
                let t = Utc::parse_rfc3339(&site.utc).map(|t| t.plus_seconds(self.animation.time_s));
                if let (Ok(t), Ok(first), Ok(last)) = (t, first, last) {
                    if !(first..=last).contains(&t) {
                        v.push(
                            Some(("site", 0)),
                            "utc",
                            format!("\"{}\"", quoted(&site.utc)),
                            "with field = \"igrf\" must be between 1900-01-01 and 2030-01-01, IGRF-14's years; set field = \"scene\" for another".into(),
                        );
                    }
                }
            }
        }

        let c = &self.colour;
        let t = Some(("colour", 0));
        if c.mode == ColourMode::Colormap {
            if c.colormap.len() < 2 {
                v.push(t, "colormap", format!("{} rows", c.colormap.len()), "needs at least 2 rows of [altitude_km, r, g, b]".into());
            }
            for (i, w) in c.colormap.windows(2).enumerate() {
                if !(w[1][0] > w[0][0]) {
                    v.push(t, "colormap", format!("row {}: {}", i + 1, w[1][0]), "altitudes must be strictly ascending".into());
                }
            }
            for (i, r) in c.colormap.iter().enumerate() {
                if r.iter().any(|x| !x.is_finite()) || r[1..].iter().any(|&x| !(0.0..=MAX_COLORMAP_VALUE).contains(&x)) {
                    v.push(
                        t,
                        "colormap",
                        format!("row {i}: {r:?}"),
                        format!("values must be finite, colours in [0, {MAX_COLORMAP_VALUE:e}]"),
                    );
                }
            }
        }

        let g = &self.grid;
        let t = Some(("grid", 0));
        let keys = LINE_KEYS.map(|k| format!("\"{k}\"")).join(", ");
        for (i, name) in g.lines.iter().enumerate() {
            if !LINE_KEYS.contains(&name.as_str()) {
                v.push(t, "lines", format!("\"{name}\""), format!("must be one of {keys}"));
            } else if g.lines[..i].contains(name) {
                v.push(t, "lines", format!("\"{name}\""), "is listed twice".into());
            }
        }
        if !g.lines.is_empty() && self.colour.mode != ColourMode::Physical {
            v.push(t, "lines", format!("{:?}", g.lines), "needs colour.mode = \"physical\" (a colour map has no lines)".into());
        }

        for (key, value, allowed) in self.camera.problems() {
            v.push(Some(("camera", 0)), key, value, allowed);
        }

        let ter = &self.terrain;
        if !(ter.extent[2] > ter.extent[0] && ter.extent[3] > ter.extent[1]) {
            v.push(Some(("terrain", 0)), "extent", format!("{:?}", ter.extent), "must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0".into());
        }
    }
}

/// Keys a `path` replaces.
const STRAIGHT_KEYS: [&str; 3] = ["center", "length", "rotation_deg"];

/// Refuses arrays of the wrong length before serde sees them (serde fills a
/// fixed-size array from the first N values of a longer TOML array and drops
/// the rest silently: `center = [-20, 0, 999]` would bake at (-20, 0)).
///
/// The expected shapes come from the scene's own defaults, so every key added
/// later is covered: an array of numbers there is a fixed-size array (its
/// length is the one required); an array of arrays (the colour map) has rows
/// of the default row's length; an array of tables (`[[curtain]]`) is checked
/// table by table against a default curtain.
pub fn check_shapes(text: &str, file: &str) -> Result<(), SceneError> {
    let user: toml::Table = match text.parse() {
        Ok(t) => t,
        // Syntax errors are reported by the parser proper, with its message.
        Err(_) => return Ok(()),
    };
    let reference = Scene { curtains: vec![Curtain::default()], ..Scene::default() };
    let reference = toml::Table::try_from(&reference).expect("a scene serialises to a table");
    let mut v = Validator { file, text: Some(text), errors: Vec::new() };
    shapes_table(&user, &reference, None, &mut v);
    if let Some(toml::Value::Array(curtains)) = user.get("curtain") {
        for (i, c) in curtains.iter().enumerate() {
            let toml::Value::Table(c) = c else { continue };
            if c.contains_key("magnetic_path") {
                let both: Vec<&str> = STRAIGHT_KEYS.iter().copied().filter(|k| c.contains_key(*k)).collect();
                if !both.is_empty() {
                    let has = both.join(", ");
                    v.push(Some(("curtain", i)), "magnetic_path", String::new(), format!("a curtain takes either a `center` or a `magnetic_path`, not both; this one has magnetic_path and {has}: remove {has} or the magnetic path"));
                }
                if let Some(toml::Value::Array(rows)) = c.get("magnetic_path") {
                    for (k, r) in rows.iter().enumerate() {
                        if !matches!(r, toml::Value::Array(a) if a.len() == 2) {
                            v.push(
                                Some(("curtain", i)),
                                "magnetic_path",
                                format!("point {k}: {r}"),
                                "every point must be [latitude, mlt] (2 values)".into(),
                            );
                        }
                    }
                }
            }
            let Some(path) = c.get("path") else { continue };
            let t = Some(("curtain", i));
            let both: Vec<&str> = STRAIGHT_KEYS.iter().copied().filter(|k| c.contains_key(*k)).collect();
            if !both.is_empty() {
                let has = both.join(", ");
                v.push(
                    t,
                    "path",
                    String::new(),
                    format!(
                        "a curtain takes either a `center` (with `length` and `rotation_deg`) or a `path` (the points of its \
                         ground track), not both; this one has path and {has}: remove {has} or the path"
                    ),
                );
            }
            if let toml::Value::Array(rows) = path {
                for (k, r) in rows.iter().enumerate() {
                    if !matches!(r, toml::Value::Array(a) if a.len() == 2) {
                        v.push(t, "path", format!("point {k}: {r}"), "every point must be [x, y] (2 values, km)".into());
                    }
                }
            }
        }
    }
    if v.errors.is_empty() {
        Ok(())
    } else {
        Err(SceneError::Invalid(v.errors))
    }
}

fn shapes_table(user: &toml::Table, reference: &toml::Table, table: Option<(&str, usize)>, v: &mut Validator<'_>) {
    use toml::Value;
    for (key, uv) in user {
        let Some(rv) = reference.get(key) else { continue };
        match (uv, rv) {
            (Value::Table(ut), Value::Table(rt)) if table.is_none() => shapes_table(ut, rt, Some((key.as_str(), 0)), v),
            (Value::Array(ua), Value::Array(ra)) => match ra.first() {
                Some(Value::Table(rt)) if table.is_none() => {
                    for (i, u) in ua.iter().enumerate() {
                        if let Value::Table(ut) = u {
                            shapes_table(ut, rt, Some((key.as_str(), i)), v);
                        }
                    }
                }
                Some(Value::Array(row)) => {
                    for (i, u) in ua.iter().enumerate() {
                        if let Value::Array(ur) = u {
                            if ur.len() != row.len() {
                                v.push(table, key, format!("row {i}: {u}"), format!("every row must have {} values", row.len()));
                            }
                        }
                    }
                }
                Some(_) if ua.len() != ra.len() => {
                    v.push(table, key, uv.to_string(), format!("must have exactly {} values, not {}", ra.len(), ua.len()));
                }
                _ => {}
            },
            _ => {}
        }
    }
}

struct Validator<'a> {
    file: &'a str,
    text: Option<&'a str>,
    errors: Vec<RangeError>,
}

/// The finest voxel a bake takes, km (10 cm): 2^30 voxels of it span
/// 107,000 km, more than any scene's extent, so every index fits the
/// grid's 32 bits.
pub const MIN_VOXEL_KM: f64 = 1e-4;

/// The coarsest voxel a bake takes, km: beyond it the whole aurora is a
/// voxel or two.
pub const MAX_VOXEL_KM: f64 = 1e5;

/// Most errors one check reports: a file with a million bad entries is
/// refused with its first ones named, in time linear in its size (each
/// error's line is found by a scan of the text).
pub const MAX_REPORTED_ERRORS: usize = 20;

/// Said after the last error reported when there were more.
const MORE_ERRORS: &str = " (and more errors after these; the first ones are named)";

/// Most characters of a value an error quotes: a line's worth.
pub const MAX_QUOTED_CHARS: usize = 120;

/// `text` as an error quotes it: whole, or its first
/// [`MAX_QUOTED_CHARS`] characters and its length.
pub fn quoted(text: &str) -> String {
    quoted_within(text, MAX_QUOTED_CHARS)
}

/// `text` as an error quotes it: whole, or its first `chars` characters
/// and its length.
pub fn quoted_within(text: &str, chars: usize) -> String {
    match text.char_indices().nth(chars) {
        None => text.to_string(),
        Some((at, _)) => format!("{}... ({} bytes in all)", &text[..at], text.len()),
    }
}

impl Validator<'_> {
    fn push(&mut self, table: Option<(&str, usize)>, key: &str, value: String, allowed: String) {
        if self.errors.len() >= MAX_REPORTED_ERRORS {
            if let Some(last) = self.errors.last_mut() {
                if !last.allowed.ends_with(MORE_ERRORS) {
                    last.allowed.push_str(MORE_ERRORS);
                }
            }
            return;
        }
        let line = self.text.and_then(|t| find_key_line(t, table, key));
        let key = match table {
            Some(("curtain", i)) => format!("curtain[{i}].{key}"),
            Some((t, _)) => format!("{t}.{key}"),
            None => key.to_string(),
        };
        self.errors.push(RangeError { file: self.file.to_string(), line, key, value, allowed });
    }
    /// Every key of one table outside its range ([`KeySpec::problem`]).
    fn table(&mut self, t: Option<(&str, usize)>, keys: &[KeySpec], values: &toml::Table) {
        for k in keys {
            if let Some((value, allowed)) = values.get(k.name).and_then(|x| k.problem(x)) {
                self.push(t, k.name, value, allowed);
            }
        }
    }
    /// Whether an error already names `key` (as `table.key`).
    fn names(&self, key: &str) -> bool {
        self.errors.iter().any(|e| e.key == key)
    }
    /// The checks of a curtain's `magnetic_path` (`super::curtain::MAGNETIC_PATH_RULE`).
    fn magnetic_path(&mut self, t: Option<(&str, usize)>, p: &[[f64; 2]], has_path: bool, site: Option<&super::site::SiteParams>) {
        if has_path {
            self.push(t, "magnetic_path", String::new(), "a curtain takes a `path` or a `magnetic_path`, not both: remove one".into());
        }
        if site.is_none() {
            self.push(
                t,
                "magnetic_path",
                String::new(),
                "magnetic coordinates need a place and an hour: add a [site] table (latitude_deg, longitude_deg, utc)".into(),
            );
        }
        if p.len() < 2 {
            self.push(t, "magnetic_path", format!("{} points", p.len()), "needs at least 2 points [latitude, mlt]".into());
        }
        let south = p.first().is_some_and(|q| q[0] < 0.0);
        for (k, q) in p.iter().enumerate() {
            let lat = if south { -q[0] } else { q[0] };
            if !(10.0..=85.0).contains(&lat) {
                self.push(
                    t,
                    "magnetic_path",
                    format!("point {k}: latitude {}", q[0]),
                    "each latitude must be 10 to 85 degrees from the magnetic equator, all in one hemisphere".into(),
                );
            }
            if !(0.0..=24.0).contains(&q[1]) {
                self.push(t, "magnetic_path", format!("point {k}: mlt {}", q[1]), "each magnetic local time must be in [0, 24] h".into());
            }
        }
    }

    /// The checks of a curtain's `path` ([`PATH_RULE`]).
    fn path(&mut self, t: Option<(&str, usize)>, p: &[[f64; 2]]) {
        if p.len() < 2 {
            self.push(t, "path", format!("{} points", p.len()), "needs at least 2 points [x, y]".into());
            return;
        }
        if let Some(k) = p.iter().position(|q| !q.iter().all(|x| x.is_finite() && x.abs() <= 1e4)) {
            self.push(t, "path", format!("point {k}: {:?}", p[k]), "each coordinate must be in [-1e4, 1e4] km".into());
            return;
        }
        for (k, w) in p.windows(2).enumerate() {
            if (fmath::powi(w[1][0] - w[0][0], 2) + fmath::powi(w[1][1] - w[0][1], 2)).sqrt() < 1e-3 {
                self.push(
                    t,
                    "path",
                    format!("points {k} and {}: {:?}", k + 1, w[1]),
                    "consecutive points must be at least 1 m (0.001 km) apart (a repeated point)".into(),
                );
            }
        }
        let length: f64 = p.windows(2).map(|w| (fmath::powi(w[1][0] - w[0][0], 2) + fmath::powi(w[1][1] - w[0][1], 2)).sqrt()).sum();
        if length > 1e4 {
            self.push(t, "path", format!("{length:.1} km long"), "must be at most 1e4 km long".into());
        }
    }
}

/// 1-based line of `key = ...` inside `[table]` (or the `index`-th
/// `[[table]]`), or at the top level when `table` is None. A plain text scan:
/// enough to point a user at the line, not a TOML parser.
pub fn find_key_line(text: &str, table: Option<(&str, usize)>, key: &str) -> Option<usize> {
    let mut current: Option<(String, usize)> = None;
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    for (ln, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if let Some(rest) = line.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let c = counts.entry(name.clone()).or_insert(0);
            current = Some((name, *c));
            *c += 1;
            continue;
        }
        if let Some(rest) = line.strip_prefix('[') {
            let name = rest.split(']').next().unwrap_or("").trim().to_string();
            current = Some((name, 0));
            continue;
        }
        let here = match (&current, table) {
            (None, None) => true,
            (Some((n, i)), Some((t, j))) => n == t && *i == j,
            _ => false,
        };
        if here {
            if let Some((k, _)) = line.split_once('=') {
                if k.trim().trim_matches('"') == key {
                    return Some(ln + 1);
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::*;
    #[test]
    fn unknown_key_is_an_error_naming_key_and_line() {
        let e = Scene::from_toml_str("seed = 1\n[beams]\ncount = 5\nbogus = 3\n", "x.toml").unwrap_err();
        let m = e.to_string();
        assert!(m.contains("x.toml") && m.contains("bogus") && m.contains("line 4"), "{m}");
    }

    #[test]
    fn out_of_range_names_file_line_key_value_and_range() {
        let text = "[beams]\ncount = 100\nalpha_d_deg = 95.0\n";
        let m = Scene::from_toml_str(text, "s.toml").unwrap_err().to_string();
        assert!(m.contains("s.toml:3: beams.alpha_d_deg = 95"), "{m}");
        assert!(m.contains("[0, 90)"), "{m}");
        let m = Scene::from_toml_str("[photons]\nradius_km = -1\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("s.toml:2: photons.radius_km = -1"), "{m}");
        let m = Scene::from_toml_str("[beams]\ncount = 0\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("beams.count = 0") && m.contains("[1, "), "{m}");
        // Validity does not depend on the machine: a tiny voxel is valid here and
        // refused by the bake's memory budget (crate::pipeline::memory::budget).
        assert!(Scene::from_toml_str("[grid]\nvoxel_size = 0.0001\n", "s.toml").is_ok());
        let m = Scene::from_toml_str("[footprint]\nresolution = [100000000, 8]\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("s.toml:2: footprint.resolution") && m.contains("[8, 4096]"), "{m}");
    }

    #[test]
    fn prune_budget_outside_its_range_is_refused() {
        let m = Scene::from_toml_str("[grid]\nprune = 0.7\n", "p.toml").unwrap_err().to_string();
        assert!(m.contains("p.toml:2: grid.prune = 0.7") && m.contains("[0, 0.5]"), "{m}");
        assert!(Scene::from_toml_str("[grid]\nprune = 0.01\n", "p.toml").is_ok());
    }

    #[test]
    fn arrays_of_the_wrong_length_are_refused_naming_key_and_line() {
        let cases = [
            ("[[curtain]]\ncenter = [-20.0, 0.0, 999.0]\n", "curtain[0].center", 2),
            ("[camera]\nposition = [0.0, -90.0, 1.0, 5.0]\n", "camera.position", 2),
            ("[camera]\nup = [0.0, 1.0]\n", "camera.up", 2),
            ("[footprint]\nresolution = [64, 32, 8]\n", "footprint.resolution", 2),
            ("[colour]\nmode = \"colormap\"\ncolormap = [[90.0, 0.1, 0.2, 0.3, 9.0], [100.0, 0.1, 0.2, 0.3]]\n", "colour.colormap", 3),
            ("[terrain]\nextent = [0.0, 0.0, 1.0]\n", "terrain.extent", 2),
        ];
        for (text, key, line) in cases {
            let e = Scene::from_toml_str(text, "s.toml").unwrap_err().to_string();
            assert!(e.contains(key) && e.contains(&format!("s.toml:{line}:")), "{text}: {e}");
        }
        // Right lengths still parse.
        Scene::from_toml_str("[[curtain]]\ncenter = [-20.0, 0.0]\n[camera]\nposition = [0.0, -90.0, 1.0]\n", "s.toml").unwrap();
    }

    #[test]
    fn atmosphere_and_deposition_models_parse_and_unknown_names_are_refused() {
        let s = Scene::from_toml_str("[atmosphere]\nmodel = \"us1976\"\n[beams]\ndeposition = \"sampled\"\n", "m.toml").unwrap();
        assert_eq!(s.atmosphere.model, AtmosphereModel::Us1976);
        assert_eq!(s.beams.deposition, Deposition::Sampled);
        let d = Scene::default();
        assert_eq!((d.atmosphere.model, d.beams.deposition), (AtmosphereModel::Us1976, Deposition::Expected));
        let m = Scene::from_toml_str("[atmosphere]\nmodel = \"msis00\"\n", "m.toml").unwrap_err().to_string();
        assert!(m.contains("m.toml") && m.contains("msis00") && m.contains("nrlmsis21") && m.contains("us1976"), "{m}");
        let m = Scene::from_toml_str("[beams]\ndeposition = \"mean\"\n", "m.toml").unwrap_err().to_string();
        assert!(m.contains("mean") && m.contains("expected") && m.contains("sampled") && m.contains("csda"), "{m}");
    }

    /// Voxel sizes the grid's indices cannot hold (5e-324 once hung the
    /// bake) or that hold the aurora in one voxel are refused naming the
    /// range.
    #[test]
    fn voxel_sizes_at_the_ends_of_the_arithmetic_are_refused() {
        for vs in ["5e-324", "1e-9", "1e100", "1e300"] {
            let e = Scene::from_toml_str(&format!("[grid]\nvoxel_size = {vs}\n"), "f.toml").unwrap_err().to_string();
            assert!(e.contains("grid.voxel_size = ") && e.contains("must be in [0.0001, 100000] km"), "{vs}: {e}");
        }
        for vs in ["1e-4", "0.5", "1e4"] {
            Scene::from_toml_str(&format!("[grid]\nvoxel_size = {vs}\n"), "f.toml").unwrap();
        }
    }

    #[test]
    fn voxel_size_auto_parses() {
        let s = Scene::from_toml_str("[grid]\nvoxel_size = \"auto\"\n", "a.toml").unwrap();
        assert_eq!(s.grid.voxel_size, VoxelSize::Auto(AutoTag::Auto));
        let s = Scene::from_toml_str("[grid]\nvoxel_size = 1\n", "a.toml").unwrap();
        assert_eq!(s.grid.voxel_size, VoxelSize::Km(1.0));
        let e = Scene::from_toml_str("[grid]\nvoxel_size = \"AUTO\"\n", "a.toml").unwrap_err().to_string();
        assert!(e.contains("voxel_size") && e.contains("\"auto\"") && !e.contains("untagged"), "{e}");
    }
}
