//! Point sets read from files (`.xyz`, `.ply`, `.obj`, through
//! [`crate::pointsets`]), and explicit particle lists.

use std::path::{Path, PathBuf};

use op_dynamics::{Point3, Vec3};

use crate::pointsets::{self, PointSet, PointSetError};

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

/// Reads a points file (`.xyz`, `.ply` or `.obj`, [`crate::pointsets`]:
/// the one reader of `opsim fit` and the `Points` generator) at `resolved`;
/// `shown` is the path as written in the scene, `path` the field path and
/// `file` the scene in messages. An empty set is returned as such.
///
/// # Errors
/// A missing file ([`SceneError::Invalid`] naming the field), an
/// unreadable one ([`SceneError::Io`]), malformed content
/// ([`SceneError::Points`]: the points file, its line, what is wrong, and
/// which field of which scene reads it) or more than `max` points.
pub(crate) fn read_points(
    resolved: &Path,
    file: &str,
    path: &str,
    shown: &Path,
    max: usize,
) -> Result<PointSet, SceneError> {
    if !resolved.is_file() {
        return Err(missing(file, path, shown, resolved));
    }
    let set = pointsets::read_points(resolved).map_err(|e| match e {
        PointSetError::Io { source, .. } => SceneError::Io {
            path: resolved.to_path_buf(),
            source,
        },
        PointSetError::Format {
            file: points,
            line,
            message,
        } => SceneError::Points {
            file: points,
            line: line.unwrap_or(0),
            message: format!("{message} (points file of {path} in {file})"),
        },
    })?;
    if set.positions.len() > max {
        return Err(SceneError::value(
            file,
            path,
            format!("{:?}", shown.display().to_string()),
            &format!(
                "the points file holds {} points; at most {max} are allowed",
                set.positions.len()
            ),
        ));
    }
    Ok(set)
}

/// The particles of a point set: its normals (+z when the file has none)
/// and curvature 0.
pub(super) fn generated(set: PointSet) -> Generated {
    let n = set.positions.len();
    Generated {
        normals: set.normals.unwrap_or_else(|| vec![Vec3::z(); n]),
        curvatures: vec![0.0; n],
        positions: set.positions,
    }
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

    fn temp(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("op-scene-points-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn points_without_normals_face_plus_z() {
        let p = temp("plain.xyz", "# patch\n0 0 0\n\n1, 2, 3 # tail\n");
        let g = generated(read_points(&p, "s.ron", "g", Path::new("plain.xyz"), 10).unwrap());
        assert_eq!(
            g.positions,
            vec![Point3::origin(), Point3::new(1.0, 2.0, 3.0)]
        );
        assert_eq!(g.normals, vec![Vec3::z(); 2]);
        assert_eq!(g.curvatures, vec![0.0; 2]);
    }

    #[test]
    fn bad_files_name_file_line_and_field() {
        for (name, text, needle) in [
            ("a.xyz", "0 0 0\n1 2\n", "a.xyz:2: expected 3 numbers"),
            ("b.xyz", "0 0 x\n", "b.xyz:1: `x` is not a number"),
            (
                "c.xyz",
                "0 0 0\n\n0 0 NaN\n",
                "c.xyz:3: `NaN` is not finite",
            ),
            ("d.xyz", "0 0 0 0 inf 1\n", "d.xyz:1: `inf` is not finite"),
            (
                "e.xyz",
                "0 0 0 0 0 1\n1 1 1\n",
                "e.xyz:2: 3 numbers where earlier lines have 6",
            ),
        ] {
            let p = temp(name, text);
            let e =
                read_points(&p, "s.ron", "objects[0].generator", Path::new(name), 10).unwrap_err();
            assert!(matches!(e, SceneError::Points { .. }), "{e}");
            let e = e.to_string();
            assert!(e.contains(needle), "{e} / {needle}");
            assert!(e.contains("objects[0].generator in s.ron"), "{e}");
        }
        let p = temp("f.xyz", "0 0 0\n1 1 1\n2 2 2\n");
        let e = read_points(&p, "s.ron", "g.path", Path::new("f.xyz"), 2)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.ron: g.path") && e.contains("3 points; at most 2"),
            "{e}"
        );
        let e = read_points(
            &p.with_extension("ply"),
            "s.ron",
            "g.path",
            Path::new("f.ply"),
            2,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("not found"), "{e}");
    }
}
