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
