//! Frame ranges, frame file names and shards: the contract every render farm
//! speaks (docs/guide.md, "Farms").
//!
//! - **Range syntax** ([`parse_range`]): Open Job Description's integer range
//!   expression (specification `jobtemplate-2023-09`, "RangeExpressionString";
//!   the reference implementation is `openjd-model`'s `IntRangeExpr`): a
//!   comma-separated list of items, each `A`, `A-B` or `A-B:S`, integers
//!   possibly negative (`-5--1`), whitespace allowed around every token.
//!   `A-B` runs from A to B inclusive with step 1 and needs A <= B; `A-B:S`
//!   needs S != 0 and a step whose sign walks from A towards B (`10-1:-3` is
//!   10, 7, 4, 1); the end need not be hit. Items must not share a value
//!   (OpenJD refuses overlapping ranges); the frames are the union, ascending.
//! - **Names** ([`frame_file_name`]): the frame number zero-padded to at least
//!   four digits just before the extension, `aurora.0001.vdb`: Blender's
//!   sequence loader replaces exactly those digits (volume.cc,
//!   `volume_sequence_frame`), and USD lists every frame by name.
//! - **Shards** ([`Shard`]): shard I of N bakes the frames at positions p of
//!   the ascending list with p mod N = I, so N shards cover every frame once,
//!   whatever the range. `auto` reads Slurm's array variables
//!   (I = `SLURM_ARRAY_TASK_ID` - `SLURM_ARRAY_TASK_MIN`,
//!   N = `SLURM_ARRAY_TASK_COUNT`; a stepped array, `SLURM_ARRAY_TASK_STEP`
//!   != 1, would leave holes in I and is refused); `auto/N` reads Kubernetes'
//!   `JOB_COMPLETION_INDEX` (Indexed Jobs, 0 .. completions - 1).

/// A malformed range, name or shard. Every message quotes the offending text.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    #[error("frame range `{text}`: {why} (syntax: `4`, `1-100`, `1,3,7-20:2`, `10-1:-1`)")]
    Range { text: String, why: String },
    #[error("--shard `{text}`: {why} (syntax: `I/N` with 0 <= I < N, `auto` under a Slurm array, `auto/N` in a Kubernetes Indexed Job)")]
    Shard { text: String, why: String },
}

impl FrameError {
    /// Always the user's input: the range or shard given (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// Largest number of frames one expression may expand to (a guard against
/// `1-9999999999`: a 10-minute show at 60 fps is 36,000 frames).
pub const MAX_FRAMES: usize = 10_000_000;

/// Most shards a farm's variables may name: as many as the most frames.
pub const MAX_SHARDS: u64 = MAX_FRAMES as u64;

fn range_err(text: &str, why: impl Into<String>) -> FrameError {
    FrameError::Range { text: text.to_string(), why: why.into() }
}

/// Tokens of the range grammar.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok {
    Int(i64),
    Minus,
    Colon,
    Comma,
}

fn tokenize(text: &str) -> Result<Vec<Tok>, FrameError> {
    let mut out = Vec::new();
    let b = text.as_bytes();
    let mut k = 0;
    while k < b.len() {
        let c = b[k];
        match c {
            b' ' | b'\t' | b'\n' | b'\r' => k += 1,
            b'-' => {
                out.push(Tok::Minus);
                k += 1
            }
            b':' => {
                out.push(Tok::Colon);
                k += 1
            }
            b',' => {
                out.push(Tok::Comma);
                k += 1
            }
            b'0'..=b'9' => {
                let s = k;
                while k < b.len() && b[k].is_ascii_digit() {
                    k += 1;
                }
                let digits = &text[s..k];
                let v: i64 = digits.parse().map_err(|_| range_err(text, format!("`{digits}` is too large")))?;
                out.push(Tok::Int(v));
            }
            _ => {
                let ch = text[k..].chars().next().unwrap_or('?');
                return Err(range_err(text, format!("unexpected `{ch}` at character {}", k + 1)));
            }
        }
    }
    Ok(out)
}

/// One item `A-B:S` (A = B, S = 1 for a single value).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Item {
    start: i64,
    end: i64,
    step: i64,
}

impl Item {
    fn values(&self) -> impl Iterator<Item = i64> + '_ {
        let n = (self.end - self.start) / self.step + 1;
        (0..n).map(move |k| self.start + k * self.step)
    }
    fn len(&self) -> i64 {
        (self.end - self.start) / self.step + 1
    }
}

/// Parses a signed integer at `toks[*k]`: `Int` or `Minus Int`.
fn signed(text: &str, toks: &[Tok], k: &mut usize, what: &str) -> Result<i64, FrameError> {
    let neg = toks.get(*k) == Some(&Tok::Minus);
    if neg {
        *k += 1;
    }
    match toks.get(*k) {
        Some(Tok::Int(v)) => {
            *k += 1;
            Ok(if neg { -v } else { *v })
        }
        _ => Err(range_err(text, format!("expected {what}"))),
    }
}

/// Parses an Open Job Description range expression into its frames,
/// ascending and distinct.
pub fn parse_range(text: &str) -> Result<Vec<i64>, FrameError> {
    let toks = tokenize(text)?;
    if toks.is_empty() {
        return Err(range_err(text, "empty"));
    }
    let mut items = Vec::new();
    let mut k = 0;
    loop {
        let start = signed(text, &toks, &mut k, "a frame number")?;
        let mut item = Item { start, end: start, step: 1 };
        if toks.get(k) == Some(&Tok::Minus) {
            k += 1;
            item.end = signed(text, &toks, &mut k, "an end frame after `-`")?;
            if toks.get(k) == Some(&Tok::Colon) {
                k += 1;
                item.step = signed(text, &toks, &mut k, "a step after `:`")?;
                if item.step == 0 {
                    return Err(range_err(text, format!("item {}-{}:0: the step must not be 0", item.start, item.end)));
                }
            } else if item.end < item.start {
                return Err(range_err(
                    text,
                    format!("item {}-{} runs backwards: write {}-{}:-1", item.start, item.end, item.start, item.end),
                ));
            }
            if (item.end - item.start).signum() * item.step.signum() < 0 {
                return Err(range_err(text, format!("item {}-{}:{}: the step walks away from the end", item.start, item.end, item.step)));
            }
        }
        items.push(item);
        match toks.get(k) {
            None => break,
            Some(Tok::Comma) => {
                k += 1;
                if k == toks.len() {
                    return Err(range_err(text, "trailing `,`"));
                }
            }
            Some(t) => {
                let what = match t {
                    Tok::Int(v) => v.to_string(),
                    Tok::Minus => "-".into(),
                    Tok::Colon => ":".into(),
                    Tok::Comma => ",".into(),
                };
                return Err(range_err(text, format!("unexpected `{what}` after item {}", items.len())));
            }
        }
    }
    let total: i64 = items.iter().map(Item::len).sum();
    if total as u64 > MAX_FRAMES as u64 {
        return Err(range_err(text, format!("{total} frames, more than {MAX_FRAMES}")));
    }
    let mut frames: Vec<i64> = items.iter().flat_map(|i| i.values().collect::<Vec<_>>()).collect();
    frames.sort_unstable();
    if let Some(w) = frames.windows(2).find(|w| w[0] == w[1]) {
        return Err(range_err(text, format!("frame {} is listed twice (overlapping items)", w[0])));
    }
    Ok(frames)
}

/// `stem.NNNN.ext`: the frame zero-padded to at least four digits. Frames
/// must be >= 0 (a sign would break Blender's digits-before-extension rule).
pub fn frame_file_name(stem: &str, frame: i64, ext: &str) -> String {
    debug_assert!(frame >= 0);
    format!("{stem}.{frame:04}.{ext}")
}

/// Which share of the frames this process bakes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shard {
    /// Shard `index` of `count` (from `I/N`).
    Fixed { index: u64, count: u64 },
    /// From a Slurm job array's variables.
    Slurm,
    /// Index from `JOB_COMPLETION_INDEX` (a Kubernetes Indexed Job), count given.
    Indexed { count: u64 },
}

impl Shard {
    /// Parses `I/N`, `auto` or `auto/N`.
    pub fn parse(text: &str) -> Result<Shard, FrameError> {
        let err = |why: &str| FrameError::Shard { text: text.to_string(), why: why.to_string() };
        let t = text.trim();
        let count = |s: &str| -> Result<u64, FrameError> {
            let n: u64 = s.trim().parse().map_err(|_| err("N must be a whole number"))?;
            if n == 0 {
                return Err(err("N must be at least 1"));
            }
            Ok(n)
        };
        if t == "auto" {
            return Ok(Shard::Slurm);
        }
        let (a, b) = t.split_once('/').ok_or_else(|| err("expected `I/N`, `auto` or `auto/N`"))?;
        if a.trim() == "auto" {
            return Ok(Shard::Indexed { count: count(b)? });
        }
        let index: u64 = a.trim().parse().map_err(|_| err("I must be a whole number"))?;
        let count = count(b)?;
        if index >= count {
            return Err(err("I must be below N (shards count from 0)"));
        }
        Ok(Shard::Fixed { index, count })
    }

    /// (index, count), reading the scheduler's variables through `env`.
    pub fn resolve(&self, env: impl Fn(&str) -> Option<String>) -> Result<(u64, u64), FrameError> {
        let text = match self {
            Shard::Fixed { index, count } => return Ok((*index, *count)),
            Shard::Slurm => "auto",
            Shard::Indexed { .. } => "auto/N",
        };
        let err = |why: String| FrameError::Shard { text: text.to_string(), why };
        let var = |name: &str| -> Result<i64, FrameError> {
            let v = env(name).ok_or_else(|| err(format!("{name} is not set (not running under the scheduler?)")))?;
            v.trim().parse::<i64>().map_err(|_| err(format!("{name} = `{v}` is not a whole number")))
        };
        match self {
            Shard::Fixed { .. } => unreachable!(),
            Shard::Slurm => {
                if let Some(step) = env("SLURM_ARRAY_TASK_STEP") {
                    if step.trim() != "1" {
                        return Err(err(format!(
                            "SLURM_ARRAY_TASK_STEP = {step}: a stepped array (--array=A-B:S) leaves gaps in the task ids; submit --array=0-{{N-1}} instead"
                        )));
                    }
                }
                let (id, min, count) = (var("SLURM_ARRAY_TASK_ID")?, var("SLURM_ARRAY_TASK_MIN")?, var("SLURM_ARRAY_TASK_COUNT")?);
                // In i128: ID - MIN of two 64-bit values cannot overflow.
                let index = id as i128 - min as i128;
                if count < 1 || index < 0 || index >= count as i128 {
                    return Err(err(format!(
                        "SLURM_ARRAY_TASK_ID = {id}, SLURM_ARRAY_TASK_MIN = {min}, SLURM_ARRAY_TASK_COUNT = {count} do not give 0 <= ID - MIN < COUNT (a list like --array=1,5,9 is not contiguous)"
                    )));
                }
                if count as u64 > MAX_SHARDS {
                    return Err(err(format!(
                        "SLURM_ARRAY_TASK_COUNT = {count}: more shards than {MAX_SHARDS}, the most frames one range may hold; not an array aurora can use"
                    )));
                }
                Ok((index as u64, count as u64))
            }
            Shard::Indexed { count } => {
                let i = var("JOB_COMPLETION_INDEX")?;
                if *count > MAX_SHARDS {
                    return Err(err(format!("N = {count}: more shards than {MAX_SHARDS}, the most frames one range may hold")));
                }
                if i < 0 || i as u64 >= *count {
                    return Err(err(format!("JOB_COMPLETION_INDEX = {i} is not below N = {count}")));
                }
                Ok((i as u64, *count))
            }
        }
    }
}

/// The frames at positions p with p mod `count` = `index`.
pub fn select(frames: &[i64], index: u64, count: u64) -> Vec<i64> {
    frames.iter().enumerate().filter(|(p, _)| *p as u64 % count == index).map(|(_, &f)| f).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn examples_from_the_specification() {
        assert_eq!(parse_range("4").unwrap(), vec![4]);
        assert_eq!(parse_range("1-5").unwrap(), vec![1, 2, 3, 4, 5]);
        assert_eq!(parse_range("1,3,7-20:2").unwrap(), vec![1, 3, 7, 9, 11, 13, 15, 17, 19]);
        assert_eq!(parse_range("10-1:-3").unwrap(), vec![1, 4, 7, 10]);
        assert_eq!(parse_range("-5--3").unwrap(), vec![-5, -4, -3]);
        assert_eq!(parse_range(" 1 - 3 : 1 , 8 ").unwrap(), vec![1, 2, 3, 8]);
        assert_eq!(parse_range("3-3").unwrap(), vec![3]);
        assert_eq!(parse_range("1-4:10").unwrap(), vec![1]);
    }

    #[test]
    fn errors_name_the_offending_text() {
        for (bad, needle) in [
            ("", "empty"),
            ("1-", "end frame"),
            ("1-5:0", "step must not be 0"),
            ("5-1", "runs backwards"),
            ("1-5:-1", "walks away"),
            ("1,,2", "frame number"),
            ("1,", "trailing"),
            ("1 2", "unexpected `2`"),
            ("1-3,2", "listed twice"),
            ("a", "unexpected `a`"),
            ("1.5", "unexpected `.`"),
            ("99999999999999999999", "too large"),
            ("0-99999999999", "more than"),
        ] {
            let e = parse_range(bad).unwrap_err().to_string();
            assert!(e.contains(needle) && e.contains(&format!("`{bad}`")), "{bad}: {e}");
        }
    }

    /// The oracle: a random list of items written out with random spacing,
    /// expanded by brute force (walk from start while not past the end).
    #[test]
    fn parser_matches_a_brute_force_expansion() {
        let mut r = crate::util::rng::rng(&[13, 1]);
        for _ in 0..2000 {
            let n_items = r.random_range(1..5);
            let mut text = String::new();
            let mut expect = Vec::new();
            for it in 0..n_items {
                let a: i64 = r.random_range(-30..60);
                let b: i64 = r.random_range(-30..60);
                let sp = |r: &mut rand_pcg::Pcg64Mcg| if r.random_bool(0.3) { " " } else { "" };
                let form = r.random_range(0..3);
                if it > 0 {
                    text += sp(&mut r);
                    text += ",";
                }
                text += sp(&mut r);
                match form {
                    0 => {
                        text += &a.to_string();
                        expect.push(a);
                    }
                    1 => {
                        let (lo, hi) = (a.min(b), a.max(b));
                        text += &format!("{lo}{}-{}{hi}", sp(&mut r), sp(&mut r));
                        expect.extend(lo..=hi);
                    }
                    _ => {
                        let s: i64 = r.random_range(1..7) * if b < a { -1 } else { 1 };
                        text += &format!("{a}-{b}{}:{}{s}", sp(&mut r), sp(&mut r));
                        let mut v = a;
                        while (s > 0 && v <= b) || (s < 0 && v >= b) {
                            expect.push(v);
                            v += s;
                        }
                    }
                }
                text += sp(&mut r);
            }
            expect.sort_unstable();
            let dup = expect.windows(2).any(|w| w[0] == w[1]);
            match parse_range(&text) {
                Ok(f) => {
                    assert!(!dup, "{text}: overlap accepted");
                    assert_eq!(f, expect, "{text}");
                }
                Err(e) => assert!(dup && e.to_string().contains("twice"), "{text}: {e}"),
            }
        }
    }

    #[test]
    fn names_pad_to_four_digits_before_the_extension() {
        assert_eq!(frame_file_name("aurora", 1, "vdb"), "aurora.0001.vdb");
        assert_eq!(frame_file_name("aurora", 0, "json"), "aurora.0000.json");
        assert_eq!(frame_file_name("aurora", 12345, "vdb"), "aurora.12345.vdb");
    }

    #[test]
    fn shards_partition_every_range() {
        let frames = parse_range("1-37,50-60:3").unwrap();
        for n in 1..9u64 {
            let mut all: Vec<i64> = (0..n).flat_map(|i| select(&frames, i, n)).collect();
            all.sort_unstable();
            assert_eq!(all, frames, "N = {n}");
            // Balanced: shard sizes differ by at most one.
            let sizes: Vec<usize> = (0..n).map(|i| select(&frames, i, n).len()).collect();
            assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1);
        }
    }

    #[test]
    fn shard_syntax_and_scheduler_variables() {
        assert_eq!(Shard::parse("1/4").unwrap(), Shard::Fixed { index: 1, count: 4 });
        assert_eq!(Shard::parse("auto").unwrap(), Shard::Slurm);
        assert_eq!(Shard::parse("auto/8").unwrap(), Shard::Indexed { count: 8 });
        for bad in ["4/4", "1/0", "x/2", "1", "auto/0", "-1/3"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("`{bad}`")), "{e}");
        }
        let env =
            |vars: &'static [(&'static str, &'static str)]| move |k: &str| vars.iter().find(|(n, _)| *n == k).map(|(_, v)| v.to_string());
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "7"),
            ("SLURM_ARRAY_TASK_MIN", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_STEP", "1"),
        ]);
        assert_eq!(Shard::Slurm.resolve(slurm).unwrap(), (2, 4));
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
        ]);
        assert!(Shard::Slurm.resolve(stepped).unwrap_err().to_string().contains("stepped"));
        assert!(Shard::Slurm.resolve(env(&[])).unwrap_err().to_string().contains("SLURM_ARRAY_TASK_ID is not set"));
        // Variables at the ends of a 64-bit integer are refused, never
        // taken as a shard that bakes nothing.
        let (max, min) = (i64::MAX.to_string(), i64::MIN.to_string());
        let (max, min) = (max.as_str(), min.as_str());
        for (id, lo, count) in [(max, min, "4"), (min, max, "4"), (max, "0", max), ("0", "0", max), ("5", min, max)] {
            let vars = [
                ("SLURM_ARRAY_TASK_ID", id.to_string()),
                ("SLURM_ARRAY_TASK_MIN", lo.to_string()),
                ("SLURM_ARRAY_TASK_COUNT", count.to_string()),
            ];
            let r = Shard::Slurm.resolve(|k: &str| vars.iter().find(|(n, _)| *n == k).map(|(_, v)| v.clone()));
            let e = r.unwrap_err().to_string();
            assert!(e.starts_with("--shard `auto`: SLURM_ARRAY_TASK_"), "{id} {lo} {count}: {e}");
        }
        assert!(Shard::Slurm
            .resolve(env(&[("SLURM_ARRAY_TASK_ID", "99999999999999999999")]))
            .unwrap_err()
            .to_string()
            .contains("not a whole number"));
        let k8s = env(&[("JOB_COMPLETION_INDEX", "2")]);
        assert_eq!(Shard::Indexed { count: 3 }.resolve(k8s).unwrap(), (2, 3));
        assert!(Shard::Indexed { count: 2 }.resolve(env(&[("JOB_COMPLETION_INDEX", "2")])).is_err());
    }
}
