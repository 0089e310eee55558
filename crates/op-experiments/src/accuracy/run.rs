//! One run of a case with one method, sampled at fixed scene times, and
//! its errors against a reference run (docs/model.md §6).

use std::time::Instant;

use op_dynamics::{Point3, Quat, Real};

use super::case::{Case, Method};

/// The state of a run at the case's sample times, particles in id order
/// (the world re-sorts its particles in memory; ids are stable).
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Scene time of each sample.
    pub times: Vec<Real>,
    /// Positions, per sample, per particle.
    pub positions: Vec<Vec<Point3>>,
    /// Orientations, per sample, per particle.
    pub orientations: Vec<Vec<Quat>>,
    /// Total energy (kinetic, translational and rotational, plus internal
    /// pair potential; gravity and external forces are not counted) per
    /// sample.
    pub energies: Vec<Real>,
    /// Steps taken (settle phase included).
    pub steps: u64,
    /// Force evaluations (all stages, rejected adaptive attempts and the
    /// one energy evaluation per sample included).
    pub force_evaluations: u64,
}

/// Builds the case's scene with `method` (its integrator and step
/// replace the scene's), runs the settle phase, then advances through the
/// sample times the way the op-scene runner does
/// ([`op_scene::BuiltScene::advance_to`]: contact, when the scene has it,
/// is evaluated at every force evaluation).
///
/// # Errors
///
/// A message when the scene does not build or the run diverges.
pub fn simulate(case: &Case, method: &Method) -> Result<Trajectory, String> {
    let mut scene = case.scene.clone();
    scene.world.integrator = method.scheme;
    scene.world.dt = method.dt;
    let mut built = scene
        .build(case.base_dir.as_deref(), None)
        .map_err(|e| e.to_string())?;
    built.settle().map_err(|e| format!("while settling: {e}"))?;
    let t0 = built.world().time();
    let mut ids: Vec<u32> = built.world().particles().ids().to_vec();
    ids.sort_unstable();
    let mut out = Trajectory {
        times: Vec::new(),
        positions: Vec::new(),
        orientations: Vec::new(),
        energies: Vec::new(),
        steps: 0,
        force_evaluations: 0,
    };
    for &t in &case.entry.samples {
        built.advance_to(t0 + t).map_err(|e| e.to_string())?;
        let energy = built.world_mut().diagnostics().total;
        let p = built.world().particles();
        let slots: Vec<usize> = ids
            .iter()
            .map(|&id| p.slot_of(id).expect("a particle of the scene"))
            .collect();
        out.times.push(built.scene_time());
        out.positions
            .push(slots.iter().map(|&k| p.positions()[k]).collect());
        out.orientations
            .push(slots.iter().map(|&k| p.orientations()[k]).collect());
        out.energies.push(energy);
    }
    out.steps = built.world().steps();
    out.force_evaluations = built.world().force_evaluations();
    Ok(out)
}

/// Errors of a run against a reference run of the same case.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Errors {
    /// RMS over sample times and particles of `|p - p_ref|`, over `r0`.
    pub position: Real,
    /// RMS over sample times and particles of the angle of
    /// `q_ref⁻¹ q` (radians).
    pub orientation: Real,
    /// Largest `|E(t) - E_ref(t)|` over the samples, over the largest
    /// `|E_ref|`.
    pub energy: Real,
    /// For conservative cases: the relative energy drift, the largest
    /// `|E(t) - E(0)| / |E(0)|` over the samples (t = 0 is the first
    /// sample); `None` otherwise.
    pub drift: Option<Real>,
}

/// The errors of `run` against `reference` (same case, same samples and
/// particles); `r0` is the length unit, `conservative` says whether the
/// energy drift means anything.
///
/// # Panics
///
/// If the two trajectories have different shapes.
pub fn errors(run: &Trajectory, reference: &Trajectory, r0: Real, conservative: bool) -> Errors {
    assert_eq!(
        run.positions.len(),
        reference.positions.len(),
        "trajectories with different sample counts"
    );
    let (mut sp, mut sq, mut n) = (0.0, 0.0, 0usize);
    for (k, (pos, pos_ref)) in run.positions.iter().zip(&reference.positions).enumerate() {
        assert_eq!(pos.len(), pos_ref.len(), "different particle counts");
        for (i, (p, p_ref)) in pos.iter().zip(pos_ref).enumerate() {
            sp += (p - p_ref).norm_squared();
            let angle = reference.orientations[k][i].angle_to(&run.orientations[k][i]);
            sq += angle * angle;
            n += 1;
        }
    }
    let n = n.max(1) as Real;
    let scale = reference
        .energies
        .iter()
        .fold(0.0, |m: Real, e| m.max(e.abs()))
        .max(Real::MIN_POSITIVE);
    let energy = run
        .energies
        .iter()
        .zip(&reference.energies)
        .fold(0.0, |m: Real, (e, r)| m.max((e - r).abs()))
        / scale;
    let drift = conservative.then(|| {
        let e0 = run.energies.first().copied().unwrap_or(0.0);
        run.energies
            .iter()
            .fold(0.0, |m: Real, e| m.max((e - e0).abs()))
            / e0.abs().max(Real::MIN_POSITIVE)
    });
    Errors {
        position: (sp / n).sqrt() / r0,
        orientation: (sq / n).sqrt(),
        energy,
        drift,
    }
}

/// Wall-clock seconds of repeated identical runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// Every run's seconds, sorted.
    pub seconds: Vec<f64>,
}

impl Timing {
    /// The median (mean of the two middle runs for an even count).
    pub fn median(&self) -> f64 {
        let s = &self.seconds;
        match s.len() {
            0 => f64::NAN,
            n if n % 2 == 1 => s[n / 2],
            n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
        }
    }

    /// The fastest run.
    pub fn min(&self) -> f64 {
        self.seconds.first().copied().unwrap_or(f64::NAN)
    }

    /// The slowest run.
    pub fn max(&self) -> f64 {
        self.seconds.last().copied().unwrap_or(f64::NAN)
    }
}

/// One method measured on one case.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// The method.
    pub method: Method,
    /// Its errors, or why the run failed (diverged).
    pub outcome: Result<Errors, String>,
    /// Steps of one run.
    pub steps: u64,
    /// Force evaluations of one run.
    pub force_evaluations: u64,
    /// Wall time of the runs.
    pub timing: Timing,
}

/// Runs `method` on `case` `repeats` times (at least once), timing each
/// run, and measures the first run against `reference`. Every run must
/// give the same trajectory bit for bit (the engine is deterministic);
/// a run that differs is reported as a failure.
pub fn measure(
    case: &Case,
    method: &Method,
    reference: &Trajectory,
    repeats: usize,
) -> Measurement {
    let mut seconds = Vec::new();
    let mut first: Option<Result<Trajectory, String>> = None;
    for _ in 0..repeats.max(1) {
        let clock = Instant::now();
        let run = simulate(case, method);
        seconds.push(clock.elapsed().as_secs_f64());
        match &first {
            None => {
                let failed = run.is_err();
                first = Some(run);
                if failed {
                    break;
                }
            }
            Some(f) if *f != run => {
                first = Some(Err("repeated runs differ: not deterministic".into()));
                break;
            }
            Some(_) => {}
        }
    }
    seconds.sort_by(f64::total_cmp);
    let run = first.expect("at least one run");
    let (steps, force_evaluations) = run
        .as_ref()
        .map_or((0, 0), |t| (t.steps, t.force_evaluations));
    Measurement {
        method: *method,
        outcome: run.map(|t| errors(&t, reference, case.r0, case.entry.conservative)),
        steps,
        force_evaluations,
        timing: Timing { seconds },
    }
}
