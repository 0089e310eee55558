//! The scene's stages (op-dynamics [`op_dynamics::driver::Driver`] stages acting on a
//! [`SceneState`]), in the order they run:
//!
//! 1. [`FitRelease`] (edit): frees a fit's samples at their release time
//!    (seed 000 §7);
//! 2. [`Creation`] (edit): the creation rules every `interval` steps
//!    (merging, stretching, growing; seed 000 §7), the created particles
//!    joining their object;
//! 3. op-implicit's [`ContactStage`] (forces): skin contact reactions,
//!    computed at the start of every interval of at most `dt` and held
//!    over it (seed 002 §6);
//! 4. op-implicit's [`SkinStage`] (follower): every skin gains primitives
//!    for created particles of its object, drops those of removed ones
//!    (merged, released, erased by tools), and is re-posed on the
//!    particles at the target time.
//!
//! Each stage is built only when the scene uses it
//! ([`crate::BuiltScene::stages`]).

use op_dynamics::driver::{Effects, Phase, Stage, StageError};
use op_dynamics::{Real, World};
pub use op_implicit::skin_stages::{ContactStage, SkinStage};
use op_implicit::skin_stages::{SkinParts, SkinnedState};

use crate::built_scene::BuiltObject;
use crate::creation::CreationState;
use crate::skins::{ContactStats, ObjectSkin, SkinTool};

/// What the scene's stages share: lent by [`crate::BuiltScene`] to its
/// driver during [`crate::BuiltScene::advance_to`].
#[derive(Debug, Default)]
pub struct SceneState {
    /// The objects (created particles are added to them).
    pub objects: Vec<BuiltObject>,
    /// The skins.
    pub skins: Vec<ObjectSkin>,
    /// Obstacle tools met by skins.
    pub skin_tools: Vec<SkinTool>,
    /// Contact figures.
    pub contact: ContactStats,
    /// The creation rules, when the scene has some.
    pub creation: Option<CreationState>,
}

impl SkinnedState for SceneState {
    fn skin_parts(&mut self) -> SkinParts<'_> {
        SkinParts {
            skins: &mut self.skins,
            tools: &self.skin_tools,
            contact: &mut self.contact,
        }
    }
}

fn pending_release(ctx: &SceneState) -> Option<&crate::fit::SceneFit> {
    ctx.creation
        .as_ref()
        .and_then(|c| c.fit.as_ref())
        .filter(|f| !f.released)
}

/// Frees a fit's samples at their release time.
pub struct FitRelease;

impl Stage<SceneState> for FitRelease {
    fn name(&self) -> &str {
        "fit"
    }

    fn phase(&self) -> Phase {
        Phase::Edit
    }

    fn due(&self, world: &World, ctx: &SceneState) -> bool {
        pending_release(ctx)
            .is_some_and(|f| world.time() >= f.release_time - 1e-12 * world.params().dt)
    }

    fn horizon(&self, _world: &World, ctx: &SceneState) -> Real {
        pending_release(ctx).map_or(Real::INFINITY, |f| f.release_time)
    }

    fn run(
        &mut self,
        world: &mut World,
        ctx: &mut SceneState,
        _until: Real,
    ) -> Result<Effects, StageError> {
        let Some(fit) = ctx.creation.as_mut().and_then(|c| c.fit.as_mut()) else {
            return Ok(Effects::default());
        };
        // Seed 000 §7: the samples are freed, creation stops.
        fit.released = true;
        // The surviving samples (an eraser may have removed some) keep their
        // rest positions under their new ids.
        let o = &mut ctx.objects[fit.object];
        let p = world.particles();
        let (ids, rest): (Vec<u32>, Vec<_>) = o
            .ids
            .iter()
            .zip(&o.rest)
            .filter(|(&id, _)| p.slot_of(id).is_some())
            .unzip();
        let new_ids = crate::fit::release(world, &ids)
            .map_err(|e| StageError::new("fit", format!("releasing the samples: {e}")))?;
        o.ids = new_ids.clone();
        o.rest = rest;
        Ok(Effects {
            state_changed: true,
            forces_stale: false,
            inserted: new_ids,
            removed: ids,
        })
    }
}

/// The creation rules (see [`crate::creation`]).
pub struct Creation;

impl Creation {
    fn active(ctx: &SceneState) -> Option<&CreationState> {
        ctx.creation
            .as_ref()
            .filter(|c| !c.fit.as_ref().is_some_and(|f| f.released))
    }
}

impl Stage<SceneState> for Creation {
    fn name(&self) -> &str {
        "creation"
    }

    fn phase(&self) -> Phase {
        Phase::Edit
    }

    fn due(&self, world: &World, ctx: &SceneState) -> bool {
        Self::active(ctx).is_some_and(|c| world.steps() >= c.next_step)
    }

    fn horizon(&self, world: &World, ctx: &SceneState) -> Real {
        Self::active(ctx).map_or(Real::INFINITY, |c| {
            let steps_left = c.next_step.saturating_sub(world.steps()).max(1);
            world.time() + steps_left as Real * world.params().dt
        })
    }

    fn run(
        &mut self,
        world: &mut World,
        ctx: &mut SceneState,
        _until: Real,
    ) -> Result<Effects, StageError> {
        fn err(e: impl std::fmt::Display) -> StageError {
            StageError::new("creation", e)
        }
        let Some(state) = ctx.creation.as_mut() else {
            return Ok(Effects::default());
        };
        state.next_step = world.steps() + state.params.interval;
        let fit = state.fit.as_ref();
        let created = op_modeling::creation::apply_now(world, &state.params, |d| {
            fit.is_none_or(|f| f.near.contains(&d.position))
        })
        .map_err(err)?;
        for (&object, &id) in created.objects.iter().zip(&created.inserted) {
            if let Some(o) = ctx.objects.get_mut(object as usize) {
                o.created.push(id);
            }
        }
        Ok(Effects {
            state_changed: !created.inserted.is_empty() || !created.removed.is_empty(),
            forces_stale: false,
            inserted: created.inserted,
            removed: created.removed,
        })
    }
}
