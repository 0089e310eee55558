//! Classical fourth-order Runge–Kutta (Kutta 1901) on `p, v, ω`, with its
//! Runge–Kutta–Munthe-Kaas version on the orientation (see [`super::rkmk`]):
//! four force evaluations per step, global error `O(h⁴)`. The `dexp⁻¹`
//! series is truncated after its `θ×(θ×ω)` term, which order 4 requires
//! (terms of degree `≤ p − 2`).

use super::rkmk::{self, RkBuffers, Tableau};
use super::{Bodies, ForceField, StateMut};
use crate::math::{Real, Vec3};

/// The classical RK4 tableau (stage part).
pub(crate) const RK4: Tableau = Tableau {
    a: &[&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]],
    c: &[0.0, 0.5, 0.5, 1.0],
};

/// The RK4 weights.
pub(crate) const RK4_B: [Real; 4] = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];

/// One RK4 step of all particles. Returns the number of force evaluations
/// (4). `forces`/`torques` are scratch.
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_all<F: ForceField>(
    field: &mut F,
    bodies: &Bodies<'_>,
    t: Real,
    h: Real,
    state: StateMut<'_>,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    buf: &mut RkBuffers,
) -> u32 {
    let n = state.len();
    buf.ensure(n, RK4.stages());
    field.forces(t, state.view(), forces, torques);
    rkmk::first_slope(bodies, state.view(), forces, torques, &mut buf.k[..n]);
    let evals = 1 + rkmk::later_stages(
        field,
        bodies,
        t,
        h,
        state.view(),
        &RK4,
        buf,
        forces,
        torques,
    );
    buf.combine_all(state.view(), h, &RK4_B);
    state.positions.copy_from_slice(&buf.positions);
    state.velocities.copy_from_slice(&buf.velocities);
    state.orientations.copy_from_slice(&buf.orientations);
    state
        .angular_velocities
        .copy_from_slice(&buf.angular_velocities);
    evals
}
