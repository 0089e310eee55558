//! Point sets read from files for point-set interpolation (seed 000 §7,
//! README "Running scenes", `opsim fit`): `.xyz` text (and `.pwn`, CGAL's
//! points with normals, the same text), `.ply` (ascii and
//! binary_little_endian) and `.obj` (`v` and `vn` lines).
//!
//! Entry points: [`read_point_set`] (by extension) and the parsers
//! [`parse_xyz`], [`parse_ply`], [`parse_obj`]. Every error names the file,
//! the line for text input, and what is wrong (a long offending token is
//! cut to [`EXCERPT_CHARS`] characters); nothing panics on bad input.
//!
//! **Limits**: the input must be a regular file (a symlink is followed; a
//! directory, device, pipe or socket is refused before it is opened) of at
//! most [`MAX_POINT_FILE_BYTES`] (1 GiB). A UTF-8 byte-order mark at the
//! start of the file is skipped.

use std::path::Path;

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

pub use crate::input::EXCERPT_CHARS;
use crate::input::{excerpt, read_regular_file, strip_bom, InputFileError};

/// Samples of a surface, with normals when the file gives them (the input
/// of the fit, [`op_modeling::fit::PointSet`]).
pub use op_modeling::fit::PointSet;

/// Largest point-set file read (1 GiB); a larger one is an error naming it.
pub const MAX_POINT_FILE_BYTES: u64 = 1 << 30;

/// A point-set file could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PointSetError {
    /// The file could not be opened or read. Fix: check the path.
    #[error("{file}: cannot read")]
    Io {
        /// The file.
        file: String,
        /// The system error.
        source: std::io::Error,
    },
    /// The file is not a usable point set: not a regular file, larger than
    /// [`MAX_POINT_FILE_BYTES`], or malformed content. Fix: give a regular
    /// file, or edit that line (or the header) of the file.
    #[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Format {
        /// The file.
        file: String,
        /// 1-based line for text content, `None` for binary data or the
        /// file as a whole.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
}

fn format_err(file: &str, line: Option<usize>, message: impl Into<String>) -> PointSetError {
    PointSetError::Format {
        file: file.to_string(),
        line,
        message: message.into(),
    }
}

/// Reads a point set, the format chosen by the extension (`xyz`, `ply`,
/// `obj`, case-insensitive).
///
/// # Errors
/// An unreadable file, one that is not a regular file or is larger than
/// [`MAX_POINT_FILE_BYTES`], an unknown extension, malformed content, no
/// point, or a non-finite value.
pub fn read_point_set(path: &Path) -> Result<PointSet, PointSetError> {
    read_point_set_at_most(path, usize::MAX)
}

/// [`read_point_set`], refusing a file of more than `max_points` points
/// before its points are parsed: from a PLY file's header, from the point
/// lines of an `.xyz` or `.obj` file (`opsim fit` reads at most
/// [`op_modeling::fit::MAX_PARTICLES`] samples).
///
/// # Errors
/// As [`read_point_set`], and more points than `max_points`.
pub fn read_point_set_at_most(path: &Path, max_points: usize) -> Result<PointSet, PointSetError> {
    let set = read_points_at_most(path, max_points)?;
    if set.positions.is_empty() {
        return Err(format_err(
            &path.display().to_string(),
            None,
            "no point in the file",
        ));
    }
    Ok(set)
}

/// [`read_point_set`], except that a file without a point gives an empty
/// set (the scene layer reports that against the field that reads it).
///
/// # Errors
/// An unreadable file, one that is not a regular file or is larger than
/// [`MAX_POINT_FILE_BYTES`], an unknown extension, malformed content or a
/// non-finite value.
pub fn read_points(path: &Path) -> Result<PointSet, PointSetError> {
    read_points_at_most(path, usize::MAX)
}

/// [`read_points`] with the limit of [`read_point_set_at_most`].
fn read_points_at_most(path: &Path, max_points: usize) -> Result<PointSet, PointSetError> {
    let file = path.display().to_string();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !matches!(ext.as_str(), "xyz" | "pwn" | "ply" | "obj") {
        return Err(format_err(
            &file,
            None,
            format!("unknown point-set format `.{ext}`: use .xyz (or .pwn), .ply or .obj"),
        ));
    }
    let bytes = match read_regular_file(path, MAX_POINT_FILE_BYTES) {
        Ok(b) => b,
        Err(InputFileError::Io(source)) => {
            return Err(PointSetError::Io {
                file: file.clone(),
                source,
            })
        }
        Err(e) => return Err(format_err(&file, None, e.message(MAX_POINT_FILE_BYTES))),
    };
    let bytes = strip_bom(&bytes);
    Ok(match ext.as_str() {
        "ply" => parse_ply_at_most(bytes, &file, max_points)?,
        _ => {
            let lines = point_lines(bytes, ext == "obj");
            if lines > max_points {
                return Err(format_err(
                    &file,
                    None,
                    format!("it has {lines} point lines, more than the {max_points} allowed"),
                ));
            }
            let text = std::str::from_utf8(bytes)
                .map_err(|e| format_err(&file, None, format!("not UTF-8 text: {e}")))?;
            if ext != "obj" {
                // `.xyz`, or `.pwn`: `x y z nx ny nz` per line.
                parse_xyz(text, &file)?
            } else {
                parse_obj(text, &file)?
            }
        }
    })
}

fn number(field: &str, file: &str, line: usize) -> Result<Real, PointSetError> {
    let x: Real = field.parse().map_err(|_| {
        format_err(
            file,
            Some(line),
            format!("`{}` is not a number", excerpt(field)),
        )
    })?;
    if !x.is_finite() {
        return Err(format_err(
            file,
            Some(line),
            format!("`{}` is not finite", excerpt(field)),
        ));
    }
    Ok(x)
}

/// A file's normal made unit length; `None` for the zero vector, which
/// writers use for "no normal" (CGAL writes `0 0 0` for points without
/// one): see [`given_normals`].
///
/// # Errors
/// A non-finite normal.
fn unit(n: Vec3, file: &str, line: Option<usize>) -> Result<Option<Vec3>, PointSetError> {
    let length = n.norm();
    if !length.is_finite() {
        return Err(format_err(
            file,
            line,
            format!("normal ({}, {}, {}) is not finite", n.x, n.y, n.z),
        ));
    }
    Ok((length > 1e-12).then(|| n / length))
}

/// The normals of a file whose every point has a normal column: the
/// normals when all are usable, `None` (the fit estimates them) when any is
/// the zero vector, "no normal" in the writers' convention. Normals are
/// all or nothing: the orientation the fit propagates must agree with
/// the given ones, so a file mixing both is taken as having none.
fn given_normals(normals: Vec<Option<Vec3>>) -> Option<Vec<Vec3>> {
    normals.into_iter().collect()
}

/// Parses `.xyz` text: `x y z` or `x y z nx ny nz` per line (whitespace or
/// commas between numbers), `#` starts a comment, blank lines skipped.
/// Either every point has a normal or none has.
pub fn parse_xyz(text: &str, file: &str) -> Result<PointSet, PointSetError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Each line parsed on its own, in parallel; the lines are then taken
    // in order, so the first error is the first bad line's, as a serial
    // reading reports it.
    let lines: Vec<&str> = text.lines().collect();
    let parsed: Vec<XyzLine> = lines
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(k, raw)| xyz_line(raw, file, k + 1))
        .collect();
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut columns = None;
    for (k, parsed) in parsed.into_iter().enumerate() {
        let line = k + 1;
        let (count, values) = match parsed {
            XyzLine::Empty => continue,
            XyzLine::Miscounted(count) => {
                return Err(format_err(
                    file,
                    Some(line),
                    format!("expected 3 numbers (x y z) or 6 (x y z nx ny nz), found {count}"),
                ))
            }
            XyzLine::Point(count, values) => (count, values),
        };
        match columns {
            None => columns = Some(count),
            Some(c) if c != count => {
                return Err(format_err(
                    file,
                    Some(line),
                    format!(
                    "{count} numbers where earlier lines have {c}: give normals for every point or none"
                ),
                ))
            }
            Some(_) => {}
        }
        let (p, n) = values?;
        positions.push(p);
        if let Some(n) = n {
            normals.push(n);
        }
    }
    let has_normals = columns == Some(6);
    Ok(PointSet {
        positions,
        normals: has_normals.then(|| given_normals(normals)).flatten(),
    })
}

/// One line of an `.xyz` file.
enum XyzLine {
    /// No fields: blank or a comment.
    Empty,
    /// A number of fields other than 3 or 6.
    Miscounted(usize),
    /// 3 or 6 fields: the point and, for 6, its normal ([`unit`]), or why
    /// they are not numbers.
    Point(usize, Result<(Point3, Option<Option<Vec3>>), PointSetError>),
}

/// Parses line number `line` (`raw`, without its end) of an `.xyz` file.
fn xyz_line(raw: &str, file: &str, line: usize) -> XyzLine {
    let content = raw.split('#').next().unwrap_or("");
    let fields: Vec<&str> = content
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .collect();
    if fields.is_empty() {
        return XyzLine::Empty;
    }
    let count = fields.len();
    if count != 3 && count != 6 {
        return XyzLine::Miscounted(count);
    }
    let values = (|| {
        let v = fields
            .iter()
            .map(|f| number(f, file, line))
            .collect::<Result<Vec<_>, _>>()?;
        let p = Point3::new(v[0], v[1], v[2]);
        let n = if count == 6 {
            Some(unit(Vec3::new(v[3], v[4], v[5]), file, Some(line))?)
        } else {
            None
        };
        Ok((p, n))
    })();
    XyzLine::Point(count, values)
}

/// Parses `.obj` text: `v x y z [w]` lines are the points; `vn` lines, when
/// there are exactly as many as `v` lines, their normals (in order). Other
/// lines (faces, groups, ...) are ignored.
pub fn parse_obj(text: &str, file: &str) -> Result<PointSet, PointSetError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut fields = content.split_whitespace();
        let tag = fields.next();
        if tag != Some("v") && tag != Some("vn") {
            continue;
        }
        let v: Vec<&str> = fields.collect();
        let wanted = if tag == Some("v") { 3..=4 } else { 3..=3 };
        if !wanted.contains(&v.len()) {
            return Err(format_err(
                file,
                Some(line),
                format!(
                    "`{}` needs 3 numbers, found {}",
                    tag.unwrap_or_default(),
                    v.len()
                ),
            ));
        }
        let x = [
            number(v[0], file, line)?,
            number(v[1], file, line)?,
            number(v[2], file, line)?,
        ];
        if tag == Some("v") {
            positions.push(Point3::new(x[0], x[1], x[2]));
        } else {
            normals.push(unit(Vec3::new(x[0], x[1], x[2]), file, Some(line))?);
        }
    }
    let has_normals = !normals.is_empty() && normals.len() == positions.len();
    Ok(PointSet {
        positions,
        normals: has_normals.then(|| given_normals(normals)).flatten(),
    })
}

mod ply;
pub use ply::{parse_ply, parse_ply_at_most};

/// The lines of a text point set that can hold a point (one pass over the
/// bytes, before parsing): `v` lines of an OBJ file, lines of an `.xyz`
/// file that are neither blank nor `#` comments.
fn point_lines(bytes: &[u8], obj: bool) -> usize {
    bytes
        .split(|&b| b == b'\n')
        .filter(|line| {
            let start = line.iter().position(|b| !b.is_ascii_whitespace());
            let line = start.map_or(&[][..], |s| &line[s..]);
            if obj {
                line.len() > 1 && line[0] == b'v' && line[1].is_ascii_whitespace()
            } else {
                !line.is_empty() && line[0] != b'#'
            }
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xyz_with_and_without_normals() {
        let s = parse_xyz("# c\n0 0 0\n1, 2, 3\n\n", "a.xyz").unwrap();
        assert_eq!(s.positions.len(), 2);
        assert!(s.normals.is_none());
        let s = parse_xyz("0 0 0 0 0 2\n1 0 0 1 0 0\n", "a.xyz").unwrap();
        assert_eq!(s.normals.unwrap()[0], Vec3::z());
    }

    /// Zero normals mean "no normal" (CGAL writes `0 0 0` for points
    /// without one): a file with any is read as having no normals, which
    /// the fit then estimates, in every format; a non-finite normal is
    /// still an error.
    #[test]
    fn zero_normals_mean_no_normals() {
        let s = parse_xyz("0 0 0 0 0 0\n1 0 0 0 0 0\n", "z.xyz").unwrap();
        assert_eq!(s.positions.len(), 2);
        assert!(s.normals.is_none());
        let s = parse_xyz("0 0 0 0 0 1\n1 0 0 0 0 0\n", "z.xyz").unwrap();
        assert!(s.normals.is_none(), "a file mixing zero normals has none");
        let s = parse_obj("v 0 0 0\nv 1 0 0\nvn 0 0 0\nvn 0 0 0\n", "z.obj").unwrap();
        assert!(s.normals.is_none());
        let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n0 0 0 0 0 0\n1 0 0 0 0 0\n";
        let s = parse_ply(ply.as_bytes(), "z.ply").unwrap();
        assert_eq!(s.positions.len(), 2);
        assert!(s.normals.is_none());
        let e = parse_xyz("0 0 0 0 0 1\n1 0 0 nan 0 0\n", "n.xyz").unwrap_err();
        assert!(e.to_string().contains("n.xyz"), "{e}");
    }

    #[test]
    fn xyz_errors_name_file_and_line() {
        let e = parse_xyz("0 0 0\n1 2\n", "bad.xyz")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("bad.xyz:2:"), "{e}");
        let e = parse_xyz("0 0 0\n1 2 x\n", "bad.xyz")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.xyz:2") && e.contains("`x`"), "{e}");
        let e = parse_xyz("0 0 0\n1 2 3 0 0 1\n", "m.xyz")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.xyz:2"), "{e}");
    }

    /// Lines are parsed in parallel chunks (thousands of lines): the error
    /// is still the first bad line's, and a line with the wrong number of
    /// columns is named for that before its numbers are looked at.
    #[test]
    fn the_first_bad_line_of_a_long_file_is_named() {
        let lines = |bad: &[(usize, &str)]| {
            (1..=20_000)
                .map(|k| {
                    bad.iter()
                        .find(|(at, _)| *at == k)
                        .map_or(format!("{k} 0 0"), |(_, l)| l.to_string())
                })
                .collect::<Vec<_>>()
                .join("\n")
        };
        let text = lines(&[(7001, "1 2 x"), (15_000, "1 2")]);
        let e = parse_xyz(&text, "long.xyz").unwrap_err().to_string();
        assert!(e.starts_with("long.xyz:7001:") && e.contains("`x`"), "{e}");
        let text = lines(&[(12_000, "1 2 y 0 0 1"), (19_000, "1 2")]);
        let e = parse_xyz(&text, "long.xyz").unwrap_err().to_string();
        assert!(
            e.starts_with("long.xyz:12000:") && e.contains("earlier lines have 3"),
            "{e}"
        );
        let set = parse_xyz(&lines(&[]), "long.xyz").unwrap();
        assert_eq!(set.positions.len(), 20_000);
        assert_eq!(set.positions[19_999], Point3::new(20_000.0, 0.0, 0.0));
    }

    #[test]
    fn obj_vertices_and_normals() {
        let text = "# c\nv 0 0 0\nv 1 0 0\nvn 0 0 1\nvn 0 0 1\nf 1 2 1\n";
        let s = parse_obj(text, "a.obj").unwrap();
        assert_eq!(s.positions[1], Point3::new(1.0, 0.0, 0.0));
        assert_eq!(s.normals.unwrap().len(), 2);
        let e = parse_obj("v 0 0\n", "b.obj").unwrap_err().to_string();
        assert!(e.starts_with("b.obj:1:"), "{e}");
    }

    #[test]
    fn ascii_ply_skips_faces_and_reads_normals() {
        let text = "ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
        let s = parse_ply(text.as_bytes(), "a.ply").unwrap();
        assert_eq!(s.positions.len(), 3);
        assert_eq!(s.positions[2], Point3::new(0.0, 1.0, 0.0));
        assert_eq!(s.normals.unwrap()[1], Vec3::z());
        let bad = text.replace("1 0 0 0 0 1", "1 0 0 0 1");
        let e = parse_ply(bad.as_bytes(), "b.ply").unwrap_err().to_string();
        assert!(e.starts_with("b.ply:15:"), "{e}");
    }

    #[test]
    fn binary_ply_written_here_reads_back() {
        // A face element first (skipped), then vertices: double x y z and
        // an unused uchar, no normals.
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nend_header\n".to_vec();
        bytes.push(3);
        for i in [0i32, 1, 1] {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
        for p in [[1.5f64, -2.0, 3.25], [0.0, 0.5, 1e3]] {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
            bytes.push(255);
        }
        let s = parse_ply(&bytes, "b.ply").unwrap();
        assert_eq!(
            s.positions,
            vec![Point3::new(1.5, -2.0, 3.25), Point3::new(0.0, 0.5, 1e3)]
        );
        assert!(s.normals.is_none());
        let e = parse_ply(&bytes[..bytes.len() - 3], "b.ply")
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.ply") && e.contains("ends early"), "{e}");
        let big = String::from_utf8_lossy(&bytes).replace("little", "big");
        let e = parse_ply(big.as_bytes(), "c.ply").unwrap_err().to_string();
        assert!(e.starts_with("c.ply:2:"), "{e}");
    }

    /// CGAL's `.pwn` (points with normals, as its example data ships
    /// them: `oni.pwn`) is `.xyz` text under another name.
    #[test]
    fn pwn_files_read_as_xyz() {
        let d = temp_dir("pwn");
        let path = d.join("oni.PWN");
        std::fs::write(
            &path,
            "-0.12 -0.04 -0.22 -0.51 -0.56 -0.64\n0.1 0.2 0.3 0 0 2\n",
        )
        .unwrap();
        let s = read_point_set(&path).unwrap();
        assert_eq!(s.positions[1], Point3::new(0.1, 0.2, 0.3));
        assert_eq!(s.normals.unwrap()[1], Vec3::z());
        std::fs::write(&path, "0 0 0 0 0 1\n1 0 0 0 1\n").unwrap();
        let e = read_point_set(&path).unwrap_err().to_string();
        assert!(e.contains("oni.PWN:2"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn unknown_extension_is_an_error() {
        let e = read_point_set(Path::new("points.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("points.txt") && e.contains(".xyz"), "{e}");
    }

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("op-pointsets-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A 100 000-character token is quoted cut to 80 characters, with the
    /// line number (it was echoed whole).
    #[test]
    fn long_bad_tokens_are_elided() {
        let long = "x".repeat(100_000);
        let e = parse_xyz(&format!("0 0 0\n1 2 {long}\n"), "l.xyz")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("l.xyz:2:"), "{e}");
        assert!(
            e.contains(&format!("`{}...`", "x".repeat(EXCERPT_CHARS - 3))),
            "{e}"
        );
        assert!(e.len() < 200, "{} characters", e.len());
        let e = parse_obj(&format!("v 0 0 {long}\n"), "l.obj")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("l.obj:1:") && e.len() < 200, "{e}");
        let ply = format!("ply\nformat ascii 1.0\n{long}\nend_header\n");
        let e = parse_ply(ply.as_bytes(), "l.ply").unwrap_err().to_string();
        assert!(e.starts_with("l.ply:3:") && e.len() < 200, "{e}");
        assert_eq!(excerpt("short"), "short");
        assert_eq!(excerpt(&"é".repeat(81)).chars().count(), EXCERPT_CHARS);
    }

    /// Text files that start with a UTF-8 byte-order mark read as without
    /// it (the first line was `\u{feff}0`, not a number).
    #[test]
    fn a_byte_order_mark_is_skipped() {
        let dir = temp_dir("bom");
        let body = [
            ("p.xyz", "0 0 0\n1 0 0\n0 1 0\n"),
            ("p.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
            ("p.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n"),
        ];
        for (name, text) in body {
            let path = dir.join(name);
            std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
            let s = read_point_set(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(s.positions[1], Point3::new(1.0, 0.0, 0.0), "{name}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A symlink to /dev/zero (read until 2 GB before) and a directory are
    /// refused before they are read, naming the file; a file over the
    /// limit is refused.
    #[cfg(unix)]
    #[test]
    fn only_regular_files_under_the_limit_are_read() {
        let dir = temp_dir("regular");
        let zero = dir.join("zero.xyz");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let e = read_point_set(&zero).unwrap_err().to_string();
        assert!(
            e.contains("zero.xyz") && e.contains("not a regular file (a character device)"),
            "{e}"
        );
        let sub = dir.join("d.ply");
        std::fs::create_dir(&sub).unwrap();
        let e = read_point_set(&sub).unwrap_err().to_string();
        assert!(e.contains("d.ply") && e.contains("a directory"), "{e}");
        let small = dir.join("s.xyz");
        std::fs::write(&small, "0 0 0\n").unwrap();
        assert!(matches!(
            read_regular_file(&small, 5),
            Err(InputFileError::TooLarge(6))
        ));
        assert_eq!(read_regular_file(&small, 6).unwrap().len(), 6);
        let e = InputFileError::TooLarge(6).message(5);
        assert!(e.contains("limit of 5 bytes"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A binary PLY element without properties and a huge count is
    /// skipped at once (the loop ran over the count).
    #[test]
    fn binary_ply_empty_element_with_a_huge_count_is_skipped() {
        let mut bytes = format!(
            "ply\nformat binary_little_endian 1.0\nelement empty {}\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
            usize::MAX
        )
        .into_bytes();
        for c in [1f32, 2.0, 3.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        let s = parse_ply(&bytes, "e.ply").unwrap();
        assert_eq!(s.positions, vec![Point3::new(1.0, 2.0, 3.0)]);
    }

    /// The I/O error's message is not repeated by its source.
    #[test]
    fn io_errors_do_not_repeat_the_system_message() {
        let e = read_point_set(Path::new("/nonexistent/p.xyz")).unwrap_err();
        let source = std::error::Error::source(&e).expect("a source").to_string();
        assert!(!e.to_string().contains(&source), "{e} / {source}");
        assert!(e.to_string().contains("p.xyz"), "{e}");
    }

    /// A PLY whose header declares fewer rows than its data holds is
    /// refused (not fitted on the header's count with the rest ignored),
    /// in ascii and in binary, and elements after the vertices
    /// are read, not mistaken for extra data.
    #[test]
    fn ply_data_beyond_the_header_counts_is_refused() {
        let header = |n: usize, format: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex {n}\nproperty float x\n\
                 property float y\nproperty float z\nelement face 1\n\
                 property list uchar int vertex_indices\nend_header\n"
            )
        };
        let ascii = format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", header(3, "ascii"));
        assert_eq!(
            parse_ply(ascii.as_bytes(), "a.ply")
                .unwrap()
                .positions
                .len(),
            3
        );
        let short = ascii.replace("vertex 3", "vertex 2");
        let e = parse_ply(short.as_bytes(), "a.ply")
            .unwrap_err()
            .to_string();
        assert!(e.contains("after the rows its header declares"), "{e}");
        let mut binary = header(3, "binary_little_endian").into_bytes();
        for c in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            binary.extend_from_slice(&c.to_le_bytes());
        }
        binary.push(3);
        for i in [0i32, 1, 2] {
            binary.extend_from_slice(&i.to_le_bytes());
        }
        assert_eq!(parse_ply(&binary, "b.ply").unwrap().positions.len(), 3);
        binary.extend_from_slice(&[0; 12]);
        let e = parse_ply(&binary, "b.ply").unwrap_err().to_string();
        assert!(e.contains("12 bytes of data after"), "{e}");
    }

    /// A point limit is applied from a PLY header (before the data, which
    /// here does not even exist) and from the point lines of text formats.
    #[test]
    fn the_point_limit_is_applied_before_the_points_are_read() {
        let ply = "ply\nformat binary_little_endian 1.0\nelement vertex 25000000\n\
                   property float x\nproperty float y\nproperty float z\nend_header\n";
        let e = parse_ply_at_most(ply.as_bytes(), "big.ply", 1_000_000)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("declares 25000000 points, more than the 1000000"),
            "{e}"
        );
        let dir = std::env::temp_dir().join(format!("op-pointset-limit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let xyz = dir.join("p.xyz");
        std::fs::write(&xyz, "# three points\n0 0 0\n1 0 0\n\n0 1 0\n").unwrap();
        assert_eq!(read_point_set_at_most(&xyz, 3).unwrap().positions.len(), 3);
        let e = read_point_set_at_most(&xyz, 2).unwrap_err().to_string();
        assert!(e.contains("3 point lines, more than the 2"), "{e}");
        let obj = dir.join("p.obj");
        std::fs::write(&obj, "v 0 0 0\nvn 0 0 1\nv 1 0 0\nf 1 2 1\n").unwrap();
        assert_eq!(read_point_set_at_most(&obj, 2).unwrap().positions.len(), 2);
        assert!(read_point_set_at_most(&obj, 1).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
