//! The surface figures of seed 000 (Szeliski & Tonnesen 1992; issue 7,
//! DESIGN §4): welding (fig. 6), cloth draping, plastic deformation and
//! tearing (fig. 12) as scenes (`scenes/fig_06_*.ron`, `scenes/fig_12_*.ron`,
//! `scenes/drape_sphere.ron`) run the way `opsim run` runs them, each with a
//! check of what the figure claims. Durations are the scenes' own unless
//! said otherwise.

mod figure_support;

use oriented_particles::op_dynamics::{Point3, Real, Role, ToolShape, Vec3};
use oriented_particles::op_scene::run::rest_shape_error;
use oriented_particles::op_scene::{BuiltScene, Scene};

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

/// A dented shell's state at one instant: rest shape error (DESIGN §7) and
/// how far its pushed side (the particles within 1 of the +x axis, on the
/// +x side) reaches out from the centre.
#[derive(Clone, Copy, Debug)]
struct Dent {
    error: Real,
    side: Real,
}

fn dent(built: &BuiltScene) -> Dent {
    let x = built.world.particles().positions();
    let c = x.iter().map(|p| p.coords).sum::<Vec3>() / x.len() as Real;
    let side = x
        .iter()
        .map(|p| p.coords - c)
        .filter(|d| d.x > 0.0 && d.y * d.y + d.z * d.z < 1.0)
        .map(|d| d.x)
        .fold(Real::MIN, Real::max);
    Dent {
        error: rest_shape_error(built, &built.objects[0]),
        side,
    }
}

/// One fig. 12b run: the settled state, the state when the finger has
/// come in deepest (t = 2, scene time; it holds until 3), the end state, the largest rest
/// shape error seen (sampled at the frame rate, as `opsim run` does) and
/// the remembered curvatures by id after the settle phase and at the end.
struct DentRun {
    settled: Dent,
    pushed: Dent,
    end: Dent,
    max_error: Real,
    kappa_settled: Vec<Real>,
    kappa_end: Vec<Real>,
    /// Settled positions by id, relative to the centre.
    rest: Vec<Vec3>,
}

fn dent_run(name: &str) -> DentRun {
    let scene = load(name);
    let mut built = build(&scene);
    built.settle().expect("settles");
    let by_id = |b: &BuiltScene| -> Vec<Real> {
        let p = b.world.particles();
        b.objects[0]
            .ids
            .iter()
            .map(|&id| p.curvatures()[p.slot_of(id).expect("alive")])
            .collect()
    };
    let kappa_settled = by_id(&built);
    let x0 = positions(&built, &built.objects[0].ids);
    let c0 = x0.iter().map(|p| p.coords).sum::<Vec3>() / x0.len() as Real;
    let rest = x0.iter().map(|p| p.coords - c0).collect();
    let settled = dent(&built);
    let (t0, frame) = (scene.world.settle, 1.0 / scene.world.frame_rate);
    let frames = (scene.world.duration * scene.world.frame_rate).round() as usize;
    let (mut pushed, mut max_error) = (settled, 0.0 as Real);
    for k in 1..=frames {
        let t = k as Real * frame;
        built.world.advance_to(t0 + t).expect("does not diverge");
        let d = dent(&built);
        max_error = max_error.max(d.error);
        if (t - 2.0).abs() < 1e-9 {
            pushed = d;
        }
    }
    let end = dent(&built);
    println!(
        "{name}: pushed side {:.2} -> {:.2} (t = 2) -> {:.2} above the centre; rest shape \
         error max {max_error:.3}, final {:.3} (ratio {:.2})",
        settled.side,
        pushed.side,
        end.side,
        end.error,
        end.error / max_error
    );
    DentRun {
        settled,
        pushed,
        end,
        max_error,
        kappa_settled,
        kappa_end: by_id(&built),
        rest,
    }
}

/// Fig. 12b: the same shape-memory shell (cohesion + form with rest
/// curvature 1/radius, seed 002) pushed in by the same finger, which then
/// withdraws. With a plastic memory (`scenes/fig_12_plastic.ron`) the dent
/// stays: the side stays in, the final rest shape error is most of its
/// maximum, and the remembered curvature changed where the shell was
/// dented and hardly at all on the far side. Without plasticity
/// (`scenes/fig_12_plastic_memory.ron`) it springs back: the side returns
/// and the final error is a small part of the maximum.
///
/// Measured (ci profile; settled -> finger arrived at t = 2 -> end): plastic
/// side 3.45 -> 2.29 -> 0.23 (the dented cap snaps through while the
/// finger holds and stays inverted), error max 0.71, final 0.71; elastic
/// side 3.47 -> 2.48 -> 3.57, error max 0.33, final 0.13 (ratio 0.39: the
/// surface is back, the particles around the dent rearranged).
/// The worlds are stepped as `opsim run` steps them (frame by frame), with
/// no files written.
#[test]
fn fig_12b_plastic_shell_keeps_its_dent_elastic_shell_springs_back() {
    let plastic = dent_run("fig_12_plastic");
    let memory = dent_run("fig_12_plastic_memory");
    // The same push: both sides were pushed about as deep when the finger
    // reached its deepest point.
    let depth = |r: &DentRun| r.settled.side - r.pushed.side;
    let (dp, dm) = (depth(&plastic), depth(&memory));
    assert!(dp > 0.75 && dm > 0.75, "pushed: {dp} {dm}");
    assert!((dp - dm).abs() < 0.25 * dm.max(dp), "comparable: {dp} {dm}");
    // Plastic: the dent stays (at least as deep as pushed) and most of the
    // deformation remains.
    let kept = plastic.settled.side - plastic.end.side;
    assert!(kept > 0.9 * dp, "plastic dent kept {kept} of {dp}");
    assert!(
        plastic.end.error > 0.7 * plastic.max_error,
        "{} vs {}",
        plastic.end.error,
        plastic.max_error
    );
    // Shape memory: no dent is left (less than a tenth of the push; the
    // side comes back 0.1 proud of where it settled, see above), and most
    // of the error is recovered.
    let left = memory.settled.side - memory.end.side;
    assert!(left < 0.1 * dm, "elastic dent left {left} of {dm}");
    assert!(
        memory.end.error < 0.5 * memory.max_error,
        "{} vs {}",
        memory.end.error,
        memory.max_error
    );
    // The elastic memory never changes; the plastic one changed on the
    // pushed side (x > 2 at rest) and not on the far side (x < -2).
    assert_eq!(memory.kappa_settled, memory.kappa_end);
    let change = |pick: &dyn Fn(&Vec3) -> bool| {
        plastic
            .rest
            .iter()
            .zip(plastic.kappa_settled.iter().zip(&plastic.kappa_end))
            .filter(|(x, _)| pick(x))
            .map(|(_, (a, b))| (b - a).abs())
            .fold(0.0 as Real, Real::max)
    };
    let near = change(&|x| x.x > 2.0);
    let far = change(&|x| x.x < -2.0);
    println!(
        "largest change of the remembered curvature: pushed side {near:.3}, far side {far:.3}"
    );
    // Measured: 0.57 where pushed, 0.006 on the far side (particles there
    // sit near the yield band's edge after settling and creep a little as
    // the whole shell adjusts to the inverted cap).
    assert!(near > 0.1, "{near}");
    assert!(far < 0.05 * near, "far side {far} vs pushed side {near}");
}
