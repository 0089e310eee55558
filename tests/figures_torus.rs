//! Seed 000 §8, fig. 14: a sphere pushed in at both poles by two
//! spherical shaping tools becomes a torus; "new particles are created
//! inside the torus due to stretching during the formation process, and
//! some old sphere particles are deleted when trapped between the two
//! shaping tools". The scene `scenes/fig_14_sphere_to_torus.ron` is run the
//! way `opsim run` runs it; the triangulation is the one its frames hold
//! (seed 000 §5, `op_modeling::triangulation`, radius 1.7 times the
//! object's measured rest spacing, 0.88 for this Fibonacci sphere).

mod figure_support;

use oriented_particles::op_dynamics::Real;
use oriented_particles::op_modeling::triangulation::{
    triangulate, Triangulation, TriangulationParams,
};
use oriented_particles::op_scene::BuiltScene;

use figure_support::*;

/// The triangulation of the scene's (single) object, as its frames hold it.
fn surface(built: &BuiltScene) -> Triangulation {
    let radius = built.outputs().triangulation_radius * built.objects()[0].rest_spacing;
    triangulate(
        built.world().particles(),
        &TriangulationParams::with_radius(radius),
    )
    .expect("valid radius")
}

/// What a run of the scene did to the shell.
struct Outcome {
    start: Triangulation,
    end: Triangulation,
    /// Particles the stretching rule added (alive or not at the end).
    created: usize,
    /// Particles deleted by the trap rule or merged away (original or
    /// created).
    deleted: usize,
    /// Smallest distance to the z axis among the particles with |z| < 1.
    hole: Real,
}

/// Runs the scene (`tag` keeps the output directories of tests running
/// at the same time apart).
fn run_scene(tag: &str) -> Outcome {
    let scene = load("fig_14_sphere_to_torus");
    assert!(scene.outputs.triangulation, "the scene outputs its surface");
    let start = surface(&build(&scene));
    let (built, summary) = run(&scene, tag);
    let object = &built.objects()[0];
    let p = built.world().particles();
    let alive = |id: u32| p.slot_of(id).is_some();
    let deleted = object.all_ids().filter(|&id| !alive(id)).count();
    let hole = p
        .positions()
        .iter()
        .filter(|x| x.z.abs() < 1.0)
        .map(|x| x.x.hypot(x.y))
        .fold(Real::INFINITY, Real::min);
    let end = surface(&built);
    println!(
        "{} particles at the end ({} created, {deleted} deleted, summary {}); start chi {}, \
         end chi {}, boundary loops {}, manifold {}; nearest particle to the axis for |z| < 1: \
         {hole:.3}",
        p.len(),
        object.created.len(),
        summary.objects[0].particles,
        start.euler_characteristic(),
        end.euler_characteristic(),
        end.boundary_loops(),
        end.is_manifold()
    );
    Outcome {
        start,
        end,
        created: object.created.len(),
        deleted,
        hole,
    }
}

/// Fig. 14, how it gets there: it starts from a closed sphere (Euler
/// characteristic 2, no boundary); the shaping tools open a hole through
/// the middle (no particle within 1.5 r0 of the z axis for |z| < 1, where
/// the sphere had its centre), particles are created by stretching and
/// others deleted between the tools, as the paper says.
#[test]
fn fig_14_shaping_tools_open_a_hole_creating_and_deleting_particles() {
    let o = run_scene("hole");
    assert_eq!(o.start.euler_characteristic(), 2);
    assert_eq!(o.start.boundary_loops(), 0);
    assert!(o.start.is_manifold());
    assert!(o.created > 0, "no particle created");
    assert!(o.deleted > 0, "no particle deleted");
    assert!(o.hole > 1.5, "no hole through the middle: {:.3}", o.hole);
}

/// Connected pieces of a triangulation (triangles sharing a vertex).
fn pieces(t: &Triangulation) -> usize {
    let n = t
        .triangles
        .iter()
        .flatten()
        .max()
        .map_or(0, |&m| m as usize + 1);
    let mut sets = op_modeling::disjoint_sets::DisjointSets::new(n);
    for tri in &t.triangles {
        for &v in &tri[1..] {
            sets.union(tri[0] as usize, v as usize);
        }
    }
    let roots: std::collections::BTreeSet<usize> = t
        .vertices()
        .iter()
        .map(|&v| sets.root(v as usize))
        .collect();
    roots.len()
}

/// Fig. 14, the topology the paper shows: the final surface has genus 1.
/// The triangulation is one connected, consistently oriented manifold with
/// no edge in three triangles; its genus `g = (2 - chi - b) / 2` (`b`
/// boundary loops) is 1, and what boundary it has is a few small holes
/// (at most 2% of its edges).
///
/// Measured (`cargo test --profile ci --test figures_torus -- --nocapture`):
/// 363 particles at the start (chi 2, closed); at t = 22, 428 particles
/// (131 created, 66 deleted by the trap rule or merged away), and the
/// triangulation is the closed torus: chi 0, no boundary, manifold, one
/// piece (856 triangles). Over the frames: genus 1 from t = 12 (chi -5
/// with 5 small holes), closed from t = 16 on. The hole has radius 2.6
/// (nearest particle to the axis for |z| < 1); the tube is round, radius
/// about 2, 4.6 around the axis.
///
/// **Sensitivity** (the scene's parameters were set from the reasoning in
/// its comment, not by trying values until this passed; these neighbours
/// were run afterwards with `opsim run` on edited copies, final frame):
/// dt 2.1e-3 also ends a closed torus; dt 1.9e-3 ends genus 1 with two
/// small holes (chi -2); linear damping 2.2 ends genus 1 by the formula
/// but with one non-manifold vertex; linear damping 1.8 does not: the
/// run gains energy and ends shredded (961 particles, 5 pieces). A variant
/// whose balls withdraw after opening the hole (t = 10 to 14) ended genus
/// 1 with one or two small holes at dt 2e-3 and 1.9e-3 but shredded at dt
/// 2.1e-3 and at damping 2.2 (the inner wall sealed across the hole while
/// the balls withdrew, and the stretching rule filled the seal). Before
/// the merging rule and the overfull-edge pass of the triangulation, the
/// withdrawing variant ended with 69 doubled particle pairs (less than 0.2
/// r0 apart), 30 edges in three triangles and chi -3.
#[test]
fn fig_14_final_surface_has_genus_one() {
    println!("claim: {}", claim("fig_14_sphere_to_torus"));
    let o = run_scene("genus");
    let (chi, loops) = (o.end.euler_characteristic(), o.end.boundary_loops() as i64);
    let edges = o.end.edges();
    let boundary = edges.values().filter(|&&c| c == 1).count();
    println!(
        "end: {} triangles, {} edges ({boundary} on the boundary), chi {chi}, {loops} loops, \
         {} pieces",
        o.end.len(),
        edges.len(),
        pieces(&o.end)
    );
    assert_eq!(pieces(&o.end), 1, "one surface");
    assert!(o.end.is_manifold());
    assert!(o.end.is_consistently_oriented());
    assert_eq!(edges.values().filter(|&&c| c > 2).count(), 0);
    assert_eq!(
        2 - chi - loops,
        2,
        "genus (2 - chi - b) / 2 is 1: chi {chi}, {loops} loops"
    );
    assert!(
        50 * boundary <= edges.len(),
        "the holes are small: {boundary} of {} edges on the boundary",
        edges.len()
    );
}
