//! Every field that sets a run's work is in the work estimate (issue 38):
//! the structural mutants that `opsim check` used to accept, or to take
//! minutes and gigabytes over, are refused quickly with the field, the
//! value and the flag that lifts the limit; the same scenes without the
//! mutation pass, and `--no-work-limits` lifts each refusal.

use op_scene::load::parse_unvalidated;
use op_scene::{Format, Scene, WorkLimits};

/// A scene of `objects` (RON object entries) with material `m` of `extra`
/// settings and outputs `outputs`.
fn scene(material: &str, objects: &[String], outputs: &str) -> String {
    format!(
        r#"(name: "work", world: (dt: 0.01, duration: 1),
        materials: {{"m": ({material})}},
        objects: [{}],
        outputs: ({outputs}))"#,
        objects.join(",\n")
    )
}

fn parse(text: &str) -> Scene {
    parse_unvalidated(text, Format::Ron, "<work.ron>").expect("parses")
}

/// The validation error of `text`, which must be refused by a work limit
/// and pass without limits.
fn refused(text: &str) -> String {
    let s = parse(text);
    let e = s.validate(None).expect_err("refused").to_string();
    assert!(e.contains("--no-work-limits"), "{e}");
    let mut unlimited = s;
    unlimited.limits = WorkLimits::unlimited();
    unlimited.validate(None).expect("valid without work limits");
    e
}

fn chain(name: &str, count: usize, y: f64) -> String {
    format!(
        r#"(name: "{name}", material: "m", generator: Chain(count: {count}, spacing: 1, start: (0, {y}, 0)))"#
    )
}

fn sheet(name: &str, n: usize) -> String {
    format!(r#"(name: "{name}", material: "m", generator: HexSheet(nx: {n}, ny: {n}, spacing: 1))"#)
}

/// A bond radius far beyond the spacing bonds every particle with
/// thousands: a 2-particle object next to a 40,000-particle sheet used to
/// take 6 GB before an allocation abort.
#[test]
fn a_bond_radius_counts_as_the_range() {
    let objects = [chain("pair", 2, 0.5), sheet("big", 200)];
    let ok = scene("bonds: (radius: 1.2)", &objects, "");
    parse(&ok).validate(None).unwrap();
    let e = refused(&scene("bonds: (radius: 100)", &objects, ""));
    assert!(e.contains("interacting pairs"), "{e}");
}

/// A thousand chains on top of each other each pass a per-object
/// estimate; together they hold a thousand times more pairs.
#[test]
fn overlapping_objects_count_their_shared_pairs() {
    let apart: Vec<String> = (0..30)
        .map(|k| chain(&format!("c{k}"), 100, 10.0 * k as f64))
        .collect();
    let text = scene("", &apart, "");
    let spread = parse(&text);
    spread.validate(None).unwrap();
    let together: Vec<String> = (0..1000)
        .map(|k| chain(&format!("c{k}"), 1000, 1e-3 * k as f64))
        .collect();
    let s = parse(&scene("", &together, ""));
    let alone = s.work_estimate(None).unwrap().pairs;
    assert!(alone > 1e8, "{alone}");
    let e = s.validate(None).unwrap_err().to_string();
    assert!(e.contains("interacting pairs"), "{e}");
    // Apart, the same chains hold their own pairs only.
    let apart: Vec<String> = (0..1000)
        .map(|k| chain(&format!("c{k}"), 1000, 100.0 * k as f64))
        .collect();
    let pairs = parse(&scene("", &apart, ""))
        .work_estimate(None)
        .unwrap()
        .pairs;
    assert!(pairs < 1e7, "{pairs}");
}

/// A list of particles on one point is a cloud of N² pairs, counted from a
/// sample of its neighbourhoods.
#[test]
fn a_list_on_one_point_is_counted_dense() {
    let particles = vec!["(position: (1, 2, 3))"; 50_000].join(", ");
    let list =
        format!(r#"(name: "heap", material: "m", generator: List(particles: [{particles}]))"#);
    let e = refused(&scene("", &[list], ""));
    assert!(e.contains("objects[0] \"heap\""), "{e}");
}

/// A skin whose support covers the object many times over samples its
/// field at millions of nodes per frame from every primitive.
#[test]
fn a_skin_radius_counts_its_field_evaluations() {
    let skinned = |radius: f64| {
        format!(
            r#"(name: "s", material: "m", generator: HexSheet(nx: 20, ny: 20, spacing: 1),
            skin: Some((primitive: Point, radius: {radius}, cell_size: 0.2)))"#
        )
    };
    let mut ok = parse(&scene("", &[skinned(1.2)], ""));
    ok.world.duration = 100.0;
    ok.validate(None).unwrap();
    let text = scene("", &[skinned(20.0)], "").replace("duration: 1", "duration: 100");
    let e = refused(&text);
    assert!(e.contains("skin field evaluations"), "{e}");
    assert!(e.contains("objects[0] \"s\".skin"), "{e}");
}

/// A triangulation radius of 1e308 rest spacings pairs every particle of
/// an object with every other at each frame.
#[test]
fn a_triangulation_radius_counts_its_pairs() {
    let objects = [sheet("s", 300)];
    let with = |radius: &str| {
        scene(
            "",
            &objects,
            &format!("triangulation: true, triangulation_radius: {radius}"),
        )
        .replace("duration: 1", "duration: 100")
    };
    parse(&with("1.7")).validate(None).unwrap();
    let e = refused(&with("1e308"));
    assert!(e.contains("outputs.triangulation_radius"), "{e}");
}

/// More objects than the limit are refused before anything compares them
/// pairwise.
#[test]
fn objects_are_counted_against_a_limit() {
    let many: Vec<String> = (0..10_001)
        .map(|k| chain(&format!("c{k}"), 1, 10.0 * k as f64))
        .collect();
    let e = refused(&scene("", &many, ""));
    assert!(e.contains("10001 objects"), "{e}");
}

/// A solid ball of nine million particles is counted without making
/// them.
#[test]
fn a_large_solid_ball_is_counted_not_built() {
    let ball = r#"(name: "b", material: "m", generator: SolidBall(radius: 115, spacing: 1))"#;
    let mut s = parse(&scene("", &[ball.to_string()], ""));
    s.limits = WorkLimits::unlimited();
    let counts = s.validate(None).unwrap();
    let estimate = 4.0 / 3.0 * std::f64::consts::PI * 115f64.powi(3) * 2f64.sqrt();
    assert!(
        (counts[0] as f64 / estimate - 1.0).abs() < 0.01,
        "{counts:?}"
    );
}

/// Creation rules may add particles up to `creation.max_particles`: the
/// run's particle-steps count that many, not only the particles it starts
/// with (a three-frame run of a sphere pushed into a torus, with a
/// velocity and a long settle, ran past 90 s under a particle-step budget
/// it was checked against with its 363 starting particles).
#[test]
fn created_particles_count_up_to_their_cap() {
    let text = |cap: usize| {
        format!(
            r#"(name: "work", world: (dt: 0.01, duration: 1),
            materials: {{"m": ()}},
            objects: [{}],
            creation: Some((stretching: Some((d_min: 1.6, d_max: 2.5)), max_particles: {cap})))"#,
            chain("c", 10, 0.0)
        )
    };
    let limited = |cap: usize| {
        let mut s = parse(&text(cap));
        s.limits.max_particle_steps = 5e4;
        s
    };
    // 100 steps of up to 1,000 particles; of up to 100.
    let e = limited(1000)
        .validate(None)
        .expect_err("refused")
        .to_string();
    assert!(e.contains("up to 1000 particles"), "{e}");
    limited(100).validate(None).expect("within the budget");
    let estimate = limited(1000).work_estimate(None).unwrap();
    assert_eq!((estimate.particles, estimate.created), (10.0, 990.0));
    // Without a rule that creates, the cap adds nothing.
    let merging_only = text(1000).replace(
        "stretching: Some((d_min: 1.6, d_max: 2.5))",
        "merging: Some((distance: 0.3))",
    );
    let e = parse(&merging_only).work_estimate(None).unwrap();
    assert_eq!(e.created, 0.0);
}

/// A skinned object is in contact with every skinned object its support
/// overlaps: five copies of a skinned sheet on top of each other each
/// meet the four others every step (a ball and five spirals copied onto
/// one another ran 67 s of contact for a three-frame run checked at a
/// fifth of that).
#[test]
fn overlapping_skins_count_their_contact_with_each_other() {
    let skinned = |name: &str, y: f64| {
        format!(
            r#"(name: "{name}", material: "m",
            generator: HexSheet(nx: 10, ny: 10, spacing: 1, center: (0, {y}, 0)),
            skin: Some((primitive: Point, radius: 1.2, cell_size: 0.25)))"#
        )
    };
    let contact = |objects: &[String]| {
        parse(&scene("", objects, ""))
            .work_estimate(None)
            .unwrap()
            .contact_evaluations_per_step
    };
    // Two sheets far apart meet at most each other: one partner each.
    let apart = contact(&[skinned("a", 0.0), skinned("b", 100.0)]);
    let five: Vec<String> = (0..5).map(|k| skinned(&format!("s{k}"), 0.0)).collect();
    let piled = contact(&five);
    // Five piled sheets: each has four partners, so 5 x 4 against 2 x 1.
    assert!((piled / apart - 10.0).abs() < 1e-9, "{piled} vs {apart}");
    // The refusal names a skin and the skins it overlaps.
    let mut long = parse(&scene("", &five, ""));
    long.world.duration = 1e4;
    long.limits = WorkLimits::default().with_particle_steps(1e9);
    let e = long.validate(None).expect_err("refused").to_string();
    assert!(e.contains("overlapping 4 other skin(s)"), "{e}");
}

/// Bonds are evaluated every step besides the neighbour pairs within the
/// cut-off: a bonded material's pairs count both (100,000 particles of a
/// plastic clay, bonded within 1.5 of a cut-off of 2, evaluated about 2.3
/// million interactions a step where the estimate counted 1.6 million).
#[test]
fn bonds_count_besides_the_neighbour_pairs() {
    let objects = [sheet("s", 30)];
    let pairs = |material: &str| {
        parse(&scene(material, &objects, ""))
            .work_estimate(None)
            .unwrap()
            .pairs
    };
    let unbonded = pairs("");
    let bonded = pairs("bonds: (radius: 1.2)");
    // Six bonds per particle of a hexagonal sheet at spacing 1 (the
    // estimate's density: π 1.2² / 0.866 ≈ 5.2), three per particle
    // counted once per pair.
    let per_particle = (bonded - unbonded) / 900.0;
    assert!(per_particle > 2.0 && per_particle < 3.5, "{per_particle}");
}

/// A message that lists the scene's objects lists a few, each name
/// elided, and counts the rest: a force on an unknown object in a scene
/// of a thousand objects named with 5,000 characters each wrote a 5 MB
/// message (and a reader that stopped at a megabyte killed the process
/// with its pipe).
#[test]
fn messages_list_a_few_object_names_elided() {
    let long = "y".repeat(5000);
    let objects: Vec<String> = (0..1000)
        .map(|k| chain(&format!("{long}_{k}"), 2, k as f64 * 10.0))
        .collect();
    let text = scene("", &objects, "").replace(
        "objects: [",
        r#"forces: [(object: "chain", force: (1, 0, 0))], objects: ["#,
    );
    let e = parse(&text)
        .validate(None)
        .expect_err("refused")
        .to_string();
    assert!(e.contains("unknown object (defined objects: "), "{e}");
    assert!(
        e.contains("(5002 characters)") && e.contains("and 980 more"),
        "{e}"
    );
    assert!(e.len() < 4000, "{} bytes", e.len());
}
