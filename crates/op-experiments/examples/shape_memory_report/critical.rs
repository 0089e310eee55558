//! Section 2b of the report: critical damping of the slowest mode
//! (`op_experiments::spiral_damping`), one rule for spirals of 8 to 20
//! particles and any smooth curvature law, against the fixed recipe.

use std::fmt::Write as _;

use op_dynamics::Real;
use op_experiments::spiral::{run_spiral, SpiralRecipe, SpiralShape, Units};
use op_experiments::spiral_damping::{critical_recipe, CriticalSchedule};
use op_scene::CurvatureLaw;

use crate::Res;

/// The laws of the section: name, law, ratio of the end curvatures.
const LAWS: [(&str, CurvatureLaw, Real); 5] = [
    ("constant", CurvatureLaw::Linear, 1.0),
    ("linear", CurvatureLaw::Linear, 3.4),
    ("sine", CurvatureLaw::Sine, 3.4),
    ("quadratic", CurvatureLaw::Quadratic, 3.4),
    ("geometric", CurvatureLaw::Geometric, 9.0),
];

/// Turns of every spiral of the section.
const TURNS: Real = 0.75;

/// The section: every law at 8, 14 and 20 particles under the critical
/// recipe, and the fixed recipe on the same spirals for comparison.
pub(crate) fn critical_damping() -> Res<String> {
    let schedule = CriticalSchedule::default();
    let mut s =
        String::from("### Critical damping of the slowest mode: one rule for any law and size\n\n");
    writeln!(
        s,
        "The fixed recipe suits the seed spiral, but the slowest deformation mode of a chain \
         softens like 1/N² (ω1 = 0.33-0.48 for 8 particles, 0.16-0.18 for 14, 0.08-0.09 for 20, \
         below): a long spiral is far underdamped by β0 = 0.3 and its window is under three periods. \
         `op_experiments::spiral_damping::critical_recipe` takes ω1 from the Hessian of the \
         settled spiral's energy (`op_scene::modes::planar_modes`), damps it critically (linear \
         and angular damping 2 ω1 times each particle's mass and moment of inertia: no mode \
         decays slower than (1 + ω1 t) e^(-ω1 t)) and sets every phase in units of τ = 1/ω1: \
         settle {settle} τ, ramps {ramp} τ, hold {hold} τ, free recovery {recovery} τ. Spirals \
         of {TURNS} turns (fewer where the curvature would pass 0.9), laws of ratio 3.4 (the \
         seed's 0.85/0.25) and a geometric law of ratio 9; end forces as in the recipe \
         (0.45 f_max). `tests/shape_memory.rs` asserts the rows marked there.\n",
        settle = schedule.settle,
        ramp = schedule.ramp,
        hold = schedule.hold,
        recovery = schedule.recovery,
    )?;
    s.push_str(
        "| particles | law | curvature | ω1 | β0 = 2 ω1 | window (T) | max error | final error (critical) | final error (fixed recipe) | recovered (final <= 0.01) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let fixed = SpiralRecipe::default();
    for count in [8, 14, 20] {
        for (name, law, ratio) in LAWS {
            let shape = SpiralShape::with_turns(count, law, ratio, TURNS)?;
            let critical = critical_recipe(&fixed, &shape, &schedule)?;
            let recipe = &critical.recipe;
            let units = Units::of(&shape);
            let run = run_spiral(&recipe.scene("spiral", &shape), &recipe.schedule(&units))?;
            let plain = run_spiral(&fixed.scene("spiral", &shape), &fixed.schedule(&units))?;
            writeln!(
                s,
                "| {count} | {name} | {:.3} → {:.3} | {:.4} | {:.3} | {:.0} | {:.3} | {:.5} | {:.4} | {} |",
                shape.curvature_start,
                shape.curvature_end,
                critical.omega1,
                recipe.linear_damping,
                recipe.schedule(&units).end,
                run.max_error,
                run.final_error,
                plain.final_error,
                if run.final_error <= 0.01 { "yes" } else { "**no**" },
            )?;
        }
    }
    s.push_str(
        "\nEvery law of ratio 3.4 recovers at every size under the one rule (below 1e-4); the \
         fixed recipe leaves the 20-particle spirals about one spacing from their shape. **Not \
         met: the geometric law of ratio 9 at 14 and 20 particles.** At 14 the spiral comes to \
         rest with the settled potential energy to five digits (-2.91652 before and after) but \
         0.139 from the settled shape: its tight end (curvature 0.9, the most the recipe \
         allows) curls tighter, second neighbours at 1.60-1.69 spacings instead of 1.76-1.84, \
         the last four normals turned 3-11 degrees against the chain: a second configuration of \
         the same energy, which the energy terms do not tell apart. At 20 the tip folds onto \
         itself during the recoil (second neighbours at 0.96 spacings, held by cohesion); bonding \
         nearest neighbours only (`bonds`) takes its final error from 0.62 to 0.34. Not \
         resolved (issue 15).\n\n",
    );
    Ok(s)
}
