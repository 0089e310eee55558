//! Reading scene files: RON or JSON by extension, parsed into one schema,
//! then validated (README "Running scenes").

use std::path::Path;

use ron::extensions::Extensions;

use crate::built_scene::BuiltScene;
use crate::error::SceneError;
use crate::schema::Scene;

/// A scene file format.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Format {
    /// [RON](https://github.com/ron-rs/ron), extension `.ron`. `Option`
    /// fields may omit `Some(...)` (the `implicit_some` extension is on).
    Ron,
    /// JSON, extension `.json`.
    Json,
}

impl Format {
    /// The format of `path` from its extension (case-insensitive), or
    /// [`SceneError::UnsupportedExtension`].
    pub fn from_path(path: &Path) -> Result<Format, SceneError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        match ext.to_ascii_lowercase().as_str() {
            "ron" => Ok(Format::Ron),
            "json" => Ok(Format::Json),
            _ => Err(SceneError::UnsupportedExtension {
                path: path.to_path_buf(),
                extension: ext,
            }),
        }
    }
}

/// Reads, parses and validates the scene file at `path` (format from the
/// extension: `.ron` or `.json`). Points files are resolved relative to the
/// scene file's directory. The returned scene's [`Scene::origin`] is
/// `path`.
///
/// Errors: [`SceneError::UnsupportedExtension`], [`SceneError::Io`],
/// [`SceneError::Parse`] (with line and column), then the validation
/// errors of [`Scene::validate`].
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    load_scene_with(path, crate::schema::WorkLimits::default(), None)
}

/// [`load_scene`] under the given work limits (kept in
/// [`Scene::limits`], so building validates under them too). With
/// `frames` (the runner's frame count override, at least 2), the duration
/// is set to those frames first ([`Scene::set_frames`]), so the limits
/// count the run that will actually be made.
pub fn load_scene_with(
    path: &Path,
    limits: crate::schema::WorkLimits,
    frames: Option<usize>,
) -> Result<Scene, SceneError> {
    load_scene_estimated(path, limits, frames).map(|(scene, _, _)| scene)
}

/// [`load_scene_with`], also returning what validation found
/// ([`Scene::validate_estimated`]): each object's particle count and the
/// work estimate, so that a caller that prints them does not read the
/// scene's points files again.
///
/// # Errors
///
/// As [`load_scene`].
pub fn load_scene_estimated(
    path: &Path,
    limits: crate::schema::WorkLimits,
    frames: Option<usize>,
) -> Result<(Scene, Vec<usize>, crate::WorkEstimate), SceneError> {
    let format = Format::from_path(path)?;
    let text = read_text_file(path, MAX_SCENE_FILE_BYTES)?;
    let mut scene = parse_unvalidated(&text, format, &path.display().to_string())?;
    scene.limits = limits;
    if let Some(n) = frames {
        scene.set_frames(n);
    }
    let (counts, estimate) = scene.validate_estimated(path.parent())?;
    Ok((scene, counts, estimate))
}

impl Scene {
    /// Sets the run's length to `frames` frames (the runner's frame count
    /// override, `opsim run --frames`): the duration becomes `(frames - 1)
    /// / frame_rate`, shorter or longer than the file's, so that
    /// validation counts the work of the run that will be made (a longer
    /// run is held to the frame and step limits like a longer
    /// `world.duration`). Fewer than 2 frames leave the duration as it is
    /// (frame 0 alone is written).
    pub fn set_frames(&mut self, frames: usize) {
        if frames < 2 {
            return;
        }
        let d = (frames - 1) as op_dynamics::Real / self.world.frame_rate;
        if d.is_finite() && d > 0.0 {
            self.world.duration = d;
            self.frames_override = Some(frames);
        }
    }
}

/// Largest scene file read, in bytes (256 MiB: a `List` of a million
/// particles takes about 100 MiB).
pub const MAX_SCENE_FILE_BYTES: u64 = 256 << 20;

/// Reads the regular file at `path` (symbolic links followed) as UTF-8 text
/// of at most `limit` bytes: a device, a FIFO or a directory is refused
/// before anything is read, and so is a larger file.
pub fn read_text_file(path: &Path, limit: u64) -> Result<String, SceneError> {
    use std::io::Read;
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(io(std::io::Error::other(
            "not a regular file (a scene must be a .ron or .json file)",
        )));
    }
    if meta.len() > limit {
        return Err(io(std::io::Error::other(format!(
            "{} bytes, more than the limit of {limit} bytes",
            meta.len()
        ))));
    }
    let mut text = String::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(limit + 1)
        .read_to_string(&mut text)
        .map_err(io)?;
    if text.len() as u64 > limit {
        return Err(io(std::io::Error::other(format!(
            "more than the limit of {limit} bytes"
        ))));
    }
    Ok(text)
}

/// Loads the scene file at `path` and builds it for a run ([`load_scene`]
/// then [`Scene::build_for_run`] with the file's directory and path).
pub fn build_scene_file(path: &Path) -> Result<BuiltScene, SceneError> {
    let scene = load_scene(path)?;
    scene.build_for_run(path.parent(), Some(path.to_path_buf()))
}

/// Parses and validates scene text (embedded scenes, tests). `origin`
/// names it in messages (e.g. `<demo: scenes/sheet.ron>`). Points files
/// are resolved relative to the working directory; use
/// [`Scene::validate`] / [`Scene::build`] with a directory otherwise.
pub fn parse_scene(text: &str, format: Format, origin: &str) -> Result<Scene, SceneError> {
    let scene = parse_unvalidated(text, format, origin)?;
    scene.validate(None)?;
    Ok(scene)
}

/// Parses scene text without validating it.
/// A UTF-8 byte order mark at the start is skipped.
pub fn parse_unvalidated(text: &str, format: Format, origin: &str) -> Result<Scene, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut scene: Scene = match format {
        Format::Ron => ron::Options::default()
            .with_default_extension(Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| SceneError::Parse {
                file: origin.to_string(),
                line: e.position.line,
                column: e.position.col,
                message: format!(
                    "{}{}",
                    e.code,
                    excerpt(text, e.position.line, e.position.col)
                ),
            })?,
        Format::Json => serde_json::from_str(text).map_err(|e| {
            let message = e.to_string();
            // serde_json appends " at line L column C"; the position is
            // reported separately.
            let message = match message.rfind(" at line ") {
                Some(k) => message[..k].to_string(),
                None => message,
            };
            SceneError::Parse {
                file: origin.to_string(),
                line: e.line(),
                column: e.column(),
                message: format!("{message}{}", excerpt(text, e.line(), e.column())),
            }
        })?,
    };
    scene.origin = origin.to_string();
    if format == Format::Ron {
        scene.expected_warnings = crate::schema::expected_warnings(text);
    }
    crate::presets::resolve(&mut scene);
    Ok(scene)
}

/// The source line `line` (1-based) of `text` with a caret under column
/// `column` (1-based, in characters), as two indented lines starting with
/// a newline, for a parse error: the parser's message ("Expected float")
/// names no field, the line shows it. At most [`EXCERPT_WIDTH`] characters
/// around the column (a minified JSON scene is one long line); empty when
/// the line does not exist.
fn excerpt(text: &str, line: usize, column: usize) -> String {
    let Some(source) = text.lines().nth(line.saturating_sub(1)) else {
        return String::new();
    };
    let chars: Vec<char> = source.chars().collect();
    let at = column.saturating_sub(1).min(chars.len());
    let start = at.saturating_sub(EXCERPT_WIDTH / 2);
    let end = (start + EXCERPT_WIDTH).min(chars.len());
    let shown: String = chars[start..end].iter().collect();
    let number = line.to_string();
    format!(
        "\n  {number} | {}\n  {} | {}^",
        shown.trim_end(),
        " ".repeat(number.len()),
        " ".repeat(at - start)
    )
}

/// Characters of a source line shown by [`excerpt`].
const EXCERPT_WIDTH: usize = 100;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_show_the_line_with_a_caret() {
        let text = "(\n    name: \"x\",\n    world: (dt: \"fast\"),\n)";
        let e = parse_unvalidated(text, Format::Ron, "x.ron")
            .unwrap_err()
            .to_string();
        let caret = e.lines().last().unwrap();
        let source = e.lines().nth(e.lines().count() - 2).unwrap();
        assert!(source.contains("world: (dt: \"fast\")"), "{e}");
        // The caret stands under the value the parser stopped at.
        let col = caret.find('^').unwrap();
        assert!(
            source[col..].starts_with('"') || source[..col].ends_with(": "),
            "{e}"
        );
        // A long line is cut around the column; a missing line shows nothing.
        let long = format!("{}x", " ".repeat(10_000));
        assert!(excerpt(&long, 1, 10_001).len() < 2 * EXCERPT_WIDTH);
        assert_eq!(excerpt("a", 3, 1), "");
    }

    const BASE: &str = r#"(name: "t", materials: {"m": ()},
        objects: [(name: "a", material: "m", generator: Chain(count: 3, spacing: 1))])"#;

    #[test]
    fn the_base_scene_parses_in_both_formats() {
        let s = parse_scene(BASE, Format::Ron, "<t>").unwrap();
        assert_eq!(s.origin(), "<t>");
        assert_eq!(s.world, crate::schema::WorldSettings::default());
        let json = serde_json::to_string(&s).unwrap();
        let back = parse_scene(&json, Format::Json, "<t.json>").unwrap();
        assert_eq!(back.objects, s.objects);
    }

    /// `--frames N` sets the run's length both ways, and a run made longer
    /// than the limits allow is refused naming the flag (issue 38: five
    /// million frames of a 161-frame scene used to start).
    #[test]
    fn frames_set_the_run_length_and_count_against_the_limits() {
        let base = parse_scene(BASE, Format::Ron, "<t>").unwrap();
        let rate = base.world.frame_rate;
        for (frames, duration) in [(5, 4.0 / rate), (1_000, 999.0 / rate)] {
            let mut s = base.clone();
            s.set_frames(frames);
            assert_eq!(s.world.duration, duration);
            s.validate(None).unwrap();
        }
        let mut one = base.clone();
        one.set_frames(1);
        assert_eq!(one.world.duration, base.world.duration);
        let mut long = base.clone();
        long.set_frames(5_000_000);
        let e = long.validate(None).unwrap_err().to_string();
        assert!(e.contains("(set by --frames 5000000)"), "{e}");
        assert!(e.contains("--no-work-limits"), "{e}");
        long.limits = crate::schema::WorkLimits::unlimited();
        long.validate(None).unwrap();
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let with_bom = format!("\u{feff}{BASE}");
        assert!(parse_scene(&with_bom, Format::Ron, "<t>").is_ok());
    }

    #[test]
    fn non_regular_and_oversized_scene_files_are_refused() {
        let e = read_text_file(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(format!("{:?}", e).contains("not a regular file"), "{e:?}");
        let dir = std::env::temp_dir().join(format!("op-scene-big-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.ron");
        std::fs::write(&big, "x".repeat(2000)).unwrap();
        let e = read_text_file(&big, 1000).unwrap_err();
        assert!(format!("{:?}", e).contains("limit"), "{e:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unknown_fields_are_rejected_at_every_level() {
        for (text, format, needle) in [
            (
                BASE.replace("spacing: 1)", "spacing: 1, colour: 2)"),
                Format::Ron,
                "colour",
            ),
            (
                BASE.replace(
                    "materials: {\"m\": ()}",
                    "materials: {\"m\": (stiffness: 1)}",
                ),
                Format::Ron,
                "stiffness",
            ),
            (
                BASE.replace(
                    "(name: \"t\",",
                    "(name: \"t\", world: (divergence: (max_sped: 1)),",
                ),
                Format::Ron,
                "max_sped",
            ),
            (
                BASE.replace(")])", ", overrides: [(particles: All, fixed: true)])])"),
                Format::Ron,
                "fixed",
            ),
            (
                BASE.replace(
                    ")])",
                    ")], forces: [(object: \"a\", force: (1, 0, 0), stop: 2)])",
                ),
                Format::Ron,
                "stop",
            ),
            (
                BASE.replace(")])", ")], outputs: (glyphs: 2))"),
                Format::Ron,
                "glyphs",
            ),
            (
                r#"{"name": "t", "materials": {"m": {}}, "objects": [{"name": "a", "material": "m",
                   "generator": {"List": {"particles": [{"position": [0, 0, 0], "colour": 1}]}}}]}"#
                    .to_string(),
                Format::Json,
                "unknown field `colour`",
            ),
        ] {
            let e = parse_scene(&text, format, "<t>").unwrap_err();
            assert!(matches!(e, SceneError::Parse { .. }), "{e}");
            assert!(e.to_string().contains(needle), "{needle}: {e}");
        }
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(
            Format::from_path(Path::new("a/b.RON")).unwrap(),
            Format::Ron
        );
        assert_eq!(
            Format::from_path(Path::new("b.json")).unwrap(),
            Format::Json
        );
        for bad in ["b.yaml", "b", "b.ron.txt"] {
            let e = Format::from_path(Path::new(bad)).unwrap_err();
            assert!(e.to_string().contains(".ron, .json"), "{e}");
        }
    }

    #[test]
    fn a_missing_file_is_an_io_error_naming_it() {
        let e = load_scene(Path::new("/nonexistent/dir/scene.ron")).unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/dir/scene.ron"), "{e}");
    }
}
