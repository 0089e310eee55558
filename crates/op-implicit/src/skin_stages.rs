//! The skin stages of a simulation driver (op-dynamics
//! [`op_dynamics::driver`]): skins that follow their objects' particles,
//! and skin contact (seed 002 §6).
//!
//! - [`ContactStage`] (forces): the reactions of every pair of skins and
//!   of every skin against the obstacle tools it meets act as a force
//!   contributor evaluated at every force evaluation of a step, on the
//!   state being evaluated ([`ContactForces`]; [`World::advance_to_with`]):
//!   contact scenes keep the integrator's order, and velocity Verlet
//!   evaluates its forces once per step. Before each interval of at most
//!   `dt` the stage refreshes the contributor's snapshot of the skins and
//!   adds the last evaluation's figures to the run's.
//! - [`SkinStage`] (follower): every skin gains primitives for created
//!   particles of its object, drops those of removed ones (merged,
//!   released, erased by tools), and is re-posed on the particles at the
//!   target time.
//!
//! Both act on any driver state that lends its skins ([`SkinnedState`]).

use op_dynamics::driver::{Effects, Lent, Phase, Stage, StageError};
use op_dynamics::{Real, World};

use crate::contact_forces::ContactForces;
use crate::object_skin::{ContactStats, ObjectSkin, SkinTool};

/// What the skin stages borrow of a driver's shared state.
pub struct SkinParts<'a> {
    /// The skins, one per skinned object.
    pub skins: &'a mut [ObjectSkin],
    /// The obstacle tools skins meet.
    pub tools: &'a [SkinTool],
    /// The contact figures, accumulated.
    pub contact: &'a mut ContactStats,
}

/// A driver state that holds skins.
pub trait SkinnedState {
    /// The skins, the tools they meet and the contact figures.
    fn skin_parts(&mut self) -> SkinParts<'_>;
}

/// Skin contact: a force contributor evaluated at every force evaluation
/// ([`ContactForces`], module docs), its snapshot of the skins refreshed
/// before each interval of at most `dt`, when the figures of the last
/// evaluation are added to the run's.
#[derive(Default)]
pub struct ContactStage {
    forces: ContactForces,
    /// When the figures were last added to the run's.
    folded: Option<Real>,
}

impl ContactStage {
    /// Adds the last evaluation's figures over the time since they were
    /// last added (its force times that time) to `stats`, or fails with
    /// the error the evaluations met.
    fn fold(&mut self, now: Real, stats: &mut ContactStats) -> Result<(), StageError> {
        let (figures, error) = self.forces.take_last();
        if let Some(e) = error {
            return Err(StageError::new("contact", e));
        }
        if let Some(from) = self.folded {
            stats.total_impulse += figures.force * (now - from).max(0.0);
        }
        stats.max_penetration = stats.max_penetration.max(figures.max_penetration);
        self.folded = Some(now);
        Ok(())
    }
}

impl<C: SkinnedState> Stage<C> for ContactStage {
    fn name(&self) -> &str {
        "contact"
    }

    fn phase(&self) -> Phase {
        Phase::Forces
    }

    fn due(&self, _world: &World, _ctx: &C) -> bool {
        true
    }

    fn horizon(&self, world: &World, _ctx: &C) -> Real {
        world.time() + world.params().dt
    }

    /// An interval within 1e-6 steps of the target takes all of it, as
    /// [`World::advance_to`] does for its last step.
    fn slack(&self, world: &World) -> Real {
        1e-6 * world.params().dt
    }

    fn run(&mut self, world: &mut World, ctx: &mut C, _until: Real) -> Result<Effects, StageError> {
        let parts = ctx.skin_parts();
        self.fold(world.time(), parts.contact)?;
        self.forces
            .update(parts.skins, parts.tools, world.params().dt);
        Ok(Effects::default())
    }

    fn lend(&mut self) -> Lent<'_> {
        Lent {
            contributor: Some(&self.forces),
            after_step: None,
        }
    }

    fn at_target(&mut self, world: &World, ctx: &mut C) -> Result<(), StageError> {
        self.fold(world.time(), ctx.skin_parts().contact)
    }
}

/// Skins follow their objects' particles (module docs).
pub struct SkinStage;

impl<C: SkinnedState> Stage<C> for SkinStage {
    fn name(&self) -> &str {
        "skin"
    }

    fn phase(&self) -> Phase {
        Phase::Edit
    }

    fn notify(&mut self, world: &World, ctx: &mut C, effects: &Effects) -> Result<(), StageError> {
        let p = world.particles();
        for s in ctx.skin_parts().skins.iter_mut() {
            s.detach(&effects.removed);
            let object = s.object as u32;
            let new: Vec<u32> = effects
                .inserted
                .iter()
                .copied()
                .filter(|&id| p.slot_of(id).is_some_and(|k| p.objects()[k] == object))
                .collect();
            s.attach(&new);
        }
        Ok(())
    }

    fn at_target(&mut self, world: &World, ctx: &mut C) -> Result<(), StageError> {
        for s in ctx.skin_parts().skins.iter_mut() {
            s.repose(world)
                .map_err(|e| StageError::new("skin", format!("posing {}: {e}", s.name)))?;
        }
        Ok(())
    }
}
