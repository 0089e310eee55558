//! The world's own stages after every step, in this order, each only in a
//! world that uses it (pay for what you use):
//!
//! 1. **heat** ([`crate::heat`], seed 000 §6 and §8): heat sources at the
//!    step's end time, conduction over the interacting pairs, cooling; a
//!    world whose materials weaken with heat then has stale cached forces;
//! 2. **bonds** ([`crate::bonds`], seed 000 fig. 12c): bonds stretched
//!    beyond their break length break for good;
//! 3. **plasticity** (seed 000 fig. 12b): the remembered offsets of bond
//!    memories flow toward the current ones beyond their yield
//!    ([`crate::bond_memory`]), then the remembered curvatures toward the
//!    current ones beyond the yield curvature ([`crate::plasticity`]);
//!    changed memories make cached forces stale;
//! 4. **erase** (seed 000 fig. 7 and 14): erasers and trapping shapers
//!    remove particles.
//!
//! Each returns its [`Effects`]; [`World::step`] merges them, drops cached
//! forces once if any asked, and keeps the removed particles for the
//! driver ([`World::take_effects`]), which tells its stages (a skin drops
//! the primitives of erased particles).

use super::{Stage, StepReport, World};
use crate::bond_memory;
use crate::driver::Effects;
use crate::heat;
use crate::math::Real;
use crate::plasticity;

impl World {
    /// The after-step stages this world uses, in order.
    pub(super) fn after_step_stages(&self) -> impl Iterator<Item = Stage> {
        let uses = [
            (Stage::Heat, self.params.heat.is_some()),
            (Stage::Bonds, self.model.bonds.is_some()),
            (Stage::Plasticity, self.plastic || self.memory_flows),
            (
                Stage::Erase,
                self.model
                    .tools
                    .as_ref()
                    .is_some_and(|t| t.removes_particles()),
            ),
        ];
        uses.into_iter().filter(|u| u.1).map(|u| u.0)
    }

    /// Runs after-step stage `stage` for the step of length `dt` just taken
    /// and records what it did in `report`.
    pub(super) fn run_after_step(
        &mut self,
        stage: Stage,
        dt: Real,
        report: &mut StepReport,
    ) -> Effects {
        let mut effects = Effects::default();
        match stage {
            Stage::Heat => effects.forces_invalid = self.advance_heat(dt),
            Stage::Bonds => {
                if let Some(bonds) = self.model.bonds.as_mut() {
                    report.bonds_broken = bonds.break_stretched(&self.particles);
                }
            }
            Stage::Plasticity => {
                if let (true, Some(bonds)) = (self.memory_flows, self.model.bonds.as_mut()) {
                    effects.forces_invalid |=
                        bond_memory::flow(bonds, &self.particles, &self.model.materials, dt);
                }
                if let (true, Some(list)) = (self.plastic, self.model.neighbours.as_mut()) {
                    // Cached forces were computed with the old curvatures.
                    effects.forces_invalid |= plasticity::apply(
                        &mut self.particles,
                        &self.model.materials,
                        list,
                        self.model.bonds.as_ref(),
                        dt,
                        &mut self.plastic_scratch,
                    );
                }
            }
            Stage::Erase => {
                // On the state at the end of the step, before the divergence
                // check, which then sees only the survivors.
                let erased = match self.model.tools.as_mut() {
                    Some(tools) => tools.erase(self.time, &self.particles),
                    None => Vec::new(),
                };
                if !erased.is_empty() {
                    self.remove_live(&erased);
                    effects.forces_invalid = true;
                    effects.removed.clone_from(&erased);
                }
                report.erased = erased;
            }
            Stage::Reorder | Stage::Neighbours | Stage::Integrate | Stage::Check => {}
        }
        effects
    }

    /// Advances the temperatures over the step just taken (sources at its
    /// end time, conduction over the pairs within the interaction cut-off,
    /// cooling; [`crate::heat`]). Returns whether cached forces are stale:
    /// when some material weakens with heat they were computed at the old
    /// temperatures.
    fn advance_heat(&mut self, dt: Real) -> bool {
        let Some(params) = &self.params.heat else {
            return false;
        };
        let pairs = self.model.neighbours.as_mut().map(|list| {
            list.update(self.particles.positions());
            list.build_incoming();
            let cutoff = list.cutoff();
            (&*list, cutoff)
        });
        let pairs = pairs.map(|(l, c)| (l.pairs(), c));
        let (positions, objects, temperatures) = self.particles.heat_view();
        heat::advance(
            params,
            self.model.tools.as_deref(),
            self.time,
            dt,
            positions,
            objects,
            pairs,
            temperatures,
            &mut self.heat_scratch,
        );
        self.model.heated
    }
}
