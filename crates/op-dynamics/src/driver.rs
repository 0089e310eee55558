//! The simulation driver: one home for the flow of a step.
//!
//! A [`World`] steps particles: forces, integration and its own per-step
//! actions (heat, bonds, plasticity, erasers; see [`World::step`]). What
//! acts *between* steps on a schedule (particle creation, the release of a
//! fit's samples, skin contact, skin posing) is a [`Stage`], and a
//! [`Driver`] runs an ordered list of them around the world's steps:
//!
//! 1. every due [`Phase::Edit`] stage runs (in list order) and returns its
//!    [`Effects`]: particles inserted or removed, state changed, forces
//!    stale; the driver applies them once ([`World::apply_effects`]),
//!    and tells every stage of the particles inserted and removed
//!    ([`Stage::notify`]), so a skin gains primitives for created particles
//!    and drops those of merged ones;
//! 2. the interval's end is the earliest [`Stage::horizon`] (and the
//!    target time);
//! 3. every due [`Phase::Forces`] stage runs: it prepares the forces it
//!    adds over the interval, which it then lends ([`Stage::lend`]);
//! 4. the world advances to the interval's end with what every stage lends
//!    it ([`World::advance_to_with`], landing on it exactly): a force
//!    [`Contributor`] acting in every force evaluation (computed once for
//!    the interval and held, an explicit coupling; or evaluated on the
//!    state, [`Contributor::follows_state`]: op-implicit's skin contact,
//!    op-scene's wind), in the order of [`crate::contributors`], and an
//!    [`AfterStep`] action run after every step, after the world's own
//!    (op-scene's speed clamp). Their time counts as the lending stage's.
//!
//! [`Driver::advance_to`] repeats this until the target time, then runs
//! every stage's [`Stage::at_target`] (skins follow the particles, dropping
//! the primitives of particles the world erased). Each stage, and the
//! world's advance, is timed ([`Driver::timings`]). The context
//! `C` is the state the stages share (for op-scene: objects, skins,
//! contact figures); op-dynamics knows nothing of it.
//!
//! The driver's list is the one registry of a run's pipeline: the world
//! holds only its own physics (the step's [`crate::world::CORE_STAGES`],
//! its after-step stages and built-in contributors, [`RESERVED`]), and
//! everything a caller adds, a stage between steps, a force or an action
//! after every step, is a [`Stage`] pushed here, its name unique.

use std::time::Instant;

use crate::checkpoint::StateError;
use crate::contributors::Contributor;
use crate::world::{AfterStep, Divergence, World};
use crate::Real;

/// Names a stage may not take: the world's own parts (the step's core
/// stages, its after-step stages, its built-in contributors) and `world`
/// (the world's steps in [`Driver::timings`]). Timings are reported by
/// name, so a stage named like one of them would merge with it.
pub const RESERVED: [&str; 13] = [
    "reorder",
    "neighbours",
    "integrate",
    "check",
    "heat",
    "bonds",
    "plasticity",
    "erase",
    "tools",
    "gravity and damping",
    "pending forces",
    "force windows",
    "world",
];

/// What a stage changed; [`World::apply_effects`] gives the one meaning
/// of each flag, wherever the stage ran.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Effects {
    /// The force function changed (a memory flowed, temperatures changed,
    /// velocities a damping reads were edited): forces cached at the
    /// current state are stale and are evaluated anew.
    pub forces_stale: bool,
    /// The particle set or its state changed (particles inserted, removed
    /// or moved): everything the integrator cached from the state is
    /// dropped (forces, velocity Verlet's angular momenta).
    pub state_changed: bool,
    /// Ids of particles inserted.
    pub inserted: Vec<u32>,
    /// Ids of particles removed (merged or erased).
    pub removed: Vec<u32>,
}

impl Effects {
    /// Whether anything changed.
    pub fn is_empty(&self) -> bool {
        !self.forces_stale
            && !self.state_changed
            && self.inserted.is_empty()
            && self.removed.is_empty()
    }

    /// Adds `other`'s effects to these (ids in the order they happened).
    pub fn merge(&mut self, other: Effects) {
        self.forces_stale |= other.forces_stale;
        self.state_changed |= other.state_changed;
        self.inserted.extend(other.inserted);
        self.removed.extend(other.removed);
    }
}

/// When in the interval a stage runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Before the interval, first: changes the particle set or state.
    Edit,
    /// Before the interval, after the edits: adds external forces held
    /// over the interval.
    Forces,
    /// Never runs between intervals: acts only inside the world's steps,
    /// through what it lends ([`Stage::lend`]), a force in every force
    /// evaluation or an action after every step (op-scene's features).
    Step,
}

/// What a stage lends the world's steps over an interval
/// ([`Stage::lend`], [`World::advance_to_with`]).
#[derive(Default)]
pub struct Lent<'a> {
    /// Forces it adds in every force evaluation.
    pub contributor: Option<&'a dyn Contributor>,
    /// An action after every step, after the world's own after-step
    /// stages.
    pub after_step: Option<&'a mut dyn AfterStep>,
}

/// A stage's failure.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[error("{stage}: {message}")]
pub struct StageError {
    /// The stage's name.
    pub stage: String,
    /// What went wrong.
    pub message: String,
}

impl StageError {
    /// An error of `stage`.
    pub fn new(stage: &str, message: impl std::fmt::Display) -> Self {
        StageError {
            stage: stage.to_string(),
            message: message.to_string(),
        }
    }
}

/// Why [`Driver::advance_to`] stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DriveError {
    /// The world diverged.
    #[error(transparent)]
    Diverged(#[from] Divergence),
    /// A stage failed.
    #[error(transparent)]
    Stage(#[from] StageError),
}

/// Something acting on the world between steps, on a schedule; see the
/// module docs for the order.
pub trait Stage<C>: Send {
    /// Name, for timings and errors.
    fn name(&self) -> &str;

    /// When it runs.
    fn phase(&self) -> Phase;

    /// Whether it runs before the next interval. Default: never (a
    /// follower that only reacts through [`Stage::notify`] and
    /// [`Stage::at_target`]).
    fn due(&self, _world: &World, _ctx: &C) -> bool {
        false
    }

    /// The latest world time the world may reach before this stage must
    /// run again. Default: infinity (no constraint).
    fn horizon(&self, _world: &World, _ctx: &C) -> Real {
        Real::INFINITY
    }

    /// How far beyond [`Stage::horizon`] the interval may stretch when that
    /// reaches the target of [`Driver::advance_to`] (no sliver interval
    /// from round-off). Default 0: the horizon is exact (a schedule counted
    /// in steps, such as the creation rules', would shift by the sliver
    /// step otherwise).
    fn slack(&self, _world: &World) -> Real {
        0.0
    }

    /// Runs; `until` is the end of the coming interval (for a
    /// [`Phase::Edit`] stage, the target time: the interval is not known
    /// yet).
    /// Default: changes nothing.
    fn run(
        &mut self,
        _world: &mut World,
        _ctx: &mut C,
        _until: Real,
    ) -> Result<Effects, StageError> {
        Ok(Effects::default())
    }

    /// What it lends the world's steps over the coming interval: forces in
    /// every force evaluation (a [`Phase::Forces`] stage offers what its
    /// [`Stage::run`] computed), an action after every step. Default:
    /// nothing.
    fn lend(&mut self) -> Lent<'_> {
        Lent::default()
    }

    /// Whether what it lends may add energy to the scene (a passive scene,
    /// whose energy only damping changes, is checked for energy gain).
    /// Default: true for a stage that lends forces or actions
    /// ([`Phase::Forces`], [`Phase::Step`]), false for an edit (whose
    /// changes its owner accounts for); a stage that only removes energy
    /// says false.
    fn may_add_energy(&self) -> bool {
        self.phase() != Phase::Edit
    }

    /// The largest speed what it lends can give a particle on its own (a
    /// wind's air speed): what an explosion check allows beyond gravity
    /// and the initial velocities. Default: 0.
    fn speed_allowance(&self) -> Real {
        0.0
    }

    /// Told of the effects of the stages that ran before the interval.
    fn notify(
        &mut self,
        _world: &World,
        _ctx: &mut C,
        _effects: &Effects,
    ) -> Result<(), StageError> {
        Ok(())
    }

    /// Once the world reached the target of [`Driver::advance_to`].
    fn at_target(&mut self, _world: &World, _ctx: &mut C) -> Result<(), StageError> {
        Ok(())
    }

    /// What the stage itself changes as the run goes on (not its
    /// context's: that is its owner's to save), encoded
    /// ([`crate::checkpoint::encode`]), for a checkpoint taken at a target
    /// time ([`Driver::states`]). Default: nothing, right for a stage that
    /// recomputes what it holds at the start of every interval.
    fn save_state(&self) -> Vec<u8> {
        Vec::new()
    }

    /// Puts back what [`Stage::save_state`] returned. Default: accepts only
    /// the empty state.
    fn restore_state(&mut self, state: &[u8]) -> Result<(), StateError> {
        crate::checkpoint::no_state(self.name(), state)
    }
}

/// Runs stages around a world's steps; see the module docs.
pub struct Driver<C> {
    stages: Vec<Box<dyn Stage<C>>>,
    seconds: Vec<f64>,
    world_seconds: f64,
}

impl<C> Default for Driver<C> {
    fn default() -> Self {
        Driver {
            stages: Vec::new(),
            seconds: Vec::new(),
            world_seconds: 0.0,
        }
    }
}

impl<C> Driver<C> {
    /// A driver with no stage: [`Driver::advance_to`] is the world's.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a stage (stages of one phase run in the order added).
    ///
    /// # Errors
    ///
    /// A stage of the same name is already there, or the name is one of
    /// the world's own ([`RESERVED`]): names are unique, so timings keyed
    /// by name never merge two stages.
    pub fn push(&mut self, stage: Box<dyn Stage<C>>) -> Result<(), StageError> {
        let name = stage.name();
        if RESERVED.contains(&name) {
            return Err(StageError::new(
                name,
                "the world has a part of this name: names must be unique",
            ));
        }
        if self.stages.iter().any(|s| s.name() == name) {
            return Err(StageError::new(
                name,
                "a stage of this name is already in the driver: names must be unique",
            ));
        }
        self.stages.push(stage);
        self.seconds.push(0.0);
        Ok(())
    }

    /// Every stage's state ([`Stage::save_state`]) by name, in order: what a
    /// checkpoint saves of the driver between two calls of
    /// [`Driver::advance_to`].
    pub fn states(&self) -> Vec<(String, Vec<u8>)> {
        self.stages
            .iter()
            .map(|s| (s.name().to_string(), s.save_state()))
            .collect()
    }

    /// Puts back the states [`Driver::states`] returned, into a driver with
    /// the same stages in the same order.
    pub fn restore(&mut self, states: &[(String, Vec<u8>)]) -> Result<(), StateError> {
        let names: Vec<&str> = states.iter().map(|(n, _)| n.as_str()).collect();
        if names != self.names() {
            return Err(StateError(format!(
                "the checkpoint has the stages {names:?}, the scene {:?}",
                self.names()
            )));
        }
        for (stage, (_, state)) in self.stages.iter_mut().zip(states) {
            stage.restore_state(state)?;
        }
        Ok(())
    }

    /// The stages' names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.stages.iter().map(|s| s.name()).collect()
    }

    /// Names of the stages of `phase`, in order.
    pub fn names_of(&self, phase: Phase) -> Vec<&str> {
        self.stages
            .iter()
            .filter(|s| s.phase() == phase)
            .map(|s| s.name())
            .collect()
    }

    /// Whether some stage's lent forces or actions may add energy
    /// ([`Stage::may_add_energy`]).
    pub fn may_add_energy(&self) -> bool {
        self.stages.iter().any(|s| s.may_add_energy())
    }

    /// The largest speed a stage's lent forces can give a particle
    /// ([`Stage::speed_allowance`]).
    pub fn speed_allowance(&self) -> Real {
        self.stages
            .iter()
            .map(|s| s.speed_allowance())
            .fold(0.0, Real::max)
    }

    /// Seconds spent in each stage, then in the world's steps (`"world"`),
    /// since the driver was made.
    pub fn timings(&self) -> Vec<(String, f64)> {
        self.stages
            .iter()
            .zip(&self.seconds)
            .map(|(s, t)| (s.name().to_string(), *t))
            .chain(std::iter::once(("world".to_string(), self.world_seconds)))
            .collect()
    }

    /// Advances `world` to time `t_end` with the stages acting between
    /// intervals (see the module docs); lands on `t_end` exactly.
    ///
    /// # Errors
    ///
    /// The world's divergence or a stage's failure; the world is left as
    /// it was when it happened.
    pub fn advance_to(
        &mut self,
        world: &mut World,
        ctx: &mut C,
        t_end: Real,
    ) -> Result<(), DriveError> {
        let eps = 1e-12 * world.params().dt;
        loop {
            let remaining = t_end - world.time();
            if remaining <= eps {
                break;
            }
            // 1. Edits, then their effects told to everyone.
            let mut effects = Effects::default();
            for k in 0..self.stages.len() {
                if self.stages[k].phase() != Phase::Edit || !self.stages[k].due(world, ctx) {
                    continue;
                }
                let clock = Instant::now();
                let e = self.stages[k].run(world, ctx, t_end)?;
                self.seconds[k] += clock.elapsed().as_secs_f64();
                effects.merge(e);
            }
            if !effects.is_empty() {
                world.apply_effects(&effects);
                for k in 0..self.stages.len() {
                    let clock = Instant::now();
                    self.stages[k].notify(world, ctx, &effects)?;
                    self.seconds[k] += clock.elapsed().as_secs_f64();
                }
            }
            // 2. The interval: up to the earliest horizon, or to the target
            // when every stage lets its interval stretch that far.
            let mut target = t_end;
            for s in &self.stages {
                let h = s.horizon(world, ctx);
                if t_end > h + s.slack(world) {
                    target = target.min(h);
                }
            }
            if t_end - target <= eps {
                target = t_end;
            }
            if target <= world.time() + eps {
                // A stage that cannot let time pass would loop forever.
                return Err(StageError::new(
                    "driver",
                    format!(
                        "no stage lets time pass beyond t = {} (target {t_end})",
                        world.time()
                    ),
                )
                .into());
            }
            // 3. The forces of the interval, offered as contributors.
            for k in 0..self.stages.len() {
                if self.stages[k].phase() != Phase::Forces || !self.stages[k].due(world, ctx) {
                    continue;
                }
                let clock = Instant::now();
                let e = self.stages[k].run(world, ctx, target)?;
                self.seconds[k] += clock.elapsed().as_secs_f64();
                world.apply_effects(&e);
            }
            // 4. The world's steps, with what the stages lend, whose time
            // counts as their stages'.
            let mut contributors: Vec<(usize, &dyn Contributor)> = Vec::new();
            let mut after_steps: Vec<(usize, &mut dyn AfterStep)> = Vec::new();
            for (k, s) in self.stages.iter_mut().enumerate() {
                let lent = s.lend();
                contributors.extend(lent.contributor.map(|c| (k, c)));
                after_steps.extend(lent.after_step.map(|a| (k, a)));
            }
            let (forces_by, forces): (Vec<usize>, Vec<&dyn Contributor>) =
                contributors.into_iter().unzip();
            let (actions_by, mut actions): (Vec<usize>, Vec<&mut dyn AfterStep>) =
                after_steps.into_iter().unzip();
            let clock = Instant::now();
            let stepped = world.advance_to_with(target, &forces, &mut actions);
            let mut world_seconds = clock.elapsed().as_secs_f64();
            let (force_seconds, action_seconds) = world.interval_seconds();
            let lent = forces_by.iter().zip(force_seconds);
            for (&k, &spent) in lent.chain(actions_by.iter().zip(action_seconds)) {
                self.seconds[k] += spent;
                world_seconds -= spent;
            }
            self.world_seconds += world_seconds;
            stepped?;
            // 5. What the world's own stages did (particles erased): told to
            // every stage. The world already dropped its cached forces.
            let effects = world.take_effects();
            if !effects.is_empty() {
                for k in 0..self.stages.len() {
                    let clock = Instant::now();
                    self.stages[k].notify(world, ctx, &effects)?;
                    self.seconds[k] += clock.elapsed().as_secs_f64();
                }
            }
        }
        for k in 0..self.stages.len() {
            let clock = Instant::now();
            self.stages[k].at_target(world, ctx)?;
            self.seconds[k] += clock.elapsed().as_secs_f64();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Named(&'static str);

    impl Stage<()> for Named {
        fn name(&self) -> &str {
            self.0
        }

        fn phase(&self) -> Phase {
            Phase::Edit
        }
    }

    #[test]
    fn stage_names_are_unique() {
        let mut driver = Driver::<()>::new();
        driver.push(Box::new(Named("creation"))).unwrap();
        assert!(driver.push(Box::new(Named("creation"))).is_err());
        for name in RESERVED {
            assert!(driver.push(Box::new(Named(name))).is_err(), "{name}");
        }
        // Every name of the world's own parts is reserved.
        let own = crate::world::CORE_STAGES
            .iter()
            .chain(&crate::world::after_step::BUILT_IN)
            .chain(&crate::contributors::BUILT_IN);
        for name in own {
            assert!(RESERVED.contains(name), "{name} is not reserved");
        }
        driver.push(Box::new(Named("contact"))).unwrap();
        assert_eq!(driver.names(), ["creation", "contact"]);
    }
}
