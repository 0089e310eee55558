//! Surfaces in scenes (seed 000 §5, §7): the triangulation written in the
//! OBJ frames (`<object>_surface`) and drawn by the renderer, and the
//! creation rules run by the runner (created particles counted, frames
//! identical at 1 and 2 threads).

use std::path::Path;

use op_modeling::triangulation::Triangulation;
use op_render::{render, ObjData, ObjObject, RenderOptions, Style};
use op_scene::{load_scene, parse_scene, run, Format, RunOptions, Scene, Summary};
use op_test_support::temp_dir;

fn run_scene(scene: &Scene, out: &Path, frames: usize) -> Summary {
    let mut built = scene.build(None, None).unwrap_or_else(|e| panic!("{e}"));
    let opts = RunOptions {
        out_dir: out.to_path_buf(),
        frames: Some(frames),
        formats: vec![op_scene::export::FrameFormat::OBJ],
        ..Default::default()
    };
    run(&mut built, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"))
}

fn frame(out: &Path, k: usize) -> ObjData {
    op_render::read_run_frame(out, k as u64).unwrap()
}

fn object<'a>(data: &'a ObjData, name: &str) -> &'a ObjObject {
    data.objects()
        .iter()
        .find(|o| o.name() == name)
        .unwrap_or_else(|| panic!("no object {name}"))
}

/// The triangles of an OBJ object, for the topology helpers.
fn topology(o: &ObjObject) -> Triangulation {
    Triangulation {
        triangles: o.triangles().iter().map(|t| t.map(|k| k as u32)).collect(),
    }
}

/// The sphere scene's frames hold a closed, consistently oriented,
/// outward triangulation over every particle (Euler characteristic 2),
/// and the shaded and wireframe styles draw it.
#[test]
fn sphere_surface_scene_writes_a_closed_triangulation_and_renders_it() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sphere_surface.ron");
    let scene = load_scene(&path).unwrap();
    let out = temp_dir("sphere");
    let summary = run_scene(&scene, &out, 4);
    assert!(summary.enabled.contains(&"triangulation".to_string()));
    for k in [0, 3] {
        let data = frame(&out, k);
        let particles = object(&data, "ball");
        let surface = object(&data, "ball_surface");
        assert_eq!(surface.vertices().len(), particles.vertices().len());
        let t = topology(surface);
        assert_eq!(t.vertices().len(), surface.vertices().len(), "frame {k}");
        assert_eq!(t.boundary_loops(), 0, "frame {k}: closed");
        assert_eq!(t.euler_characteristic(), 2, "frame {k}");
        assert!(t.is_manifold() && t.is_consistently_oriented(), "frame {k}");
        // Outward: the enclosed volume (sum of signed tetrahedra) is positive.
        let v = |i: usize| nalgebra::Vector3::from(surface.vertices()[i]);
        let volume: f64 = surface
            .triangles()
            .iter()
            .map(|t| v(t[0]).dot(&v(t[1]).cross(&v(t[2]))) / 6.0)
            .sum();
        assert!(volume > 0.0, "frame {k}: volume {volume}");
        // Every triangle carries the particles' normals as vn.
        assert!(surface.normals().iter().all(|n| n.is_some()));
        for style in [Style::Shaded, Style::Wireframe] {
            let opts = RenderOptions {
                width: 160,
                height: 120,
                style,
                ..Default::default()
            };
            let r = render(&data, &opts).unwrap();
            assert!(
                r.notes.iter().all(|n| !n.contains("no faces")),
                "{style}: {:?}",
                r.notes
            );
        }
    }
}

const STRETCHED: &str = r#"(
    name: "stretched",
    world: (dt: 2e-3, frame_rate: 10, linear_damping: 1),
    materials: {
        "sheet": (spacing: Cohesion((e: 200, r0: 1, alpha: 16, cutoff: 1.5)), coplanarity: 2),
    },
    objects: [(name: "sheet", material: "sheet", generator: HexSheet(nx: 8, ny: 7, spacing: 2.2))],
    creation: Some((spacing: Some(1), stretching: Some(()), interval: 10)),
    outputs: (triangulation: true, triangulation_radius: 0.8),
)"#;

/// A sheet generated pulled apart (neighbours 2.2 r0 apart): the stretching
/// rule fills every edge at the start of the run; the summary counts the
/// created particles; the refined sheet triangulates as a disc; the frames
/// are the same bytes at 1 and 2 threads.
#[test]
fn stretching_in_a_scene_fills_the_gaps_deterministically() {
    let scene = parse_scene(STRETCHED, Format::Ron, "<stretched>").unwrap();
    let go = |threads: usize| {
        let out = temp_dir(&format!("stretched{threads}"));
        let summary = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run_scene(&scene, &out, 3));
        (out, summary)
    };
    let (out, summary) = go(1);
    let (nx, ny) = (8, 7);
    let edges = (nx - 1) * ny + (2 * nx - 1) * (ny - 1);
    assert_eq!(summary.objects[0].particles, nx * ny + edges);
    assert!(summary.enabled.contains(&"creation".to_string()));
    assert!(summary.objects[0].rest_shape_error_final.is_finite());
    assert_eq!(object(&frame(&out, 0), "sheet").vertices().len(), nx * ny);
    let last = frame(&out, 2);
    assert_eq!(object(&last, "sheet").vertices().len(), nx * ny + edges);
    let t = topology(object(&last, "sheet_surface"));
    assert_eq!(t.euler_characteristic(), 1);
    assert_eq!(t.boundary_loops(), 1);
    assert!(t.is_manifold() && t.is_consistently_oriented());
    let (out2, _) = go(2);
    for k in 0..3 {
        for stem in ["sheet", "sheet_surface"] {
            let name = format!("frames/{stem}/{stem}_{k:05}.obj");
            let a = std::fs::read(out.join(&name)).unwrap();
            let b = std::fs::read(out2.join(&name)).unwrap();
            assert!(a == b, "{name} differs between 1 and 2 threads");
        }
    }
}

/// The generators' closed shells, triangulated as written in frame 0:
/// a sphere has Euler characteristic 2, a torus 0 (seed 000 §5 on the
/// shapes the scenes use).
#[test]
fn generated_shells_triangulate_with_their_euler_characteristic() {
    for (generator, chi) in [
        ("SphereShell(radius: 3, spacing: 1)", 2),
        ("TorusShell(major: 6, minor: 2.5, spacing: 1)", 0),
        ("TorusShell(major: 4, minor: 1.5, spacing: 0.5)", 0),
    ] {
        let text = format!(
            r#"(
                name: "shell",
                materials: {{"m": (spacing: Cohesion((cutoff: 1.5)))}},
                objects: [(name: "shell", material: "m", generator: {generator})],
                outputs: (particles: None, triangulation: true, metrics: false),
            )"#
        );
        let scene = parse_scene(&text, Format::Ron, "<shell>").unwrap();
        let out = temp_dir("shell");
        run_scene(&scene, &out, 1);
        let data = frame(&out, 0);
        let surface = object(&data, "shell_surface");
        let t = topology(surface);
        assert_eq!(t.vertices().len(), surface.vertices().len(), "{generator}");
        assert_eq!(t.boundary_loops(), 0, "{generator}");
        assert!(t.is_manifold(), "{generator}");
        assert!(t.is_consistently_oriented(), "{generator}");
        assert_eq!(t.euler_characteristic(), chi, "{generator}");
    }
}

/// The settle phase runs the scene's stages: a skinned sheet falling onto
/// an obstacle while settling meets it through its skin (the contact
/// stage) and rests on it at frame 0 instead of falling through.
#[test]
fn obstacles_meet_skins_while_settling() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sheet_on_box.ron");
    let mut scene = load_scene(&path).unwrap();
    scene.world.settle = 4.0;
    let mut built = scene.build(path.parent(), None).unwrap();
    built.settle().unwrap();
    assert!(
        built.contact().total_impulse > 0.0,
        "contact acted while settling"
    );
    // The lowest particle above the box's top (|x| < 3, |y| < 5 at z 0):
    // the part of the sheet beyond its edge drapes down.
    let lowest = built
        .world()
        .particles()
        .positions()
        .iter()
        .filter(|p| p.x.abs() < 2.5 && p.y.abs() < 4.5)
        .map(|p| p.z)
        .fold(f64::MAX, f64::min);
    // Free fall for 4 would reach z = -6.5.
    println!("lowest particle over the box after settling: z = {lowest}");
    assert!(
        lowest > -0.5,
        "the sheet fell through the box: z = {lowest}"
    );
}
