//! Cohesion spacing force (seed 002 §3).
//!
//! Lombardo & Puech replace Lennard-Jones by the force
//!
//! `f(r) = E (r0 - r)³ / r · exp(-α (r0 - r)²)`   (positive = repulsive)
//!
//! which is repulsive below `r0`, zero at `r0` with zero slope (`f'(r0) = 0`,
//! so explicit integrators oscillate much less), attractive beyond with a
//! maximum attraction at `r_m` and a Gaussian fall-off. We taper it,
//! `f_cut = f s(r)` (see [`super::cutoff`]), and define the energy as its
//! integral, `U(r) = ∫_r^{r_c} f_cut`, so that the force on `j` is exactly
//! `-U'(r) r/|r|` and energy is conserved.
//!
//! `U` has no closed form. Two evaluation modes ([`CohesionMode`]):
//!
//! - **exact**: the force in closed form; the energy by composite 16-point
//!   Gauss–Legendre quadrature on a fixed partition of `[0.01 r0, r_c]` whose
//!   tail integrals are precomputed (a query integrates one partial panel).
//!   Panels are at most `min(0.5/√α, r0/4)` wide and never span more than a
//!   factor 2 in `r`, so the `1/r` growth near 0 stays three half-widths away
//!   from every panel and the rule is accurate to round-off (~1e-14
//!   relative, measured in the tests). Below `0.01 r0` panels halve down to
//!   `r` (the energy grows like `-ln r`).
//! - **tabulated** (default): a cubic Hermite table of `U` with `U' = -f_cut`
//!   at uniform nodes over the range where the force is not negligible
//!   (below); the tabulated force is exactly minus the derivative of the
//!   tabulated energy. Below `table_start r0` the exact mode is used (the
//!   two join continuously).
//!
//! **Tabulated range.** `f` decays like a Gaussian away from `r0`, so a
//! cut-off far beyond the well (up to 1000 r0 is accepted) would spread
//! uniform nodes over a range where the force is zero to round-off: 1024
//! nodes up to 1000 r0 made the force 121% wrong and the well 4.7x too
//! deep. The table covers only `[a, b]`: `b = min(r_c, r0 + u_b)` with
//! `|f| <= 1e-16 f_max` beyond `r0 + u_b` ([`NEGLIGIBLE_FORCE`]; `|f|`
//! decreases monotonically there), and `a = max(table_start r0, r0 - u_a)`
//! with `E u³/(table_start r0) exp(-α u²) <= 1e-16 f_max` for `u >= u_a`.
//! Beyond `b` the energy and force are exactly 0 (the dropped tail
//! `∫_b^{r_c} f_cut` is below `1e-16 f_max / κ`, `κ = -d ln|f|/dr` at `b`,
//! as `ln|f|` is concave there); on `[table_start r0, a)` the energy is the
//! constant `U(a)` with zero force. The energy stays continuous everywhere
//! (0 at `b` and at the cut-off) and the force is `-dU/dr` exactly; the
//! force jumps by at most `1e-16 f_max` at `a` and `b`.
//!
//! **Error bound (tabulated mode).** For every `r > 0`,
//! `|f_table(r) - f_cut(r)| <= 1e-6 f_max` ([`TABLE_FORCE_TOLERANCE`]) and
//! `|U_table(r) - U(r)| <= 1e-9 |U(r0)|` ([`TABLE_ENERGY_TOLERANCE`], the
//! well depth). [`CohesionParams::prepare`] checks it on every interval at
//! the points where the cubic Hermite error of the force (`τ = ½ ± 1/√12`)
//! and of the energy (`τ = ½`) peaks, against the exact mode, and raises
//! the node count above `table_nodes` until it holds (at most 1 000 000
//! nodes, an error beyond; no accepted parameters need that many: the
//! tests sweep `α r0²` from 1e-2 to 1e6 and cut-offs up to 1000 r0). The
//! default (cut-off ≈ 2.08 r0) keeps its 1024 nodes over
//! `[0.5 r0, r_c]`.
//!
//! Default cut-off: where `|f|` falls to [`AUTO_CUTOFF_RATIO`] (1e-6) of the
//! maximum attraction. Reach and core softness are traded against each other
//! by `α` (docs/model.md §7): a large `α` narrows the well and shortens the reach
//! but softens the repulsive core.

use super::cutoff::{validate_fraction, Taper};
use super::quadrature::{gauss_legendre, HermiteTable};
use crate::error::{check, positive, ParamError};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// The default cut-off is where `|f|` has fallen to this fraction of the
/// maximum attraction force.
pub const AUTO_CUTOFF_RATIO: Real = 1e-6;

/// Force magnitude, as a fraction of the maximum attraction `f_max`, below
/// which the tabulated mode treats the force as zero (module docs).
pub const NEGLIGIBLE_FORCE: Real = 1e-16;

/// Largest tabulated force error as a fraction of `f_max` (module docs).
pub const TABLE_FORCE_TOLERANCE: Real = 1e-6;

/// Largest tabulated energy error as a fraction of the well depth
/// `|U(r0)|` (module docs).
pub const TABLE_ENERGY_TOLERANCE: Real = 1e-9;

/// Most table nodes [`CohesionParams::prepare`] may use to meet the
/// tolerances, and the largest [`CohesionParams::table_nodes`].
const MAX_TABLE_NODES: usize = 1_000_000;
/// The smallest [`CohesionParams::table_nodes`].
const MIN_TABLE_NODES: usize = 16;

/// How the cohesion energy and force are evaluated.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum CohesionMode {
    /// Closed-form force, quadrature energy (reference; slower).
    Exact,
    /// Cubic Hermite table of the energy (fast; see the module docs).
    Tabulated,
}

/// Parameters of the cohesion force (seed 002 §3).
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct CohesionParams {
    /// Scaling factor `E` (> 0): stiffness. Default: 200 (maximum
    /// attraction ≈ 0.98 at `r ≈ 1.29` with the default `r0` and `alpha`).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub e: Real,
    /// Rest distance `r0` (> 0). Default: 1.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub r0: Real,
    /// Gaussian decay `α` (> 0, units 1/length²). Default: 16 (reach
    /// ≈ 2.08 r0 with the automatic cut-off).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub alpha: Real,
    /// Cut-off radius, or `None` for the automatic one (where `|f|` falls
    /// to 1e-6 of its maximum attraction). The taper must start beyond the
    /// maximum-attraction distance `r_m`. Default: `None`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub cutoff: Option<Real>,
    /// Fraction of the cut-off over which the force is tapered to 0
    /// (`0 < taper <= 1`). Default: 0.1.
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 1))]
    pub taper: Real,
    /// Evaluation mode. Default: `Tabulated`.
    pub mode: CohesionMode,
    /// Start of the table as a fraction of `r0` (`0 < table_start < 1`);
    /// shorter distances use the exact mode. Default: 0.5.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    pub table_start: Real,
    /// Number of table nodes at least (16 ..= 1 000 000), over the range
    /// where the force is not negligible; raised when needed to meet the
    /// error bound of the module docs. Default: 1024.
    #[schemars(range(min = MIN_TABLE_NODES, max = MAX_TABLE_NODES))]
    pub table_nodes: usize,
}

impl Default for CohesionParams {
    fn default() -> Self {
        CohesionParams {
            e: 200.0,
            r0: 1.0,
            alpha: 16.0,
            cutoff: None,
            taper: 0.1,
            mode: CohesionMode::Tabulated,
            table_start: 0.5,
            table_nodes: 1024,
        }
    }
}

/// The untapered cohesion force `f(r) = E (r0-r)³/r exp(-α(r0-r)²)`
/// (positive = repulsive).
#[inline]
pub fn cohesion_force(e: Real, r0: Real, alpha: Real, r: Real) -> Real {
    let d = r0 - r;
    e * d * d * d / r * (-alpha * d * d).exp()
}

/// Offset `u_m = r_m - r0` of the maximum attraction: the positive root of
/// `3 r0 + 2u - 2α r0 u² - 2α u³` (from `d ln|f|/du = 0`).
fn max_attraction_offset(r0: Real, alpha: Real) -> Real {
    let p = |u: Real| 3.0 * r0 + 2.0 * u - 2.0 * alpha * u * u * (r0 + u);
    let mut hi = (1.5 / alpha).sqrt();
    while p(hi) > 0.0 {
        hi *= 2.0;
    }
    bisect(0.0, hi, |u| p(u) > 0.0)
}

/// Bisection to round-off of a predicate true at `lo` and false at `hi`.
fn bisect(mut lo: Real, mut hi: Real, below: impl Fn(Real) -> bool) -> Real {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

impl CohesionParams {
    /// `(r_m, f_max)`: where the untapered force is most attractive and the
    /// magnitude of that attraction. Useful to match Lennard-Jones to
    /// cohesion (same maximum attraction, docs/model.md §7). Needs `r0`, `alpha`
    /// and `e` valid.
    pub fn max_attraction(&self) -> (Real, Real) {
        let u = max_attraction_offset(self.r0, self.alpha);
        let r_m = self.r0 + u;
        (r_m, cohesion_force(self.e, self.r0, self.alpha, r_m).abs())
    }

    /// The cut-off in use: `cutoff`, or where `|f|` falls to
    /// [`AUTO_CUTOFF_RATIO`] of the maximum attraction.
    pub fn effective_cutoff(&self) -> Real {
        if let Some(c) = self.cutoff {
            return c;
        }
        let (r_m, f_max) = self.max_attraction();
        let u_m = r_m - self.r0;
        let target = (AUTO_CUTOFF_RATIO * f_max).ln();
        let ln_f = |u: Real| self.e.ln() + 3.0 * u.ln() - (self.r0 + u).ln() - self.alpha * u * u;
        let mut hi = 2.0 * u_m;
        while ln_f(hi) > target {
            hi *= 2.0;
        }
        self.r0 + bisect(u_m, hi, |u| ln_f(u) > target)
    }

    /// Rejects NaN, infinite and out-of-range values.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("e", self.e)?;
        positive("r0", self.r0)?;
        positive("alpha", self.alpha)?;
        // Bounds that keep the quadrature partition and the automatic
        // cut-off search finite: the well's width is ~1/sqrt(alpha), so
        // alpha r0^2 outside [1e-6, 1e6] describes no useful cohesion and
        // would need an unbounded number of panels.
        let a = self.alpha * self.r0 * self.r0;
        check(
            "alpha",
            self.alpha,
            (1e-6..=1e6).contains(&a),
            "must satisfy 1e-6 <= alpha * r0^2 <= 1e6 (the well's width is about 1/sqrt(alpha))",
        )?;
        if let Some(c) = self.cutoff {
            positive("cutoff", c)?;
            check(
                "cutoff",
                c,
                c <= 1000.0 * self.r0,
                "must be at most 1000 r0 (cohesion acts over a few r0)",
            )?;
        }
        validate_fraction("taper", self.taper)?;
        check(
            "table_start",
            self.table_start,
            self.table_start.is_finite() && self.table_start > 0.0 && self.table_start < 1.0,
            "must be a fraction of r0 with 0 < table_start < 1",
        )?;
        check(
            "table_nodes",
            self.table_nodes as Real,
            (MIN_TABLE_NODES..=MAX_TABLE_NODES).contains(&self.table_nodes),
            "must be between 16 and 1000000",
        )?;
        let (r_m, _) = self.max_attraction();
        let r_c = self.effective_cutoff();
        let r_on = r_c * (1.0 - self.taper);
        if r_on.is_nan() || r_on < r_m {
            return Err(ParamError::Invalid {
                field: "cutoff".into(),
                message: format!(
                    "the taper starts at cutoff*(1-taper) = {r_on} (cutoff {r_c}), which must be \
                     beyond the maximum attraction distance r_m = {r_m}: raise cutoff or lower taper"
                ),
            });
        }
        Ok(())
    }

    /// Validates, integrates the energy partition and (in tabulated mode)
    /// builds the table.
    pub fn prepare(&self) -> Result<Cohesion, ParamError> {
        self.validate()?;
        let (r_m, f_max) = self.max_attraction();
        let r_c = self.effective_cutoff();
        let mut c = Cohesion {
            e: self.e,
            r0: self.r0,
            alpha: self.alpha,
            taper: Taper::new(r_c, self.taper),
            r_m,
            f_max,
            breaks: Vec::new(),
            tail: Vec::new(),
            table: None,
            zero_from: r_c,
            flat_from: r_c,
            flat_energy: 0.0,
            exact_offset: 0.0,
        };
        c.build_partition();
        if self.mode == CohesionMode::Tabulated {
            c.build_table(self.table_start * self.r0, self.table_nodes)?;
        }
        Ok(c)
    }
}

/// The largest `x` in `[lo, hi]` with `g(x) > 0`, for `g` decreasing on
/// `[lo, hi]` with `g(lo) > 0` (bisection to round-off; `hi` if `g(hi) > 0`).
fn last_positive(lo: Real, hi: Real, g: impl Fn(Real) -> Real) -> Real {
    if g(hi) > 0.0 {
        hi
    } else {
        bisect(lo, hi, |x| g(x) > 0.0)
    }
}

/// The prepared cohesion force and energy (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Cohesion {
    e: Real,
    r0: Real,
    alpha: Real,
    taper: Taper,
    r_m: Real,
    f_max: Real,
    /// Ascending panel breakpoints from `0.01 r0` to `r_c` (includes `r_on`).
    breaks: Vec<Real>,
    /// `tail[k] = ∫_{breaks[k]}^{r_c} f_cut`.
    tail: Vec<Real>,
    table: Option<HermiteTable>,
    /// Energy and force are 0 from here on: the cut-off, or the table's end
    /// where the force became negligible.
    zero_from: Real,
    /// With a table starting above `table_start r0`: from here up to the
    /// table the energy is `flat_energy` and the force 0 (module docs).
    flat_from: Real,
    /// The table's energy at its first node.
    flat_energy: Real,
    /// Subtracted from the exact energy below the flat part / table, so
    /// the energy stays continuous where the table drops the negligible
    /// integrals.
    exact_offset: Real,
}

impl Cohesion {
    /// `(a, b)`: the range `[a, b]` within `[start, r_c]` outside which the
    /// force is negligible (module docs).
    fn table_range(&self, start: Real) -> (Real, Real) {
        let (r0, alpha, e) = (self.r0, self.alpha, self.e);
        let target = (NEGLIGIBLE_FORCE * self.f_max).ln();
        // Beyond the well: |f| decreases monotonically past r_m.
        let u_m = self.r_m - r0;
        let ln_f = |u: Real| e.ln() + 3.0 * u.ln() - (r0 + u).ln() - alpha * u * u;
        let mut hi = 2.0 * u_m;
        while ln_f(hi) > target && r0 + hi < self.cutoff() {
            hi *= 2.0;
        }
        let b = (r0 + last_positive(u_m, hi, |u| ln_f(u) - target)).min(self.cutoff());
        // Inside the core: bound |f| by E u³/start exp(-α u²), which
        // increases up to u* = sqrt(1.5/α) and decreases beyond.
        let u_max = r0 - start;
        let u_star = (1.5 / alpha).sqrt();
        let ln_bound = |u: Real| e.ln() + 3.0 * u.ln() - start.ln() - alpha * u * u;
        let a = if u_star >= u_max || ln_bound(u_max) > target {
            start
        } else {
            r0 - last_positive(u_star, u_max, |u| ln_bound(u) - target)
        };
        (a.max(start), b)
    }

    /// Builds the table over [`Self::table_range`] with at least `nodes`
    /// nodes, raising the count until the error bound of the module docs
    /// holds at the interpolation error peaks of every interval.
    fn build_table(&mut self, start: Real, nodes: usize) -> Result<(), ParamError> {
        let (a, b) = self.table_range(start);
        let tail_b = self.energy_exact(b);
        let depth = self.energy_exact(self.r0).abs();
        let mut n = nodes;
        loop {
            let table =
                HermiteTable::new(a, b, n, |r| (self.energy_exact(r) - tail_b, -self.force(r)));
            let (ef, eu) = self.table_error(&table);
            let (rf, ru) = (
                ef / (TABLE_FORCE_TOLERANCE * self.f_max),
                eu / (TABLE_ENERGY_TOLERANCE * depth),
            );
            if rf <= 1.0 && ru <= 1.0 {
                self.zero_from = b;
                self.flat_from = start;
                self.flat_energy = table.eval(a).0;
                self.exact_offset = self.energy_exact(start) - self.flat_energy;
                self.table = Some(table);
                return Ok(());
            }
            if n >= MAX_TABLE_NODES {
                return Err(ParamError::Invalid {
                    field: "table_nodes".into(),
                    message: format!(
                        "{MAX_TABLE_NODES} nodes on [{a}, {b}] do not reach the table's error \
                         bound (force error {:.1e} f_max, energy error {:.1e} of the well \
                         depth): use the exact mode",
                        ef / self.f_max,
                        eu / depth
                    ),
                });
            }
            // Force error ~ n^-3, energy error ~ n^-4; 25% margin.
            let grow = rf.cbrt().max(ru.powf(0.25)).max(1.0) * 1.25;
            n = ((n as Real * grow).ceil() as usize).min(MAX_TABLE_NODES);
        }
    }

    /// Largest force and energy errors of `table` against the exact mode,
    /// at the points of every interval where the cubic Hermite error of the
    /// energy (`τ = ½`) and of its derivative (`τ = ½ ± 1/√12`) peaks.
    fn table_error(&self, table: &HermiteTable) -> (Real, Real) {
        let offset = 0.5 / (3.0 as Real).sqrt();
        let (a, h) = (table.start(), table.spacing());
        let intervals = ((table.end() - a) / h).round() as usize;
        let (mut ef, mut eu): (Real, Real) = (0.0, 0.0);
        for k in 0..intervals {
            for t in [0.5 - offset, 0.5, 0.5 + offset] {
                let r = a + (k as Real + t) * h;
                let (u, du) = table.eval(r);
                ef = ef.max((du + self.force(r)).abs());
                eu = eu.max((u - self.energy_exact(r)).abs());
            }
        }
        (ef, eu)
    }

    fn build_partition(&mut self) {
        let r_c = self.taper.cutoff();
        let r_on = self.taper.r_on();
        let width = (0.5 / self.alpha.sqrt()).min(0.25 * self.r0);
        let s_lo = 0.01 * self.r0;
        let mut breaks = Vec::new();
        let mut b = r_on;
        loop {
            breaks.push(b);
            if b <= s_lo {
                break;
            }
            b = (b - width).max(0.5 * b).max(s_lo);
        }
        breaks.reverse();
        let n_top = ((r_c - r_on) / width).ceil().max(1.0) as usize;
        for k in 1..=n_top {
            breaks.push(if k == n_top {
                r_c
            } else {
                r_on + (r_c - r_on) * k as Real / n_top as Real
            });
        }
        let mut tail = vec![0.0; breaks.len()];
        for k in (0..breaks.len() - 1).rev() {
            tail[k] = tail[k + 1] + self.panel(breaks[k], breaks[k + 1]);
        }
        self.breaks = breaks;
        self.tail = tail;
    }

    /// `∫_a^b f_cut` on one panel.
    fn panel(&self, a: Real, b: Real) -> Real {
        gauss_legendre(a, b, |s| self.force(s))
    }

    /// The cut-off radius.
    #[inline]
    pub fn cutoff(&self) -> Real {
        self.taper.cutoff()
    }

    /// The rest distance `r0`.
    pub fn r0(&self) -> Real {
        self.r0
    }

    /// `(r_m, f_max)`: distance and magnitude of the maximum attraction.
    pub fn max_attraction(&self) -> (Real, Real) {
        (self.r_m, self.f_max)
    }

    /// True when the energy is tabulated.
    pub fn is_tabulated(&self) -> bool {
        self.table.is_some()
    }

    /// The tapered force `f_cut(r) = f(r) s(r)` (positive = repulsive),
    /// closed form, for `r > 0`.
    #[inline]
    pub fn force(&self, r: Real) -> Real {
        if r >= self.taper.cutoff() {
            return 0.0;
        }
        cohesion_force(self.e, self.r0, self.alpha, r) * self.taper.eval(r).0
    }

    /// `U(r) = ∫_r^{r_c} f_cut` by quadrature, for `r > 0`.
    pub fn energy_exact(&self, r: Real) -> Real {
        if r >= self.taper.cutoff() {
            return 0.0;
        }
        let s_lo = self.breaks[0];
        if r >= s_lo {
            let k = self.breaks.partition_point(|&b| b <= r);
            self.panel(r, self.breaks[k]) + self.tail[k]
        } else {
            let mut sum = self.tail[0];
            let mut b = s_lo;
            while b > r {
                let a = (0.5 * b).max(r);
                sum += self.panel(a, b);
                b = a;
            }
            sum
        }
    }

    /// `(U(r), dU/dr)` in the exact mode.
    pub fn eval_exact(&self, r: Real) -> (Real, Real) {
        (self.energy_exact(r), -self.force(r))
    }

    /// `(U(r), dU/dr)` in the configured mode, for `r > 0`; zero beyond
    /// the cut-off (and, tabulated, beyond the range where the force is
    /// not negligible, see the module docs).
    #[inline]
    pub fn eval(&self, r: Real) -> (Real, Real) {
        if r >= self.zero_from {
            return (0.0, 0.0);
        }
        match &self.table {
            Some(t) if r >= t.start() => t.eval(r),
            _ => self.eval_below_table(r),
        }
    }

    /// [`Self::eval`] below the table: the flat part, then the exact mode
    /// (shifted to join the table continuously).
    #[cold]
    fn eval_below_table(&self, r: Real) -> (Real, Real) {
        if self.table.is_none() {
            self.eval_exact(r)
        } else if r >= self.flat_from {
            (self.flat_energy, 0.0)
        } else {
            (self.energy_exact(r) - self.exact_offset, -self.force(r))
        }
    }

    /// The tabulated range `[a, b]` (module docs), or `None` in the exact
    /// mode.
    pub fn table_range_in_use(&self) -> Option<(Real, Real)> {
        self.table.as_ref().map(|t| (t.start(), t.end()))
    }

    /// Number of table nodes in use (0 in the exact mode).
    pub fn table_nodes_in_use(&self) -> usize {
        self.table.as_ref().map_or(0, |t| {
            ((t.end() - t.start()) / t.spacing()).round() as usize + 1
        })
    }
}

#[cfg(test)]
mod tests;
