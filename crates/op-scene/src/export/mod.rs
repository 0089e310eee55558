//! Frame files (README "Running scenes"): what a run writes per frame, in the formats
//! asked for ([`FrameFormat`]: OBJ by default, binary PLY, VTU, USD; each a
//! [`FileFormat`] of the [`format::REGISTRY`]).
//!
//! Layout under the output directory (see [`layout`]):
//!
//! - `frames/<stem>/<stem>_00000.obj` (and `.ply`): one file per frame for
//!   each sequence ([`Sequence`]): every scene object's particles (as
//!   [`Outputs::particles`] asks), every skin `<object>_skin`, every
//!   triangulation `<object>_surface` (when [`Outputs::triangulation`] is
//!   set) and every tool `tool_<name>`. One object per file, because OBJ
//!   importers (Blender's among them) drop the loose vertices of a point
//!   cloud that shares its file with other objects; each sequence is then
//!   also what sequence loaders (Blender add-ons, Houdini, ParaView) take;
//!   `frames/<stem>/<stem>.obj.series` (`.ply.series`) lists its files
//!   with their scene times ([`series`]);
//! - `vtu/state_00000.vtu` and `vtu/state.vtu.series`: every particle
//!   with its attributes ([`vtu`]); beside them every skin, surface and
//!   tool as VTU, `vtu/<stem>_00000.vtu` and `vtu/<stem>.vtu.series`, so
//!   ParaView loads the whole scene from `vtu/` as time series;
//! - `usd/run.usda`: one file for the whole run, every sequence a prim
//!   time-sampled at the frame rate ([`usd`]), written at each checkpoint
//!   and at the end of the run ([`run_cache`]).
//!
//! Axes: scenes are z-up. OBJ files are written y-up (scene `(x, y, z)`
//! as `(x, z, -y)`, see [`obj`]), the convention of OBJ and of Blender's
//! OBJ importer, so frames import upright; PLY, VTU and USD files hold scene
//! coordinates (the USD stage says `upAxis = "Z"`) (Blender's PLY importer and ParaView take z-up as is).
//! `summary.json` names the formats, their axes and the sequences.
//!
//! Every file is written atomically (temporary file + rename,
//! [`write_atomically`]), so a file on disk is always complete.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use op_dynamics::{Real, World};
use op_modeling::Tool;

use crate::built_scene::BuiltObject;
use crate::outputs::{Outputs, ParticleOutput};
use crate::skins::{ObjectSkin, SkinTool};

pub mod file_queue;
pub mod format;
pub mod geometry;
pub mod layout;
pub mod obj;
mod obj_text;
pub mod ply;
pub mod run_cache;
pub mod series;
pub mod usd;
pub mod vtu;

/// A sized writer over a `dyn Write`, for the format crates whose writers
/// take a sized `W: Write` (obj-exporter, ply-rs-bw).
struct SizedWriter<'a>(&'a mut dyn Write);

impl Write for SizedWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

use file_queue::FileQueue;
pub use file_queue::WriteFailure;
pub use format::{FileFormat, Files, FrameFormat};
pub use geometry::{FrameMesh, SheetGap};
pub use layout::{Sequence, SequenceKind};

/// Writes `bytes_fn`'s output to `path` atomically: a temporary file in the
/// same directory, flushed and synced, then renamed over `path`. The
/// temporary file is created exclusively (`create_new`: it fails rather than
/// follow a symbolic link or reuse a file someone else made) under a name
/// no other process can predict (process id, a counter and the clock's
/// nanoseconds), and removed when anything fails.
pub fn write_atomically(
    path: &Path,
    bytes_fn: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_through_temporary(path, bytes_fn, true)
}

/// [`write_atomically`] without syncing the file to disk before the
/// rename: for the files rewritten after every frame that list others
/// (the series files, [`series`]). A process killed at any moment leaves
/// the old file or the new one, whole; only a crash of the machine can
/// lose the last versions. Syncing them doubled the files a frame waits
/// for: the demo's run took 2.1-2.4 s instead of 0.7-1.0 s.
pub fn replace_atomically(
    path: &Path,
    bytes_fn: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_through_temporary(path, bytes_fn, false)
}

/// [`write_atomically`], syncing the file before the rename when `sync`.
fn write_through_temporary(
    path: &Path,
    bytes_fn: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    sync: bool,
) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let (tmp, file) = create_temporary(dir, &name)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        bytes_fn(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        if sync {
            file.sync_all()?;
        }
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Whether `file_name` is one of [`write_atomically`]'s temporary files.
pub fn is_temporary(file_name: &str) -> bool {
    file_name.starts_with('.') && file_name.ends_with(".opsim-tmp")
}

/// A new temporary file `.{name}.{pid}-{counter}-{nanos}.opsim-tmp` in `dir`,
/// created exclusively; retried under a new name if one exists.
fn create_temporary(dir: &Path, name: &str) -> std::io::Result<(PathBuf, fs::File)> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut last = None;
    for _ in 0..16 {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let k = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(
            ".{name}.{}-{k}-{nanos}.opsim-tmp",
            std::process::id()
        ));
        match fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("cannot create a temporary file")))
}

/// What a sequence is drawn from.
#[derive(Copy, Clone, Debug)]
enum Source {
    Particles(usize),
    Skin(usize),
    Surface(usize),
    Tool(usize),
}

/// Writes a run's frames: the sequences of a scene in the chosen formats,
/// fixed when the run starts.
#[derive(Debug)]
pub struct FrameWriter {
    out: PathBuf,
    formats: Vec<FrameFormat>,
    sequences: Vec<Sequence>,
    sources: Vec<Source>,
    /// The frames written so far: number and scene time, for the series
    /// files.
    frames: Vec<(usize, Real)>,
    sheet_gap: SheetGap,
    files: FileQueue,
    /// The caches of the formats of one file per run
    /// ([`Files::Run`]), in `formats` order.
    caches: Vec<(FrameFormat, Box<dyn run_cache::RunCache>)>,
    /// The frames of the caches when their files were last handed to the
    /// writing thread.
    run_frames_written: Option<usize>,
    /// The skins written coarser than their cell size because they outgrew
    /// the polygonizer's grid: name, first frame, cell size, cell used.
    coarsened: Vec<(String, usize, Real, Real)>,
}

/// What a [`FrameWriter`] remembers of the frames it wrote (a checkpoint
/// saves it, [`crate::run::checkpoint`]): the frames listed in the series
/// files (number and time), and the skins written coarser.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WriterState {
    frames: Vec<(usize, Real)>,
    coarsened: Vec<(String, usize, Real, Real)>,
}

impl FrameWriter {
    /// What the writer remembers of the frames written so far.
    pub fn state(&self) -> WriterState {
        WriterState {
            frames: self.frames.clone(),
            coarsened: self.coarsened.clone(),
        }
    }

    /// Puts back what [`FrameWriter::state`] returned, into a writer of the
    /// same formats (the checkpoint's run hash covers them), after frame
    /// `last` (a checkpoint's): the files of one per run are read back up
    /// to that frame ([`run_cache::RunCache::resume`]).
    pub fn restore(&mut self, state: WriterState, last: usize) -> Result<(), String> {
        if state.frames.windows(2).any(|w| w[0].0 >= w[1].0) {
            return Err("the checkpoint's frames are out of order".into());
        }
        for (f, cache) in &mut self.caches {
            cache.resume(&layout::run_path(&self.out, *f), last)?;
        }
        self.frames = state.frames;
        self.coarsened = state.coarsened;
        Ok(())
    }

    /// Waits until every frame file handed to the writer is on disk, the
    /// files of one per run written with every frame so far (the writing
    /// thread starts again with the next frame).
    ///
    /// # Errors
    ///
    /// The first file that could not be written.
    pub fn flush(&mut self) -> Result<(), WriteFailure> {
        let runs = self.write_runs();
        let files = self.files.finish();
        runs.and(files)
    }

    /// Hands the file of each format of one per run, with the frames so
    /// far, to the writing thread, unless it was handed with as many
    /// frames already (a checkpoint after the last frame, then the end).
    fn write_runs(&mut self) -> Result<(), WriteFailure> {
        let frames = self.caches.first().map(|c| c.1.frames());
        if frames == self.run_frames_written {
            return Ok(());
        }
        self.run_frames_written = frames;
        for (f, cache) in &self.caches {
            let path = layout::run_path(&self.out, *f);
            let frame = cache.frames().saturating_sub(1);
            let mut bytes = Vec::new();
            if let Err(error) = cache.encode(&mut bytes) {
                return Err(WriteFailure { frame, path, error });
            }
            self.files.push(frame, path, bytes)?;
        }
        Ok(())
    }

    /// Warnings about what was written: each skin written coarser than its
    /// cell size because it outgrew the polygonizer's grid (its particles
    /// flung apart), from which frame and at which cell size.
    pub fn warnings(&self) -> Vec<String> {
        self.coarsened
            .iter()
            .map(|(name, k, h, used)| {
                format!(
                    "skin {name:?} outgrew its polygonization grid from frame {k}: written with \
                     cells of {} instead of {} (its particles spread too far apart)",
                    crate::error::short(*used),
                    crate::error::short(*h)
                )
            })
            .collect()
    }

    /// The writer of a scene's frames under `out` in `formats` (duplicates
    /// ignored), `frame_rate` frames per unit of scene time: unless [`Outputs::particles`] is `None`, a particle
    /// sequence per object; a skin sequence per skin; a surface sequence
    /// per object when [`Outputs::triangulation`] is set; a tool sequence
    /// per tool when any of these is written; in that order.
    pub fn new(
        out: &Path,
        formats: &[FrameFormat],
        objects: &[BuiltObject],
        skins: &[ObjectSkin],
        tools: &[Tool],
        outputs: &Outputs,
        frame_rate: Real,
    ) -> Self {
        let mut named = Vec::new();
        let particles = outputs.particles != ParticleOutput::None;
        if particles {
            for (k, o) in objects.iter().enumerate() {
                named.push((
                    o.name.clone(),
                    SequenceKind::Particles,
                    Source::Particles(k),
                ));
            }
        }
        // An object's skin is written whenever it has one
        // (`BuiltScene::stages`' `polygonize`), with or without particles.
        for (k, s) in skins.iter().enumerate() {
            named.push((s.name.clone(), SequenceKind::Skin, Source::Skin(k)));
        }
        if outputs.triangulation {
            for (k, o) in objects.iter().enumerate() {
                named.push((
                    geometry::surface_name(o),
                    SequenceKind::Surface,
                    Source::Surface(k),
                ));
            }
        }
        if particles || outputs.triangulation || !skins.is_empty() {
            for (k, t) in tools.iter().enumerate() {
                named.push((
                    geometry::tool_name(k, t),
                    SequenceKind::Tool,
                    Source::Tool(k),
                ));
            }
        }
        let sources = named.iter().map(|n| n.2).collect();
        let sequences = layout::sequences(named.into_iter().map(|(n, kind, _)| (n, kind)));
        let mut formats = formats.to_vec();
        formats.sort();
        formats.dedup();
        let caches = formats
            .iter()
            .filter_map(|f| Some((*f, f.format().run_cache(&sequences, frame_rate)?)))
            .collect();
        FrameWriter {
            out: out.to_path_buf(),
            frames: Vec::new(),
            formats,
            sequences,
            sources,
            sheet_gap: SheetGap::default(),
            files: FileQueue::default(),
            caches,
            run_frames_written: None,
            coarsened: Vec::new(),
        }
    }

    /// Sets the gaps the surfaces span between particles that no longer
    /// attract ([`geometry::SheetGap`]; the scene's
    /// [`crate::BuiltScene::sheet_gap`]). Default: none.
    pub fn with_sheet_gap(mut self, gap: SheetGap) -> Self {
        self.sheet_gap = gap;
        self
    }

    /// The sequences, in the order they are written.
    pub fn sequences(&self) -> &[Sequence] {
        &self.sequences
    }

    /// The formats written, in order.
    pub fn formats(&self) -> &[FrameFormat] {
        &self.formats
    }

    /// The formats of one layout, in order.
    fn formats_of(&self, files: Files) -> impl Iterator<Item = FrameFormat> + '_ {
        self.formats
            .iter()
            .copied()
            .filter(move |f| f.files() == files)
    }

    /// Whether a frame writes any file.
    pub fn writes_anything(&self) -> bool {
        self.formats_of(Files::State).next().is_some()
            || !self.caches.is_empty()
            || (!self.sequences.is_empty() && self.formats_of(Files::PerSequence).next().is_some())
    }

    /// Whether sequence files are written (some per-sequence format).
    pub fn writes_sequences(&self) -> bool {
        self.formats_of(Files::PerSequence).next().is_some()
    }

    /// The series files of the state formats, relative to the output
    /// directory (`vtu/state.vtu.series`).
    pub fn series_files(&self) -> Vec<PathBuf> {
        self.formats_of(Files::State)
            .map(|f| layout::series_path(Path::new(""), f))
            .collect()
    }

    /// Every series file the run writes, relative to the output directory,
    /// in writing order ([`series`]): per sequence, one per format that
    /// writes it (`frames/<stem>/<stem>.ply.series`,
    /// `vtu/<stem>.vtu.series`), then the state formats'
    /// (`vtu/state.vtu.series`).
    pub fn all_series_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = self
            .sequences
            .iter()
            .flat_map(|seq| {
                self.formats
                    .iter()
                    .filter(|&&f| self.writes(seq, f))
                    .map(|&f| seq.series_path(Path::new(""), f))
            })
            .collect();
        files.extend(self.series_files());
        files
    }

    /// Whether `format` writes the files of `seq`: every per-sequence
    /// format does; a state format that
    /// [`FileFormat::writes_meshes_with_state`] writes the skins, surfaces
    /// and tools (its state files hold the particles).
    fn writes(&self, seq: &Sequence, format: FrameFormat) -> bool {
        writes(seq, format)
    }

    /// The files of sequence `seq` in `format` written so far with their
    /// times, named relative to its series file.
    fn listed(&self, seq: Option<&Sequence>, format: FrameFormat) -> Vec<(String, Real)> {
        self.frames
            .iter()
            .map(|&(k, time)| {
                let path = match seq {
                    Some(seq) => seq.path(Path::new(""), k, format),
                    None => layout::state_path(Path::new(""), k, format),
                };
                let name = path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                (name, time)
            })
            .collect()
    }

    /// The files of the formats of one per run, relative to the output
    /// directory (`usd/run.usda`), with their formats.
    pub fn run_files(&self) -> Vec<(FrameFormat, PathBuf)> {
        self.caches
            .iter()
            .map(|(f, _)| (*f, layout::run_path(Path::new(""), *f)))
            .collect()
    }

    /// The folders the frames go to (created by the runner).
    pub fn folders(&self) -> Vec<PathBuf> {
        let mut dirs: Vec<PathBuf> = if self.writes_sequences() {
            self.sequences.iter().map(|s| s.folder(&self.out)).collect()
        } else {
            Vec::new()
        };
        dirs.extend(
            self.formats_of(Files::State)
                .chain(self.formats_of(Files::Run))
                .map(|f| layout::state_folder(&self.out, f)),
        );
        dirs
    }

    /// Writes frame `k` at scene time `time`: every sequence's file in each
    /// format that writes it (skins polygonized at their current pose,
    /// deformed where they touch another skin and clipped where they press
    /// on an obstacle tool), each followed by its series file listing the
    /// frames written so far, then the VTU state and its series file. The
    /// files are
    /// encoded here and written by the writer's own thread
    /// ([`file_queue`]) while the run goes on; [`FrameWriter::finish`]
    /// waits for them. A failure (here, or of an earlier frame's file on
    /// that thread) leaves the files written before it complete.
    #[allow(clippy::too_many_arguments)]
    pub fn write_frame(
        &mut self,
        k: usize,
        time: Real,
        world: &World,
        objects: &[BuiltObject],
        skins: &[ObjectSkin],
        skin_tools: &[SkinTool],
        tools: &[Tool],
        outputs: &Outputs,
    ) -> Result<(), WriteFailure> {
        let failure = |path: PathBuf, error| WriteFailure {
            frame: k,
            path,
            error,
        };
        // Frame `k` (again, on a resumed run) replaces what was listed
        // from it on.
        self.frames.retain(|&(j, _)| j < k);
        self.frames.push((k, time));
        // Each sequence's geometry and encoded files, made in parallel (the
        // sequences are independent; the skins polygonize in parallel
        // themselves), then handed to the writer and the caches in the
        // sequences' order: the same files and bytes at any thread count.
        let caching = !self.caches.is_empty();
        // The file a skin's failure names when no frame file has it.
        let cache_file = self
            .caches
            .first()
            .map(|(f, _)| layout::run_path(&self.out, *f));
        let inputs = FrameInputs {
            world,
            objects,
            skins,
            skin_tools,
            tools,
            outputs,
        };
        // Side by side only when there is work to share: a skin to
        // polygonize or a large world. A small frame's sequences cost less
        // than waking a thread, which then spins while the frame writer
        // needs the core (`cookbook/ball_bounce`, 800 frames of 177
        // particles: 28,052 `sched_yield` at 2 threads, `strace -c -f`).
        let parallel =
            !skins.is_empty() || world.particles().len() >= op_dynamics::MIN_PARALLEL_LEN;
        let prepared: Vec<Result<Option<PreparedSequence>, WriteFailure>> = {
            use rayon::prelude::*;
            let (out, formats, sheet_gap) = (&self.out, &self.formats, &self.sheet_gap);
            let n = self.sequences.len();
            self.sequences
                .par_iter()
                .with_min_len(if parallel { 1 } else { n.max(1) })
                .zip(&self.sources)
                .map(|(seq, source)| {
                    let cache = cache_file.as_deref();
                    prepare_sequence(seq, *source, k, out, formats, sheet_gap, cache, &inputs)
                })
                .collect()
        };
        let mut coarsened = Vec::new();
        // The sequences' geometry for the caches of one file per run.
        let mut cached = Vec::new();
        for ((seq, source), prepared) in self.sequences.iter().zip(&self.sources).zip(prepared) {
            if let (Source::Particles(o), true) = (*source, caching) {
                cached.push(run_cache::SequenceFrame::Particles {
                    world,
                    object: &objects[o],
                    width: 2.0 * outputs.glyph_size * objects[o].rest_spacing,
                });
            }
            let Some(p) = prepared? else {
                continue;
            };
            if let Some((name, cell, export)) = p.coarsened {
                coarsened.push((name, k, cell, export));
            }
            for (f, path, pieces) in p.files {
                self.files.push_pieces(k, path, pieces)?;
                // After the frame's file: on disk, the series lists only
                // files already there.
                let series = seq.series_path(&self.out, f);
                let mut bytes = Vec::new();
                f.format()
                    .encode_series(&self.listed(Some(seq), f), &mut bytes)
                    .map_err(|e| failure(series.clone(), e))?;
                self.files.push_index(k, series, bytes)?;
            }
            if let Some(mesh) = p.mesh {
                cached.push(run_cache::SequenceFrame::Mesh(mesh));
            }
        }
        for (f, cache) in &mut self.caches {
            cache
                .add_frame(k, &cached)
                .map_err(|e| failure(layout::run_path(&self.out, *f), e))?;
        }
        for c in coarsened {
            if !self.coarsened.iter().any(|d| d.0 == c.0) {
                self.coarsened.push(c);
            }
        }
        for f in self.formats.clone() {
            if f.files() != Files::State {
                continue;
            }
            let path = layout::state_path(&self.out, k, f);
            let title = format!("opsim frame {k}, t = {time}");
            let mut bytes = Vec::new();
            f.format()
                .encode_state(world, objects, &title, &mut bytes)
                .map_err(|e| failure(path.clone(), e))?;
            self.files.push(k, path, bytes)?;
            let series = layout::series_path(&self.out, f);
            let mut bytes = Vec::new();
            f.format()
                .encode_series(&self.listed(None, f), &mut bytes)
                .map_err(|e| failure(series.clone(), e))?;
            self.files.push_index(k, series, bytes)?;
        }
        Ok(())
    }

    /// Writes the files of one per run with every frame so far and waits
    /// until every frame file handed to the writer's thread is on disk.
    ///
    /// # Errors
    ///
    /// The first file that could not be written (the frames before its
    /// frame are complete).
    pub fn finish(&mut self) -> Result<(), WriteFailure> {
        let runs = self.write_runs();
        let files = self.files.finish();
        runs.and(files)
    }
}

/// Whether `format` writes sequence `seq` with the frames: every
/// per-sequence format, and the state formats that carry meshes for the
/// sequences that are not particles.
fn writes(seq: &Sequence, format: FrameFormat) -> bool {
    match format.files() {
        Files::PerSequence => true,
        Files::State => {
            format.format().writes_meshes_with_state() && seq.kind != SequenceKind::Particles
        }
        Files::Run => false,
    }
}

/// What a frame is made from ([`FrameWriter::write_frame`]'s arguments).
struct FrameInputs<'a> {
    world: &'a World,
    objects: &'a [BuiltObject],
    skins: &'a [ObjectSkin],
    skin_tools: &'a [SkinTool],
    tools: &'a [Tool],
    outputs: &'a Outputs,
}

/// One sequence's part of a frame, made on any thread.
struct PreparedSequence {
    /// The frame file of each format that writes the sequence, encoded.
    files: Vec<(FrameFormat, PathBuf, Vec<Vec<u8>>)>,
    /// The geometry for the caches of one file per run (meshes only).
    mesh: Option<FrameMesh>,
    /// A skin exported coarser than its cell size: its name, cell size and
    /// export cell size.
    coarsened: Option<(String, Real, Real)>,
}

/// Sequence `seq` (from `source`) of frame `k`: its geometry and its frame
/// files encoded in each of `formats` that writes it (`None` when nothing
/// is written and no cache wants its mesh); `cache_file` is the first file
/// of one per run when the run writes one (it then wants the meshes).
#[allow(clippy::too_many_arguments)]
fn prepare_sequence(
    seq: &Sequence,
    source: Source,
    k: usize,
    out: &Path,
    formats: &[FrameFormat],
    sheet_gap: &SheetGap,
    cache_file: Option<&Path>,
    inputs: &FrameInputs,
) -> Result<Option<PreparedSequence>, WriteFailure> {
    let failure = |path: PathBuf, error| WriteFailure {
        frame: k,
        path,
        error,
    };
    let FrameInputs {
        world,
        objects,
        skins,
        skin_tools,
        tools,
        outputs,
    } = *inputs;
    let formats: Vec<FrameFormat> = formats
        .iter()
        .copied()
        .filter(|&f| writes(seq, f))
        .collect();
    let meshes_cached = cache_file.is_some() && !matches!(source, Source::Particles(_));
    if formats.is_empty() && !meshes_cached {
        return Ok(None);
    }
    // The file a skin's failure names: its first frame file, or the run
    // file of the first cache.
    let first = match (formats.first(), cache_file) {
        (Some(&f), _) => seq.path(out, k, f),
        (None, Some(run)) => run.to_path_buf(),
        (None, None) => PathBuf::new(),
    };
    let mut coarsened = None;
    let mesh = match source {
        Source::Particles(o) => geometry::object_geometry(world, &objects[o], outputs),
        Source::Surface(o) => geometry::surface_geometry(world, &objects[o], outputs, *sheet_gap),
        Source::Tool(t) => geometry::tool_geometry(t, &tools[t], world.time()),
        Source::Skin(s) => {
            let skin = &skins[s];
            let h = skin.export_cell_size();
            if h > skin.cell_size {
                coarsened = Some((skin.name.clone(), skin.cell_size, h));
            }
            let mesh = skin
                .mesh_in(skins, skin_tools, world.time())
                .map_err(|e| failure(first, std::io::Error::other(e)))?;
            geometry::mesh_geometry(&skin.name, mesh)
        }
    };
    let mut files = Vec::with_capacity(formats.len());
    for f in formats {
        let path = seq.path(out, k, f);
        let pieces = f
            .format()
            .encode_mesh_pieces(&mesh)
            .map_err(|e| failure(path.clone(), e))?;
        files.push((f, path, pieces));
    }
    Ok(Some(PreparedSequence {
        files,
        mesh: meshes_cached.then_some(mesh),
        coarsened,
    }))
}
