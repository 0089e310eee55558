//! What `summary.json` holds: the run's figures, per object, and the
//! frame files it wrote.

use op_dynamics::Real;
use serde::Serialize;

use crate::built_scene::BuiltScene;
use crate::export::{FrameFormat, FrameWriter, Sequence};
use crate::skins::ContactStats;

use super::RunError;

/// Per-object figures of a run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ObjectSummary {
    /// Object name.
    pub name: String,
    /// Number of particles at the end of the run (created ones included).
    pub particles: usize,
    /// Rest shape error at the last frame: RMS distance to the rest shape
    /// after the best rigid alignment (Kabsch), divided by the object's
    /// mean rest spacing. Measured over the object's original particles
    /// (particles added by the creation rules have no rest position; see
    /// [`crate::creation`]).
    pub rest_shape_error_final: Real,
    /// Largest rest shape error over the frames.
    pub rest_shape_error_max: Real,
    /// Particles the creation rules added to the object over the run.
    pub created: usize,
    /// Connected components of the object's particles at the last frame,
    /// two particles joined when closer than its material's interaction
    /// range (see [`crate::health`]); absent when the material has none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pieces: Option<usize>,
    /// Largest bond stretch seen: the largest ratio of current to rest
    /// distance over the object's rest neighbour pairs, over the frames
    /// (see [`crate::health`]).
    pub bond_stretch_max: Real,
    /// Highest temperature of any of its particles over the frames, when
    /// the scene has `world.heat` (seed 000 §6, §8).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temperature_max: Option<Real>,
}

/// What `summary.json` holds.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// Steps taken.
    pub steps: u64,
    /// Scene time reached (from frame 0, after the settle phase).
    pub sim_time: Real,
    /// Duration of the settle phase simulated before frame 0 (its steps
    /// count in `steps`).
    pub settle: Real,
    /// Wall-clock seconds of the run, the scene's making included
    /// ([`BuiltScene::setup_seconds`]).
    pub wall_seconds: f64,
    /// True when the run stopped because it diverged.
    pub diverged: bool,
    /// The divergence message, when it diverged (its step and time are the
    /// world's, settle phase included).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub divergence: Option<String>,
    /// What a user should know before trusting the frames: an object that
    /// broke into pieces, left the scene's bounds, a passive scene that
    /// gained energy, a step above the estimated stable step (see
    /// [`crate::health`]). Also printed by `opsim run`. A finding the
    /// scene's header expects is under `expected` instead.
    pub warnings: Vec<String>,
    /// The findings the scene's header expects (`// expect-warning: TEXT`,
    /// [`crate::Scene::expected_warnings`]), such as the tear of a tearing
    /// scene: what the scene is meant to do, so `opsim run` prints them as
    /// `expected:` lines, not as warnings. A breakup accepted by `opsim run
    /// --allow-breakup` alone stays a warning.
    pub expected: Vec<String>,
    /// Why the run stopped early other than by diverging (an output that
    /// could not be written, a skin that could not be polygonized), when
    /// it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Seconds spent per stage over the run: the scene's making (`build`,
    /// `estimate`: [`BuiltScene::setup_seconds`]), the world's own stages
    /// (integrate, neighbours, reorder, check, heat, bonds, plasticity,
    /// erase: those it has), the scene's stages ([`crate::stages`]: fit,
    /// creation, contact, skin), then the runner's `prepare` (output
    /// folders, checks before the first step), `measure` (energies, rest
    /// shape errors, health) and `export` (frames, with their polygonized
    /// skins and triangulations). `opsim run --profile` prints them.
    pub stages: std::collections::BTreeMap<String, f64>,
    /// Frames written.
    pub frames: usize,
    /// Frames per unit of scene time (the scene's `world.frame_rate`):
    /// frame `k` is at scene time `k / frame_rate`.
    pub frame_rate: Real,
    /// The scene's up direction in scene coordinates: `outputs.up` when
    /// given, else against gravity, or `+z` in a scene without gravity.
    /// Scenes are z-up by convention.
    pub up: [Real; 3],
    /// The direction the scene's pictures look along (`outputs.view`), in
    /// scene coordinates, when the scene gives one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<[Real; 3]>,
    /// The frame files: formats, axis conventions and sequences.
    pub files: FrameFiles,
    /// Rayon threads used.
    pub threads: usize,
    /// What the scene computes: [`BuiltScene::stages`] (the world's
    /// kernel, terms and external actions, then skin, polygonize, contact
    /// when used).
    pub enabled: Vec<String>,
    /// Contact figures, for scenes with implicit contact (two or more
    /// skinned objects; see [`crate::skins`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactStats>,
    /// Bonds broken over the run (settle phase included), for scenes with
    /// bonded materials (op-dynamics `bonds`; seed 000 fig. 12c tearing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bonds_broken: Option<u64>,
    /// What `linear_damping: "Critical"` resolved to, when the scene asked
    /// for it ([`crate::damping::CriticalDamping`]: the slowest mode, the
    /// damping, settle phase and duration run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_damping: Option<crate::damping::CriticalDamping>,
    /// Per-object figures.
    pub objects: Vec<ObjectSummary>,
}

/// The frame files of a run, as `summary.json` describes them for the
/// tools that read them (the Blender add-on, `opsim render`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FrameFiles {
    /// Formats written, e.g. `["obj", "ply"]`.
    pub formats: Vec<FrameFormat>,
    /// Axis convention per format (by extension): `"y_up"` for OBJ (scene
    /// `(x, y, z)` written as `(x, z, -y)`), `"z_up"` (scene coordinates)
    /// for PLY, VTU and USD (`usda`).
    pub axes: std::collections::BTreeMap<String, String>,
    /// One sequence per scene object's particles, skin, triangulation and
    /// tool: frame `k` of format `ext` is
    /// `frames/<stem>/<stem>_<k:05>.<ext>`.
    pub sequences: Vec<Sequence>,
    /// The particle state files, when VTU is written:
    /// `vtu/state_<k:05>.vtu`, listed in `vtu/state.vtu.series`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vtu_series: Option<String>,
    /// Every series file (ParaView's file-series JSON: a sequence's files
    /// with their scene times, `crate::export::series`), relative to the
    /// output directory: `frames/<stem>/<stem>.<ext>.series` per sequence
    /// and OBJ or PLY format, `vtu/<stem>.vtu.series` per skin, surface
    /// and tool when VTU is written, then `vtu/state.vtu.series`.
    pub series: Vec<String>,
    /// The USD cache, when USD is written ([`crate::export::usd`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub usd: Option<UsdFile>,
}

/// The USD cache of a run, as `summary.json` describes it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UsdFile {
    /// The file, relative to the output directory: `usd/run.usda`.
    pub file: String,
    /// Its default prim, `/Run`, parent of every sequence's prim.
    pub default_prim: String,
    /// The prim of each sequence (every scene object's particles, skin,
    /// triangulation and tool), in the order of the sequences.
    pub prims: Vec<UsdPrim>,
}

/// One sequence's prim in the USD cache.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UsdPrim {
    /// The sequence's name (the OBJ `o` name).
    pub name: String,
    /// What it shows.
    pub kind: crate::export::SequenceKind,
    /// The prim's path: `/Run/<name>` (a `Points` prim for particles, a
    /// `Mesh` otherwise).
    pub path: String,
}

/// The frame files a writer wrote (the summary's `files`).
pub(super) fn frame_files(writer: &FrameWriter) -> FrameFiles {
    FrameFiles {
        formats: writer.formats().to_vec(),
        axes: writer
            .formats()
            .iter()
            .map(|f| (f.extension().to_string(), f.axes().to_string()))
            .collect(),
        sequences: if writer.writes_sequences() {
            writer.sequences().to_vec()
        } else {
            Vec::new()
        },
        vtu_series: writer
            .series_files()
            .first()
            .map(|p| p.to_string_lossy().replace('\\', "/")),
        series: writer
            .all_series_files()
            .iter()
            .map(|p| p.to_string_lossy().replace('\\', "/"))
            .collect(),
        usd: writer.run_files().first().map(|(_, p)| {
            let root = format!("/{}", crate::export::usd::ROOT);
            let names = crate::export::usd::prim_names(writer.sequences());
            UsdFile {
                file: p.to_string_lossy().replace('\\', "/"),
                prims: writer
                    .sequences()
                    .iter()
                    .zip(names)
                    .map(|(s, n)| UsdPrim {
                        name: s.name.clone(),
                        kind: s.kind,
                        path: format!("{root}/{n}"),
                    })
                    .collect(),
                default_prim: root,
            }
        }),
    }
}

/// The scene's up direction: against gravity, `+z` without gravity.
pub(super) fn up_direction(scene: &BuiltScene) -> [Real; 3] {
    let g = scene.world.params().external.gravity();
    match (-g).try_normalize(0.0) {
        // `+ 0.0` turns the `-0.0` of a negated zero into `0`.
        Some(u) if u.iter().all(|c| c.is_finite()) => u.map(|c| c + 0.0).into(),
        _ => [0.0, 0.0, 1.0],
    }
}

/// An error and its sources, `: `-separated (one line for the summary).
pub(super) fn error_chain(e: &RunError) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}
