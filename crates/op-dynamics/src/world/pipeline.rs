//! What the world's pipeline holds, as callers see it: the names of what
//! it evaluates, its stages in order, and the force contributors callers
//! register ([`World::add_contributor`]; after-step stages are registered
//! with [`World::add_after_step`]).

use super::{World, WorldError, CORE_STAGES};
use crate::contributors::Contributor;
use crate::math::{Real, Vec3};

impl World {
    /// Names of what this world evaluates: the kernel, each enabled
    /// interaction term of the materials in use, and the external actions.
    pub fn enabled(&self) -> Vec<String> {
        let mut out = vec![format!("kernel:{:?}", self.model.kernel).to_lowercase()];
        let mut terms: Vec<&'static str> = Vec::new();
        let mut seen = vec![false; self.model.materials.len()];
        self.particles
            .materials()
            .iter()
            .for_each(|&m| seen[m as usize] = true);
        for (m, s) in self.model.materials.iter().zip(seen) {
            if s {
                for t in m.enabled_terms() {
                    if (t != "repulsion" || self.repulsion) && !terms.contains(&t) {
                        terms.push(t);
                    }
                }
            }
        }
        out.extend(terms.iter().map(|t| format!("term:{t}")));
        if self.model.friction {
            out.push("friction".into());
        }
        if self.model.heated {
            out.push("heat_weakening".into());
        }
        if self.params.heat.is_some() {
            out.push("heat".into());
        }
        let e = &self.params.external;
        if e.gravity() != Vec3::zeros() {
            out.push("gravity".into());
        }
        if e.linear_damping > 0.0 || e.angular_damping > 0.0 {
            out.push("damping".into());
        }
        if !e.forces.is_empty() {
            out.push("force_windows".into());
        }
        if let Some(tools) = &self.model.tools {
            out.extend(tools.roles().into_iter().map(|r| format!("tool:{r}")));
        }
        out.extend(self.model.contributors.iter().map(|c| c.name().to_string()));
        out.extend(self.registered_stages.iter().map(|s| s.name().to_string()));
        out
    }

    /// Adds a force contributor to every force evaluation of every step,
    /// after the pending forces and before the interval's and the force
    /// windows ([`crate::contributors`] gives the order); contributors
    /// registered earlier come first. Cached forces are dropped.
    ///
    /// # Errors
    ///
    /// A contributor of the same name is already in the world.
    pub fn add_contributor(
        &mut self,
        contributor: Box<dyn Contributor + Send>,
    ) -> Result<(), WorldError> {
        let name = contributor.name();
        if crate::contributors::BUILT_IN.contains(&name)
            || self.model.contributors.iter().any(|c| c.name() == name)
        {
            return Err(WorldError::DuplicateName {
                kind: "force contributor",
                name: name.to_string(),
            });
        }
        self.may_rotate |= contributor.adds_torque();
        self.model.contributors.push(contributor);
        self.invalidate_forces();
        Ok(())
    }

    /// Whether some contributor or after-step stage a caller registered
    /// ([`World::add_contributor`], [`World::add_after_step`]) may add
    /// energy to the scene.
    pub fn registered_may_add_energy(&self) -> bool {
        self.model.contributors.iter().any(|c| c.may_add_energy())
            || self.registered_stages.iter().any(|s| s.may_add_energy())
    }

    /// The largest speed the registered contributors can give a particle
    /// on their own ([`Contributor::speed_allowance`]): what an explosion
    /// check allows beyond gravity and the initial velocities.
    pub fn registered_speed_allowance(&self) -> Real {
        self.model
            .contributors
            .iter()
            .map(|c| c.speed_allowance())
            .fold(0.0, Real::max)
    }

    /// The names of the stages of a step, in order: [`CORE_STAGES`] with
    /// the world's after-step stages before `check`.
    pub fn stage_names(&self) -> Vec<&'static str> {
        let after = self
            .built_in_stages
            .iter()
            .chain(&self.registered_stages)
            .map(|s| s.name());
        CORE_STAGES[..3]
            .iter()
            .copied()
            .chain(after)
            .chain(std::iter::once(CORE_STAGES[3]))
            .collect()
    }
}
