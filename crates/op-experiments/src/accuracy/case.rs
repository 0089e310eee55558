//! The cases of the work-precision study (docs/model.md §6, error
//! against run time): a scene, the scene times it is sampled at, the steps and
//! tolerances swept, and the reference method. The list is data
//! ([`case_table`]): a scene file becomes a case with one [`CaseEntry`].

use std::path::{Path, PathBuf};

use op_dynamics::interactions::Spacing;
use op_dynamics::{AdaptiveParams, Real, Scheme};
use op_scene::{load_scene, Generator, ObjectSpec, Scene, WorldSettings};

use crate::matching::reference_cohesion;
use crate::spiral::{SpiralRecipe, SpiralShape};

/// An integrator with its time step: the step of a fixed-step scheme, or
/// the largest step of [`Scheme::Adaptive`] (whose tolerance is in the
/// scheme).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Method {
    /// The integrator.
    pub scheme: Scheme,
    /// Time step (fixed-step schemes) or largest step (adaptive).
    pub dt: Real,
}

impl Method {
    /// `scheme` with step `dt` (the largest step, for an adaptive scheme
    /// whose tolerances are in its parameters).
    pub fn new(scheme: Scheme, dt: Real) -> Method {
        Method { scheme, dt }
    }

    /// The adaptive Dormand–Prince scheme with every tolerance `tol` and
    /// largest step `dt_max`.
    pub fn adaptive(tol: Real, dt_max: Real) -> Method {
        Method {
            scheme: Scheme::Adaptive(AdaptiveParams::with_tolerance(tol)),
            dt: dt_max,
        }
    }

    /// The adaptive tolerance (`rtol`), `None` for fixed-step schemes.
    pub fn tolerance(&self) -> Option<Real> {
        match self.scheme {
            Scheme::Adaptive(p) => Some(p.rtol),
            _ => None,
        }
    }

    /// The same scheme made finer: half the step for a fixed-step scheme,
    /// a tenth of the tolerance for the adaptive one (the check that a
    /// reference has converged).
    pub fn refined(&self) -> Method {
        match self.scheme {
            Scheme::Adaptive(p) => Method::adaptive(p.rtol / 10.0, self.dt),
            _ => Method::new(self.scheme, self.dt / 2.0),
        }
    }

    /// `rk4 dt=0.001`, `adaptive tol=1e-8 (dt<=0.01)`.
    pub fn label(&self) -> String {
        match self.tolerance() {
            Some(tol) => format!("adaptive tol={tol:e} (dt<={})", self.dt),
            None => format!("{} dt={}", self.scheme.name(), self.dt),
        }
    }
}

/// Where a case's scene comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A scene file, relative to the repository root.
    File(&'static str),
    /// [`triangle_scene`]: the cohesion triangle, undamped.
    Triangle,
    /// [`free_spiral_scene`]: the seed spiral released from its analytic
    /// shape, undamped, without friction or load.
    FreeSpiral,
}

/// One line of the case table: plain data, turned into a [`Case`] by
/// [`CaseEntry::load`].
#[derive(Clone, Debug, PartialEq)]
pub struct CaseEntry {
    /// Short name (file names, table headings).
    pub name: &'static str,
    /// One sentence on what the case is and why it is there.
    pub about: &'static str,
    /// The scene.
    pub source: SceneSource,
    /// Scene times (after the settle phase) at which the state is
    /// compared with the reference; the run ends at the last one.
    pub samples: Vec<Real>,
    /// True when nothing damps or drives the motion (no damping, no
    /// friction, no force window, no gravity, no contact): the total
    /// energy (kinetic + internal potential) is then conserved and its
    /// drift is reported.
    pub conservative: bool,
    /// Time steps swept for the fixed-step schemes.
    pub steps: Vec<Real>,
    /// Further (smaller) steps swept for the two first-order schemes
    /// (explicit and symplectic Euler) only: they need them to reach the
    /// errors the others reach at the common steps.
    pub first_order_steps: Vec<Real>,
    /// Tolerances swept for the adaptive scheme (empty: not run).
    pub tolerances: Vec<Real>,
    /// Largest step of the adaptive scheme.
    pub adaptive_dt_max: Real,
    /// The coarser of the two reference runs: the finer one
    /// ([`Method::refined`], half the step) is the reference the runs are
    /// measured against, and the difference between the two bounds its
    /// error (see [`super::sweep::sweep_case`]).
    pub reference: Method,
}

/// A loaded case.
#[derive(Clone, Debug)]
pub struct Case {
    /// The table line it came from.
    pub entry: CaseEntry,
    /// The scene (its integrator and step are replaced per run).
    pub scene: Scene,
    /// Directory that relative paths inside the scene are resolved from.
    pub base_dir: Option<PathBuf>,
    /// The length unit of the errors: the rest distance `r0` of the first
    /// object's spacing potential.
    pub r0: Real,
}

impl CaseEntry {
    /// Loads the scene (files relative to `root`) and finds `r0`.
    ///
    /// # Errors
    ///
    /// The scene file's load or validation message.
    pub fn load(&self, root: &Path) -> Result<Case, String> {
        let (scene, base_dir) = match &self.source {
            SceneSource::File(rel) => {
                let path = root.join(rel);
                let scene = load_scene(&path).map_err(|e| e.to_string())?;
                (scene, path.parent().map(Path::to_path_buf))
            }
            SceneSource::Triangle => (triangle_scene(0.8), None),
            SceneSource::FreeSpiral => (free_spiral_scene(), None),
        };
        let r0 = scene
            .objects
            .first()
            .and_then(|o| scene.materials.get(&o.material))
            .and_then(|m| match m.spacing {
                Some(Spacing::Cohesion(c)) => Some(c.r0),
                Some(Spacing::LennardJones(l)) => Some(l.r0),
                None => None,
            })
            .or_else(|| {
                scene
                    .objects
                    .first()
                    .and_then(|o| o.generator.nominal_spacing())
            })
            .unwrap_or(1.0);
        Ok(Case {
            entry: self.clone(),
            scene,
            base_dir,
            r0,
        })
    }
}

impl Case {
    /// The methods swept: every fixed-step scheme at every step (the
    /// first-order ones also at [`CaseEntry::first_order_steps`]), then the
    /// adaptive scheme at every tolerance.
    pub fn methods(&self) -> Vec<Method> {
        let e = &self.entry;
        let mut out = Vec::new();
        for scheme in fixed_schemes() {
            let extra = if scheme.order() == 1 {
                &e.first_order_steps[..]
            } else {
                &[]
            };
            for &dt in e.steps.iter().chain(extra) {
                out.push(Method::new(scheme, dt));
            }
        }
        for &tol in &e.tolerances {
            out.push(Method::adaptive(tol, e.adaptive_dt_max));
        }
        out
    }
}

/// The fixed-step schemes, in the order of the tables.
pub fn fixed_schemes() -> [Scheme; 4] {
    [
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
    ]
}

/// The cohesion triangle of seed 002 §3 (`crates/op-experiments/src/triangle.rs`):
/// three unit-mass particles held by the reference cohesion (`E = 200`,
/// `r0 = 1`, `α = 16`, cut-off 1.5), started at rest on an equilateral
/// triangle of side `p · r0`, here WITHOUT damping, so it breathes for ever
/// and its energy is conserved. Translation only (no orientation terms).
pub fn triangle_scene(p: Real) -> Scene {
    let c = reference_cohesion();
    let h = 3f64.sqrt() / 2.0;
    let corners = [[0.0, 0.0], [1.0, 0.0], [0.5, h]];
    let particles = corners
        .iter()
        .map(|[x, y]| op_scene::generators::ListParticle {
            position: [x * p * c.r0, y * p * c.r0, 0.0],
            normal: None,
            curvature: None,
        })
        .collect();
    let mut materials = std::collections::BTreeMap::new();
    materials.insert(
        "cohesion".to_string(),
        op_dynamics::Material {
            spacing: Some(Spacing::Cohesion(c)),
            ..op_dynamics::Material::empty()
        },
    );
    Scene {
        name: "triangle".into(),
        world: WorldSettings {
            integrator: Scheme::VelocityVerlet,
            dt: 1e-3,
            duration: 1.0,
            ..WorldSettings::default()
        },
        materials,
        objects: vec![ObjectSpec::new(
            "triangle",
            "cohesion",
            Generator::List { particles },
        )],
        forces: Vec::new(),
        tools: Vec::new(),
        features: Vec::new(),
        creation: None,
        outputs: Default::default(),
        origin: "<triangle>".into(),
        limits: Default::default(),
        frames_override: None,
        expected_warnings: Vec::new(),
    }
}

/// The seed spiral of [`SpiralRecipe`] (cohesion, form, co-planarity;
/// `scenes/spiral.ron` without its settle phase, damping, friction and
/// end forces), released at rest from its analytic shape, which is close
/// to but not at rest (docs/model.md §7): it oscillates about its rest shape,
/// rotating its particles, with its energy conserved. Every force is
/// smooth and independent of velocities, so each scheme should show its
/// nominal order.
pub fn free_spiral_scene() -> Scene {
    let mut scene = SpiralRecipe::default().scene("spiral_free", &SpiralShape::seed());
    scene.world.settle = 0.0;
    scene.world.linear_damping = 0.0.into();
    scene.world.angular_damping = 0.0;
    scene.forces.clear();
    for m in scene.materials.values_mut() {
        m.friction = 0.0;
    }
    scene.origin = "<spiral_free>".into();
    scene
}

/// The cases of `reports/accuracy.md`, in order. The sweeps are chosen so
/// that the whole report runs in a few minutes in release (each run is
/// timed five times).
pub fn case_table() -> Vec<CaseEntry> {
    vec![
        CaseEntry {
            name: "triangle",
            about: "The cohesion triangle of seed 002 §3 started at 80% of its rest side, \
                    undamped: three particles breathing, translation only.",
            source: SceneSource::Triangle,
            samples: vec![0.0, 2.5, 5.0, 7.5, 10.0],
            conservative: true,
            steps: vec![0.02, 0.01, 0.005, 0.0025, 0.00125],
            first_order_steps: vec![0.000625],
            tolerances: vec![1e-4, 1e-6, 1e-8, 1e-10],
            adaptive_dt_max: 0.5,
            reference: Method::new(Scheme::Rk4, 1.25e-4),
        },
        CaseEntry {
            name: "spiral_free",
            about: "The seed spiral released from its analytic shape without damping, \
                    friction or load: ten oriented particles oscillating about their rest \
                    shape, energy conserved.",
            source: SceneSource::FreeSpiral,
            samples: vec![0.0, 2.5, 5.0, 7.5, 10.0],
            conservative: true,
            steps: vec![0.02, 0.01, 0.005, 0.0025, 0.00125],
            first_order_steps: vec![0.000625],
            tolerances: vec![1e-4, 1e-6, 1e-8, 1e-10],
            adaptive_dt_max: 0.5,
            reference: Method::new(Scheme::Rk4, 1.25e-4),
        },
        CaseEntry {
            name: "spiral",
            about: "`scenes/spiral.ron` (seed 002 fig. 5): settle 40, then the ends pulled \
                    apart by ramped forces, held, released, recovery to scene time 80; \
                    damped, with inter-particle friction.",
            source: SceneSource::File("scenes/spiral.ron"),
            samples: vec![0.0, 10.0, 30.0, 40.0, 60.0, 80.0],
            conservative: false,
            steps: vec![0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125],
            // Explicit Euler is first order: the two finest steps are where
            // it reaches 1e-6 r0 (measured, not extrapolated).
            first_order_steps: vec![0.000625, 0.0003125, 0.000078125, 0.0000390625],
            tolerances: vec![1e-4, 1e-6, 1e-8, 1e-10],
            adaptive_dt_max: 0.5,
            reference: Method::new(Scheme::Rk4, 2.5e-4),
        },
        CaseEntry {
            name: "drape_sphere",
            about: "`scenes/drape_sphere.ron` (seed 000 fig. 12a): a 400-particle \
                    Lennard-Jones cloth with co-planarity falling under gravity onto a rigid \
                    parry ball (obstacle tool, penalty contact with normal damping); sampled \
                    to scene time 3 (the first contact and the start of the fold).",
            source: SceneSource::File("scenes/drape_sphere.ron"),
            samples: vec![0.0, 1.0, 2.0, 3.0],
            conservative: false,
            steps: vec![0.01, 0.005, 0.0025, 0.00125],
            first_order_steps: vec![0.000625],
            tolerances: vec![1e-4, 1e-6, 1e-8],
            adaptive_dt_max: 0.05,
            reference: Method::new(Scheme::Rk4, 2.5e-4),
        },
        CaseEntry {
            name: "ball_vs_spiral",
            about: "`scenes/ball_vs_spiral.ron` (seed 002 fig. 6): the skinned spiral hit by \
                    a skinned ball, implicit contact (the gradient of Gascuel's contact energy) \
                    evaluated by the op-scene runner at every force evaluation; sampled to scene \
                    time 20 (the hit and the start of the recovery). The adaptive scheme runs at \
                    one tolerance (Findings).",
            source: SceneSource::File("scenes/ball_vs_spiral.ron"),
            samples: vec![0.0, 2.5, 5.0, 10.0, 20.0],
            conservative: false,
            steps: vec![0.01, 0.005],
            first_order_steps: Vec::new(),
            tolerances: vec![1e-6],
            adaptive_dt_max: 0.01,
            reference: Method::new(Scheme::Rk4, 1.25e-3),
        },
    ]
}
