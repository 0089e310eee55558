//! The bad-scene corpus (`tests/bad_scenes/`): every scene fails with the
//! right error (kind, location, what is wrong), and mutated example scenes
//! (hostile numbers, truncated text) give errors, never panics.

use std::path::{Path, PathBuf};

use op_test_support::scene_files;

/// The kind of error a bad scene must give.
#[derive(Debug)]
enum Expect {
    /// `SceneError::Parse` at this line and column.
    Parse(usize, usize),
    Invalid,
    Points,
    Unsupported,
    Build,
}

/// The bad-scene corpus: file, error kind, fragments the message must
/// contain.
const BAD_SCENES: &[(&str, Expect, &[&str])] = &[
    ("syntax_error.ron", Expect::Parse(4, 5), &["Expected comma"]),
    ("wrong_type.ron", Expect::Parse(7, 16), &["Expected float"]),
    (
        "wrong_type.json",
        Expect::Parse(5, 75),
        &["invalid type: string \"three\"", "expected usize"],
    ),
    (
        "unknown_field.ron",
        Expect::Parse(7, 16),
        &["colour", "expected one of", "generator"],
    ),
    (
        "unknown_field.json",
        Expect::Parse(3, 34),
        &["unknown field `timestep`", "expected one of", "`dt`"],
    ),
    (
        "unknown_generator.ron",
        Expect::Parse(5, 57),
        &["Cube", "Spiral", "HexSheet"],
    ),
    (
        "missing_field.ron",
        Expect::Parse(5, 40),
        &["missing", "generator"],
    ),
    (
        "nan_mass.ron",
        Expect::Invalid,
        &["objects[0] \"sheet\".mass = NaN: must be finite and > 0"],
    ),
    (
        "infinite_dt.ron",
        Expect::Invalid,
        &["world.dt = inf: must be finite and > 0"],
    ),
    (
        "negative_mass.ron",
        Expect::Invalid,
        &["objects[0] \"sheet\".mass = -1: must be finite and > 0"],
    ),
    (
        "negative_spacing.ron",
        Expect::Invalid,
        &["objects[1] \"sheet\".generator.HexSheet.spacing = -0.5: must be finite and > 0"],
    ),
    (
        "zero_radius.ron",
        Expect::Invalid,
        &["generator.SphereShell.radius = 0: must be finite and > 0"],
    ),
    (
        "zero_count.ron",
        Expect::Invalid,
        &["generator.Chain.count = 0: must be in 1..="],
    ),
    (
        "empty_list.ron",
        Expect::Invalid,
        &["generator.List.particles: is empty"],
    ),
    (
        "empty_points.ron",
        Expect::Invalid,
        &["generator.Points.path", "holds no point"],
    ),
    (
        "missing_points.ron",
        Expect::Invalid,
        &["generator.Points.path", "does_not_exist.xyz", "not found"],
    ),
    (
        "bad_points_line.ron",
        Expect::Points,
        &[
            "bad_line.xyz:3:",
            "`oops` is not a number",
            "objects[0] \"cloud\".generator.Points.path",
        ],
    ),
    (
        "unsupported.yaml",
        Expect::Unsupported,
        &["unsupported.yaml", "\"yaml\"", ".ron, .json"],
    ),
    (
        "unknown_material.ron",
        Expect::Invalid,
        &[
            "objects[0] \"sheet\".material = \"steel\": unknown material",
            "\"membrane\", \"rubber\"",
        ],
    ),
    (
        "duplicate_names.ron",
        Expect::Invalid,
        &["objects[1] \"sheet\".name", "duplicate", "objects[0]"],
    ),
    (
        "selection_out_of_range.ron",
        Expect::Invalid,
        &[
            "objects[0] \"rope\".overrides[0].particles = Range(5, 12)",
            "valid indices: 0..10",
        ],
    ),
    (
        "force_index_out_of_range.ron",
        Expect::Invalid,
        &["forces[0].particles", "index 10", "0..10"],
    ),
    (
        "force_unknown_object.ron",
        Expect::Invalid,
        &["forces[0].object = \"cable\"", "\"rope\""],
    ),
    (
        "force_window.ron",
        Expect::Invalid,
        &["forces[0].end = 1", "greater than start = 2"],
    ),
    (
        "heater_without_heat.ron",
        Expect::Invalid,
        &["tools[0].role", "needs heat settings", "heat: Some("],
    ),
    (
        "bad_heat.ron",
        Expect::Invalid,
        &["world.heat", "conduction", ">= 0"],
    ),
    (
        "bad_material.ron",
        Expect::Invalid,
        &["materials.\"soft\".spacing.cohesion.alpha = -1", "> 0"],
    ),
    (
        "too_noisy.ron",
        Expect::Invalid,
        &["generator.HexSheet.noise = 0.6", "spacing/4"],
    ),
    (
        "spindle_torus.ron",
        Expect::Invalid,
        &["generator.TorusShell.major = 1", "greater than minor = 2"],
    ),
    (
        "too_many_particles.ron",
        Expect::Invalid,
        &["SphereShell.spacing", "at most 10000000"],
    ),
    (
        "too_big_solid_ball.ron",
        Expect::Invalid,
        &["SolidBall.spacing", "at most 10000000"],
    ),
    (
        "zero_spacing_solid_ball.ron",
        Expect::Invalid,
        &["generator.SolidBall.spacing = 0: must be finite and > 0"],
    ),
    ("no_objects.json", Expect::Invalid, &["objects: is empty"]),
    (
        "bad_name.ron",
        Expect::Invalid,
        &["name = \"../escape\"", "/"],
    ),
    (
        "zero_normal.ron",
        Expect::Invalid,
        &["generator.Spiral.normal = [0, 0, 0]", "non-zero"],
    ),
    (
        "coincident.ron",
        Expect::Build,
        &["objects[0] \"pair\"", "particles 0 and 1 coincide"],
    ),
    (
        "adaptive_params.ron",
        Expect::Invalid,
        &["world.integrator.adaptive.rtol = -1"],
    ),
    (
        "negative_settle.ron",
        Expect::Invalid,
        &["world.settle = -2: must be finite and >= 0"],
    ),
    (
        "creation_d_max.ron",
        Expect::Invalid,
        &["creation.stretching.d_max = 1.5", ">= d_min"],
    ),
    (
        "creation_no_rule.ron",
        Expect::Invalid,
        &["creation", "enables no rule"],
    ),
    (
        "creation_interval.ron",
        Expect::Invalid,
        &["creation.interval", ">= 1"],
    ),
    (
        "creation_gap.ron",
        Expect::Invalid,
        &["creation.growing.min_gap = 7", "(0, 2π]"],
    ),
    (
        "creation_spacing.ron",
        Expect::Invalid,
        &["creation.spacing = -1", "> 0"],
    ),
    (
        "creation_unknown_field.ron",
        Expect::Parse(5, 44),
        &["d_mid", "d_min"],
    ),
    (
        "triangulation_radius.ron",
        Expect::Invalid,
        &["outputs.triangulation_radius = 0", "> 0"],
    ),
    (
        "triangulation_not_bool.ron",
        Expect::Parse(5, 30),
        &["Expected boolean"],
    ),
];

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_scenes")
}

#[test]
fn bad_scenes_fail_with_the_right_error() {
    use op_scene::SceneError;
    for (file, expect, fragments) in BAD_SCENES {
        let path = bad_dir().join(file);
        assert!(path.is_file(), "{file} is missing");
        let err = match op_scene::build_scene_file(&path) {
            Ok(_) => panic!("{file}: built without error"),
            Err(e) => e,
        };
        let text = err.to_string();
        let ok = match (expect, &err) {
            (Expect::Parse(l, c), SceneError::Parse { line, column, .. }) => {
                assert_eq!((line, column), (l, c), "{file}: {text}");
                true
            }
            (Expect::Invalid, SceneError::Invalid { .. })
            | (Expect::Points, SceneError::Points { .. })
            | (Expect::Unsupported, SceneError::UnsupportedExtension { .. })
            | (Expect::Build, SceneError::Build { .. }) => true,
            _ => false,
        };
        assert!(ok, "{file}: expected {expect:?}, got {err:?}");
        assert!(
            text.contains(file),
            "{file}: the message names the file: {text}"
        );
        for f in *fragments {
            assert!(text.contains(f), "{file}: {text:?} lacks {f:?}");
        }
    }
}

#[test]
fn the_bad_scene_table_covers_the_corpus() {
    for entry in std::fs::read_dir(bad_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.is_file() {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            assert!(
                BAD_SCENES.iter().any(|(f, _, _)| *f == name),
                "{name} has no expectation in BAD_SCENES"
            );
        }
    }
}

/// Replaces the `k`-th number of `text` by `with`.
fn replace_number(text: &str, k: usize, with: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut found = 0;
    let mut i = 0;
    while i < bytes.len() {
        let starts = bytes[i].is_ascii_digit()
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if starts {
            let mut j = i;
            while j < bytes.len()
                && (bytes[j].is_ascii_digit() || matches!(bytes[j], b'.' | b'e' | b'-'))
            {
                j += 1;
            }
            if found == k {
                return Some(format!("{}{with}{}", &text[..i], &text[j..]));
            }
            found += 1;
            i = j;
        } else {
            i += 1;
        }
    }
    None
}

/// Mutated example scenes (every number replaced by hostile values, and
/// every prefix of the text) give errors, never panics.
#[test]
fn mutated_scenes_never_panic() {
    for path in scene_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        let format = op_scene::Format::from_path(&path).unwrap();
        let dir = path.parent().unwrap();
        let try_build = |t: &str| {
            if let Ok(s) = op_scene::load::parse_unvalidated(t, format, "<mutant>") {
                let _ = s.build(Some(dir), None);
            }
        };
        for k in 0.. {
            let mut any = false;
            for with in ["NaN", "-1", "0", "1e300", "-inf", "4294967296", "0.5"] {
                if let Some(m) = replace_number(&text, k, with) {
                    any = true;
                    eprintln!("MUTANT {} #{k} -> {with}", path.display());
                    try_build(&m);
                }
            }
            if !any {
                break;
            }
        }
        for cut in (0..text.len())
            .step_by(7)
            .filter(|&c| text.is_char_boundary(c))
        {
            try_build(&text[..cut]);
        }
    }
}
