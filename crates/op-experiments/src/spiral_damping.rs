//! Critical damping of a spiral's slowest mode (seed 002 §5, fig. 5): the
//! damping and the time window of the uncoil-and-recover experiment
//! computed from the material and the spiral instead of fixed numbers.
//!
//! The fixed recipe ([`SpiralRecipe::default`]) damps every spiral with
//! `β0 = 0.3` and gives it 40 time units to recover. That suits the seed
//! spiral, whose slowest deformation mode has `ω1 ≈ 0.30`, but the
//! slowest mode of a chain softens like `1/N²` (measured: `ω1` = 0.44 for
//! 8 particles, 0.16 for 14, 0.07 for 20 at 0.75 turns): a spiral of 20
//! particles is then far underdamped and its 40 units are under three
//! periods `1/ω1`.
//!
//! **Rule.** Linearized at rest, `M ẍ + D ẋ + H x = 0`. With damping
//! proportional to the masses, `D = c M` (linear damping `β0 = c m`,
//! angular damping `β1 = c I`), every mode `k` has the damping ratio
//! `ζ_k = c / (2 ω_k)`; `c = 2 ω1` damps the slowest deformation mode
//! critically and leaves the faster ones underdamped under the same
//! envelope `e^{-ω1 t}`: no mode decays slower than `(1 + ω1 t) e^{-ω1 t}`.
//! `ω1` is the smallest nonzero frequency of the planar modes of the
//! settled spiral ([`op_scene::modes::planar_modes`]), computed from the
//! Hessian of its energy (cohesion, form, co-planarity) and its masses and
//! moments of inertia. Every phase of the schedule is then a multiple of
//! `τ = 1/ω1` ([`CriticalSchedule`]). Inter-particle friction (damping of
//! relative velocities only) keeps the recipe's value.
//!
//! Finding `ω1` needs a state at rest, and settling needs a damping: the
//! spiral is settled with the recipe's damping, `ω1` taken there, then
//! settled again with the damping and settle time of that `ω1`, until
//! `ω1` changes by less than 5% (a settle that has not reached rest shows
//! as a negative `ω²`: the settle time is then doubled).

use op_dynamics::Real;

use crate::spiral::{SpiralRecipe, SpiralShape};

/// The phases of the experiment in units of `τ = 1/ω1`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CriticalSchedule {
    /// Settle phase, in `τ`: the settled state is the reference of the rest
    /// shape error, so it must be at rest well below the tolerance: under
    /// critical damping the slowest mode is down to `(1 + x) e^{-x}` =
    /// 8e-5 of its start after `x = 12`.
    pub settle: Real,
    /// Each load ramp, in `τ`: slower than the slowest mode, so the load
    /// is close to quasi-static (seed 002's recipe: 3 `τ` of the seed).
    pub ramp: Real,
    /// Time at full load, in `τ`: long enough to come to balance.
    pub hold: Real,
    /// Free recovery, in `τ`: measured, not derived (see the module docs of
    /// [`crate::spiral_damping`]): the linear bound `(1 + x) e^{-x}` is
    /// below 1e-3 of the release error after 9.2 `τ`, but the release
    /// starts far from rest (error 0.6 to 4 spacings), where the stiffness
    /// of cohesion (zero at its rest distance) and form differs from the
    /// linearization; 12 `τ` left a quadratic-law spiral of 8 particles
    /// at 0.019, 20 `τ` brings every recovering spiral of
    /// `tests/shape_memory.rs` below 0.001.
    pub recovery: Real,
    /// Frames per `τ`.
    pub frames: Real,
}

impl Default for CriticalSchedule {
    fn default() -> Self {
        CriticalSchedule {
            settle: 12.0,
            ramp: 3.0,
            hold: 6.0,
            recovery: 20.0,
            frames: 6.0,
        }
    }
}

/// What [`critical_recipe`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct CriticalDamping {
    /// The recipe with the damping and the schedule of the rule.
    pub recipe: SpiralRecipe,
    /// `ω1`, the slowest deformation mode of the settled spiral, 1/time.
    pub omega1: Real,
    /// Settle-and-measure passes taken.
    pub passes: usize,
}

/// Largest number of settle-and-measure passes.
const PASSES: usize = 8;

/// The recipe `base` with linear and angular damping `c = 2 ω1` times the
/// particle's mass and moment of inertia and the phases of `schedule` in
/// units of `1/ω1`, for `shape` (see the module docs).
///
/// # Errors
///
/// A message when the scene does not build, a settle diverges, or no
/// settled state with a positive slowest frequency is found in
/// eight passes.
pub fn critical_recipe(
    base: &SpiralRecipe,
    shape: &SpiralShape,
    schedule: &CriticalSchedule,
) -> Result<CriticalDamping, String> {
    let mut recipe = base.clone();
    let mut omega_old: Option<Real> = None;
    for pass in 1..=PASSES {
        let scene = recipe.scene("spiral", shape);
        let mut built = scene.build(None, None).map_err(|e| e.to_string())?;
        built.settle().map_err(|e| format!("while settling: {e}"))?;
        let modes = op_scene::modes::planar_modes(built.world_mut());
        let lambda = modes.omega2.first().copied().unwrap_or(0.0);
        if !(lambda > 0.0 && lambda.is_finite()) {
            // Not at rest yet: settle longer with the same damping.
            recipe.settle *= 2.0;
            continue;
        }
        let omega = lambda.sqrt();
        recipe = with_omega(base, omega, schedule);
        if let Some(old) = omega_old {
            if (omega / old - 1.0).abs() < 0.05 {
                return Ok(CriticalDamping {
                    recipe,
                    omega1: omega,
                    passes: pass,
                });
            }
        }
        omega_old = Some(omega);
    }
    Err(format!(
        "no settled state with a positive slowest frequency after {PASSES} passes"
    ))
}

/// `base` with the damping and schedule of the rule for `omega` (unit
/// mass and time, as [`crate::spiral::Units::of`]).
fn with_omega(base: &SpiralRecipe, omega: Real, s: &CriticalSchedule) -> SpiralRecipe {
    let c = 2.0 * omega;
    let tau = 1.0 / omega;
    SpiralRecipe {
        linear_damping: c,
        angular_damping: c * base.inertia,
        settle: s.settle * tau,
        ramp: s.ramp * tau,
        hold: s.hold * tau,
        recovery: s.recovery * tau,
        frame_rate: s.frames / tau,
        ..base.clone()
    }
}
