//! Wind: every particle of the chosen objects is dragged toward the air's
//! velocity, `F = c (w(t) - v)`. It is the linear damping of seed 000 eq.
//! 12 (`-β0 v`) taken relative to moving air instead of still air, so a
//! particle left to the wind drifts at the air's speed; gusts change `w`
//! over time along keyframes. Drag does work and has no energy: a scene
//! with wind is not passive.

use op_dynamics::contributors::{Contribution, Contributor, ContributorInput};
use op_dynamics::driver::{Lent, Phase, Stage};
use op_dynamics::{Real, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{check_objects, object_mask, Feature, InstallContext};
use crate::error::SceneError;
use crate::schema::checks::{finite, finite3, positive};
use crate::schema::Scene;
use crate::stages::SceneState;

/// A wind on some objects: RON `Wind((velocity: (2, 0, 0), drag: 0.1))`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Wind {
    /// The air's velocity (finite). Default: still air.
    #[serde(default)]
    pub velocity: [Real; 3],
    /// Drag coefficient `c`: the force on a particle per unit of its speed
    /// relative to the air, > 0 and finite. Required.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub drag: Real,
    /// Gusts: keyframes of a velocity added to `velocity`, interpolated
    /// linearly between keyframes and held before the first and after the
    /// last; times in scene time (from the end of the settle phase),
    /// strictly increasing. Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gusts: Vec<Gust>,
    /// Names of the objects it blows on. Default: all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objects: Option<Vec<String>>,
}

/// A keyframe of [`Wind::gusts`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Gust {
    /// Scene time of the keyframe (finite).
    pub time: Real,
    /// The velocity added to the wind's at that time (finite).
    pub velocity: [Real; 3],
}

/// Units of the numeric fields (the scene reference).
pub(super) const UNITS: &[(&str, &str)] = &[
    ("Wind.velocity", "L/T"),
    ("Wind.drag", "M/T"),
    ("Gust.time", "T"),
    ("Gust.velocity", "L/T"),
];

impl Feature for Wind {
    fn validate(&self, scene: &Scene, path: &str) -> Result<(), SceneError> {
        let file = scene.origin();
        finite3(file, &format!("{path}.velocity"), &self.velocity)?;
        positive(file, &format!("{path}.drag"), self.drag)?;
        for (k, g) in self.gusts.iter().enumerate() {
            let at = format!("{path}.gusts[{k}]");
            finite(file, &format!("{at}.time"), g.time)?;
            if k > 0 && g.time <= self.gusts[k - 1].time {
                return Err(SceneError::value(
                    file,
                    format!("{at}.time"),
                    g.time,
                    "keyframe times must increase strictly",
                ));
            }
            finite3(file, &format!("{at}.velocity"), &g.velocity)?;
        }
        check_objects(scene, path, self.objects.as_deref())
    }

    fn stage(&self, ctx: &InstallContext<'_>) -> Box<dyn Stage<SceneState>> {
        Box::new(WindForce {
            velocity: Vec3::from(self.velocity),
            drag: self.drag,
            gusts: self
                .gusts
                .iter()
                .map(|g| (ctx.settle + g.time, Vec3::from(g.velocity)))
                .collect(),
            objects: object_mask(ctx.objects, self.objects.as_deref()),
        })
    }
}

/// The wind as a force contributor, lent to every step by its stage.
struct WindForce {
    velocity: Vec3,
    drag: Real,
    /// Gust keyframes in world time.
    gusts: Vec<(Real, Vec3)>,
    /// Blown objects, by object id.
    objects: Vec<bool>,
}

impl WindForce {
    /// The air's velocity at world time `t`.
    fn air(&self, t: Real) -> Vec3 {
        let gust = match self.gusts.iter().position(|(time, _)| *time > t) {
            None => self.gusts.last().map_or(Vec3::zeros(), |g| g.1),
            Some(0) => self.gusts[0].1,
            Some(k) => {
                let ((t0, v0), (t1, v1)) = (self.gusts[k - 1], self.gusts[k]);
                v0 + (v1 - v0) * ((t - t0) / (t1 - t0))
            }
        };
        self.velocity + gust
    }
}

impl Stage<SceneState> for WindForce {
    fn name(&self) -> &str {
        "wind"
    }

    fn phase(&self) -> Phase {
        Phase::Step
    }

    fn lend(&mut self) -> Lent<'_> {
        Lent {
            contributor: Some(self),
            after_step: None,
        }
    }

    // The default `may_add_energy`, true: drag does work and has no
    // energy, so a scene with wind is not passive.

    /// The largest air speed, which the explosion check allows.
    fn speed_allowance(&self) -> Real {
        let gust = self.gusts.iter().map(|g| g.1.norm()).fold(0.0, Real::max);
        self.velocity.norm() + gust
    }
}

impl Contributor for WindForce {
    fn name(&self) -> &str {
        "wind"
    }

    /// The drag at a state and time: forces cached at an interval's end
    /// stay valid for the next.
    fn follows_state(&self) -> bool {
        true
    }

    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>) {
        let w = self.air(input.t);
        let objects = input.attributes.objects;
        let v = input.state.velocities;
        let forces = out.forces.par_iter_mut();
        let forces = forces.with_min_len(op_dynamics::MIN_PARALLEL_LEN);
        forces.enumerate().for_each(|(i, f)| {
            if self.objects.get(objects[i] as usize) == Some(&true) {
                *f += self.drag * (w - v[i]);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gusts_interpolate_and_hold() {
        let wind = WindForce {
            velocity: Vec3::new(1.0, 0.0, 0.0),
            drag: 1.0,
            gusts: vec![(1.0, Vec3::zeros()), (2.0, Vec3::new(0.0, 4.0, 0.0))],
            objects: vec![true],
        };
        assert_eq!(wind.air(0.0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(wind.air(1.5), Vec3::new(1.0, 2.0, 0.0));
        assert_eq!(wind.air(9.0), Vec3::new(1.0, 4.0, 0.0));
        assert_eq!(Stage::<SceneState>::speed_allowance(&wind), 5.0);
    }
}
