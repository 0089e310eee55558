//! Tests of the cohesion module.

use super::*;

fn exact(p: CohesionParams) -> Cohesion {
    CohesionParams {
        mode: CohesionMode::Exact,
        ..p
    }
    .prepare()
    .unwrap()
}

fn variants() -> Vec<CohesionParams> {
    let d = CohesionParams::default();
    vec![
        d,
        CohesionParams {
            e: 3.0,
            r0: 2.0,
            alpha: 1.5,
            taper: 0.25,
            ..d
        },
        CohesionParams {
            alpha: 60.0,
            cutoff: Some(1.8),
            ..d
        },
    ]
}

#[test]
fn extreme_alpha_and_cutoff_are_rejected_not_allocated() {
    for (alpha, cutoff) in [(1e12, None), (1e-12, None), (16.0, Some(1e300))] {
        let p = CohesionParams {
            alpha,
            cutoff,
            ..Default::default()
        };
        let e = p.prepare().unwrap_err().to_string();
        assert!(e.contains("alpha") || e.contains("cutoff"), "{e}");
    }
}

#[test]
fn force_is_zero_with_zero_slope_at_r0() {
    for p in variants() {
        let c = exact(p);
        assert_eq!(c.force(p.r0), 0.0);
        // f ~ -E (r - r0)³/r0: a central difference of step h gives
        // -E h²/r0, so h = 1e-5 resolves a zero slope to ~1e-8.
        let h = 1e-5 * p.r0;
        let slope = (c.force(p.r0 + h) - c.force(p.r0 - h)) / (2.0 * h);
        assert!(slope.abs() < 1e-6 * c.max_attraction().1, "{slope}");
        assert!(c.force(0.9 * p.r0) > 0.0 && c.force(1.1 * p.r0) < 0.0);
        // Energy minimum at r0.
        let u0 = c.energy_exact(p.r0);
        assert!(u0 < 0.0 && c.energy_exact(0.99 * p.r0) > u0);
        assert!(c.energy_exact(1.01 * p.r0) > u0);
    }
}

#[test]
fn max_attraction_and_automatic_cutoff() {
    for p in variants() {
        let c = exact(p);
        let (r_m, f_max) = c.max_attraction();
        assert!((c.force(r_m) + f_max).abs() < 1e-14 * f_max);
        let h = 1e-5 * p.r0;
        assert!(c.force(r_m - h) > c.force(r_m) && c.force(r_m + h) > c.force(r_m));
        if p.cutoff.is_none() {
            let f_rc = cohesion_force(p.e, p.r0, p.alpha, c.cutoff());
            assert!((f_rc.abs() / f_max / AUTO_CUTOFF_RATIO - 1.0).abs() < 1e-9);
        }
    }
    let (r_m, f_max) = CohesionParams::default().max_attraction();
    assert!((r_m - 1.294).abs() < 1e-3 && (f_max - 0.98).abs() < 0.01);
    assert!((CohesionParams::default().effective_cutoff() - 2.08).abs() < 0.01);
}

/// Exact energy against a reference integrated on a 6x finer partition,
/// and its derivative against the closed-form force.
#[test]
fn exact_energy_is_accurate_to_round_off() {
    let mut worst: Real = 0.0;
    for p in variants() {
        let c = exact(p);
        let r_c = c.cutoff();
        let scale = c.energy_exact(p.r0).abs();
        for k in 0..60 {
            let r = p.r0 * (0.002 + (r_c / p.r0 - 0.002) * (k as Real / 60.0).powf(0.7));
            // Reference: split [r, r_c] at r_on and at 6x finer panels.
            let mut pts = vec![r];
            let n = 240;
            for i in 1..=n {
                let x = i as Real / n as Real;
                pts.push(r * (r_c / r).powf(x));
            }
            if c.taper.r_on() > r {
                pts.push(c.taper.r_on());
            }
            pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let reference: Real = pts.windows(2).map(|w| c.panel(w[0], w[1])).sum();
            let u = c.energy_exact(r);
            let err = (u - reference).abs() / reference.abs().max(scale);
            worst = worst.max(err);
            assert!(err < 1e-13, "r={r}: {u} vs {reference} ({err:e})");
            let h = 1e-6 * r;
            let du = (c.energy_exact(r + h) - c.energy_exact(r - h)) / (2.0 * h);
            let f = c.force(r);
            assert!(
                (du + f).abs() < 1e-6 * (f.abs() + c.f_max),
                "r={r}: {du} vs {f}"
            );
        }
    }
    eprintln!("cohesion exact energy: max relative quadrature error {worst:.2e}");
}

/// Interpolation error of the default table against the exact mode.
#[test]
fn table_error_is_small() {
    let p = CohesionParams::default();
    let c = p.prepare().unwrap();
    let x = exact(p);
    let (_, f_max) = c.max_attraction();
    let depth = x.energy_exact(p.r0).abs();
    let start = p.table_start * p.r0;
    let (mut ef, mut eu, mut ef_rel) = (0.0 as Real, 0.0 as Real, 0.0 as Real);
    let n = 20_000;
    for k in 0..=n {
        let r = start + (c.cutoff() - start) * k as Real / n as Real;
        let (u, du) = c.eval(r);
        let (ue, due) = x.eval(r);
        ef = ef.max((du - due).abs() / f_max);
        eu = eu.max((u - ue).abs() / depth);
        if r > 0.8 * p.r0 && r < 1.6 * p.r0 {
            ef_rel = ef_rel.max((du - due).abs() / due.abs().max(1e-3 * f_max));
        }
    }
    eprintln!(
        "cohesion table ({} nodes on [{start}, {:.4}]): max |force error|/f_max = {ef:.2e}, \
         max |energy error|/depth = {eu:.2e}, force error relative to |f| on [0.8, 1.6] r0 \
         = {ef_rel:.2e}",
        p.table_nodes,
        c.cutoff()
    );
    assert!(ef < 1e-6, "{ef:e}");
    assert!(eu < 1e-9, "{eu:e}");
}

/// Uniform nodes spread to a large cut-off lost the well: 1024 nodes up
/// to 1000 r0 gave a force error of 121% of f_max and a well 4.7x too
/// deep. Now the tabulated force and energy stay within the stated
/// bound of the direct evaluation (closed-form force, quadrature energy
/// accurate to round-off) at any accepted cut-off and alpha.
#[test]
fn table_error_bound_holds_at_any_cutoff() {
    let d = CohesionParams::default();
    // (alpha, cut-off, taper): a narrow well needs a short taper to
    // start beyond the maximum attraction.
    let cases = [
        (16.0, None, 0.1),
        (16.0, Some(100.0), 0.1),
        (16.0, Some(1000.0), 0.1),
        (1e-5, Some(1000.0), 0.1),
        (1e-3, Some(100.0), 0.1),
        (1e-2, None, 0.1),
        (1e-2, Some(1000.0), 0.1),
        (1.0, Some(1000.0), 0.1),
        (1e4, None, 0.02),
        (1e4, Some(1000.0), 0.1),
        (1e6, None, 0.002),
        (1e6, Some(100.0), 0.1),
    ];
    for (alpha, cutoff, taper) in cases {
        let p = CohesionParams {
            alpha,
            cutoff,
            taper,
            ..d
        };
        let c = p.prepare().unwrap();
        let x = exact(p);
        let (_, f_max) = x.max_attraction();
        let depth = x.energy_exact(p.r0).abs();
        let (a, b) = c.table_range_in_use().unwrap();
        let start = p.table_start * p.r0;
        let r_c = c.cutoff();
        let mut samples = Vec::new();
        for (lo, hi, n) in [(a, b, 20_000), (start, b, 10_000), (start, r_c, 5_000)] {
            samples.extend((0..=n).map(|k| lo + (hi - lo) * (k as Real + 0.37) / n as Real));
        }
        samples.extend([0.2 * start, 0.9 * start, a, b, 0.5 * (b + r_c), r_c * 0.999]);
        let (mut ef, mut eu): (Real, Real) = (0.0, 0.0);
        for r in samples.into_iter().filter(|&r| r > 0.0 && r < r_c) {
            let (u, du) = c.eval(r);
            let (ue, due) = x.eval_exact(r);
            ef = ef.max((du - due).abs() / f_max);
            eu = eu.max((u - ue).abs() / depth);
        }
        eprintln!(
            "cohesion table alpha {alpha:e} cutoff {r_c:.4}: {} nodes on [{a:.4}, {b:.4}], \
             force error {ef:.2e} f_max, energy error {eu:.2e} depth",
            c.table_nodes_in_use()
        );
        assert!(
            ef <= TABLE_FORCE_TOLERANCE,
            "alpha {alpha} cutoff {r_c}: {ef:e}"
        );
        assert!(
            eu <= TABLE_ENERGY_TOLERANCE,
            "alpha {alpha} cutoff {r_c}: {eu:e}"
        );
    }
    // The default keeps its table: 1024 nodes over [table_start r0, r_c].
    let c = d.prepare().unwrap();
    assert_eq!(c.table_nodes_in_use(), 1024);
    assert_eq!(c.table_range_in_use(), Some((0.5, c.cutoff())));
}

#[test]
fn tabulated_force_is_the_derivative_of_the_tabulated_energy() {
    let c = CohesionParams::default().prepare().unwrap();
    assert!(c.is_tabulated());
    for k in 0..500 {
        let r = 0.3 + 1.75 * k as Real / 499.0;
        let h = 1e-7;
        let fd = (c.eval(r + h).0 - c.eval(r - h).0) / (2.0 * h);
        let du = c.eval(r).1;
        assert!(
            (fd - du).abs() < 1e-6 * (1.0 + du.abs()),
            "r={r}: {fd} vs {du}"
        );
    }
    // Joins the exact fallback continuously at the table start.
    let s = 0.5;
    let (a, b) = (c.eval(s - 1e-12), c.eval(s + 1e-12));
    assert!((a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-8);
}

#[test]
fn continuous_at_the_cutoff() {
    for p in variants() {
        for c in [exact(p), p.prepare().unwrap()] {
            let rc = c.cutoff();
            let (u, du) = c.eval(rc * (1.0 - 1e-7));
            assert!(u.abs() < 1e-15 && du.abs() < 1e-12, "{u} {du}");
            assert_eq!(c.eval(rc), (0.0, 0.0));
        }
    }
}

#[test]
fn validation_rejects_bad_values() {
    let d = CohesionParams::default();
    let cases = [
        (CohesionParams { e: Real::NAN, ..d }, "cohesion.e"),
        (CohesionParams { r0: 0.0, ..d }, "cohesion.r0"),
        (CohesionParams { alpha: -3.0, ..d }, "cohesion.alpha"),
        (
            CohesionParams {
                cutoff: Some(Real::INFINITY),
                ..d
            },
            "cohesion.cutoff",
        ),
        (
            CohesionParams {
                cutoff: Some(1.2),
                ..d
            },
            "maximum attraction",
        ),
        (CohesionParams { taper: 0.9, ..d }, "maximum attraction"),
        (
            CohesionParams {
                taper: Real::NAN,
                ..d
            },
            "cohesion.taper",
        ),
        (
            CohesionParams {
                table_start: 1.0,
                ..d
            },
            "cohesion.table_start",
        ),
        (
            CohesionParams {
                table_nodes: 3,
                ..d
            },
            "cohesion.table_nodes",
        ),
    ];
    for (p, needle) in cases {
        let e = p.prepare().unwrap_err().within("cohesion").to_string();
        assert!(e.contains(needle), "{needle}: {e}");
    }
}
