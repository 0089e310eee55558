//! The world's after-step stages: what acts on the particles once per step,
//! after the integrator and before the divergence check.
//!
//! Every such stage implements [`AfterStep`] and sits in one ordered list
//! of the world. The world puts its own stages first, in this order, each
//! only when it uses it (pay for what you use):
//!
//! 1. **heat** ([`crate::heat`], seed 000 §6 and §8): heat sources at the
//!    step's end time, conduction over the interacting pairs, cooling; a
//!    world whose materials weaken with heat then has stale forces;
//! 2. **bonds** ([`crate::bonds`], seed 000 fig. 12c): bonds stretched
//!    beyond their break length break for good;
//! 3. **plasticity** (seed 000 fig. 12b): the remembered offsets of bond
//!    memories flow toward the current ones beyond their yield
//!    ([`crate::bond_memory`]), then the remembered curvatures toward the
//!    current ones beyond the yield curvature ([`crate::plasticity`]);
//!    changed memories make the forces stale;
//! 4. **erase** (seed 000 fig. 7 and 14): erasers and trapping shapers
//!    remove particles.
//!
//! Then come the actions the driver's stages lend for the interval
//! ([`crate::driver::Stage::lend`], [`World::advance_to_with`]; op-scene's
//! features, such as a speed clamp), in the driver's order. Each stage
//! returns its [`Effects`]; the world merges them, applies them once
//! ([`World::apply_effects`]), removes the particles they name and keeps
//! those for the driver ([`World::take_effects`]), which tells its stages
//! (a skin drops the primitives of erased particles).

use super::{StepReport, World};
use crate::bond_memory;
use crate::bonds::Bonds;
use crate::driver::Effects;
use crate::heat::{self, HeatParams, HeatScratch};
use crate::interactions::PreparedMaterial;
use crate::math::Real;
use crate::neighbours::NeighbourList;
use crate::particles::Particles;
use crate::plasticity::{self, PlasticScratch};
use crate::tooling::ToolSet;

/// What an after-step stage may read and change: the state at the end of
/// the step just taken.
pub struct AfterStepContext<'a> {
    /// World time at the end of the step.
    pub time: Real,
    /// Length of the step just taken.
    pub dt: Real,
    /// The particles (positions, velocities, ... by slot).
    pub particles: &'a mut Particles,
    /// The prepared materials, indexed by the particles' material index.
    pub materials: &'a [PreparedMaterial],
    /// The neighbour list, when the world has an interaction kernel.
    pub neighbours: Option<&'a mut NeighbourList>,
    /// The bonds, when some material is bonded.
    pub bonds: Option<&'a mut Bonds>,
    /// The tools, when the world has some.
    pub tools: Option<&'a mut (dyn ToolSet + 'static)>,
    /// The report of the step, for what a stage did (bonds broken).
    pub report: &'a mut StepReport,
}

/// A stage the world runs after every step, after the integrator and
/// before the divergence check: the world's own, and those a driver stage
/// lends ([`crate::driver::Lent::after_step`]).
pub trait AfterStep: Send + Sync {
    /// Name, unique in the world's pipeline (timings, `enabled`, errors).
    fn name(&self) -> &'static str;

    /// Runs on the state at the end of the step. Particles to remove go
    /// in the effects' `removed` (the world removes them); changed
    /// velocities or a changed force function set `forces_stale`.
    fn run(&mut self, ctx: &mut AfterStepContext<'_>) -> Effects;
}

/// Names of the world's own stages, in their order (all reserved for
/// driver stages, [`crate::driver::RESERVED`]).
#[cfg(test)]
pub(crate) const BUILT_IN: [&str; 4] = ["heat", "bonds", "plasticity", "erase"];

/// Heat conduction, sources and cooling ([`crate::heat`]).
struct HeatStage {
    params: HeatParams,
    /// Some material weakens with heat: new temperatures make the forces
    /// stale.
    weakens: bool,
    scratch: HeatScratch,
}

impl AfterStep for HeatStage {
    fn name(&self) -> &'static str {
        "heat"
    }

    fn run(&mut self, ctx: &mut AfterStepContext<'_>) -> Effects {
        let pairs = ctx.neighbours.as_deref_mut().map(|list| {
            list.update(ctx.particles.positions());
            list.build_incoming();
            let cutoff = list.cutoff();
            (&*list, cutoff)
        });
        let pairs = pairs.map(|(l, c)| (l.pairs(), c));
        let (positions, objects, temperatures) = ctx.particles.heat_view();
        heat::advance(
            &self.params,
            ctx.tools.as_deref(),
            ctx.time,
            ctx.dt,
            positions,
            objects,
            pairs,
            temperatures,
            &mut self.scratch,
        );
        Effects {
            forces_stale: self.weakens,
            ..Effects::default()
        }
    }
}

/// Breaking of bonds stretched beyond their break length
/// ([`crate::bonds`]).
struct BondBreaking;

impl AfterStep for BondBreaking {
    fn name(&self) -> &'static str {
        "bonds"
    }

    fn run(&mut self, ctx: &mut AfterStepContext<'_>) -> Effects {
        if let Some(bonds) = ctx.bonds.as_deref_mut() {
            ctx.report.bonds_broken = bonds.break_stretched(ctx.particles);
        }
        Effects::default()
    }
}

/// Plastic flow of bond memories and of remembered curvatures.
struct PlasticFlow {
    /// Some material has a bond memory that flows.
    memory_flows: bool,
    /// Some material has plasticity of its remembered curvature.
    curvature: bool,
    scratch: PlasticScratch,
}

impl AfterStep for PlasticFlow {
    fn name(&self) -> &'static str {
        "plasticity"
    }

    fn run(&mut self, ctx: &mut AfterStepContext<'_>) -> Effects {
        let mut stale = false;
        if let (true, Some(bonds)) = (self.memory_flows, ctx.bonds.as_deref_mut()) {
            stale |= bond_memory::flow(bonds, ctx.particles, ctx.materials, ctx.dt);
        }
        if let (true, Some(list)) = (self.curvature, ctx.neighbours.as_deref_mut()) {
            // Cached forces were computed with the old curvatures.
            stale |= plasticity::apply(
                ctx.particles,
                ctx.materials,
                list,
                ctx.bonds.as_deref(),
                ctx.dt,
                &mut self.scratch,
            );
        }
        Effects {
            forces_stale: stale,
            ..Effects::default()
        }
    }
}

/// Erasers and trapping shapers remove particles (seed 000 fig. 7, 14).
struct Erasers;

impl AfterStep for Erasers {
    fn name(&self) -> &'static str {
        "erase"
    }

    fn run(&mut self, ctx: &mut AfterStepContext<'_>) -> Effects {
        // On the state at the end of the step, before the divergence check,
        // which then sees only the survivors.
        let erased = match ctx.tools.as_deref_mut() {
            Some(tools) => tools.erase(ctx.time, ctx.particles),
            None => Vec::new(),
        };
        ctx.report.erased.clone_from(&erased);
        Effects {
            state_changed: !erased.is_empty(),
            removed: erased,
            ..Effects::default()
        }
    }
}

impl World {
    /// Brings the world's own after-step stages in line with what it uses
    /// now (after building, editing the particle set, or new tools).
    pub(super) fn sync_built_in_stages(&mut self) {
        let heat = self.params.heat.clone().map(|params| HeatStage {
            params,
            weakens: self.model.heated,
            scratch: HeatScratch::default(),
        });
        let wanted: [Option<Box<dyn AfterStep>>; 4] = [
            heat.map(|s| Box::new(s) as Box<dyn AfterStep>),
            self.model
                .bonds
                .is_some()
                .then(|| Box::new(BondBreaking) as Box<dyn AfterStep>),
            (self.plastic || self.memory_flows).then(|| {
                Box::new(PlasticFlow {
                    memory_flows: self.memory_flows,
                    curvature: self.plastic,
                    scratch: PlasticScratch::default(),
                }) as Box<dyn AfterStep>
            }),
            self.model
                .tools
                .as_ref()
                .is_some_and(|t| t.removes_particles())
                .then(|| Box::new(Erasers) as Box<dyn AfterStep>),
        ];
        self.built_in_stages = wanted.into_iter().flatten().collect();
    }

    /// Runs every after-step stage for the step of length `dt` just taken,
    /// the world's own and then the `lent` ones, timing each (the world's
    /// in `report`, the lent ones in [`World::interval_seconds`]), and
    /// applies their merged effects: the particles they name are removed,
    /// cached forces dropped once.
    pub(super) fn run_after_step_stages(
        &mut self,
        dt: Real,
        report: &mut StepReport,
        lent: &mut [&mut dyn AfterStep],
    ) -> Effects {
        let mut effects = Effects::default();
        let mut built_in = std::mem::take(&mut self.built_in_stages);
        let mut lent_seconds = std::mem::take(&mut self.model.scratch.lent_after_step_seconds);
        lent_seconds.resize(lent.len(), 0.0);
        type Timed<'s> = (&'s mut dyn AfterStep, Option<&'s mut f64>);
        let own = built_in
            .iter_mut()
            .map(|s| -> Timed<'_> { (&mut **s, None) });
        let borrowed = lent
            .iter_mut()
            .zip(lent_seconds.iter_mut())
            .map(|(s, spent)| -> Timed<'_> { (&mut **s, Some(spent)) });
        let mut edited = false;
        for (stage, spent) in own.chain(borrowed) {
            let clock = std::time::Instant::now();
            let mut ctx = AfterStepContext {
                time: self.time,
                dt,
                particles: &mut self.particles,
                materials: &self.model.materials,
                neighbours: self.model.neighbours.as_mut(),
                bonds: self.model.bonds.as_mut(),
                tools: self.model.tools.as_deref_mut(),
                report,
            };
            let e = stage.run(&mut ctx);
            if !e.removed.is_empty() {
                self.remove_live(&e.removed);
                edited = true;
            }
            let seconds = clock.elapsed().as_secs_f64();
            match spent {
                Some(total) => *total += seconds,
                None => report.seconds.push((stage.name(), seconds)),
            }
            effects.merge(e);
        }
        self.model.scratch.lent_after_step_seconds = lent_seconds;
        self.built_in_stages = built_in;
        if edited {
            // What the world uses may have changed with its particles.
            self.sync_built_in_stages();
        }
        self.apply_effects(&effects);
        effects
    }
}
