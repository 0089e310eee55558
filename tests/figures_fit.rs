//! Seed 000 figs. 10-11 as scenes (§7, point-set interpolation): the
//! scenes `opsim run` runs, checked against the figures' claims. Fig. 10:
//! the surface grows from seeds fixed at samples of a closed surface until
//! it is closed (Euler characteristic 2, no boundary) and passes through the
//! samples. Fig. 11: open data filled by stretching with a bounded search
//! range keeps a hole wider than the range (two boundary loops: rim and
//! hole) and covers the rest. Also: bad `creation.fit` sections are
//! rejected with messages naming the field.

mod figure_support;

use std::path::Path;

use figure_support::{build, claim, load, run};
use oriented_particles::op_dynamics::{Flags, Point3, Real, Vec3};
use oriented_particles::op_scene::fit::SurfaceMesh;
use oriented_particles::op_scene::pointsets::read_point_set;
use oriented_particles::op_scene::{parse_scene, BuiltScene, Format};

/// The samples of `scenes/data/<name>`.
fn samples(name: &str) -> Vec<Point3> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/data")
        .join(name);
    read_point_set(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .positions
}

/// The triangulation of object 0 as the frames write it (radius
/// `outputs.triangulation_radius` rest spacings), measured against
/// `data`; and the rest spacing.
fn mesh(built: &BuiltScene, data: &[Point3]) -> (SurfaceMesh, Real) {
    let p = built.world().particles();
    let o = &built.objects()[0];
    let slots: Vec<usize> = o.all_ids().filter_map(|id| p.slot_of(id)).collect();
    let positions: Vec<Point3> = slots.iter().map(|&s| p.positions()[s]).collect();
    let normals: Vec<Vec3> = slots.iter().map(|&s| p.normal(s)).collect();
    let radius = built.outputs().triangulation_radius * o.rest_spacing;
    let m = SurfaceMesh::new(&positions, &normals, radius, data).expect("valid radius");
    (m, o.rest_spacing)
}

/// Prints what a figure test measured (shown with `--nocapture`).
fn print_figures(fig: &str, particles: usize, m: &SurfaceMesh, r0: Real) {
    println!(
        "fig. {fig}: {particles} particles, chi {}, {} loops, sample RMS {:.4} max {:.4} (r0 {r0})",
        m.euler_characteristic, m.boundary_loops, m.rms_distance, m.max_distance
    );
}

/// Fig. 10: before the release the seeds sit on their samples and
/// particles have been grown between them, none far from the data; at the
/// end the released surface is closed (χ = 2, no boundary loop), its
/// samples within 0.1 r0 (RMS) of the mesh, its normals outward.
#[test]
fn fig_10_closed_interpolation_grows_a_closed_surface_through_the_samples() {
    println!("claim: {}", claim("fig_10_interpolation"));
    let scene = load("fig_10_interpolation");
    let data = samples("fig_10_sphere.xyz");

    let mut growing = build(&scene);
    let fit = growing.creation().as_ref().and_then(|c| c.fit.clone());
    let release = fit.expect("the scene has creation.fit").release_time;
    growing.advance_to(0.5 * release).expect("no divergence");
    let p = growing.world().particles();
    let o = &growing.objects()[0];
    assert_eq!(o.ids.len(), data.len());
    for (k, &id) in o.ids.iter().enumerate() {
        let s = p.slot_of(id).expect("seeds live");
        assert_eq!(
            p.positions()[s],
            data[k],
            "seed {k} moved before the release"
        );
        assert!(p.flags()[s].contains(Flags::FIXED_POSITION));
    }
    assert!(
        o.created.len() > 2 * data.len(),
        "{} particles created between {} samples",
        o.created.len(),
        data.len()
    );
    // Closed data: within d_max / √3 = 1.44 r0 of a sample (the runner's
    // DataNeighbourhood), plus what the short relaxations moved them.
    for &id in &o.created {
        let x = p.positions()[p.slot_of(id).expect("live")];
        let d = data
            .iter()
            .map(|q| (q - x).norm())
            .fold(Real::INFINITY, Real::min);
        assert!(d < 1.8, "created particle {id} is {d} from the data");
    }

    let (built, summary) = run(&scene, "closed");
    let (m, r0) = mesh(&built, &data);
    print_figures("10", summary.objects[0].particles, &m, r0);
    assert_eq!(m.boundary_loops, 0, "{} boundary loops", m.boundary_loops);
    assert_eq!(m.euler_characteristic, 2);
    assert!(
        m.rms_distance < 0.1 * r0,
        "sample RMS distance {} vs r0 {r0}",
        m.rms_distance
    );
    let centre = data.iter().fold(Vec3::zeros(), |s, q| s + q.coords) / data.len() as Real;
    let inward = m
        .vertices
        .iter()
        .zip(&m.normals)
        .filter(|(v, n)| n.dot(&(v.coords - centre)) <= 0.0)
        .count();
    assert_eq!(inward, 0, "normals pointing inward");
    // The seeds are free after the release: they drifted, a little.
    assert!(summary.objects[0].rest_shape_error_final > 0.0);
    assert!(summary.objects[0].rest_shape_error_final < 0.5);
}

/// Fig. 11: the open saddle keeps its hole (no particle near its centre,
/// two boundary loops: the rim and the hole, χ = 0) and every other gap,
/// at most the search range wide, is closed: the samples lie within 0.1
/// r0 (RMS) of the mesh, none farther than r0 / 4.
#[test]
fn fig_11_open_interpolation_keeps_the_hole_and_covers_the_rest() {
    println!("claim: {}", claim("fig_11_open_interpolation"));
    let scene = load("fig_11_open_interpolation");
    let data = samples("fig_11_saddle.xyz");
    let (built, summary) = run(&scene, "open");
    let (m, r0) = mesh(&built, &data);
    print_figures("11", summary.objects[0].particles, &m, r0);
    assert_eq!(m.boundary_loops, 2, "{} boundary loops", m.boundary_loops);
    assert_eq!(m.euler_characteristic, 0);
    assert!(m.rms_distance < 0.1 * r0, "RMS {}", m.rms_distance);
    assert!(m.max_distance < 0.25 * r0, "largest {}", m.max_distance);
    // The hole: radius 3.5 about (3, 1) in x-y; particles are created at
    // most d_max / 2 = 1.25 r0 from a sample.
    let p = built.world().particles();
    let nearest = p
        .positions()
        .iter()
        .map(|x| (x.x - 3.0).hypot(x.y - 1.0))
        .fold(Real::INFINITY, Real::min);
    assert!(nearest > 2.0, "a particle {nearest} from the hole's centre");
    assert!(built.objects()[0].created.len() > 2 * data.len());
}

/// The fig. 11 scene through `opsim run` gives the same frames, byte for
/// byte, with 1 and 2 worker threads (creation, release and triangulation
/// included).
#[test]
fn fit_scene_frames_are_identical_at_one_and_two_threads() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fig_11_open_interpolation.ron");
    let root = std::env::temp_dir().join(format!("opsim-fit-threads-{}", std::process::id()));
    let mut last = Vec::new();
    for threads in ["1", "2"] {
        let out = root.join(threads);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_opsim"))
            .arg("run")
            .arg(&scene)
            .args(["--frames", "26", "--threads", threads, "--out"])
            .arg(&out)
            .output()
            .expect("run opsim");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut frame = Vec::new();
        for e in std::fs::read_dir(out.join("frames")).expect("frames") {
            let folder = e.expect("entry").path();
            let stem = folder.file_name().unwrap().to_string_lossy().into_owned();
            let file = folder.join(format!("{stem}_00025.obj"));
            frame.push((stem, std::fs::read(file).expect("frame 25")));
        }
        frame.sort();
        last.push(frame);
    }
    let _ = std::fs::remove_dir_all(&root);
    assert_eq!(last[0], last[1]);
}

/// A scene around `fit` (and creation rules `rules`) for the validation
/// checks.
fn fit_scene(fit: &str, rules: &str) -> String {
    // `, world_settle: x` at the end of `fit` sets the settle phase.
    let (fit, settle) = fit.split_once(", world_settle: ").unwrap_or((fit, "0"));
    format!(
        r#"(
        name: "bad_fit",
        world: (duration: 2, settle: {settle}),
        materials: {{"m": (spacing: Cohesion((r0: 1, cutoff: 1.5)))}},
        objects: [(name: "samples", material: "m",
                   generator: HexSheet(nx: 4, ny: 4, spacing: 2))],
        creation: Some(({rules}, fit: Some({fit}))),
    )"#
    )
}

#[test]
fn bad_fit_sections_are_rejected_naming_the_field() {
    let stretch = "stretching: Some((d_min: 2.0, d_max: 2.5))";
    let grow = "stretching: Some((d_min: 2.0, d_max: 2.5)), growing: Some(())";
    for (fit, rules, needles) in [
        (
            r#"(object: "sample", release: 1)"#,
            stretch,
            &["bad.ron: creation.fit.object = \"sample\"", "\"samples\""][..],
        ),
        (
            r#"(object: "samples", release: 2)"#,
            stretch,
            &["creation.fit.release = 2", "below world.duration = 2"][..],
        ),
        (
            r#"(object: "samples", release: -1)"#,
            stretch,
            &["creation.fit.release = -1"][..],
        ),
        (
            r#"(object: "samples", release: 1), world_settle: 1"#,
            stretch,
            &["world.settle = 1: must be 0 with `creation.fit`"][..],
        ),
        (
            r#"(object: "samples", release: 1)"#,
            "growing: Some(())",
            &["creation.stretching", "search range"][..],
        ),
        (
            r#"(object: "samples", release: 1, open: true)"#,
            grow,
            &["creation.growing", "open"][..],
        ),
    ] {
        let e = parse_scene(&fit_scene(fit, rules), Format::Ron, "bad.ron")
            .unwrap_err()
            .to_string();
        for n in needles {
            assert!(e.contains(n), "{e} / {n}");
        }
    }
    let e = parse_scene(
        &fit_scene(r#"(object: "samples", release: 1, opne: true)"#, stretch),
        Format::Ron,
        "typo.ron",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("typo.ron:") && e.contains("opne"), "{e}");
    // A valid one builds: the samples are fixed, the others are not.
    let scene = parse_scene(
        &fit_scene(r#"(object: "samples", release: 1)"#, grow),
        Format::Ron,
        "ok.ron",
    )
    .unwrap();
    let built = scene.build(None, None).unwrap();
    let p = built.world().particles();
    assert!(p
        .flags()
        .iter()
        .all(|f| f.contains(Flags::FIXED_POSITION) && f.contains(Flags::FIXED_ORIENTATION)));
}
