//! The tables that are not compiled in, because their terms forbid what
//! aurora's users may do with the binary (docs/data.md): NRLMSIS 2.1
//! (`nrlmsis21.csv`: research, academic and non-profit use only) and NCAR
//! GLOW's ionosphere (`ionosphere.csv`: no sale). A scene that asks for
//! one (`[atmosphere] model = "nrlmsis21"`, `ionosphere = "glow"`) reads
//! it from one folder, the first of:
//!
//! 1. `[atmosphere] data`, relative to the scene file's folder;
//! 2. the `AURORA_DATA` environment variable;
//! 3. the source tree's `data/` this binary was built from.
//!
//! A missing file is [`DataError::Missing`] (the user's input: exit 2),
//! naming the file, its terms and how to point to it. A file read is kept
//! for the life of the process ([`read`]), so a scene checked once is read
//! the same by every stage after.

use crate::scene::AtmosphereParams;
use crate::util::input_file::InputFileError;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// One table that is read from the data folder.
#[derive(Debug)]
pub struct DataFile {
    /// File name in the data folder.
    pub name: &'static str,
    /// The `[atmosphere]` key and value that ask for it.
    pub key: &'static str,
    pub value: &'static str,
    /// What it holds and where from.
    pub source: &'static str,
    /// The terms it is used under (its header's `# terms:` line says the same).
    pub terms: &'static str,
    /// The compiled-in choice that needs no file.
    pub instead: &'static str,
}

/// NRLMSIS 2.1's neutral atmosphere (`tools/reference/msis_table.py`).
pub const NRLMSIS21: DataFile = DataFile {
    name: "nrlmsis21.csv",
    key: "model",
    value: "nrlmsis21",
    source: "NRLMSIS 2.1, U.S. Naval Research Laboratory",
    terms: "research, academic and non-profit use only; commercial use needs NRL's written consent",
    instead: "model = \"us1976\"",
};

/// NCAR GLOW's ambient ionosphere and NO (`tools/reference/glow_tables.py`).
pub const IONOSPHERE: DataFile = DataFile {
    name: "ionosphere.csv",
    key: "ionosphere",
    value: "glow",
    source: "NCAR GLOW 4.0.4, UCAR",
    terms: "GLOW's Open Source Academic Research License: research, academic and non-profit use; no sale; derivative works open source",
    instead: "ionosphere = \"closed-form\"",
};

/// The source tree's `data/` of this build (the last place looked).
pub const BUILD_DATA_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data");

/// The environment variable naming the data folder.
pub const DATA_ENV: &str = "AURORA_DATA";

/// Why a data file was not read.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    #[error(
        "[atmosphere] {key} = \"{value}\" needs {name} ({source}; terms: {terms}), which is not compiled into aurora, \
         and {name} is not in {folder} (chosen by {how}); put it there, name its folder with [atmosphere] data = \"FOLDER\" \
         (relative to the scene file) or the {DATA_ENV} environment variable, or use {instead} (docs/data.md)",
        key = file.key, value = file.value, name = file.name, source = file.source, terms = file.terms,
        instead = file.instead, folder = folder.display()
    )]
    Missing { file: &'static DataFile, folder: PathBuf, how: &'static str },
    #[error("{0}")]
    Read(#[from] InputFileError),
    #[error("{}:{line}: {message}", path.display())]
    Malformed { path: PathBuf, line: usize, message: String },
}

impl DataError {
    /// Always the user's input: the scene asks for a table the data folder
    /// does not hold, or holds damaged (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// The data folder of `params` and what chose it (module doc).
pub fn folder(params: &AtmosphereParams) -> (PathBuf, &'static str) {
    if let Some(d) = &params.data {
        let base = params.base_dir.clone().unwrap_or_default();
        return (base.join(d), "[atmosphere] data");
    }
    match std::env::var_os(DATA_ENV).filter(|v| !v.is_empty()) {
        Some(v) => (PathBuf::from(v), "the AURORA_DATA environment variable"),
        None => (PathBuf::from(BUILD_DATA_DIR), "the source tree's data/ of this build"),
    }
}

/// The text of `file` in `params`' data folder, read once per path.
pub fn read(file: &'static DataFile, params: &AtmosphereParams) -> Result<(PathBuf, Arc<str>), DataError> {
    static READ: Mutex<Vec<(PathBuf, Arc<str>)>> = Mutex::new(Vec::new());
    let (dir, how) = folder(params);
    let path = dir.join(file.name);
    if let Some((_, text)) = READ.lock().unwrap_or_else(|e| e.into_inner()).iter().find(|(p, _)| *p == path) {
        return Ok((path, text.clone()));
    }
    if !path.exists() && path.symlink_metadata().is_err() {
        return Err(DataError::Missing { file, folder: dir, how });
    }
    let text: Arc<str> = crate::util::input_file::read_to_string(&path)?.into();
    READ.lock().unwrap_or_else(|e| e.into_inner()).push((path.clone(), text.clone()));
    Ok((path, text))
}

/// The tables `params` selects that are read from the data folder.
pub fn selected(params: &AtmosphereParams) -> Vec<&'static DataFile> {
    let mut out = Vec::new();
    if params.model == crate::scene::AtmosphereModel::Nrlmsis21 {
        out.push(&NRLMSIS21);
    }
    if params.ionosphere == crate::scene::Ionosphere::Glow {
        out.push(&IONOSPHERE);
    }
    out
}

/// What the tables `params` reads from the data folder add to a bake's
/// identity: each one's name and the FNV-1a hash of its bytes (empty for
/// the compiled-in default; "missing" for a table not there, which the
/// bake refuses before it starts).
pub fn identity(params: &AtmosphereParams) -> String {
    selected(params)
        .into_iter()
        .map(|f| match read(f, params) {
            Ok((_, text)) => format!("|{}:{:016x}", f.name, crate::scene::fnv1a(text.as_bytes())),
            Err(_) => format!("|{}:missing", f.name),
        })
        .collect()
}

/// The rows of numbers of a table (lines starting with `#` are comments,
/// the header starts with a letter), each with at least `columns` values.
/// Errors name the line (1-based) and what is wrong.
pub fn rows(text: &str, columns: usize) -> Result<Vec<Vec<f64>>, (usize, String)> {
    // A byte-order mark (a spreadsheet's UTF-8 export) is not part of the
    // first line's text.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out: Vec<Vec<f64>> = Vec::new();
    for (i, l) in text.lines().enumerate() {
        if l.starts_with('#') || l.starts_with(|c: char| c.is_ascii_alphabetic()) || l.trim().is_empty() {
            continue;
        }
        let r: Vec<f64> = l
            .split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|_| (i + 1, format!("'{}' is not a number", excerpt(x.trim())))))
            .collect::<Result<_, _>>()?;
        if r.len() < columns {
            return Err((i + 1, format!("{} columns, expected at least {columns}", r.len())));
        }
        if !r.iter().all(|x| x.is_finite()) {
            return Err((i + 1, "a value is not finite".into()));
        }
        if out.last().is_some_and(|p| p[0] >= r[0]) {
            return Err((i + 1, format!("altitude {} km does not ascend", figure(r[0]))));
        }
        out.push(r);
    }
    if out.len() < 2 {
        return Err((text.lines().count(), "fewer than 2 rows".into()));
    }
    Ok(out)
}

/// A value as a message quotes it: in full when short, else in scientific
/// notation (1e300, not its 301 digits).
fn figure(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 12 {
        plain
    } else {
        format!("{x:e}")
    }
}

/// At most 40 characters of a field, for a message.
fn excerpt(field: &str) -> String {
    match field.char_indices().nth(40) {
        None => field.to_string(),
        Some((at, _)) => format!("{}... ({} bytes)", &field[..at], field.len()),
    }
}

/// [`rows`] of a file read from `path`, as a [`DataError`], with columns 1
/// to `columns - 1` (densities and temperatures) positive and, if
/// `falling` names one, that column falling with altitude (a density the
/// column mass integrates).
pub fn file_rows(path: &Path, text: &str, columns: usize, falling: Option<usize>) -> Result<Vec<Vec<f64>>, DataError> {
    let bad = |line: usize, message: String| DataError::Malformed { path: path.to_path_buf(), line, message };
    let out = rows(text, columns).map_err(|(line, message)| bad(line, message))?;
    // Row i's line: the i-th line of numbers.
    let line_of = |i: usize| {
        text.lines()
            .enumerate()
            .filter(|(_, l)| l.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.'))
            .nth(i)
            .map_or(0, |(n, _)| n + 1)
    };
    for (i, r) in out.iter().enumerate() {
        if let Some(k) = (1..columns).find(|&k| r[k] <= 0.0) {
            return Err(bad(line_of(i), format!("column {} is {}, must be positive", k + 1, figure(r[k]))));
        }
        if let Some(k) = falling.filter(|_| i > 0) {
            if r[k] >= out[i - 1][k] {
                return Err(bad(line_of(i), format!("column {} must fall with altitude", k + 1)));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table saved with a byte-order mark reads as without it; absurd
    /// values and long fields are quoted in a few characters.
    #[test]
    fn a_byte_order_mark_is_read_and_absurd_values_are_quoted_short() {
        let table = "alt_km,n_cm3,t_k\n100,5,200\n110,4,210\n";
        let want = rows(table, 3).unwrap();
        assert_eq!(rows(&format!("\u{feff}{table}"), 3).unwrap(), want);
        assert_eq!(rows("\u{feff}100,5,200\n110,4,210\n", 3).unwrap(), want);
        let p = Path::new("t.csv");
        let e = file_rows(p, "alt_km,n,t\n100,-1e300,200\n110,4,210\n", 3, None).unwrap_err().to_string();
        assert!(e.contains("column 2 is -1e300, must be positive") && e.len() < 200, "{e}");
        let (_, m) = rows(&format!("100,5,200\n1e300,4,210\n50,{},1\n", "9".repeat(5000)), 3).unwrap_err();
        assert!(m.len() < 120, "{m}");
        let (_, m) = rows(&format!("100,5,200\n110,{}x,1\n", "9".repeat(5000)), 3).unwrap_err();
        assert!(m.starts_with("'9999") && m.contains("(5001 bytes)' is not a number") && m.len() < 120, "{m}");
    }

    #[test]
    fn the_folder_is_the_scene_key_then_the_build_tree() {
        let mut p = AtmosphereParams { data: Some("tables".into()), base_dir: Some(PathBuf::from("scenes")), ..Default::default() };
        assert_eq!(folder(&p), (PathBuf::from("scenes/tables"), "[atmosphere] data"));
        p.base_dir = None;
        assert_eq!(folder(&p).0, PathBuf::from("tables"));
    }

    #[test]
    fn a_missing_file_names_itself_its_terms_and_the_way_to_point_to_it() {
        let p = AtmosphereParams { data: Some("no such folder".into()), ..Default::default() };
        let e = read(&NRLMSIS21, &p).unwrap_err();
        assert!(e.is_input());
        let m = e.to_string();
        for want in ["nrlmsis21.csv", "model = \"nrlmsis21\"", "non-profit", "no such folder", "[atmosphere] data", "AURORA_DATA", "us1976"]
        {
            assert!(m.contains(want), "{want}: {m}");
        }
        let m = read(&IONOSPHERE, &p).unwrap_err().to_string();
        assert!(m.contains("ionosphere.csv") && m.contains("no sale") && m.contains("closed-form"), "{m}");
    }

    #[test]
    fn the_identity_holds_the_bytes_of_the_tables_read() {
        use crate::scene::{AtmosphereModel, Ionosphere};
        assert_eq!(identity(&AtmosphereParams::default()), "");
        let p = AtmosphereParams {
            model: AtmosphereModel::Nrlmsis21,
            ionosphere: Ionosphere::Glow,
            data: Some(BUILD_DATA_DIR.into()),
            base_dir: None,
        };
        let bytes = std::fs::read(format!("{BUILD_DATA_DIR}/nrlmsis21.csv")).unwrap();
        let id = identity(&p);
        assert!(id.contains(&format!("|nrlmsis21.csv:{:016x}", crate::scene::fnv1a(&bytes))) && id.contains("|ionosphere.csv:"), "{id}");
        let gone = AtmosphereParams { data: Some("no such folder".into()), ..p };
        assert_eq!(identity(&gone), "|nrlmsis21.csv:missing|ionosphere.csv:missing");
    }

    #[test]
    fn damaged_rows_are_named_by_line() {
        assert_eq!(rows("# c\nh,a\n1,2\n2,x\n", 2).unwrap_err().0, 4);
        assert_eq!(rows("1,2\n1,3\n", 2).unwrap_err().0, 2);
        assert_eq!(rows("1,2\n2\n", 2).unwrap_err().0, 2);
        assert_eq!(rows("1,2\n2,inf\n", 2).unwrap_err().0, 2);
        assert_eq!(rows("# c\n1,2\n2,3\n", 2).unwrap(), vec![vec![1.0, 2.0], vec![2.0, 3.0]]);
        let p = Path::new("t.csv");
        let e = file_rows(p, "h,a\n1,2\n2,0\n", 2, None).unwrap_err().to_string();
        assert!(e.contains("t.csv:3:") && e.contains("positive"), "{e}");
        let e = file_rows(p, "1,2\n2,3\n", 2, Some(1)).unwrap_err().to_string();
        assert!(e.contains("t.csv:2:") && e.contains("fall"), "{e}");
    }
}
