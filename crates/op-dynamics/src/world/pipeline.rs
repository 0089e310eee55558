//! What the world's pipeline holds, as callers see it: the names of what
//! it evaluates and its stages in order. What a caller adds (forces,
//! actions after every step) is a driver stage
//! ([`crate::driver::Stage::lend`]), listed by the driver.

use super::{World, CORE_STAGES};
use crate::math::Vec3;

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
        out
    }

    /// The names of the stages of a step, in order: [`CORE_STAGES`] with
    /// the world's after-step stages before `check`.
    pub fn stage_names(&self) -> Vec<&'static str> {
        let after = self.built_in_stages.iter().map(|s| s.name());
        CORE_STAGES[..3]
            .iter()
            .copied()
            .chain(after)
            .chain(std::iter::once(CORE_STAGES[3]))
            .collect()
    }
}
