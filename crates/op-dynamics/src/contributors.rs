//! Force contributors: everything besides the pair interactions that adds
//! forces and torques in a force evaluation (seed 000 §4, eq. 12-13: the
//! external forces and the damping of the equations of motion).
//!
//! A [`Contributor`] adds to every particle's force, torque and energy at
//! one state and time. Every force evaluation of a step (each stage of a
//! Runge–Kutta scheme, each half kick of velocity Verlet) asks the
//! contributors in one fixed order, after the pair kernel:
//!
//! 1. the tools ([`crate::tooling::ToolSet`], op-modeling `tools`: obstacles, attractors, movers,
//!    with their energies);
//! 2. the uniform field ([`crate::external::UniformField`]: gravity, linear
//!    and angular damping, the cold drag of heated materials);
//! 3. pending forces ([`crate::World::add_external_force`], for one step);
//! 4. the contributors the caller passes for the interval
//!    ([`crate::World::advance_to_with`]): the driver passes those its
//!    stages lend ([`crate::driver::Stage::lend`]), in the driver's order
//!    (op-scene's features, such as wind, then op-implicit's skin contact);
//! 5. the force windows ([`crate::external::ForceWindows`]);
//!
//! and finally fixed particles get zero force or torque. Each particle's
//! sum is formed in this order whatever the thread count, so results are
//! the same bits at any thread count. The world builds only the
//! contributors a scene uses: a world without tools, gravity, damping or
//! windows pays for none of them.

use crate::integrators::StateRef;
use crate::interactions::PreparedMaterial;
use crate::math::{Real, Vec3};
use crate::particles::{live_slot, Attributes};

/// Names of the contributors every world may have (tools, uniform field,
/// pending forces, force windows): a driver stage may not take them
/// ([`crate::driver::RESERVED`]).
pub const BUILT_IN: [&str; 4] = [
    "tools",
    "gravity and damping",
    "pending forces",
    "force windows",
];

/// What a contributor reads: the time, the state being evaluated and the
/// particles' attributes (by slot).
pub struct ContributorInput<'a> {
    /// Time of the evaluated state.
    pub t: Real,
    /// Start time of the step being taken, when evaluating inside one
    /// (force windows are evaluated from inside the step,
    /// [`crate::external::ForceWindow::factor_within`]).
    pub step_start: Option<Real>,
    /// The state (by slot).
    pub state: StateRef<'a>,
    /// Ids, objects, masses, flags, ... (by slot).
    pub attributes: &'a Attributes<'a>,
    /// The prepared materials, indexed by `attributes.materials`.
    pub materials: &'a [PreparedMaterial],
}

impl ContributorInput<'_> {
    /// Slot of particle `id`, `None` when it was removed or never existed.
    #[inline]
    pub fn slot(&self, id: u32) -> Option<usize> {
        live_slot(self.attributes.slot_of, id)
    }
}

/// Where a contributor adds (by slot).
pub struct Contribution<'a> {
    /// Forces.
    pub forces: &'a mut [Vec3],
    /// Torques (world frame, about the particle's position).
    pub torques: &'a mut [Vec3],
    /// Potential energy attributed to each particle (only contributors
    /// with an energy, the tools, add to it).
    pub energies: &'a mut [Real],
}

/// Something that adds forces and torques in every force evaluation; see
/// the [module docs](self) for the order.
pub trait Contributor: Sync {
    /// Name, for listings.
    fn name(&self) -> &str;

    /// Whether it adds anything at all (an inactive contributor is
    /// skipped, and does not make cached forces stale).
    fn is_active(&self) -> bool {
        true
    }

    /// Whether it may add a torque: a world whose pair kernel never turns
    /// particles then integrates rotations too.
    fn adds_torque(&self) -> bool {
        false
    }

    /// Whether its contribution is a function of the evaluated state and
    /// time alone, the same whichever interval of
    /// [`crate::World::advance_to_with`] evaluates it (op-implicit's skin
    /// contact, evaluated at every force evaluation): the forces cached at
    /// an interval's end stay valid for the next one. Default: false (a
    /// contribution computed once per interval and held over it).
    fn follows_state(&self) -> bool {
        false
    }

    /// Adds its forces, torques and energies at `input`'s state to `out`.
    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>);
}
