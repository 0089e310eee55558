//! The extreme cases (`scenes/extreme/`, docs/model.md §6),
//! each run short through the op-scene runner into a temporary directory:
//! it must end converged or with a clean report (the runner's divergence,
//! exit 3, or an object that broke apart), never write a NaN or infinity
//! (OBJ frames, metrics.csv, summary.json), and its summary must say
//! `diverged` exactly when the runner reported it. The cohesion triangle
//! must converge from 20% (and 10%) of its rest length with the scene's
//! default integrator settings (velocity Verlet, dt 1e-3).

use std::path::{Path, PathBuf};

use op_experiments::stability::extreme::{
    cases, coincident_in_one_object, files_with_non_finite, run_scene, ExtremeOutcome, ExtremeRun,
    Overrides, RunLength,
};
use op_test_support::fresh_path;
use oriented_particles::op_dynamics::Scheme;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Whether frame 0 of every sequence of the run in `out` is on disk.
fn frame_zero_written(out: &std::path::Path) -> bool {
    let Ok(folders) = std::fs::read_dir(out.join("frames")) else {
        return false;
    };
    let folders: Vec<PathBuf> = folders.map(|e| e.unwrap().path()).collect();
    !folders.is_empty()
        && folders.iter().all(|f| {
            let stem = f.file_name().unwrap().to_string_lossy().into_owned();
            f.join(format!("{stem}_00000.obj")).is_file()
        })
}

/// Runs case `name` for `length` and checks the contract common to all.
fn run_case(name: &str, overrides: Overrides) -> ExtremeRun {
    let case = cases()
        .into_iter()
        .find(|c| c.name == name)
        .expect("a known case");
    let out = fresh_path(name);
    let run = run_scene(&case.scene(&repo()), &out, overrides).expect("the scene runs");
    let bad = files_with_non_finite(&out);
    assert!(bad.is_empty(), "{name}: non-finite output: {bad:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let diverged = matches!(run.outcome, ExtremeOutcome::Diverged(_));
    assert_eq!(summary["diverged"], diverged, "{name}: {:?}", run.outcome);
    assert_eq!(summary.get("divergence").is_some(), diverged, "{name}");
    assert!(
        out.join("metrics.csv").exists() && frame_zero_written(&out),
        "{name}: frame 0 and the metrics are written even when it diverges"
    );
    let _ = std::fs::remove_dir_all(&out);
    run
}

/// Converged, or a clean report (the runner's divergence or an object that
/// broke apart).
fn ended_cleanly(run: &ExtremeRun) -> bool {
    matches!(
        run.outcome,
        ExtremeOutcome::Converged | ExtremeOutcome::Diverged(_) | ExtremeOutcome::BrokeApart(_)
    )
}

fn full() -> Overrides {
    Overrides::default()
}

fn frames(frames: usize, frame_rate: f64) -> Overrides {
    Overrides {
        length: Some(RunLength { frames, frame_rate }),
        ..Overrides::default()
    }
}

#[test]
fn compressed_triangles_converge_with_the_default_integrator() {
    for p in [50, 30, 20, 10] {
        let run = run_case(&format!("compress_{p}"), full());
        assert_eq!(run.scheme, "velocity_verlet");
        assert!(ended_cleanly(&run));
        assert_eq!(run.outcome, ExtremeOutcome::Converged, "{p}%: {run:?}");
        let (a, b) = run.neighbour_range.expect("three particles");
        assert!(
            (a - 1.0).abs() < 0.01 && (b - 1.0).abs() < 0.01,
            "{p}%: {a} {b}"
        );
    }
}

#[test]
fn coincident_particles_of_two_objects_separate_without_nan() {
    // The pair energy is taken as 0 at r = 0, but the repulsion between
    // objects tends to e^(sigma/lambda) = e^10 times its contact value as
    // r -> 0: once the pair separates the total energy jumps, which the
    // scene's energy-gain check reports (otherwise one of the pair is
    // flung away and the objects break apart).
    let run = run_case("coincident", frames(6, 1.0));
    assert!(ended_cleanly(&run), "{run:?}");
}

#[test]
fn coincident_particles_of_one_object_stay_finite() {
    // Zero force at r = 0 (no direction): the two move together, by
    // symmetry never apart, and settle at r0 from the third.
    let run = coincident_in_one_object(Scheme::VelocityVerlet, 1e-3, 20.0);
    assert!(run.finite, "{run:?}");
    assert_eq!(run.separation, 0.0, "{run:?}");
    assert!((run.distance_to_third - 1.0).abs() < 0.01, "{run:?}");
}

#[test]
fn mass_ratio_of_a_million_is_reported() {
    let run = run_case("mass_ratio", full());
    assert!(ended_cleanly(&run), "{run:?}");
}

#[test]
fn curvature_radius_of_a_hundredth_r0_is_reported() {
    // The form energy at r0 is (kappa r0)^2 = 1e4 times its scale: the
    // chain tears into pairs that cohesion lets come within about 0.01 r0.
    // Until the normalized orientation terms faded out near coincidence
    // (below a quarter of the well's distance, op-dynamics material docs)
    // the pairs kept tumbling with energy pumped by velocity Verlet, which
    // only the scene's opt-in energy-gain check saw; now they come to rest
    // and the run reports where: nearest neighbours far below r0, no
    // energy gain, finite.
    let run = run_case("tight_curvature", full());
    match &run.outcome {
        ExtremeOutcome::Settled(m) => assert!(m.contains("nearest neighbours"), "{m}"),
        other => panic!("expected the settled report, got {other:?}"),
    }
}

#[test]
fn force_a_million_times_the_internal_ones_is_reported() {
    let run = run_case("huge_force", frames(4, 1.0));
    assert!(
        matches!(run.outcome, ExtremeOutcome::Diverged(_)),
        "{run:?}"
    );
}

#[test]
fn thousand_particles_on_one_point_are_reported() {
    // The crowded start is the expensive part (all 499 500 pairs within
    // 1e-3 r0 for about 0.4 time units): in CI the step is 1e-2 instead of
    // the scene's 1e-3 (reports/stability.md runs it as written).
    let run = run_case(
        "thousand_on_a_point",
        Overrides {
            dt: Some(1e-2),
            ..frames(11, 1.0)
        },
    );
    assert!(ended_cleanly(&run), "{run:?}");
}

#[test]
fn extreme_scenes_exist_for_every_case() {
    for c in cases() {
        assert!(Path::new(&c.scene(&repo())).exists(), "{}", c.name);
    }
}
