//! The surface figures of seed 000 (Szeliski & Tonnesen 1992; issue 7,
//! DESIGN §4): welding (fig. 6), cloth draping, plastic deformation and
//! tearing (fig. 12) as scenes (`scenes/fig_06_*.ron`, `scenes/fig_12_*.ron`,
//! `scenes/drape_sphere.ron`) run the way `opsim run` runs them, each with a
//! check of what the figure claims. Durations are the scenes' own unless
//! said otherwise.

mod figure_support;

use oriented_particles::op_dynamics::{Point3, Real, Role, ToolShape};
use oriented_particles::op_scene::Scene;

use figure_support::*;

/// The tearing scene with each hand carried `pull` units outward (the
/// scene's own pull is 6).
fn pulled(scene: &Scene, pull: Real) -> Scene {
    let mut s = scene.clone();
    for tool in &mut s.tools {
        let start = tool.path.keyframes[0].position[0];
        let end = &mut tool.path.keyframes[1].position[0];
        *end = start + start.signum() * pull;
    }
    s
}

/// Fig. 12c: a sheet pulled apart by two movers beyond the Lennard-Jones
/// cut-off tears into two (or more) pieces (components of the neighbour
/// graph within the cut-off, 1.5 r0), while a small pull only stretches it
/// elastically (one component). Prints the smallest pull of a sweep at
/// which it tore.
#[test]
fn fig_12c_pulled_sheet_tears_beyond_the_cutoff() {
    let scene = load("fig_12_tearing");
    let cutoff = 1.5;
    // Distance between the two hands at the start (tool centres).
    let span = {
        let k = |i: usize| scene.tools[i].path.keyframes[0].position[0];
        (k(1) - k(0)).abs()
    };
    let pieces = |scene: &Scene, tag: &str| {
        let (built, _) = run(scene, tag);
        let p = built.world.particles();
        assert_eq!(p.len(), built.objects[0].ids.len(), "no particle lost");
        let widest = nearest_distances(p.positions())
            .into_iter()
            .fold(0.0, Real::max);
        println!("{tag}: largest nearest-neighbour distance {widest:.3} r0");
        components(p.positions(), cutoff)
    };
    let torn = pieces(&scene, "torn");
    let elastic = pieces(&pulled(&scene, 0.5), "elastic");
    println!(
        "pull 6 per side (strain {:.2}): components {torn:?}; pull 0.5 per side (strain \
         {:.2}): components {elastic:?}",
        12.0 / span,
        1.0 / span
    );
    assert!(torn.len() >= 2, "not torn: {torn:?}");
    // Both pieces are real pieces of sheet, not a few particles pulled off.
    assert!(torn[1] >= 6, "{torn:?}");
    assert_eq!(elastic.len(), 1, "a small pull tore the sheet: {elastic:?}");
    // Where between the two it tears (reported, not asserted).
    let mut tore_at = None;
    for pull in [1.0, 2.0, 3.0, 4.0, 5.0] {
        let sizes = pieces(&pulled(&scene, pull), &format!("sweep{pull}"));
        println!(
            "pull {pull} per side (strain {:.2}): components {sizes:?}",
            2.0 * pull / span
        );
        if sizes.len() >= 2 && tore_at.is_none() {
            tore_at = Some(pull);
        }
    }
    match tore_at {
        Some(pull) => println!(
            "tears at a pull of {pull} per side of the sweep 0.5, 1, 2, 3, 4, 5, 6 (strain {:.2})",
            2.0 * pull / span
        ),
        None => println!("tears between a pull of 5 and 6 per side"),
    }
}

/// Fig. 6: two sheets of one object carried edge to edge by movers weld
/// into one seamless surface: one component of the neighbour graph within
/// the cut-off (1.5 r0) and every nearest-neighbour distance, across the
/// seam too, within 10% of r0.
#[test]
fn fig_06_two_sheets_weld_into_one() {
    let scene = load("fig_06_weld");
    let start = build(&scene);
    let x0 = start.world.particles().positions().to_vec();
    assert_eq!(components(&x0, 1.5), vec![36, 36], "two sheets at first");
    let (built, _) = run(&scene, "weld");
    let p = built.world.particles();
    let x = p.positions();
    let sizes = components(x, 1.5);
    let nearest = nearest_distances(x);
    let (lo, hi) = nearest
        .iter()
        .fold((Real::INFINITY, 0.0 as Real), |(a, b), &d| {
            (a.min(d), b.max(d))
        });
    // The seam: the facing edge columns (the last of the left sheet, the
    // first of the right one).
    let seam: Vec<Real> = (0..6)
        .flat_map(|row| [row * 6 + 5, 36 + row * 6])
        .map(|i| nearest[i])
        .collect();
    let (seam_lo, seam_hi) = seam
        .iter()
        .fold((Real::INFINITY, 0.0 as Real), |(a, b), &d| {
            (a.min(d), b.max(d))
        });
    let gap = (0..6)
        .map(|row| (x[36 + row * 6] - x[row * 6 + 5]).norm())
        .fold(0.0, Real::max);
    println!(
        "components {sizes:?}; nearest-neighbour distance in [{lo:.3}, {hi:.3}] r0; at the \
         seam in [{seam_lo:.3}, {seam_hi:.3}]; widest edge-to-edge pair across it {gap:.3}"
    );
    assert_eq!(sizes, vec![72]);
    assert!(lo >= 0.9 && hi <= 1.1, "[{lo}, {hi}]");
}

/// Fig. 12a (`scenes/drape_sphere.ron`): a cloth dropped on a sphere rests
/// on it and hangs down around it. At the end no particle is inside the
/// sphere grown by the contact margin (beyond a small penalty depth), the
/// highest particles rest at about radius + margin above the centre, and
/// the lowest hang below the sphere's equator.
///
/// Not reproduced by the scene as it stands: at t = 12 the cloth hangs
/// around the sphere (lowest particle 2.5 below the centre) but is not at
/// rest (fastest particle at speed 6), particles bunch up above the top of
/// the sphere (highest 6.3 above the centre, contact radius 4.5; 7.7 at
/// t = 30) and some are pushed 0.2 into the contact margin. The energy
/// record (`outputs.metrics`) shows why: from t = 6 the potential falls
/// (-11210 to -14090 at t = 12) and the kinetic energy rises (79 to 1628)
/// while the total falls: where the cloth folds over the sphere, layers of
/// the same object come within the cut-off and bind (isotropic weight,
/// `K = 1`), so the cloth condenses into a clump on top instead of
/// draping. Halving `dt` changes nothing (not a step-size instability).
/// Ignored until the scene is revised; run it with `--ignored` to see the
/// numbers.
#[test]
#[ignore = "scenes/drape_sphere.ron does not settle on the sphere (see the doc comment)"]
fn fig_12a_cloth_drapes_over_the_sphere() {
    let scene = load("drape_sphere");
    let (radius, margin) = match (&scene.tools[0].shape, &scene.tools[0].role) {
        (ToolShape::Ball { radius }, Role::Obstacle { margin, .. }) => (*radius, *margin),
        other => panic!("the sphere is a ball obstacle: {other:?}"),
    };
    let centre = Point3::from(
        scene.tools[0]
            .path
            .keyframes
            .first()
            .map_or([0.0; 3], |k| k.position),
    );
    let (built, _) = run(&scene, "drape");
    let x = built.world.particles().positions();
    let closest = x
        .iter()
        .map(|p| (p - centre).norm())
        .fold(Real::INFINITY, Real::min);
    let top = x.iter().map(|p| p.z - centre.z).fold(Real::MIN, Real::max);
    let lowest = x
        .iter()
        .map(|p| p.z - centre.z)
        .fold(Real::INFINITY, Real::min);
    println!(
        "contact radius {:.2}: closest particle {closest:.3} from the centre; highest {top:.3}, \
         lowest {lowest:.3} above it",
        radius + margin
    );
    // Resting on the sphere: a penalty contact lets particles in by
    // load / stiffness only.
    assert!(closest > radius + margin - 0.1, "{closest}");
    assert!((top - (radius + margin)).abs() < 0.1, "{top}");
    // Hanging around it, not lying flat on top.
    assert!(lowest < 0.0, "{lowest}");
}

/// Fig. 12b: a shell without shape memory (Lennard-Jones + co-planarity)
/// dented by a mover that then lets go keeps the dent: its rest shape
/// error at the end is close to its maximum. The same dent in a
/// shape-memory shell (cohesion + form with rest curvature 1/radius, seed
/// 002) springs back: its final error is a small part of its maximum.
///
/// Not reproduced by these scenes: the Lennard-Jones shell keeps its dent
/// (rest shape error max 0.433, final 0.356 after the settle phase), but
/// so does the shape-memory shell (max 0.714, final 0.702; the pushed cap
/// stays inverted, at rest, top particle at z = 0.96 instead of 3.84).
/// A shallower push (1 unit instead of 3, not in the scene) gave a partial
/// recovery of the memory shell (0.269 -> 0.153). The Lennard-Jones shell
/// also crumples during the settle phase (distances to the centre from
/// 1.2 to 4.6): co-planarity and Lennard-Jones do not hold a sphere.
/// Ignored until the scenes are revised; run it with `--ignored`.
#[test]
#[ignore = "the shape-memory shell keeps the dent too (see the doc comment)"]
fn fig_12b_shell_without_memory_keeps_its_dent() {
    let error = |name: &str| {
        let (built, summary) = run(&load(name), "dent");
        let o = &summary.objects[0];
        assert_eq!(built.world.particles().len(), built.objects[0].ids.len());
        println!(
            "{name}: rest shape error max {:.3}, final {:.3} (ratio {:.2})",
            o.rest_shape_error_max,
            o.rest_shape_error_final,
            o.rest_shape_error_final / o.rest_shape_error_max
        );
        (o.rest_shape_error_max, o.rest_shape_error_final)
    };
    let (plastic_max, plastic_end) = error("fig_12_plastic");
    let (memory_max, memory_end) = error("fig_12_plastic_memory");
    // Both were dented comparably (the same push).
    assert!(
        plastic_max > 0.1 && memory_max > 0.1,
        "{plastic_max} {memory_max}"
    );
    // Plastic: most of the deformation stays.
    assert!(
        plastic_end > 0.7 * plastic_max,
        "{plastic_end} vs {plastic_max}"
    );
    // Shape memory: most of it is recovered.
    assert!(
        memory_end < 0.25 * memory_max,
        "{memory_end} vs {memory_max}"
    );
}
