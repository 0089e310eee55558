//! Point sets read from `.xyz` text files, and explicit particle lists.

use std::path::{Path, PathBuf};

use op_dynamics::{Point3, Real, Vec3};

use super::{Generated, ListParticle};
use crate::error::SceneError;
use crate::schema::checks;

/// The points file `path` resolved against the scene's directory
/// (`base_dir`); absolute paths and scenes without a directory use `path`
/// as is (relative to the working directory).
pub fn resolve(base_dir: Option<&Path>, path: &Path) -> PathBuf {
    match base_dir {
        Some(dir) if path.is_relative() => dir.join(path),
        _ => path.to_path_buf(),
    }
}

/// Parses `.xyz` text: one point per line, `x y z` or `x y z nx ny nz`
/// (whitespace or commas between numbers), `#` starts a comment, blank
/// lines are skipped. Normals default to +z. Stops with an error naming
/// `file` and the line when a line is malformed, a value is not finite, a
/// normal is zero, or there are more than `max` points.
pub fn parse_xyz(text: &str, file: &str, max: usize) -> Result<Generated, SceneError> {
    let mut out = Generated::default();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let err = |message: String| SceneError::Points {
            file: file.to_string(),
            line,
            message,
        };
        let content = raw.split('#').next().unwrap_or("");
        let fields: Vec<&str> = content
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .collect();
        if fields.is_empty() {
            continue;
        }
        if fields.len() != 3 && fields.len() != 6 {
            return Err(err(format!(
                "expected 3 numbers (x y z) or 6 (x y z nx ny nz), found {}",
                fields.len()
            )));
        }
        let mut v = [0.0; 6];
        for (slot, f) in v.iter_mut().zip(&fields) {
            let x: Real = f
                .parse()
                .map_err(|_| err(format!("`{f}` is not a number")))?;
            if !x.is_finite() {
                return Err(err(format!("`{f}` is not finite")));
            }
            *slot = x;
        }
        let normal = if fields.len() == 6 {
            let n = Vec3::new(v[3], v[4], v[5]);
            if n.norm() <= 1e-12 {
                return Err(err(format!(
                    "normal ({}, {}, {}) is zero; give a non-zero direction or omit it",
                    v[3], v[4], v[5]
                )));
            }
            n.normalize()
        } else {
            Vec3::z()
        };
        if out.positions.len() >= max {
            return Err(err(format!("more than {max} points")));
        }
        out.positions.push(Point3::new(v[0], v[1], v[2]));
        out.normals.push(normal);
        out.curvatures.push(0.0);
    }
    Ok(out)
}

/// Reads and parses a points file; `shown` is the file name used in
/// messages.
pub(super) fn read_xyz(
    resolved: &Path,
    file: &str,
    path: &str,
    shown: &Path,
    max: usize,
) -> Result<Generated, SceneError> {
    let text = match std::fs::read_to_string(resolved) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(missing(file, path, shown, resolved));
        }
        Err(source) => {
            return Err(SceneError::Io {
                path: resolved.to_path_buf(),
                source,
            })
        }
    };
    parse_xyz(&text, &resolved.display().to_string(), max).map_err(|e| match e {
        SceneError::Points {
            file: points,
            line,
            message,
        } => SceneError::Points {
            file: points,
            line,
            message: format!("{message} (points file of {path} in {file})"),
        },
        other => other,
    })
}

/// The error for a points file that does not exist.
pub(super) fn missing(file: &str, path: &str, shown: &Path, resolved: &Path) -> SceneError {
    SceneError::value(
        file,
        path,
        format!("{:?}", shown.display().to_string()),
        &format!(
            "points file not found (looked for {}; relative paths are relative to the scene file's directory)",
            resolved.display()
        ),
    )
}

/// Checks an explicit particle list (path: `...generator.List.particles`).
pub(super) fn validate_list(
    particles: &[ListParticle],
    file: &str,
    path: &str,
) -> Result<(), SceneError> {
    for (i, p) in particles.iter().enumerate() {
        let at = format!("{path}[{i}]");
        checks::finite3(file, &format!("{at}.position"), &p.position)?;
        if let Some(n) = &p.normal {
            checks::direction(file, &format!("{at}.normal"), n)?;
        }
        if let Some(k) = p.curvature {
            checks::finite(file, &format!("{at}.curvature"), k)?;
        }
    }
    Ok(())
}

/// The particles of an explicit list (validated).
pub(super) fn list(particles: &[ListParticle]) -> Generated {
    Generated {
        positions: particles.iter().map(|p| Point3::from(p.position)).collect(),
        normals: particles
            .iter()
            .map(|p| p.normal.map_or(Vec3::z(), |n| Vec3::from(n).normalize()))
            .collect(),
        curvatures: particles
            .iter()
            .map(|p| p.curvature.unwrap_or(0.0))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_points_with_and_without_normals() {
        let g = parse_xyz("# patch\n0 0 0\n\n1, 2, 3  0 0 2 # tail\n", "p.xyz", 10).unwrap();
        assert_eq!(g.positions.len(), 2);
        assert_eq!(g.normals[0], Vec3::z());
        assert_eq!(g.positions[1], Point3::new(1.0, 2.0, 3.0));
        assert_eq!(g.normals[1], Vec3::z());
    }

    #[test]
    fn bad_lines_name_file_and_line() {
        for (text, needle) in [
            ("0 0 0\n1 2\n", "p.xyz:2: expected 3 numbers"),
            ("0 0 x\n", "p.xyz:1: `x` is not a number"),
            ("0 0 0\n\n0 0 NaN\n", "p.xyz:3: `NaN` is not finite"),
            ("0 0 0 0 0 0\n", "p.xyz:1: normal (0, 0, 0) is zero"),
            ("0 0 0\n1 1 1\n2 2 2\n", "p.xyz:3: more than 2 points"),
        ] {
            let e = parse_xyz(text, "p.xyz", 2).unwrap_err();
            assert!(matches!(e, SceneError::Points { .. }));
            assert!(e.to_string().contains(needle), "{e} / {needle}");
        }
    }
}
