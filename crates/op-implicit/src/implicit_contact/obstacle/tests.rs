//! Tests of [`super`]: the reactions are the obstacle contact energy's
//! gradient (finite differences in every particle's position and
//! orientation), the energy converges to the integral it approximates,
//! velocity Verlet conserves the energy with contact to second order in
//! the step, the sums do not depend on the thread count, and each lattice
//! edge is found by one block.

use crate::field::Field;
use crate::kernel::ISO;
use crate::primitives::Primitive;
use crate::{ImplicitContactParams, ObstacleContact};
use op_dynamics::{Point3, Quat, Real, Vec3};
use op_test_support::Rng;
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::{Ball, Cuboid, HalfSpace, Shape};

/// An obstacle: a shape and its pose.
type Obstacle<'a> = (&'a dyn Shape, Pose);

/// A skin: each particle's position and orientation, and the primitive
/// it carries.
struct Skin {
    positions: Vec<Point3>,
    orientations: Vec<Quat>,
    primitives: Vec<Primitive>,
}

impl Skin {
    fn field(&self) -> Field {
        Field::new(
            self.primitives
                .iter()
                .enumerate()
                .map(|(i, prim)| prim.posed(i as u32, &self.positions[i], &self.orientations[i]))
                .collect(),
        )
    }

    fn energy(&self, obstacle: &Obstacle<'_>, params: &ImplicitContactParams) -> Real {
        let field = self.field();
        ObstacleContact::new(&field, obstacle.0, &obstacle.1)
            .energy(params)
            .unwrap()
    }

    /// Force and torque on every particle (zero when it has none).
    fn reactions(
        &self,
        obstacle: &Obstacle<'_>,
        params: &ImplicitContactParams,
    ) -> Vec<(Vec3, Vec3)> {
        let field = self.field();
        let r = ObstacleContact::new(&field, obstacle.0, &obstacle.1)
            .reactions(params)
            .unwrap();
        let mut out = vec![(Vec3::zeros(), Vec3::zeros()); self.positions.len()];
        for x in r.reactions() {
            out[x.particle as usize].0 += x.force;
            out[x.particle as usize].1 += x.torque;
        }
        out
    }
}

const PARAMS: ImplicitContactParams = ImplicitContactParams {
    stiffness: 100.0,
    cell_size: 0.05,
    max_nodes_per_axis: 512,
};

/// A ball of radius 1 at the origin.
fn ball() -> (Ball, Pose) {
    (Ball::new(1.0), Pose::identity())
}

/// A box turned about two axes, its top face near z = 0 under the origin.
fn tilted_box() -> (Cuboid, Pose) {
    let rotation = Rotation::from_scaled_axis(Vector::new(0.2, -0.1, 0.05));
    (
        Cuboid::new(Vector::new(2.0, 2.0, 0.5)),
        Pose::from_parts(Vector::new(0.05, -0.02, -0.5), rotation),
    )
}

/// Two point blobs pressed into the top of the ball, off its axis.
fn blobs_on_ball() -> Skin {
    Skin {
        positions: vec![Point3::new(0.2, 0.1, 1.45), Point3::new(-0.25, 0.05, 1.42)],
        orientations: vec![Quat::identity(); 2],
        primitives: vec![Primitive::point(Vec3::zeros(), 0.8); 2],
    }
}

/// A wavy row of tilted squares and offset ellipsoids (oriented: torques)
/// pressed into the box's top face, at random.
fn ribbon(rng: &mut Rng) -> Skin {
    let mut s = Skin {
        positions: Vec::new(),
        orientations: Vec::new(),
        primitives: Vec::new(),
    };
    for i in 0..6 {
        let x = 0.35 * i as Real - 0.9;
        s.positions
            .push(Point3::new(x, 0.1 * x, 0.12 + 0.05 * (2.0 * x).sin()));
        s.orientations.push(rng.quat(0.5));
        s.primitives.push(if i % 2 == 0 {
            Primitive::square(Vec3::z(), 0.2, 0.35)
        } else {
            Primitive::ellipsoid(
                Vec3::new(0.05, 0.0, -0.03),
                Quat::identity(),
                Vec3::new(1.0, 0.6, 0.8),
                0.4,
            )
        });
    }
    s
}

/// Every particle's force is minus the energy's derivative in its
/// position, and its torque minus the derivative in a rotation about
/// itself (central differences of 1e-6). Points and ellipsoids are
/// polynomials along a line, which the quadrature integrates to
/// round-off; a square's distance is C1, not C2, across its edges, where
/// no quadrature piece ends. Measured: 1.0e-10 of the largest reaction for
/// the blobs on the ball, 4.6e-6 and 3.4e-6 for the ribbons on the box.
#[test]
fn reactions_are_the_energy_gradient() {
    let (b, bp) = ball();
    let (c, cp) = tilted_box();
    let mut rng = Rng::new(7);
    let mut cases: Vec<(&str, Skin, Obstacle<'_>, Real)> =
        vec![("blobs on a ball", blobs_on_ball(), (&b, bp), 1e-7)];
    for _ in 0..2 {
        cases.push(("ribbon on a box", ribbon(&mut rng), (&c, cp), 2e-4));
    }
    let d = 1e-6;
    for (name, mut s, obstacle, tolerance) in cases {
        let analytic = s.reactions(&obstacle, &PARAMS);
        let scale = analytic
            .iter()
            .map(|(f, t)| f.norm().max(t.norm()))
            .fold(0.0, Real::max);
        assert!(scale > 1e-2, "{name}: the skin is in contact ({scale})");
        let mut worst: Real = 0.0;
        for (i, (force_i, torque_i)) in analytic.iter().enumerate() {
            for k in 0..3 {
                let mut step = Vec3::zeros();
                step[k] = d;
                let p = s.positions[i];
                s.positions[i] = p + step;
                let up = s.energy(&obstacle, &PARAMS);
                s.positions[i] = p - step;
                let down = s.energy(&obstacle, &PARAMS);
                s.positions[i] = p;
                worst = worst.max((-(up - down) / (2.0 * d) - force_i[k]).abs());

                let q = s.orientations[i];
                s.orientations[i] = Quat::from_scaled_axis(step) * q;
                let up = s.energy(&obstacle, &PARAMS);
                s.orientations[i] = Quat::from_scaled_axis(-step) * q;
                let down = s.energy(&obstacle, &PARAMS);
                s.orientations[i] = q;
                worst = worst.max((-(up - down) / (2.0 * d) - torque_i[k]).abs());
            }
        }
        eprintln!(
            "{name}: largest reaction {scale:.3e}, worst FD difference {:.2e} of it",
            worst / scale
        );
        assert!(worst < tolerance * scale, "{name}: {worst:e} of {scale:e}");
    }
}

/// `k ∫_{z<0} max(0, f - ISO) dV` for one point blob of radius `r` at
/// height `z` over the half-space `z < 0`, by nested Simpson rules in
/// cylindrical coordinates (the reference the lattice converges to).
fn half_space_energy(k: Real, r: Real, z: Real) -> Real {
    let prim =
        Primitive::point(Vec3::zeros(), r).posed(0, &Point3::new(0.0, 0.0, z), &Quat::identity());
    let simpson = |n: usize, a: Real, b: Real, f: &dyn Fn(Real) -> Real| {
        let h = (b - a) / n as Real;
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(a + h * i as Real)
            })
            .sum::<Real>()
            * h
            / 3.0
    };
    let layer = |zz: Real| {
        simpson(2000, 0.0, r, &|rho| {
            let e = prim.field(&Point3::new(rho, 0.0, zz)) - ISO;
            2.0 * std::f64::consts::PI * rho * e.max(0.0)
        })
    };
    k * simpson(2000, z - r, 0.0, &layer)
}

/// The lattice's energy and force converge to the half-space integral as
/// the cell shrinks, for a blob pressed a fifth of its skin's radius into
/// a flat face (a box's, and a half-space, whose bounding box is
/// infinite): the force is `-dE/dz` of the reference. Measured
/// (energy, force): 1.6e-3 and 4.6e-3 at cell 0.1, 1.0e-4 and 1.4e-3 at
/// 0.05, 1.4e-5 and 6.5e-5 at 0.025.
#[test]
fn the_energy_converges_to_the_volume_integral() {
    let (r, z) = (1.0, crate::kernel::iso_radius(1.0) - 0.2);
    let plate = (
        Cuboid::new(Vector::new(3.0, 3.0, 1.0)),
        Pose::from_translation(Vector::new(0.013, -0.007, -1.0)),
    );
    let s = Skin {
        positions: vec![Point3::new(0.0, 0.0, z)],
        orientations: vec![Quat::identity()],
        primitives: vec![Primitive::point(Vec3::zeros(), r)],
    };
    let reference = half_space_energy(PARAMS.stiffness, r, z);
    let dz = 1e-4;
    let force = -(half_space_energy(PARAMS.stiffness, r, z + dz)
        - half_space_energy(PARAMS.stiffness, r, z - dz))
        / (2.0 * dz);
    assert!(reference > 0.0 && force > 0.0, "{reference} {force}");
    let half_space = (
        HalfSpace::new(Vector::new(0.0, 0.0, 1.0)),
        Pose::from_translation(Vector::new(0.013, -0.007, 0.0)),
    );
    let obstacles: [(&str, Obstacle<'_>); 2] = [
        ("plate", (&plate.0, plate.1)),
        ("half-space", (&half_space.0, half_space.1)),
    ];
    for (name, obstacle) in obstacles {
        let mut errors = Vec::new();
        for h in [0.1, 0.05, 0.025] {
            let params = ImplicitContactParams {
                cell_size: h,
                ..PARAMS
            };
            let e = s.energy(&obstacle, &params);
            let f = s.reactions(&obstacle, &params)[0].0;
            let (de, df) = (
                (e - reference).abs() / reference,
                (f.z - force).abs() / force,
            );
            eprintln!("{name}, cell {h}: energy {e:.6e} ({de:.1e}), force {:.6e} ({df:.1e}) against {reference:.6e}, {force:.6e}", f.z);
            assert!(f.xy().norm() < 1e-9 * force, "{name}: sideways {f:?}");
            errors.push(de.max(df));
        }
        assert!(errors[2] < 5e-4, "{name}: {errors:?}");
        assert!(errors[2] <= errors[0], "{name}: {errors:?}");
    }
}

/// The largest drift of the total energy (kinetic plus contact) over a
/// bounce of two blobs off the ball (unit masses, no other force),
/// integrated by velocity Verlet with step `dt`, and the peak contact
/// energy, both over the kinetic energy.
fn bounce_energy_drift(dt: Real) -> (Real, Real) {
    let (b, bp) = ball();
    let obstacle: Obstacle<'_> = (&b, bp);
    let params = PARAMS;
    let mut s = blobs_on_ball();
    for p in &mut s.positions {
        p.z += 0.35;
    }
    let mut velocity = [Vec3::new(0.05, 0.0, -0.5), Vec3::new(0.0, 0.03, -0.45)];
    crate::implicit_contact::tests::verlet_energy_drift(
        &mut s,
        &mut velocity,
        (dt, 1.6),
        |s| &mut s.positions,
        |s| s.energy(&obstacle, &params),
        |s| {
            s.reactions(&obstacle, &params)
                .iter()
                .map(|r| r.0)
                .collect()
        },
    )
}

/// Velocity Verlet conserves the total energy with obstacle contact to
/// second order: halving the step quarters the drift over a whole bounce
/// (the contact energy peaks at 0.72 of the kinetic energy). Measured:
/// drifts 1.4e-3, 3.7e-4, 8.9e-5 of the energy at steps 0.02, 0.01 and
/// 0.005 (ratios 3.7 and 4.1).
#[test]
fn verlet_conserves_energy_with_obstacle_contact_at_second_order() {
    let drifts: Vec<(Real, Real)> = [0.02, 0.01, 0.005].map(bounce_energy_drift).to_vec();
    crate::implicit_contact::tests::assert_second_order(&drifts, "the blobs bounce");
}

/// A skin of squares on a grid, pressed into the tilted box's top face,
/// a little wavy (seeded): 1200 particles 0.1 apart.
fn mat(rng: &mut Rng) -> Skin {
    let n = 1200;
    Skin {
        positions: (0..n)
            .map(|i| {
                let (x, y) = ((i % 40) as Real * 0.1 - 2.0, (i / 40) as Real * 0.1 - 1.5);
                Point3::new(x, y, 0.1 + 0.02 * rng.vec3(1.0).z)
            })
            .collect(),
        orientations: (0..n).map(|_| rng.quat(0.3)).collect(),
        primitives: vec![Primitive::square(Vec3::z(), 0.05, 0.15); n],
    }
}

/// Each lattice edge is integrated once: the edges the blocks own
/// (`owned_edges`, every block's merged) are, with their ends' flags,
/// those of an oracle that splats every block whole from every primitive,
/// tests every node for containment and merges the blocks' edges without
/// duplicates. The skin spans many blocks, so many edges lie on faces two
/// blocks share.
#[test]
fn each_edge_is_found_by_one_block() {
    use super::band;
    use crate::polygonize::blocks::{splat_block, BlockLists};

    let s = mat(&mut Rng::new(3));
    let field = s.field();
    let (c, cp) = tilted_box();
    let obstacle = super::Obstacle::new(&c, &cp);
    let grid = super::lattice(&field, &obstacle, PARAMS.cell_size, 512)
        .unwrap()
        .unwrap();
    let n_blocks: usize = grid.blocks().iter().product();
    let arch = pulp::Arch::new();
    let lists = BlockLists::filtered(&field, &grid, |c, r| {
        obstacle.may_reach_inside(c, r + grid.h)
    });
    let per_block: Vec<Vec<(usize, usize, [bool; 2])>> = (0..n_blocks)
        .map(|b| {
            super::owned_edges(&grid, &field, &obstacle, &lists, b, arch)
                .into_iter()
                .map(|e| (e.node, e.axis, e.ends))
                .collect()
        })
        .collect();
    assert!(per_block.iter().filter(|e| !e.is_empty()).count() >= 6);
    let mut owned: Vec<_> = per_block.concat();
    owned.sort_unstable();

    let all = BlockLists::new(&field, &grid);
    let mut dense = Vec::new();
    for b in 0..n_blocks {
        let block = grid.block(b);
        let (values, _) = splat_block(&field, &grid, &block, all.of(b), arch);
        let nodes = block.nodes();
        let mut inside = Vec::with_capacity(values.len());
        for z in 0..nodes[2] {
            for y in 0..nodes[1] {
                for x in 0..nodes[0] {
                    let p = grid.node(block.start[0] + x, block.start[1] + y, block.start[2] + z);
                    inside.push(if obstacle.contains(&p) {
                        ISO + 1.0
                    } else {
                        0.0
                    });
                }
            }
        }
        let strides = [1, nodes[0], nodes[0] * nodes[1]];
        for (node, axis) in band::block_edges(&grid, &values, &inside, &block, band::overlapped) {
            let at = band::coords(&grid, node);
            let l: usize = (0..3).map(|k| (at[k] - block.start[k]) * strides[k]).sum();
            let end = |l: usize| inside[l] > ISO;
            dense.push((node, axis, [end(l), end(l + strides[axis])]));
        }
    }
    dense.sort_unstable();
    dense.dedup();
    assert!(dense.len() > 1000, "{} edges", dense.len());
    let first_difference = owned.iter().zip(&dense).position(|(a, b)| a != b);
    assert!(
        owned == dense,
        "{} edges owned, {} in the oracle; first difference at {first_difference:?}",
        owned.len(),
        dense.len()
    );
}

/// A skin of more particles than the parallel threshold gets the same
/// bits at 1 and 3 threads; a skin away from the obstacle gets nothing,
/// and a bad cell size is an error.
#[test]
fn the_sums_do_not_depend_on_the_thread_count() {
    let s = mat(&mut Rng::new(3));
    let (c, cp) = tilted_box();
    let obstacle: Obstacle<'_> = (&c, cp);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| s.reactions(&obstacle, &PARAMS))
    };
    let one = run(1);
    assert!(one.iter().filter(|r| r.0 != Vec3::zeros()).count() > 100);
    assert_eq!(one, run(3));

    let far = Skin {
        positions: vec![Point3::new(0.0, 0.0, 3.0)],
        orientations: vec![Quat::identity()],
        primitives: vec![Primitive::point(Vec3::zeros(), 0.8)],
    };
    assert_eq!(far.energy(&obstacle, &PARAMS), 0.0);
    assert!(far.reactions(&obstacle, &PARAMS)[0].0 == Vec3::zeros());
    let field = far.field();
    let bad = ImplicitContactParams {
        cell_size: 0.0,
        ..PARAMS
    };
    assert!(ObstacleContact::new(&field, &c, &cp)
        .reactions(&bad)
        .is_err());
}

/// The bounding-box shortcut of `may_reach_inside` answers as the signed
/// distance alone does, for balls near and far from a tilted box, a ball
/// and a half-space (whose box is infinite), including balls just
/// touching the box's faces.
#[test]
fn the_box_shortcut_answers_as_the_signed_distance() {
    let (c, cp) = tilted_box();
    let ball = Ball::new(1.5);
    let half = HalfSpace::new(Vector::new(0.1, -0.2, 1.0).normalize());
    let at = Pose::from_parts(Vector::new(0.3, -0.1, 0.2), Rotation::IDENTITY);
    let shapes: [(&dyn Shape, &Pose); 3] = [(&c, &cp), (&ball, &at), (&half, &at)];
    let mut rng = Rng::new(17);
    for (shape, pose) in shapes {
        let obstacle = super::Obstacle::new(shape, pose);
        let (lo, hi) = obstacle.bounding_box();
        for _ in 0..4000 {
            let r = rng.uniform(0.0, 1.0);
            let mut x = Point3::new(
                rng.uniform(-5.0, 5.0),
                rng.uniform(-5.0, 5.0),
                rng.uniform(-5.0, 5.0),
            );
            // A quarter of the balls sit just beyond the box's +x face,
            // centred on it in y and z (where the ball obstacle touches its
            // box): there the shortcut's margin decides.
            if rng.uniform(0.0, 1.0) < 0.25 && hi.x.is_finite() {
                x = Point3::new(
                    hi.x + r + rng.uniform(-1e-3, 1e-3),
                    0.5 * (lo.y + hi.y),
                    0.5 * (lo.z + hi.z),
                );
            }
            let by_distance = obstacle.signed(&x).0 <= r + 1e-9 * (1.0 + r);
            assert_eq!(obstacle.may_reach_inside(&x, r), by_distance, "{x} {r}");
        }
    }
}
