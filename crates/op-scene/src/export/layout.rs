//! Where a run's frame files go: one sequence of files per thing of the
//! scene, `frames/<stem>/<stem>_00000.obj` (and `.ply`) with the series
//! file `frames/<stem>/<stem>.obj.series` (`.ply.series`), and the particle
//! state `vtu/state_00000.vtu` with its ParaView series file
//! `vtu/state.vtu.series`, beside the skins, surfaces and tools as VTU,
//! `vtu/<stem>_00000.vtu` with `vtu/<stem>.vtu.series` (the layouts of
//! [`super::format::Files`]; the series files: [`super::series`]).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::format::{Files, FrameFormat};

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
    /// `out/frames/<stem>/<stem>_<k:05>.<ext>`, or in the state folder of a
    /// [`Files::State`] format, `out/<name>/<stem>_<k:05>.<ext>`.
    pub fn path(&self, out: &Path, k: usize, format: FrameFormat) -> PathBuf {
        self.folder_in(out, format)
            .join(format!("{}_{k:05}.{}", self.stem, format.extension()))
    }

    /// The series file listing its files in `format` with their times
    /// ([`super::series`]): `out/frames/<stem>/<stem>.<ext>.series`, or
    /// `out/<name>/<stem>.<ext>.series` for a [`Files::State`] format.
    pub fn series_path(&self, out: &Path, format: FrameFormat) -> PathBuf {
        self.folder_in(out, format)
            .join(format!("{}.{}.series", self.stem, format.extension()))
    }

    /// The folder of its files in `format`.
    fn folder_in(&self, out: &Path, format: FrameFormat) -> PathBuf {
        if format.files() == Files::State {
            state_folder(out, format)
        } else {
            self.folder(out)
        }
    }

    /// The folder of its files: `out/frames/<stem>`.
    pub fn folder(&self, out: &Path) -> PathBuf {
        out.join("frames").join(&self.stem)
    }
}

/// Longest stem, in bytes: a frame file's name (`<stem>_<frame>.<ext>`)
/// and the temporary name it is written under (`.<file>.<pid>-<n>-<ns>.opsim-tmp`,
/// [`super::write_atomically`]) stay far below the 255 bytes file systems
/// allow in one path component, whatever the object's name.
pub const MAX_STEM: usize = 96;

/// Gives each name a file-system-safe stem, unique ignoring case: every
/// character other than ASCII letters, digits, `-`, `_` and `.` becomes
/// `_`, a leading `.` becomes `_`, the stem is cut to [`MAX_STEM`] bytes,
/// and a stem already taken gets `-2`, `-3`, ... appended. The name itself
/// is kept whole (in `summary.json` `files.sequences`).
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
        // ASCII only: cutting at a byte is cutting at a character.
        base.truncate(MAX_STEM);
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

/// The folder of a state format's files ([`super::format::Files::State`]):
/// `out/<name>`.
pub fn state_folder(out: &Path, format: FrameFormat) -> PathBuf {
    out.join(format.name())
}

/// A state format's file of frame `k`: `out/<name>/state_<k:05>.<name>`
/// (`out/vtu/state_00003.vtu`).
pub fn state_path(out: &Path, k: usize, format: FrameFormat) -> PathBuf {
    state_folder(out, format).join(format!("state_{k:05}.{}", format.extension()))
}

/// A state format's series file listing its frames and their times:
/// `out/<name>/state.<name>.series` (`out/vtu/state.vtu.series`, which
/// ParaView opens as a time series).
pub fn series_path(out: &Path, format: FrameFormat) -> PathBuf {
    state_folder(out, format).join(format!("state.{}.series", format.extension()))
}

/// A run format's one file ([`super::format::Files::Run`]):
/// `out/<name>/run.<extension>` (`out/usd/run.usda`), in the same folder as
/// a state format's files ([`state_folder`]).
pub fn run_path(out: &Path, format: FrameFormat) -> PathBuf {
    state_folder(out, format).join(format!("run.{}", format.extension()))
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
            s[0].path(Path::new("o"), 7, FrameFormat::PLY),
            Path::new("o/frames/sheet/sheet_00007.ply")
        );
        assert_eq!(
            s[0].series_path(Path::new("o"), FrameFormat::PLY),
            Path::new("o/frames/sheet/sheet.ply.series")
        );
        assert_eq!(
            s[0].path(Path::new("o"), 7, FrameFormat::VTU),
            Path::new("o/vtu/sheet_00007.vtu")
        );
        assert_eq!(
            s[0].series_path(Path::new("o"), FrameFormat::VTU),
            Path::new("o/vtu/sheet.vtu.series")
        );
    }

    /// A name of thousands of characters gives a stem that fits a file
    /// name with room for the frame number and the temporary suffix; two
    /// long names alike in their first bytes stay apart.
    #[test]
    fn long_names_give_short_unique_stems() {
        let long = "a".repeat(5000);
        let s = sequences([
            (long.clone(), SequenceKind::Particles),
            (format!("{long}b"), SequenceKind::Particles),
        ]);
        assert_eq!(s[0].stem.len(), MAX_STEM);
        assert_eq!(s[1].stem, format!("{}-2", &s[0].stem));
        assert_eq!(s[0].name, long, "the name is kept whole");
        let file = s[1].path(Path::new(""), 999_999, FrameFormat::PLY);
        let file = file.file_name().unwrap().to_string_lossy().len();
        // `.{file}.{pid}-{counter}-{nanos}.opsim-tmp`: at most 54 more.
        assert!(file + 54 < 255, "{file}");
    }
}
