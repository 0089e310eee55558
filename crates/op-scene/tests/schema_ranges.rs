//! The JSON Schema `opsim schema` prints and the validation `opsim check`
//! runs ([`op_scene::parse_scene`]: the reader, then `Scene::validate`)
//! agree on single-field mistakes: each broken scene below differs from a
//! valid one in one field, `check` refuses every one of them, and the
//! schema refuses every one it can express. The few that only `check`
//! catches (rules between fields, or beyond what JSON Schema states) form
//! a fixed list, [`check_only_mistakes`], the one docs/scenes.md gives: the test
//! fails when the schema stops catching a mistake, and when it starts
//! catching one of the listed (then the list and the docs shrink).
//!
//! Values that `check` accepts at the edges of the ranges pass the schema
//! too, and so does every scene and object name `check` accepts.

use op_scene::reference::json_schema;
use op_scene::{parse_scene, Format};
use serde_json::{json, Value};
use Edit::{Remove, Set};

fn validator() -> jsonschema::Validator {
    jsonschema::validator_for(&json_schema()).expect("the scene schema is a valid JSON Schema")
}

/// A valid scene touching the fields the cases break: two objects, two
/// materials (Lennard-Jones and cohesion), a skin, a force window, a tool
/// with a keyframed path, creation rules with a fit, a wind and a speed
/// clamp, and outputs with a view.
fn base() -> Value {
    json!({
        "name": "probe",
        "world": {
            "dt": 1e-3, "duration": 1, "frame_rate": 10, "gravity": [0, 0, -1],
            "angular_damping": 0.1,
            "neighbours": {"skin": 0.2},
            "divergence": {"energy_growth": 1e6}
        },
        "materials": {
            "lj": {"spacing": {"LennardJones": {"r0": 1, "cutoff": 2.5, "taper": 0.2}},
                   "coplanarity": 1, "friction": 0.1},
            "co": {"spacing": {"Cohesion": {"r0": 1, "table_start": 0.5, "table_nodes": 1024}}}
        },
        "objects": [
            {"name": "chain", "material": "lj",
             "generator": {"Chain": {"count": 5, "spacing": 1, "direction": [1, 0, 0]}},
             "mass": 1, "inertia": [0.1, 0.1, 0.1], "normal_axis": [0, 0, 1],
             "overrides": [{"particles": {"First": 1}, "mass": 2}]},
            {"name": "sheet", "material": "co",
             "generator": {"HexSheet": {"nx": 3, "ny": 3, "spacing": 1, "center": [0, 0, 5],
                                        "noise": 0.1}},
             "velocities": {"Temperature": {"t": 1, "seed": 7}},
             "skin": {"primitive": {"Square": {"half_side": 0.5}}, "radius": 0.8,
                      "cell_size": 0.25, "stiffness": 100, "smoothness": 1.5,
                      "thickness": 0.3, "smoothing": 2}}
        ],
        "forces": [
            {"object": "chain", "particles": {"Last": 1}, "force": [0, 1, 0],
             "start": 0, "end": 1, "ramp": 0.1}
        ],
        "tools": [
            {"shape": {"Plane": {"normal": [0, 0, 1]}},
             "role": {"Obstacle": {"stiffness": 100, "damping": 1}},
             "path": [{"time": 0, "position": [0, 0, -1]}, {"time": 1, "position": [0, 0, -2]}]}
        ],
        "creation": {
            "spacing": 1, "interval": 10, "max_particles": 1000,
            "stretching": {"d_min": 2, "d_max": 2.5, "reach": 1.5, "max_normal_angle": 1.5},
            "growing": {"radius": 1.5, "min_gap": 1.7, "max_gap": 6, "clearance": 0.7},
            "merging": {"distance": 0.3},
            "fit": {"object": "chain", "release": 0.5}
        },
        "features": [
            {"Wind": {"velocity": [1, 0, 0], "drag": 0.1,
                      "gusts": [{"time": 0, "velocity": [0, 0, 1]}]}},
            {"SpeedClamp": {"max_speed": 5}}
        ],
        "outputs": {"glyph_size": 0.4, "view": [0, -1, 0]}
    })
}

/// One change to [`base`]: set the field at a JSON pointer (adding it when
/// its parent is an object), or remove it.
enum Edit {
    Set(&'static str, Value),
    Remove(&'static str),
}

fn apply(scene: &mut Value, edit: &Edit) {
    let (pointer, value) = match edit {
        Edit::Set(p, v) => (*p, Some(v.clone())),
        Edit::Remove(p) => (*p, None),
    };
    let (parent, key) = pointer.rsplit_once('/').unwrap();
    let parent = scene
        .pointer_mut(parent)
        .unwrap_or_else(|| panic!("{pointer}: no such parent"));
    match (parent, value) {
        (Value::Object(m), Some(v)) => {
            m.insert(key.to_string(), v);
        }
        (Value::Object(m), None) => {
            m.remove(key)
                .unwrap_or_else(|| panic!("{pointer}: nothing to remove"));
        }
        (Value::Array(a), Some(v)) => a[key.parse::<usize>().unwrap()] = v,
        _ => panic!("{pointer}: cannot edit"),
    }
}

/// A broken scene: the mistake's name and the edit that makes it.
type Case = (&'static str, Edit);

/// Mistakes of the world and the materials, one field each, which the
/// schema catches: first those of shape (the schema caught them before
/// it stated ranges), then ranges.
fn world_and_material_mistakes() -> Vec<Case> {
    vec![
        ("misspelt field", Set("/materials/lj/frictoin", json!(0.1))),
        ("wrong type", Set("/objects/0/mass", json!("heavy"))),
        (
            "unknown generator",
            Set("/objects/0/generator", json!({"Cube": {"side": 3}})),
        ),
        (
            "unknown integrator",
            Set("/world/integrator", json!("Leapfrog")),
        ),
        ("missing generator", Remove("/objects/0/generator")),
        ("missing objects", Remove("/objects")),
        (
            "gravity of two components",
            Set("/world/gravity", json!([0, -9.8])),
        ),
        // Ranges of one field.
        ("negative dt", Set("/world/dt", json!(-1))),
        ("zero dt", Set("/world/dt", json!(0))),
        ("zero frame_rate", Set("/world/frame_rate", json!(0))),
        ("zero duration", Set("/world/duration", json!(0))),
        ("negative settle", Set("/world/settle", json!(-1))),
        (
            "negative angular_damping",
            Set("/world/angular_damping", json!(-0.5)),
        ),
        (
            "negative linear_damping",
            Set("/world/linear_damping", json!(-1)),
        ),
        ("zero skin", Set("/world/neighbours/skin", json!(0))),
        ("skin above 10", Set("/world/neighbours/skin", json!(11))),
        (
            "zero energy_growth",
            Set("/world/divergence/energy_growth", json!(0)),
        ),
        (
            "zero max_speed",
            Set("/world/divergence/max_speed", json!(0)),
        ),
        (
            "negative friction",
            Set("/materials/lj/friction", json!(-0.1)),
        ),
        (
            "negative coplanarity",
            Set("/materials/lj/coplanarity", json!(-1)),
        ),
        (
            "zero Lennard-Jones r0",
            Set("/materials/lj/spacing/LennardJones/r0", json!(0)),
        ),
        (
            "zero Lennard-Jones taper",
            Set("/materials/lj/spacing/LennardJones/taper", json!(0)),
        ),
        (
            "taper above 1",
            Set("/materials/lj/spacing/LennardJones/taper", json!(1.5)),
        ),
        (
            "zero cohesion alpha",
            Set("/materials/co/spacing/Cohesion/alpha", json!(0)),
        ),
        (
            "negative cohesion cutoff",
            Set("/materials/co/spacing/Cohesion/cutoff", json!(-1)),
        ),
        (
            "table_start of 1",
            Set("/materials/co/spacing/Cohesion/table_start", json!(1)),
        ),
        (
            "8 table nodes",
            Set("/materials/co/spacing/Cohesion/table_nodes", json!(8)),
        ),
    ]
}

/// Mistakes of names, objects, forces, tools and outputs, one field each,
/// which the schema catches.
fn object_mistakes() -> Vec<Case> {
    vec![
        ("empty scene name", Set("/name", json!(""))),
        ("scene name with a slash", Set("/name", json!("a/b"))),
        ("scene name with a backslash", Set("/name", json!("a\\b"))),
        ("scene name ..", Set("/name", json!(".."))),
        ("scene name with a newline", Set("/name", json!("a\nb"))),
        ("empty object name", Set("/objects/0/name", json!(""))),
        (
            "object name with a control character",
            Set("/objects/0/name", json!("a\u{7}")),
        ),
        ("zero mass", Set("/objects/0/mass", json!(0))),
        (
            "zero inertia component",
            Set("/objects/0/inertia", json!([0.1, 0, 0.1])),
        ),
        (
            "zero normal_axis",
            Set("/objects/0/normal_axis", json!([0, 0, 0])),
        ),
        (
            "zero chain count",
            Set("/objects/0/generator/Chain/count", json!(0)),
        ),
        (
            "zero chain spacing",
            Set("/objects/0/generator/Chain/spacing", json!(0)),
        ),
        (
            "zero chain direction",
            Set("/objects/0/generator/Chain/direction", json!([0, 0, 0])),
        ),
        (
            "zero sheet rows",
            Set("/objects/1/generator/HexSheet/ny", json!(0)),
        ),
        (
            "negative sheet noise",
            Set("/objects/1/generator/HexSheet/noise", json!(-0.1)),
        ),
        (
            "zero sheet normal",
            Set("/objects/1/generator/HexSheet/normal", json!([0, 0, 0])),
        ),
        (
            "zero sphere radius",
            Set(
                "/objects/1/generator",
                json!({"SphereShell": {"radius": 0, "spacing": 1}}),
            ),
        ),
        (
            "empty particle list",
            Set("/objects/1/generator", json!({"List": {"particles": []}})),
        ),
        (
            "zero override mass",
            Set("/objects/0/overrides/0/mass", json!(0)),
        ),
        (
            "selection First(0)",
            Set("/objects/0/overrides/0/particles", json!({"First": 0})),
        ),
        (
            "empty selection list",
            Set("/objects/0/overrides/0/particles", json!({"List": []})),
        ),
        (
            "negative temperature",
            Set("/objects/1/velocities/Temperature/t", json!(-1)),
        ),
        ("negative ramp", Set("/forces/0/ramp", json!(-1))),
        (
            "zero plane normal",
            Set("/tools/0/shape/Plane/normal", json!([0, 0, 0])),
        ),
        (
            "zero ball radius",
            Set("/tools/0/shape", json!({"Ball": {"radius": 0}})),
        ),
        (
            "zero obstacle stiffness",
            Set("/tools/0/role/Obstacle/stiffness", json!(0)),
        ),
        (
            "negative obstacle damping",
            Set("/tools/0/role/Obstacle/damping", json!(-1)),
        ),
        ("zero glyph_size", Set("/outputs/glyph_size", json!(0))),
        ("zero view", Set("/outputs/view", json!([0, 0, 0]))),
    ]
}

/// Mistakes of skins, creation rules, the fit and the features, one field
/// each, which the schema catches.
fn skin_creation_and_feature_mistakes() -> Vec<Case> {
    let skin = |field: &'static str, v: Value| -> Edit {
        let pointer: &'static str = Box::leak(format!("/objects/1/skin/{field}").into_boxed_str());
        Set(pointer, v)
    };
    vec![
        ("zero skin radius", skin("radius", json!(0))),
        ("zero skin cell_size", skin("cell_size", json!(0))),
        ("negative skin stiffness", skin("stiffness", json!(-1))),
        ("skin smoothness below 1", skin("smoothness", json!(0.5))),
        ("skin smoothness above 4", skin("smoothness", json!(5))),
        ("zero skin thickness", skin("thickness", json!(0))),
        ("101 smoothing iterations", skin("smoothing", json!(101))),
        (
            "negative square half_side",
            skin("primitive", json!({"Square": {"half_side": -0.5}})),
        ),
        ("zero creation spacing", Set("/creation/spacing", json!(0))),
        (
            "zero creation interval",
            Set("/creation/interval", json!(0)),
        ),
        (
            "zero max_particles",
            Set("/creation/max_particles", json!(0)),
        ),
        ("zero d_min", Set("/creation/stretching/d_min", json!(0))),
        ("zero reach", Set("/creation/stretching/reach", json!(0))),
        (
            "max_normal_angle above pi",
            Set("/creation/stretching/max_normal_angle", json!(3.5)),
        ),
        (
            "zero growing radius",
            Set("/creation/growing/radius", json!(0)),
        ),
        ("zero min_gap", Set("/creation/growing/min_gap", json!(0))),
        (
            "max_gap above 2 pi",
            Set("/creation/growing/max_gap", json!(7)),
        ),
        (
            "clearance above 1",
            Set("/creation/growing/clearance", json!(1.5)),
        ),
        (
            "merging distance 1",
            Set("/creation/merging/distance", json!(1)),
        ),
        (
            "negative fit release",
            Set("/creation/fit/release", json!(-1)),
        ),
        ("zero wind drag", Set("/features/0/Wind/drag", json!(0))),
        (
            "negative clamp speed",
            Set("/features/1/SpeedClamp/max_speed", json!(-5)),
        ),
    ]
}

/// The mistakes only `check` catches (rules between fields, and a
/// tolerance): what docs/scenes.md lists under "What the JSON Schema
/// checks and what only `opsim check` checks".
fn check_only_mistakes() -> Vec<Case> {
    let mut cases = check_only_scene_mistakes();
    cases.extend(check_only_creation_and_tool_mistakes());
    cases
}

/// The check-only mistakes of the world, materials, objects, forces,
/// outputs and skins.
fn check_only_scene_mistakes() -> Vec<Case> {
    vec![
        ("dt above the frame interval", Set("/world/dt", json!(0.2))),
        (
            "Lennard-Jones taper starting below r0",
            Set("/materials/lj/spacing/LennardJones/cutoff", json!(0.9)),
        ),
        (
            "Lennard-Jones n not above m",
            Set("/materials/lj/spacing/LennardJones/n", json!(5)),
        ),
        (
            "cohesion cutoff beyond 1000 r0",
            Set("/materials/co/spacing/Cohesion/cutoff", json!(2000)),
        ),
        (
            "cohesion alpha r0^2 above 1e6",
            Set("/materials/co/spacing/Cohesion/alpha", json!(2e6)),
        ),
        (
            "unknown material",
            Set("/objects/0/material", json!("steel")),
        ),
        (
            "duplicate object name",
            Set("/objects/1/name", json!("chain")),
        ),
        (
            "nearly zero normal_axis",
            Set("/objects/0/normal_axis", json!([1e-13, 0, 0])),
        ),
        (
            "sheet noise above spacing/4",
            Set("/objects/1/generator/HexSheet/noise", json!(0.3)),
        ),
        (
            "sheet of more than 1e7 particles",
            Set("/objects/1/generator/HexSheet/nx", json!(4_000_000)),
        ),
        (
            "force on an unknown object",
            Set("/forces/0/object", json!("rope")),
        ),
        (
            "selection beyond the object",
            Set("/forces/0/particles", json!({"Last": 6})),
        ),
        (
            "force ending before it starts",
            Set("/forces/0/end", json!(-1)),
        ),
        (
            "ramp above half the window",
            Set("/forces/0/ramp", json!(0.6)),
        ),
        ("up parallel to view", Set("/outputs/up", json!([0, -2, 0]))),
        (
            "skin radius below its cell size",
            Set("/objects/1/skin/radius", json!(0.2)),
        ),
        (
            "skin thickness below half a cell",
            Set("/objects/1/skin/thickness", json!(0.1)),
        ),
    ]
}

/// The check-only mistakes of the creation rules, tools and features.
fn check_only_creation_and_tool_mistakes() -> Vec<Case> {
    vec![
        (
            "d_max below d_min",
            Set("/creation/stretching/d_max", json!(1.5)),
        ),
        (
            "reach not above d_max / 2",
            Set("/creation/stretching/reach", json!(1)),
        ),
        (
            "max_neighbours below min_neighbours",
            Set("/creation/growing/min_neighbours", json!(6)),
        ),
        (
            "max_gap below min_gap",
            Set("/creation/growing/max_gap", json!(1)),
        ),
        (
            "creation without a rule",
            Set("/creation", json!({"interval": 10})),
        ),
        (
            "fit of an unknown object",
            Set("/creation/fit/object", json!("rope")),
        ),
        (
            "fit released after the run",
            Set("/creation/fit/release", json!(2)),
        ),
        (
            "tool keyframes out of order",
            Set("/tools/0/path/1/time", json!(0)),
        ),
        (
            "gusts out of order",
            Set(
                "/features/0/Wind/gusts",
                json!([{"time": 1, "velocity": [0, 0, 1]}, {"time": 0, "velocity": [0, 0, 1]}]),
            ),
        ),
    ]
}

/// `check`'s verdict: the reader and `Scene::validate`, as `opsim check`
/// runs them.
fn check(scene: &Value) -> Result<(), String> {
    parse_scene(&scene.to_string(), Format::Json, "<case>")
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn schema_errors(v: &jsonschema::Validator, scene: &Value) -> Vec<String> {
    v.iter_errors(scene)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect()
}

#[test]
fn the_base_scene_is_valid_for_both() {
    let scene = base();
    check(&scene).unwrap();
    assert_eq!(schema_errors(&validator(), &scene), Vec::<String>::new());
}

#[test]
fn the_schema_catches_every_single_field_mistake_it_can_state() {
    let v = validator();
    let mut only_check = Vec::new();
    let mut passes_check = Vec::new();
    let mut caught = 0;
    let expected: Vec<&str> = check_only_mistakes().iter().map(|c| c.0).collect();
    let mut cases = world_and_material_mistakes();
    cases.extend(object_mistakes());
    cases.extend(skin_creation_and_feature_mistakes());
    cases.extend(check_only_mistakes());
    for (name, edit) in &cases {
        let mut scene = base();
        apply(&mut scene, edit);
        if check(&scene).is_ok() {
            passes_check.push(*name);
        }
        if v.is_valid(&scene) {
            only_check.push(*name);
        } else {
            caught += 1;
        }
    }
    assert!(passes_check.is_empty(), "check accepts {passes_check:?}");
    println!(
        "{} broken scenes: the schema catches {caught}, only check catches {}:",
        cases.len(),
        only_check.len()
    );
    for name in &only_check {
        println!("  {name}");
    }
    assert_eq!(only_check, expected);
}

/// Values at the edges of the ranges, which `check` accepts: the schema
/// must too.
#[test]
fn values_check_accepts_at_the_edges_pass_the_schema() {
    let v = validator();
    let edges = [
        Set("/world/settle", json!(0)),
        Set("/world/angular_damping", json!(0)),
        Set("/world/linear_damping", json!(0)),
        Set("/world/dt", json!(0.1)),
        Set("/world/neighbours/skin", json!(10)),
        Set("/materials/lj/friction", json!(0)),
        Set("/materials/lj/coplanarity", json!(0)),
        Set("/materials/co/spacing/Cohesion/table_nodes", json!(16)),
        Set(
            "/materials/co/spacing/Cohesion/table_nodes",
            json!(1_000_000),
        ),
        Set("/name", json!("a.b")),
        Set("/name", json!("...")),
        Set("/name", json!(" ")),
        Set("/name", json!("名前")),
        Set("/objects/1/name", json!("a/b")),
        Set("/objects/1/name", json!("..")),
        Set("/objects/0/generator/Chain/count", json!(1)),
        Set("/objects/0/normal_axis", json!([1e-9, 0, 0])),
        Set("/objects/0/overrides/0/particles", json!({"Last": 5})),
        Set("/objects/1/generator/HexSheet/noise", json!(0)),
        Set("/objects/1/generator/HexSheet/noise", json!(0.25)),
        Set("/objects/1/velocities/Temperature/t", json!(0)),
        Set("/forces/0/ramp", json!(0)),
        Set("/forces/0/ramp", json!(0.5)),
        Set("/tools/0/shape/Plane/normal", json!([0, 0, -1e-100])),
        Set("/tools/0/role/Obstacle/damping", json!(0)),
        Set("/outputs/view", json!([0, 0, 1e-6])),
        Set("/objects/1/skin/smoothness", json!(1)),
        Set("/objects/1/skin/smoothness", json!(4)),
        Set("/objects/1/skin/smoothing", json!(100)),
        Set("/objects/1/skin/stiffness", json!(0)),
        Set("/objects/1/skin/thickness", json!(0.125)),
        Set(
            "/objects/1/skin/primitive",
            json!({"Square": {"half_side": 0}}),
        ),
        Set("/creation/interval", json!(1)),
        Set("/creation/max_particles", json!(1)),
        Set(
            "/creation/stretching/max_normal_angle",
            json!(std::f64::consts::PI),
        ),
        Set("/creation/growing/max_gap", json!(std::f64::consts::TAU)),
        Set("/creation/growing/clearance", json!(1)),
        Set("/creation/merging/distance", json!(0.999)),
        Set("/creation/fit/release", json!(0)),
    ];
    for edit in &edges {
        let mut scene = base();
        apply(&mut scene, edit);
        let Set(pointer, value) = edit else {
            unreachable!()
        };
        check(&scene).unwrap_or_else(|e| panic!("{pointer} = {value}: check refuses: {e}"));
        let errors = schema_errors(&v, &scene);
        assert!(errors.is_empty(), "{pointer} = {value}: {errors:?}");
    }
}

/// The name patterns are `check`'s rules exactly: for every character of
/// the first planes' start (and some beyond), a scene or object name
/// holding it passes the schema exactly when `check` accepts it.
#[test]
fn name_patterns_agree_with_check_character_by_character() {
    let v = validator();
    let chars = (0u32..0x3000)
        .chain([0xFEFF, 0xFFFD, 0x1F600, 0x10FFFF])
        .filter_map(char::from_u32);
    let mut disagree = Vec::new();
    for c in chars {
        for (pointer, name) in [
            ("/name", format!("a{c}b")),
            ("/objects/0/name", format!("{c}")),
        ] {
            let mut scene = json!({
                "name": "n",
                "materials": {"lj": {"spacing": {"LennardJones": {"cutoff": 1.5}}}},
                "objects": [{"name": "o", "material": "lj",
                             "generator": {"Chain": {"count": 2, "spacing": 1}}}]
            });
            *scene.pointer_mut(pointer).unwrap() = json!(name);
            if v.is_valid(&scene) != check(&scene).is_ok() {
                disagree.push(format!("{pointer} {name:?}"));
            }
        }
    }
    assert!(disagree.is_empty(), "{disagree:?}");
}

/// Every scene the project ships or tests with (scenes/ and tests/data/),
/// written as JSON, passes the schema with its ranges.
#[test]
fn every_shipped_and_test_scene_passes_the_ranges() {
    let root = op_test_support::workspace_root();
    let files = op_test_support::scene_files_under(&[root.join("scenes"), root.join("tests/data")]);
    assert!(files.len() > 40, "found only {} scenes", files.len());
    let v = validator();
    let mut failures = Vec::new();
    for path in &files {
        let scene = op_scene::load_scene(path).unwrap_or_else(|e| panic!("{e}"));
        let errors = schema_errors(&v, &serde_json::to_value(&scene).unwrap());
        if !errors.is_empty() {
            failures.push(format!("{}: {}", path.display(), errors.join("; ")));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
