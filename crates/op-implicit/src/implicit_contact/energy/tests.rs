//! Tests of [`super`]: the reactions are the contact energy's gradient
//! (finite differences in every particle's position and orientation),
//! they sum to zero, their torques balance as the quadrature converges,
//! the flat-contact pressure is Gascuel's, and velocity Verlet conserves
//! the energy with contact to second order in the step.

use crate::field::Field;
use crate::primitives::Primitive;
use crate::{ContactPair, ImplicitContactParams};
use op_dynamics::{Point3, Quat, Real, Vec3};
use op_test_support::Rng;

/// A state of two skins: each particle's position and orientation, and
/// the primitives it carries (particle index, primitive, on B).
struct Skins {
    positions: Vec<Point3>,
    orientations: Vec<Quat>,
    primitives: Vec<(usize, Primitive, bool)>,
}

impl Skins {
    fn fields(&self) -> (Field, Field) {
        let posed = |on_b: bool| {
            Field::new(
                self.primitives
                    .iter()
                    .filter(|(_, _, b)| *b == on_b)
                    .map(|(i, prim, _)| {
                        prim.posed(*i as u32, &self.positions[*i], &self.orientations[*i])
                    })
                    .collect(),
            )
        };
        (posed(false), posed(true))
    }

    fn energy(&self, params: &ImplicitContactParams) -> Real {
        let (a, b) = self.fields();
        ContactPair::new(&a, &b).energy(params).unwrap()
    }

    /// Force and torque on every particle (zero when it has none).
    fn reactions(&self, params: &ImplicitContactParams) -> Vec<(Vec3, Vec3)> {
        let (a, b) = self.fields();
        let r = ContactPair::new(&a, &b).reactions(params).unwrap();
        let mut out = vec![(Vec3::zeros(), Vec3::zeros()); self.positions.len()];
        for x in r.a().reactions().iter().chain(r.b().reactions()) {
            out[x.particle as usize].0 += x.force;
            out[x.particle as usize].1 += x.torque;
        }
        out
    }
}

fn point(radius: Real) -> Primitive {
    Primitive::point(Vec3::zeros(), radius)
}

/// Two point blobs against one, off-centre.
fn blobs() -> Skins {
    Skins {
        positions: vec![
            Point3::new(-0.45, 0.15, 0.02),
            Point3::new(-0.45, -0.15, 0.0),
            Point3::new(0.4, 0.05, -0.03),
        ],
        orientations: vec![Quat::identity(); 3],
        primitives: vec![
            (0, point(1.0), false),
            (1, point(1.0), false),
            (2, point(1.0), true),
        ],
    }
}

/// A wavy row of tilted squares (oriented: torques) and a clump of
/// ellipsoids and points pressed into it, at random.
fn ribbon_and_clump(rng: &mut Rng) -> Skins {
    let mut s = Skins {
        positions: Vec::new(),
        orientations: Vec::new(),
        primitives: Vec::new(),
    };
    for i in 0..8 {
        let x = 0.5 * i as Real - 2.0;
        s.positions.push(Point3::new(x, 0.0, 0.4 * (0.4 * x).sin()));
        s.orientations.push(rng.quat(0.4));
        s.primitives
            .push((i, Primitive::square(Vec3::z(), 0.25, 0.4), false));
    }
    for i in 0..6 {
        s.positions
            .push(Point3::new(0.0, 0.0, 0.55) + rng.vec3(0.5));
        s.orientations.push(rng.quat(3.0));
        let prim = if i % 2 == 0 {
            Primitive::ellipsoid(
                Vec3::new(0.05, 0.0, 0.0),
                Quat::identity(),
                Vec3::new(1.0, 0.6, 0.8),
                0.6,
            )
        } else {
            point(0.6)
        };
        s.primitives.push((8 + i, prim, true));
    }
    s
}

const PARAMS: ImplicitContactParams = ImplicitContactParams {
    stiffness: 100.0,
    cell_size: 0.04,
    max_nodes_per_axis: 512,
};

/// Every particle's force is minus the energy's derivative in its
/// position, and its torque minus the derivative in a rotation about
/// itself (central differences of 1e-6). Point and ellipsoid primitives
/// are polynomials along a line, which the quadrature integrates to
/// round-off: measured, the worst difference is 3e-10 of the largest
/// reaction. A square's distance is C1, not C2, across its edges, where
/// no quadrature piece ends: 6e-5 (the lattice term spreads that error
/// over every particle).
#[test]
fn reactions_are_the_energy_gradient() {
    let mut rng = Rng::new(5);
    let mut cases = vec![("blobs", blobs(), 1e-8)];
    for _ in 0..3 {
        cases.push(("ribbon and clump", ribbon_and_clump(&mut rng), 2e-4));
    }
    let d = 1e-6;
    for (name, mut s, tolerance) in cases {
        let analytic = s.reactions(&PARAMS);
        let scale = analytic
            .iter()
            .map(|(f, t)| f.norm().max(t.norm()))
            .fold(0.0, Real::max);
        assert!(scale > 1e-3, "{name}: the skins are in contact ({scale})");
        let mut worst: Real = 0.0;
        for (i, (force_i, torque_i)) in analytic.iter().enumerate() {
            for k in 0..3 {
                let mut step = Vec3::zeros();
                step[k] = d;
                let p = s.positions[i];
                s.positions[i] = p + step;
                let up = s.energy(&PARAMS);
                s.positions[i] = p - step;
                let down = s.energy(&PARAMS);
                s.positions[i] = p;
                let force = -(up - down) / (2.0 * d);
                worst = worst.max((force - force_i[k]).abs());

                let q = s.orientations[i];
                s.orientations[i] = Quat::from_scaled_axis(step) * q;
                let up = s.energy(&PARAMS);
                s.orientations[i] = Quat::from_scaled_axis(-step) * q;
                let down = s.energy(&PARAMS);
                s.orientations[i] = q;
                let torque = -(up - down) / (2.0 * d);
                worst = worst.max((torque - torque_i[k]).abs());
            }
        }
        eprintln!(
            "{name}: largest reaction {scale:.3e}, worst FD difference {:.2e} of it",
            worst / scale
        );
        assert!(worst < tolerance * scale, "{name}: {worst:e} of {scale:e}");
    }
}

/// Two skins of one point blob each (support radius 2, skins of radius 1)
/// whose skins overlap by `depth`, centred off the lattice's axes.
fn pressed(depth: Real) -> Skins {
    let gap = 2.0 - depth;
    Skins {
        positions: vec![
            Point3::new(-gap / 2.0, 0.0, 0.0),
            Point3::new(gap / 2.0, 0.013, 0.007),
        ],
        orientations: vec![Quat::identity(); 2],
        primitives: vec![(0, point(2.0), false), (1, point(2.0), true)],
    }
}

/// Where two skins meet, the energy's pressure is Gascuel's: the total
/// force equals `k e n` summed over the contact surface's samples (on a
/// fine grid), even where the lens is thinner than the lattice's cell
/// (the integrals run along edges that cross it, weighted by the normal).
/// The lens is about `2 sqrt(depth)` across, sampled by few lines when
/// that is a few cells. Measured (depth, cell: relative difference):
/// 0.05, 0.25 (1.8 cells across): 19%; 0.05, 0.1 (4.5): 5.4%; 0.2, 0.25
/// (3.6): 5.7%; 0.1, 0.1 (6.3): 1.7%; 0.12% or less from 8 cells across.
#[test]
fn the_pressure_is_gascuels_also_in_thin_lenses() {
    for depth in [0.05, 0.1, 0.2] {
        let s = pressed(depth);
        let (a, b) = s.fields();
        let pair = ContactPair::new(&a, &b);
        let fine = ImplicitContactParams {
            cell_size: 0.002,
            max_nodes_per_axis: 4096,
            ..PARAMS
        };
        let gascuel: Vec3 = pair
            .contact_surface(&fine)
            .unwrap()
            .iter()
            .map(|x| x.normal * (PARAMS.stiffness * x.excess * x.area))
            .sum();
        for h in [0.25, 0.1, 0.05, 0.025] {
            let params = ImplicitContactParams {
                cell_size: h,
                ..PARAMS
            };
            let on_b = s.reactions(&params)[1].0;
            let rel = (on_b - gascuel).norm() / gascuel.norm();
            eprintln!("lens {depth} cell {h}: force on B {on_b:?} against Gascuel's {gascuel:?}: {rel:.2e}");
            // The lens is about 2 sqrt(depth) across: one only a few cells
            // across is sampled by few lines.
            let cells_across = 2.0 * depth.sqrt() / h;
            let bound = match cells_across {
                c if c >= 8.0 => 2e-3,
                c if c >= 3.0 => 0.1,
                _ => 0.25,
            };
            assert!(rel < bound, "lens {depth}, cell {h}: {rel}");
        }
    }
}

/// The largest drift of the total energy (kinetic plus contact) over a
/// collision of two point blobs against one (unit masses, no other
/// force), integrated by velocity Verlet with step `dt`.
fn collision_energy_drift(dt: Real, params: &ImplicitContactParams) -> (Real, Real) {
    let mut s = blobs();
    for p in &mut s.positions {
        p.x *= 1.6;
    }
    let mut velocity = [
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.5, 0.02, 0.0),
        Vec3::new(-0.5, 0.0, 0.01),
    ];
    crate::implicit_contact::tests::verlet_energy_drift(
        &mut s,
        &mut velocity,
        (dt, 2.0),
        |s| &mut s.positions,
        |s| s.energy(params),
        |s| s.reactions(params).iter().map(|r| r.0).collect(),
    )
}

/// Velocity Verlet conserves the total energy with contact to second
/// order: halving the step quarters the drift over a whole collision
/// (the contact energy peaks at 0.88 of the kinetic energy). Measured:
/// drifts 1.3e-3, 3.3e-4, 9.0e-5 of the energy at steps 0.02, 0.01 and
/// 0.005 (ratios 3.9 and 3.7).
#[test]
fn verlet_conserves_energy_with_contact_at_second_order() {
    let params = ImplicitContactParams {
        cell_size: 0.05,
        ..PARAMS
    };
    let drifts: Vec<(Real, Real)> = [0.02, 0.01, 0.005]
        .map(|dt| collision_energy_drift(dt, &params))
        .to_vec();
    crate::implicit_contact::tests::assert_second_order(&drifts, "the blobs collide");
}

/// Moving one particle of a skin pressed into another around a small
/// square loop does (almost) no work, and the contact's stiffness between
/// two particles is symmetric. Measured: work 1.1e-5 of `|F| L` and
/// asymmetry 6e-3 (the squares' quadrature is exact to about 1e-4); the
/// contact surface's pressures shared among primitives by field value,
/// the reactions before this energy, did 2.4e-3 of `|F| L` with an
/// asymmetry of 0.55 in the same test.
#[test]
fn contact_does_no_work_around_a_loop_and_its_stiffness_is_symmetric() {
    let mut s = ribbon_and_clump(&mut Rng::new(5));
    let reactions = s.reactions(&PARAMS);
    // The most loaded particle of each skin.
    let most = |range: std::ops::Range<usize>| {
        range
            .max_by(|&i, &j| reactions[i].0.norm().total_cmp(&reactions[j].0.norm()))
            .unwrap()
    };
    let (i, j) = (most(0..8), most(8..14));
    let load = reactions[i].0.norm();
    assert!(load > 1.0, "particle {i} is pressed ({load})");

    let side = 0.02;
    let per_side = 40;
    let start = s.positions[i];
    let corners = [
        Vec3::zeros(),
        Vec3::new(side, 0.0, 0.0),
        Vec3::new(side, 0.0, side),
        Vec3::new(0.0, 0.0, side),
        Vec3::zeros(),
    ];
    let mut work = 0.0;
    let mut previous = reactions[i].0;
    for c in corners.windows(2) {
        for n in 1..=per_side {
            let t = n as Real / per_side as Real;
            let step = (c[1] - c[0]) / per_side as Real;
            s.positions[i] = start + c[0] + (c[1] - c[0]) * t;
            let f = s.reactions(&PARAMS)[i].0;
            work += 0.5 * (f + previous).dot(&step);
            previous = f;
        }
    }
    s.positions[i] = start;
    let relative_work = work.abs() / (load * 4.0 * side);

    // Stiffness between the two particles' positions: K_ab = -dF_a/dx_b.
    let d = 1e-6;
    let mut k = nalgebra::SMatrix::<Real, 6, 6>::zeros();
    for (col, (p, axis)) in [(i, 0), (i, 1), (i, 2), (j, 0), (j, 1), (j, 2)]
        .into_iter()
        .enumerate()
    {
        let at = s.positions[p];
        let mut step = Vec3::zeros();
        step[axis] = d;
        s.positions[p] = at + step;
        let up = s.reactions(&PARAMS);
        s.positions[p] = at - step;
        let down = s.reactions(&PARAMS);
        s.positions[p] = at;
        for (row, q) in [i, i, i, j, j, j].into_iter().enumerate() {
            k[(row, col)] = -(up[q].0[row % 3] - down[q].0[row % 3]) / (2.0 * d);
        }
    }
    let asymmetry = (k - k.transpose()).norm() / k.norm();
    eprintln!(
        "particles {i} and {j}: loop work {relative_work:.2e} of |F| L, stiffness asymmetry {asymmetry:.2e}"
    );
    assert!(relative_work < 1e-3, "{relative_work}");
    assert!(asymmetry < 1e-2, "{asymmetry}");
}
