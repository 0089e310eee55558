//! The JSON Schema `opsim schema` prints describes the format the reader
//! accepts: every shipped scene, written as JSON, validates against it, and
//! the mistakes a user makes (a misspelt field, a missing required field, a
//! wrong type) are caught by an editor using it.

use std::path::Path;

use op_scene::reference::json_schema;

fn validator() -> jsonschema::Validator {
    jsonschema::validator_for(&json_schema()).expect("the scene schema is a valid JSON Schema")
}

fn shipped_scenes() -> Vec<std::path::PathBuf> {
    op_test_support::scene_files_under(&[op_test_support::scenes_dir()])
}

#[test]
fn every_shipped_scene_validates_as_json() {
    let v = validator();
    let scenes = shipped_scenes();
    assert!(scenes.len() > 30, "found only {} scenes", scenes.len());
    let mut failures = Vec::new();
    for path in &scenes {
        let scene =
            op_scene::load_scene(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let json = serde_json::to_value(&scene).unwrap();
        let errors: Vec<String> = v
            .iter_errors(&json)
            .map(|e| format!("{} at {}", e, e.instance_path()))
            .collect();
        if !errors.is_empty() {
            failures.push(format!("{}: {}", path.display(), errors.join("; ")));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_json_demo_file_validates_as_written() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/chain.json");
    let text = std::fs::read_to_string(path).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(validator().is_valid(&json));
}

#[test]
fn common_mistakes_are_caught() {
    let v = validator();
    let good = serde_json::json!({
        "name": "ball",
        "materials": {"elastic": {"coplanarity": 10}},
        "objects": [{"name": "ball", "material": "elastic",
                     "generator": {"SphereShell": {"radius": 3, "spacing": 1}}}]
    });
    assert!(
        v.is_valid(&good),
        "{:?}",
        v.iter_errors(&good)
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
    );
    let mut misspelt = good.clone();
    misspelt["materials"]["elastic"]["coplanarty"] = 10.into();
    assert!(!v.is_valid(&misspelt), "a misspelt material field passes");
    let mut missing = good.clone();
    missing.as_object_mut().unwrap().remove("objects");
    assert!(!v.is_valid(&missing), "a scene without objects passes");
    let mut wrong_type = good.clone();
    wrong_type["objects"][0]["mass"] = "heavy".into();
    assert!(!v.is_valid(&wrong_type), "a string mass passes");
    let mut unknown_variant = good;
    unknown_variant["objects"][0]["generator"] = serde_json::json!({"Cube": {"side": 3}});
    assert!(!v.is_valid(&unknown_variant), "an unknown generator passes");
}

/// `world.linear_damping` is a number >= 0 or the string `"Critical"`
/// (`op_scene::Damping`), in the schema as in the reader.
#[test]
fn linear_damping_is_a_number_or_critical() {
    let v = validator();
    let scene = |damping: serde_json::Value| {
        serde_json::json!({
            "name": "chain",
            "world": {"linear_damping": damping},
            "materials": {"lj": {"spacing": {"LennardJones": {"cutoff": 1.5}}}},
            "objects": [{"name": "c", "material": "lj",
                         "generator": {"Chain": {"count": 3, "spacing": 1}}}]
        })
    };
    for good in [
        serde_json::json!(0.3),
        serde_json::json!(0),
        serde_json::json!("Critical"),
    ] {
        assert!(v.is_valid(&scene(good.clone())), "{good} refused");
        let text = scene(good.clone()).to_string();
        op_scene::parse_scene(&text, op_scene::Format::Json, "<test>")
            .unwrap_or_else(|e| panic!("{good}: {e}"));
    }
    for bad in [
        serde_json::json!(-1),
        serde_json::json!("critical"),
        serde_json::json!(null),
    ] {
        assert!(!v.is_valid(&scene(bad.clone())), "{bad} passes the schema");
    }
}
