//! The figures of seed 000 (Szeliski & Tonnesen 1992)
//! as scenes (`scenes/fig_*.ron`) run the way `opsim run` runs them, each
//! with a check of what the figure claims rather than only that it ran.
//! Durations are the scenes' own unless said otherwise.

mod figure_support;

use oriented_particles::op_dynamics::{Real, Vec3};
use oriented_particles::op_scene::{BuiltScene, Scene};

use figure_support::*;

/// Fig. 8: a sheet folded a quarter turn with its centre row unoriented
/// creases along that row: both halves stay flat while the fold is sharp.
/// The same fold without the crease (every particle oriented) bends the
/// sheet smoothly, so its halves are curved.
#[test]
fn fig_08_unoriented_row_makes_a_sharp_crease() {
    println!("claim: {}", claim("fig_08_crease"));
    let scene = load("fig_08_crease");
    let mut plain = scene.clone();
    plain.objects[0]
        .overrides
        .retain(|o| o.unoriented != Some(true));
    assert_eq!(plain.objects[0].overrides.len(), 1);
    let measure = |scene: &Scene, tag: &str| {
        let (built, _) = run(scene, tag);
        let ids = &built.objects()[0].ids;
        // Rows 0-3 and 5-8 of the 10 x 9 sheet; row 4 is the crease.
        let (a_normal, a_rms) = plane_fit(&positions(&built, &ids[..40]));
        let (b_normal, b_rms) = plane_fit(&positions(&built, &ids[50..]));
        let dihedral = a_normal.dot(&b_normal).abs().min(1.0).acos().to_degrees();
        (dihedral, a_rms, b_rms)
    };
    let (dihedral, a_rms, b_rms) = measure(&scene, "crease");
    let (plain_dihedral, plain_a, plain_b) = measure(&plain, "plain");
    println!(
        "crease: dihedral {dihedral:.1} deg, planarity rms {a_rms:.4} / {b_rms:.4} r0; \
         without crease: dihedral {plain_dihedral:.1} deg, planarity rms {plain_a:.4} / \
         {plain_b:.4} r0"
    );
    // The mover turns one edge a quarter turn: the halves meet at about
    // 90 degrees along the crease.
    assert!(dihedral > 70.0, "dihedral {dihedral}");
    // Flat halves: within a tenth of the spacing of a plane.
    assert!(a_rms < 0.1 && b_rms < 0.1, "{a_rms} {b_rms}");
    // Without the crease the same fold is spread over the halves.
    assert!(
        plain_a.max(plain_b) > 2.0 * a_rms.max(b_rms),
        "{plain_a} {plain_b} vs {a_rms} {b_rms}"
    );
}

/// Every figure scene (`scenes/fig_*.ron`) states its claim in its header
/// (`// claim: ...`, one sentence a viewer can check on the picture); the
/// figure tests print it next to what they measured.
#[test]
fn every_figure_scene_states_a_claim() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("fig_") && n.ends_with(".ron"))
        .map(|n| n.trim_end_matches(".ron").to_string())
        .collect();
    names.sort();
    assert!(!names.is_empty());
    for n in &names {
        assert!(!claim(n).trim().is_empty(), "{n}");
    }
}

/// Fig. 9: a ball pushing up through a sheet with the stretching rule
/// stretches it until particles are created in the gaps; at the end every
/// particle's nearest neighbour is within `[0.8 r0, d_max]`: no particle
/// pushed into another's Lennard-Jones core, no gap left unfilled. The
/// claim on the exported surface: a disc (one component, one boundary
/// loop, chi 1, manifold) in every frame.
#[test]
fn fig_09_ball_stretches_the_sheet_and_particles_are_created() {
    let scene = load("fig_09_stretching");
    println!("claim: {}", claim("fig_09_stretching"));
    let mut worst = 0.0 as Real;
    let end = each_frame(&scene, |k, built| {
        let t = surface_topology(built, "sheet");
        assert!(t.is_disc(), "frame {k}: {t:?}");
        let mesh = surface_mesh(built, "sheet");
        for f in &mesh.triangles {
            for e in 0..3 {
                let (a, b) = (f[e] as usize, f[(e + 1) % 3] as usize);
                worst = worst.max((mesh.vertices[a] - mesh.vertices[b]).norm());
            }
        }
    });
    let t = surface_topology(&end, "sheet");
    println!(
        "every frame a disc; last frame {t:?} over {} particles; longest surface edge \
         {worst:.3} r0",
        end.world().particles().len()
    );
    let stretching = scene
        .creation
        .as_ref()
        .and_then(|c| c.stretching.clone())
        .expect("the stretching rule is on");
    let (built, summary) = run(&scene, "stretch");
    let initial = built.objects()[0].ids.len();
    let created = built.objects()[0].created.len();
    let p = built.world().particles();
    let points = p.positions();
    let nearest = nearest_distances(points);
    let (lo, hi) = nearest
        .iter()
        .fold((Real::INFINITY, 0.0 as Real), |(a, b), &d| {
            (a.min(d), b.max(d))
        });
    let top = points.iter().map(|x| x.z).fold(Real::MIN, Real::max);
    println!(
        "particles {initial} -> {} ({created} created); nearest-neighbour distance in \
         [{lo:.3}, {hi:.3}] r0, median {:.3}; highest particle z = {top:.2}",
        p.len(),
        median(nearest.clone())
    );
    assert_eq!(summary.objects[0].particles, p.len());
    assert!(created > 0, "no particle created");
    assert_eq!(p.len(), initial + created);
    assert!(top > 3.0, "the ball lifted the sheet to {top}");
    assert!(
        lo >= 0.8 && hi <= stretching.d_max,
        "nearest-neighbour distances [{lo}, {hi}] outside [0.8, {}]",
        stretching.d_max
    );
}

/// Fig. 15: the spin torque (seed 000 eq. 15) turns the local x axes to
/// the direction of smallest absolute curvature: along the axis of a
/// cylinder, along the meridians of a prolate spheroid. Particles near the
/// cylinder's open ends and near the spheroid's umbilic poles are not
/// counted. Returns the median angles before and after (degrees).
fn spin_alignment(name: &str, axis: Vec3, keep_within: Real) -> (Real, Real) {
    let scene = load(name);
    let axis = axis.normalize();
    let angles = |built: &BuiltScene| {
        let p = built.world().particles();
        let a = p.attributes();
        (0..p.len())
            .filter(|&s| p.positions()[s].coords.dot(&axis).abs() < keep_within)
            .map(|s| {
                let n = p.normal(s);
                let x = p.orientations()[s] * a.tangent_axes[s];
                // Smallest absolute curvature: the axis direction projected
                // on the tangent plane (the meridian of a surface of
                // revolution, the ruling of a cylinder).
                let d = (axis - n * n.dot(&axis)).normalize();
                x.dot(&d).abs().min(1.0).acos().to_degrees()
            })
            .collect::<Vec<_>>()
    };
    let before = angles(&build(&scene));
    let (built, _) = run(&scene, "spin");
    let after = angles(&built);
    assert_eq!(before.len(), after.len());
    let within = after.iter().filter(|&&a| a <= 10.0).count();
    let (m0, m1) = (median(before), median(after.clone()));
    println!(
        "{name}: {} particles counted, median angle to the min-|curvature| direction \
         {m0:.1} -> {m1:.1} deg, {within} within 10 deg, max {:.1} deg",
        after.len(),
        after.iter().copied().fold(0.0, Real::max)
    );
    (m0, m1)
}

#[test]
fn fig_15_spin_aligns_x_with_the_cylinder_axis() {
    println!("claim: {}", claim("fig_15_spin_cylinder"));
    let (before, after) = spin_alignment("fig_15_spin_cylinder", Vec3::new(0.3, 0.5, 1.0), 4.0);
    assert!(before > 10.0, "the frames start misaligned ({before} deg)");
    assert!(after <= 10.0, "median {after} deg");
}

#[test]
fn fig_15_spin_aligns_x_with_the_spheroid_meridians() {
    println!("claim: {}", claim("fig_15_spin_spheroid"));
    let (before, after) = spin_alignment("fig_15_spin_spheroid", Vec3::new(-0.4, 0.2, 1.0), 4.5);
    assert!(before > 10.0, "the frames start misaligned ({before} deg)");
    assert!(after <= 10.0, "median {after} deg");
}

/// Fig. 7: an eraser swept across a sheet cuts it into two pieces, one on
/// each side of the cut, and removes only the particles on its path.
#[test]
fn fig_07_eraser_cuts_the_sheet_in_two() {
    println!("claim: {}", claim("fig_07_cut"));
    let scene = load("fig_07_cut");
    // The slab's half width across the cut.
    let half_width = 0.9;
    let in_path = {
        let built = build(&scene);
        let p = built.world().particles();
        let mut ids: Vec<u32> = (0..p.len())
            .filter(|&s| p.positions()[s].x.abs() < half_width)
            .map(|s| p.ids()[s])
            .collect();
        ids.sort_unstable();
        ids
    };
    let (built, summary) = run(&scene, "cut");
    let p = built.world().particles();
    let n0 = built.objects()[0].ids.len();
    let points = p.positions().to_vec();
    let sizes = components(&points, 1.5);
    let left = points.iter().filter(|x| x.x < 0.0).count();
    println!(
        "particles {n0} -> {} ({} erased); components of the 1.5 r0 neighbour graph {sizes:?}; \
         {left} left of the cut",
        p.len(),
        n0 - p.len()
    );
    assert_eq!(summary.objects[0].particles, p.len());
    assert!(built.world().enabled().contains(&"tool:eraser".to_string()));
    // Exactly the particles that started on the slab's path are gone.
    let mut erased: Vec<u32> = built.objects()[0]
        .ids
        .iter()
        .copied()
        .filter(|&id| p.slot_of(id).is_none())
        .collect();
    erased.sort_unstable();
    assert_eq!(erased, in_path);
    assert_eq!(sizes.len(), 2, "{sizes:?}");
    assert_eq!(sizes, vec![left, p.len() - left]);
}

/// Fig. 5: two chains hanging from fixed ends swing under gravity and link
/// into one: their free ends end as neighbours and every particle is
/// connected to every other through neighbours (1.5 r0, the cut-off).
#[test]
fn fig_05_two_swinging_chains_link_into_one() {
    println!("claim: {}", claim("fig_05_chain_linking"));
    let scene = load("fig_05_chain_linking");
    let start = build(&scene);
    let x0 = positions(&start, &start.objects()[0].ids);
    assert_eq!(
        components(&x0, 1.5).len(),
        2,
        "two separate chains at first"
    );
    let (built, _) = run(&scene, "chains");
    let ids = &built.objects()[0].ids;
    let x = positions(&built, ids);
    // Free ends: the last particle of each chain.
    let ends = (x[7] - x[15]).norm();
    let sizes = components(&x, 1.5);
    let lowest = x.iter().map(|p| p.z).fold(Real::INFINITY, Real::min);
    println!("free ends {ends:.3} r0 apart; components {sizes:?}; lowest z {lowest:.2}");
    assert!(ends < 1.5, "free ends {ends} apart");
    assert_eq!(sizes, vec![ids.len()]);
    // It hangs (a trapeze below the anchors), not a straight bar.
    assert!(lowest < -2.0, "lowest particle at z = {lowest}");
}
