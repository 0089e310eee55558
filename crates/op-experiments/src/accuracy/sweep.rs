//! A case swept over methods: the reference and its convergence check,
//! every measurement, the Pareto front of (wall time, error) and the time
//! each integrator needs to reach an error (docs/model.md §6).

use op_dynamics::Real;

use super::case::{Case, Method};
use super::run::{errors, measure, simulate, Errors, Measurement, Trajectory};

/// Everything measured on one case.
#[derive(Clone, Debug)]
pub struct CaseSweep {
    /// The case name.
    pub name: String,
    /// The reference method.
    pub reference: Method,
    /// The reference run.
    pub reference_run: Trajectory,
    /// The reference against [`Method::refined`] of it: how far the
    /// reference is from converged (its own error is about this
    /// difference, or less, for a method of order >= 1).
    pub reference_check: Errors,
    /// Wall seconds of the reference run and of the refined run.
    pub reference_seconds: (f64, f64),
    /// One measurement per method of [`Case::methods`].
    pub rows: Vec<Measurement>,
}

/// Runs the reference, its refined check, then every method of the case
/// (`repeats` timed runs each); `progress` is told each method's label.
///
/// # Errors
///
/// When the reference or its check fails (diverges, does not build).
pub fn sweep_case(
    case: &Case,
    repeats: usize,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseSweep, String> {
    let e = &case.entry;
    progress(&format!("{}: reference {}", e.name, e.reference.label()));
    let clock = std::time::Instant::now();
    let reference_run =
        simulate(case, &e.reference).map_err(|m| format!("{}: reference: {m}", e.name))?;
    let t_ref = clock.elapsed().as_secs_f64();
    let refined = e.reference.refined();
    progress(&format!("{}: reference check {}", e.name, refined.label()));
    let clock = std::time::Instant::now();
    let refined_run =
        simulate(case, &refined).map_err(|m| format!("{}: refined reference: {m}", e.name))?;
    let t_refined = clock.elapsed().as_secs_f64();
    let reference_check = errors(&reference_run, &refined_run, case.r0, e.conservative);
    let rows = case
        .methods()
        .iter()
        .map(|m| {
            progress(&format!("{}: {}", e.name, m.label()));
            measure(case, m, &refined_run, repeats)
        })
        .collect();
    Ok(CaseSweep {
        name: e.name.to_string(),
        reference: refined,
        reference_run: refined_run,
        reference_check,
        reference_seconds: (t_ref, t_refined),
        rows,
    })
}

/// For each point `(time, error)`, whether it is on the Pareto front: no
/// other point is at least as fast and at least as accurate, and strictly
/// better in one. Points with a non-finite coordinate are never on it
/// and never dominate.
pub fn pareto(points: &[(Real, Real)]) -> Vec<bool> {
    let ok = |&(t, e): &(Real, Real)| t.is_finite() && e.is_finite();
    points
        .iter()
        .map(|p| {
            ok(p)
                && !points
                    .iter()
                    .any(|q| ok(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

/// The wall time at which a curve of `(time, error)` points first reaches
/// `target`, interpolated linearly in `(log time, log error)` between the
/// last point above the target and the first one at or below it (points
/// taken in order of time). `None` if no point reaches it; the first
/// point's time if it already does (an upper bound).
pub fn time_to_error(curve: &[(Real, Real)], target: Real) -> Option<Real> {
    let mut pts: Vec<(Real, Real)> = curve
        .iter()
        .copied()
        .filter(|(t, e)| t.is_finite() && *t > 0.0 && e.is_finite() && *e > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let k = pts.iter().position(|&(_, e)| e <= target)?;
    if k == 0 {
        return Some(pts[0].0);
    }
    let (t0, e0) = pts[k - 1];
    let (t1, e1) = pts[k];
    let (lt0, lt1, le0, le1) = (t0.ln(), t1.ln(), e0.ln(), e1.ln());
    if le0 <= le1 {
        return Some(t1);
    }
    let s = (le0 - target.ln()) / (le0 - le1);
    Some((lt0 + s * (lt1 - lt0)).exp())
}

/// The least-squares slope of `log y` against `log x` (the measured order
/// when `x` is the step and `y` the error). NaN with fewer than two
/// positive points.
pub fn log_slope(x: &[Real], y: &[Real]) -> Real {
    let pts: Vec<(Real, Real)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| **a > 0.0 && **b > 0.0 && a.is_finite() && b.is_finite())
        .map(|(a, b)| (a.ln(), b.ln()))
        .collect();
    let n = pts.len() as Real;
    if pts.len() < 2 {
        return Real::NAN;
    }
    let mx = pts.iter().map(|p| p.0).sum::<Real>() / n;
    let my = pts.iter().map(|p| p.1).sum::<Real>() / n;
    let sxy: Real = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: Real = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

impl CaseSweep {
    /// The rows of one integrator ([`op_dynamics::Scheme::name`]), in sweep order.
    pub fn rows_of<'a>(&'a self, scheme: &'a str) -> impl Iterator<Item = &'a Measurement> + 'a {
        self.rows
            .iter()
            .filter(move |m| m.method.scheme.name() == scheme)
    }

    /// `(median wall time, RMS position error in r0)` of an integrator's
    /// runs that did not fail.
    pub fn curve(&self, scheme: &str) -> Vec<(Real, Real)> {
        self.rows_of(scheme)
            .filter_map(|m| {
                m.outcome
                    .as_ref()
                    .ok()
                    .map(|e| (m.timing.median(), e.position))
            })
            .collect()
    }

    /// The Pareto flag of every row (failed runs are off the front), for
    /// the position error.
    pub fn pareto_rows(&self) -> Vec<bool> {
        let pts: Vec<(Real, Real)> = self
            .rows
            .iter()
            .map(|m| match &m.outcome {
                Ok(e) => (m.timing.median(), e.position),
                Err(_) => (Real::NAN, Real::NAN),
            })
            .collect();
        pareto(&pts)
    }

    /// The measured order of a fixed-step integrator: the slope of its
    /// position error against its step, over its successful runs whose
    /// error is above `floor` (round-off and the reference's own error
    /// flatten the curve below it).
    pub fn order(&self, scheme: &str, floor: Real) -> Real {
        let (dts, errs): (Vec<Real>, Vec<Real>) = self
            .rows_of(scheme)
            .filter_map(|m| {
                m.outcome
                    .as_ref()
                    .ok()
                    .filter(|e| e.position > floor && e.position < 1e-1)
                    .map(|e| (m.method.dt, e.position))
            })
            .unzip();
        log_slope(&dts, &errs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_drops_dominated_points() {
        let front = pareto(&[
            (1.0, 1.0),
            (2.0, 0.5),
            (2.0, 2.0),
            (0.5, 3.0),
            (Real::NAN, 0.0),
        ]);
        assert_eq!(front, vec![true, true, false, true, false]);
    }

    #[test]
    fn time_to_error_interpolates_in_log_log() {
        let curve = [(1.0, 1e-2), (100.0, 1e-6)];
        let t = time_to_error(&curve, 1e-4).unwrap();
        assert!((t - 10.0).abs() < 1e-9, "{t}");
        assert_eq!(time_to_error(&curve, 1e-8), None);
        assert_eq!(time_to_error(&curve, 1.0), Some(1.0));
    }

    #[test]
    fn log_slope_of_a_power_law() {
        let x = [0.1, 0.05, 0.025];
        let y: Vec<Real> = x.iter().map(|h: &Real| 3.0 * h.powi(4)).collect();
        assert!((log_slope(&x, &y) - 4.0).abs() < 1e-9);
    }
}
