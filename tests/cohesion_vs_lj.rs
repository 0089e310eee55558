//! Cohesion against Lennard-Jones (seed 002 §3, fig. 4): the matching rule,
//! the robustness of the equilateral triangle started at p% of the rest
//! length for every integrator, and the oscillations of systems released
//! near equilibrium.

use op_experiments::matching::{matched_lennard_jones, reference_cohesion};
use op_experiments::oscillation::{release_near_equilibrium, Dynamics};
use op_experiments::single_threaded;
use op_experiments::triangle::{
    largest_diverging, lowest_converging, percentages, schemes, RobustnessTable, TriangleSettings,
};
use oriented_particles::op_dynamics::interactions::Spacing;
use oriented_particles::op_dynamics::Scheme;

/// Same rest distance, same maximum attraction force, same cut-off.
#[test]
fn matching_rule() {
    let c = reference_cohesion();
    let l = matched_lennard_jones(&c);
    assert_eq!(l.r0, c.r0);
    assert_eq!(l.cutoff, c.effective_cutoff());
    assert_eq!((l.n, l.m), (12.0, 6.0));
    // Maximum attraction of the forces actually used (tapers included),
    // checked on a fine grid independent of the matching code.
    let peak = |s: Spacing| {
        let k = s.prepare().unwrap();
        (0..=100_000)
            .map(|i| 1.0 + 0.5 * i as f64 / 100_000.0)
            .map(|r| k.eval(r).1)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let (fc, fl) = (peak(Spacing::Cohesion(c)), peak(Spacing::LennardJones(l)));
    assert!((fc - fl).abs() < 1e-6 * fc, "{fc} vs {fl}");
    assert!(
        (fc - c.max_attraction().1).abs() < 1e-6 * fc,
        "cohesion's taper adds nothing"
    );
    // The untapered 12-6 peak is lower: the taper of the energy attracts.
    assert!(l.prepare().unwrap().max_attraction().1 < 0.95 * fl);
}

/// With the papers' explicit Euler, cohesion converges from 60% of the
/// rest length while the matched Lennard-Jones diverges at a larger p; the
/// table states the cohesion alpha and the damping.
#[test]
fn triangle_robustness_with_explicit_euler() {
    let c = reference_cohesion();
    let l = matched_lennard_jones(&c);
    let settings = TriangleSettings::default();
    assert_eq!(settings.dynamics.scheme, Scheme::ExplicitEuler);
    let sizes: Vec<u32> = (0..=8).map(|k| 100 - 5 * k).collect();
    let table =
        single_threaded(|| RobustnessTable::run(c, l, settings, &[Scheme::ExplicitEuler], &sizes));
    let (coh, lj) = (&table.columns[0].cohesion, &table.columns[0].lennard_jones);
    eprintln!("{}", table.markdown());
    assert_eq!(
        lowest_converging(coh),
        Some(60),
        "cohesion converges from 60%"
    );
    let lj_fails = largest_diverging(lj).expect("Lennard-Jones diverges somewhere");
    assert!(
        lj_fails > 60,
        "Lennard-Jones diverges at a larger p: {lj_fails}"
    );
    let md = table.markdown();
    assert!(
        md.contains("**alpha = 16**") && md.contains("**Linear damping beta0 = 1**"),
        "{md}"
    );
}

/// Every integrator, p from 100% down to 20%: Lennard-Jones diverges at a
/// larger p than any cohesion failure, for every scheme.
#[test]
fn where_each_integrator_stands() {
    let c = reference_cohesion();
    let l = matched_lennard_jones(&c);
    let table = single_threaded(|| {
        RobustnessTable::run(
            c,
            l,
            TriangleSettings::default(),
            &schemes(),
            &percentages(),
        )
    });
    eprintln!("{}", table.markdown());
    for c in &table.columns {
        let name = &c.scheme;
        let lj_fails = largest_diverging(&c.lennard_jones).unwrap_or(0);
        let coh_ok = lowest_converging(&c.cohesion).unwrap_or(100);
        assert!(
            lj_fails > coh_ok,
            "{name}: LJ fails at {lj_fails}%, cohesion converges from {coh_ok}%"
        );
        assert!(coh_ok <= 60, "{name}: {coh_ok}");
    }
}

/// Released near equilibrium with the same damping, mass and step,
/// cohesion reaches O < 1e-6 √N sooner than Lennard-Jones (seed 002 §3).
#[test]
fn cohesion_settles_sooner_than_lennard_jones() {
    let c = reference_cohesion();
    let l = matched_lennard_jones(&c);
    let d = Dynamics::default();
    for n in [3, 10, 100] {
        let (rc, rl) = single_threaded(|| {
            (
                release_near_equilibrium(Spacing::Cohesion(c), n, 0.05, 1, &d, 30.0, 1e-6),
                release_near_equilibrium(Spacing::LennardJones(l), n, 0.05, 1, &d, 30.0, 1e-6),
            )
        });
        eprintln!(
            "N = {n}: cohesion {:?}, Lennard-Jones {:?}",
            rc.converged_at, rl.converged_at
        );
        assert!(rc.diverged.is_none() && rl.diverged.is_none());
        let (tc, tl) = (rc.converged_at.unwrap(), rl.converged_at.unwrap());
        assert!(tc < tl, "N = {n}: {tc} vs {tl}");
    }
}
