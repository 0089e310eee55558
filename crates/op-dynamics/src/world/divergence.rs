//! Divergence: the world's checks after each step (non-finite state, the
//! speed limit, a run that cannot make progress) and the report they give.

use rayon::prelude::*;

use super::World;
use crate::forces::Kernel;
use crate::math::Real;

/// Adaptive steps in a row that may be forced through at `dt_min` with
/// their error above the tolerance before the run stops as diverged
/// ([`crate::integrators::StepInfo::tolerance_met`]).
pub const MAX_FORCED_STEPS: u32 = 1000;

/// A run that blew up: the step, time and (when one is to blame) particle
/// where it was detected, and what was wrong. The one divergence of the
/// workspace: the world's checks (non-finite state, speed limit) and the
/// runner's (runaway energy, energy gain, explosion beyond the scene's
/// bounds) all report it, in one format:
/// `simulation diverged at step N (t = T): particle P: reason`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct Divergence {
    /// Index of the step that produced the bad state (1-based).
    pub step: u64,
    /// Simulation time after that step.
    pub time: Real,
    /// Stable id of the first bad particle, when one is to blame (the
    /// energy gain of a whole scene has none).
    pub particle: Option<u32>,
    /// What was wrong.
    pub reason: String,
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "simulation diverged at step {} (t = {}): ",
            self.step, self.time
        )?;
        if let Some(p) = self.particle {
            write!(f, "particle {p}: ")?;
        }
        f.write_str(&self.reason)
    }
}

impl World {
    /// A run that cannot make progress within its means is stopped like a
    /// divergence: more steps than [`World::set_step_budget`] allows (an
    /// adaptive step collapsing toward `dt_min`), or [`MAX_FORCED_STEPS`]
    /// adaptive steps in a row forced through at `dt_min` with the error
    /// above the tolerance (tolerances no step can meet: the run would
    /// crawl at `dt_min` to its end).
    pub(super) fn check_progress(
        &self,
        info: &crate::integrators::StepInfo,
    ) -> Result<(), Divergence> {
        let stop = |reason: String| Divergence {
            step: self.steps,
            time: self.time,
            particle: None,
            reason,
        };
        if self.steps > self.step_budget {
            return Err(stop(format!(
                "{} steps, more than the run's budget of {} (its work limit; the last step was \
                 {:.3e}): the step collapsed",
                self.steps, self.step_budget, info.dt_taken
            )));
        }
        if self.forced_in_a_row >= MAX_FORCED_STEPS {
            return Err(stop(format!(
                "{} adaptive steps in a row were forced through at dt_min = {:.3e} with the error \
                 above the tolerance (error norm {:.3e}): no step meets these tolerances; raise \
                 the tolerances or dt_min",
                self.forced_in_a_row,
                info.dt_taken,
                info.error_norm.unwrap_or(Real::NAN)
            )));
        }
        Ok(())
    }

    /// Stops the run as diverged once it has taken more than `steps` steps
    /// in all ([`World::steps`]): the runner sets the budget its work
    /// limits allow, so that an adaptive step collapsing toward `dt_min`
    /// ends the run instead of running past its estimated work.
    pub fn set_step_budget(&mut self, steps: u64) {
        self.step_budget = steps;
    }

    pub(super) fn check_divergence(&self) -> Result<(), Divergence> {
        let p = &self.particles;
        let vmax2 = self.params.divergence.max_speed.powi(2);
        // Without torques (spacing kernel, no pending torque) and without
        // initial spin, orientations cannot change: skip reading them.
        let rotating = self.model.kernel == Kernel::Oriented || self.may_rotate;
        let check = |i: usize| {
            let finite = p.positions()[i].iter().all(|c| c.is_finite())
                && p.velocities()[i].iter().all(|c| c.is_finite())
                && (!rotating
                    || (p.angular_velocities()[i].iter().all(|c| c.is_finite())
                        && p.orientations()[i].coords.iter().all(|c| c.is_finite())));
            if !finite {
                Some((
                    i,
                    "non-finite position, velocity or orientation".to_string(),
                ))
            } else if p.velocities()[i].norm_squared() > vmax2 {
                Some((
                    i,
                    format!(
                        "speed {:.3e} exceeds divergence.max_speed = {:.3e}",
                        p.velocities()[i].norm(),
                        self.params.divergence.max_speed
                    ),
                ))
            } else {
                None
            }
        };
        // In parallel over fixed chunks, each scanned in slot order; the
        // first chunk with a bad slot reports it: the same report at any
        // thread count.
        const CHUNK: usize = 4096;
        let n = p.len();
        let bad = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).find_map(check))
            .find_first(Option::is_some)
            .flatten();
        match bad {
            None => Ok(()),
            Some((i, reason)) => Err(Divergence {
                step: self.steps,
                time: self.time,
                particle: Some(p.ids()[i]),
                reason,
            }),
        }
    }
}
