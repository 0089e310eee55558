//! Normal modes of a world at rest: the angular frequencies of its small
//! oscillations, in the plane `z = 0` ([`Basis::Planar`]) or in space
//! ([`Basis::Spatial`]).
//!
//! Near a rest state `x*` the equations of motion linearize to
//! `M ẍ = -H (x - x*)`, `H` the Hessian of the potential energy; the modes
//! are the eigenpairs `(ω², v)` of the mass-weighted Hessian
//! `M^-1/2 H M^-1/2` (seed 002 §3 treats the same linearization for its
//! oscillation measure). Each particle has its degrees of freedom
//! ([`Dof`]):
//!
//! - **planar**: its `x`, `y` and its rotation angle about `z`, for an
//!   object whose motion stays in its plane (every orientation a rotation
//!   about `z`, as the spiral recipe arranges): `3 N` of them;
//! - **spatial**: its `x`, `y`, `z` and its rotations about its three
//!   principal axes (where its moment of inertia is diagonal): `6 N`.
//!
//! A held degree of freedom (a fixed position or orientation, an infinite
//! mass) is left out. `H` is assembled column by column from central
//! differences of the forces and torques (as the stable-step estimate of
//! [`crate::stability`] does for its products), then symmetrized and
//! decomposed densely, so this is meant for small objects (a few hundred
//! degrees of freedom: [`MAX_DEGREES_OF_FREEDOM`]). The rigid motions of
//! each object whose particles are all free (translations and rotations
//! about its centre of mass, those of the basis) are projected out, so
//! that they are exactly the zero modes and every other mode is orthogonal
//! to them; they are not among the modes returned.

use op_dynamics::{Flags, Point3, Quat, Real, Vec3, World};

/// The largest number of degrees of freedom [`modes`] is meant for: its
/// dense decomposition takes about a second at this size (`6 N` for 100
/// particles in space, `3 N` for 200 in a plane).
pub const MAX_DEGREES_OF_FREEDOM: usize = 600;

/// Which motions the modes are made of.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// In the plane `z = 0`: `x`, `y` and the rotation about `z`.
    Planar,
    /// In space: `x`, `y`, `z` and the rotations about the principal axes.
    Spatial,
}

impl Basis {
    /// Degrees of freedom per particle.
    pub fn per_particle(self) -> usize {
        match self {
            Basis::Planar => 3,
            Basis::Spatial => 6,
        }
    }
}

/// One degree of freedom: a particle slot moved along, or turned about, a
/// world direction.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Dof {
    /// The particle's slot.
    pub slot: usize,
    /// True for a rotation, false for a translation.
    pub turn: bool,
    /// The unit direction (world frame) it moves along or turns about.
    pub axis: Vec3,
    /// Its inertia: the particle's mass for a translation, its moment of
    /// inertia about `axis` for a rotation.
    pub inertia: Real,
}

/// The modes of a world at its current state ([`modes`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Modes {
    /// The motions they are made of.
    pub basis: Basis,
    /// The degrees of freedom they move, in slot order.
    pub dofs: Vec<Dof>,
    /// `ω²` of each mode, ascending, in 1/time², the rigid motions left
    /// out.
    pub omega2: Vec<Real>,
    /// Each mode's displacement shape (`M^-1/2 v`, unit mass-weighted
    /// norm): one number per entry of [`Modes::dofs`].
    pub shapes: Vec<Vec<Real>>,
    /// Rigid motions projected out (those of the objects whose particles
    /// are all free).
    pub rigid: usize,
    /// Rotations left out because no force or torque depends on them to
    /// first order and they move none (the spin of a particle no
    /// orientation term acts on), when [`modes`] was asked to.
    pub inert: usize,
}

impl Modes {
    /// The mass and the moment of inertia mode `k` moves: the mean mass
    /// of its translations and the mean moment of its rotations, each
    /// weighted by the square of its amplitude (`Σ m u² / Σ u²`; `None`
    /// when it has no translation, or no rotation). With these as the
    /// linear and angular damping coefficient's mass the mode's damping
    /// ratio is what a mass-proportional damping would give it
    /// ([`crate::damping`]); with equal particles they are the particle's
    /// mass and moment.
    pub fn moved_inertia(&self, k: usize) -> (Option<Real>, Option<Real>) {
        let mean = |turn: bool| {
            let mut of_kind = self.dofs.iter().filter(|d| d.turn == turn);
            let first = of_kind.next()?.inertia;
            if of_kind.all(|d| d.inertia == first) {
                // Equal particles: their own, exactly.
                return self.shapes[k]
                    .iter()
                    .zip(&self.dofs)
                    .any(|(u, d)| d.turn == turn && *u != 0.0)
                    .then_some(first);
            }
            let (mut weighted, mut total) = (0.0, 0.0);
            for (d, u) in self.dofs.iter().zip(&self.shapes[k]) {
                if d.turn == turn {
                    weighted += d.inertia * u * u;
                    total += u * u;
                }
            }
            (total > 0.0).then(|| weighted / total)
        };
        (mean(false), mean(true))
    }
}

/// The planar modes of a world at its current state ([`planar_modes`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarModes {
    /// `ω²` of each mode, ascending, in 1/time². When every particle is
    /// free the three rigid motions of the plane are left out: these are
    /// the `3 N - 3` modes that deform the object.
    pub omega2: Vec<Real>,
    /// Each mode's displacement shape (`M^-1/2 v`, unit mass-weighted norm):
    /// `3 N` numbers per mode, `(dx, dy, dθ)` per particle slot (0 for a
    /// held one).
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

/// The planar modes of `world` at its current state (see the module docs):
/// [`modes`] over [`Basis::Planar`], every degree of freedom kept. A world
/// with no free particle gives no modes. Velocity-dependent forces
/// (damping, friction) are the same on both sides of a central difference
/// and cancel; external forces acting at the current time only shift the
/// rest state. The state is restored afterwards.
pub fn planar_modes(world: &mut World) -> PlanarModes {
    let m = modes(world, Basis::Planar, false);
    let n = world.particles().len();
    let shapes = m
        .shapes
        .iter()
        .map(|u| {
            let mut full = vec![0.0; 3 * n];
            for (d, x) in m.dofs.iter().zip(u) {
                let c = if d.turn {
                    2
                } else if d.axis.x != 0.0 {
                    0
                } else {
                    1
                };
                full[3 * d.slot + c] = *x;
            }
            full
        })
        .collect();
    PlanarModes {
        omega2: m.omega2,
        shapes,
    }
}

/// The modes of `world` at its current state over `basis` (see the module
/// docs). With `leave_out_inert`, rotations that no force or torque
/// depends on to first order and that move none (their row and column of
/// the Hessian vanish) are left out instead of giving zero modes. The state is
/// restored afterwards.
pub fn modes(world: &mut World, basis: Basis, leave_out_inert: bool) -> Modes {
    let base = Base {
        p: world.particles().positions().to_vec(),
        q: world.particles().orientations().to_vec(),
    };
    let mut dofs = degrees_of_freedom(world, basis);
    let h = difference_step(&base.p);
    let mut hess = weighted_hessian(world, &base, &dofs, h);
    hess = (&hess + hess.transpose()) * 0.5;
    let inert = if leave_out_inert {
        let keep = active(&hess, &dofs);
        let left_out = dofs.len() - keep.len();
        hess = hess.select_rows(&keep).select_columns(&keep);
        dofs = keep.iter().map(|&k| dofs[k]).collect();
        left_out
    } else {
        0
    };
    let rigid = rigid_basis(world, &base.p, &dofs, basis);
    if let Some(q) = &rigid {
        let p = nalgebra::DMatrix::<Real>::identity(dofs.len(), dofs.len()) - q * q.transpose();
        hess = &p * hess * &p;
    }
    // Every degree of freedom left out as inert (a particle whose spins
    // nothing resists and that no force moves): no mode; nalgebra refuses
    // the empty matrix.
    let (omega2, shapes) = if dofs.is_empty() {
        (Vec::new(), Vec::new())
    } else {
        let eig = nalgebra::SymmetricEigen::new(hess);
        sorted_modes(&eig, rigid.as_ref(), &dofs)
    };
    Modes {
        basis,
        rigid: rigid.as_ref().map_or(0, |q| q.ncols()),
        dofs,
        omega2,
        shapes,
        inert,
    }
}

/// The rest state the differences are taken around: positions and
/// orientations by slot.
struct Base {
    p: Vec<Point3>,
    q: Vec<Quat>,
}

/// The degrees of freedom of `basis` that are not held, slot by slot
/// (translations first). A planar rotation has the body moment of inertia
/// about the world `z` axis; a spatial one turns about a principal axis.
fn degrees_of_freedom(world: &World, basis: Basis) -> Vec<Dof> {
    let p = world.particles();
    let mut dofs = Vec::new();
    for s in 0..p.len() {
        let f = p.flags()[s];
        let (inv_mass, i, q) = (p.inv_masses()[s], p.inertias()[s], p.orientations()[s]);
        let mut add = |turn: bool, axis: Vec3, inertia: Real| {
            if inertia > 0.0 && inertia.is_finite() {
                dofs.push(Dof {
                    slot: s,
                    turn,
                    axis,
                    inertia,
                });
            }
        };
        let moves: &[Vec3] = match basis {
            Basis::Planar => &[Vec3::x(), Vec3::y()],
            Basis::Spatial => &[Vec3::x(), Vec3::y(), Vec3::z()],
        };
        if !f.contains(Flags::FIXED_POSITION) && inv_mass > 0.0 {
            for &a in moves {
                add(false, a, 1.0 / inv_mass);
            }
        }
        if f.contains(Flags::FIXED_ORIENTATION) {
            continue;
        }
        match basis {
            Basis::Planar => {
                let z = q.inverse_transform_vector(&Vec3::z());
                add(
                    true,
                    Vec3::z(),
                    i.x * z.x * z.x + i.y * z.y * z.y + i.z * z.z * z.z,
                );
            }
            Basis::Spatial => {
                for (k, e) in [Vec3::x(), Vec3::y(), Vec3::z()].into_iter().enumerate() {
                    add(true, q.transform_vector(&e), i[k]);
                }
            }
        }
    }
    dofs
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

/// Gradient of the energy over `dofs` at a displacement of `dofs[k]` by
/// `step`; the slot is put back afterwards.
fn gradient(world: &mut World, base: &Base, dofs: &[Dof], k: usize, step: Real) -> Vec<Real> {
    let d = dofs[k];
    let s = d.slot;
    {
        let p = world.particles_mut();
        if d.turn {
            p.set_orientation(s, Quat::from_scaled_axis(d.axis * step) * base.q[s]);
        } else {
            p.set_position(s, base.p[s] + d.axis * step);
        }
    }
    let (f, t, _) = world.evaluate_forces();
    let g = dofs
        .iter()
        .map(|e| {
            if e.turn {
                -t[e.slot].dot(&e.axis)
            } else {
                -f[e.slot].dot(&e.axis)
            }
        })
        .collect();
    let p = world.particles_mut();
    p.set_position(s, base.p[s]);
    p.set_orientation(s, base.q[s]);
    g
}

/// The mass-weighted Hessian `M^-1/2 H M^-1/2` over `dofs`, column by
/// column from central differences of the gradient; not yet symmetrized.
fn weighted_hessian(
    world: &mut World,
    base: &Base,
    dofs: &[Dof],
    h: Real,
) -> nalgebra::DMatrix<Real> {
    let n = dofs.len();
    let w: Vec<Real> = dofs.iter().map(|d| 1.0 / d.inertia.sqrt()).collect();
    let mut hess = nalgebra::DMatrix::<Real>::zeros(n, n);
    for k in 0..n {
        let plus = gradient(world, base, dofs, k, h);
        let minus = gradient(world, base, dofs, k, -h);
        for j in 0..n {
            hess[(j, k)] = w[j] * (plus[j] - minus[j]) / (2.0 * h) * w[k];
        }
    }
    hess
}

/// The indices of the degrees of freedom to keep: every translation, and
/// every rotation whose row of the symmetric `hess` is not zero (below
/// `1e-12` of its largest entry). A translation without stiffness is a
/// motion (the pair's transverse drift at rest), a rotation without it a
/// spin no term sees.
fn active(hess: &nalgebra::DMatrix<Real>, dofs: &[Dof]) -> Vec<usize> {
    let largest = hess.amax();
    (0..hess.nrows())
        .filter(|&k| !dofs[k].turn || hess.row(k).amax() > 1e-12 * largest)
        .collect()
}

/// An orthonormal basis, in mass-weighted coordinates over `dofs`, of the
/// rigid motions of `basis` (translations, rotations about the centre of
/// mass) of each object whose particles are all free (every one of its
/// slots has every degree of freedom of the basis); `None` when there is
/// none. Dependent motions (the rotation of a single particle whose
/// rotations were left out) count once.
fn rigid_basis(
    world: &World,
    base_p: &[Point3],
    dofs: &[Dof],
    basis: Basis,
) -> Option<nalgebra::DMatrix<Real>> {
    let p = world.particles();
    let full = degrees_of_freedom(world, basis);
    let per = basis.per_particle();
    let mut count = std::collections::BTreeMap::<u32, (usize, usize)>::new();
    for s in 0..p.len() {
        count.entry(p.objects()[s]).or_default().0 += per;
    }
    for d in &full {
        count.entry(p.objects()[d.slot]).or_default().1 += 1;
    }
    let (moves, turns): (&[Vec3], &[Vec3]) = match basis {
        Basis::Planar => (&[Vec3::x(), Vec3::y()], &[Vec3::z()]),
        Basis::Spatial => (
            &[Vec3::x(), Vec3::y(), Vec3::z()],
            &[Vec3::x(), Vec3::y(), Vec3::z()],
        ),
    };
    let mut columns: Vec<Vec<Real>> = Vec::new();
    for (&object, &(wanted, free)) in &count {
        if wanted != free {
            continue;
        }
        let slots = |d: &Dof| p.objects()[d.slot] == object;
        let (mut mass, mut centre) = (0.0, Vec3::zeros());
        for d in dofs
            .iter()
            .filter(|d| slots(d) && !d.turn && d.axis == moves[0])
        {
            mass += d.inertia;
            centre += base_p[d.slot].coords * d.inertia;
        }
        let centre = if mass > 0.0 { centre / mass } else { centre };
        // Velocity of each degree of freedom under a unit rigid motion.
        let column = |velocity: &dyn Fn(&Dof) -> Real| -> Vec<Real> {
            dofs.iter()
                .map(|d| {
                    if slots(d) {
                        velocity(d) * d.inertia.sqrt()
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        for &e in moves {
            columns.push(column(&|d| if d.turn { 0.0 } else { d.axis.dot(&e) }));
        }
        for &e in turns {
            columns.push(column(&|d| {
                if d.turn {
                    d.axis.dot(&e)
                } else {
                    d.axis.dot(&e.cross(&(base_p[d.slot].coords - centre)))
                }
            }));
        }
    }
    orthonormal(columns, dofs.len())
}

/// Modified Gram-Schmidt (twice, for round-off), dropping columns that
/// depend on the earlier ones; `None` when none is left.
fn orthonormal(columns: Vec<Vec<Real>>, rows: usize) -> Option<nalgebra::DMatrix<Real>> {
    let mut kept: Vec<nalgebra::DVector<Real>> = Vec::new();
    for c in columns {
        let mut v = nalgebra::DVector::from_vec(c);
        let norm0 = v.norm();
        if norm0 == 0.0 {
            continue;
        }
        for _ in 0..2 {
            for k in &kept {
                let along = k.dot(&v);
                v -= k * along;
            }
        }
        let norm = v.norm();
        if norm > 1e-8 * norm0 {
            kept.push(v / norm);
        }
    }
    (!kept.is_empty()).then(|| {
        let mut q = nalgebra::DMatrix::<Real>::zeros(rows, kept.len());
        for (j, k) in kept.iter().enumerate() {
            q.set_column(j, k);
        }
        q
    })
}

/// The modes by ascending `ω²`, without the eigenvectors lying most in
/// the `rigid` subspace (as many as it has columns) when there is one,
/// shapes scaled back by the weights (`M^-1/2 v`).
fn sorted_modes(
    eig: &nalgebra::SymmetricEigen<Real, nalgebra::Dyn>,
    rigid: Option<&nalgebra::DMatrix<Real>>,
    dofs: &[Dof],
) -> (Vec<Real>, Vec<Vec<Real>>) {
    let n = dofs.len();
    let mut order: Vec<usize> = (0..n).collect();
    if let Some(q) = rigid {
        let mut by_rigidity: Vec<(Real, usize)> = (0..n)
            .map(|k| ((q.transpose() * eig.eigenvectors.column(k)).norm(), k))
            .collect();
        by_rigidity.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let dropped: Vec<usize> = by_rigidity[..q.ncols().min(n)]
            .iter()
            .map(|e| e.1)
            .collect();
        order.retain(|k| !dropped.contains(k));
    }
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let omega2 = order.iter().map(|&k| eig.eigenvalues[k]).collect();
    let shapes = order
        .iter()
        .map(|&k| {
            (0..n)
                .map(|j| eig.eigenvectors[(j, k)] / dofs[j].inertia.sqrt())
                .collect()
        })
        .collect();
    (omega2, shapes)
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

    /// In space the pair's rotations move no force (Lennard-Jones has no
    /// orientation term): left out as inert, they leave, of the six
    /// translations, three rigid ones, two rotations of the pair about
    /// the centre (the one about its axis moves nothing) and the stretch,
    /// at the same frequency as in the plane.
    #[test]
    fn a_pair_in_space_has_one_mode_once_its_spins_are_left_out() {
        let mut w = world(
            r#"(name: "pair", world: (dt: 0.001),
                materials: {"lj": (spacing: LennardJones((epsilon: 10, r0: 1, cutoff: 1.5)))},
                objects: [(name: "p", material: "lj", mass: 2,
                           generator: Chain(count: 2, spacing: 1))])"#,
        );
        let m = modes(&mut w, Basis::Spatial, true);
        assert_eq!((m.inert, m.rigid, m.dofs.len()), (6, 5, 6));
        assert_eq!(m.omega2.len(), 1, "{:?}", m.omega2);
        let expected = 72.0 * 10.0 * (1.0 / 2.0 + 1.0 / 2.0);
        assert!(
            (m.omega2[0] / expected - 1.0).abs() < 1e-6,
            "{:?}",
            m.omega2
        );
        assert_eq!(m.moved_inertia(0), (Some(2.0), None));
    }

    /// Two fixed particles too far apart to interact: every degree of
    /// freedom is left out as inert and there is no mode (nalgebra's
    /// eigen-decomposition panics on the empty matrix that would remain).
    #[test]
    fn fixed_particles_far_apart_have_no_mode() {
        let mut w = world(
            r#"(name: "far", world: (dt: 0.001),
                materials: {"lj": (spacing: LennardJones((epsilon: 10, r0: 1, cutoff: 1.5)))},
                objects: [(name: "p", material: "lj", generator: Chain(count: 2, spacing: 10),
                           overrides: [(particles: All, fixed_position: Some(true))])])"#,
        );
        let m = modes(&mut w, Basis::Spatial, true);
        assert!(m.dofs.is_empty() && m.omega2.is_empty(), "{:?}", m.omega2);
    }

    /// The spatial modes of the settled seed spiral hold its planar ones:
    /// every planar `ω²` is one of them (to 1e-6 of the largest). The
    /// others include the chain's torsion, which costs no energy.
    #[test]
    fn the_planar_modes_of_a_spiral_are_among_its_spatial_ones() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/spiral.ron");
        let mut built = crate::load_scene(&path).unwrap().build(None, None).unwrap();
        built.settle().unwrap();
        let planar = planar_modes(built.world_mut());
        let spatial = modes(built.world_mut(), Basis::Spatial, true);
        assert_eq!((spatial.rigid, spatial.inert), (6, 0));
        assert_eq!(spatial.omega2.len(), 60 - 6);
        let largest = spatial.omega2.last().copied().unwrap();
        for l in &planar.omega2 {
            let nearest = spatial
                .omega2
                .iter()
                .map(|s| (s - l).abs())
                .fold(Real::INFINITY, Real::min);
            assert!(nearest < 1e-6 * largest, "{l}: {nearest}");
        }
        // Its torsion: zero to 1e-5 of the largest (slightly negative: the
        // settled plane is not quite a minimum out of the plane).
        assert!(
            spatial.omega2[0].abs() < 1e-5 * largest,
            "{:?}",
            &spatial.omega2[..4]
        );
    }
}
