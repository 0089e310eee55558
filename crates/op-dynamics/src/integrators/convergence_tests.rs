//! Accuracy tests of the schemes on [`Smooth`] and on a torque-free
//! anisotropic body: measured orders of accuracy, energy behaviour,
//! angular momentum conservation and adaptive error control. Measured
//! figures are printed (run with `--nocapture` to see them).

use super::test_problem::{log_slope, Free, Smooth, System};
use super::{AdaptiveParams, Integrator, Scheme};
use crate::math::Real;

const T_END: Real = 1.0;

/// `[1.234e-5, ...]`.
fn sci(v: &[Real]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.3e}")).collect();
    format!("[{}]", parts.join(", "))
}

/// The state at `T_END` from `System::three()` with `steps` steps of `scheme`.
fn solve(scheme: Scheme, field: &Smooth, steps: usize) -> System {
    let mut sys = System::three();
    sys.run(
        scheme,
        &mut field.clone(),
        T_END / steps as Real,
        steps,
        |_, _| {},
    );
    sys
}

/// Fitted order of `scheme` over the step counts `steps`, against an RK4
/// reference with 8000 steps.
fn measured_order(scheme: Scheme, field: &Smooth, steps: &[usize]) -> Real {
    let reference = solve(Scheme::Rk4, field, 8000);
    let dts: Vec<Real> = steps.iter().map(|&n| T_END / n as Real).collect();
    let errors: Vec<Real> = steps
        .iter()
        .map(|&n| solve(scheme, field, n).distance(&reference))
        .collect();
    let order = log_slope(&dts, &errors);
    eprintln!(
        "{:>16}: dt {} error {} order {order:.3}",
        scheme.name(),
        sci(&dts),
        sci(&errors)
    );
    order
}

#[test]
fn explicit_euler_is_first_order() {
    let p = measured_order(
        Scheme::ExplicitEuler,
        &Smooth::default(),
        &[200, 400, 800, 1600],
    );
    assert!((p - 1.0).abs() < 0.3, "order {p}");
}

#[test]
fn symplectic_euler_is_first_order() {
    let p = measured_order(
        Scheme::SymplecticEuler,
        &Smooth::default(),
        &[200, 400, 800, 1600],
    );
    assert!((p - 1.0).abs() < 0.3, "order {p}");
}

#[test]
fn velocity_verlet_is_second_order() {
    let p = measured_order(
        Scheme::VelocityVerlet,
        &Smooth::default(),
        &[50, 100, 200, 400],
    );
    assert!((p - 2.0).abs() < 0.3, "order {p}");
}

#[test]
fn rk4_is_fourth_order() {
    let p = measured_order(Scheme::Rk4, &Smooth::default(), &[20, 40, 80, 160]);
    assert!((p - 4.0).abs() < 0.3, "order {p}");
}

/// The documented price of evaluating velocity-dependent forces at the
/// half-step velocity: with damping, velocity Verlet drops to first order
/// (RK4 keeps its order).
#[test]
fn velocity_verlet_with_damping_is_first_order() {
    let damped = Smooth {
        damping: 0.5,
        angular_damping: 0.3,
        ..Smooth::default()
    };
    let p = measured_order(Scheme::VelocityVerlet, &damped, &[100, 200, 400, 800]);
    assert!((p - 1.0).abs() < 0.3, "order {p}");
    let p4 = measured_order(Scheme::Rk4, &damped, &[20, 40, 80, 160]);
    assert!((p4 - 4.0).abs() < 0.3, "order {p4}");
}

/// Largest `|E(t) − E(0)|` over `t ≤ t_end`, and `E(t_end) − E(0)`.
fn energy_deviation(scheme: Scheme, dt: Real, t_end: Real) -> (Real, Real) {
    let field = Smooth::default();
    let mut sys = System::three();
    let e0 = sys.kinetic() + field.potential(sys.view());
    let mut worst: Real = 0.0;
    let mut last = 0.0;
    let steps = (t_end / dt).round() as usize;
    sys.run(scheme, &mut field.clone(), dt, steps, |s, _| {
        last = s.kinetic() + field.potential(s.view()) - e0;
        worst = worst.max(last.abs());
    });
    (worst, last)
}

#[test]
fn velocity_verlet_energy_error_is_bounded_and_second_order() {
    let t_end = 200.0;
    let (coarse, _) = energy_deviation(Scheme::VelocityVerlet, 0.02, t_end);
    let (fine, _) = energy_deviation(Scheme::VelocityVerlet, 0.01, t_end);
    // Over the first tenth of the run the deviation is already as large:
    // no drift.
    let (early, _) = energy_deviation(Scheme::VelocityVerlet, 0.02, t_end / 10.0);
    eprintln!("verlet max |dE| over t<={t_end}: dt=0.02 {coarse:.3e}, dt=0.01 {fine:.3e}, ratio {:.3}; first tenth {early:.3e}", coarse / fine);
    assert!(
        (3.2..4.8).contains(&(coarse / fine)),
        "ratio {}",
        coarse / fine
    );
    assert!(coarse < 2.0 * early, "drift: {early:.3e} -> {coarse:.3e}");
}

#[test]
fn explicit_euler_energy_grows() {
    let t_end = 10.0;
    let (_, half) = energy_deviation(Scheme::ExplicitEuler, 0.002, t_end / 2.0);
    let (_, full) = energy_deviation(Scheme::ExplicitEuler, 0.002, t_end);
    let (_, fine) = energy_deviation(Scheme::ExplicitEuler, 0.001, t_end);
    eprintln!(
        "explicit euler E(t)-E(0): dt=0.002 t={:.0} {half:.3e}, t={t_end:.0} {full:.3e}; dt=0.001 t={t_end:.0} {fine:.3e}",
        t_end / 2.0
    );
    assert!(half > 0.0 && full > 1.5 * half, "{half:.3e} {full:.3e}");
    // The drift rate is proportional to dt (first order).
    assert!((1.6..2.5).contains(&(full / fine)), "ratio {}", full / fine);
}

#[test]
fn energy_figures_for_all_schemes() {
    // Informative table (the asserted properties are tested above).
    for scheme in [
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
    ] {
        let (worst, last) = energy_deviation(scheme, 0.01, 10.0);
        eprintln!(
            "{:>16}: dt=0.01 t<=10: max |dE| {worst:.3e}, final dE {last:.3e}",
            scheme.name()
        );
        assert!(worst.is_finite());
    }
}

/// Relative drift of the world angular momentum of the tumbling body after
/// `t_end` with step `dt`.
fn momentum_drift(scheme: Scheme, dt: Real, t_end: Real) -> Real {
    let mut sys = System::tumbling();
    let l0 = sys.angular_momentum();
    let mut worst: Real = 0.0;
    sys.run(
        scheme,
        &mut Free,
        dt,
        (t_end / dt).round() as usize,
        |s, _| {
            worst = worst.max((s.angular_momentum() - l0).norm() / l0.norm());
        },
    );
    worst
}

#[test]
fn torque_free_body_conserves_angular_momentum() {
    let t_end = 20.0;
    let verlet = momentum_drift(Scheme::VelocityVerlet, 0.05, t_end);
    let rk4 = [
        momentum_drift(Scheme::Rk4, 0.02, t_end),
        momentum_drift(Scheme::Rk4, 0.01, t_end),
    ];
    let euler = [
        momentum_drift(Scheme::ExplicitEuler, 0.002, t_end),
        momentum_drift(Scheme::ExplicitEuler, 0.001, t_end),
    ];
    let symplectic = [
        momentum_drift(Scheme::SymplecticEuler, 0.002, t_end),
        momentum_drift(Scheme::SymplecticEuler, 0.001, t_end),
    ];
    let adaptive = momentum_drift(
        Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-8)),
        0.1,
        t_end,
    );
    eprintln!(
        "max |L-L0|/|L0| over t<={t_end}: verlet(0.05) {verlet:.2e}, rk4(0.02, 0.01) {}, euler(0.002, 0.001) {}, symplectic euler {}, adaptive(1e-8) {adaptive:.2e}",
        sci(&rk4),
        sci(&euler),
        sci(&symplectic)
    );
    // Velocity Verlet kicks L by the torque only: conserved to round-off
    // (a relative 1e-15 per step from the L <-> ω conversions).
    assert!(verlet < 1e-12, "{verlet}");
    assert!(
        rk4[0] < 1e-5 && (10.0..24.0).contains(&(rk4[0] / rk4[1])),
        "{rk4:?}"
    );
    assert!((1.6..2.5).contains(&(euler[0] / euler[1])), "{euler:?}");
    assert!(
        (1.6..2.5).contains(&(symplectic[0] / symplectic[1])),
        "{symplectic:?}"
    );
    assert!(adaptive < 1e-6, "{adaptive}");
}

/// Adaptive run of `System::three()` to `T_END` with every tolerance
/// `tol`: error against the RK4 reference and the number of steps.
fn adaptive_error(tol: Real, reference: &System) -> (Real, u32) {
    let mut sys = System::three();
    let mut integrator = Integrator::new(Scheme::Adaptive(AdaptiveParams::with_tolerance(tol)));
    let (state, bodies) = sys.split();
    let info = integrator.advance(&mut Smooth::default(), &bodies, 0.0, T_END, 0.5, state);
    (sys.distance(reference), info.steps)
}

#[test]
fn adaptive_error_follows_the_tolerance() {
    let reference = solve(Scheme::Rk4, &Smooth::default(), 8000);
    let mut previous = Real::INFINITY;
    for tol in [1e-3, 1e-5, 1e-7, 1e-9] {
        let (err, steps) = adaptive_error(tol, &reference);
        eprintln!(
            "adaptive tol {tol:.0e}: error {err:.3e} ({:.2} x tol), {steps} steps",
            err / tol
        );
        assert!(err < previous, "tol {tol}: {err} !< {previous}");
        assert!(err < 10.0 * tol, "tol {tol}: error {err}");
        previous = err;
    }
}
