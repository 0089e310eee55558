//! The adaptive scheme: the embedded Dormand–Prince 5(4) pair (Dormand &
//! Prince 1980, "A family of embedded Runge-Kutta formulae", J. Comput.
//! Appl. Math. 6, 19-26) in Runge–Kutta–Munthe-Kaas form (see
//! [`super::rkmk`]), with local extrapolation (the 5th-order solution is
//! kept), FSAL (the last stage is the new state, its forces are the next
//! step's first stage), error-based step rejection and the standard step
//! size controller (Hairer, Nørsett & Wanner, "Solving Ordinary
//! Differential Equations I", 2nd ed., §II.4).
//!
//! The error norm and the controller are documented on [`AdaptiveParams`].

use super::rkmk::{self, Deriv, RkBuffers, Tableau};
use super::{Bodies, ForceField, StateMut, StateRef, StepInfo};
use crate::error::{check, positive, ParamError};
use crate::math::{Real, Vec3};

/// Parameters of [`super::Scheme::Adaptive`]. All times are in the scene's
/// time unit, lengths in its length unit.
///
/// **Error norm.** For each particle the embedded Dormand–Prince error
/// estimate `e = h Σ_j (b_j − b̂_j) K_j` has four 3-vectors, each measured
/// by its Euclidean length (so the norm does not depend on the world axes)
/// against a scale in its own units:
///
/// - position (length): `atol_position + rtol · max(‖p₀‖, ‖p₁‖)`;
/// - velocity (length/time): `atol_velocity + rtol · max(‖v₀‖, ‖v₁‖)`;
/// - rotation increment `θ` of the step (rad): `atol_angle` (an
///   orientation has no magnitude for a relative tolerance to scale);
/// - angular velocity (rad/time):
///   `atol_angular_velocity + rtol · max(‖ω₀‖, ‖ω₁‖)`.
///
/// The error norm is the MAXIMUM of `‖e‖ / scale` over all particles and
/// the four quantities (a maximum rather than the usual RMS, so that one
/// particle in a collision is not averaged away by a thousand quiet ones).
/// A step is accepted when the norm is `<= 1`; NaN counts as infinite. The
/// 5th-order solution is kept (local extrapolation), so the global error
/// measured on smooth problems is about the tolerance (0.7-1.6 × in the
/// tests).
///
/// **Controller** (Hairer, Nørsett & Wanner, "Solving ODEs I", §II.4):
/// `h_new = h · clamp(safety · err^(−1/5), min_factor, max_factor)`
/// (exponent `1/(q+1)` with the embedded order `q = 4`), with no growth
/// right after a rejection and a cut of at least 10% after each rejected
/// attempt; a step clipped by the requested `dt` does not lower the next
/// proposal.
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(default, deny_unknown_fields)]
pub struct AdaptiveParams {
    /// Relative tolerance (dimensionless) on positions, velocities and
    /// angular velocities. Default: `1e-6`.
    pub rtol: Real,
    /// Absolute position tolerance (length). Default: `1e-6`.
    pub atol_position: Real,
    /// Absolute velocity tolerance (length/time). Default: `1e-6`.
    pub atol_velocity: Real,
    /// Absolute tolerance on the rotation of a step (rad). Default: `1e-6`.
    pub atol_angle: Real,
    /// Absolute angular velocity tolerance (rad/time). Default: `1e-6`.
    pub atol_angular_velocity: Real,
    /// Smallest step (time): a step this small is accepted even when its
    /// error is above the tolerance (reported by
    /// [`super::StepInfo::tolerance_met`]). Default: `1e-10`.
    pub dt_min: Real,
    /// Largest step (time). Default: `Real::MAX` (only the `dt` passed to
    /// [`super::Integrator::step`] limits the step).
    pub dt_max: Real,
    /// Safety factor of the controller, in `(0, 1]`. Default: `0.9`.
    pub safety: Real,
    /// Smallest step ratio `h_new / h`, in `(0, 1)`. Default: `0.2`.
    pub min_factor: Real,
    /// Largest step ratio `h_new / h`, `> 1`. Default: `5`.
    pub max_factor: Real,
}

impl Default for AdaptiveParams {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol_position: 1e-6,
            atol_velocity: 1e-6,
            atol_angle: 1e-6,
            atol_angular_velocity: 1e-6,
            dt_min: 1e-10,
            dt_max: Real::MAX,
            safety: 0.9,
            min_factor: 0.2,
            max_factor: 5.0,
        }
    }
}

impl AdaptiveParams {
    /// The defaults with every tolerance (relative and the four absolute
    /// ones) set to `tol`.
    pub fn with_tolerance(tol: Real) -> Self {
        Self {
            rtol: tol,
            atol_position: tol,
            atol_velocity: tol,
            atol_angle: tol,
            atol_angular_velocity: tol,
            ..Self::default()
        }
    }

    /// Checks every field: tolerances finite with `rtol >= 0` and absolute
    /// tolerances `> 0`; `0 < dt_min <= dt_max`, both finite;
    /// `0 < safety <= 1`; `0 < min_factor < 1`; `1 < max_factor`, finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        check(
            "rtol",
            self.rtol,
            self.rtol.is_finite() && self.rtol >= 0.0,
            "must be finite and >= 0",
        )?;
        positive("atol_position", self.atol_position)?;
        positive("atol_velocity", self.atol_velocity)?;
        positive("atol_angle", self.atol_angle)?;
        positive("atol_angular_velocity", self.atol_angular_velocity)?;
        positive("dt_min", self.dt_min)?;
        positive("dt_max", self.dt_max)?;
        check(
            "dt_max",
            self.dt_max,
            self.dt_max >= self.dt_min,
            &format!("must be >= dt_min ({})", self.dt_min),
        )?;
        check(
            "safety",
            self.safety,
            self.safety > 0.0 && self.safety <= 1.0,
            "must be in (0, 1]",
        )?;
        check(
            "min_factor",
            self.min_factor,
            self.min_factor > 0.0 && self.min_factor < 1.0,
            "must be in (0, 1)",
        )?;
        check(
            "max_factor",
            self.max_factor,
            self.max_factor.is_finite() && self.max_factor > 1.0,
            "must be finite and > 1",
        )
    }

    /// The controller's step ratio for error norm `err`; capped at 1 right
    /// after a rejection.
    pub(crate) fn factor(&self, err: Real, after_reject: bool) -> Real {
        let max = if after_reject { 1.0 } else { self.max_factor };
        if err.is_nan() || err.is_infinite() {
            self.min_factor
        } else if err <= 0.0 {
            max
        } else {
            (self.safety * err.powf(-0.2)).clamp(self.min_factor, max)
        }
    }
}

/// Dormand–Prince 5(4): the 7 stages, the last one with the 5th-order
/// weights (FSAL), so the last stage state IS the new state.
pub(crate) const DOPRI5: Tableau = Tableau {
    a: &[
        &[],
        &[1.0 / 5.0],
        &[3.0 / 40.0, 9.0 / 40.0],
        &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
        &[
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
        ],
        &[
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
        ],
        &[
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ],
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
};

/// `b − b̂`: 5th-order minus 4th-order weights.
pub(crate) const DOPRI5_E: [Real; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// The error norm (module docs) of a step of size `h` from `y0` to `y1`
/// with slopes `k` (stage-major, `n` particles).
pub(crate) fn error_norm(
    p: &AdaptiveParams,
    y0: StateRef<'_>,
    y1: StateRef<'_>,
    h: Real,
    k: &[Deriv],
) -> Real {
    let n = y0.len();
    let mut worst: Real = 0.0;
    for i in 0..n {
        let mut e = Deriv::default();
        for (j, &c) in DOPRI5_E.iter().enumerate() {
            let kj = &k[j * n + i];
            e.dp += c * kj.dp;
            e.dv += c * kj.dv;
            e.dth += c * kj.dth;
            e.dw += c * kj.dw;
        }
        let (a, b) = (y0.particle(i), y1.particle(i));
        let scale = |atol: Real, x: &Vec3, y: &Vec3| atol + p.rtol * x.norm().max(y.norm());
        let ratios = [
            h * e.dp.norm() / scale(p.atol_position, &a.p.coords, &b.p.coords),
            h * e.dv.norm() / scale(p.atol_velocity, &a.v, &b.v),
            h * e.dth.norm() / p.atol_angle,
            h * e.dw.norm() / scale(p.atol_angular_velocity, &a.w, &b.w),
        ];
        for r in ratios {
            if r.is_nan() {
                return Real::INFINITY;
            }
            worst = worst.max(r);
        }
    }
    worst
}

/// One accepted adaptive step of all particles (after as many rejected
/// attempts as needed), at most `dt`. `forces`/`torques` hold the forces at
/// the current state when `cached`, and at the new state on return.
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_all<F: ForceField>(
    p: &AdaptiveParams,
    field: &mut F,
    bodies: &Bodies<'_>,
    t: Real,
    dt: Real,
    state: StateMut<'_>,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    buf: &mut RkBuffers,
    cached: bool,
    suggested: Option<Real>,
) -> StepInfo {
    let n = state.len();
    buf.ensure(n, DOPRI5.stages());
    let mut evals = 0;
    if !cached {
        field.forces(t, state.view(), forces, torques);
        evals += 1;
    }
    // Stage 0 does not depend on h: computed once, kept across rejections.
    rkmk::first_slope(bodies, state.view(), forces, torques, &mut buf.k[..n]);

    let proposal = suggested.unwrap_or(p.dt_max).min(p.dt_max);
    let floor = p.dt_min.min(dt);
    let mut h = proposal.min(dt).max(floor);
    let mut rejected = 0;
    loop {
        evals += rkmk::later_stages(
            field,
            bodies,
            t,
            h,
            state.view(),
            &DOPRI5,
            buf,
            forces,
            torques,
        );
        let err = error_norm(p, state.view(), buf.view(), h, &buf.k);
        if err <= 1.0 || h <= floor {
            // The last stage is the 5th-order solution, and `forces` hold
            // its forces (FSAL).
            state.positions.copy_from_slice(&buf.positions);
            state.velocities.copy_from_slice(&buf.velocities);
            state.orientations.copy_from_slice(&buf.orientations);
            state
                .angular_velocities
                .copy_from_slice(&buf.angular_velocities);
            let mut next = h * p.factor(err, rejected > 0);
            if rejected == 0 && proposal > h {
                // The step was clipped by `dt` (e.g. at the end of a
                // frame): do not let the short step shrink the proposal.
                next = next.max(proposal);
            }
            return StepInfo {
                dt_taken: h,
                dt_next: next.clamp(p.dt_min, p.dt_max),
                rejected,
                force_evaluations: evals,
                error_norm: Some(err),
            };
        }
        rejected += 1;
        // At least a 10% cut, so the loop ends even with `safety = 1` and an
        // error norm a hair above 1.
        h = (h * p.factor(err, true).min(0.9)).max(floor);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::rk4::{RK4, RK4_B};

    fn check_order_conditions(tab: &Tableau, b: &[Real], order: usize) {
        let s = tab.stages();
        for (i, row) in tab.a.iter().enumerate() {
            assert!(
                (row.iter().sum::<Real>() - tab.c[i]).abs() < 1e-14,
                "row {i}"
            );
        }
        let bc = |f: &dyn Fn(usize) -> Real| (0..s).map(|i| b[i] * f(i)).sum::<Real>();
        let ac =
            |i: usize, f: &dyn Fn(usize) -> Real| (0..i).map(|j| tab.a[i][j] * f(j)).sum::<Real>();
        let c = |i: usize| tab.c[i];
        let mut conditions = vec![(bc(&|_| 1.0), 1.0), (bc(&c), 0.5)];
        if order >= 3 {
            conditions.push((bc(&|i| c(i) * c(i)), 1.0 / 3.0));
            conditions.push((bc(&|i| ac(i, &c)), 1.0 / 6.0));
        }
        if order >= 4 {
            conditions.push((bc(&|i| c(i).powi(3)), 0.25));
            conditions.push((bc(&|i| c(i) * ac(i, &c)), 1.0 / 8.0));
            conditions.push((bc(&|i| ac(i, &|j| c(j) * c(j))), 1.0 / 12.0));
            conditions.push((bc(&|i| ac(i, &|j| ac(j, &c))), 1.0 / 24.0));
        }
        for (k, (got, want)) in conditions.into_iter().enumerate() {
            assert!((got - want).abs() < 1e-14, "condition {k}: {got} vs {want}");
        }
    }

    #[test]
    fn tableaux_satisfy_order_conditions() {
        check_order_conditions(&RK4, &RK4_B, 4);
        let b5: Vec<Real> = DOPRI5.a[6].iter().copied().chain([0.0]).collect();
        check_order_conditions(&DOPRI5, &b5, 4);
        let b4: Vec<Real> = b5.iter().zip(DOPRI5_E).map(|(b, e)| b - e).collect();
        check_order_conditions(&DOPRI5, &b4, 4);
        assert!(DOPRI5_E.iter().sum::<Real>().abs() < 1e-15);
    }

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        AdaptiveParams::default().validate().unwrap();
        AdaptiveParams::with_tolerance(1e-9).validate().unwrap();
        let bad = [
            AdaptiveParams {
                rtol: Real::NAN,
                ..Default::default()
            },
            AdaptiveParams {
                atol_angle: 0.0,
                ..Default::default()
            },
            AdaptiveParams {
                dt_min: 1.0,
                dt_max: 0.5,
                ..Default::default()
            },
            AdaptiveParams {
                safety: 1.5,
                ..Default::default()
            },
            AdaptiveParams {
                min_factor: 1.0,
                ..Default::default()
            },
            AdaptiveParams {
                max_factor: Real::INFINITY,
                ..Default::default()
            },
        ];
        let fields = [
            "rtol",
            "atol_angle",
            "dt_max",
            "safety",
            "min_factor",
            "max_factor",
        ];
        for (p, field) in bad.iter().zip(fields) {
            let msg = p.validate().unwrap_err().to_string();
            assert!(msg.contains(field), "{msg}");
        }
        let scheme = crate::integrators::Scheme::Adaptive(bad[0]);
        assert!(scheme
            .validate()
            .unwrap_err()
            .to_string()
            .contains("adaptive.rtol"));
        assert!(crate::integrators::Integrator::try_new(scheme).is_err());
    }

    #[test]
    fn controller_shrinks_grows_and_caps() {
        let p = AdaptiveParams::default();
        assert_eq!(p.factor(0.0, false), 5.0);
        assert_eq!(p.factor(0.0, true), 1.0);
        assert_eq!(p.factor(Real::NAN, false), 0.2);
        assert_eq!(p.factor(1e9, false), 0.2);
        let f = p.factor(2.0, true);
        assert!((f - 0.9 * 2.0_f64.powf(-0.2)).abs() < 1e-15);
        assert!(p.factor(0.5, false) > 1.0);
    }
}
