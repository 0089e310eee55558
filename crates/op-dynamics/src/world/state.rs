//! Taking and restoring a world's state ([`crate::checkpoint`]).

use super::{Config, World};
use crate::checkpoint::{encode_parts, StateError, StateRef, WorldState};

impl World {
    /// Everything the world changes as it steps, to restore later with
    /// [`World::restore`] ([`crate::checkpoint`]). Take it between steps.
    pub fn state(&self) -> WorldState {
        WorldState {
            particles: self.particles.clone(),
            integrator: self.integrator.clone(),
            neighbours: self.model.neighbours.clone(),
            bonds: self.model.bonds.clone(),
            tools: self.model.tools.as_ref().map(|t| t.save_state()),
            accumulator: self.accumulator.clone(),
            forces: self.forces.clone(),
            torques: self.torques.clone(),
            prev_positions: self.prev_positions.clone(),
            time: self.time,
            steps: self.steps,
            dt_next: self.dt_next,
            may_rotate: self.may_rotate,
            forced_in_a_row: self.forced_in_a_row,
        }
    }

    /// [`crate::checkpoint::encode_state`] of [`World::state`], without
    /// taking (copying) the state: the parts of its encoding, encoded side
    /// by side.
    pub fn encode_state(&self) -> Vec<Vec<u8>> {
        encode_parts(StateRef {
            particles: &self.particles,
            integrator: &self.integrator,
            neighbours: &self.model.neighbours,
            bonds: &self.model.bonds,
            tools: self.model.tools.as_ref().map(|t| t.save_state()),
            accumulator: &self.accumulator,
            forces: &self.forces,
            torques: &self.torques,
            prev_positions: &self.prev_positions,
            scalars: (
                self.time,
                self.steps,
                self.dt_next,
                self.may_rotate,
                self.forced_in_a_row,
            ),
        })
    }

    /// Puts back a state taken by [`World::state`] from a world built from
    /// the same inputs (materials, parameters, tools):
    /// the world then steps exactly as the one the state was taken from.
    /// What depends on the particle set (kernel, neighbour radius, the
    /// after-step stages in use) is derived again.
    ///
    /// A state that does not fit this world (other materials, integrator,
    /// tools, or arrays of inconsistent sizes) is refused, and the world is
    /// left as it was.
    pub fn restore(&mut self, state: WorldState) -> Result<(), StateError> {
        let fail = |what: &str| {
            Err(StateError(format!(
                "the state does not fit the world: {what}"
            )))
        };
        let p = &state.particles;
        let n = p.len();
        if !p.is_consistent() {
            return fail("its particle arrays are inconsistent");
        }
        if let Some(&m) = p
            .materials()
            .iter()
            .find(|&&m| m as usize >= self.model.materials.len())
        {
            return fail(&format!(
                "a particle has material {m}, the world has {}",
                self.model.materials.len()
            ));
        }
        if state.integrator.scheme() != self.params.scheme {
            return fail("it was taken with another integrator");
        }
        if state.tools.is_some() != self.model.tools.is_some() {
            return fail("tools in one and not in the other");
        }
        if state.bonds.is_some() != self.model.bonds.is_some() {
            return fail("bonds in one and not in the other");
        }
        if [
            state.forces.len(),
            state.torques.len(),
            state.prev_positions.len(),
        ] != [n; 3]
            || state.accumulator.capacity() < p.id_bound()
        {
            return fail("its force or position arrays do not match its particles");
        }
        let config = Config::of(p, &self.model.materials);
        let list_fits = match (&state.neighbours, config.kernel) {
            (None, super::Kernel::None) => true,
            (Some(l), k) => {
                k != super::Kernel::None && l.cutoff() == config.cutoff && l.is_consistent(n)
            }
            (None, _) => false,
        };
        if !list_fits {
            return fail("its neighbour list does not match its particles");
        }
        if let (Some(tools), Some(saved)) = (self.model.tools.as_mut(), &state.tools) {
            tools.restore_state(saved)?;
        }
        self.apply_config(&config);
        self.model.neighbours = state.neighbours;
        self.model.scratch.forget_lists();
        self.model.bonds = state.bonds;
        self.particles = state.particles;
        self.integrator = state.integrator;
        self.accumulator = state.accumulator;
        self.forces = state.forces;
        self.torques = state.torques;
        self.prev_positions = state.prev_positions;
        self.time = state.time;
        self.steps = state.steps;
        self.dt_next = state.dt_next;
        self.may_rotate = state.may_rotate;
        self.forced_in_a_row = state.forced_in_a_row;
        self.effects = Default::default();
        self.sync_built_in_stages();
        Ok(())
    }
}
