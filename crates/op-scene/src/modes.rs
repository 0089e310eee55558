//! Normal modes of a planar world at rest: the angular frequencies of its
//! small oscillations in the plane `z = 0`.
//!
//! Near a rest state `x*` the equations of motion linearize to
//! `M ẍ = -H (x - x*)`, `H` the Hessian of the potential energy; the modes
//! are the eigenpairs `(ω², v)` of the mass-weighted Hessian
//! `M^-1/2 H M^-1/2` (seed 002 §3 treats the same linearization for its
//! oscillation measure). For a planar object whose motion stays in its
//! plane (every orientation a rotation about `z`, as the spiral recipe
//! arranges), the degrees of freedom are each particle's `x`, `y` and its
//! rotation angle about `z`: `3 N` of them. `H` is assembled column by
//! column from central differences of the forces and torques (as the
//! stable-step estimate of [`crate::stability`] does for its products), then
//! symmetrized and decomposed densely, so this is meant for small objects
//! (a few hundred degrees of freedom).

use op_dynamics::{Flags, Point3, Quat, Real, Vec3, World};

/// The planar modes of a world at its current state.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarModes {
    /// `ω²` of each mode, ascending, in 1/time². When every particle is
    /// free the three rigid motions of the plane are left out: these are
    /// the `3 N - 3` modes that deform the object.
    pub omega2: Vec<Real>,
    /// Each mode's displacement shape (`M^-1/2 v`, unit mass-weighted norm):
    /// `3 N` numbers per mode, `(dx, dy, dθ)` per particle slot.
    pub shapes: Vec<Vec<Real>>,
}

impl PlanarModes {
    /// Of mode `k`, the share of its relative motion along the bonds
    /// `(a, b)` (slot pairs): `Σ (r̂·(u_b - u_a))² / Σ |u_b - u_a|²`, with
    /// `r̂` the unit bond direction at the current state. Bending modes move
    /// neighbours across their bonds (share near 0), stretching modes along
    /// them (near 1). `None` when the mode moves no bond (a rigid mode).
    pub fn stretch_share(
        &self,
        k: usize,
        positions: &[Point3],
        bonds: &[(usize, usize)],
    ) -> Option<Real> {
        let u = &self.shapes[k];
        let (mut along, mut total) = (0.0, 0.0);
        for &(a, b) in bonds {
            let d = Vec3::new(u[3 * b] - u[3 * a], u[3 * b + 1] - u[3 * a + 1], 0.0);
            let r = (positions[b] - positions[a]).normalize();
            along += r.dot(&d).powi(2);
            total += d.norm_squared();
        }
        (total > 0.0).then(|| along / total)
    }
}

/// The planar modes of `world` at its current state (see the module docs).
/// Every particle must be free (no fixed position or orientation); a
/// world with none gives no modes. Velocity-dependent forces (damping,
/// friction) are the same on both sides of a central difference and
/// cancel; external forces acting at the current time only shift the
/// rest state. The state is restored afterwards.
pub fn planar_modes(world: &mut World) -> PlanarModes {
    let n = world.particles().len();
    let dof = 3 * n;
    let base = Base {
        p: world.particles().positions().to_vec(),
        q: world.particles().orientations().to_vec(),
    };
    let weights = mass_weights(world, &base.q);
    let h = difference_step(&base.p);
    let hess = weighted_hessian(world, &base, &weights, h);
    let mut sym = (&hess + hess.transpose()) * 0.5;
    // The rigid motions of the plane (two translations, the rotation about
    // the centre of mass), in mass-weighted coordinates, when every
    // particle is free: projected out, so that they are exactly the zero
    // modes and every other mode is orthogonal to them.
    let rigid = if weights.iter().all(|w| *w > 0.0) && n > 1 {
        let q = rigid_basis(&weights, &base.p);
        let p = nalgebra::DMatrix::<Real>::identity(dof, dof) - &q * q.transpose();
        sym = &p * sym * &p;
        Some(q)
    } else {
        None
    };
    sorted_modes(nalgebra::SymmetricEigen::new(sym), rigid.as_ref(), &weights)
}

/// The rest state the differences are taken around: positions and
/// orientations by slot.
struct Base {
    p: Vec<Point3>,
    q: Vec<Quat>,
}

/// `1/sqrt(mass)` per degree of freedom (0 for held or massless ones); the
/// rotation about z has the body moment of inertia about the world z axis.
fn mass_weights(world: &World, base_q: &[Quat]) -> Vec<Real> {
    let p = world.particles();
    (0..3 * p.len())
        .map(|k| {
            let s = k / 3;
            let f = p.flags()[s];
            let free = !f.contains(Flags::FIXED_POSITION) && !f.contains(Flags::FIXED_ORIENTATION);
            let w = if !free {
                0.0
            } else if k % 3 < 2 {
                p.inv_masses()[s].sqrt()
            } else {
                let z = base_q[s].inverse_transform_vector(&Vec3::z());
                let i = p.inertias()[s];
                let iz = i[0] * z.x * z.x + i[1] * z.y * z.y + i[2] * z.z * z.z;
                1.0 / iz.sqrt()
            };
            if w.is_finite() {
                w
            } else {
                0.0
            }
        })
        .collect()
}

/// The central-difference step: `1e-6` of the shortest distance between
/// consecutive slots (at most 1).
fn difference_step(base_p: &[Point3]) -> Real {
    let length = base_p
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .fold(Real::INFINITY, Real::min);
    1e-6 * if length.is_finite() && length > 0.0 {
        length.min(1.0)
    } else {
        1.0
    }
}

/// Gradient of the energy over (x, y, θ) at a displacement of degree of
/// freedom `k` (slot `k / 3`, coordinate `k % 3`) by `step`; the slot is
/// put back afterwards.
fn planar_gradient(world: &mut World, base: &Base, k: usize, step: Real) -> Vec<Real> {
    let dof = 3 * base.p.len();
    let (s, c) = (k / 3, k % 3);
    {
        let p = world.particles_mut();
        if c < 2 {
            let mut d = Vec3::zeros();
            d[c] = step;
            p.set_position(s, base.p[s] + d);
        } else {
            p.set_orientation(s, Quat::from_scaled_axis(Vec3::z() * step) * base.q[s]);
        }
    }
    let (f, t, _) = world.evaluate_forces();
    let g = (0..dof)
        .map(|j| {
            let (sj, cj) = (j / 3, j % 3);
            if cj < 2 {
                -f[sj][cj]
            } else {
                -t[sj].z
            }
        })
        .collect();
    let p = world.particles_mut();
    p.set_position(s, base.p[s]);
    p.set_orientation(s, base.q[s]);
    g
}

/// The mass-weighted Hessian `M^-1/2 H M^-1/2`, column by column from
/// central differences of the gradient (columns of held degrees of
/// freedom stay zero); not yet symmetrized.
fn weighted_hessian(
    world: &mut World,
    base: &Base,
    weights: &[Real],
    h: Real,
) -> nalgebra::DMatrix<Real> {
    let dof = weights.len();
    let mut hess = nalgebra::DMatrix::<Real>::zeros(dof, dof);
    for k in 0..dof {
        if weights[k] == 0.0 {
            continue;
        }
        let plus = planar_gradient(world, base, k, h);
        let minus = planar_gradient(world, base, k, -h);
        for j in 0..dof {
            hess[(j, k)] = weights[j] * (plus[j] - minus[j]) / (2.0 * h) * weights[k];
        }
    }
    hess
}

/// An orthonormal basis of the rigid motions of the plane (two
/// translations, the rotation about the centre of mass) in mass-weighted
/// coordinates; every weight must be positive.
fn rigid_basis(weights: &[Real], base_p: &[Point3]) -> nalgebra::DMatrix<Real> {
    let (n, dof) = (base_p.len(), weights.len());
    let sqrt_m = |k: usize| 1.0 / weights[k];
    let mass: Vec<Real> = (0..n).map(|s| sqrt_m(3 * s).powi(2)).collect();
    let total: Real = mass.iter().sum();
    let centre = (0..n).fold(Vec3::zeros(), |c, s| c + base_p[s].coords * mass[s]) / total;
    let mut q = nalgebra::DMatrix::<Real>::zeros(dof, 3);
    for s in 0..n {
        let d = base_p[s].coords - centre;
        q[(3 * s, 0)] = sqrt_m(3 * s);
        q[(3 * s + 1, 1)] = sqrt_m(3 * s + 1);
        q[(3 * s, 2)] = -d.y * sqrt_m(3 * s);
        q[(3 * s + 1, 2)] = d.x * sqrt_m(3 * s + 1);
        q[(3 * s + 2, 2)] = sqrt_m(3 * s + 2);
    }
    q.qr().q()
}

/// The modes by ascending `ω²`, without the three eigenvectors lying most
/// in the `rigid` subspace when there is one, shapes scaled back by the
/// weights (`M^-1/2 v`).
fn sorted_modes(
    eig: nalgebra::SymmetricEigen<Real, nalgebra::Dyn>,
    rigid: Option<&nalgebra::DMatrix<Real>>,
    weights: &[Real],
) -> PlanarModes {
    let dof = weights.len();
    let mut order: Vec<usize> = (0..dof).collect();
    if let Some(q) = rigid {
        // Drop the three eigenvectors lying most in the rigid subspace.
        let mut by_rigidity: Vec<(Real, usize)> = (0..dof)
            .map(|k| ((q.transpose() * eig.eigenvectors.column(k)).norm(), k))
            .collect();
        by_rigidity.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let dropped: Vec<usize> = by_rigidity[..3].iter().map(|e| e.1).collect();
        order.retain(|k| !dropped.contains(k));
    }
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    PlanarModes {
        omega2: order.iter().map(|&k| eig.eigenvalues[k]).collect(),
        shapes: order
            .iter()
            .map(|&k| {
                (0..dof)
                    .map(|j| eig.eigenvectors[(j, k)] * weights[j])
                    .collect()
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{parse_scene, Format};

    fn world(scene: &str) -> World {
        let scene = parse_scene(scene, Format::Ron, "<test>").unwrap();
        scene.build(None, None).unwrap().world
    }

    /// Two particles at the Lennard-Jones minimum (`U''(r0) = n m ε / r0²`),
    /// no orientation terms: of the three deformation modes of the pair only
    /// the stretch is stiff, `ω² = U''(r0) (1/m1 + 1/m2)`.
    #[test]
    fn a_pair_stretches_at_the_lennard_jones_frequency() {
        let mut w = world(
            r#"(name: "pair", world: (dt: 0.001),
                materials: {"lj": (spacing: LennardJones((epsilon: 10, r0: 1, cutoff: 1.5)))},
                objects: [(name: "p", material: "lj", mass: 2,
                           generator: Chain(count: 2, spacing: 1))])"#,
        );
        let modes = planar_modes(&mut w);
        assert_eq!(
            modes.omega2.len(),
            3,
            "6 planar degrees of freedom, 3 rigid"
        );
        let expected = 72.0 * 10.0 * (1.0 / 2.0 + 1.0 / 2.0);
        assert!(
            (modes.omega2[2] / expected - 1.0).abs() < 1e-6,
            "{:?}",
            modes.omega2
        );
        assert!(modes.omega2[0].abs() < 1e-6 * expected);
        assert!(modes.omega2[1].abs() < 1e-6 * expected);
        let bonds = [(0, 1)];
        let positions = w.particles().positions().to_vec();
        let share = modes.stretch_share(2, &positions, &bonds).unwrap();
        assert!((share - 1.0).abs() < 1e-9, "{share}");
    }

    /// Rigid motions are left out and the state is restored: a chain of
    /// three has `9 - 3` modes, none negative at its rest state, and the
    /// world's positions are the same bits afterwards.
    #[test]
    fn rigid_motions_are_projected_out_and_the_state_restored() {
        let mut w = world(
            r#"(name: "chain", world: (dt: 0.001),
                materials: {"lj": (spacing: LennardJones((epsilon: 1, r0: 1, cutoff: 1.5)))},
                objects: [(name: "c", material: "lj", generator: Chain(count: 3, spacing: 1))])"#,
        );
        let before = w.particles().positions().to_vec();
        let modes = planar_modes(&mut w);
        assert_eq!(modes.omega2.len(), 6);
        assert_eq!(modes.shapes.len(), 6);
        assert!(
            modes.omega2.iter().all(|l| *l > -1e-6),
            "{:?}",
            modes.omega2
        );
        assert!(modes.omega2.windows(2).all(|p| p[0] <= p[1]));
        assert_eq!(w.particles().positions(), &before[..]);
    }
}
