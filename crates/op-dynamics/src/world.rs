//! The world: particles, materials, the enabled interaction kernel, the
//! neighbour list, external actions and the integrator, stepped in time.

use crate::bonds::Bonds;
use crate::diagnostics::{self, Diagnostics};
use crate::driver::Effects;
use crate::error::ParamError;
use crate::external::ExternalAccumulator;
use crate::forces::{ForceModel, ForceScratch, Kernel};
use crate::integrators::Integrator;
use crate::interactions::{Material, PreparedMaterial};
use crate::math::{Point3, Real, Vec3};
use crate::neighbours::{NeighbourList, PairList};
use crate::particles::Particles;
use crate::tooling::ToolSet;

pub(crate) mod after_step;
mod config;
mod divergence;
mod editing;
mod params;
mod pipeline;
mod state;
mod step;
pub use after_step::{AfterStep, AfterStepContext};
use config::{neighbour_radius_check, Config};
pub use divergence::{Divergence, MAX_FORCED_STEPS};
pub use editing::Merge;
pub use params::{DivergenceParams, NeighbourParams, WorldParams, MAX_SKIN};

/// Why building a world failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WorldError {
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    Param(#[from] ParamError),
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
                precision: params.precision,
                neighbours,
                bonds,
                tools: None,
                scratch: ForceScratch::default(),
            },
            repulsion: config.repulsion,
            plastic: config.plastic,
            memory_flows: config.memory_flows,
            built_in_stages: Vec::new(),
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

    /// Whether the pairs run in mixed precision: the world asked for it
    /// ([`WorldParams::precision`]) and its particles are a spacing-only
    /// set of one 12-6 Lennard-Jones material without heat or bonds, the
    /// worlds the cluster kernel serves. Other worlds run in double
    /// precision whatever they asked.
    pub fn runs_mixed_precision(&self) -> bool {
        crate::forces::cluster_material(
            self.params.precision,
            self.model.kernel,
            &self.particles.attributes(),
            &self.model.materials,
            self.model.heated,
            self.model.bonds.is_some(),
        )
        .is_some()
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

    /// The neighbour list, if any interaction is enabled. Its particle
    /// rows ([`NeighbourList::pairs`]) are empty in worlds that run the
    /// cluster kernel ([`World::runs_mixed_precision`]), which never
    /// search them: [`World::neighbour_pairs`] searches them on request.
    pub fn neighbours(&self) -> Option<&NeighbourList> {
        self.model.neighbours.as_ref()
    }

    /// The particle pairs of the neighbour list's last build (every pair
    /// within `cutoff + skin` of its reference positions), searched now if
    /// the world's kernel did not need them ([`NeighbourList::ensure_rows`]).
    /// Changes neither the list's reference positions nor its rebuilds, so
    /// the trajectory is the same whether or not it is called.
    pub fn neighbour_pairs(&mut self) -> Option<&PairList> {
        let list = self.model.neighbours.as_mut()?;
        list.ensure_rows();
        Some(list.pairs())
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

    /// Seconds each contributor of the last [`World::advance_to_with`]
    /// (its `extra`, in order) spent in its force evaluations, then each
    /// of its after-step actions (`after_steps`, in order): not in
    /// [`World::stage_seconds`], for the stages that lend them to report.
    pub fn interval_seconds(&self) -> (&[f64], &[f64]) {
        let s = &self.model.scratch;
        (&s.extra_seconds, &s.lent_after_step_seconds)
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
    /// [`Contributor`](crate::contributors::Contributor) to
    /// [`World::advance_to_with`] instead.
    pub fn add_external_force(&mut self, id: u32, force: Vec3, torque: Vec3) {
        self.may_rotate |= torque != Vec3::zeros();
        self.accumulator.add(id, force, torque);
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
