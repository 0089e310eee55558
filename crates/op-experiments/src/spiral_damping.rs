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
//! **Rule** ([`op_scene::damping`], where it lives so that scenes can ask
//! for it with `linear_damping: "Critical"`): damping proportional to the
//! masses, `c = 2 ω1` (linear damping `β0 = c m`, angular damping
//! `β1 = c I`), damps the slowest deformation mode critically and leaves
//! no mode decaying slower than `(1 + ω1 t) e^{-ω1 t}`; `ω1` is the
//! smallest nonzero frequency of the planar modes of the settled spiral
//! ([`op_scene::modes::planar_modes`]). Every phase of the recipe's
//! schedule is then a multiple of `τ = 1/ω1` ([`CriticalSchedule`]: settle,
//! ramps and hold too, which a scene's own load keeps). Inter-particle
//! friction (damping of relative velocities only) keeps the recipe's
//! value.
//!
//! Finding `ω1` needs a state at rest, and settling needs a damping: the
//! spiral is settled with the recipe's damping, `ω1` taken there, then
//! settled again with the damping and settle time of that `ω1`, until
//! `ω1` changes by less than 5% ([`op_scene::damping::converge`]; a settle
//! that has not reached rest shows as a negative `ω²`: the settle time is
//! then doubled).

use op_dynamics::Real;
use op_scene::damping::{converge, critical_coefficients, Measured, PASSES};

pub use op_scene::damping::CriticalSchedule;

use crate::spiral::{SpiralRecipe, SpiralShape};

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
    let found = converge(|omega, stretch| -> Result<Measured, String> {
        let mut recipe = omega.map_or_else(|| base.clone(), |w| with_omega(base, w, schedule));
        recipe.settle *= stretch;
        let scene = recipe.scene("spiral", shape);
        let mut built = scene.build(None, None).map_err(|e| e.to_string())?;
        built.settle().map_err(|e| format!("while settling: {e}"))?;
        let modes = op_scene::modes::planar_modes(built.world_mut());
        let lambda = modes.omega2.first().copied().unwrap_or(0.0);
        Ok(if lambda > 0.0 && lambda.is_finite() {
            Measured::Omega(lambda.sqrt())
        } else {
            // Not at rest yet: settle longer with the same damping.
            Measured::NotAtRest
        })
    })?;
    let (omega1, passes) = found.ok_or_else(|| {
        format!("no settled state with a positive slowest frequency after {PASSES} passes")
    })?;
    Ok(CriticalDamping {
        recipe: with_omega(base, omega1, schedule),
        omega1,
        passes,
    })
}

/// `base` with the damping and schedule of the rule for `omega` (unit
/// mass and time, as [`crate::spiral::Units::of`]).
fn with_omega(base: &SpiralRecipe, omega: Real, s: &CriticalSchedule) -> SpiralRecipe {
    let (linear_damping, angular_damping) = critical_coefficients(omega, 1.0, base.inertia);
    let tau = 1.0 / omega;
    SpiralRecipe {
        linear_damping,
        angular_damping,
        settle: s.settle * tau,
        ramp: s.ramp * tau,
        hold: s.hold * tau,
        recovery: s.recovery * tau,
        frame_rate: s.frames / tau,
        ..base.clone()
    }
}
