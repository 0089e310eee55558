//! Measured orders of accuracy of every integrator on a full world (a
//! reduced work-precision sweep, docs/model.md §6): the seed spiral released from
//! its analytic shape without damping, friction or load (ten oriented
//! particles with cohesion, form and co-planarity: smooth,
//! velocity-independent forces, rotations included), compared at scene
//! times 1 and 2 with an RK4 run at a much smaller step. Fitted slopes of
//! log(error) against log(dt), for positions and orientations.
//! `reports/accuracy.md` has the full sweep.

use op_experiments::accuracy::{errors, log_slope, simulate, CaseEntry, Method, SceneSource};
use oriented_particles::op_dynamics::{Real, Scheme};

fn entry() -> CaseEntry {
    CaseEntry {
        name: "spiral_free_short",
        about: "the free seed spiral, two time units",
        source: SceneSource::FreeSpiral,
        samples: vec![0.0, 1.0, 2.0],
        conservative: true,
        steps: Vec::new(),
        first_order_steps: Vec::new(),
        tolerances: Vec::new(),
        adaptive_dt_max: 0.5,
        reference: Method::new(Scheme::Rk4, 1.25e-4),
    }
}

/// `[1.234e-5, ...]`.
fn sci(v: &[Real]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.3e}")).collect();
    format!("[{}]", parts.join(", "))
}

/// `(position order, orientation order, errors)` of `scheme` over `steps`.
fn orders(scheme: Scheme, steps: &[Real]) -> (Real, Real, Vec<Real>) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let e = entry();
    let case = e.load(root).expect("the free spiral builds");
    let reference = simulate(&case, &e.reference).expect("the reference runs");
    let (mut pos, mut rot) = (Vec::new(), Vec::new());
    for &dt in steps {
        let run = simulate(&case, &Method::new(scheme, dt)).expect("the run does not diverge");
        let err = errors(&run, &reference, case.r0, true);
        pos.push(err.position);
        rot.push(err.orientation);
    }
    let p = log_slope(steps, &pos);
    let q = log_slope(steps, &rot);
    println!(
        "{}: position order {p:.3}, orientation order {q:.3}, position errors {}, \
         orientation errors {}",
        scheme.name(),
        sci(&pos),
        sci(&rot)
    );
    (p, q, pos)
}

fn assert_order(scheme: Scheme, steps: &[Real], expected: Real, slack: Real) {
    let (p, q, errs) = orders(scheme, steps);
    assert!(
        errs.iter().all(|e| *e > 1e-11),
        "{}: errors {errs:?} reach the reference's own error: choose larger steps",
        scheme.name()
    );
    assert!(
        (p - expected).abs() < slack,
        "{}: measured position order {p:.3}, expected {expected} ± {slack}",
        scheme.name()
    );
    assert!(
        (q - expected).abs() < slack,
        "{}: measured orientation order {q:.3}, expected {expected} ± {slack}",
        scheme.name()
    );
}

#[test]
fn explicit_euler_is_first_order_on_a_world() {
    assert_order(Scheme::ExplicitEuler, &[0.002, 0.001, 0.0005], 1.0, 0.25);
}

#[test]
fn symplectic_euler_is_first_order_on_a_world() {
    assert_order(Scheme::SymplecticEuler, &[0.004, 0.002, 0.001], 1.0, 0.25);
}

#[test]
fn velocity_verlet_is_second_order_on_a_world() {
    assert_order(Scheme::VelocityVerlet, &[0.02, 0.01, 0.005], 2.0, 0.25);
}

#[test]
fn rk4_is_fourth_order_on_a_world() {
    assert_order(Scheme::Rk4, &[0.04, 0.02, 0.01], 4.0, 0.4);
}

#[test]
fn adaptive_error_falls_with_its_tolerance() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let e = entry();
    let case = e.load(root).expect("the free spiral builds");
    let reference = simulate(&case, &e.reference).expect("the reference runs");
    let tolerances = [1e-4, 1e-6, 1e-8];
    let errs: Vec<Real> = tolerances
        .iter()
        .map(|&tol| {
            let run = simulate(&case, &Method::adaptive(tol, e.adaptive_dt_max))
                .expect("the run does not diverge");
            errors(&run, &reference, case.r0, true).position
        })
        .collect();
    println!(
        "adaptive: tolerances {tolerances:?}, position errors {}",
        sci(&errs)
    );
    for k in 1..errs.len() {
        assert!(
            errs[k] < errs[k - 1] / 10.0,
            "a 100 times smaller tolerance should cut the error at least 10 times: {errs:?}"
        );
    }
    for (tol, err) in tolerances.iter().zip(&errs) {
        assert!(
            *err < 100.0 * tol,
            "error {err:.3e} far above the tolerance {tol:e}"
        );
    }
}
