//! The world: particles, materials, the enabled interaction kernel, the
//! neighbour list, external actions and the integrator, stepped in time.

use rayon::prelude::*;

use crate::bonds::Bonds;
use crate::contributors::Contributor;
use crate::diagnostics::{self, Diagnostics};
use crate::driver::Effects;
use crate::error::ParamError;
use crate::external::ExternalAccumulator;
use crate::flags::Flags;
use crate::forces::{ForceModel, ForceScratch, Kernel};
use crate::integrators::Integrator;
use crate::interactions::{Material, PreparedMaterial};
use crate::math::{Point3, Real, Vec3};
use crate::neighbours::{copy_positions, spatial_order, NeighbourList};
use crate::particles::{ParticleType, Particles};
use crate::tooling::ToolSet;

mod after_step;
mod editing;
mod params;
mod pipeline;
mod state;
pub use after_step::{AfterStep, AfterStepContext};
pub use editing::Merge;
pub use params::{DivergenceParams, NeighbourParams, WorldParams, MAX_SKIN};

/// Why building a world failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WorldError {
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    Param(#[from] ParamError),
    /// Two parts of the pipeline (after-step stages, or force
    /// contributors) have the same name.
    #[error("{kind} {name:?} is already in the world's pipeline: names must be unique")]
    DuplicateName {
        /// What was registered twice.
        kind: &'static str,
        /// The name.
        name: String,
    },
}

/// Adaptive steps in a row that may be forced through at `dt_min` with
/// their error above the tolerance before the run stops as diverged
/// ([`crate::integrators::StepInfo::tolerance_met`]).
pub const MAX_FORCED_STEPS: u32 = 1000;

/// A run that blew up: the step, time and (when one is to blame) particle
/// where it was detected, and what was wrong. The one divergence of the
/// workspace: the world's checks (non-finite state, speed limit) and the
/// runner's (runaway energy, energy gain, explosion beyond the scene's
/// bounds) all report it, in one format:
/// `simulation diverged at step N (t = T): particle P: reason`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct Divergence {
    /// Index of the step that produced the bad state (1-based).
    pub step: u64,
    /// Simulation time after that step.
    pub time: Real,
    /// Stable id of the first bad particle, when one is to blame (the
    /// energy gain of a whole scene has none).
    pub particle: Option<u32>,
    /// What was wrong.
    pub reason: String,
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "simulation diverged at step {} (t = {}): ",
            self.step, self.time
        )?;
        if let Some(p) = self.particle {
            write!(f, "particle {p}: ")?;
        }
        f.write_str(&self.reason)
    }
}

/// The stages every step has, around the after-step stages
/// ([`AfterStep`]): `reorder` (spatial re-sort at neighbour rebuilds),
/// `neighbours` (neighbour-list updates inside force evaluations),
/// `integrate` (integration with its force evaluations) first, `check`
/// (the divergence check) last.
pub const CORE_STAGES: [&str; 4] = ["reorder", "neighbours", "integrate", "check"];

/// What one call of [`World::step`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Step size taken.
    pub dt: Real,
    /// Steps rejected by the adaptive controller.
    pub rejected: u32,
    /// Force evaluations.
    pub force_evaluations: u32,
    /// Whether particles were re-sorted.
    pub reordered: bool,
    /// Seconds per stage of the step, in the order they ran: `reorder`,
    /// `neighbours`, `integrate`, the after-step stages the world has,
    /// `check` ([`CORE_STAGES`], [`AfterStep`]).
    pub seconds: Vec<(&'static str, f64)>,
    /// Stable ids of the particles eraser tools removed at the end of the
    /// step (seed 000 fig. 7), or shaping tools trapped between them (fig.
    /// 14, op-modeling `Role::Shaper`), in increasing order.
    pub erased: Vec<u32>,
    /// Bonds that broke at the end of the step, stretched beyond their
    /// break length ([`crate::bonds`]; seed 000 fig. 12c tearing).
    pub bonds_broken: usize,
}

impl StepReport {
    /// Seconds the step spent in stage `name` (0 for a stage it does not
    /// have).
    pub fn seconds_of(&self, name: &str) -> f64 {
        self.seconds
            .iter()
            .filter(|(n, _)| *n == name)
            .map(|(_, t)| t)
            .sum()
    }
}

/// True when some pair of particles does not interact completely (several
/// objects, several standard types, or two hinges), so the typing repulsion
/// of seed 002 §5 can act and its cut-off counts for the neighbour radius.
fn may_repel(p: &Particles) -> bool {
    let objects = p.objects();
    if objects.iter().any(|&o| Some(&o) != objects.first()) {
        return true;
    }
    let kinds = p.kinds();
    let hinges = kinds.iter().filter(|k| **k == ParticleType::Hinge).count();
    let mut standard = kinds.iter().filter(|k| **k != ParticleType::Hinge);
    let first = standard.next();
    hinges >= 2 || standard.any(|k| Some(k) != first)
}

/// What the particle set and the materials enable (fixed when the world is
/// built, recomputed when particles are inserted or removed).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Config {
    kernel: Kernel,
    /// Largest cut-off among the enabled terms of the materials in use.
    cutoff: Real,
    friction: bool,
    /// Some material in use weakens with heat.
    heated: bool,
    has_fixed: bool,
    repulsion: bool,
    /// Some material in use has plasticity of its remembered curvature.
    plastic: bool,
    /// Some material in use has a bond memory (it turns the particles).
    memory: bool,
    /// Some material in use has a bond memory that flows.
    memory_flows: bool,
}

impl Config {
    /// The configuration of `particles` with these (prepared) materials;
    /// every particle's material index must exist.
    fn of(particles: &Particles, prepared: &[PreparedMaterial]) -> Config {
        let used: Vec<&PreparedMaterial> = {
            let mut seen = vec![false; prepared.len()];
            particles
                .materials()
                .iter()
                .for_each(|&m| seen[m as usize] = true);
            prepared
                .iter()
                .zip(seen)
                .filter(|(_, s)| *s)
                .map(|(m, _)| m)
                .collect()
        };
        // Bond-governed pairs of one object that are not bonded repel.
        let repulsion = may_repel(particles) || used.iter().any(|m| m.bonds().is_some());
        let cutoff = used
            .iter()
            .map(|m| {
                let c = m.spacing_cutoff().max(m.orientation_cutoff());
                if repulsion {
                    c.max(m.repulsion_cutoff())
                } else {
                    c
                }
            })
            .fold(0.0, Real::max);
        let friction = used.iter().any(|m| m.friction() > 0.0);
        let heated = used.iter().any(|m| m.heat_response().is_some());
        let oriented = used.iter().any(|m| m.has_orientation_terms());
        let kernel = if cutoff <= 0.0 || particles.len() < 2 {
            Kernel::None
        } else if oriented || friction {
            Kernel::Oriented
        } else {
            Kernel::Spacing
        };
        Config {
            kernel,
            cutoff,
            friction,
            heated,
            has_fixed: particles
                .flags()
                .iter()
                .any(|f| f.contains(Flags::FIXED_POSITION) || f.contains(Flags::FIXED_ORIENTATION)),
            repulsion,
            plastic: used.iter().any(|m| m.plasticity().is_some()),
            memory: used.iter().any(|m| m.bond_memory().is_some()),
            memory_flows: used
                .iter()
                .any(|m| m.bond_memory().is_some_and(|b| b.flow.is_some())),
        }
    }

    /// The neighbour list this configuration needs (none without a kernel).
    ///
    /// Cannot fail once [`neighbour_radius_check`] accepted every material:
    /// the configuration's cut-off is one of theirs.
    fn neighbour_list(&self, params: &NeighbourParams) -> Option<NeighbourList> {
        (self.kernel != Kernel::None)
            .then(|| NeighbourList::new(params.backend, self.cutoff, self.cutoff * params.skin))
    }
}

impl World {
    /// Takes the kernel and the flags of `config` (what the materials in
    /// use enable), after its particles changed ([`World::insert_particles`]
    /// and the other edits) or were restored from a checkpoint; the
    /// neighbour list is the caller's.
    fn apply_config(&mut self, config: &Config) {
        self.model.kernel = config.kernel;
        self.model.friction = config.friction;
        self.model.heated = config.heated;
        self.model.memory = config.memory;
        self.model.has_fixed = config.has_fixed;
        self.repulsion = config.repulsion;
        self.plastic = config.plastic;
        self.memory_flows = config.memory_flows;
    }
}

/// Checks that every material's cut-off with the skin gives a neighbour
/// list (a finite radius `cutoff * (1 + skin)`), so that no later choice of
/// the materials in use (particles inserted by [`World::insert_particles`]
/// included) can meet an impossible list.
fn neighbour_radius_check(
    prepared: &[PreparedMaterial],
    params: &NeighbourParams,
) -> Result<(), ParamError> {
    for (k, m) in prepared.iter().enumerate() {
        let cutoff = m.cutoff();
        if NeighbourList::try_new(params.backend, cutoff, cutoff * params.skin).is_err() {
            return Err(ParamError::Invalid {
                field: format!("materials[{k}]"),
                message: format!(
                    "cut-off {cutoff} with neighbours.skin {}: the neighbour radius \
                     cutoff * (1 + skin) = {} is not a finite number; lower the cut-offs \
                     (spacing, weight, repulsion) or the skin",
                    params.skin,
                    cutoff + cutoff * params.skin
                ),
            });
        }
    }
    Ok(())
}

/// An oriented particle world.
pub struct World {
    particles: Particles,
    params: WorldParams,
    /// The force evaluation's configuration and scratch.
    model: ForceModel,
    repulsion: bool,
    /// Some material in use has plasticity of its remembered curvature: the
    /// plastic stage updates the curvatures.
    plastic: bool,
    /// Some material in use has a bond memory that flows: the plastic stage
    /// flows the remembered offsets.
    memory_flows: bool,
    /// The world's own after-step stages it uses, in their order
    /// ([`after_step`]).
    built_in_stages: Vec<Box<dyn AfterStep>>,
    /// The after-step stages callers registered
    /// ([`World::add_after_step`]), after the world's own.
    registered_stages: Vec<Box<dyn AfterStep>>,
    /// Something may have set particles rotating (initial spin, external
    /// torques, direct state edits): the divergence check reads frames.
    may_rotate: bool,
    integrator: Integrator,
    accumulator: ExternalAccumulator,
    forces: Vec<Vec3>,
    torques: Vec<Vec3>,
    prev_positions: Vec<Point3>,
    time: Real,
    /// Effects of the world's own stages since [`World::take_effects`].
    effects: Effects,
    steps: u64,
    /// Steps this world may take before it stops as diverged
    /// ([`World::set_step_budget`]). Default: unbounded.
    step_budget: u64,
    /// Adaptive steps forced through at `dt_min` in a row (tolerance not
    /// met; [`MAX_FORCED_STEPS`]).
    forced_in_a_row: u32,
    dt_next: Real,
    report: StepReport,
    /// Seconds per stage (by name, in the order first run) summed over
    /// every step.
    stage_seconds: Vec<(&'static str, f64)>,
}

impl World {
    /// Builds a world. Only what the materials enable is built: the kernel
    /// (none, spacing-only or oriented) and the neighbour radius (the
    /// largest cut-off among enabled terms; no list at all when nothing
    /// interacts).
    pub fn new(
        particles: Particles,
        materials: &[Material],
        params: WorldParams,
    ) -> Result<World, WorldError> {
        params.validate(particles.len())?;
        let prepared = materials
            .iter()
            .enumerate()
            .map(|(k, m)| {
                m.prepare()
                    .map_err(|e| e.within(&format!("materials[{k}]")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(&bad) = particles
            .materials()
            .iter()
            .find(|&&m| m as usize >= prepared.len())
        {
            return Err(ParamError::Invalid {
                field: "particles.material".into(),
                message: format!(
                    "material index {bad} does not exist ({} materials defined)",
                    prepared.len()
                ),
            }
            .into());
        }
        neighbour_radius_check(&prepared, &params.neighbours)?;
        let config = Config::of(&particles, &prepared);
        let neighbours = config.neighbour_list(&params.neighbours);
        let bonds = Bonds::needed(&particles, &prepared).then(|| {
            let mut b = Bonds::new(&prepared);
            b.form(&particles, &prepared, 0);
            b
        });
        let n = particles.len();
        let mut world = World {
            model: ForceModel {
                kernel: config.kernel,
                materials: prepared,
                friction: config.friction,
                heated: config.heated,
                memory: config.memory,
                has_fixed: config.has_fixed,
                neighbours,
                bonds,
                tools: None,
                contributors: Vec::new(),
                scratch: ForceScratch::default(),
            },
            repulsion: config.repulsion,
            plastic: config.plastic,
            memory_flows: config.memory_flows,
            built_in_stages: Vec::new(),
            registered_stages: Vec::new(),
            may_rotate: config.memory
                || particles
                    .angular_velocities()
                    .iter()
                    .any(|w| *w != Vec3::zeros()),
            integrator: Integrator::new(params.scheme),
            accumulator: ExternalAccumulator::new(particles.id_bound()),
            forces: vec![Vec3::zeros(); n],
            torques: vec![Vec3::zeros(); n],
            prev_positions: particles.positions().to_vec(),
            time: 0.0,
            effects: Effects::default(),
            step_budget: u64::MAX,
            forced_in_a_row: 0,
            steps: 0,
            dt_next: params.dt,
            report: StepReport::default(),
            stage_seconds: Vec::new(),
            particles,
            params,
        };
        world.sync_built_in_stages();
        Ok(world)
    }

    /// The particles (read-only; slots may be re-sorted between steps, use
    /// [`Particles::ids`] / [`Particles::slot_of`]).
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Mutable access to the particles (scripted motion, tests). Cached
    /// forces are invalidated.
    pub fn particles_mut(&mut self) -> &mut Particles {
        self.integrator.invalidate();
        self.may_rotate = true;
        &mut self.particles
    }

    /// The parameters the world was built with.
    pub fn params(&self) -> &WorldParams {
        &self.params
    }

    /// The prepared materials.
    pub fn materials(&self) -> &[PreparedMaterial] {
        &self.model.materials
    }

    /// The pair kernel chosen from the enabled terms.
    pub fn kernel(&self) -> Kernel {
        self.model.kernel
    }

    /// The bonds ([`crate::bonds`]), if some particle has a bonded
    /// material.
    pub fn bonds(&self) -> Option<&Bonds> {
        self.model.bonds.as_ref()
    }

    /// The neighbour list, if any interaction is enabled.
    pub fn neighbours(&self) -> Option<&NeighbourList> {
        self.model.neighbours.as_ref()
    }

    /// Gives the world its tools (seed 000 §6; op-modeling `tools`), in
    /// place of any it had. Tools that heat need the world's heat settings
    /// ([`WorldParams::heat`]); cached forces are dropped.
    pub fn set_tools(&mut self, tools: Box<dyn ToolSet>) -> Result<(), WorldError> {
        if tools.heats() && self.params.heat.is_none() {
            return Err(ParamError::Invalid {
                field: "tools".into(),
                message: "a heater or knife needs the world's heat settings \
                          (heat: conduction, cooling, ambient)"
                    .into(),
            }
            .into());
        }
        self.model.tools = Some(tools);
        self.sync_built_in_stages();
        self.invalidate_forces();
        Ok(())
    }

    /// The tools acting on the particles ([`World::set_tools`]), if any.
    pub fn tools(&self) -> Option<&dyn ToolSet> {
        self.model.tools.as_deref()
    }

    /// Current simulation time.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The oscillation measure of the last step (seed 002 §3):
    /// `O = sqrt(sum_i |dx_i|^2 - |sum_i dx_i|^2 / N)`, the movement of the
    /// particles about their mean displacement during one step. The
    /// extracted paper text lost the `1/N`; without it the quantity is not a
    /// spread about the mass centre and can be negative.
    ///
    /// Computed on demand from the positions before and after the last step
    /// (the step itself only copies the positions), 0 before the first step.
    pub fn oscillation(&self) -> Real {
        if self.steps == 0 {
            return 0.0;
        }
        diagnostics::oscillation(&self.prev_positions, self.particles.positions())
    }

    /// What the last step did.
    pub fn last_report(&self) -> &StepReport {
        &self.report
    }

    /// Seconds spent in each stage of [`World::step`] over every step so
    /// far, by stage name ([`CORE_STAGES`] and the after-step stages, in
    /// the order they first ran; none before the first step).
    pub fn stage_seconds(&self) -> Vec<(&'static str, f64)> {
        self.stage_seconds.clone()
    }

    /// What the world's own stages did since the last call (particles that
    /// erasers removed; [`crate::driver`] tells its stages), and forgets it.
    pub fn take_effects(&mut self) -> Effects {
        std::mem::take(&mut self.effects)
    }

    /// Drops the integrator's cached forces: the next step evaluates them
    /// anew (what they depend on changed: a memory flowed, temperatures
    /// changed, tools were set; [`Effects::forces_stale`]).
    pub fn invalidate_forces(&mut self) {
        self.integrator.invalidate_forces();
    }

    /// Applies what stages changed, with one meaning wherever they ran
    /// (the world's after-step stages, the driver's stages): a changed
    /// state ([`Effects::state_changed`]: particles inserted, removed or
    /// edited) drops everything the integrator cached from it (forces and
    /// velocity Verlet's angular momenta); stale forces
    /// ([`Effects::forces_stale`]) drop the forces only.
    pub fn apply_effects(&mut self, effects: &Effects) {
        if effects.state_changed {
            self.integrator.invalidate();
        } else if effects.forces_stale {
            self.integrator.invalidate_forces();
        }
    }

    /// Adds a force and a torque (world frame, torque about the particle's
    /// position) to particle `id`, held constant during the next step and
    /// then cleared (the "pending forces" contributor,
    /// [`crate::contributors`]). To act over a longer interval, pass a
    /// [`Contributor`] to [`World::advance_to_with`] instead.
    pub fn add_external_force(&mut self, id: u32, force: Vec3, torque: Vec3) {
        self.may_rotate |= torque != Vec3::zeros();
        self.accumulator.add(id, force, torque);
    }

    /// Advances by one step: the configured `dt`, or the adaptive
    /// controller's suggestion (at most `dt`).
    ///
    /// Stages, in order: (1) re-sort particles in spatial order when the
    /// neighbour list is about to be rebuilt; (2) integrate, each force
    /// evaluation updating the neighbour list (list-only rebuild when a
    /// stage moved particles past the skin bound), running the pair kernel
    /// and gathering per particle, adding external actions; (3) clear the
    /// pending external forces; (4) advance the temperatures
    /// ([`crate::heat`], when the world has heat); (5) break the bonds
    /// stretched beyond their break length ([`crate::bonds`]); (6) with
    /// plastic materials only, flow the remembered offsets of bond memories
    /// ([`crate::bond_memory`]) and update the remembered curvatures
    /// ([`crate::plasticity`]; the neighbour list is brought up to date for
    /// the new positions first); (7) erasers remove particles; (8) check
    /// for divergence (the oscillation measure is computed on demand from
    /// the positions before and after the step).
    ///
    /// A world of more than 1024 particles takes the step on a thread of
    /// the current rayon pool (the calling thread waits), so that the
    /// step's parallel passes fork and join by work stealing.
    pub fn step(&mut self) -> Result<&StepReport, Divergence> {
        let dt = self.dt_next.min(self.params.dt);
        let n = self.particles.len();
        on_pool(n, || self.step_by(dt, false, &[]).map(|_| ()))?;
        Ok(&self.report)
    }

    /// Advances until `t_end`, landing on it exactly: the last step is
    /// shortened (a shortened step does not change the adaptive
    /// controller's suggestion for the next one).
    pub fn advance_to(&mut self, t_end: Real) -> Result<(), Divergence> {
        self.advance_to_with(t_end, &[])
    }

    /// [`World::advance_to`] with `extra` contributors acting in every force
    /// evaluation of the interval (after the pending forces, before the
    /// force windows; [`crate::contributors`]): an explicit coupling
    /// evaluated once per interval (op-scene's skin contact) acts over all
    /// of it, also when an adaptive scheme takes several steps. Cached
    /// forces are dropped when the interval ends if some of them was
    /// active: the next interval's contributions differ. The steps run on
    /// a pool thread as [`World::step`]'s do.
    pub fn advance_to_with(
        &mut self,
        t_end: Real,
        extra: &[&dyn Contributor],
    ) -> Result<(), Divergence> {
        if extra.iter().any(|c| c.is_active() && c.adds_torque()) {
            self.may_rotate = true;
        }
        let active = extra.iter().any(|c| c.is_active());
        let n = self.particles.len();
        on_pool(n, || self.advance_steps(t_end, extra, active))
    }

    /// The steps of [`World::advance_to_with`] (on a pool thread).
    fn advance_steps(
        &mut self,
        t_end: Real,
        extra: &[&dyn Contributor],
        active: bool,
    ) -> Result<(), Divergence> {
        loop {
            let remaining = t_end - self.time;
            if remaining <= 1e-12 * self.params.dt {
                if active {
                    self.integrator.invalidate_forces();
                }
                return Ok(());
            }
            let h = self.dt_next.min(self.params.dt);
            // A step within 1e-6 of the remaining time takes all of it, so
            // round-off in the accumulated time never leaves a sliver step.
            if remaining <= h * (1.0 + 1e-6) {
                self.step_by(remaining, true, extra)?;
                if self.time < t_end && self.report.dt == remaining {
                    // Land exactly despite round-off in `time + dt`.
                    self.time = t_end;
                }
            } else {
                self.step_by(h, false, extra)?;
            }
        }
    }

    fn step_by(
        &mut self,
        dt: Real,
        clipped: bool,
        extra: &[&dyn Contributor],
    ) -> Result<&StepReport, Divergence> {
        // The last report's buffer, to time this step's stages in.
        let mut seconds = std::mem::take(&mut self.report.seconds);
        seconds.clear();
        let mut report = StepReport {
            seconds,
            ..StepReport::default()
        };
        let clock = std::time::Instant::now();
        if let Some(list) = self.model.neighbours.as_mut() {
            if self.params.neighbours.reorder && list.rebuild_due(self.particles.positions()) {
                let order = spatial_order(self.particles.positions(), list.cutoff() + list.skin());
                self.particles.permute(&order);
                list.rebuild(self.particles.positions());
                self.integrator.permute(&order);
                report.reordered = true;
            }
        }
        copy_positions(&mut self.prev_positions, self.particles.positions());
        report
            .seconds
            .push(("reorder", clock.elapsed().as_secs_f64()));

        let clock = std::time::Instant::now();
        let neighbour_before = self.model.scratch.neighbour_seconds;
        // Spacing-only worlds that nothing set spinning never rotate.
        let rotating = self.model.kernel == Kernel::Oriented || self.may_rotate;
        self.integrator.set_translation_only(!rotating);
        let (state, bodies, attributes) = self.particles.split();
        let mut ctx =
            self.model
                .context(attributes, &self.params.external, &self.accumulator, extra);
        ctx.step_start = Some(self.time);
        let info = self
            .integrator
            .step(&mut ctx, &bodies, self.time, dt, state);
        let neighbour_seconds = self.model.scratch.neighbour_seconds - neighbour_before;
        report.seconds.push(("neighbours", neighbour_seconds));
        report.seconds.push((
            "integrate",
            clock.elapsed().as_secs_f64() - neighbour_seconds,
        ));
        report.dt = info.dt_taken;
        report.rejected = info.rejected;
        report.force_evaluations = info.force_evaluations;
        self.time += info.dt_taken;
        self.steps += 1;
        self.forced_in_a_row = match info.tolerance_met() {
            true => 0,
            false => self.forced_in_a_row.saturating_add(1),
        };
        if !clipped || info.dt_taken < dt {
            self.dt_next = info.dt_next;
        }
        if self.accumulator.is_active() {
            self.accumulator.clear();
            self.integrator.invalidate_forces();
        }
        // The after-step stages, in order; their effects applied once and
        // kept for the driver.
        let effects = self.run_after_step_stages(info.dt_taken, &mut report);
        self.effects.merge(effects);

        let clock = std::time::Instant::now();
        let check = self
            .check_divergence()
            .and_then(|()| self.check_progress(&info));
        report
            .seconds
            .push(("check", clock.elapsed().as_secs_f64()));
        for &(name, s) in &report.seconds {
            match self.stage_seconds.iter_mut().find(|(n, _)| *n == name) {
                Some(total) => total.1 += s,
                None => self.stage_seconds.push((name, s)),
            }
        }
        self.report = report;
        check?;
        Ok(&self.report)
    }

    /// A run that cannot make progress within its means is stopped like a
    /// divergence: more steps than [`World::set_step_budget`] allows (an
    /// adaptive step collapsing toward `dt_min`), or [`MAX_FORCED_STEPS`]
    /// adaptive steps in a row forced through at `dt_min` with the error
    /// above the tolerance (tolerances no step can meet: the run would
    /// crawl at `dt_min` to its end).
    fn check_progress(&self, info: &crate::integrators::StepInfo) -> Result<(), Divergence> {
        let stop = |reason: String| Divergence {
            step: self.steps,
            time: self.time,
            particle: None,
            reason,
        };
        if self.steps > self.step_budget {
            return Err(stop(format!(
                "{} steps, more than the run's budget of {} (its work limit; the last step was \
                 {:.3e}): the step collapsed",
                self.steps, self.step_budget, info.dt_taken
            )));
        }
        if self.forced_in_a_row >= MAX_FORCED_STEPS {
            return Err(stop(format!(
                "{} adaptive steps in a row were forced through at dt_min = {:.3e} with the error \
                 above the tolerance (error norm {:.3e}): no step meets these tolerances; raise \
                 the tolerances or dt_min",
                self.forced_in_a_row,
                info.dt_taken,
                info.error_norm.unwrap_or(Real::NAN)
            )));
        }
        Ok(())
    }

    /// Stops the run as diverged once it has taken more than `steps` steps
    /// in all ([`World::steps`]): the runner sets the budget its work
    /// limits allow, so that an adaptive step collapsing toward `dt_min`
    /// ends the run instead of running past its estimated work.
    pub fn set_step_budget(&mut self, steps: u64) {
        self.step_budget = steps;
    }

    fn check_divergence(&self) -> Result<(), Divergence> {
        let p = &self.particles;
        let vmax2 = self.params.divergence.max_speed.powi(2);
        // Without torques (spacing kernel, no pending torque) and without
        // initial spin, orientations cannot change: skip reading them.
        let rotating = self.model.kernel == Kernel::Oriented || self.may_rotate;
        let check = |i: usize| {
            let finite = p.positions()[i].iter().all(|c| c.is_finite())
                && p.velocities()[i].iter().all(|c| c.is_finite())
                && (!rotating
                    || (p.angular_velocities()[i].iter().all(|c| c.is_finite())
                        && p.orientations()[i].coords.iter().all(|c| c.is_finite())));
            if !finite {
                Some((
                    i,
                    "non-finite position, velocity or orientation".to_string(),
                ))
            } else if p.velocities()[i].norm_squared() > vmax2 {
                Some((
                    i,
                    format!(
                        "speed {:.3e} exceeds divergence.max_speed = {:.3e}",
                        p.velocities()[i].norm(),
                        self.params.divergence.max_speed
                    ),
                ))
            } else {
                None
            }
        };
        // In parallel over fixed chunks, each scanned in slot order; the
        // first chunk with a bad slot reports it: the same report at any
        // thread count.
        const CHUNK: usize = 4096;
        let n = p.len();
        let bad = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).find_map(check))
            .find_first(Option::is_some)
            .flatten();
        match bad {
            None => Ok(()),
            Some((i, reason)) => Err(Divergence {
                step: self.steps,
                time: self.time,
                particle: Some(p.ids()[i]),
                reason,
            }),
        }
    }

    /// Evaluates forces, torques and potential energy at the current state
    /// (one extra force evaluation; used by diagnostics and tests).
    pub fn evaluate_forces(&mut self) -> (&[Vec3], &[Vec3], Real) {
        let state = self.particles.state();
        let attributes = self.particles.attributes();
        let mut ctx = self
            .model
            .context(attributes, &self.params.external, &self.accumulator, &[]);
        ctx.evaluate(self.time, state, &mut self.forces, &mut self.torques);
        (&self.forces, &self.torques, self.model.scratch.potential())
    }

    /// Energies, momenta and the oscillation measure at the current state
    /// (docs/model.md §6). Costs one force evaluation for the potential energy.
    pub fn diagnostics(&mut self) -> Diagnostics {
        let potential = self.evaluate_forces().2;
        let mut d = diagnostics::kinematic(&self.particles);
        d.potential = potential;
        d.total = d.kinetic_translational + d.kinetic_rotational + potential;
        d.oscillation = self.oscillation();
        d
    }

    /// Forces evaluated so far (all stages of all steps).
    pub fn force_evaluations(&self) -> u64 {
        self.model.scratch.evaluations
    }
}

/// Runs `f`, the steps of a world of `n` particles, on a thread of the
/// current rayon pool: on the calling thread when it is one (inside
/// [`rayon::ThreadPool::install`]), else on one of the global pool's
/// threads while the caller waits. A step has several parallel passes
/// (the neighbour list's motion check, the integrator's kick and drift,
/// the pair passes, the divergence check): entered from a pool thread,
/// each fork-join hands its work to the other threads by work stealing;
/// entered from outside the pool, each one injects a job, wakes a pool
/// thread and puts the caller to sleep until it is done, two thread
/// wake-ups per pass. Worlds of one accumulation block (fewer than
/// [`crate::forces::SPLIT_MIN`] particles, so also one integrator chunk,
/// [`crate::integrators::per_particle::CHUNK`]) have no parallel pass and stay on the
/// caller's thread. Same work, same bits: only the thread that runs the
/// serial parts changes.
///
/// Measured (the performance report's spacing child, 97,556 particles, 10
/// steps, 3 interleaved pairs against the caller's thread): 1 thread 0.49
/// against 0.51 s, 2 threads 0.26-0.29 s either way. It costs memory: what
/// the steps allocate comes from the pool thread's malloc arena, not the
/// caller's, and peak memory was 10% higher at 1 thread (133 against 120
/// MB) and 4% at 2.
fn on_pool<R: Send>(n: usize, f: impl FnOnce() -> R + Send) -> R {
    if n < crate::forces::SPLIT_MIN || rayon::current_thread_index().is_some() {
        return f();
    }
    rayon::scope(|_| f())
}
