//! A scene turned into a world: what the runner needs and nothing more.

use std::path::PathBuf;

use op_dynamics::driver::{DriveError, Driver, Phase};
use op_dynamics::{Point3, Real, World};
use op_modeling::Tool;

use crate::creation::CreationState;
use crate::export::geometry::SheetGap;
use crate::outputs::Outputs;
use crate::skins::{ContactStats, ObjectSkin, SkinTool};
use crate::stages::SceneState;

/// One object of a built scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct BuiltObject {
    /// Object name (unique in the scene; the OBJ object name).
    pub name: String,
    /// Stable particle ids of the object, in generation order.
    pub ids: Vec<u32>,
    /// Rest positions (in `ids` order): the reference of the rest shape
    /// error. The positions at build time, replaced by the settled ones
    /// when [`BuiltScene::settle`] runs a settle phase.
    pub rest: Vec<Point3>,
    /// Mean nearest-neighbour distance of `rest`: the `r0` that divides
    /// the rest shape error (docs/model.md §6).
    pub rest_spacing: Real,
    /// Ids of the particles the creation rules added to the object, in
    /// creation order (see [`crate::creation`]); they have no rest
    /// position and do not count in the rest shape error.
    pub created: Vec<u32>,
}

impl BuiltScene {
    /// The gaps the exported surfaces span between particles that no
    /// longer attract: those the stretching rule leaves as sheet (seed 000
    /// §7; its `d_min` and `d_max` times its `r0`) when the scene creates
    /// particles by stretching, none otherwise
    /// ([`crate::export::geometry::SheetGap`]).
    pub fn sheet_gap(&self) -> SheetGap {
        self.creation
            .as_ref()
            .and_then(|c| {
                c.params.stretching.as_ref().map(|s| SheetGap {
                    d_min: s.d_min * c.params.r0,
                    d_max: s.d_max * c.params.r0,
                })
            })
            .unwrap_or_default()
    }
}

impl BuiltObject {
    /// Every particle id of the object: the original ones, then the
    /// created ones.
    pub fn all_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.ids.iter().chain(&self.created).copied()
    }
}

/// A validated scene built into a world containing only what it enables.
pub struct BuiltScene {
    /// Scene name (summary `scene` field, default output folder name).
    pub(crate) name: String,
    /// The file it came from, if any.
    pub(crate) source: Option<PathBuf>,
    /// The world, ready to step.
    pub(crate) world: World,
    /// The objects, in scene order.
    pub(crate) objects: Vec<BuiltObject>,
    /// Simulated duration (after the settle phase).
    pub(crate) duration: Real,
    /// Duration of the settle phase run before frame 0 (`world.settle`;
    /// the force windows start counting at its end).
    pub(crate) settle: Real,
    /// True once the settle phase ran (or when there is none): see
    /// [`BuiltScene::settle`].
    pub(crate) settled: bool,
    /// Frames written per unit of simulated time.
    pub(crate) frame_rate: Real,
    /// What to write.
    pub(crate) outputs: Outputs,
    /// Runaway-energy threshold: the run is declared diverged when the
    /// kinetic energy exceeds `energy_growth` times the initial energy
    /// scale (|kinetic| + |potential| at t = 0, at least 1e-12 per
    /// particle). Default 1e6; infinity disables the check.
    pub(crate) energy_growth: Real,
    /// Explosion threshold: a particle this many scene sizes beyond the
    /// scene's bounds ends the run as diverged (see [`crate::health`]).
    pub(crate) extent_growth: Real,
    /// Warnings known before the run starts (a step above the estimated
    /// stable step, see [`crate::stability`]); the runner puts them first
    /// in the summary's `warnings`.
    pub(crate) step_warnings: Vec<String>,
    /// Energy-gain threshold of passive scenes (no force window, zero
    /// gravity, no contact): the run is declared diverged when a frame's
    /// total energy exceeds the lowest earlier one by more than
    /// `energy_gain` times the initial energy scale. Infinity (the
    /// default) disables the check.
    pub(crate) energy_gain: Real,
    /// The implicit skins of the skinned objects, in scene order (empty
    /// when no object has a skin: nothing of op-implicit is built).
    pub(crate) skins: Vec<ObjectSkin>,
    /// Every tool of the scene, in scene order (drawn in the frames as
    /// `tool_<name>`; the world and [`BuiltScene::skin_tools`] hold the
    /// ones that act).
    pub(crate) tools: Vec<Tool>,
    /// Obstacle tools met by skins (empty when no skinned object meets an
    /// obstacle).
    pub(crate) skin_tools: Vec<SkinTool>,
    /// Contact figures accumulated by [`BuiltScene::advance_to`].
    pub(crate) contact: ContactStats,
    /// The creation rules, when the scene has some (see
    /// [`crate::creation`]).
    pub(crate) creation: Option<CreationState>,
    /// The driver of the scene's stages ([`crate::stages`]): only those
    /// the scene uses.
    pub(crate) driver: Driver<SceneState>,
    /// Wall seconds spent making the scene before its first step, by
    /// part: `build` (validation, particles, world, skins, tools:
    /// [`crate::Scene::build`]), then `estimate` (the stable-step estimate
    /// of [`crate::Scene::build_for_run`]) when it ran; `damping` first
    /// when `linear_damping: "Critical"` was resolved ([`crate::damping`]).
    /// The runner counts them in the run's wall time and its stage table.
    pub(crate) setup_seconds: Vec<(String, f64)>,
    /// The scene's expected warnings ([`crate::Scene::expected_warnings`]).
    pub(crate) expected_warnings: Vec<String>,
    /// Every breakup is accepted ([`BuiltScene::accept_breakup`]).
    pub(crate) breakup_accepted: bool,
    /// The stable-step estimate, when [`crate::Scene::build_for_run`]
    /// made one.
    pub(crate) step_estimate: Option<crate::stability::StepEstimate>,
    /// Hash of the scene as built (its every setting, after any change
    /// made in code), which a checkpoint records so that `--resume`
    /// refuses another scene ([`crate::run::checkpoint`]).
    pub(crate) inputs: u64,
    /// What `linear_damping: "Critical"` resolved to, when the scene asked
    /// for it ([`crate::damping`]).
    pub(crate) critical_damping: Option<crate::damping::CriticalDamping>,
}

impl BuiltScene {
    /// What `linear_damping: "Critical"` resolved to ([`crate::damping`]:
    /// the slowest mode, the damping, settle phase and duration this scene
    /// runs with), when the scene asked for it.
    pub fn critical_damping(&self) -> Option<&crate::damping::CriticalDamping> {
        self.critical_damping.as_ref()
    }

    /// Records what the rule resolved to and the seconds it took (a
    /// `damping` part of [`BuiltScene::setup_seconds`]), when it ran.
    pub(crate) fn set_critical_damping(
        &mut self,
        critical: Option<crate::damping::CriticalDamping>,
        seconds: f64,
    ) {
        if critical.is_some() {
            self.setup_seconds.insert(0, ("damping".into(), seconds));
        }
        self.critical_damping = critical;
    }
}

/// Reading the built scene: what it holds, as built and as it runs.
impl BuiltScene {
    /// Scene name (summary `scene` field, default output folder name).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file it came from, if any.
    pub fn source(&self) -> Option<&std::path::Path> {
        self.source.as_deref()
    }

    /// The world, ready to step.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to step or edit it directly (particles, tools, stages);
    /// [`BuiltScene::advance_to`] runs the scene's own stages as well.
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The objects, in scene order.
    pub fn objects(&self) -> &[BuiltObject] {
        &self.objects
    }

    /// Simulated duration (after the settle phase).
    pub fn duration(&self) -> Real {
        self.duration
    }

    /// Duration of the settle phase run before frame 0 (`world.settle`;
    /// the force windows start counting at its end).
    pub fn settle_duration(&self) -> Real {
        self.settle
    }

    /// True once the settle phase ran (or when there is none): see
    /// [`BuiltScene::settle`].
    pub fn is_settled(&self) -> bool {
        self.settled
    }

    /// Frames written per unit of simulated time.
    pub fn frame_rate(&self) -> Real {
        self.frame_rate
    }

    /// Sets the frames written per unit of simulated time (> 0).
    pub fn set_frame_rate(&mut self, frame_rate: Real) {
        self.frame_rate = frame_rate;
    }

    /// What to write.
    pub fn outputs(&self) -> &Outputs {
        &self.outputs
    }

    /// What to write, to change it before a run.
    pub fn outputs_mut(&mut self) -> &mut Outputs {
        &mut self.outputs
    }

    /// Runaway-energy threshold: the run is declared diverged when the
    /// kinetic energy exceeds this many times the energy scale
    /// (`world.divergence.energy_growth`).
    pub fn energy_growth(&self) -> Real {
        self.energy_growth
    }

    /// Energy-gain threshold of passive scenes
    /// (`world.divergence.energy_gain`; infinity: off).
    pub fn energy_gain(&self) -> Real {
        self.energy_gain
    }

    /// Explosion threshold in scene sizes (`world.divergence.extent_growth`,
    /// see [`crate::health`]).
    pub fn extent_growth(&self) -> Real {
        self.extent_growth
    }

    /// Warnings known before the run starts (a step above the estimated
    /// stable step, see [`crate::stability`]); the runner puts them first
    /// in the summary's `warnings`.
    pub fn step_warnings(&self) -> &[String] {
        &self.step_warnings
    }

    /// The implicit skins of the skinned objects, in scene order (empty
    /// when no object has a skin).
    pub fn skins(&self) -> &[ObjectSkin] {
        &self.skins
    }

    /// Every tool of the scene, in scene order (drawn in the frames as
    /// `tool_<name>`).
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }

    /// Obstacle tools met by skins (empty when no skinned object meets an
    /// obstacle).
    pub fn skin_tools(&self) -> &[SkinTool] {
        &self.skin_tools
    }

    /// Contact figures accumulated by [`BuiltScene::advance_to`].
    pub fn contact(&self) -> &ContactStats {
        &self.contact
    }

    /// The creation rules, when the scene has some (see
    /// [`crate::creation`]).
    pub fn creation(&self) -> Option<&CreationState> {
        self.creation.as_ref()
    }

    /// The stable-step estimate ([`crate::stability`]), when
    /// [`crate::Scene::build_for_run`] made one.
    pub fn step_estimate(&self) -> Option<&crate::stability::StepEstimate> {
        self.step_estimate.as_ref()
    }

    /// Wall seconds spent making the scene before its first step, by part
    /// (`build`, then `estimate` when it ran).
    pub fn setup_seconds(&self) -> &[(String, f64)] {
        &self.setup_seconds
    }

    /// Accepts that objects break into pieces in this run (`opsim run
    /// --allow-breakup`): a breakup is then a warning in the summary, not
    /// a divergence.
    pub fn accept_breakup(&mut self) {
        self.breakup_accepted = true;
    }

    /// Whether the run accepts the breakup warning `warning`: every
    /// breakup is accepted ([`BuiltScene::accept_breakup`]), or the scene
    /// expects a warning its message begins with.
    pub fn accepts_breakup(&self, warning: &str) -> bool {
        self.breakup_accepted || self.expects(warning)
    }

    /// Whether the scene's header expects `warning`: one of its
    /// `// expect-warning: TEXT` lines begins the message
    /// ([`crate::Scene::expected_warnings`]). The run reports such a
    /// finding under `expected`, not as a warning.
    pub fn expects(&self, warning: &str) -> bool {
        self.expected_warnings
            .iter()
            .any(|e| warning.starts_with(e))
    }
}

impl BuiltScene {
    /// Runs the settle phase once (the runner calls this before frame 0):
    /// advances the scene to world time [`BuiltScene::settle`] through its
    /// driver, as [`BuiltScene::advance_to`] does, so every stage acts
    /// while settling (tools, skin contact, creation; no force window acts
    /// before its end), then takes the settled positions as each object's
    /// rest shape and recomputes its rest spacing. Does nothing when there
    /// is no settle phase or it already ran.
    ///
    /// # Errors
    ///
    /// The divergence or a stage's failure while settling (the rest shapes
    /// are then left as built).
    pub fn settle(&mut self) -> Result<(), DriveError> {
        if self.settled {
            return Ok(());
        }
        self.advance_to(self.settle)?;
        self.settled = true;
        let p = self.world.particles();
        for o in &mut self.objects {
            // Eraser tools may have removed particles while settling: the
            // reference holds the survivors.
            o.ids.retain(|&id| p.slot_of(id).is_some());
            o.rest = o
                .ids
                .iter()
                .filter_map(|&id| p.slot_of(id).map(|s| p.positions()[s]))
                .collect();
            // Particles cannot coincide after a finite, non-divergent settle
            // phase unless the material lets them; keep the built spacing then.
            if let Ok(r0) = crate::builder::rest_spacing(&o.rest, Some(o.rest_spacing)) {
                o.rest_spacing = r0;
            }
        }
        Ok(())
    }

    /// What the scene computes ([`stage_names`]): the world's stages
    /// ([`World::enabled`]) and its features' ([`crate::features`]) with
    /// every tool's role (an obstacle that meets
    /// skins acts in the contact stage, not in the world, and is listed
    /// all the same), followed by `skin` (skins are posed) and `polygonize`
    /// (skins are written in the frames, whatever [`Outputs::particles`]
    /// is) when some object has a skin, and `contact` when at least two
    /// have or an obstacle meets one (implicit contact).
    pub fn stages(&self) -> Vec<String> {
        stage_names(
            self.enabled(),
            self.tools.iter().map(|t| t.params().role.name()),
            !self.skins.is_empty(),
            self.has_contact(),
            self.creation.as_ref().map(|c| c.fit.is_some()),
            self.outputs.triangulation,
        )
    }

    /// What the world evaluates ([`World::enabled`]), then the scene's
    /// features, the driver's [`Phase::Step`] stages ([`crate::features`]).
    pub(crate) fn enabled(&self) -> Vec<String> {
        let mut enabled = self.world.enabled();
        let features = self.driver.names_of(Phase::Step);
        enabled.extend(features.into_iter().map(String::from));
        enabled
    }

    /// Whether nothing feeds energy into the scene or changes its energy
    /// function: no force window, zero gravity, no tool, no contact, no
    /// heat, no creation, no bonds, no plastic material and no spin term
    /// (a torque without a potential, seed 000 eq. 14-15), and no feature
    /// that may add energy ([`crate::features`]). Only such a scene is
    /// checked for energy gain.
    pub fn is_passive(&self) -> bool {
        let w = &self.world;
        let e = &w.params().external;
        e.forces.is_empty()
            && e.gravity().iter().all(|g| *g == 0.0)
            && self.tools.is_empty()
            && !self.has_contact()
            && w.params().heat.is_none()
            && self.creation.is_none()
            && w.bonds().is_none()
            && !self.driver.may_add_energy()
            && w.materials()
                .iter()
                .all(|m| m.plasticity().is_none() && !m.enabled_terms().contains(&"spin"))
    }

    /// The largest speed the scene's features can give a particle on their
    /// own (a wind's air speed, [`op_dynamics::driver::Stage::speed_allowance`]):
    /// what the explosion check allows beyond gravity and the initial
    /// velocities.
    pub fn speed_allowance(&self) -> Real {
        self.driver.speed_allowance()
    }

    /// Whether skins are in contact: implicit contact (two or more skinned
    /// objects) or contact with obstacle tools.
    pub fn has_contact(&self) -> bool {
        contact(self.skins.len(), !self.skin_tools.is_empty())
    }

    /// Advances the world to world time `t_end` through the scene's driver:
    /// the stages of [`crate::stages`] act between
    /// the world's steps (creation, a fit's release, skin contact) and skins
    /// follow the particles. The shared state ([`BuiltScene::objects`],
    /// `skins`, `skin_tools`, `contact`, `creation`) is lent to the driver
    /// for the call.
    ///
    /// # Errors
    ///
    /// The world's divergence or a stage's failure.
    pub fn advance_to(&mut self, t_end: Real) -> Result<(), DriveError> {
        let mut state = SceneState {
            objects: std::mem::take(&mut self.objects),
            skins: std::mem::take(&mut self.skins),
            skin_tools: std::mem::take(&mut self.skin_tools),
            contact: self.contact,
            creation: self.creation.take(),
        };
        let result = self.driver.advance_to(&mut self.world, &mut state, t_end);
        self.objects = state.objects;
        self.skins = state.skins;
        self.skin_tools = state.skin_tools;
        self.contact = state.contact;
        self.creation = state.creation;
        result
    }

    /// Seconds spent per stage so far: the scene's making
    /// ([`BuiltScene::setup_seconds`]), the world's own stages
    /// ([`World::stage_seconds`]; those it does not have are left out),
    /// then the scene's ([`crate::stages`]).
    pub fn timings(&self) -> Vec<(String, f64)> {
        let setup = self.setup_seconds.iter().cloned();
        let world = self
            .world
            .stage_seconds()
            .into_iter()
            .filter(|(_, t)| *t > 0.0)
            .map(|(n, t)| (n.to_string(), t));
        let scene = self
            .driver
            .timings()
            .into_iter()
            .filter(|(n, _)| n != "world");
        setup.chain(world).chain(scene).collect()
    }

    /// Scene time: the world's time minus the settle phase once it ran
    /// (frame 0 is at scene time 0; force windows are in scene time).
    pub fn scene_time(&self) -> Real {
        if self.settled {
            self.world.time() - self.settle
        } else {
            self.world.time()
        }
    }
}

/// The stage names of [`BuiltScene::stages`] from their parts: the world's
/// stages (its own tool roles replaced by `roles`, every tool of the
/// scene), then `skin` and `polygonize` with `skinned`, `contact`,
/// `creation` and `fit` (`creation` is `Some(has_fit)` when the scene has
/// creation rules), `triangulation`. `opsim check` lists a sample's stages
/// with the full scene's parts this way.
pub fn stage_names<'a>(
    world: Vec<String>,
    roles: impl Iterator<Item = &'a str>,
    skinned: bool,
    contact: bool,
    creation: Option<bool>,
    triangulation: bool,
) -> Vec<String> {
    let mut stages: Vec<String> = world
        .into_iter()
        .filter(|s| !s.starts_with("tool:"))
        .collect();
    stages.extend(roles.map(|r| format!("tool:{r}")));
    if skinned {
        stages.push("skin".into());
        stages.push("polygonize".into());
    }
    if contact {
        stages.push("contact".into());
    }
    if let Some(fit) = creation {
        stages.push("creation".into());
        if fit {
            stages.push("fit".into());
        }
    }
    if triangulation {
        stages.push("triangulation".into());
    }
    stages
}

/// The contact rule of [`BuiltScene::has_contact`], from the number of
/// skinned objects and whether an obstacle tool meets a skin (`opsim check`
/// asks it of the scene, whose sample has no skins).
pub(crate) fn contact(skins: usize, skins_meet_tools: bool) -> bool {
    skins >= 2 || skins_meet_tools
}
