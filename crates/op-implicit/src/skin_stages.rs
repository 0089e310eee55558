//! The skin stages of a simulation driver (op-dynamics
//! [`op_dynamics::driver`]): skins that follow their objects' particles,
//! and skin contact (seed 002 §6).
//!
//! - [`ContactStage`] (forces): before every interval of at most `dt` the
//!   skins are re-posed on the particles and [`contact_step`] computes the
//!   reactions of every pair of skins and of every skin against the
//!   obstacle tools it meets; they act over the interval as a force
//!   contributor ([`op_dynamics::contributors`],
//!   [`World::advance_to_with`]). With the adaptive scheme an interval may
//!   take several steps and the reactions act on all of them: contact is
//!   explicit, one evaluation per interval, so contact scenes are first
//!   order in `dt` whatever the scheme.
//! - [`SkinStage`] (follower): every skin gains primitives for created
//!   particles of its object, drops those of removed ones (merged,
//!   released, erased by tools), and is re-posed on the particles at the
//!   target time.
//!
//! Both act on any driver state that lends its skins ([`SkinnedState`]).

use op_dynamics::contributors::Contributor;
use op_dynamics::driver::{Effects, Phase, Stage, StageError};
use op_dynamics::external::ExternalAccumulator;
use op_dynamics::{Real, World};

use crate::object_skin::{contact_step, ContactStats, ObjectSkin, SkinTool};

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

/// Skin contact: reactions computed at the start of each interval of at
/// most `dt` and acting over it as a force contributor (module docs).
#[derive(Default)]
pub struct ContactStage {
    /// The reactions of the current interval, by particle id.
    held: ExternalAccumulator,
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

    fn run(&mut self, world: &mut World, ctx: &mut C, until: Real) -> Result<Effects, StageError> {
        let h = until - world.time();
        let parts = ctx.skin_parts();
        contact_step(
            world,
            parts.skins,
            parts.tools,
            h,
            parts.contact,
            &mut self.held,
        )
        .map_err(|e| StageError::new("contact", e))?;
        Ok(Effects::default())
    }

    fn contributor(&self) -> Option<&dyn Contributor> {
        Some(&self.held)
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
