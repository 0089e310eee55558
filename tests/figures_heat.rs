//! The heat figures of seed 000 (Szeliski & Tonnesen 1992, §6 and §8):
//! cutting with a hot knife (fig. 7) and forming a handle by
//! heating the surface near the tool (fig. 13), as scenes
//! (`scenes/fig_07_knife.ron`, `scenes/fig_13_handle.ron`) run the way
//! `opsim run` runs them, each checked against what the figure claims.

mod figure_support;

use oriented_particles::op_dynamics::Real;
use oriented_particles::op_modeling::Role;
use oriented_particles::op_scene::Scene;

use figure_support::*;

/// The knife scene with a cold blade: the same obstacle without heating,
/// and a material that does not weaken.
fn cold_knife(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for m in s.materials.values_mut() {
        m.heat = None;
    }
    for t in &mut s.tools {
        if let Role::Knife {
            stiffness,
            margin,
            damping,
            ..
        } = t.role
        {
            t.role = Role::Obstacle {
                stiffness,
                margin,
                damping,
                friction: 0.0,
            };
        }
    }
    s
}

/// Fig. 7 with heat: the hot knife coming down through the held sheet cuts
/// it in two halves (components of the neighbour graph within the
/// Lennard-Jones cut-off, 1.5 r0), one on each side of the blade, and
/// heated the particles along the cut; the same blade cold pushes the sheet
/// into a V and leaves it whole.
#[test]
fn fig_07_hot_knife_cuts_the_sheet_in_two() {
    let scene = load("fig_07_knife");
    let (built, summary) = run(&scene, "hot");
    let p = built.world().particles();
    let points = p.positions().to_vec();
    let sizes = components(&points, 1.5);
    let below = points.iter().filter(|x| x.y < 0.0).count();
    let hottest = p.temperatures().iter().copied().fold(Real::MIN, Real::max);
    let lowest = points.iter().map(|x| x.z).fold(Real::INFINITY, Real::min);
    println!(
        "hot knife: components {sizes:?} ({below} on the y < 0 side), hottest {hottest:.2}, \
         lowest z {lowest:.2}"
    );
    assert!(built.world().enabled().contains(&"tool:knife".to_string()));
    assert_eq!(summary.objects[0].particles, p.len());
    assert_eq!(sizes.len(), 2, "{sizes:?}");
    assert_eq!(sizes, vec![below, p.len() - below]);
    assert!(hottest > 1.0, "the knife heated nothing: {hottest}");
    // The claim on the exported surface: two discs, no triangle across the
    // slit (every edge's two ends on one side of the blade, y = 0).
    println!("claim: {}", claim("fig_07_knife"));
    let t = surface_topology(&built, "sheet");
    let mesh = surface_mesh(&built, "sheet");
    let across = mesh
        .triangles
        .iter()
        .filter(|f| {
            let ys = f.map(|v| mesh.vertices[v as usize].y);
            ys.iter().any(|&y| y < 0.0) && ys.iter().any(|&y| y > 0.0)
        })
        .count();
    println!("hot knife: last frame surface {t:?}, {across} triangles across y = 0");
    assert!(t.is_discs(2), "{t:?}");
    assert_eq!(across, 0);

    let (built, _) = run(&cold_knife(&scene), "cold");
    let points = built.world().particles().positions().to_vec();
    let sizes = components(&points, 1.5);
    let lowest = points.iter().map(|x| x.z).fold(Real::INFINITY, Real::min);
    let t = surface_topology(&built, "sheet");
    // Printed only: the cold blade stretches the sheet over its edge beyond
    // the cut-off, so the surface is one piece with holes along the blade.
    println!("cold blade: components {sizes:?}, lowest z {lowest:.2}, surface {t:?}");
    assert_eq!(sizes.len(), 1, "the cold blade cut the sheet: {sizes:?}");
    assert!(
        lowest < -1.0,
        "the cold blade did not push the sheet: {lowest}"
    );
}

/// Fig. 13, first stage (the stem): a hot tool pulls a stem out of a
/// sphere. Only the hot part stretches: every created particle lies along
/// the tool's path (above the sphere's equator, z > 3), the body below the
/// equator stays colder than the stretching threshold, and the surface
/// stays one closed piece (one component; its triangulation a manifold
/// without boundary of Euler characteristic 2, a sphere still) with its tip
/// where the tool took it.
///
/// Not reproduced: the paper's contrast,
/// "without this modification, the extruded part of the surface has a
/// tendency to pinch off": the same pull without heat (stretching
/// everywhere, no weakening) also extrudes a stem in one piece here. The
/// handle that follows is `fig_13_stem_looped_onto_the_body_makes_a_handle`.
#[test]
fn fig_13_hot_tool_extrudes_a_stem() {
    println!("claim: {}", claim("fig_13_stem"));
    use oriented_particles::op_modeling::triangulation::{triangulate, TriangulationParams};
    let scene = load("fig_13_stem");
    let (built, summary) = run(&scene, "stem");
    let p = built.world().particles();
    let points = p.positions().to_vec();
    let sizes = components(&points, 1.5);
    let t = triangulate(p, &TriangulationParams::from_spacing(1.0, 1.7)).unwrap();
    let top = points.iter().map(|x| x.z).fold(Real::MIN, Real::max);
    let created: Vec<usize> = built.objects()[0]
        .created
        .iter()
        .filter_map(|&id| p.slot_of(id))
        .collect();
    let lowest_created = created
        .iter()
        .map(|&s| points[s].z)
        .fold(Real::INFINITY, Real::min);
    let body_hottest = (0..p.len())
        .filter(|&s| points[s].z < 0.0)
        .map(|s| p.temperatures()[s])
        .fold(Real::MIN, Real::max);
    println!(
        "stem: particles {} -> {} ({} created, lowest at z {lowest_created:.2}), components \
         {sizes:?}, chi {}, boundary loops {}, tip z {top:.2}, body below the equator at most \
         {body_hottest:.3} hot, hottest {:?}",
        built.objects()[0].ids.len(),
        p.len(),
        created.len(),
        t.euler_characteristic(),
        t.boundary_loops(),
        summary.objects[0].temperature_max
    );
    assert!(created.len() > 50, "{} created", created.len());
    assert!(lowest_created > 3.0, "created at z {lowest_created}");
    assert!(body_hottest < 1.0, "the body got hot: {body_hottest}");
    assert_eq!(sizes.len(), 1, "{sizes:?}");
    assert_eq!(t.boundary_loops(), 0);
    assert_eq!(t.euler_characteristic(), 2, "still a sphere");
    assert!(t.is_manifold());
    assert!(top > 9.0, "tip at {top}");
}

/// How many triangles of `t` (over the particles of `built`) the segment
/// from `a` to `b` crosses (Möller–Trumbore).
fn crossings(
    built: &oriented_particles::op_scene::BuiltScene,
    t: &oriented_particles::op_modeling::triangulation::Triangulation,
    a: oriented_particles::op_dynamics::Point3,
    b: oriented_particles::op_dynamics::Point3,
) -> usize {
    let p = built.world().particles();
    let at = |id: u32| p.positions()[p.slot_of(id).expect("live")];
    let d = b - a;
    t.triangles
        .iter()
        .filter(|tri| {
            let (p0, p1, p2) = (at(tri[0]), at(tri[1]), at(tri[2]));
            let (e1, e2) = (p1 - p0, p2 - p0);
            let h = d.cross(&e2);
            let det = e1.dot(&h);
            if det.abs() < 1e-12 {
                return false;
            }
            let s = a - p0;
            let u = s.dot(&h) / det;
            let q = s.cross(&e1);
            let v = d.dot(&q) / det;
            let along = e2.dot(&q) / det;
            (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&along)
        })
        .count()
}

/// The triangulation the frames of `built` hold (radius 1.7 rest spacings).
fn frames_surface(
    built: &oriented_particles::op_scene::BuiltScene,
) -> oriented_particles::op_modeling::triangulation::Triangulation {
    use oriented_particles::op_modeling::triangulation::{triangulate, TriangulationParams};
    let radius = built.outputs().triangulation_radius * built.objects()[0].rest_spacing;
    triangulate(
        built.world().particles(),
        &TriangulationParams::with_radius(radius),
    )
    .unwrap()
}

/// Fig. 13, the handle: the hot stem is looped over onto the sphere's
/// shoulder and its end opens into the body (`scenes/fig_13_handle.ron`).
/// Checked:
/// - at the start a closed sphere (chi 2);
/// - when the stem's cap rests on the shoulder (t = 17), the segment from
///   the sphere's centre to the centre of the tool inside the stem's end
///   crosses two walls (the sphere's and the cap);
/// - at the end it crosses none: the stem's inside and the body's inside
///   are one, through the neck where the two rims joined;
/// - the final triangulation is one manifold piece whose genus
///   `(2 - chi - b) / 2` (`b` boundary loops) is 1, and whose boundary is
///   only small holes (at most 2% of its edges, as for fig. 14);
/// - the exported surface of the last frame (`ball_surface`, only what
///   holds together, `op_scene::export::geometry::surface_geometry`) is
///   closed: one manifold piece, no boundary, chi 0 (808 particles, 1616
///   triangles; chi -1 with one 3-edge hole before the stretching rule's
///   filled gaps counted as sheet, `SheetGap`).
///
/// Measured (`cargo test --profile ci --test figures_heat -- --nocapture`):
/// 363 -> 809 particles; at t = 28 the triangulation (radius 1.8 rest
/// spacings, the scene's) is closed: chi 0, no boundary, manifold, one
/// piece, the Euler characteristic changed 2 -> 0. With radius 1.7
/// two holes of 4 and 5 vertices stay (chi -2, still genus 1). Frames
/// every second from t = 22: 3 vertices of the neck not manifold (two
/// fans) at t = 22 and 1 at t = 25 while the neck settles after the hand
/// lets go; the other frames genus 1 with at most two small holes; closed
/// at t = 28.
/// Neighbours of the scene's parameters (edited copies, final frame; the
/// segment is open in all): dt 1.9e-3 genus 1 with 2 holes, dt 2.1e-3
/// genus 1 with 3, linear damping 1.1 genus 1 with 2, damping 0.9 has two
/// non-manifold vertices at the neck. The test asserts the genus, which
/// tolerates small holes, rather than chi 0. With the cap only squeezed
/// against the wall (no tools inside), one wall opened at a time,
/// stretching mended each opening, and the rims stayed 1.6 to 4.9 apart.
#[test]
fn fig_13_stem_looped_onto_the_body_makes_a_handle() {
    println!("claim: {}", claim("fig_13_handle"));
    use oriented_particles::op_dynamics::Point3;
    let scene = load("fig_13_handle");
    let start = frames_surface(&build(&scene));
    assert_eq!(start.euler_characteristic(), 2);
    assert_eq!(start.boundary_loops(), 0);

    let inside_tip = |built: &oriented_particles::op_scene::BuiltScene| {
        let tool = oriented_particles::op_modeling::Tools::of(built.world())
            .expect("the world's tools")
            .tools()
            .iter()
            .find(|t| t.params().name == "tip")
            .expect("a tool named tip");
        Point3::from(tool.pose(built.world().time()).position)
    };
    let mut touch = scene.clone();
    touch.world.duration = 17.0;
    let (built, _) = run(&touch, "touch");
    let walls = crossings(
        &built,
        &frames_surface(&built),
        Point3::origin(),
        inside_tip(&built),
    );
    println!("t = 17: the segment to the stem's end crosses {walls} walls");
    assert_eq!(walls, 2, "cap and sphere wall");

    let (built, _) = run(&scene, "handle");
    let end = frames_surface(&built);
    let open = crossings(&built, &end, Point3::origin(), inside_tip(&built));
    let (chi, loops) = (end.euler_characteristic(), end.boundary_loops() as i64);
    let edges = end.edges();
    let boundary = edges.values().filter(|&&c| c == 1).count();
    println!(
        "end: {} particles, chi {chi}, {loops} boundary loops ({boundary} of {} edges), \
         manifold {}, segment crossings {open}",
        built.world().particles().len(),
        edges.len(),
        end.is_manifold()
    );
    assert_eq!(open, 0, "the stem's end did not open into the body");
    assert!(end.is_manifold());
    assert_eq!(2 - chi - loops, 2, "genus 1: chi {chi}, {loops} loops");
    assert!(
        50 * boundary <= edges.len(),
        "the holes are small: {boundary} of {} edges on the boundary",
        edges.len()
    );
    let p = built.world().particles();
    let pieces = components(p.positions(), 1.5);
    assert_eq!(pieces.len(), 1, "{pieces:?}");
    // The claim on the exported surface (the frames' `ball_surface`, only
    // what holds together): one closed piece of genus 1.
    let exported = surface_topology(&built, "ball");
    println!("exported surface at the end: {exported:?}");
    assert!(exported.manifold, "{exported:?}");
    assert_eq!(exported.components, 1, "{exported:?}");
    assert_eq!(exported.loops, 0, "closed: {exported:?}");
    assert_eq!(exported.chi, 0, "genus 1: {exported:?}");
}
