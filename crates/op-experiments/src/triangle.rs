//! The robustness test of seed 002 §3 (fig. 4): three particles on an
//! equilateral triangle of side `p · r0`, released at rest, for `p` from
//! 100% down to 20%.
//!
//! **Outcomes.** A run *diverges* when [`op_dynamics::World::step`] reports
//! it (non-finite state, or a speed above `1e3 r0/T`) or when a side
//! grows beyond the potential's cut-off: the bond is broken and the object
//! has exploded (seed 002 footnote 4, "the object explodes under the action
//! of too large interaction forces"). It *converges* at the first time the
//! oscillation measure `O` is below `tolerance · √3` and every side is
//! within `side_tolerance · r0` of `r0`. Otherwise, at `t_max`, it is
//! *undecided* (still oscillating).

use op_dynamics::interactions::{CohesionParams, LennardJonesParams, Spacing};
use op_dynamics::{Real, Scheme};

use super::oscillation::{hex_patch, oscillation_tolerance, spacing_world, Dynamics};

/// Criteria and limits of a triangle run.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TriangleSettings {
    /// Integration, damping and mass.
    pub dynamics: Dynamics,
    /// Longest simulated time.
    pub t_max: Real,
    /// Tolerance on `O` per particle (see
    /// [`super::oscillation::oscillation_tolerance`]).
    pub tolerance: Real,
    /// Largest `|side - r0| / r0` of a converged triangle.
    pub side_tolerance: Real,
}

impl Default for TriangleSettings {
    /// [`Dynamics::default`] (explicit Euler, `dt = 2e-3`, `β0 = 1`, unit
    /// masses), `t_max = 60`, `O < 1e-6 √3`, sides within 1% of `r0`.
    fn default() -> Self {
        TriangleSettings {
            dynamics: Dynamics::default(),
            t_max: 60.0,
            tolerance: 1e-6,
            side_tolerance: 0.01,
        }
    }
}

/// How a triangle run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Converged at this time.
    Converged(Real),
    /// Diverged at this time, for this reason.
    Diverged(Real, String),
    /// Neither by `t_max`.
    Undecided,
}

impl Outcome {
    /// True for [`Outcome::Converged`].
    pub fn converged(&self) -> bool {
        matches!(self, Outcome::Converged(_))
    }

    /// True for [`Outcome::Diverged`].
    pub fn diverged(&self) -> bool {
        matches!(self, Outcome::Diverged(..))
    }

    /// A short table cell: `conv. 12.3` (time to converge),
    /// `**DIVERGED** (0.41)` (time of divergence) or `undecided`.
    pub fn cell(&self) -> String {
        match self {
            Outcome::Converged(t) => format!("conv. {t:.1}"),
            Outcome::Diverged(t, _) => format!("**DIVERGED** ({t:.2})"),
            Outcome::Undecided => "undecided".into(),
        }
    }
}

/// Runs the triangle started at `p · r0` with `spacing`.
pub fn triangle(p: Real, spacing: Spacing, s: &TriangleSettings) -> Outcome {
    let (r0, cutoff) = match &spacing {
        Spacing::Cohesion(c) => (c.r0, c.effective_cutoff()),
        Spacing::LennardJones(l) => (l.r0, l.cutoff),
    };
    let start: Vec<_> = hex_patch(3, r0)
        .iter()
        .map(|q| op_dynamics::Point3::from(q.coords * p))
        .collect();
    let mut world = spacing_world(&start, spacing, &s.dynamics);
    let tol = oscillation_tolerance(s.tolerance, 3);
    while world.time() < s.t_max {
        if let Err(e) = world.step() {
            return Outcome::Diverged(world.time(), e.reason);
        }
        let pos = world.particles().positions();
        let sides = [(0, 1), (1, 2), (2, 0)].map(|(a, b)| (pos[b] - pos[a]).norm());
        if let Some(&side) = sides.iter().find(|&&d| d >= cutoff) {
            return Outcome::Diverged(
                world.time(),
                format!(
                    "a side reached {side:.3} >= the cut-off {cutoff}: the triangle broke apart"
                ),
            );
        }
        let off = sides.iter().map(|d| (d - r0).abs()).fold(0.0, Real::max);
        if world.oscillation() < tol && off < s.side_tolerance * r0 {
            return Outcome::Converged(world.time());
        }
    }
    Outcome::Undecided
}

/// The integrators of the table, in order.
pub fn schemes() -> Vec<Scheme> {
    vec![
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
        Scheme::Adaptive(op_dynamics::AdaptiveParams::with_tolerance(1e-6)),
    ]
}

/// The starting sizes of the table: 100% down to 20% in 5% steps.
pub fn percentages() -> Vec<u32> {
    (0..=16).map(|k| 100 - 5 * k).collect()
}

/// The largest `p` (percent) in `rows` where `outcome(row)` diverged.
pub fn largest_diverging(rows: &[(u32, Outcome)]) -> Option<u32> {
    rows.iter()
        .filter(|(_, o)| o.diverged())
        .map(|(p, _)| *p)
        .max()
}

/// The smallest `p` (percent) such that every run from 100% down to it
/// converged.
pub fn lowest_converging(rows: &[(u32, Outcome)]) -> Option<u32> {
    let mut sorted: Vec<&(u32, Outcome)> = rows.iter().collect();
    sorted.sort_by_key(|r| std::cmp::Reverse(r.0));
    let mut lowest = None;
    for (p, o) in sorted {
        if !o.converged() {
            break;
        }
        lowest = Some(*p);
    }
    lowest
}

/// Runs the triangle for every `p` of `percentages` with `spacing`.
pub fn sweep(spacing: Spacing, percentages: &[u32], s: &TriangleSettings) -> Sweep {
    percentages
        .iter()
        .map(|&p| (p, triangle(p as Real / 100.0, spacing, s)))
        .collect()
}

/// Outcomes by starting size in percent.
pub type Sweep = Vec<(u32, Outcome)>;

/// One integrator's runs of the p% table.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustnessColumn {
    /// The integrator ([`Scheme::name`]).
    pub scheme: String,
    /// Runs with cohesion.
    pub cohesion: Sweep,
    /// Runs with the matched Lennard-Jones.
    pub lennard_jones: Sweep,
}

/// The p% table: every integrator, both potentials.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustnessTable {
    /// The cohesion parameters it was measured with.
    pub cohesion: CohesionParams,
    /// The matched Lennard-Jones parameters.
    pub lennard_jones: LennardJonesParams,
    /// Settings (the scheme of `settings.dynamics` is replaced per column).
    pub settings: TriangleSettings,
    /// One column pair per integrator.
    pub columns: Vec<RobustnessColumn>,
}

impl RobustnessTable {
    /// Runs the triangle for every scheme of `schemes` and every size of
    /// `percentages`, with both potentials.
    pub fn run(
        cohesion: CohesionParams,
        lennard_jones: LennardJonesParams,
        settings: TriangleSettings,
        schemes: &[Scheme],
        percentages: &[u32],
    ) -> RobustnessTable {
        let columns = schemes
            .iter()
            .map(|&scheme| {
                let s = TriangleSettings {
                    dynamics: Dynamics {
                        scheme,
                        ..settings.dynamics
                    },
                    ..settings
                };
                RobustnessColumn {
                    scheme: scheme.name().to_string(),
                    cohesion: sweep(Spacing::Cohesion(cohesion), percentages, &s),
                    lennard_jones: sweep(Spacing::LennardJones(lennard_jones), percentages, &s),
                }
            })
            .collect();
        RobustnessTable {
            cohesion,
            lennard_jones,
            settings,
            columns,
        }
    }

    /// The parameters the table was measured with, as a sentence: the
    /// cohesion `E`, `r0`, `α` and cut-off, the matched `ε`, the damping,
    /// mass, step and criteria (the thresholds depend on them).
    pub fn conditions(&self) -> String {
        let c = &self.cohesion;
        let (_, f_max) = c.max_attraction();
        let d = &self.settings.dynamics;
        format!(
            "Cohesion E = {}, r0 = {}, **alpha = {}** (alpha r0² = {}), cut-off {}; Lennard-Jones \
             12-6 matched to it (same r0, same maximum attraction f_max = {:.4} with tapers, same \
             cut-off): \
             epsilon = {:.4}. **Linear damping beta0 = {}**, mass {}, time step {}, at most {} time \
             units. Converged: O < {:.0e} √3 and every side within {}% of r0. Diverged: non-finite \
             state or a speed above 1e3, or a side beyond the cut-off (the triangle broke apart).",
            c.e,
            c.r0,
            c.alpha,
            c.alpha * c.r0 * c.r0,
            c.effective_cutoff(),
            f_max,
            self.lennard_jones.epsilon,
            d.damping,
            d.mass,
            d.dt,
            self.settings.t_max,
            self.settings.tolerance,
            self.settings.side_tolerance * 100.0,
        )
    }

    /// The markdown table: one row per starting size, two columns
    /// (cohesion, Lennard-Jones) per integrator, converged runs with their
    /// time to converge; then the lowest size from which every larger one
    /// converged, and the largest size that diverged.
    pub fn markdown(&self) -> String {
        let mut s = format!("{}\n\n| p |", self.conditions());
        for c in &self.columns {
            s.push_str(&format!(" {0}: cohesion | {0}: LJ |", c.scheme));
        }
        s.push_str("\n|---|");
        s.push_str(&"---|---|".repeat(self.columns.len()));
        s.push('\n');
        let sizes: Vec<u32> = self
            .columns
            .first()
            .map(|c| c.cohesion.iter().map(|r| r.0).collect())
            .unwrap_or_default();
        for (row, p) in sizes.iter().enumerate() {
            s.push_str(&format!("| {p}% |"));
            for c in &self.columns {
                s.push_str(&format!(
                    " {} | {} |",
                    c.cohesion[row].1.cell(),
                    c.lennard_jones[row].1.cell()
                ));
            }
            s.push('\n');
        }
        let pct = |v: Option<u32>| v.map_or("none".to_string(), |p| format!("{p}%"));
        s.push_str("| lowest p, all above converge |");
        for c in &self.columns {
            s.push_str(&format!(
                " {} | {} |",
                pct(lowest_converging(&c.cohesion)),
                pct(lowest_converging(&c.lennard_jones))
            ));
        }
        s.push_str("\n| largest p that diverges |");
        for c in &self.columns {
            s.push_str(&format!(
                " {} | {} |",
                pct(largest_diverging(&c.cohesion)),
                pct(largest_diverging(&c.lennard_jones))
            ));
        }
        s.push('\n');
        s
    }
}
