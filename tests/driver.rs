//! The simulation driver composes every stage (issue: one simulation
//! driver): a skinned sheet with creation, heat, an eraser and an obstacle
//! runs to the end with its skin in every frame; the skin gains the
//! primitives of created particles and loses those of erased ones, so the
//! eraser's cut is a slot in the skin.

use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The vertices of each OBJ object of a frame, by object name.
fn objects(frame: &Path) -> std::collections::HashMap<String, Vec<[f64; 3]>> {
    let mut out = std::collections::HashMap::new();
    let mut current = String::new();
    for line in std::fs::read_to_string(frame).unwrap().lines() {
        if let Some(name) = line.strip_prefix("o ") {
            current = name.to_string();
        } else if let Some(v) = line.strip_prefix("v ") {
            let c: Vec<f64> = v.split_whitespace().map(|x| x.parse().unwrap()).collect();
            out.entry(current.clone())
                .or_insert_with(Vec::new)
                .push([c[0], c[1], c[2]]);
        }
    }
    out
}

#[test]
fn a_skinned_sheet_with_creation_heat_eraser_and_obstacle_runs_with_its_skin() {
    let path = repo().join("tests/data/skinned_cut.ron");
    let mut built = op_scene::build_scene_file(&path).expect("the scene builds");
    let out = std::env::temp_dir().join(format!("opsim-driver-{}", std::process::id()));
    let opts = op_scene::RunOptions {
        out_dir: out.clone(),
        frames: None,
        formats: vec![op_scene::export::FrameFormat::OBJ],
        ..Default::default()
    };
    let summary = op_scene::run(&mut built, &opts, &mut |_, _| {}).expect("runs to the end");
    assert!(!summary.diverged);
    let o = &summary.objects[0];
    assert!(o.created > 10, "creation made {} particles", o.created);
    assert_eq!(o.pieces, Some(2), "the eraser cuts the sheet in two");
    for stage in [
        "creation",
        "contact",
        "skin",
        "heat",
        "bonds",
        "plasticity",
        "erase",
        "integrate",
        "export",
    ] {
        assert!(
            summary.stages.contains_key(stage),
            "{stage}: {:?}",
            summary.stages
        );
    }
    // The skin follows the particle set: one primitive per live particle of
    // the object, created ones included, erased ones gone.
    let skin = &built.skins()[0].skin;
    assert_eq!(skin.attachments().len(), o.particles);
    let p = built.world().particles();
    assert!(skin
        .attachments()
        .iter()
        .all(|(id, _)| p.slot_of(*id).is_some()));

    // The skin's own sequence: frames/sheet_skin/sheet_skin_00000.obj, ...
    let mut frames: Vec<PathBuf> = std::fs::read_dir(out.join("frames/sheet_skin"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    frames.sort();
    assert_eq!(frames.len(), summary.frames);
    for f in &frames {
        let skin = objects(f).remove("sheet_skin").unwrap_or_default();
        assert!(
            skin.len() > 1000,
            "{}: skin of {} vertices",
            f.display(),
            skin.len()
        );
    }
    // The knife swept x = 3 (half width 0.9) until t = 1.5: at the end the
    // skin has a slot there, with skin on both sides (OBJ x is scene x).
    let skin = objects(frames.last().unwrap())
        .remove("sheet_skin")
        .unwrap();
    let in_slot = skin.iter().filter(|v| (v[0] - 3.0).abs() < 0.3).count();
    assert_eq!(in_slot, 0, "skin vertices in the slot");
    assert!(skin.iter().filter(|v| v[0] < 2.0).count() > 100);
    assert!(skin.iter().filter(|v| v[0] > 4.0).count() > 100);
    let _ = std::fs::remove_dir_all(&out);
}

/// `outputs.particles: None` leaves out the particles, not the skin: a
/// skinned sheet still writes its skin in every frame (found by a new
/// user, whose run wrote nothing).
#[test]
fn a_skin_is_written_without_particle_output() {
    let text = r#"(
        name: "skin_only",
        world: (dt: 0.005, duration: 0.1, frame_rate: 10),
        objects: [(
            name: "cloth",
            material: "cloth",
            generator: HexSheet(nx: 6, ny: 6, spacing: 1),
            skin: Some((primitive: Square(half_side: 0.5), radius: 1.2, cell_size: 0.25)),
        )],
        outputs: (particles: None),
    )"#;
    let scene = op_scene::parse_scene(text, op_scene::Format::Ron, "skin_only.ron").unwrap();
    let mut built = scene.build(None, None).expect("the scene builds");
    let out = std::env::temp_dir().join(format!("opsim-skin-only-{}", std::process::id()));
    let opts = op_scene::RunOptions {
        out_dir: out.clone(),
        frames: None,
        formats: vec![op_scene::export::FrameFormat::OBJ],
        ..Default::default()
    };
    let summary = op_scene::run(&mut built, &opts, &mut |_, _| {}).expect("runs");
    let dirs: Vec<String> = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        dirs,
        ["cloth_skin"],
        "no particle sequence, one skin sequence"
    );
    let frames: Vec<PathBuf> = std::fs::read_dir(out.join("frames/cloth_skin"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    assert_eq!(frames.len(), summary.frames);
    assert!(out
        .join("frames/cloth_skin/cloth_skin.obj.series")
        .is_file());
    for frame in &frames {
        let skin = objects(frame).remove("cloth_skin").unwrap_or_default();
        assert!(skin.len() > 100, "a skin of {} vertices", skin.len());
    }
    let _ = std::fs::remove_dir_all(&out);
}
