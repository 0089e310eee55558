//! The extreme cases of docs/model.md §6: each either converges or ends in
//! a clean divergence report, with no NaN in any output and no panic.
//!
//! The scenes live in `scenes/extreme/` (so `opsim run` exercises the exit-3
//! path on them); [`ExtremeCase::scene`] gives each one's file and what it
//! tests. Two coincident particles of one object cannot be written as a
//! scene (the builder rejects coincident particles within an object), so
//! [`coincident_in_one_object`] builds them in code; the scene
//! `coincident.ron` puts two particles of two objects on the same point.
//!
//! **Outcome** ([`ExtremeOutcome`]) after a run through the op-scene runner:
//! *diverged* when the runner reports it (NaN or infinity, a speed above
//! the limit, runaway energy, or, in the passive extreme scenes that opt
//! in with `divergence.energy_gain`, a gain of total energy, or an object
//! broken into pieces the scene does not expect: exit code 3,
//! `summary.json` with `diverged: true`); else *broke apart* when some
//! particle has no other within the spacing cut-off (seed 002 footnote 4)
//! although no object ended in more pieces than it started in; else *converged*
//! when the last step's oscillation measure is below `1e-6 √N` and every
//! particle's nearest neighbour is within 1% of `r0` (the rest spacing);
//! *settled* when it is at rest in another shape; *oscillating* otherwise.

use std::path::{Path, PathBuf};

use op_dynamics::interactions::Spacing;
use op_dynamics::world::DivergenceParams;
use op_dynamics::{
    ExternalParams, Material, ParticleDesc, Particles, Point3, Real, Scheme, World, WorldParams,
};
use op_scene::{load_scene, run, RunError, RunOptions, Summary};

use crate::matching::reference_cohesion;

/// One extreme case given as a scene.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ExtremeCase {
    /// Scene name (file stem in `scenes/extreme/`).
    pub name: &'static str,
    /// What it tests.
    pub what: &'static str,
}

impl ExtremeCase {
    /// The scene file, under the repository root `root`.
    pub fn scene(&self, root: &Path) -> PathBuf {
        root.join("scenes/extreme")
            .join(format!("{}.ron", self.name))
    }
}

/// The extreme cases given as scenes, in report order.
pub fn cases() -> Vec<ExtremeCase> {
    vec![
        ExtremeCase {
            name: "compress_50",
            what: "cohesion triangle started at 50% of its rest length",
        },
        ExtremeCase {
            name: "compress_30",
            what: "cohesion triangle started at 30% of its rest length",
        },
        ExtremeCase {
            name: "compress_20",
            what: "cohesion triangle started at 20% of its rest length",
        },
        ExtremeCase {
            name: "compress_10",
            what: "cohesion triangle started at 10% of its rest length",
        },
        ExtremeCase {
            name: "coincident",
            what: "two particles (of two objects) on the same point",
        },
        ExtremeCase {
            name: "mass_ratio",
            what: "chain whose neighbours' masses differ by 1e6 (1 and 1e-6)",
        },
        ExtremeCase {
            name: "tight_curvature",
            what: "form term with rest curvature radius 0.01 r0",
        },
        ExtremeCase {
            name: "huge_force",
            what: "external force 1e6 times the largest internal force",
        },
        ExtremeCase {
            name: "thousand_on_a_point",
            what: "1000 particles released within 1e-3 r0 of one point",
        },
    ]
}

/// How an extreme run ended (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub enum ExtremeOutcome {
    /// At rest in the rest spacing.
    Converged,
    /// At rest in another shape (the detail says how far from `r0`).
    Settled(String),
    /// Some particle has no neighbour within the cut-off.
    BrokeApart(String),
    /// Still moving at the end.
    Oscillating,
    /// The runner reported a divergence (its message).
    Diverged(String),
}

impl ExtremeOutcome {
    /// A short table cell.
    pub fn cell(&self) -> String {
        match self {
            ExtremeOutcome::Converged => "converged".into(),
            ExtremeOutcome::Settled(d) => format!("settled elsewhere ({d})"),
            ExtremeOutcome::BrokeApart(d) => format!("broke apart ({d})"),
            ExtremeOutcome::Oscillating => "oscillating".into(),
            ExtremeOutcome::Diverged(m) => format!("**diverged** (exit 3): {m}"),
        }
    }
}

/// What an extreme run produced.
#[derive(Clone, Debug)]
pub struct ExtremeRun {
    /// How it ended.
    pub outcome: ExtremeOutcome,
    /// The summary the runner wrote.
    pub summary: Summary,
    /// Oscillation measure of the last step.
    pub final_oscillation: Real,
    /// Smallest and largest nearest-neighbour distance at the end, in
    /// `r0` (`None` for fewer than two particles or after a divergence).
    pub neighbour_range: Option<(Real, Real)>,
    /// The integrator used.
    pub scheme: String,
}

/// `r0` and the cut-off of a spacing potential.
fn spacing_scale(s: &Spacing) -> (Real, Real) {
    let cutoff = s.prepare().map(|k| k.cutoff()).unwrap_or(Real::INFINITY);
    match s {
        Spacing::Cohesion(c) => (c.r0, cutoff),
        Spacing::LennardJones(l) => (l.r0, cutoff),
    }
}

/// Nearest-neighbour distance of each point (all pairs; `INFINITY` for a
/// lone point).
pub fn nearest_neighbour_distances(points: &[Point3]) -> Vec<Real> {
    let mut d = vec![Real::INFINITY; points.len()];
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            let r = (points[j] - points[i]).norm();
            d[i] = d[i].min(r);
            d[j] = d[j].min(r);
        }
    }
    d
}

/// How long to run a scene: `frames` frames at `frame_rate` per unit time
/// (the run lasts `(frames - 1) / frame_rate`).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RunLength {
    /// Frames written, frame 0 included.
    pub frames: usize,
    /// Frames per unit of simulated time.
    pub frame_rate: Real,
}

/// Changes to a scene's world settings for one run (`None`: as written).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Duration and frame rate.
    pub length: Option<RunLength>,
    /// Integrator.
    pub scheme: Option<Scheme>,
    /// Time step.
    pub dt: Option<Real>,
}

/// Runs the scene at `path` through the op-scene runner into `out_dir`,
/// with the world settings changed by `overrides`, and classifies the end
/// (see the module docs). Errors: the scene could not be loaded or built,
/// or an output could not be written.
pub fn run_scene(path: &Path, out_dir: &Path, overrides: Overrides) -> Result<ExtremeRun, String> {
    let mut scene = load_scene(path).map_err(|e| e.to_string())?;
    if let Some(s) = overrides.scheme {
        scene.world.integrator = s;
    }
    if let Some(dt) = overrides.dt {
        scene.world.dt = dt;
    }
    let length = overrides.length;
    if let Some(l) = length {
        scene.world.frame_rate = l.frame_rate;
    }
    let (r0, cutoff) = scene
        .objects
        .first()
        .and_then(|o| scene.materials.get(&o.material))
        .and_then(|m| m.spacing.as_ref())
        .map(spacing_scale)
        .unwrap_or((1.0, Real::INFINITY));
    let used = scene.world.integrator.name().to_string();
    let mut built = scene
        .build(path.parent(), Some(path.to_path_buf()))
        .map_err(|e| e.to_string())?;
    let opts = RunOptions {
        out_dir: out_dir.to_path_buf(),
        frames: length.map(|l| l.frames),
        formats: vec![op_scene::export::FrameFormat::OBJ],
        ..Default::default()
    };
    let result = run(&mut built, &opts, &mut |_, _| {});
    let (summary, diverged) = match result {
        Ok(s) => (s, None),
        Err(RunError::Diverged { message, summary }) => (*summary, Some(message)),
        Err(e) => return Err(e.to_string()),
    };
    let n = built.world().particles().len();
    let final_oscillation = built.world().oscillation();
    if let Some(message) = diverged {
        return Ok(ExtremeRun {
            outcome: ExtremeOutcome::Diverged(message),
            summary,
            final_oscillation,
            neighbour_range: None,
            scheme: used,
        });
    }
    let nn = nearest_neighbour_distances(built.world().particles().positions());
    let range = (n >= 2).then(|| {
        nn.iter()
            .fold((Real::INFINITY, 0.0), |(a, b): (Real, Real), &d| {
                (a.min(d / r0), b.max(d / r0))
            })
    });
    let at_rest = final_oscillation < 1e-6 * (n as Real).sqrt();
    let isolated = nn.iter().filter(|&&d| d >= cutoff).count();
    let outcome = if n >= 2 && isolated > 0 {
        ExtremeOutcome::BrokeApart(format!(
            "{isolated} of {n} particles have no neighbour within the cut-off {cutoff:.3}"
        ))
    } else if !at_rest {
        ExtremeOutcome::Oscillating
    } else if range.is_none_or(|(a, b)| (a - 1.0).abs() <= 0.01 && (b - 1.0).abs() <= 0.01) {
        ExtremeOutcome::Converged
    } else {
        let (a, b) = range.unwrap_or((1.0, 1.0));
        ExtremeOutcome::Settled(format!("nearest neighbours {a:.3} to {b:.3} r0"))
    };
    Ok(ExtremeRun {
        outcome,
        summary,
        final_oscillation,
        neighbour_range: range,
        scheme: used,
    })
}

/// Files under `dir` (recursively) holding a non-finite number: a token
/// `nan`, `inf`, `infinity` (any case, any sign) or a JSON `null` (how
/// serde_json writes NaN). Each with the first offending line.
pub fn files_with_non_finite(dir: &Path) -> Vec<(PathBuf, String)> {
    let mut bad = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let Ok(text) = std::fs::read_to_string(&p) else {
                continue;
            };
            let hit = text.lines().find(|line| {
                line.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '_'))
                    .any(|t| {
                        matches!(
                            t.to_ascii_lowercase().as_str(),
                            "nan" | "inf" | "infinity" | "null"
                        )
                    })
            });
            if let Some(line) = hit {
                bad.push((p, line.to_string()));
            }
        }
    }
    bad.sort();
    bad
}

/// The end of [`coincident_in_one_object`].
#[derive(Clone, Debug, PartialEq)]
pub struct CoincidentRun {
    /// Every position and velocity stayed finite and no divergence was
    /// reported.
    pub finite: bool,
    /// The divergence message, if any.
    pub divergence: Option<String>,
    /// Final distance between the two coincident particles.
    pub separation: Real,
    /// Final distance from them to the third particle, in `r0`.
    pub distance_to_third: Real,
    /// Oscillation measure of the last step.
    pub final_oscillation: Real,
}

/// Two particles of one object on the same point and a third at `0.8 r0`
/// (reference cohesion, unit masses, `β0 = 1`), stepped by `scheme` at
/// `dt` for `duration`. The pair force has no direction at `r = 0` and is
/// zero there (op-dynamics `evaluate_pair`); the two coincident particles
/// feel the same force from the third, so they move together: by symmetry
/// they never separate, and the three settle with the pair at `r0` from
/// the third.
pub fn coincident_in_one_object(scheme: Scheme, dt: Real, duration: Real) -> CoincidentRun {
    let mut particles = Particles::new();
    for x in [0.0, 0.0, 0.8] {
        particles
            .push(ParticleDesc::at(Point3::new(x, 0.0, 0.0)))
            .expect("a valid particle");
    }
    let material = Material {
        spacing: Some(Spacing::Cohesion(reference_cohesion())),
        ..Material::empty()
    };
    let params = WorldParams {
        scheme,
        dt,
        external: ExternalParams {
            linear_damping: 1.0,
            ..ExternalParams::default()
        },
        divergence: DivergenceParams { max_speed: 1e3 },
        ..WorldParams::default()
    };
    let mut world = World::new(particles, &[material], params).expect("a valid world");
    let divergence = world.advance_to(duration).err().map(|d| d.to_string());
    let p = world.particles();
    let at = |id: u32| p.positions()[p.slot_of(id).expect("an id of the world")];
    let finite = divergence.is_none()
        && p.positions()
            .iter()
            .all(|x| x.iter().all(|c| c.is_finite()))
        && p.velocities()
            .iter()
            .all(|v| v.iter().all(|c| c.is_finite()));
    CoincidentRun {
        finite,
        divergence,
        separation: (at(1) - at(0)).norm(),
        distance_to_third: (at(2) - at(0)).norm() / reference_cohesion().r0,
        final_oscillation: world.oscillation(),
    }
}
