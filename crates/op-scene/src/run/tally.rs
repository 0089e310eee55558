//! What a run accumulates over its frames, and the summary made from it.

use std::collections::BTreeMap;
use std::time::Instant;

use op_dynamics::Real;

use crate::built_scene::BuiltScene;
use crate::error::short;
use crate::export::FrameWriter;
use crate::health::{Health, ObjectFindings, ENERGY_GAIN_WARNING};

use super::checkpoint::Carried;
use super::energy_watch::EnergyWatch;
use super::metrics::Metrics;
use super::summary::{error_chain, frame_files, up_direction, ObjectSummary, Summary};
use super::{io, rest_shape_error, RunError, RUNNER_STAGES};

/// One frame to take: its index and time, the run's wall seconds so far,
/// where it goes.
pub(super) struct Frame<'a> {
    pub(super) k: usize,
    pub(super) t: Real,
    pub(super) wall: f64,
    pub(super) writer: &'a mut FrameWriter,
    pub(super) metrics: Option<&'a mut Metrics>,
}

/// What a run accumulates over its frames: per-object rest-shape errors and
/// temperatures, frames written, the stage timings of the runner, and how
/// it ended.
#[derive(serde::Serialize, serde::Deserialize)]
pub(super) struct Tally {
    pub(super) max_err: Vec<Real>,
    pub(super) last_err: Vec<Real>,
    /// The world has heat: track each object's hottest particle.
    pub(super) heat: bool,
    pub(super) hottest: Vec<Real>,
    pub(super) written: usize,
    pub(super) measure_seconds: f64,
    pub(super) export_seconds: f64,
    /// Checkpoints written ([`checkpoint`](super::checkpoint)).
    pub(super) checkpoint_seconds: f64,
    /// The output folders prepared and the scene checked before its first
    /// step.
    pub(super) prepare_seconds: f64,
    /// The run settles the scene before frame 0.
    pub(super) settles: bool,
    pub(super) divergence: Option<String>,
    #[serde(skip)]
    pub(super) failure: Option<RunError>,
}

impl Tally {
    pub(super) fn new(scene: &BuiltScene) -> Self {
        let n = scene.objects.len();
        Tally {
            max_err: vec![0.0; n],
            last_err: vec![0.0; n],
            heat: scene.world.params().heat.is_some(),
            hottest: vec![Real::NEG_INFINITY; n],
            written: 0,
            measure_seconds: 0.0,
            export_seconds: 0.0,
            checkpoint_seconds: 0.0,
            prepare_seconds: 0.0,
            settles: false,
            divergence: None,
            failure: None,
        }
    }

    /// Advances to the frame, checks it, measures and writes it. Returns
    /// whether the run goes on.
    pub(super) fn frame(
        &mut self,
        scene: &mut BuiltScene,
        health: &mut Health,
        watch: &mut EnergyWatch,
        frame: Frame<'_>,
    ) -> bool {
        // Frame 0 poses the skins on the settled particles.
        let t = if frame.k == 0 {
            scene.world.time()
        } else {
            frame.t
        };
        if let Err(d) = scene.advance_to(t) {
            // A stage's failure ends the run as a divergence does (exit 3):
            // the state it left cannot be continued.
            self.divergence = Some(d.to_string());
            return false;
        }
        let measuring = Instant::now();
        let d = scene.world.diagnostics();
        // Frame 0 is the end of the settle phase: what went wrong there
        // went wrong while settling.
        let when = if frame.k == 0 && self.settles {
            "while settling: "
        } else {
            ""
        };
        if let Some(d) = watch
            .check(scene, &d)
            .err()
            .or_else(|| health.observe(scene))
            .or_else(|| crate::health::unwritable(scene))
        {
            self.divergence = Some(format!("{when}{d}"));
            return false;
        }
        self.measure(scene);
        self.measure_seconds += measuring.elapsed().as_secs_f64();
        let exporting = Instant::now();
        if frame.writer.writes_anything() {
            if let Err(f) = frame.writer.write_frame(
                frame.k,
                scene.scene_time(),
                &scene.world,
                &scene.objects,
                &scene.skins,
                &scene.skin_tools,
                &scene.tools,
                &scene.outputs,
            ) {
                self.write_failed(f);
                return false;
            }
        }
        self.written += 1;
        self.export_seconds += exporting.elapsed().as_secs_f64();
        if let Some(m) = frame.metrics {
            let kinetic = d.kinetic_translational + d.kinetic_rotational;
            if let Err(e) = m.push(format_args!(
                "{},{},{kinetic},{},{},{},{},{}",
                frame.k,
                scene.scene_time(),
                d.potential,
                d.total,
                d.oscillation,
                d.max_speed,
                frame.wall
            )) {
                self.failure = Some(e);
                return false;
            }
        }
        true
    }

    /// The health findings at the end of the run: its warnings (energy
    /// gained without input, the health report's, accepted breakups) go
    /// into `warnings`, and a breakup the scene does not expect ends the
    /// run as a divergence. After a divergence the state is the blown-up
    /// one: its pieces and escape say nothing the divergence does not.
    pub(super) fn conclude(
        &mut self,
        scene: &BuiltScene,
        health: &Health,
        watch: &EnergyWatch,
        warnings: &mut Vec<String>,
    ) -> Vec<ObjectFindings> {
        if watch.gain_seen > ENERGY_GAIN_WARNING {
            warnings.push(format!(
                "the scene gained energy without input: the total energy rose {} times its \
                 energy scale above the lowest earlier frame (a step too large for the \
                 stiffness, or particles started on top of each other)",
                short(watch.gain_seen)
            ));
        }
        let (findings, health_warnings, breakups) = health.finish(scene);
        if self.divergence.is_some() {
            return findings;
        }
        warnings.extend(health_warnings);
        let (accepted, unexpected): (Vec<String>, Vec<String>) =
            breakups.into_iter().partition(|b| scene.accepts_breakup(b));
        warnings.extend(accepted);
        if let Some(first) = unexpected.first() {
            self.divergence = Some(format!(
                "{first}; the scene does not expect it (a scene that tears on purpose says so \
                 in its header, `// expect-warning: {}`; `opsim run --allow-breakup` accepts \
                 any breakup)",
                first.split(" (").next().unwrap_or(first)
            ));
        }
        findings
    }

    /// Each object's rest-shape error and hottest particle at this frame.
    fn measure(&mut self, scene: &BuiltScene) {
        for (o, obj) in scene.objects.iter().enumerate() {
            let e = rest_shape_error(scene, obj);
            self.last_err[o] = e;
            self.max_err[o] = Real::max(self.max_err[o], e);
            if self.heat {
                let p = scene.world.particles();
                self.hottest[o] = obj
                    .all_ids()
                    .filter_map(|id| p.slot_of(id))
                    .map(|s| p.temperatures()[s])
                    .fold(self.hottest[o], Real::max);
            }
        }
    }

    /// A frame file that could not be written ends the run: the frames
    /// before its frame are the ones written.
    pub(super) fn write_failed(&mut self, f: crate::export::WriteFailure) {
        self.written = self.written.min(f.frame);
        self.failure.get_or_insert(io(&f.path)(f.error));
    }

    /// The run's summary (`summary.json`).
    pub(super) fn summary(
        &self,
        scene: &BuiltScene,
        writer: &FrameWriter,
        findings: Vec<ObjectFindings>,
        warnings: Vec<String>,
        (wall, carried): (f64, &Carried),
    ) -> Summary {
        let (expected, warnings) = warnings.into_iter().partition(|w| scene.expects(w));
        Summary {
            scene: scene.name.clone(),
            steps: scene.world.steps(),
            sim_time: scene.scene_time(),
            settle: if scene.settled { scene.settle } else { 0.0 },
            wall_seconds: carried.wall_seconds
                + carried.setup_seconds
                + wall
                + scene.setup_seconds.iter().map(|(_, t)| t).sum::<f64>(),
            diverged: self.divergence.is_some(),
            divergence: self.divergence.clone(),
            warnings,
            expected,
            failure: self.failure.as_ref().map(error_chain),
            stages: self.stage_table(scene, carried),
            frames: self.written,
            frame_rate: scene.frame_rate,
            up: scene.outputs.up.unwrap_or_else(|| up_direction(scene)),
            view: scene.outputs.view,
            files: frame_files(writer),
            threads: rayon::current_num_threads(),
            enabled: scene.stages(),
            contact: scene.has_contact().then_some(scene.contact),
            bonds_broken: scene.world.bonds().map(|b| b.broken()),
            critical_damping: scene.critical_damping.clone(),
            objects: self.objects(scene, findings),
        }
    }

    /// Seconds per stage so far (the summary's `stages`): the scene's and
    /// the runner's, plus those `carried` over from the run this one
    /// resumed.
    pub(super) fn stage_table(
        &self,
        scene: &BuiltScene,
        carried: &Carried,
    ) -> BTreeMap<String, f64> {
        let mut table = carried.stages.clone();
        let now = scene.timings().into_iter().chain(
            // `build` and `estimate` come with the scene's timings.
            RUNNER_STAGES[..4].iter().map(|s| s.to_string()).zip([
                self.prepare_seconds,
                self.measure_seconds,
                self.export_seconds,
                self.checkpoint_seconds,
            ]),
        );
        for (name, seconds) in now {
            if name == "checkpoint" && seconds == 0.0 {
                continue;
            }
            *table.entry(name).or_insert(0.0) += seconds;
        }
        table
    }

    /// A copy of the tally for a checkpoint: everything but a failure
    /// (checkpoints are taken only while the run goes well).
    pub(super) fn snapshot(&self) -> Tally {
        Tally {
            max_err: self.max_err.clone(),
            last_err: self.last_err.clone(),
            heat: self.heat,
            hottest: self.hottest.clone(),
            written: self.written,
            measure_seconds: self.measure_seconds,
            export_seconds: self.export_seconds,
            checkpoint_seconds: self.checkpoint_seconds,
            prepare_seconds: self.prepare_seconds,
            settles: self.settles,
            divergence: self.divergence.clone(),
            failure: None,
        }
    }

    /// The per-object figures of the summary.
    fn objects(&self, scene: &BuiltScene, findings: Vec<ObjectFindings>) -> Vec<ObjectSummary> {
        scene
            .objects
            .iter()
            .zip(findings)
            .enumerate()
            .map(|(o, (obj, found))| ObjectSummary {
                name: obj.name.clone(),
                particles: obj
                    .all_ids()
                    .filter(|&id| scene.world.particles().slot_of(id).is_some())
                    .count(),
                rest_shape_error_final: self.last_err[o],
                rest_shape_error_max: self.max_err[o],
                created: obj.created.len(),
                pieces: found.pieces,
                bond_stretch_max: found.bond_stretch_max,
                temperature_max: (self.heat && self.hottest[o].is_finite())
                    .then_some(self.hottest[o]),
            })
            .collect()
    }
}
