//! Errors of loading, validating and building a scene (README "Running scenes"): each
//! names the file, then the line and column or the field path, then what is
//! wrong and what would be valid. Nothing in the scene layer panics on bad
//! input; it returns one of these.

use std::path::PathBuf;

use op_dynamics::ParamError;

/// Why a scene could not be loaded, validated or built.
///
/// Display forms:
///
/// - `scenes/bad.ron:3:5: unknown field ...` ([`SceneError::Parse`])
/// - `scenes/bad.ron: objects[0] "sheet".mass = -1: must be finite and > 0`
///   ([`SceneError::Invalid`])
/// - `scenes/data/patch.xyz:7: expected 3 or 6 numbers, found 2`
///   ([`SceneError::Points`])
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// A file could not be read. Fix: check the path and permissions.
    /// (The operating system's message is the error's source, printed once
    /// by error-chain printers such as `opsim`'s.)
    #[error("cannot read {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The scene file's extension is not one the loader knows. Fix: name the
    /// file `.ron` or `.json`.
    #[error(
        "{}: unsupported scene file extension {extension:?} (valid extensions: .ron, .json)",
        path.display()
    )]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        extension: String,
    },
    /// The text is not valid RON / JSON, or does not match the schema
    /// (unknown field, wrong type, missing field). Fix: edit the file at
    /// `line:column`.
    #[error("{file}:{line}:{column}: {message}")]
    Parse {
        /// The scene file (or the origin label of an embedded scene).
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// The scene parsed but a value is out of range or inconsistent. Fix:
    /// change the field named by `path` as `message` says.
    #[error("{file}: {path}{}{message}", separator(message))]
    Invalid {
        /// The scene file (or the origin label of an embedded scene).
        file: String,
        /// Field path, e.g. `objects[1] "sheet".generator.HexSheet.spacing`.
        path: String,
        /// What is wrong and what is allowed. When a value is rejected it
        /// starts with `= value: `, e.g. `= -1: must be finite and > 0`.
        message: String,
    },
    /// A points file (`Points` generator) has a bad line or no point. Fix:
    /// edit that line of the points file.
    #[error("{file}:{line}: {message}")]
    Points {
        /// The points file.
        file: String,
        /// 1-based line (0 when the problem concerns the whole file).
        line: usize,
        /// What is wrong with the line.
        message: String,
    },
    /// The validated scene could not be turned into a world (for example
    /// coincident particles, or an error reported by op-dynamics).
    #[error("{file}: {message}")]
    Build {
        /// The scene file (or the origin label of an embedded scene).
        file: String,
        /// What went wrong, with the object or material concerned.
        message: String,
    },
}

/// A number for messages: the shortest decimal that reads back as `x`
/// rounded to 12 significant digits, as Rust prints it, when that is short
/// (at most 12 characters: `0.72`, not `0.7200000000000001`), otherwise in
/// scientific notation with at most 6 significant digits (`1e308`, not 309
/// digits). Frame files do not use it: they keep every digit.
pub fn short(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.11e}").parse().unwrap_or(x);
    let plain = format!("{rounded}");
    if plain.len() <= 12 {
        return plain;
    }
    let sci = format!("{x:.5e}");
    // Trim trailing zeros of the mantissa: 1.50000e3 -> 1.5e3.
    match sci.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            let m = m.trim_end_matches('0').trim_end_matches('.');
            format!("{m}e{e}")
        }
        _ => sci,
    }
}

/// Longest text quoted whole in a message; longer text is elided.
pub const MAX_QUOTED_CHARS: usize = 80;

/// `text` for a message: whole when at most [`MAX_QUOTED_CHARS`]
/// characters, else its start and end around `...` and its length.
pub fn elide(text: &str) -> String {
    let n = text.chars().count();
    if n <= MAX_QUOTED_CHARS {
        return text.to_string();
    }
    let head: String = text.chars().take(MAX_QUOTED_CHARS / 2).collect();
    let tail: String = text.chars().skip(n - MAX_QUOTED_CHARS / 4).collect();
    format!("{head}...{tail} ({n} characters)")
}

/// Most names a message lists; the rest are counted.
pub const MAX_LISTED: usize = 20;

/// `names` for a message: quoted, each [`elide`]d, comma separated, at
/// most [`MAX_LISTED`] of them and then how many more; `none` without
/// any. (A scene of a thousand objects named with 5,000 characters each
/// made a 5 MB message.)
pub fn quoted_list<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let mut listed = Vec::new();
    let mut more = 0usize;
    for name in names {
        if listed.len() < MAX_LISTED {
            listed.push(format!("{:?}", elide(name)));
        } else {
            more += 1;
        }
    }
    match (listed.is_empty(), more) {
        (true, _) => "none".into(),
        (false, 0) => listed.join(", "),
        (false, n) => format!("{} and {n} more", listed.join(", ")),
    }
}

/// `" "` before a message that starts with `= value`, `": "` otherwise.
fn separator(message: &str) -> &'static str {
    if message.starts_with("= ") {
        " "
    } else {
        ": "
    }
}

impl SceneError {
    /// An [`SceneError::Invalid`].
    pub(crate) fn invalid(file: &str, path: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError::Invalid {
            file: file.to_string(),
            path: path.into(),
            message: message.into(),
        }
    }

    /// An [`SceneError::Invalid`] for a rejected value; numbers are shown
    /// in short form ([`short`]) and long values elided ([`elide`]).
    pub(crate) fn value(
        file: &str,
        path: impl Into<String>,
        value: impl std::fmt::Display,
        allowed: &str,
    ) -> Self {
        let text = value.to_string();
        let shown = match text.parse::<f64>() {
            Ok(x) if text.len() > 12 => short(x),
            _ => elide(&text),
        };
        Self::invalid(file, path, format!("= {shown}: {allowed}"))
    }

    /// An op-dynamics parameter error under the scene path `prefix`
    /// (`materials."soft"` + `spacing.cohesion.alpha`).
    pub(crate) fn param(file: &str, prefix: &str, e: ParamError) -> Self {
        match e {
            ParamError::OutOfRange {
                field,
                value,
                allowed,
            } => Self::value(file, join(prefix, &field), value, &allowed),
            ParamError::Invalid { field, message } => {
                Self::invalid(file, join(prefix, &field), message)
            }
            other => Self::invalid(file, prefix, other.to_string()),
        }
    }
}

/// `prefix.field`, or `field` alone when `prefix` is empty.
pub(crate) fn join(prefix: &str, field: &str) -> String {
    if prefix.is_empty() {
        field.to_string()
    } else if field.starts_with('[') {
        format!("{prefix}{field}")
    } else {
        format!("{prefix}.{field}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_forms() {
        let e = SceneError::value(
            "scenes/bad.ron",
            "objects[0] \"sheet\".mass",
            -1.0,
            "must be finite and > 0",
        );
        assert_eq!(
            e.to_string(),
            "scenes/bad.ron: objects[0] \"sheet\".mass = -1: must be finite and > 0"
        );
        let e = SceneError::invalid("a.ron", "objects[0] \"x\".material", "unknown material");
        assert_eq!(
            e.to_string(),
            "a.ron: objects[0] \"x\".material: unknown material"
        );
        let e = SceneError::Parse {
            file: "scenes/bad.ron".into(),
            line: 3,
            column: 5,
            message: "unknown field".into(),
        };
        assert_eq!(e.to_string(), "scenes/bad.ron:3:5: unknown field");
        let e = SceneError::value("s.ron", "world.dt", 1e308, "too large");
        assert_eq!(e.to_string(), "s.ron: world.dt = 1e308: too large");
        assert_eq!(short(0.7200000000000001), "0.72");
        assert_eq!(short(0.1 + 0.2), "0.3");
        assert_eq!(short(1.0 / 3.0), "3.33333e-1");
        assert_eq!(short(2.5), "2.5");
        assert_eq!(short(-1e-7 * 3.0), "-0.0000003");
        assert_eq!(short(f64::INFINITY), "inf");
        let e = SceneError::value("s.ron", "forces[0].ramp", 0.1 + 0.2, "too long");
        assert_eq!(e.to_string(), "s.ron: forces[0].ramp = 0.3: too long");
        let e = SceneError::value("s.ron", "name", "x".repeat(4_000_000), "bad");
        assert!(e.to_string().len() < 200, "{}", e.to_string().len());
        assert!(e.to_string().contains("(4000000 characters)"));
        let p = ParamError::OutOfRange {
            field: "spacing.cohesion.alpha".into(),
            value: f64::NAN,
            allowed: "must be finite and > 0".into(),
        };
        let e = SceneError::param("s.ron", "materials.\"soft\"", p);
        assert_eq!(
            e.to_string(),
            "s.ron: materials.\"soft\".spacing.cohesion.alpha = NaN: must be finite and > 0"
        );
    }
}
