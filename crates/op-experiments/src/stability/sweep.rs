//! The stability table (stiffness x time step x integrator) and the largest
//! stable step per integrator against the effective stiffness, with its
//! log-log slope (symplectic schemes should follow `dt ~ sqrt(m/k)`, slope
//! -1/2; see [`super::probe`] for the systems, the stiffness and the
//! outcomes).

use op_dynamics::{AdaptiveParams, Real, Scheme};

use super::probe::{run, Outcome, Potential, Probe};

/// Longest simulated time of a table run.
pub const TABLE_T_MAX: Real = 40.0;

/// The integrators of the table, in order (the adaptive one with
/// `rtol = 1e-6`; its `dt` is the largest step it may take).
pub fn table_schemes() -> Vec<Scheme> {
    vec![
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
        Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-6)),
    ]
}

/// The fixed-step integrators, whose largest stable step is searched.
pub fn fixed_step_schemes() -> Vec<Scheme> {
    table_schemes()
        .into_iter()
        .filter(|s| !matches!(s, Scheme::Adaptive(_)))
        .collect()
}

/// One cell of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// The probe.
    pub probe: Probe,
    /// Its effective stiffness `λ`.
    pub stiffness: Real,
    /// Time step (largest step for the adaptive scheme).
    pub dt: Real,
    /// Integrator name ([`Scheme::name`]).
    pub scheme: String,
    /// How the run ended.
    pub outcome: Outcome,
}

/// Runs every probe of `values` (per potential) with every scheme at every
/// `dt`, each until [`TABLE_T_MAX`].
pub fn table(values: &[(Potential, Vec<Real>)], dts: &[Real], schemes: &[Scheme]) -> Vec<Cell> {
    let mut cells = Vec::new();
    for (potential, vs) in values {
        for &value in vs {
            let probe = Probe {
                potential: *potential,
                value,
            };
            let stiffness = probe.stiffness();
            for &dt in dts {
                for &scheme in schemes {
                    cells.push(Cell {
                        probe,
                        stiffness,
                        dt,
                        scheme: scheme.name().to_string(),
                        outcome: run(&probe, scheme, dt, TABLE_T_MAX, u64::MAX),
                    });
                }
            }
        }
    }
    cells
}

/// Settings of the largest-stable-step search.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SearchSettings {
    /// Steps of each trial run: a step size is stable when the run does
    /// not diverge within this many steps (or [`TABLE_T_MAX`]).
    pub steps: u64,
    /// First trial, in units of `1/sqrt(λ)`.
    pub start: Real,
    /// Bisections (in log dt) after bracketing: the result is within a
    /// factor `2^(1/2^bisections)` of the boundary.
    pub bisections: u32,
}

impl Default for SearchSettings {
    /// 3000 steps, start at `0.01/sqrt(λ)`, 6 bisections (1%).
    fn default() -> Self {
        SearchSettings {
            steps: 3000,
            start: 0.01,
            bisections: 6,
        }
    }
}

/// The largest step with which `probe` does not diverge under `scheme`
/// (a broken bond is not a divergence: see [`super::probe`])
/// (within the search's resolution), found by doubling or halving from
/// `start / sqrt(λ)` until the outcome changes, then bisecting in `log dt`.
/// `None` if no step in `[1e-6, 1e3] / sqrt(λ)` is stable or all are.
pub fn largest_stable_dt(
    probe: &Probe,
    stiffness: Real,
    scheme: Scheme,
    s: &SearchSettings,
) -> Option<Real> {
    let unit = 1.0 / stiffness.sqrt();
    let stable = |dt: Real| !run(probe, scheme, dt, TABLE_T_MAX, s.steps).diverged();
    let (mut lo, mut hi) = (s.start * unit, s.start * unit);
    if stable(lo) {
        while stable(hi) {
            lo = hi;
            hi *= 2.0;
            if hi > 1e3 * unit {
                return None;
            }
        }
    } else {
        while !stable(lo) {
            hi = lo;
            lo *= 0.5;
            if lo < 1e-6 * unit {
                return None;
            }
        }
    }
    for _ in 0..s.bisections {
        let mid = (lo * hi).sqrt();
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// Largest stable steps of one integrator for one potential.
#[derive(Clone, Debug, PartialEq)]
pub struct StableSteps {
    /// The potential.
    pub potential: Potential,
    /// Integrator name.
    pub scheme: String,
    /// `(λ, largest stable dt)` per stiffness value (values without a
    /// bracket are left out).
    pub points: Vec<(Real, Real)>,
}

impl StableSteps {
    /// The least-squares slope of `log dt` against `log λ`, or `None` with
    /// fewer than two points.
    pub fn slope(&self) -> Option<Real> {
        log_log_slope(&self.points)
    }

    /// The median of `dt · sqrt(λ)` (the step in units of `sqrt(m/k)`).
    pub fn median_dimensionless(&self) -> Option<Real> {
        let mut v: Vec<Real> = self.points.iter().map(|(k, dt)| dt * k.sqrt()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(Real::total_cmp);
        Some(v[v.len() / 2])
    }
}

/// Least-squares slope of `log y` against `log x` (positive values only).
pub fn log_log_slope(points: &[(Real, Real)]) -> Option<Real> {
    let pts: Vec<(Real, Real)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as Real;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let sxy: Real = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: Real = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The largest stable step of every scheme of `schemes` for every value
/// of `values` of `potential`.
pub fn stable_steps(
    potential: Potential,
    values: &[Real],
    schemes: &[Scheme],
    s: &SearchSettings,
) -> Vec<StableSteps> {
    let probes: Vec<(Probe, Real)> = values
        .iter()
        .map(|&value| {
            let p = Probe { potential, value };
            (p, p.stiffness())
        })
        .collect();
    schemes
        .iter()
        .map(|&scheme| StableSteps {
            potential,
            scheme: scheme.name().to_string(),
            points: probes
                .iter()
                .filter_map(|(p, k)| largest_stable_dt(p, *k, scheme, s).map(|dt| (*k, dt)))
                .collect(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law_is_its_exponent() {
        let pts: Vec<(Real, Real)> = (0..5)
            .map(|k| {
                let x = 10f64.powi(k);
                (x, 3.0 * x.powf(-0.5))
            })
            .collect();
        assert!((log_log_slope(&pts).unwrap() + 0.5).abs() < 1e-12);
        assert_eq!(log_log_slope(&pts[..1]), None);
    }

    #[test]
    fn verlet_limit_is_near_the_linear_one_for_lennard_jones() {
        // Velocity Verlet on a linear oscillator is stable for ω dt < 2;
        // the damped, nonlinear pair should be close to it.
        let probe = Probe {
            potential: Potential::LennardJones,
            value: 4.0,
        };
        let k = probe.stiffness();
        let dt = largest_stable_dt(
            &probe,
            k,
            Scheme::VelocityVerlet,
            &SearchSettings::default(),
        )
        .expect("a bracket");
        let ratio = dt * k.sqrt();
        assert!(ratio > 1.0 && ratio < 4.0, "ω dt = {ratio}");
    }
}
