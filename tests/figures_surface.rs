//! The surface figures of seed 000 (Szeliski & Tonnesen 1992;
//! seed 000 §6-8): welding (fig. 6), cloth draping, plastic deformation and
//! tearing (fig. 12) as scenes (`scenes/fig_06_*.ron`, `scenes/fig_12_*.ron`)
//! run the way `opsim run` runs them, each with a check of what the figure
//! claims. Durations are the scenes' own unless
//! said otherwise.

mod figure_support;

use oriented_particles::op_dynamics::diagnostics::kinematic;
use oriented_particles::op_dynamics::{Point3, Real, Vec3};
use oriented_particles::op_modeling::{Role, ToolShape};
use oriented_particles::op_scene::run::rest_shape_error;
use oriented_particles::op_scene::{BuiltScene, Scene};

use figure_support::*;

/// The tearing scene with each hand (its movers) carried `pull` units
/// outward (the scene's own pull is 6).
fn pulled(scene: &Scene, pull: Real) -> Scene {
    let mut s = scene.clone();
    for tool in &mut s.tools {
        if !matches!(tool.role, Role::Mover { .. }) {
            continue;
        }
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
        let p = built.world().particles();
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

/// The claim of the tearing scenes (seed 000 fig. 12c), on the exported
/// surface of every frame: one disc until the tear, then two discs to the
/// end, never anything else (no free piece, no hole, no flap), except while
/// the tear runs across: the frames just before the split may show one
/// piece that is not a disc (the opening crack, pinched where the last
/// particles hold), at most [`TEARING_FRAMES`] of them. At the end the two
/// discs are one in each hand (no piece crosses x = 0, each at least a
/// third of the sheet). Returns the first frame in two pieces.
fn assert_one_tear(name: &str) -> usize {
    println!("claim: {}", claim(name));
    let scene = load(name);
    let mut torn_at = None;
    let mut tearing = Vec::new();
    let built = each_frame(&scene, |k, built| {
        let t = surface_topology(built, "sheet");
        if torn_at.is_none() && t.is_discs(2) {
            torn_at = Some(k);
        }
        if torn_at.is_none() && !t.is_disc() {
            assert_eq!(t.components, 1, "{name} frame {k}: {t:?}");
            println!("{name} frame {k}, tearing: {t:?}");
            tearing.push(k);
            return;
        }
        let expected = if torn_at.is_some() { 2 } else { 1 };
        assert!(t.is_discs(expected), "{name} frame {k}: {t:?}");
    });
    let torn_at = torn_at.unwrap_or_else(|| panic!("{name} did not tear"));
    assert!(
        tearing.len() <= TEARING_FRAMES && tearing.iter().all(|&k| k + tearing.len() >= torn_at),
        "{name}: tearing frames {tearing:?}, in two at {torn_at}"
    );
    let mesh = surface_mesh(&built, "sheet");
    let count = mesh.vertices.len();
    let left = mesh.vertices.iter().filter(|v| v.x < 0.0).count();
    println!(
        "{name}: one disc to frame {}, tearing in frames {tearing:?}, two discs from frame \
         {torn_at} to the end; final surface {count} vertices, {left} left of x = 0 and {} \
         right",
        torn_at - 1 - tearing.len(),
        count - left
    );
    // One piece in each hand: no piece has vertices on both sides.
    let tri = oriented_particles::op_modeling::triangulation::Triangulation {
        triangles: mesh.triangles.clone(),
    };
    for &(a, b) in tri.edges().keys() {
        let (xa, xb) = (mesh.vertices[a as usize].x, mesh.vertices[b as usize].x);
        assert!(xa * xb > 0.0, "{name}: an edge crosses x = 0");
    }
    assert!(
        3 * left >= count && 3 * (count - left) >= count,
        "{name}: {left} of {count}"
    );
    torn_at
}

/// Frames of one piece that is not a disc allowed while the tear runs
/// across: 0.5 time units at 10 frames per unit time, 2% of the 24-unit
/// pull, so the tear is one event rather than an unzipping over the pull
/// (measured: 0 frames for fig_12_tearing, 3 for fig_12_tearing_bonds).
const TEARING_FRAMES: usize = 5;

/// Fig. 12c (`scenes/fig_12_tearing.ron`): the claim in the header.
#[test]
fn fig_12c_tearing_claim_one_tear_two_pieces() {
    assert_one_tear("fig_12_tearing");
}

/// Fig. 12c with bonds (`scenes/fig_12_tearing_bonds.ron`): the claim in
/// the header.
#[test]
fn fig_12c_bonded_tearing_claim_one_tear_two_pieces() {
    assert_one_tear("fig_12_tearing_bonds");
}

/// Sizes, largest first, of the connected components of the bond graph of
/// `built`'s world (every live particle a node).
fn bond_components(built: &BuiltScene) -> Vec<usize> {
    let p = built.world().particles();
    let bonds = built.world().bonds().expect("bonded");
    let mut sets = op_modeling::disjoint_sets::DisjointSets::new(p.len());
    for &(a, b) in bonds.pairs() {
        sets.union(p.slot_of(a).expect("live"), p.slot_of(b).expect("live"));
    }
    let mut sizes = vec![0; p.len()];
    for i in 0..p.len() {
        sizes[sets.root(i)] += 1;
    }
    let mut sizes: Vec<usize> = sizes.into_iter().filter(|&s| s > 0).collect();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

/// Fig. 12c with bonds (`scenes/fig_12_tearing_bonds.ron`): the bonded
/// sheet pulled slowly by two movers starts to tear (its first bond
/// breaks) once its strain reaches about the break strain
/// `break_length / r0 - 1`, stays whole below, and ends cleanly in pieces.
///
/// The sheet's strain is measured on the particles: the distance between
/// the mean x of its two end columns over its initial value, minus 1. The
/// run is followed in steps of 0.01 time units, recording the strain when
/// the first bond breaks and when the bond graph first falls apart.
/// Checks: a pull to half the break strain (hands carried
/// `0.5 (b/r0 - 1) span / 2` outward each) breaks no bond; the first bond
/// breaks at a sheet strain between half and twice the break strain; the
/// scene's pull (hand strain 1.09) ends in at least two pieces of the bond
/// graph, each a real piece (>= 6 particles), and the pieces are apart
/// (the components of the neighbour graph within the Lennard-Jones cut-off
/// are the bond graph's: no neck, no strand). Prints both strains for the
/// scene and a sweep of smaller pulls.
///
/// What it shows (printed): the first bonds (along the pull) break at a
/// sheet strain of 0.087 (break strain 0.1: the strain is not uniform
/// next to the hands), but the sheet comes apart only at about 0.39: a
/// hexagonal lattice of central bonds loses its x bonds first, and the
/// band of rhombi they leave opens by rotating its diagonal bonds (which
/// a pull along x barely stretches) until those align and break too.
/// Pulls between the two leave one piece with a damaged band.
#[test]
fn fig_12c_bonded_sheet_tears_cleanly_beyond_the_break_length() {
    let scene = load("fig_12_tearing_bonds");
    let break_strain = scene.materials["sheet"]
        .bonds
        .expect("a bonded sheet")
        .break_length
        .expect("bonds that break")
        - 1.0;
    let span = {
        let k = |i: usize| scene.tools[i].path.keyframes[0].position[0];
        (k(1) - k(0)).abs()
    };
    // Runs `scene`; returns the time and sheet strain of the first break
    // and of the split of the bond graph (if any), the final bond
    // components, neighbour-graph components and broken count.
    let follow = |scene: &Scene| {
        let mut built = build(scene);
        let p = built.world().particles();
        let xs: Vec<Real> = p.positions().iter().map(|x| x.x).collect();
        let (lo, hi) = xs.iter().fold((Real::INFINITY, Real::MIN), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
        // Ids of the two end columns (the particles the hands hold).
        let ends = |edge: Real| -> Vec<u32> {
            (0..p.len())
                .filter(|&s| (xs[s] - edge).abs() < 0.6)
                .map(|s| p.ids()[s])
                .collect()
        };
        let (left, right) = (ends(lo), ends(hi));
        let mean_x = |b: &BuiltScene, ids: &[u32]| {
            positions(b, ids).iter().map(|x| x.x).sum::<Real>() / ids.len() as Real
        };
        let length0 = mean_x(&built, &right) - mean_x(&built, &left);
        let mut tore_at = None;
        let mut split_at = None;
        let steps = (built.duration() * 100.0).round() as usize;
        for k in 1..=steps {
            built
                .advance_to(k as Real / 100.0)
                .unwrap_or_else(|e| panic!("{e}"));
            let strain = || (mean_x(&built, &right) - mean_x(&built, &left)) / length0 - 1.0;
            if tore_at.is_none() && built.world().bonds().expect("bonded").broken() > 0 {
                tore_at = Some((built.world().time(), strain()));
            }
            if tore_at.is_some() && split_at.is_none() && bond_components(&built).len() > 1 {
                split_at = Some((built.world().time(), strain()));
            }
        }
        let bonds = bond_components(&built);
        let near = components(built.world().particles().positions(), 1.5);
        let broken = built.world().bonds().expect("bonded").broken();
        (tore_at, split_at, bonds, near, broken)
    };
    let (tore_at, split_at, pieces, near, broken) = follow(&scene);
    println!(
        "scene pull 6 per side (hand strain {:.2}): first break at (t, sheet strain) \
         {tore_at:?}, in pieces from {split_at:?}; {broken} bonds broken; bond-graph pieces \
         {pieces:?}, neighbour-graph pieces {near:?}",
        12.0 / span
    );
    let small = 0.5 * break_strain * span / 2.0;
    let (whole_at, _, whole, _, whole_broken) = follow(&pulled(&scene, small));
    println!(
        "pull {small:.3} per side (hand strain {:.3}): {whole_broken} bonds broken, pieces \
         {whole:?}",
        2.0 * small / span
    );
    assert!(whole_at.is_none() && whole_broken == 0, "{whole_at:?}");
    assert_eq!(whole.len(), 1);
    assert!(pieces.len() >= 2, "not torn: {pieces:?}");
    assert!(pieces[1] >= 6, "{pieces:?}");
    assert_eq!(near, pieces, "the pieces are apart");
    let (_, strain) = tore_at.expect("tore");
    assert!(
        strain > 0.5 * break_strain && strain < 2.0 * break_strain,
        "first break at sheet strain {strain}, break strain {break_strain}"
    );
    for pull in [0.5, 0.75, 1.0, 1.5, 2.0] {
        let (at, split, sizes, _, n) = follow(&pulled(&scene, pull));
        println!(
            "pull {pull} per side (hand strain {:.3}): first break {at:?}, in pieces from \
             {split:?}, {n} broken, pieces {sizes:?}",
            2.0 * pull / span
        );
    }
}

/// Fig. 6: two sheets of one object carried edge to edge by movers weld
/// into one seamless surface: one component of the neighbour graph within
/// the cut-off (1.5 r0) and every nearest-neighbour distance, across the
/// seam too, within 10% of r0.
#[test]
fn fig_06_two_sheets_weld_into_one() {
    println!("claim: {}", claim("fig_06_weld"));
    let scene = load("fig_06_weld");
    let start = build(&scene);
    let x0 = start.world().particles().positions().to_vec();
    assert_eq!(components(&x0, 1.5), vec![36, 36], "two sheets at first");
    let (built, _) = run(&scene, "weld");
    let p = built.world().particles();
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

/// Fig. 12a (`scenes/fig_12_drape.ron`): a bonded cloth dropped on a
/// sphere drapes over it and comes to rest. At the end no particle is
/// inside the sphere grown by the contact margin (beyond a small penalty
/// depth), the highest particles rest at about radius + margin above the
/// centre, the lowest hang well below the centre (more than half a radius),
/// the cloth is one piece (one component of the neighbour graph within the
/// Lennard-Jones cut-off, no bond broken) and it is at rest (kinetic energy
/// below 1% of its peak during the fall).
///
/// The same cloth without bonds (`scenes/drape_sphere.ron`, kept for the
/// accuracy report) does not drape: where it folds over the sphere, layers
/// of the one object come within the cut-off and bind, and the cloth
/// condenses into a clump on top (potential falling, kinetic energy rising;
/// not a step-size issue). With bonds only the bonded pairs interact
/// completely; folded layers only repel.
#[test]
fn fig_12a_cloth_drapes_over_the_sphere() {
    println!("claim: {}", claim("fig_12_drape"));
    let scene = load("fig_12_drape");
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
    let mut built = build(&scene);
    let n = built.world().particles().len();
    let frames = (built.duration() * built.frame_rate()).round() as usize;
    let mut kinetic = Vec::with_capacity(frames);
    for k in 1..=frames {
        built
            .advance_to(k as Real / built.frame_rate())
            .unwrap_or_else(|e| panic!("{e}"));
        let d = kinematic(built.world().particles());
        kinetic.push(d.kinetic_translational + d.kinetic_rotational);
    }
    let peak = kinetic.iter().copied().fold(0.0, Real::max);
    let last = *kinetic.last().expect("frames");
    let x = built.world().particles().positions();
    let closest = x
        .iter()
        .map(|p| (p - centre).norm())
        .fold(Real::INFINITY, Real::min);
    let top = x.iter().map(|p| p.z - centre.z).fold(Real::MIN, Real::max);
    let lowest = x
        .iter()
        .map(|p| p.z - centre.z)
        .fold(Real::INFINITY, Real::min);
    let pieces = components(x, 1.5);
    let bonds = built.world().bonds().expect("a bonded cloth");
    println!(
        "contact radius {:.2}: closest particle {closest:.3} from the centre; highest {top:.3}, \
         lowest {lowest:.3} above it; components {pieces:?}; {} bonds, {} broken; kinetic \
         energy peak {peak:.3e}, final {last:.3e} (ratio {:.2e}) at t = {}",
        radius + margin,
        bonds.len(),
        bonds.broken(),
        last / peak,
        built.world().time()
    );
    // Resting on the sphere: a penalty contact lets particles in by
    // load / stiffness only.
    assert!(closest > radius + margin - 0.1, "{closest}");
    assert!((top - (radius + margin)).abs() < 0.1, "{top}");
    // Hanging around it, not lying flat on top.
    assert!(lowest < -0.5 * radius, "{lowest}");
    // One piece.
    assert_eq!(pieces, vec![n]);
    assert_eq!(bonds.broken(), 0);
    // At rest.
    assert!(peak > 0.0 && last < 0.01 * peak, "{last} vs peak {peak}");
}

/// A dented shell's state at one instant: rest shape error (docs/model.md §6) and
/// how far its pushed side (the particles within 1 of the +x axis, on the
/// +x side) reaches out from the centre.
#[derive(Clone, Copy, Debug)]
struct Dent {
    error: Real,
    side: Real,
}

fn dent(built: &BuiltScene) -> Dent {
    let x = built.world().particles().positions();
    let c = x.iter().map(|p| p.coords).sum::<Vec3>() / x.len() as Real;
    let side = x
        .iter()
        .map(|p| p.coords - c)
        .filter(|d| d.x > 0.0 && d.y * d.y + d.z * d.z < 1.0)
        .map(|d| d.x)
        .fold(Real::MIN, Real::max);
    Dent {
        error: rest_shape_error(built, &built.objects()[0]),
        side,
    }
}

/// One fig. 12b run: the settled state, the state when the finger has
/// come in deepest (t = 2, scene time; it holds until 3), the end state, the largest rest
/// shape error seen (sampled at the frame rate, as `opsim run` does) and
/// the shell's memory after the settle phase and at the end.
struct DentRun {
    settled: Dent,
    pushed: Dent,
    end: Dent,
    max_error: Real,
    /// The remembered curvatures by id after the settle phase and at the end.
    kappa_settled: Vec<Real>,
    kappa_end: Vec<Real>,
    /// The bonds' remembered offsets (op_dynamics::bond_memory) after the
    /// settle phase and at the end, by bond (ids).
    offsets_settled: Vec<((u32, u32), [Vec3; 2])>,
    offsets_end: Vec<((u32, u32), [Vec3; 2])>,
    /// The shell's particle ids, and their settled positions relative to
    /// the centre.
    ids: Vec<u32>,
    rest: Vec<Vec3>,
    /// Frames (0 the settled one) whose exported shell surface is not one
    /// closed sphere.
    open_frames: Vec<usize>,
}

/// The world's bonds with their remembered offsets.
fn remembered_offsets(b: &BuiltScene) -> Vec<((u32, u32), [Vec3; 2])> {
    b.world().bonds().map_or(Vec::new(), |bonds| {
        bonds
            .pairs()
            .iter()
            .copied()
            .zip(bonds.rest_offsets().iter().copied())
            .collect()
    })
}

fn dent_run(name: &str) -> DentRun {
    let scene = load(name);
    let mut built = build(&scene);
    built.settle().expect("settles");
    let by_id = |b: &BuiltScene| -> Vec<Real> {
        let p = b.world().particles();
        b.objects()[0]
            .ids
            .iter()
            .map(|&id| p.curvatures()[p.slot_of(id).expect("alive")])
            .collect()
    };
    let kappa_settled = by_id(&built);
    let offsets_settled = remembered_offsets(&built);
    let x0 = positions(&built, &built.objects()[0].ids);
    let c0 = x0.iter().map(|p| p.coords).sum::<Vec3>() / x0.len() as Real;
    let rest = x0.iter().map(|p| p.coords - c0).collect();
    let settled = dent(&built);
    let (t0, frame) = (scene.world.settle, 1.0 / scene.world.frame_rate);
    let frames = (scene.world.duration * scene.world.frame_rate).round() as usize;
    let (mut pushed, mut max_error) = (settled, 0.0 as Real);
    let closed = |b: &BuiltScene| surface_topology(b, "shell").is_sphere();
    let mut open_frames: Vec<usize> = (!closed(&built)).then_some(0).into_iter().collect();
    for k in 1..=frames {
        let t = k as Real * frame;
        built
            .world_mut()
            .advance_to(t0 + t)
            .expect("does not diverge");
        if !closed(&built) {
            open_frames.push(k);
        }
        let d = dent(&built);
        max_error = max_error.max(d.error);
        if (t - 2.0).abs() < 1e-9 {
            pushed = d;
        }
    }
    let end = dent(&built);
    println!(
        "{name}: pushed side {:.2} -> {:.2} (t = 2) -> {:.2} above the centre; rest shape \
         error max {max_error:.3}, final {:.3} (ratio {:.2}); surface closed in {} of {} \
         frames (open: {open_frames:?})",
        settled.side,
        pushed.side,
        end.side,
        end.error,
        end.error / max_error,
        frames + 1 - open_frames.len(),
        frames + 1
    );
    DentRun {
        settled,
        pushed,
        end,
        max_error,
        kappa_settled,
        kappa_end: by_id(&built),
        offsets_settled,
        offsets_end: remembered_offsets(&built),
        ids: built.objects()[0].ids.clone(),
        rest,
        open_frames,
    }
}

/// Fig. 12b: a shell pushed in by a finger, which then withdraws. The
/// plastic shell (`scenes/fig_12_plastic.ron`: a bonded lattice whose bonds
/// remember their offsets in the particles' frames, flowing beyond a
/// yield, op_dynamics::bond_memory) keeps its dent: the side stays in, the
/// final rest shape error is most of its maximum, the memory changed where
/// the shell was dented and not on the far side, and its exported surface
/// is one closed sphere in every frame. The elastic shape-memory shell
/// (`scenes/fig_12_plastic_memory.ron`: cohesion and form with rest
/// curvature 1/radius, seed 002) springs back: the side returns, the
/// final error is a small part of the maximum, and its surface is closed
/// in every frame too.
///
/// Measured (ci profile; settled -> finger arrived at t = 2 -> end):
/// plastic side 3.97 -> 3.02 -> 3.02, error max 0.23, final 0.21 (ratio
/// 0.90), surface closed in all 101 frames, remembered offsets changed by
/// up to 0.70 on the pushed side and not at all on the far side; elastic
/// side 3.47 -> 2.47 -> 3.54, error max 0.32, final 0.079 (ratio 0.24:
/// the surface is back, the particles around the dent rearranged), surface
/// closed in all 101 frames.
/// The worlds are stepped as `opsim run` steps them (frame by frame), with
/// no files written.
#[test]
fn fig_12b_plastic_shell_keeps_its_dent_elastic_shell_springs_back() {
    println!("claim: {}", claim("fig_12_plastic"));
    println!("claim: {}", claim("fig_12_plastic_memory"));
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
    // Both shells' exported surfaces are one closed sphere in every frame.
    for (name, run) in [("plastic", &plastic), ("elastic", &memory)] {
        assert!(
            run.open_frames.is_empty(),
            "{name} shell open in frames {:?}",
            run.open_frames
        );
    }
    assert!(
        memory.end.error < 0.5 * memory.max_error,
        "{} vs {}",
        memory.end.error,
        memory.max_error
    );
    // The elastic memory never changes; the plastic one changed on the
    // pushed side (x > 2 at rest) and not on the far side (x < -2): the
    // largest change of a remembered offset of a bond with an end there.
    assert_eq!(memory.kappa_settled, memory.kappa_end);
    assert_eq!(plastic.offsets_settled.len(), plastic.offsets_end.len());
    let at_rest = |id: u32| {
        let k = plastic
            .ids
            .iter()
            .position(|&i| i == id)
            .expect("a shell particle");
        plastic.rest[k]
    };
    let change = |pick: &dyn Fn(&Vec3) -> bool| {
        plastic
            .offsets_settled
            .iter()
            .zip(&plastic.offsets_end)
            .filter(|((pair, _), _)| pick(&at_rest(pair.0)) || pick(&at_rest(pair.1)))
            .map(|((pair, a), (same, b))| {
                assert_eq!(pair, same, "no bond broke or formed");
                (a[0] - b[0]).norm().max((a[1] - b[1]).norm())
            })
            .fold(0.0 as Real, Real::max)
    };
    let near = change(&|x| x.x > 2.0);
    let far = change(&|x| x.x < -2.0);
    println!("largest change of a remembered offset: pushed side {near:.3}, far side {far:.3}");
    assert!(far < 0.05 * near, "far side {far} vs pushed side {near}");
}
