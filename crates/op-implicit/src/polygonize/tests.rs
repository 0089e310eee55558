//! Unit tests of the polygonization (seed 002 §6): a closed outward
//! sphere whose vertex error falls as the cell size squared, the narrow
//! band against the dense reference (lowered fields sampled within their
//! bounds' band, field evaluations following the area), the same mesh at
//! one and two threads, and the errors of an empty field and of bad
//! parameters.

use super::*;
use crate::kernel::iso_radius;
use crate::primitives::Primitive;
use op_dynamics::Quat;

fn ball(centre: Point3, radius: Real) -> Field {
    Field::new(vec![Primitive::point(Vec3::zeros(), radius).posed(
        0,
        &centre,
        &Quat::identity(),
    )])
}

/// Largest distance of a vertex from the exact sphere.
fn max_error(mesh: &Mesh, centre: &Point3, r: Real) -> Real {
    mesh.positions()
        .iter()
        .map(|p| ((p - centre).norm() - r).abs())
        .fold(0.0, Real::max)
}

#[test]
fn point_primitive_gives_closed_outward_sphere() {
    let c = Point3::new(0.37, -1.1, 2.05);
    let radius = 1.0;
    let h = radius / 12.0;
    let mesh = polygonize(&ball(c, radius), &PolygonizeParams::with_cell_size(h)).unwrap();
    assert!(mesh.triangles().len() > 500);
    assert!(mesh.is_closed_oriented_manifold());
    let r = iso_radius(radius);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let v = mesh.signed_volume();
    assert!(
        v > 0.0 && (v - exact).abs() < 0.05 * exact,
        "{v} vs {exact}"
    );
    assert!(max_error(&mesh, &c, r) < 0.1 * h);
    for (p, n) in mesh.positions().iter().zip(mesh.normals()) {
        assert!((n.norm() - 1.0).abs() < 1e-12);
        assert!(n.dot(&(p - c).normalize()) > 0.999);
    }
    for t in mesh.triangles() {
        let [a, b, cc] = t.map(|i| mesh.positions()[i as usize]);
        let face = (b - a).cross(&(cc - a));
        let avg: Vec3 = t.iter().map(|&i| mesh.normals()[i as usize]).sum();
        // Triangles the surface pinches to a point where it passes
        // through a grid node have no direction: skip them.
        assert!(face.norm() < 1e-12 * h * h || face.dot(&avg) >= 0.0);
    }
}

/// Max and RMS vertex error against the exact sphere at `h = R/8, R/16,
/// R/32` (coarser grids are pre-asymptotic). Measured: max 2.95e-3,
/// 8.52e-4, 2.29e-4 (order 1.84); RMS 1.79e-3, 4.39e-4, 1.08e-4 (order
/// 2.03): second order, as expected of linear interpolation along edges.
#[test]
fn vertex_error_falls_as_cell_size_squared() {
    let c = Point3::new(0.1, 0.2, -0.3);
    let radius = 1.0;
    let r = iso_radius(radius);
    let hs = [radius / 8.0, radius / 16.0, radius / 32.0];
    let errors: Vec<(Real, Real)> = hs
        .iter()
        .map(|&h| {
            let params = PolygonizeParams::with_cell_size(h);
            let mesh = polygonize(&ball(c, radius), &params).unwrap();
            let e: Vec<Real> = mesh
                .positions()
                .iter()
                .map(|p| ((p - c).norm() - r).abs())
                .collect();
            let rms = (e.iter().map(|x| x * x).sum::<Real>() / e.len() as Real).sqrt();
            (max_error(&mesh, &c, r), rms)
        })
        .collect();
    let order = |e0: Real, e2: Real| (e0 / e2).ln() / (hs[0] / hs[2]).ln();
    let max_order = order(errors[0].0, errors[2].0);
    let rms_order = order(errors[0].1, errors[2].1);
    eprintln!("h {hs:?} (max, rms) {errors:?} orders {max_order:.2} {rms_order:.2}");
    assert!(errors[0].0 > errors[1].0 && errors[1].0 > errors[2].0);
    assert!(
        max_order > 1.5 && rms_order > 1.5,
        "{max_order} {rms_order}"
    );
}

/// Point primitives of support `radius` on the lattice of spacing
/// `step` inside `keep`.
fn lattice(step: Real, n: i32, radius: Real, keep: impl Fn(&Point3) -> bool) -> Field {
    let mut prims = Vec::new();
    for k in -n..=n {
        for j in -n..=n {
            for i in -n..=n {
                // A small fixed jitter keeps nodes off symmetric spots.
                let p = Point3::new(i as Real, j as Real, k as Real) * step
                    + Vec3::new(0.013, -0.007, 0.011) * step;
                if keep(&p) {
                    let id = prims.len() as u32;
                    prims.push(Primitive::point(Vec3::zeros(), radius).posed(
                        id,
                        &p,
                        &Quat::identity(),
                    ));
                }
            }
        }
    }
    Field::new(prims)
}

/// A sheet of square primitives, `n` by `n`, gently curved.
fn sheet(n: i32) -> Field {
    let mut prims = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as Real * 0.2, j as Real * 0.2);
            let z = 0.1 * (x * 1.3).sin() * (y * 0.7).cos();
            let q = Quat::from_scaled_axis(Vec3::new(0.05 * y.sin(), -0.1 * x.cos(), 0.0));
            prims.push(Primitive::square(Vec3::z(), 0.1, 0.25).posed(
                prims.len() as u32,
                &Point3::new(x, y, z),
                &q,
            ));
        }
    }
    Field::new(prims)
}

fn torus() -> Field {
    lattice(0.1, 14, 0.3, |p| {
        let ring = (p.x * p.x + p.y * p.y).sqrt() - 0.9;
        ring * ring + p.z * p.z < 0.3 * 0.3
    })
}

/// The same field with every primitive's amplitude set to `weight`.
fn weighted(field: &Field, weight: Real) -> Field {
    let prims = field
        .primitives()
        .iter()
        .map(|p| {
            Primitive::point(Vec3::zeros(), p.bounding_sphere().1)
                .with_weight(weight)
                .posed(p.particle(), p.particle_position(), &Quat::identity())
        })
        .collect();
    Field::new(prims)
}

/// A field seen without its bounding field: every node sampled.
struct Dense<'a, F: ScalarField + ?Sized>(&'a F);

impl<F: ScalarField + ?Sized> ScalarField for Dense<'_, F> {
    fn value(&self, p: &Point3) -> Real {
        self.0.value(p)
    }
    fn value_and_gradient(&self, p: &Point3) -> crate::field::ValueGradient {
        self.0.value_and_gradient(p)
    }
    fn support_box(&self) -> Option<(Point3, Point3)> {
        self.0.support_box()
    }
}

/// Ellipsoids (the displayed skin of squares): flat discs on a sheet.
fn sheet_of_ellipsoids(n: usize) -> Field {
    let q = Quat::identity();
    let disc = Primitive::ellipsoid(Vec3::zeros(), q, Vec3::new(1.6, 1.6, 1.0), 0.15);
    let mut prims = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let at = Point3::new(i as Real * 0.1, j as Real * 0.1, 0.02 * (i as Real).sin());
            prims.push(disc.posed(prims.len() as u32, &at, &q));
        }
    }
    Field::new(prims)
}

/// Clipped and deformed fields are polygonized in the band of the
/// field they lower (their bounding field): the same mesh, bit for
/// bit, as sampling every node, with fewer nodes sampled.
#[test]
fn lowered_fields_are_sampled_in_their_bounds_band() {
    use crate::{ClippedField, ContactPair};
    use parry3d_f64::math::{Pose, Vector};
    use parry3d_f64::shape::{Cuboid, Shape};
    let torus = torus();
    let ball = lattice(0.1, 6, 0.3, |p| {
        (p - Point3::new(0.9, 0.0, 0.3)).norm() < 0.35
    });
    // A slab whose top face z = -0.1 cuts the torus.
    let floor = Cuboid::new(Vector::new(3.0, 3.0, 1.0));
    let pose = Pose::from_translation(Vector::new(0.0, 0.0, -1.1));
    let params = PolygonizeParams::with_cell_size(0.04);
    let clipped = ClippedField::new(&torus, vec![(&floor as &dyn Shape, pose)], ISO / 0.04);
    let pair = ContactPair::new(&torus, &ball);
    let deformed = pair.deformed_a();
    let discs = sheet_of_ellipsoids(10);
    let cases: Vec<(&str, &dyn ScalarField)> = vec![
        ("clipped", &clipped),
        ("deformed", &deformed),
        ("ellipsoids", &discs),
    ];
    for (name, field) in cases {
        let band = polygonize_field(field, &params).unwrap();
        let dense = polygonize_field(&Dense(field), &params).unwrap();
        assert!(band.triangles().len() > 200, "{name}");
        assert_eq!(band, dense, "{name}");
    }
}

/// A skin clipped by a collider, alone or deformed by another skin, is
/// splatted ([`polygonize_clipped`]) into the mesh that evaluating every
/// node gives: same triangles, vertices within rounding (splatted and
/// evaluated kernels differ in their last bits), at any thread count.
#[test]
fn clipped_skins_are_splatted_into_the_dense_mesh() {
    use crate::{ClippedField, ContactPair};
    use parry3d_f64::math::{Pose, Vector};
    use parry3d_f64::shape::{Ball, Cuboid, Shape};
    let (squares, torus) = (sheet(12), torus());
    let ball = lattice(0.1, 6, 0.3, |p| {
        (p - Point3::new(0.9, 0.0, 0.3)).norm() < 0.35
    });
    // A slab whose top face z = -0.1 cuts the torus and the sheet, and a
    // ball pressing the torus's side.
    let floor = Cuboid::new(Vector::new(3.0, 3.0, 1.0));
    let knob = Ball::new(0.3);
    let colliders = || -> Vec<(&dyn Shape, Pose)> {
        vec![
            (&floor, Pose::from_translation(Vector::new(0.0, 0.0, -1.1))),
            (&knob, Pose::from_translation(Vector::new(-1.0, 0.0, 0.2))),
        ]
    };
    let h = 0.04;
    let params = PolygonizeParams::with_cell_size(h);
    let slope = ISO / h;
    for (name, own, other) in [
        ("torus", &torus, None),
        ("sheet of squares", &squares, None),
        ("torus pressed by a ball", &torus, Some(&ball)),
    ] {
        let dense = match other {
            None => polygonize_field(&Dense(&ClippedField::new(own, colliders(), slope)), &params),
            Some(o) => {
                let deformed = ContactPair::new(own, o).deformed_a();
                polygonize_field(
                    &Dense(&ClippedField::new(&deformed, colliders(), slope)),
                    &params,
                )
            }
        }
        .unwrap();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let splatted = pool
                .install(|| polygonize_clipped(own, other, colliders(), slope, &params))
                .unwrap();
            assert!(splatted.triangles().len() > 200, "{name}");
            assert_eq!(splatted.triangles(), dense.triangles(), "{name}");
            assert_eq!(splatted.positions().len(), dense.positions().len());
            for (a, b) in splatted.positions().iter().zip(dense.positions()) {
                assert!((a - b).norm() < 1e-9, "{name}: {a:?} vs {b:?}");
            }
            // The clip bites: vertices lie on the slab's top face.
            let on_floor = splatted
                .positions()
                .iter()
                .filter(|p| (p.z + 0.1).abs() < 1e-9)
                .count();
            assert!(on_floor > 20, "{name}: {on_floor} vertices on the floor");
        }
    }
}

fn test_fields() -> Vec<(&'static str, Field, Real)> {
    let sphere = lattice(0.1, 6, 0.3, |p| p.coords.norm() < 0.55);
    vec![
        // Amplitude below 1 (a smoothness above 1): the band's splat
        // must weigh each kernel as the field does.
        ("weighted sphere of points", weighted(&sphere, 0.7), 0.04),
        ("sphere of points", sphere, 0.04),
        ("sheet of squares", sheet(12), 0.03),
        ("torus of points", torus(), 0.05),
    ]
}

/// The narrow band is the dense grid with the blocks that cannot cross
/// skipped: same triangles, vertices within rounding.
#[test]
fn narrow_band_equals_dense_reference() {
    for (name, field, h) in test_fields() {
        for iso in [ISO, 1.5] {
            let params = PolygonizeParams {
                iso,
                ..PolygonizeParams::with_cell_size(h)
            };
            let (band, stats) = polygonize_with_stats(&field, &params).unwrap();
            let dense = polygonize_field(&Dense(&field), &params).unwrap();
            eprintln!(
                "{name} iso {iso}: {} triangles, {stats:?}",
                band.triangles().len()
            );
            assert!(band.triangles().len() > 200, "{name}");
            assert_eq!(band.triangles(), dense.triangles(), "{name}");
            assert_eq!(band.positions().len(), dense.positions().len());
            for (a, b) in band.positions().iter().zip(dense.positions()) {
                assert!((a - b).norm() < 1e-9, "{name}: {a:?} vs {b:?}");
            }
            assert!(band.is_closed_oriented_manifold(), "{name}");
            assert!(band.signed_volume() > 0.0);
            assert!(
                name == "sheet of squares" || stats.sampled_blocks < stats.blocks,
                "{name}: no block skipped"
            );
        }
    }
}

#[test]
fn same_mesh_at_one_and_two_threads() {
    for (name, field, h) in test_fields() {
        let params = PolygonizeParams::with_cell_size(h);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| polygonize(&field, &params).unwrap())
        };
        let one = run(1);
        assert_eq!(one, run(2), "{name}");
        assert_eq!(one, run(3), "{name}");
    }
}

/// A hollow shell of point primitives, radius doubled: the area grows
/// 4x, the box ~5x (8x asymptotically; the support pads it); the
/// sampled nodes and evaluations follow the area. Measured: triangles
/// x3.86, nodes x4.09, evaluations x3.85, box x5.15; the large shell
/// samples 541 of 864 blocks (nodes on block faces counted per block).
#[test]
fn field_evaluations_follow_the_area() {
    let shell = |rho: Real| {
        let n = (rho / 0.1).ceil() as i32 + 1;
        lattice(0.1, n, 0.3, |p| (p.coords.norm() - rho).abs() < 0.06)
    };
    let params = PolygonizeParams::with_cell_size(0.05);
    let (small, s1) = polygonize_with_stats(&shell(1.0), &params).unwrap();
    let (large, s2) = polygonize_with_stats(&shell(2.0), &params).unwrap();
    assert!(small.is_closed_oriented_manifold() && large.is_closed_oriented_manifold());
    let tri_ratio = large.triangles().len() as Real / small.triangles().len() as Real;
    let node_ratio = s2.sampled_nodes as Real / s1.sampled_nodes as Real;
    let eval_ratio = s2.field_evaluations as Real / s1.field_evaluations as Real;
    let box_ratio = s2.grid_nodes as Real / s1.grid_nodes as Real;
    eprintln!("{s1:?}\n{s2:?}\ntriangles x{tri_ratio:.2} nodes x{node_ratio:.2} evaluations x{eval_ratio:.2} box x{box_ratio:.2}");
    assert!((3.5..4.5).contains(&tri_ratio));
    assert!((3.0..5.0).contains(&node_ratio) && (3.0..5.0).contains(&eval_ratio));
    assert!(box_ratio > 5.0 && node_ratio < 0.8 * box_ratio);
}

#[test]
fn empty_field_and_bad_parameters() {
    let empty = polygonize(&Field::default(), &PolygonizeParams::with_cell_size(0.1)).unwrap();
    assert!(empty.is_empty());
    let f = ball(Point3::origin(), 1.0);
    assert_eq!(
        polygonize(&f, &PolygonizeParams::with_cell_size(0.0)),
        Err(PolygonizeError::InvalidCellSize(0.0))
    );
    let bad_iso = PolygonizeParams {
        iso: 0.0,
        ..PolygonizeParams::with_cell_size(0.1)
    };
    assert_eq!(
        polygonize(&f, &bad_iso),
        Err(PolygonizeError::InvalidIso(0.0))
    );
    assert!(matches!(
        polygonize(&f, &PolygonizeParams::with_cell_size(1e-4)),
        Err(PolygonizeError::TooManyNodes { .. })
    ));
}

/// The splat of a skeleton other than a point gives each node the bits of
/// mapping it alone into the primitive's frame (`m * (p - t)`) and
/// evaluating its field there ([`PosedPrimitive::field_in_frame`]),
/// summed in increasing primitive order: segments, rectangles and
/// ellipsoids at random poses, weights and radii, over a block.
#[test]
fn skeleton_rows_are_each_node_alone_bit_for_bit() {
    use crate::polygonize::blocks::{splat_block, Block, Grid};
    let mut rng = op_test_support::Rng::new(5);
    let mut primitives = Vec::new();
    for i in 0..24u32 {
        let local = rng.vec3(0.3);
        let radius = rng.uniform(0.3, 1.0);
        let shape = match i % 3 {
            0 => Primitive::segment(-local, local, radius),
            1 => Primitive::rectangle(
                local,
                rng.quat(3.0),
                [rng.uniform(0.0, 0.4), rng.uniform(0.0, 0.4)],
                radius,
            ),
            _ => Primitive::ellipsoid(
                local,
                rng.quat(3.0),
                Vec3::new(
                    rng.uniform(0.5, 1.5),
                    rng.uniform(0.5, 1.5),
                    rng.uniform(0.5, 1.5),
                ),
                radius,
            ),
        };
        let posed = shape.with_weight(rng.uniform(0.5, 2.0)).posed(
            i,
            &Point3::from(rng.vec3(1.5)),
            &rng.quat(3.0),
        );
        primitives.push(posed);
    }
    let field = Field::new(primitives);
    let grid = Grid {
        lo: Point3::new(-2.1, -2.05, -2.02),
        h: 0.13,
        dims: [34, 34, 34],
    };
    let block = Block {
        start: [3, 5, 2],
        cells: [16, 8, 8],
    };
    let list: Vec<u32> = (0..field.primitives().len() as u32).collect();
    let (values, evaluations) = splat_block(&field, &grid, &block, &list, pulp::Arch::new());
    assert!(evaluations > 2_000, "{evaluations} evaluations");
    let nodes = block.nodes();
    let mut nonzero = 0;
    for k in 0..nodes[2] {
        for j in 0..nodes[1] {
            for i in 0..nodes[0] {
                let p = grid.node(block.start[0] + i, block.start[1] + j, block.start[2] + k);
                let mut expected = 0.0;
                for prim in field.primitives() {
                    let (c, r) = prim.bounding_sphere();
                    if (p - c).norm_squared() < r * r {
                        let (m, t) = prim.world_to_frame();
                        expected += prim.field_in_frame(&(m * (p.coords - t)));
                    }
                }
                let got = values[i + nodes[0] * (j + nodes[1] * k)];
                assert_eq!(
                    got.to_bits(),
                    expected.to_bits(),
                    "node ({i}, {j}, {k}): {got} vs {expected}"
                );
                nonzero += usize::from(got != 0.0);
            }
        }
    }
    assert!(nonzero > 500, "{nonzero} nodes reached");
}

/// The parallel weld numbers the vertices as the serial pass with a map
/// from edge to vertex does: random pieces whose shared edges recur in up
/// to four pieces (as an edge on a block corner does), each edge at most
/// once per piece, some pieces empty.
#[test]
fn weld_numbers_vertices_as_a_serial_map_does() {
    let mut state = 0x9e37_79b9_u64;
    let mut next = |m: u64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state % m
    };
    let pieces: Vec<Piece> = (0..300)
        .map(|p: usize| {
            let mut piece = Piece::default();
            if next(5) == 0 {
                return piece;
            }
            let mut keys = std::collections::BTreeSet::new();
            for _ in 0..next(40) {
                // Shared edges near the piece's index recur in later pieces.
                let shared = next(3) != 0;
                let key = if shared {
                    (p / 4 * 8) as u64 + next(64)
                } else {
                    1 << 40 | (p * 100 + keys.len()) as u64
                };
                if keys.insert(key) {
                    piece.keys.push((key, shared));
                    piece
                        .positions
                        .push(Point3::new(key as Real, p as Real, 0.0));
                }
            }
            let n = piece.positions.len() as u64;
            if n > 0 {
                for _ in 0..next(30) {
                    piece
                        .triangles
                        .push([next(n), next(n), next(n)].map(|i| i as u32));
                }
            }
            piece
        })
        .collect();
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut welded = HashMap::new();
    for piece in &pieces {
        let mut local = Vec::new();
        for (&(key, shared), p) in piece.keys.iter().zip(&piece.positions) {
            let fresh = positions.len() as u32;
            let index = if shared {
                *welded.entry(key).or_insert(fresh)
            } else {
                fresh
            };
            if index == fresh {
                positions.push(*p);
            }
            local.push(index);
        }
        triangles.extend(piece.triangles.iter().map(|t| t.map(|i| local[i as usize])));
    }
    assert!(positions.len() > 1000 && welded.len() > 300);
    let (p, t) = weld(&pieces);
    assert_eq!(p, positions);
    assert_eq!(t, triangles);
}
