//! The cookbook's scenes (`scenes/cookbook/`) each state one claim in their
//! header (`// claim: ...`); these tests check it on the simulated state,
//! frame by frame where the claim is about motion.

mod figure_support;

use std::path::Path;

use figure_support::{build, components, labels};
use oriented_particles::op_dynamics::{Point3, Real, Vec3};
use oriented_particles::op_scene::run::rest_shape_error;
use oriented_particles::op_scene::{load_scene, BuiltScene, Scene};

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/cookbook/{name}.ron"));
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// One frame of one object: positions and velocities.
struct Frame {
    x: Vec<Point3>,
    v: Vec<Vec3>,
    /// The runner's rest shape error (RMS distance to the rest shape after
    /// the best rigid alignment, in rest spacings).
    error: Real,
}

/// Runs `scene` frame by frame (after its settle phase) and records each
/// object's particles at every frame.
fn frames(scene: &Scene) -> (BuiltScene, Vec<Vec<Frame>>) {
    let mut built = build(scene);
    built.settle().expect("settles");
    let t0 = built.settle_duration();
    let n = (built.duration() * built.frame_rate()).round() as usize;
    let mut out: Vec<Vec<Frame>> = (0..built.objects().len()).map(|_| Vec::new()).collect();
    for k in 0..=n {
        built
            .advance_to(t0 + k as Real / built.frame_rate())
            .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        let p = built.world().particles();
        for (o, obj) in built.objects().iter().enumerate() {
            let slots: Vec<usize> = obj.all_ids().filter_map(|id| p.slot_of(id)).collect();
            out[o].push(Frame {
                x: slots.iter().map(|&s| p.positions()[s]).collect(),
                v: slots.iter().map(|&s| p.velocities()[s]).collect(),
                error: rest_shape_error(&built, obj),
            });
        }
    }
    (built, out)
}

fn centroid(x: &[Point3]) -> Point3 {
    Point3::from(x.iter().map(|p| p.coords).sum::<Vec3>() / x.len() as Real)
}

fn mean(v: &[Vec3]) -> Vec3 {
    v.iter().sum::<Vec3>() / v.len() as Real
}

fn kinetic(f: &Frame) -> Real {
    f.v.iter().map(|v| 0.5 * v.norm_squared()).sum()
}

/// The claim line of a cookbook scene's header.
fn claim(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/cookbook/{name}.ron"));
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix("// claim: "))
        .unwrap_or_else(|| panic!("{name} states no claim"))
        .to_string()
}

#[test]
fn every_cookbook_scene_states_a_claim() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cookbook");
    let mut n = 0;
    for e in std::fs::read_dir(dir).unwrap() {
        let name = e
            .unwrap()
            .path()
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        assert!(!claim(&name).is_empty());
        n += 1;
    }
    assert!(n >= 4, "{n} cookbook scenes");
}

/// `cloth_on_box`: on top, hanging over the four sides, one piece, at rest.
#[test]
fn cloth_rests_on_the_box_and_hangs_over_its_sides() {
    println!("claim: {}", claim("cloth_on_box"));
    let scene = load("cloth_on_box");
    let (half, margin) = match (&scene.tools[0].shape, &scene.tools[0].role) {
        (
            oriented_particles::op_modeling::tools::ToolShape::Cuboid { half_extents },
            oriented_particles::op_modeling::tools::Role::Obstacle { margin, .. },
        ) => (*half_extents, *margin),
        other => panic!("the box is a cuboid obstacle: {other:?}"),
    };
    let (_, frames) = frames(&scene);
    let cloth = &frames[0];
    let last = cloth.last().unwrap();
    let top = half[2] + margin;
    let on_top: Vec<&Point3> = last
        .x
        .iter()
        .filter(|p| p.x.abs() < half[0] - 1.0 && p.y.abs() < half[1] - 1.0)
        .collect();
    let heights: Vec<Real> = on_top.iter().map(|p| p.z).collect();
    let (lo, hi) = heights
        .iter()
        .fold((Real::MAX, Real::MIN), |(a, b), &z| (a.min(z), b.max(z)));
    println!(
        "on top: {} particles at z {lo:.3}..{hi:.3} (top + margin {top})",
        on_top.len()
    );
    assert!(on_top.len() > 100, "{} particles on top", on_top.len());
    assert!(
        lo > top - 0.15 && hi < top + 0.3,
        "z {lo}..{hi} on top {top}"
    );
    for (axis, sign) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)] {
        let hanging = last
            .x
            .iter()
            .filter(|p| sign * p[axis] > half[axis] && p.z < top - 1.0)
            .count();
        println!("side {sign:+} axis {axis}: {hanging} particles hang below the top");
        assert!(
            hanging >= 10,
            "side {sign:+} of axis {axis}: {hanging} hanging"
        );
    }
    let c = centroid(&last.x);
    assert!(
        c.x.abs() < 1.0 && c.y.abs() < 1.0,
        "the cloth slid: centroid {c}"
    );
    assert_eq!(components(&last.x, 1.5).len(), 1, "one piece");
    let peak = cloth.iter().map(kinetic).fold(0.0, Real::max);
    assert!(
        kinetic(last) < 0.01 * peak,
        "at rest: {} vs {peak}",
        kinetic(last)
    );
}

/// `ball_bounce`: squashed at impact, round in the air, at least three
/// bounces of falling height, at rest on the ground, round, one piece.
#[test]
fn solid_ball_bounces_and_comes_to_rest_round() {
    println!("claim: {}", claim("ball_bounce"));
    let scene = load("ball_bounce");
    let margin = match &scene.tools[0].role {
        oriented_particles::op_modeling::tools::Role::Obstacle { margin, .. } => *margin,
        other => panic!("the ground is an obstacle: {other:?}"),
    };
    let (_, frames) = frames(&scene);
    let ball = &frames[0];
    let lowest = |f: &Frame| f.x.iter().map(|p| p.z).fold(Real::MAX, Real::min);
    // Height over width of the ball's bounding box: 1 for the round ball.
    let aspect = |f: &Frame| {
        let span = |c: usize| {
            let (lo, hi) = f.x.iter().fold((Real::MAX, Real::MIN), |(a, b), p| {
                (a.min(p[c]), b.max(p[c]))
            });
            hi - lo
        };
        span(2) / span(0).max(span(1))
    };
    // A frame touches the ground when its lowest particle is within the
    // obstacle's margin; it is in the air when clear of it by 0.1.
    let touching: Vec<bool> = ball.iter().map(|f| lowest(f) < margin).collect();
    let mut apexes = Vec::new();
    let mut squash = Real::MAX;
    let mut k = touching.iter().position(|&t| t).expect("the ball lands");
    while k < ball.len() {
        // Leave the ground, rise, and come back.
        let Some(off) = (k..ball.len()).find(|&j| lowest(&ball[j]) > margin + 0.1) else {
            break;
        };
        squash = (k..off).map(|j| aspect(&ball[j])).fold(squash, Real::min);
        let Some(back) = (off..ball.len()).find(|&j| touching[j]) else {
            break;
        };
        let apex = (off..back).map(|j| lowest(&ball[j])).fold(0.0, Real::max);
        let in_air = (off..back)
            .map(|j| aspect(&ball[j]))
            .fold(Real::MAX, Real::min);
        println!(
            "bounce {}: apex of the lowest point {apex:.3}, height/width in the air >= {in_air:.3}",
            apexes.len() + 1
        );
        assert!(in_air > 0.97, "round again in the air: {in_air}");
        apexes.push(apex);
        k = back;
    }
    println!("squashed to height/width {squash:.3} on impact");
    assert!(squash < 0.95, "the ball squashes on impact: {squash}");
    assert!(apexes.len() >= 3, "{} bounces", apexes.len());
    assert!(
        apexes.windows(2).all(|w| w[1] < w[0]),
        "each bounce lower: {apexes:?}"
    );
    let last = ball.last().unwrap();
    let peak = ball.iter().map(kinetic).fold(0.0, Real::max);
    println!(
        "end: lowest point {:.3}, height/width {:.3}, rest shape error {:.4}, kinetic {:.2e} of peak {peak:.2}",
        lowest(last),
        aspect(last),
        last.error,
        kinetic(last)
    );
    assert!(
        lowest(last) < margin && lowest(last) > 0.0,
        "rests on the ground"
    );
    assert!(kinetic(last) < 1e-3 * peak, "at rest");
    assert!(last.error < 0.05, "round: rest shape error {}", last.error);
    assert_eq!(components(&last.x, 1.3).len(), 1, "one piece");
}

/// `wire_bend_release`: bent far from its rest shape, back below 0.01.
#[test]
fn wire_coils_back_after_release() {
    println!("claim: {}", claim("wire_bend_release"));
    let scene = load("wire_bend_release");
    let (_, frames) = frames(&scene);
    let worst = frames[0].iter().map(|f| f.error).fold(0.0, Real::max);
    let end = frames[0].last().unwrap().error;
    println!("rest shape error: worst {worst:.3}, final {end:.5}");
    assert!(worst > 0.5, "the forces bend the wire: worst {worst}");
    assert!(end < 0.01, "recovered: {end}");
}

/// `sheet_tear`: two pieces, one in each hand.
#[test]
fn notched_sheet_tears_into_two_pieces_one_per_hand() {
    println!("claim: {}", claim("sheet_tear"));
    let scene = load("sheet_tear");
    let (built, frames) = frames(&scene);
    let last = frames[0].last().unwrap();
    let t = built.world().time();
    let hands: Vec<Point3> = built.tools()[1..]
        .iter()
        .map(|tool| Point3::from(tool.pose(t).position))
        .collect();
    let label = labels(&last.x, 1.5);
    let mut pieces: Vec<usize> = label.clone();
    pieces.sort_unstable();
    pieces.dedup();
    let held: Vec<Vec<usize>> = hands
        .iter()
        .map(|h| {
            let mut l: Vec<usize> = last
                .x
                .iter()
                .zip(&label)
                .filter(|(p, _)| (p.x - h.x).abs() < 0.8)
                .map(|(_, &l)| l)
                .collect();
            l.sort_unstable();
            l.dedup();
            l
        })
        .collect();
    let sizes: Vec<usize> = pieces
        .iter()
        .map(|&p| label.iter().filter(|&&l| l == p).count())
        .collect();
    println!("pieces {sizes:?}; held by the hands: {held:?}");
    assert_eq!(pieces.len(), 2, "two pieces: {sizes:?}");
    assert_eq!(held[0].len(), 1, "the left hand holds one piece");
    assert_eq!(held[1].len(), 1, "the right hand holds one piece");
    assert_ne!(held[0], held[1], "each hand holds its own piece");
    assert!(
        sizes.iter().all(|&s| s * 5 > last.x.len()),
        "no shred: {sizes:?}"
    );
}

/// `skinned_hit`: the sheet moves along the throw, the ball stays in front.
#[test]
fn skinned_ball_pushes_the_sheet_without_passing_through() {
    println!("claim: {}", claim("skinned_hit"));
    let scene = load("skinned_hit");
    let (_, frames) = frames(&scene);
    let (sheet, ball) = (&frames[0], &frames[1]);
    let mut gap_min = Real::MAX;
    for (s, b) in sheet.iter().zip(ball) {
        // The sheet's plane is y = const: the ball's front particle stays
        // on its side of the sheet's nearest particles.
        let cs = centroid(&s.x);
        let front = b.x.iter().map(|p| p.y).fold(Real::MIN, Real::max);
        let sheet_near =
            s.x.iter()
                .filter(|p| (p.x - cs.x).abs() < 1.5 && (p.z - cs.z).abs() < 1.5)
                .map(|p| p.y)
                .fold(Real::MAX, Real::min);
        gap_min = gap_min.min(sheet_near - front);
    }
    let push = centroid(&sheet.last().unwrap().x).y - centroid(&sheet[0].x).y;
    let sheet_speed = mean(&sheet.last().unwrap().v).y;
    println!(
        "sheet moved {push:.3} along the throw (speed {sheet_speed:.3}); smallest gap {gap_min:.3}"
    );
    assert!(push > 0.5, "the sheet is pushed: {push}");
    assert!(
        gap_min > 0.2,
        "the ball stays in front of the sheet: gap {gap_min}"
    );
    for (name, f) in [("sheet", sheet), ("ball", ball)] {
        assert_eq!(
            components(&f.last().unwrap().x, 1.5).len(),
            1,
            "{name} in one piece"
        );
    }
}

/// The scene shown in README.md is valid as printed (comments included).
#[test]
fn the_readme_scene_example_is_valid() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let start = readme.find("```ron\n").expect("README shows a RON scene") + "```ron\n".len();
    let len = readme[start..].find("```").unwrap();
    let scene = oriented_particles::op_scene::parse_scene(
        &readme[start..start + len],
        oriented_particles::op_scene::Format::Ron,
        "README.md",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.objects[0].material, "cloth");
    assert!(scene.materials.contains_key("cloth"), "the preset resolves");
}

/// `clay_press`: the dent of the ball stays after it lifts away, the
/// sheet in one piece.
#[test]
fn clay_sheet_keeps_the_dent_of_the_ball() {
    println!("claim: {}", claim("clay_press"));
    let scene = load("clay_press");
    let (_, frames) = frames(&scene);
    let lowest = |f: &Frame| f.x.iter().map(|p| p.z).fold(Real::MAX, Real::min);
    let deepest = frames[0].iter().map(lowest).fold(Real::MAX, Real::min);
    let last = frames[0].last().unwrap();
    let end = lowest(last);
    let pieces = components(&last.x, 1.5).len();
    println!(
        "dent {:.3} deep at most, {:.3} at the end; {pieces} piece(s)",
        -deepest, -end
    );
    assert!(deepest < -1.0, "the ball dents the sheet: {deepest}");
    assert!(end < 0.9 * deepest, "the dent stays: {end} of {deepest}");
    assert_eq!(pieces, 1, "one piece");
}

/// `flag_in_wind`: streams downwind of the pole, droops without the wind,
/// the gust lifts its free edge, one piece.
#[test]
fn flag_streams_in_the_wind_and_the_gust_lifts_it() {
    println!("claim: {}", claim("flag_in_wind"));
    let scene = load("flag_in_wind");
    let (built, runs) = frames(&scene);
    assert!(built.stages().contains(&"wind".to_string()));
    let flag = &runs[0];
    let first = &flag[0];
    // The free edge: the particles farthest from the pole at the start.
    let far = first.x.iter().map(|p| p.x).fold(Real::MIN, Real::max);
    let edge: Vec<usize> = (0..first.x.len())
        .filter(|&i| first.x[i].x > far - 0.5)
        .collect();
    let edge_mean =
        |f: &Frame| edge.iter().map(|&i| f.x[i].coords).sum::<Vec3>() / edge.len() as Real;
    let at = |t: Real| &flag[(t * built.frame_rate()).round() as usize];
    let calm = edge_mean(at(19.0));
    let lifted = (40..=60)
        .map(|k| edge_mean(&flag[k]).z)
        .fold(Real::MIN, Real::max);
    let end = edge_mean(flag.last().unwrap());
    println!(
        "free edge (x, z): before the gust ({:.2}, {:.2}), highest in it z {lifted:.2}, \
         at the end ({:.2}, {:.2}); starts at x {far:.2}",
        calm.x, calm.z, end.x, end.z
    );
    // Streams: the free edge stays downwind, within 17 degrees of level
    // (the drag on a particle at rest is four times its weight: 14).
    let near = first.x.iter().map(|p| p.x).fold(Real::MAX, Real::min);
    let length = far - near;
    assert!(
        calm.x > far - 0.1 * length && calm.z > -0.3 * length,
        "streams: {calm}"
    );
    assert!(
        lifted > calm.z + 1.0,
        "the gust lifts the edge: {lifted} vs {}",
        calm.z
    );
    assert_eq!(
        components(&flag.last().unwrap().x, 1.5).len(),
        1,
        "one piece"
    );

    // The same flag without the wind hangs from the pole.
    let mut still = scene.clone();
    still.features.clear();
    let (_, runs) = frames(&still);
    let hang = edge_mean(&runs[0][(19.0 * built.frame_rate()).round() as usize]);
    println!(
        "without wind, the free edge at t = 19: ({:.2}, {:.2})",
        hang.x, hang.z
    );
    assert!(
        hang.z < calm.z - 4.0,
        "without wind it hangs: {hang} vs {calm}"
    );
    assert!(
        end.x > hang.x + 3.0,
        "downwind of the hanging flag: {end} vs {hang}"
    );
}
