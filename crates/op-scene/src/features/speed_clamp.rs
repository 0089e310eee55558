//! A speed clamp: after every step, a particle of the chosen objects
//! moving faster than the limit is slowed to it along its direction of
//! motion. An animator's safety net against a stray fast particle (a
//! tool's sharp kick, a stiff contact); it only removes kinetic energy,
//! so a passive scene stays passive. Fixed particles are left alone.

use op_dynamics::driver::{Effects, Lent, Phase, Stage};
use op_dynamics::world::{AfterStep, AfterStepContext};
use op_dynamics::{Flags, Real};
use serde::{Deserialize, Serialize};

use super::{check_objects, object_mask, Feature, InstallContext};
use crate::error::SceneError;
use crate::schema::checks::positive;
use crate::schema::Scene;
use crate::stages::SceneState;

/// A speed limit: RON `SpeedClamp((max_speed: 5, objects: Some(["ball"])))`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpeedClamp {
    /// The largest speed a particle keeps after a step, > 0 and finite.
    /// Required.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_speed: Real,
    /// Names of the objects it limits. Default: all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objects: Option<Vec<String>>,
}

/// Units of the numeric fields (the scene reference).
pub(super) const UNITS: &[(&str, &str)] = &[("SpeedClamp.max_speed", "L/T")];

impl Feature for SpeedClamp {
    fn validate(&self, scene: &Scene, path: &str) -> Result<(), SceneError> {
        positive(
            scene.origin(),
            &format!("{path}.max_speed"),
            self.max_speed,
        )?;
        check_objects(scene, path, self.objects.as_deref())
    }

    fn stage(&self, ctx: &InstallContext<'_>) -> Box<dyn Stage<SceneState>> {
        Box::new(ClampStage {
            max_speed: self.max_speed,
            objects: object_mask(ctx.objects, self.objects.as_deref()),
        })
    }
}

/// The clamp: a stage lending an after-step action to every step.
struct ClampStage {
    max_speed: Real,
    /// Limited objects, by object id.
    objects: Vec<bool>,
}

impl Stage<SceneState> for ClampStage {
    fn name(&self) -> &str {
        "speed_clamp"
    }

    fn phase(&self) -> Phase {
        Phase::Step
    }

    fn lend(&mut self) -> Lent<'_> {
        Lent {
            contributor: None,
            after_step: Some(self),
        }
    }

    /// Clamping only removes kinetic energy: a passive scene stays
    /// passive.
    fn may_add_energy(&self) -> bool {
        false
    }
}

impl AfterStep for ClampStage {
    fn name(&self) -> &'static str {
        "speed_clamp"
    }

    fn run(&mut self, ctx: &mut AfterStepContext<'_>) -> Effects {
        let (state, _, attributes) = ctx.particles.split();
        let mut clamped = false;
        for (i, v) in state.velocities.iter_mut().enumerate() {
            let limited = self.objects.get(attributes.objects[i] as usize) == Some(&true);
            let speed = v.norm();
            if limited && speed > self.max_speed && !attributes.flags[i].contains(Flags::FIXED_POSITION) {
                *v *= self.max_speed / speed;
                clamped = true;
            }
        }
        // Velocity-dependent forces (damping, wind) cached at the end of
        // the step read the old velocities.
        Effects {
            forces_stale: clamped,
            ..Effects::default()
        }
    }
}
