//! The heat figures of seed 000 (Szeliski & Tonnesen 1992, §6 and §8;
//! issue 7): cutting with a hot knife (fig. 7) and forming a handle by
//! heating the surface near the tool (fig. 13), as scenes
//! (`scenes/fig_07_knife.ron`, `scenes/fig_13_handle.ron`) run the way
//! `opsim run` runs them, each checked against what the figure claims.

mod figure_support;

use oriented_particles::op_dynamics::{Real, Role};
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
    let p = built.world.particles();
    let points = p.positions().to_vec();
    let sizes = components(&points, 1.5);
    let below = points.iter().filter(|x| x.y < 0.0).count();
    let hottest = p.temperatures().iter().copied().fold(Real::MIN, Real::max);
    let lowest = points.iter().map(|x| x.z).fold(Real::INFINITY, Real::min);
    println!(
        "hot knife: components {sizes:?} ({below} on the y < 0 side), hottest {hottest:.2}, \
         lowest z {lowest:.2}"
    );
    assert!(built.world.enabled().contains(&"tool:knife".to_string()));
    assert_eq!(summary.objects[0].particles, p.len());
    assert_eq!(sizes.len(), 2, "{sizes:?}");
    assert_eq!(sizes, vec![below, p.len() - below]);
    assert!(hottest > 1.0, "the knife heated nothing: {hottest}");

    let (built, _) = run(&cold_knife(&scene), "cold");
    let points = built.world.particles().positions().to_vec();
    let sizes = components(&points, 1.5);
    let lowest = points.iter().map(|x| x.z).fold(Real::INFINITY, Real::min);
    println!("cold blade: components {sizes:?}, lowest z {lowest:.2}");
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
/// Not reproduced (see the closing note of issue 7): the paper's contrast,
/// "without this modification, the extruded part of the surface has a
/// tendency to pinch off": the same pull without heat (stretching
/// everywhere, no weakening) also extrudes a stem in one piece here; and
/// the handle of fig. 13 (Euler characteristic 2 -> 0: the stem looped
/// over and joined to the body) is not built.
#[test]
fn fig_13_hot_tool_extrudes_a_stem() {
    use oriented_particles::op_dynamics::triangulation::{triangulate, TriangulationParams};
    let scene = load("fig_13_stem");
    let (built, summary) = run(&scene, "stem");
    let p = built.world.particles();
    let points = p.positions().to_vec();
    let sizes = components(&points, 1.5);
    let t = triangulate(p, &TriangulationParams::from_spacing(1.0, 1.7)).unwrap();
    let top = points.iter().map(|x| x.z).fold(Real::MIN, Real::max);
    let created: Vec<usize> = built.objects[0]
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
        built.objects[0].ids.len(),
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
