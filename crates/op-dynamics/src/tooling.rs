//! What a world needs of its tools (seed 000 §6): the interface through
//! which the modeling tools (op-modeling `tools`: obstacles, attractors,
//! movers, erasers, knives, heaters, shapers) act on a world without the
//! world knowing their shapes, paths or roles.
//!
//! A [`ToolSet`] is three things to the world, each at its place in a step:
//!
//! - a force [`Contributor`], asked first in every force evaluation
//!   ([`crate::contributors`]: tools, then the uniform field, ...);
//! - heat sources, asked by the heat stage after each step before
//!   conduction and cooling ([`crate::heat`]);
//! - an eraser, asked last after each step for the particles to remove
//!   (only when [`ToolSet::removes_particles`]).
//!
//! A world without tools ([`crate::World::set_tools`] never called) pays
//! for none of these.

use std::any::Any;

use crate::checkpoint::StateError;
use crate::contributors::Contributor;
use crate::math::{Point3, Real};
use crate::particles::Particles;

/// The tools of a world (see the module docs).
pub trait ToolSet: Contributor + std::fmt::Debug + Send + Sync {
    /// Whether some tool heats (a heater or a knife): the world then
    /// needs heat settings ([`crate::WorldParams::heat`]).
    fn heats(&self) -> bool;

    /// Adds `dt` times each tool's heating rate at time `t` to the
    /// temperatures (by slot, like `positions` and `objects`).
    fn add_heat(
        &self,
        t: Real,
        dt: Real,
        positions: &[Point3],
        objects: &[u32],
        temperatures: &mut [Real],
    );

    /// Whether the tools can delete particles: the world asks
    /// [`ToolSet::erase`] after each step only then.
    fn removes_particles(&self) -> bool;

    /// Stable ids, increasing and without repeats, of the particles the
    /// tools remove at time `t` (the state at the end of a step). The
    /// world removes them; the result must depend only on the positions,
    /// not on the thread count.
    fn erase(&mut self, t: Real, particles: &Particles) -> Vec<u32>;

    /// The names of the tools' roles, one per tool in order (for
    /// [`crate::World::enabled`], as `tool:<role>`).
    fn roles(&self) -> Vec<&'static str>;

    /// The set as [`Any`], so that its owner can read it back with its
    /// concrete type ([`crate::World::tools`]).
    fn as_any(&self) -> &dyn Any;

    /// What the tools change as the run goes on (the particles a grabbing
    /// tool holds), encoded ([`crate::checkpoint::encode`]), for a
    /// checkpoint ([`crate::World::state`]). Default: nothing.
    fn save_state(&self) -> Vec<u8> {
        Vec::new()
    }

    /// Puts back what [`ToolSet::save_state`] returned, leaving the tools
    /// unchanged when it fails. Default: accepts only the empty state.
    fn restore_state(&mut self, state: &[u8]) -> Result<(), StateError> {
        crate::checkpoint::no_state("tools", state)
    }
}
