//! Seed 000 §8, fig. 14 (issue 7): a sphere pushed in at both poles by two
//! spherical shaping tools becomes a torus; "new particles are created
//! inside the torus due to stretching during the formation process, and
//! some old sphere particles are deleted when trapped between the two
//! shaping tools". The scene `scenes/fig_14_sphere_to_torus.ron` is run the
//! way `opsim run` runs it; the triangulation is the one its frames hold
//! (seed 000 §5, `op_dynamics::triangulation`, radius 1.7 times the
//! object's measured rest spacing, 0.88 for this Fibonacci sphere).

mod figure_support;

use oriented_particles::op_dynamics::triangulation::{
    triangulate, Triangulation, TriangulationParams,
};
use oriented_particles::op_dynamics::Real;
use oriented_particles::op_scene::BuiltScene;

use figure_support::*;

/// The triangulation of the scene's (single) object, as its frames hold it.
fn surface(built: &BuiltScene) -> Triangulation {
    let radius = built.outputs.triangulation_radius * built.objects[0].rest_spacing;
    triangulate(
        built.world.particles(),
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
    /// Particles deleted by the trap rule (original or created).
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
    let object = &built.objects[0];
    let p = built.world.particles();
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

/// Fig. 14, what the run reaches: it starts from a closed sphere (Euler
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

/// Fig. 14, the topology the paper shows: the final triangulation is a
/// closed torus (Euler characteristic 0, no boundary loop, manifold).
///
/// **Not reached** (ignored). Measured with the committed scene (16 s;
/// `cargo test --profile ci --test figures_torus -- --ignored --nocapture`),
/// since stretching skips pairs with normals more than 90 degrees apart:
/// 363 particles at the start (chi 2); at the end 380 particles (27
/// created, 10 deleted), a hole of radius 2.20 r0, chi 0 but 4 boundary
/// loops and a non-manifold triangulation; without the creation cap the
/// run ends at 496 particles (148 created, 15 deleted), chi -14, 11 loops.
/// Before that rule: 380 particles (18 created, 1 deleted), a hole of
/// radius 3.02 r0, chi 0 but 6 boundary loops and 3 edges in three
/// triangles. The chi of 0 is a coincidence of
/// the holes: over the last frames (t = 10 to 16) it wanders from -3 to
/// 2, with 3 to 6 loops. About 25 boundary edges lie at the neck
/// (distance 3 from the axis, |z| <= 1: the inner wall is not closed all
/// round) and about 200 on the shoulders where the shell wraps the balls
/// (distance 4-6, |z| 2-4: holes in the stretched shell that the capped
/// creation rule did not fill). The shell has not come to rest at t = 16
/// (kinetic energy 11.6, largest speed 3.2 r0/s).
///
/// Variants tried, final (chi, boundary loops). With co-circularity 10:
/// run to t = 24 (2, 5); tools withdrawn after the hole opened (-1, 6);
/// creation cap 400 (5, 4); co-circularity 20 (1, 7). With co-circularity
/// 5 (27 non-manifold edges in the scene's run, (4, 8)): tools withdrawn
/// (9, 6), (3, 5), (2, 11), (5, 6); no creation at all (-2, 5; and no
/// particle created, against the paper); creation cap 420 with a
/// triangulation radius of 2.1 rest spacings (-18, 11); stretching window
/// 1.7-2.2 r0 (-25, 7); triangulation radius 1.9 or 2.2 (6, 8), (-50, 17);
/// more damping (38, 26); a sphere of radius 6 (64, 20), (83, 15: the
/// extra material folds); no creation cap (34, 43; balls of radius 2.5:
/// 42, 99), where the stretching rule fills the space between the two
/// approaching dimples and the run gains energy without bound (see the
/// scene's comment).
#[test]
#[ignore = "not reached: boundary loops and non-manifold edges remain (see the doc comment)"]
fn fig_14_final_surface_is_a_closed_torus() {
    let o = run_scene("closed");
    assert_eq!(o.end.euler_characteristic(), 0);
    assert_eq!(o.end.boundary_loops(), 0);
    assert!(o.end.is_manifold());
}
