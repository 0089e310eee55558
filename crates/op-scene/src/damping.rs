//! Critical damping of the slowest deformation mode (seed 002 §5, fig. 5):
//! the damping and the time windows of a run computed from its materials
//! and shapes instead of fixed numbers, as the shape-memory report found
//! them for the spiral that uncoils and recovers (`reports/shape_memory.md`
//! §2, "Critical damping of the slowest mode"). A scene asks for it with
//! `linear_damping: "Critical"` ([`crate::schema::Damping::Critical`]);
//! `opsim check` prints it for any scene small enough.
//!
//! **Rule.** Linearized at rest, `M ẍ + D ẋ + H x = 0`. With damping
//! proportional to the masses, `D = c M` (linear damping `β0 = c m`,
//! angular damping `β1 = c I`), every mode `k` has the damping ratio
//! `ζ_k = c / (2 ω_k)`; `c = 2 ω1` damps the slowest deformation mode
//! critically and leaves the faster ones underdamped under the same
//! envelope `e^{-ω1 t}`: no mode decays slower than `(1 + ω1 t) e^{-ω1 t}`.
//! `ω1` is the smallest nonzero frequency of the modes of the settled
//! world ([`crate::modes`]), computed from the Hessian of its energy and
//! its masses and moments of inertia. A world's damping is one `β0` and one
//! `β1` for every particle, so with unequal particles `m` and `I` are those
//! the slowest mode moves ([`crate::modes::Modes::moved_inertia`]): its
//! damping ratio is then exactly 1, the others' close to `ω1 / ω_k`.
//! Every phase of the schedule is a multiple of `τ = 1/ω1`
//! ([`CriticalSchedule`]). Inter-particle friction (damping of relative
//! velocities only) is the material's and stays.
//!
//! **The times matter as much as the damping.** Measured (ci profile) on
//! 14-particle spirals of 0.75 turns with a quadratic and a geometric law
//! of ratio 9 (`op_experiments`' `SpiralShape::with_turns`; `ω1` = 0.17
//! and 0.18, `τ` about 5.7), loaded by the recipe's end forces for 40
//! time units, final rest shape errors (the recipe: damping 0.3, a settle
//! of 40 and 40 time units after the load, about 7 `τ` each):
//!
//! | damping | settle | recovery | quadratic | geometric |
//! |---|---|---|---|---|
//! | 0.3 (the recipe) | 40 | 40 | 0.022 | 0.024 |
//! | `2 ω1` | 40 | 40 | 0.033 | 0.036 |
//! | `2 ω1` | 12 `τ` | 40 | 0.042 | 0.043 |
//! | `2 ω1` | 40 | 20 `τ` | 0.010 | 0.0066 |
//! | 0.3 | 40 | 20 `τ` | 0.0087 | 0.0038 |
//! | 0.3 | 12 `τ` | 20 `τ` | 0.0004 | 0.00002 |
//! | `2 ω1` (the rule) | 12 `τ` | 20 `τ` | 0.0005 | 0.0001 |
//!
//! The window does most of the work, and a settle short of rest leaves
//! a reference the spiral drifts away from; the critical damping makes
//! the window a fixed number of periods for any spiral (the fixed
//! damping, near critical here, is far underdamped at 20 particles, see
//! `op_experiments::spiral_damping`).
//!
//! **At rest.** Finding `ω1` needs a state at rest, and settling needs a
//! damping: the scene is settled, `ω1` taken there, then settled again
//! with the damping and settle time of that `ω1`, until `ω1` changes by
//! less than 5% ([`converge`]). A settle that has not reached rest shows as
//! a negative `ω²`: the settle time is then doubled. A slowest `ω²` of zero
//! (within [`ZERO`] of the largest) after a settle is a mechanism, which no
//! damping ratio describes: the scene is refused. The first settle takes
//! its damping from the built (generated) state, whose slowest mode,
//! negative or not, has the size of the soft modes (the spirals' `|ω²|`
//! there is within a factor 2 of the settled `ω1²`).
//!
//! **Which modes.** A spiral's particles can turn and move out of their
//! plane at no cost (a chain's torsion costs no energy; see
//! `op_experiments::spiral`), so its spatial modes include zero ones and its
//! slowest deformation mode is in its plane, where its motion stays bit for
//! bit. The modes are therefore taken in the plane `z = 0`
//! ([`Basis::Planar`]) when the motion provably stays there ([`basis_of`]:
//! every particle in it, turned about `z` only, at rest or moving in it,
//! no gravity, force, tool, skin or creation out of it), in space
//! otherwise ([`Basis::Spatial`]), where a zero mode other than a rigid
//! motion or a free spin (a mechanism) leaves the rule without a slowest
//! mode ([`ModeError::ZeroFrequency`]).
//!
//! **Limits.** The modes are dense eigenpairs: at most
//! [`crate::modes::MAX_DEGREES_OF_FREEDOM`] degrees of freedom (a few
//! hundred particles in a plane, 100 in space). Skin contact acts outside
//! the world's forces and cannot be part of them: a scene with a skinned
//! object is refused, as is one with creation rules (its particles
//! change). The recovery window counts from the end of the last force
//! window; a tool's motion is not a load it knows. A world's damping is
//! one number for all its particles, so with very unequal particles only
//! the slowest mode is damped exactly critically.

use op_dynamics::{Real, World};
use serde::Serialize;

use crate::error::SceneError;
use crate::modes::{modes, Basis, Modes, MAX_DEGREES_OF_FREEDOM};
use crate::schema::{Damping, Scene};

/// The phases of the experiment in units of `τ = 1/ω1`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CriticalSchedule {
    /// Settle phase, in `τ`: the settled state is the reference of the rest
    /// shape error, so it must be at rest well below the tolerance: under
    /// critical damping the slowest mode is down to `(1 + x) e^{-x}` =
    /// 8e-5 of its start after `x = 12`.
    pub settle: Real,
    /// Each load ramp, in `τ`: slower than the slowest mode, so the load
    /// is close to quasi-static (seed 002's recipe: 3 `τ` of the seed).
    pub ramp: Real,
    /// Time at full load, in `τ`: long enough to come to balance.
    pub hold: Real,
    /// Free recovery, in `τ`: measured, not derived: the linear bound
    /// `(1 + x) e^{-x}` is below 1e-3 of the release error after 9.2 `τ`,
    /// but the release starts far from rest (error 0.6 to 4 spacings),
    /// where the stiffness of cohesion (zero at its rest distance) and
    /// form differs from the linearization; 12 `τ` left a quadratic-law
    /// spiral of 8 particles at 0.019, 20 `τ` brings every recovering
    /// spiral of `tests/shape_memory.rs` below 0.001.
    pub recovery: Real,
    /// Frames per `τ`.
    pub frames: Real,
}

impl Default for CriticalSchedule {
    fn default() -> Self {
        CriticalSchedule {
            settle: 12.0,
            ramp: 3.0,
            hold: 6.0,
            recovery: 20.0,
            frames: 6.0,
        }
    }
}

/// Largest number of settle-and-measure passes of [`converge`].
pub const PASSES: usize = 8;

/// [`converge`] stops when `ω1` changes by less than this fraction.
pub const CONVERGED: Real = 0.05;

/// An `ω²` within this fraction of the largest one is zero (the central
/// differences of [`crate::modes`] are good to about 1e-10 of it).
pub const ZERO: Real = 1e-8;

/// The linear and angular damping of the rule for `omega1`: `2 ω1` times
/// `mass` and `inertia` (see the module docs).
pub fn critical_coefficients(omega1: Real, mass: Real, inertia: Real) -> (Real, Real) {
    (2.0 * omega1 * mass, 2.0 * omega1 * inertia)
}

/// The slowest deformation mode of a world ([`slowest_mode`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlowestMode {
    /// Its angular frequency `ω1`, 1/time.
    pub omega1: Real,
    /// The modes it was found among.
    pub basis: Basis,
    /// The mass it moves (see [`Modes::moved_inertia`]).
    pub mass: Real,
    /// The moment of inertia it moves; the particles' mean principal
    /// moment when it turns none (their spins are free, see
    /// [`crate::modes::modes`]).
    pub inertia: Real,
    /// Deformation modes computed (rigid motions and free spins left out).
    pub modes: usize,
}

/// Why a world has no slowest mode to damp.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModeError {
    /// Too many degrees of freedom for the dense decomposition.
    #[error(
        "{dof} degrees of freedom, more than the {max} the dense eigen-solve of the modes is for"
    )]
    TooLarge {
        /// Degrees of freedom of the world in the basis.
        dof: usize,
        /// [`MAX_DEGREES_OF_FREEDOM`].
        max: usize,
    },
    /// Nothing left to deform: no free particle, or only rigid motions.
    #[error("no deformation mode (no free particle, or only rigid motions)")]
    NoMode,
    /// The slowest `ω²` is negative: the state is not at rest.
    #[error("not at rest: its slowest mode has ω² = {omega2:.3e} < 0 (largest {largest:.3e})")]
    NotAtRest {
        /// That `ω²`, 1/time².
        omega2: Real,
        /// The largest `ω²`.
        largest: Real,
    },
    /// The slowest mode has no stiffness: a mechanism.
    #[error(
        "its slowest mode has no restoring force (ω² = {omega2:.3e}, largest {largest:.3e}): \
         a mechanism, such as a chain's torsion, has no frequency to damp"
    )]
    ZeroFrequency {
        /// That `ω²`, 1/time².
        omega2: Real,
        /// The largest `ω²`.
        largest: Real,
    },
}

/// What a step of the trial settles costs besides its particles and
/// pairs, in particle-steps: an 8-particle chain of 16 pairs
/// (`scenes/extreme/tight_curvature.ron`) steps in about 4.6 µs on this
/// project's 2-core machine, some fifty times a pair's 47 ns in the
/// densest shipped search (`fig_06_weld`).
const STEP_WORK: usize = 50;

/// The work of one mode analysis of `particles` particles over `basis`,
/// in particle-steps (what a time step of one particle costs, about a
/// microsecond): see [`mode_work_of`].
fn mode_work(basis: Basis, particles: usize) -> Real {
    mode_work_of(basis.per_particle() * particles, particles)
}

/// The work of one mode analysis of `dof` degrees of freedom over
/// `particles` particles, in particle-steps: the Hessian's central
/// differences (two force evaluations of every particle per degree of
/// freedom) and its dense eigen-decomposition, counted as `dof³ / 250`
/// particle-steps, on the high side: nalgebra's `SymmetricEigen` of a
/// 600-square test matrix took 0.24 s (1.1 ns per `dof³`), and each mode
/// pass of a 100-particle scene's `opsim check` about twice that, Hessian
/// included, against a microsecond per particle-step.
fn mode_work_of(dof: usize, particles: usize) -> Real {
    let dof = dof.min(MAX_DEGREES_OF_FREEDOM) as Real;
    2.0 * dof * particles as Real + dof.powi(3) / 250.0
}

/// The slowest deformation mode of `world` at its current state over
/// `basis` (free spins left out, see [`crate::modes::modes`]).
///
/// # Errors
///
/// [`ModeError`]: too many degrees of freedom, none, or a slowest `ω²`
/// that is negative or zero (within [`ZERO`] of the largest).
pub fn slowest_mode(world: &mut World, basis: Basis) -> Result<SlowestMode, ModeError> {
    let dof = basis.per_particle() * world.particles().len();
    if dof > MAX_DEGREES_OF_FREEDOM {
        return Err(ModeError::TooLarge {
            dof,
            max: MAX_DEGREES_OF_FREEDOM,
        });
    }
    let m = modes(world, basis, true);
    slowest_of(&m, mean_moment(world))
}

/// The mean principal moment of inertia of the particles (what the rule
/// damps spins with when the slowest mode turns no particle).
fn mean_moment(world: &World) -> Real {
    let i = world.particles().inertias();
    let sum: Real = i.iter().map(|v| v.sum() / 3.0).sum();
    sum / i.len().max(1) as Real
}

/// The slowest mode of `m` ([`slowest_mode`]); `moment` stands for the
/// moment of inertia when it turns no particle.
fn slowest_of(m: &Modes, moment: Real) -> Result<SlowestMode, ModeError> {
    let (Some(&omega2), Some(&last)) = (m.omega2.first(), m.omega2.last()) else {
        return Err(ModeError::NoMode);
    };
    let largest = last.abs().max(omega2.abs());
    if omega2 < -ZERO * largest {
        return Err(ModeError::NotAtRest { omega2, largest });
    }
    if omega2.is_nan() || omega2 <= ZERO * largest {
        return Err(ModeError::ZeroFrequency { omega2, largest });
    }
    let (mass, inertia) = m.moved_inertia(0);
    let moves: Vec<Real> = m
        .dofs
        .iter()
        .filter(|d| !d.turn)
        .map(|d| d.inertia)
        .collect();
    let mean_move = moves.iter().sum::<Real>() / moves.len().max(1) as Real;
    Ok(SlowestMode {
        omega1: omega2.sqrt(),
        basis: m.basis,
        mass: mass.unwrap_or(mean_move),
        inertia: inertia.unwrap_or(moment),
        modes: m.omega2.len(),
    })
}

/// The modes that describe `scene`'s motion from the state of `world`
/// (built from it): [`Basis::Planar`] when the motion provably stays in
/// the plane `z = 0`: every particle in it, its orientation a rotation
/// about `z` (so an in-plane normal stays in the plane), its velocity in
/// the plane and its angular velocity along `z`; no gravity, force window
/// or initial velocity out of the plane; no tool, skin or creation rule
/// (shapes and rules of their own in space). [`Basis::Spatial`] otherwise.
pub fn basis_of(scene: &Scene, world: &World) -> Basis {
    let p = world.particles();
    let in_plane = (0..p.len()).all(|s| {
        let q = p.orientations()[s];
        p.positions()[s].z == 0.0
            && q.i == 0.0
            && q.j == 0.0
            && p.velocities()[s].z == 0.0
            && p.angular_velocities()[s].x == 0.0
            && p.angular_velocities()[s].y == 0.0
    });
    let loads_in_plane =
        scene.world.gravity[2] == 0.0 && scene.forces.iter().all(|f| f.force[2] == 0.0);
    let plain = scene.tools.is_empty()
        && scene.creation.is_none()
        && scene.objects.iter().all(|o| o.skin.is_none());
    if in_plane && loads_in_plane && plain {
        Basis::Planar
    } else {
        Basis::Spatial
    }
}

/// What one settle-and-measure pass of [`converge`] found.
#[derive(Clone, Debug, PartialEq)]
pub enum Measured {
    /// The slowest deformation mode's `ω1`.
    Omega(Real),
    /// No state at rest: settle longer.
    NotAtRest,
}

/// The settle-and-measure iteration of the module docs. `measure(omega,
/// stretch)` settles with the damping and settle time of `omega` (`None`
/// on the first pass: the caller's own start) times `stretch` (doubled
/// after each pass that found no state at rest, back to 1 after one that
/// did) and measures. Returns `ω1` and the passes taken once two measured
/// `ω1` in a row differ by less than [`CONVERGED`], `None` when that does
/// not happen in [`PASSES`] passes.
///
/// # Errors
///
/// The first error of `measure`.
pub fn converge<E>(
    mut measure: impl FnMut(Option<Real>, Real) -> Result<Measured, E>,
) -> Result<Option<(Real, usize)>, E> {
    let (mut current, mut stretch) = (None, 1.0);
    let mut previous: Option<Real> = None;
    for pass in 1..=PASSES {
        let Measured::Omega(omega) = measure(current, stretch)? else {
            stretch *= 2.0;
            continue;
        };
        current = Some(omega);
        stretch = 1.0;
        if previous.is_some_and(|old| (omega / old - 1.0).abs() < CONVERGED) {
            return Ok(Some((omega, pass)));
        }
        previous = Some(omega);
    }
    Ok(None)
}

/// What [`resolve`] made of `linear_damping: "Critical"`: the numbers the
/// scene runs with (`summary.json`'s `critical_damping`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CriticalDamping {
    /// The slowest deformation mode of the settled scene.
    pub mode: SlowestMode,
    /// `τ = 1/ω1`, in time units.
    pub tau: Real,
    /// Linear damping `β0 = 2 ω1 m`.
    pub linear_damping: Real,
    /// Angular damping `β1 = 2 ω1 I`.
    pub angular_damping: Real,
    /// The settle phase run: the scene's, at least 12 `τ`.
    pub settle: Real,
    /// The duration run: the scene's, at least 20 `τ` after the end of the
    /// last force window when they all end before it (rounded up to a
    /// whole frame).
    pub duration: Real,
    /// The end of the last force window, when they all end before the
    /// scene's duration (the release the recovery window counts from).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub release: Option<Real>,
    /// Settle-and-measure passes taken.
    pub passes: usize,
}

/// When `scene`'s last force window ends, if every one ends before its
/// duration: the release the recovery window counts from.
pub fn release_time(scene: &Scene) -> Option<Real> {
    let last = scene
        .forces
        .iter()
        .map(|f| f.end)
        .fold(None, |m: Option<Real>, e| Some(m.map_or(e, |m| m.max(e))))?;
    (last.is_finite() && last < scene.world.duration).then_some(last)
}

/// The critical damping and times of `omega1` for `scene` (see the
/// module docs and [`Damping::Critical`]), `mode` the slowest mode found.
pub fn critical_damping(
    scene: &Scene,
    mode: SlowestMode,
    schedule: &CriticalSchedule,
    passes: usize,
) -> CriticalDamping {
    let tau = 1.0 / mode.omega1;
    let (linear_damping, angular_damping) =
        critical_coefficients(mode.omega1, mode.mass, mode.inertia);
    let release = release_time(scene);
    // Whole frames: the runner ends at the last frame.
    let fr = scene.world.frame_rate;
    let duration = match release {
        Some(r) => scene
            .world
            .duration
            .max(((r + schedule.recovery * tau) * fr).ceil() / fr),
        None => scene.world.duration,
    };
    CriticalDamping {
        mode,
        tau,
        linear_damping,
        angular_damping,
        settle: scene.world.settle.max(schedule.settle * tau),
        duration,
        release,
        passes,
    }
}

/// `scene` with the numbers of `c` in place of the rule: damping, settle
/// phase and duration.
pub fn apply(scene: &Scene, c: &CriticalDamping) -> Scene {
    let mut s = scene.clone();
    s.world.linear_damping = Damping::Value(c.linear_damping);
    s.world.angular_damping = c.angular_damping;
    s.world.settle = c.settle;
    s.world.duration = c.duration;
    s
}

/// Finds the critical damping of `scene` (points files relative to
/// `base_dir`) by the settle-and-measure iteration of the module docs,
/// whatever its `linear_damping` says, and returns it with the scene
/// that runs it ([`apply`]). Building a scene with `linear_damping:
/// Critical` calls it; its trial settles may take as much work as the
/// scene's own limit ([`crate::WorkLimits::max_particle_steps`]).
///
/// # Errors
///
/// See [`resolve_within`].
pub fn resolve(
    scene: &Scene,
    base_dir: Option<&std::path::Path>,
) -> Result<(Scene, CriticalDamping), SceneError> {
    resolve_within(scene, base_dir, scene.limits.max_particle_steps)
}

/// [`resolve`] with its trial settles and mode analyses limited to
/// `max_particle_steps` particle-steps in all, each pair a step evaluates
/// counted as one and each step as 50 more (its fixed cost; `opsim check`
/// gives it a few seconds' worth).
///
/// # Errors
///
/// The scene's own validation and build errors, a divergence while
/// settling, or no slowest mode ([`ModeError`]: too large, a mechanism;
/// no state at rest in [`PASSES`] passes or within the work; a skinned
/// object, whose contact the modes cannot hold; creation rules), as a
/// [`SceneError::Build`] naming `world.linear_damping`.
pub fn resolve_within(
    scene: &Scene,
    base_dir: Option<&std::path::Path>,
    max_particle_steps: Real,
) -> Result<(Scene, CriticalDamping), SceneError> {
    let file = scene.origin().to_string();
    let fail = |message: String| SceneError::Build {
        file: file.clone(),
        message: format!("world.linear_damping = \"Critical\": {message}"),
    };
    if let Some(o) = scene.objects.iter().find(|o| o.skin.is_some()) {
        return Err(fail(format!(
            "object {:?} has a skin: skin contact acts outside the world's forces, so its modes \
             would leave it out (give the damping as a number)",
            o.name
        )));
    }
    if scene.creation.is_some() {
        return Err(fail(
            "the scene creates particles: the modes of the particles it starts with are not \
             those it runs with (give the damping as a number)"
                .into(),
        ));
    }
    // At least 3 degrees of freedom per particle: refuse a scene too large
    // before building it.
    let particles: usize = scene.particle_counts(base_dir)?.iter().sum();
    if 3 * particles > MAX_DEGREES_OF_FREEDOM {
        return Err(fail(
            ModeError::TooLarge {
                dof: 3 * particles,
                max: MAX_DEGREES_OF_FREEDOM,
            }
            .to_string(),
        ));
    }
    let schedule = CriticalSchedule::default();
    let mut numeric = scene.clone();
    numeric.world.linear_damping = Damping::Value(0.0);
    numeric.world.angular_damping = 0.0;
    let (start, pairs) = first_guess(&numeric, base_dir)?;
    let start = start.map_err(|e| fail(e.to_string()))?;
    let mut last = start.clone();
    // The first guess's analysis, at the most degrees of freedom a particle
    // has.
    let mut work = mode_work_of(6 * particles, particles);
    let found = converge(|omega, stretch| {
        let guess = SlowestMode {
            omega1: omega.unwrap_or(start.omega1),
            ..last.clone()
        };
        let c = critical_damping(&numeric, guess, &schedule, 0);
        let mut probe = apply(&numeric, &c);
        probe.world.settle *= stretch;
        let mut built = probe.build_world(base_dir, None)?;
        // Each step updates every particle and evaluates every pair (those
        // of the first guess's state), each counted as a particle-step,
        // and costs STEP_WORK more whatever its size.
        let interactions = (built.world().particles().len() + pairs + STEP_WORK) as Real;
        work += (probe.world.settle / probe.world.dt).ceil() * interactions;
        if work > max_particle_steps {
            return Err(fail(format!(
                "settling to find the slowest mode would take more than {} particle-steps \
                 (each pair's evaluation counted as one, each step as {STEP_WORK} more)",
                crate::error::short(max_particle_steps)
            )));
        }
        built
            .settle()
            .map_err(|e| fail(format!("while settling to find the slowest mode: {e}")))?;
        let basis = basis_of(&probe, built.world());
        work += mode_work(basis, built.world().particles().len());
        if work > max_particle_steps {
            return Err(fail(format!(
                "measuring the slowest mode again would take more than {} particle-steps",
                crate::error::short(max_particle_steps)
            )));
        }
        match slowest_mode(built.world_mut(), basis) {
            Ok(mode) => {
                let omega1 = mode.omega1;
                last = mode;
                Ok(Measured::Omega(omega1))
            }
            Err(ModeError::NotAtRest { .. }) => Ok(Measured::NotAtRest),
            // A mode without stiffness after a settle is a mechanism, not
            // a state short of rest (which shows negative ω²).
            Err(e) => Err(fail(e.to_string())),
        }
    })?;
    let Some((_, passes)) = found else {
        return Err(fail(format!(
            "no state at rest after {PASSES} settles (its slowest mode's ω² stays negative)"
        )));
    };
    let c = critical_damping(scene, last, &schedule, passes);
    Ok((apply(scene, &c), c))
}

/// The slowest mode's size at the built (generated) state of `scene`: the
/// first `ω²` in ascending order that is not zero, taken by magnitude (a
/// state not at rest has negative ones), with the masses it moves. The
/// first settle's damping and time.
/// Also returns the pairs the world evaluates at that state (its
/// neighbour list's and its bonds, built by the analysis's force
/// evaluations).
fn first_guess(
    scene: &Scene,
    base_dir: Option<&std::path::Path>,
) -> Result<(Result<SlowestMode, ModeError>, usize), SceneError> {
    let mut built = scene.build_world(base_dir, None)?;
    let basis = basis_of(scene, built.world());
    let dof = basis.per_particle() * built.world().particles().len();
    if dof > MAX_DEGREES_OF_FREEDOM {
        let too_large = ModeError::TooLarge {
            dof,
            max: MAX_DEGREES_OF_FREEDOM,
        };
        return Ok((Err(too_large), 0));
    }
    let mut m = modes(built.world_mut(), basis, true);
    let w = built.world_mut();
    let pairs = w.neighbour_pairs().map_or(0, |p| p.num_pairs()) + w.bonds().map_or(0, |b| b.len());
    let largest = m.omega2.iter().fold(0.0, |a: Real, l| a.max(l.abs()));
    let Some(k) = m.omega2.iter().position(|l| l.abs() > ZERO * largest) else {
        return Ok((Err(ModeError::NoMode), pairs));
    };
    m.omega2.drain(..k);
    m.shapes.drain(..k);
    for l in &mut m.omega2 {
        *l = l.abs();
    }
    Ok((slowest_of(&m, mean_moment(built.world())), pairs))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The iteration settles with the caller's start, then with each
    /// measured `ω1`; a pass short of rest doubles the next settle and
    /// does not count as a measurement; it stops at two measurements
    /// within 5%.
    #[test]
    fn converge_doubles_the_settle_short_of_rest_and_stops_within_five_percent() {
        let answers = [
            Measured::Omega(0.2),
            Measured::NotAtRest,
            Measured::NotAtRest,
            Measured::Omega(0.18),
            Measured::Omega(0.175),
        ];
        let mut calls = Vec::new();
        let found = converge(|omega, stretch| {
            calls.push((omega, stretch));
            Ok::<_, ()>(answers[calls.len() - 1].clone())
        })
        .unwrap();
        assert_eq!(found, Some((0.175, 5)));
        assert_eq!(
            calls,
            [
                (None, 1.0),
                (Some(0.2), 1.0),
                (Some(0.2), 2.0),
                (Some(0.2), 4.0),
                (Some(0.18), 1.0)
            ]
        );
        let never = converge(|_, _| Ok::<_, ()>(Measured::NotAtRest)).unwrap();
        assert_eq!(never, None);
        assert_eq!(converge(|_, _| Err::<Measured, _>("no")), Err("no"));
    }

    /// `D = c M` with `c = 2 ω1`: the slowest mode's damping ratio
    /// `β / (2 ω1 m)` is 1 for the linear and the angular part alike.
    #[test]
    fn the_coefficients_damp_the_slowest_mode_critically() {
        let (b0, b1) = critical_coefficients(0.25, 2.0, 0.3);
        assert_eq!(b0 / (2.0 * 0.25 * 2.0), 1.0);
        assert!((b1 / (2.0 * 0.25 * 0.3) - 1.0).abs() < 1e-15);
    }
}
