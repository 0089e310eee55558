//! Where a run's frame files go: one sequence of files per thing of the
//! scene, `frames/<stem>/<stem>_00000.obj` (and `.ply`), and the particle
//! state `vtu/state_00000.vtu` with its ParaView series file
//! `vtu/state.vtu.series`.

use std::path::{Path, PathBuf};

use serde::Serialize;

/// A frame file format, chosen with `opsim run --format obj,ply,vtu`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameFormat {
    /// Wavefront OBJ, one file per sequence and frame, y-up (scene `z`
    /// written as OBJ `y`, scene `y` as OBJ `-z`): what Blender's OBJ
    /// importer (forward `-Z`, up `Y`) and other OBJ readers expect.
    Obj,
    /// Binary little-endian PLY, one file per sequence and frame, in scene
    /// coordinates (z-up, as Blender's PLY importer takes them): vertices
    /// with normals (`x y z nx ny nz`, float), `face` (`vertex_indices`)
    /// and `edge` (`vertex1 vertex2`) elements.
    Ply,
    /// VTK XML unstructured grid of every particle (one vertex cell each)
    /// with per-particle attributes, one file per frame, in scene
    /// coordinates, listed with their times in `vtu/state.vtu.series`
    /// (ParaView opens the series as a time series).
    Vtu,
}

impl FrameFormat {
    /// Every format, in the order files are written.
    pub const ALL: [FrameFormat; 3] = [FrameFormat::Obj, FrameFormat::Ply, FrameFormat::Vtu];

    /// The file extension (also the name on the command line).
    pub fn extension(self) -> &'static str {
        match self {
            FrameFormat::Obj => "obj",
            FrameFormat::Ply => "ply",
            FrameFormat::Vtu => "vtu",
        }
    }

    /// The format named `name` (`obj`, `ply` or `vtu`, any case).
    pub fn from_name(name: &str) -> Option<FrameFormat> {
        Self::ALL
            .into_iter()
            .find(|f| f.extension().eq_ignore_ascii_case(name.trim()))
    }

    /// The axis convention of its files: `y_up` (OBJ) or `z_up`.
    pub fn axes(self) -> &'static str {
        match self {
            FrameFormat::Obj => "y_up",
            FrameFormat::Ply | FrameFormat::Vtu => "z_up",
        }
    }
}

/// What a sequence shows.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SequenceKind {
    /// An object's particles (points, discs or axes).
    Particles,
    /// An object's polygonized skin.
    Skin,
    /// An object's particle triangulation.
    Surface,
    /// A tool's surface.
    Tool,
}

/// One sequence of frame files: one thing of the scene over the frames.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Sequence {
    /// Object name in the files (the OBJ `o` name): the scene object's
    /// name, `<object>_skin`, `<object>_surface` or `tool_<name>`.
    pub name: String,
    /// What it shows.
    pub kind: SequenceKind,
    /// The file-system-safe name of its folder and files (ASCII letters,
    /// digits, `-`, `_` and `.`, not starting with `.`; unique in the run,
    /// ignoring case).
    pub stem: String,
}

impl Sequence {
    /// The file of frame `k` in `format` under the output directory `out`:
    /// `out/frames/<stem>/<stem>_<k:05>.<ext>`.
    pub fn path(&self, out: &Path, k: usize, format: FrameFormat) -> PathBuf {
        self.folder(out)
            .join(format!("{}_{k:05}.{}", self.stem, format.extension()))
    }

    /// The folder of its files: `out/frames/<stem>`.
    pub fn folder(&self, out: &Path) -> PathBuf {
        out.join("frames").join(&self.stem)
    }
}

/// Gives each name a file-system-safe stem, unique ignoring case: every
/// character other than ASCII letters, digits, `-`, `_` and `.` becomes
/// `_`, a leading `.` becomes `_`, and a stem already taken gets `-2`,
/// `-3`, ... appended.
pub fn sequences(named: impl IntoIterator<Item = (String, SequenceKind)>) -> Vec<Sequence> {
    let mut taken = std::collections::HashSet::new();
    let mut out = Vec::new();
    for (name, kind) in named {
        let mut base: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        if base.is_empty() || base.starts_with('.') {
            base.insert(0, '_');
        }
        let mut stem = base.clone();
        let mut k = 1;
        while !taken.insert(stem.to_ascii_lowercase()) {
            k += 1;
            stem = format!("{base}-{k}");
        }
        out.push(Sequence { name, kind, stem });
    }
    out
}

/// The VTU file of frame `k`: `out/vtu/state_<k:05>.vtu`.
pub fn vtu_path(out: &Path, k: usize) -> PathBuf {
    out.join("vtu").join(format!("state_{k:05}.vtu"))
}

/// The ParaView series file listing the VTU frames and their times:
/// `out/vtu/state.vtu.series`.
pub fn vtu_series_path(out: &Path) -> PathBuf {
    out.join("vtu").join("state.vtu.series")
}

/// Whether `name` is a frame file opsim writes in a sequence folder whose
/// stem is `stem`: `<stem>_<digits>.obj` or `.ply`.
pub fn is_sequence_file(name: &str, stem: &str) -> bool {
    let Some(rest) = name.strip_prefix(stem).and_then(|r| r.strip_prefix('_')) else {
        return false;
    };
    let Some((digits, ext)) = rest.rsplit_once('.') else {
        return false;
    };
    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) && matches!(ext, "obj" | "ply")
}

/// Whether `name` is a VTU frame or series file opsim writes.
pub fn is_vtu_file(name: &str) -> bool {
    name == "state.vtu.series"
        || name
            .strip_prefix("state_")
            .and_then(|r| r.strip_suffix(".vtu"))
            .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_are_safe_and_unique() {
        let s = sequences([
            ("sheet".to_string(), SequenceKind::Particles),
            ("Sheet".to_string(), SequenceKind::Particles),
            ("a b/c".to_string(), SequenceKind::Particles),
            ("..".to_string(), SequenceKind::Particles),
            ("été".to_string(), SequenceKind::Tool),
        ]);
        let stems: Vec<&str> = s.iter().map(|q| q.stem.as_str()).collect();
        assert_eq!(stems, ["sheet", "Sheet-2", "a_b_c", "_..", "_t_"]);
        assert_eq!(
            s[0].path(Path::new("o"), 7, FrameFormat::Ply),
            Path::new("o/frames/sheet/sheet_00007.ply")
        );
    }

    #[test]
    fn file_names() {
        assert!(is_sequence_file("sheet_00012.obj", "sheet"));
        assert!(is_sequence_file("sheet_00012.ply", "sheet"));
        assert!(!is_sequence_file("sheet_skin_00012.obj", "sheet"));
        assert!(!is_sequence_file("sheet_.obj", "sheet"));
        assert!(!is_sequence_file("notes.txt", "sheet"));
        assert!(is_vtu_file("state_00003.vtu"));
        assert!(is_vtu_file("state.vtu.series"));
        assert!(!is_vtu_file("state_x.vtu"));
        assert_eq!(FrameFormat::from_name(" PLY"), Some(FrameFormat::Ply));
        assert_eq!(FrameFormat::from_name("stl"), None);
    }
}
