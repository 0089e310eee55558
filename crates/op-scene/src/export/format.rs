//! Frame file formats: one module per format (`obj.rs`, `ply.rs`,
//! `vtu.rs`, `usd.rs`) behind the [`FileFormat`] trait, and one registry of them
//! ([`REGISTRY`]). `opsim run --format NAME` and [`FrameFormat::named`] look
//! a format up there by name; the frame writer asks it for its file
//! layout ([`Files`]) and its bytes; the output directory's clean-up asks
//! it which files are its own ([`FileFormat::owns`]).
//!
//! Adding a format: write `export/<name>.rs` with a unit struct
//! implementing [`FileFormat`] and add it to [`REGISTRY`].
//!
//! Every sequence of frame files comes with a series file listing its
//! files and their scene times ([`super::series`], ParaView's file-series
//! JSON): `frames/<stem>/<stem>.<extension>.series` for the
//! [`Files::PerSequence`] formats, `<name>/state.<extension>.series` and
//! `<name>/<stem>.<extension>.series` for the [`Files::State`] formats.

use std::io::Write;

use op_dynamics::{Real, World};

use super::geometry::FrameMesh;
use super::layout::Sequence;
use super::run_cache::RunCache;
use crate::built_scene::BuiltObject;

/// How a format lays out its files under the output directory.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Files {
    /// One file per sequence (each object's particles, skin, surface, each
    /// tool) and frame: `frames/<stem>/<stem>_<k:05>.<extension>`, encoded by
    /// [`FileFormat::encode_mesh`].
    PerSequence,
    /// One file per frame holding every particle with its attributes,
    /// `<name>/state_<k:05>.<extension>` (encoded by
    /// [`FileFormat::encode_state`]), listed with their times in the
    /// series file `<name>/state.<extension>.series` (ParaView's time series,
    /// [`FileFormat::encode_series`]). A format that
    /// [`FileFormat::writes_meshes_with_state`] also writes there every
    /// skin, surface and tool, `<name>/<stem>_<k:05>.<extension>` (encoded
    /// by [`FileFormat::encode_mesh`]), each with its series file
    /// `<name>/<stem>.<extension>.series`.
    State,
    /// One file for the whole run, `<name>/run.<extension>`, holding every
    /// sequence over the frames (time-sampled): the format's
    /// [`RunCache`] ([`FileFormat::run_cache`]) accumulates the frames and
    /// encodes the file, written whenever a checkpoint is and at the end of
    /// the run ([`super::run_cache`]).
    Run,
}

/// A frame file format; see the [module docs](self).
pub trait FileFormat: Sync + std::fmt::Debug {
    /// Its name on the command line and in `summary.json` (lower case).
    fn name(&self) -> &'static str;

    /// The extension of its files. Default: its name.
    fn extension(&self) -> &'static str {
        self.name()
    }

    /// The axis convention of its files: `y_up` or `z_up` (scenes are
    /// z-up).
    fn axes(&self) -> &'static str;

    /// Its file layout.
    fn files(&self) -> Files;

    /// Whether a [`Files::State`] format also writes the meshes of the
    /// skins, surfaces and tools (not the particles: its state files hold
    /// them) in its state folder, one sequence each with its series file.
    /// Default: no.
    fn writes_meshes_with_state(&self) -> bool {
        false
    }

    /// About how many bytes [`FileFormat::encode_mesh`] writes for `mesh`
    /// (the frame's buffer is reserved at once: a file of hundreds of
    /// megabytes grown by doubling is copied and its pages cleared again
    /// at every step). Default: 0 (unknown).
    fn mesh_size_hint(&self, _mesh: &FrameMesh) -> usize {
        0
    }

    /// Encodes one sequence's frame ([`Files::PerSequence`] formats, and
    /// the meshes of [`FileFormat::writes_meshes_with_state`]).
    fn encode_mesh(&self, _mesh: &FrameMesh, _out: &mut dyn Write) -> std::io::Result<()> {
        Err(std::io::Error::other(format!(
            "{} writes no per-sequence files",
            self.name()
        )))
    }

    /// [`FileFormat::encode_mesh`]'s bytes as pieces the frame writer
    /// writes one after the other: a format that encodes its file in
    /// pieces in parallel (OBJ) hands them over as they are, instead of
    /// copying them into one more buffer of the file's size, whose fresh
    /// pages the kernel clears. Default: one piece, reserved at
    /// [`FileFormat::mesh_size_hint`].
    fn encode_mesh_pieces(&self, mesh: &FrameMesh) -> std::io::Result<Vec<Vec<u8>>> {
        let mut bytes = Vec::with_capacity(self.mesh_size_hint(mesh));
        self.encode_mesh(mesh, &mut bytes)?;
        Ok(vec![bytes])
    }

    /// Encodes the particle state of a frame ([`Files::State`] formats).
    fn encode_state(
        &self,
        _world: &World,
        _objects: &[BuiltObject],
        _title: &str,
        _out: &mut dyn Write,
    ) -> std::io::Result<()> {
        Err(std::io::Error::other(format!(
            "{} writes no state files",
            self.name()
        )))
    }

    /// Encodes the series file of one sequence's files written so far
    /// (file name relative to the series file, scene time). Default:
    /// ParaView's file-series JSON ([`super::series::write`]), which
    /// ParaView opens as a time series whatever reader the files take.
    fn encode_series(&self, files: &[(String, Real)], out: &mut dyn Write) -> std::io::Result<()> {
        super::series::write(files, out)
    }

    /// The cache of a [`Files::Run`] format for a run of `sequences` at
    /// `frame_rate` frames per unit of scene time. Default: none.
    fn run_cache(&self, _sequences: &[Sequence], _frame_rate: Real) -> Option<Box<dyn RunCache>> {
        None
    }

    /// Whether `file_name`, found in the folder of its files (a sequence
    /// folder of stem `stem`, or its state or run folder), is one it writes: the
    /// run removes those before it starts, and leaves every other file
    /// alone. In a sequence folder: `<stem>_<digits>.<extension>` and
    /// `<stem>.<extension>.series`; in the state folder the same with the
    /// stem `state`, or any stem when the format
    /// [`FileFormat::writes_meshes_with_state`].
    fn owns(&self, file_name: &str, stem: &str) -> bool {
        let ext = self.extension();
        let numbered = |rest: &str| {
            rest.strip_suffix(ext)
                .and_then(|r| r.strip_suffix('.'))
                .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        };
        let series = |stem: &str| {
            file_name
                .strip_prefix(stem)
                .and_then(|r| r.strip_prefix('.'))
                .and_then(|r| r.strip_prefix(ext))
                == Some(".series")
        };
        let of_stem = |stem: &str| {
            series(stem)
                || file_name
                    .strip_prefix(stem)
                    .and_then(|r| r.strip_prefix('_'))
                    .is_some_and(numbered)
        };
        match self.files() {
            Files::State if self.writes_meshes_with_state() => {
                file_name
                    .strip_suffix(".series")
                    .and_then(|r| r.strip_suffix(ext))
                    .and_then(|r| r.strip_suffix('.'))
                    .is_some_and(|s| !s.is_empty())
                    || file_name
                        .rsplit_once('_')
                        .is_some_and(|(s, rest)| !s.is_empty() && numbered(rest))
            }
            Files::State => of_stem("state"),
            Files::PerSequence => of_stem(stem),
            Files::Run => file_name == format!("run.{}", self.extension()),
        }
    }
}

/// Every format, in the order a frame's files are written.
pub static REGISTRY: &[&dyn FileFormat] = &[
    &super::obj::ObjFormat,
    &super::ply::PlyFormat,
    &super::vtu::VtuFormat,
    &super::usd::UsdFormat,
];

/// A registered format, as chosen for a run: compared, ordered and
/// serialized by its place and name in the [`REGISTRY`].
#[derive(Copy, Clone, Debug)]
pub struct FrameFormat(&'static dyn FileFormat);

impl FrameFormat {
    /// Wavefront OBJ ([`super::obj`]).
    pub const OBJ: FrameFormat = FrameFormat(&super::obj::ObjFormat);
    /// Binary PLY ([`super::ply`]).
    pub const PLY: FrameFormat = FrameFormat(&super::ply::PlyFormat);
    /// VTK XML unstructured grids of the particles ([`super::vtu`]).
    pub const VTU: FrameFormat = FrameFormat(&super::vtu::VtuFormat);
    /// One time-sampled USD file of the whole run ([`super::usd`]).
    pub const USD: FrameFormat = FrameFormat(&super::usd::UsdFormat);

    /// Every registered format, in the order files are written.
    pub fn all() -> impl Iterator<Item = FrameFormat> {
        REGISTRY.iter().map(|f| FrameFormat(*f))
    }

    /// The format registered as `name` (any case, surrounding blanks
    /// ignored).
    ///
    /// # Errors
    ///
    /// An unknown name, with the registered ones.
    pub fn named(name: &str) -> Result<FrameFormat, String> {
        Self::all()
            .find(|f| f.name().eq_ignore_ascii_case(name.trim()))
            .ok_or_else(|| {
                let known: Vec<&str> = Self::all().map(|f| f.name()).collect();
                format!(
                    "unknown frame format {name:?}: the formats are {} (comma-separated for several)",
                    known.join(", ")
                )
            })
    }

    /// The format's implementation.
    pub fn format(self) -> &'static dyn FileFormat {
        self.0
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        self.0.name()
    }

    /// Its file extension.
    pub fn extension(self) -> &'static str {
        self.0.extension()
    }

    /// The axis convention of its files.
    pub fn axes(self) -> &'static str {
        self.0.axes()
    }

    /// Its file layout.
    pub fn files(self) -> Files {
        self.0.files()
    }

    /// Place in the registry.
    fn rank(self) -> usize {
        REGISTRY
            .iter()
            .position(|f| f.name() == self.name())
            .unwrap_or(usize::MAX)
    }
}

impl PartialEq for FrameFormat {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for FrameFormat {}

impl PartialOrd for FrameFormat {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for FrameFormat {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.rank().cmp(&other.rank())
    }
}

impl std::hash::Hash for FrameFormat {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state);
    }
}

impl serde::Serialize for FrameFormat {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_found_by_name_and_own_their_files() {
        assert_eq!(FrameFormat::named(" PLY"), Ok(FrameFormat::PLY));
        let e = FrameFormat::named("stl").unwrap_err();
        assert!(e.contains("obj, ply, vtu, usd"), "{e}");
        let names: Vec<&str> = FrameFormat::all().map(|f| f.name()).collect();
        let mut sorted = names.clone();
        sorted.dedup();
        assert_eq!(names, sorted, "names are unique");
        let (obj, ply, vtu) = (
            super::super::obj::ObjFormat,
            super::super::ply::PlyFormat,
            super::super::vtu::VtuFormat,
        );
        assert!(obj.owns("sheet_00012.obj", "sheet"));
        assert!(!obj.owns("sheet_00012.ply", "sheet"));
        assert!(ply.owns("sheet_00012.ply", "sheet"));
        assert!(!obj.owns("sheet_skin_00012.obj", "sheet"));
        assert!(!obj.owns("sheet_.obj", "sheet"));
        assert!(!obj.owns("notes.txt", "sheet"));
        assert!(ply.owns("sheet.ply.series", "sheet"));
        assert!(!ply.owns("sheet.obj.series", "sheet"));
        assert!(!ply.owns("sheet_skin.ply.series", "sheet"));
        assert!(vtu.owns("state_00003.vtu", ""));
        assert!(vtu.owns("state.vtu.series", ""));
        assert!(!vtu.owns("state_x.vtu", ""));
        assert!(vtu.owns("sheet_skin_00003.vtu", ""));
        assert!(vtu.owns("tool_box.vtu.series", ""));
        assert!(!vtu.owns(".vtu.series", ""));
        assert!(!vtu.owns("notes.txt", ""));
        assert!(FrameFormat::OBJ < FrameFormat::VTU);
        let usd = super::super::usd::UsdFormat;
        assert!(usd.owns("run.usda", ""));
        assert!(!usd.owns("run.usdc", ""));
        assert!(!usd.owns("notes.usda", ""));
    }
}
