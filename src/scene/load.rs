//! Reading a scene: TOML text or a file, or a built-in preset by name,
//! then the overrides ([`super::overrides`]) in order. Parsing is separate
//! from validation (pbrt's `GridMedium::Create` pattern): serde reads the
//! TOML (unknown keys are errors), the overrides are applied to the
//! document, then [`Scene::validate`] checks every range once. The
//! parser's messages are put in plain words ([`super::wording`]).

use super::overrides::{self, Override};
use super::presets;
use super::root::Scene;
use super::validation::{check_shapes, SceneError};
use super::wording;
use std::path::Path;

impl Scene {
    /// Parses TOML text (unknown keys are errors), then validates it.
    /// `file` names the source in messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        Self::from_toml_str_with(text, file, &[])
    }

    /// [`from_toml_str`](Self::from_toml_str) with `overrides` applied, in
    /// order, after the text and before validation.
    pub fn from_toml_str_with(text: &str, file: &str, overrides: &[Override]) -> Result<Scene, SceneError> {
        check_shapes(text, file)?;
        let scene: Scene = toml::from_str(text).map_err(|e| parse_error(file, text, &e))?;
        if overrides.is_empty() {
            scene.validate(file, Some(text))?;
            return Ok(scene);
        }
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| parse_error(file, text, &e))?;
        Self::from_document(doc, file, Some(text), overrides)
    }

    /// Reads a scene file, or a preset by name ([`presets::PRESETS`]); a
    /// name that is neither is [`SceneError::Unknown`], naming the presets.
    pub fn load(path_or_preset: &str) -> Result<Scene, SceneError> {
        Self::load_with(path_or_preset, &[])
    }

    /// The note for a preset name that is also a folder here (an output
    /// folder named after the preset): the preset is read, and `./NAME`
    /// names the folder. None when `arg` is no such name.
    pub fn shadowed_preset(arg: &str) -> Option<String> {
        (presets::by_name(arg).is_some() && Path::new(arg).is_dir())
            .then(|| format!("{arg}: the preset `{arg}`, not the folder of that name here (pass ./{arg} to mean the folder)"))
    }

    /// [`load`](Self::load) with `overrides` applied, in order, after the
    /// file or preset and before validation.
    pub fn load_with(path_or_preset: &str, overrides: &[Override]) -> Result<Scene, SceneError> {
        if let Some(s) = presets::by_name(path_or_preset) {
            // A folder is never a scene file: a bare preset name means the
            // preset even where a folder has that name ([`shadowed_preset`]).
            if !Path::new(path_or_preset).exists() || Path::new(path_or_preset).is_dir() {
                if overrides.is_empty() {
                    return Ok(s);
                }
                let doc = toml::Table::try_from(&s).expect("a scene serialises to a table");
                return Self::from_document(doc, path_or_preset, None, overrides);
            }
        }
        // Only a regular file is read (a FIFO or a device is refused, never
        // waited on: `crate::util::input_file`).
        let path = Path::new(path_or_preset);
        if !path.exists() && path.symlink_metadata().is_err() {
            let hint = wording::suggestion(path_or_preset, presets::names());
            return Err(SceneError::Unknown { name: path_or_preset.to_string(), presets: presets::names().collect(), hint });
        }
        let text = crate::util::input_file::read_to_string(path)
            .map_err(|e| SceneError::Io { file: path_or_preset.to_string(), error: e.into() })?;
        let mut scene = Self::from_toml_str_with(&text, path_or_preset, overrides)?;
        // `[atmosphere] data` is relative to the scene file's folder.
        scene.atmosphere.base_dir = Some(path.parent().map(Path::to_path_buf).unwrap_or_default());
        Ok(scene)
    }

    /// The scene of a TOML document after `overrides`, validated; errors
    /// are located in `text` (the file's own keys) or at the override.
    fn from_document(mut doc: toml::Table, file: &str, text: Option<&str>, overrides: &[Override]) -> Result<Scene, SceneError> {
        overrides::apply(&mut doc, overrides)?;
        let merged = toml::to_string(&doc).expect("a TOML table serialises");
        // Each override and the file were checked alone; what is left is
        // their combination.
        let given: Vec<&str> = overrides.iter().map(|o| o.source.as_str()).collect();
        let with = format!("{file} with {}", given.join(", "));
        check_shapes(&merged, &with).map_err(|e| overrides::relocate(e, overrides))?;
        let mut scene: Scene = toml::from_str(&merged).map_err(|e| parse_error(&with, &merged, &e))?;
        scene.validate(file, text).map_err(|e| overrides::relocate(e, overrides))?;
        scene.overrides = overrides.iter().map(Override::record).collect();
        Ok(scene)
    }
}

/// The TOML reader's error in plain words, keeping its snippet of the
/// file (the line, a caret under the value).
fn parse_error(file: &str, text: &str, e: &toml::de::Error) -> SceneError {
    let (table, index, key, source) = e.span().map_or((None, None, None, None), |s| wording::locate(text, s.start));
    let at = wording::At { table: table.as_deref(), index, key: key.as_deref() };
    let plain = wording::plain(e.message(), at, source.as_deref());
    let full = e.to_string();
    let message = match full.rfind(e.message()) {
        Some(i) => format!("{}{plain}{}", &full[..i], &full[i + e.message().len()..]),
        None => full,
    };
    // The snippet and the message quote at most a long line's worth of each
    // line (the parser's message lists a key's words in full).
    let message: Vec<String> = message.lines().map(|l| super::validation::quoted_within(l, 400)).collect();
    SceneError::Parse { file: file.to_string(), message: message.join("\n") }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(text: &str) -> Override {
        Override::parse(text, "--set").unwrap()
    }

    /// A scene with a 10 MB string or a million bad entries is refused in
    /// linear time with a message of a few lines' worth.
    #[test]
    fn large_bad_inputs_are_refused_quickly_with_short_messages() {
        let t = std::time::Instant::now();
        let huge = format!("[camera]\nprojection = \"{}\"\n", "x".repeat(10_000_000));
        let m = Scene::from_toml_str(&huge, "f.toml").unwrap_err().to_string();
        assert!(m.len() < 2_000 && m.contains("bytes in all)"), "{}", &m[..m.len().min(3000)]);
        let points = vec!["[1.0]"; 200_000].join(", ");
        let m = Scene::from_toml_str(&format!("[[curtain]]\npath = [{points}]\n"), "f.toml").unwrap_err().to_string();
        assert!(
            m.len() < 20_000 && m.contains("point 0: [1.0]") && m.contains("and more errors after these"),
            "{}",
            &m[..m.len().min(3000)]
        );
        assert!(!m.contains("point 20: "), "{}", &m[..m.len().min(3000)]);
        let m =
            Scene::from_toml_str(&format!("[camera]\nup = [{}]\n", vec!["1.0"; 1_000_000].join(", ")), "f.toml").unwrap_err().to_string();
        assert!(m.len() < 2_000 && m.contains("must have exactly 3 values, not 1000000"), "{}", &m[..m.len().min(3000)]);
        // Generous on a loaded machine: the quadratic search took minutes.
        assert!(t.elapsed() < std::time::Duration::from_secs(60), "{:?}", t.elapsed());
    }

    /// The file's errors keep their lines; an override's error names the
    /// override; a preset with overrides is the preset with those values.
    #[test]
    fn errors_are_located_at_the_file_or_the_override() {
        let text = "[render]\nwidth = 8\n[beams]\ncount = 0\n";
        let m = Scene::from_toml_str_with(text, "f.toml", &[set("render.width=0")]).unwrap_err().to_string();
        assert!(m.contains("--set render.width=0: render.width = 0 is out of range") && m.contains("f.toml:4: beams.count = 0"), "{m}");
        // The later override wins, and the record keeps them all in order.
        let s = Scene::from_toml_str_with(text, "f.toml", &[set("beams.count=0"), set("beams.count=5")]).unwrap();
        assert_eq!((s.beams.count, s.overrides.clone()), (5, vec!["beams.count=0".to_string(), "beams.count=5".to_string()]));
        let mut want = presets::by_name("corona").unwrap();
        want.curtains[0].energy_flux = 2.0;
        let got = Scene::load_with("corona", &[set("curtain[0].energy_flux=2")]).unwrap();
        assert_eq!(got.hash(), want.hash());
        assert_eq!(Scene { overrides: Vec::new(), ..got }, want);
    }
}
