//! External actions (seed 000 eq. 12-13): gravity, forces on particle sets
//! over time windows, linear and angular damping, and the per-particle
//! force/torque accumulator other crates (op-implicit contact, tools) use to
//! act on particles during the next step.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::contributors::{Contribution, Contributor, ContributorInput};
use crate::interactions::PreparedMaterial;

use crate::error::{self, ParamError};
use crate::math::{Real, Vec3};

/// A force applied to a set of particles during a time window, with an
/// optional linear ramp at both ends (ramped loading and unloading avoid
/// the dynamic overshoot of step loads, docs/model.md §7).
///
/// The magnitude factor is 0 before `start`, rises linearly to 1 over
/// `ramp`, stays 1, and falls linearly to 0 over `ramp` ending at `end`.
///
/// **Step boundaries.** A step load (`ramp = 0`) jumps at `start` and
/// `end`. The world evaluates it from inside the step being taken
/// ([`ForceWindow::factor_within`]): at the step's start time as it is just
/// after, at later times (stages, end) as it was just before. So a window starting at a
/// step boundary acts in the steps after it and in none that ends there,
/// whether the scheme evaluates forces at the start of a step (Euler) or
/// at its end (velocity Verlet's second half kick, the last Runge–Kutta
/// stage); likewise a window ending at a step boundary acts in the step
/// that ends there and in none after. op-scene's force windows count from
/// the end of the settle phase, so one starting at scene time 0 does not
/// touch the settled state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ForceWindow {
    /// Particle ids the force acts on (each gets the full force).
    pub particles: Vec<u32>,
    /// The force vector at full magnitude.
    pub force: [Real; 3],
    /// Start time. Default: 0.
    #[serde(default)]
    pub start: Real,
    /// End time (> start). Default: infinity.
    #[serde(default = "infinity")]
    pub end: Real,
    /// Ramp duration at each end, >= 0 and at most half the window.
    /// Default: 0 (a step load).
    #[serde(default)]
    pub ramp: Real,
}

fn infinity() -> Real {
    Real::INFINITY
}

impl ForceWindow {
    /// Checks the window: finite force, `start < end`, a ramp that fits.
    pub fn validate(&self, particle_count: usize) -> Result<(), ParamError> {
        for f in self.force {
            error::finite("force", f)?;
        }
        error::finite("start", self.start)?;
        error::check(
            "end",
            self.end,
            !self.end.is_nan() && self.end > self.start,
            "must be greater than `start` (or infinite)",
        )?;
        error::non_negative("ramp", self.ramp)?;
        error::check(
            "ramp",
            self.ramp,
            2.0 * self.ramp <= self.end - self.start,
            "must be at most half of `end - start`",
        )?;
        if let Some(&bad) = self
            .particles
            .iter()
            .find(|&&p| p as usize >= particle_count)
        {
            return Err(ParamError::Invalid {
                field: "particles".into(),
                message: format!(
                    "particle id {bad} does not exist (valid ids: 0..{particle_count})"
                ),
            });
        }
        Ok(())
    }

    /// The magnitude factor in [0, 1] at time `t` (on from `start`
    /// included to `end` excluded).
    pub fn factor(&self, t: Real) -> Real {
        self.one_sided(t, false)
    }

    /// The magnitude factor at time `t` seen from inside the step that
    /// starts at `step_start`: the limit from the right at `t <= step_start`
    /// (the step's start), from the left at later times (its stages and
    /// end, however long the step turns out; see the type's docs). The two
    /// limits differ only at the jumps of a step load.
    pub fn factor_within(&self, t: Real, step_start: Real) -> Real {
        self.one_sided(t, t > step_start)
    }

    /// The factor's limit at `t` from the left (`from_left`) or from the
    /// right.
    fn one_sided(&self, t: Real, from_left: bool) -> Real {
        let off = if from_left {
            t <= self.start || t > self.end
        } else {
            t < self.start || t >= self.end
        };
        if off {
            return 0.0;
        }
        if self.ramp <= 0.0 {
            return 1.0;
        }
        let up = (t - self.start) / self.ramp;
        let down = (self.end - t) / self.ramp;
        up.min(down).min(1.0)
    }
}

/// Global external actions and damping (seed 000 eq. 12-13).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ExternalParams {
    /// Gravity acceleration. Default: zero.
    pub gravity: [Real; 3],
    /// Linear damping `beta0` (force `-beta0 v`), >= 0. Default: 0.
    pub linear_damping: Real,
    /// Angular damping `beta1` (torque `-beta1 w`), >= 0. Default: 0.
    pub angular_damping: Real,
    /// Forces on particle sets over time windows. Default: none.
    pub forces: Vec<ForceWindow>,
}

impl Default for ExternalParams {
    fn default() -> Self {
        ExternalParams {
            gravity: [0.0; 3],
            linear_damping: 0.0,
            angular_damping: 0.0,
            forces: Vec::new(),
        }
    }
}

impl ExternalParams {
    /// Checks every field; `particle_count` bounds the ids of force windows.
    pub fn validate(&self, particle_count: usize) -> Result<(), ParamError> {
        for g in self.gravity {
            error::finite("gravity", g)?;
        }
        error::non_negative("linear_damping", self.linear_damping)?;
        error::non_negative("angular_damping", self.angular_damping)?;
        for (k, w) in self.forces.iter().enumerate() {
            w.validate(particle_count)
                .map_err(|e| e.within(&format!("forces[{k}]")))?;
        }
        Ok(())
    }

    /// The gravity vector.
    pub fn gravity(&self) -> Vec3 {
        Vec3::from(self.gravity)
    }
}

/// Force and torque added to particles by other crates for the next step
/// (op-implicit contact reactions, tools), indexed by particle id. They are
/// held constant during the step, then cleared.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ExternalAccumulator {
    forces: Vec<Vec3>,
    torques: Vec<Vec3>,
    active: bool,
}

impl ExternalAccumulator {
    /// An accumulator for `n` particles.
    pub fn new(n: usize) -> Self {
        ExternalAccumulator {
            forces: vec![Vec3::zeros(); n],
            torques: vec![Vec3::zeros(); n],
            active: false,
        }
    }

    /// Adds `force` and `torque` (world frame, torque about the particle's
    /// position) to particle `id` for the next step.
    pub fn add(&mut self, id: u32, force: Vec3, torque: Vec3) {
        let i = id as usize;
        self.forces[i] += force;
        self.torques[i] += torque;
        self.active = true;
    }

    /// Grows the tables to hold ids `0..n` (new ids start with nothing
    /// pending; existing entries are kept).
    /// The ids it can hold forces for (a checkpoint's accumulator is
    /// checked against its particles).
    pub(crate) fn capacity(&self) -> usize {
        self.forces.len().min(self.torques.len())
    }

    /// Grows the accumulator to hold `n` ids.
    pub fn grow(&mut self, n: usize) {
        if n > self.forces.len() {
            self.forces.resize(n, Vec3::zeros());
            self.torques.resize(n, Vec3::zeros());
        }
    }

    /// True when something was added since the last clear.
    pub fn is_active(&self) -> bool {
        self.active
    }

    /// The force and torque pending on particle `id`.
    #[inline]
    pub fn get(&self, id: u32) -> (Vec3, Vec3) {
        (self.forces[id as usize], self.torques[id as usize])
    }

    /// Clears every pending force and torque.
    pub fn clear(&mut self) {
        if self.active {
            self.forces.iter_mut().for_each(|f| *f = Vec3::zeros());
            self.torques.iter_mut().for_each(|t| *t = Vec3::zeros());
            self.active = false;
        }
    }
}

impl Contributor for ExternalAccumulator {
    fn name(&self) -> &str {
        "pending forces"
    }

    fn is_active(&self) -> bool {
        self.active
    }

    fn adds_torque(&self) -> bool {
        self.active && self.torques.iter().any(|t| *t != Vec3::zeros())
    }

    /// Adds each particle's pending force and torque (by id).
    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>) {
        if !self.active {
            return;
        }
        let ids = input.attributes.ids;
        out.forces
            .par_iter_mut()
            .zip(out.torques.par_iter_mut())
            .enumerate()
            .with_min_len(crate::MIN_PARALLEL_LEN)
            .for_each(|(i, (f, tq))| {
                let (fe, te) = self.get(ids[i]);
                *f += fe;
                *tq += te;
            });
    }
}

/// Gravity, linear and angular damping (seed 000 eq. 12-13: `m g - β0 v`,
/// `-β1 ω`) and the cold drag of heated materials
/// ([`crate::heat::HeatResponse::cold_drag`]), as one contributor: each
/// particle gets `m g - (β0 + drag) v` and `-β1 ω`.
pub struct UniformField<'a> {
    params: &'a ExternalParams,
    /// Some material in use has a cold drag (and the world has heat).
    cold_drag: bool,
}

impl<'a> UniformField<'a> {
    /// The field of `params`; `heated`: some material in use weakens with
    /// heat (its cold drag is then read per particle).
    pub fn new(params: &'a ExternalParams, materials: &[PreparedMaterial], heated: bool) -> Self {
        let cold_drag = heated
            && materials
                .iter()
                .any(|m| m.heat_response().is_some_and(|h| h.cold_drag > 0.0));
        UniformField { params, cold_drag }
    }
}

impl Contributor for UniformField<'_> {
    fn name(&self) -> &str {
        "gravity and damping"
    }

    fn is_active(&self) -> bool {
        self.params.gravity() != Vec3::zeros()
            || self.params.linear_damping != 0.0
            || self.params.angular_damping != 0.0
            || self.cold_drag
    }

    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>) {
        if !self.is_active() {
            return;
        }
        let g = self.params.gravity();
        let b0 = self.params.linear_damping;
        let b1 = self.params.angular_damping;
        let a = input.attributes;
        let s = &input.state;
        let drag = |i: usize| {
            input.materials[a.materials[i] as usize]
                .heat_response()
                .map_or(0.0, |h| h.drag(a.temperatures[i]))
        };
        out.forces
            .par_iter_mut()
            .zip(out.torques.par_iter_mut())
            .enumerate()
            .with_min_len(crate::MIN_PARALLEL_LEN)
            .for_each(|(i, (f, tq))| {
                let b = if self.cold_drag { b0 + drag(i) } else { b0 };
                *f += a.masses[i] * g - b * s.velocities[i];
                *tq -= b1 * s.angular_velocities[i];
            });
    }
}

/// The force windows of a world ([`ForceWindow`]) as a contributor.
pub struct ForceWindows<'a>(pub &'a [ForceWindow]);

impl Contributor for ForceWindows<'_> {
    fn name(&self) -> &str {
        "force windows"
    }

    fn is_active(&self) -> bool {
        !self.0.is_empty()
    }

    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>) {
        for w in self.0 {
            let k = match input.step_start {
                Some(t0) => w.factor_within(input.t, t0),
                None => w.factor(input.t),
            };
            if k != 0.0 {
                let fw = k * Vec3::from(w.force);
                for &id in &w.particles {
                    // Removed particles (World::remove_particles) are skipped.
                    if let Some(slot) = input.slot(id) {
                        out.forces[slot] += fw;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_factor() {
        let w = ForceWindow {
            particles: vec![0],
            force: [1.0, 0.0, 0.0],
            start: 1.0,
            end: 5.0,
            ramp: 1.0,
        };
        assert_eq!(w.factor(0.5), 0.0);
        // Seen from a step: only a step load's jumps depend on the side.
        for t in [1.0, 5.0] {
            for s in [0.0, 1.0, 4.0, 5.0] {
                assert_eq!(w.factor_within(t, s), 0.0);
            }
        }
        let step = ForceWindow {
            ramp: 0.0,
            ..w.clone()
        };
        assert_eq!(step.factor_within(1.0, 0.5), 0.0, "a step ending at start");
        assert_eq!(
            step.factor_within(1.0, 1.0),
            1.0,
            "a step beginning at start"
        );
        assert_eq!(step.factor_within(5.0, 4.0), 1.0, "a step ending at end");
        assert_eq!(step.factor_within(5.0, 5.0), 0.0, "a step beginning at end");
        assert_eq!(step.factor_within(3.0, 2.5), 1.0);
        assert_eq!(step.factor(1.0), 1.0);
        assert!((w.factor(1.5) - 0.5).abs() < 1e-15);
        assert_eq!(w.factor(3.0), 1.0);
        assert!((w.factor(4.75) - 0.25).abs() < 1e-15);
        assert_eq!(w.factor(5.0), 0.0);
        assert!(w.validate(1).is_ok());
        assert!(w
            .validate(0)
            .unwrap_err()
            .to_string()
            .contains("does not exist"));
    }

    #[test]
    fn rejects_bad_windows() {
        let mut w = ForceWindow {
            particles: vec![],
            force: [Real::NAN, 0.0, 0.0],
            start: 0.0,
            end: 1.0,
            ramp: 0.0,
        };
        assert!(w.validate(0).is_err());
        w.force = [0.0; 3];
        w.ramp = 0.6;
        assert!(w.validate(0).unwrap_err().to_string().contains("ramp"));
        w.ramp = 0.0;
        w.end = -1.0;
        assert!(w.validate(0).unwrap_err().to_string().contains("end"));
        let p = ExternalParams {
            linear_damping: -1.0,
            ..Default::default()
        };
        assert!(p
            .validate(0)
            .unwrap_err()
            .to_string()
            .contains("linear_damping"));
    }

    #[test]
    fn accumulator_clears() {
        let mut a = ExternalAccumulator::new(2);
        a.add(1, Vec3::x(), Vec3::y());
        a.add(1, Vec3::x(), Vec3::zeros());
        assert_eq!(a.get(1).0, 2.0 * Vec3::x());
        a.clear();
        assert_eq!(a.get(1), (Vec3::zeros(), Vec3::zeros()));
        assert!(!a.is_active());
    }
}
