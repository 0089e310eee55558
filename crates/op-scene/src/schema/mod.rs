//! The scene schema (docs/scenes.md): one serde description read from RON or
//! JSON. Every struct denies unknown fields; every optional field documents
//! its default.
//!
//! ```
//! use op_scene::{parse_scene, Format};
//!
//! let ron = r#"(
//!     name: "sheet",
//!     world: (dt: 5e-3, duration: 20, linear_damping: 0.5),
//!     materials: {
//!         "membrane": (spacing: LennardJones((cutoff: 1.5)), coplanarity: 10),
//!     },
//!     objects: [
//!         (name: "sheet", material: "membrane",
//!          generator: HexSheet(nx: 20, ny: 20, spacing: 1, noise: 0.1)),
//!     ],
//! )"#;
//! let json = r#"{
//!     "name": "sheet",
//!     "world": {"dt": 5e-3, "duration": 20, "linear_damping": 0.5},
//!     "materials": {
//!         "membrane": {"spacing": {"LennardJones": {"cutoff": 1.5}}, "coplanarity": 10}
//!     },
//!     "objects": [
//!         {"name": "sheet", "material": "membrane",
//!          "generator": {"HexSheet": {"nx": 20, "ny": 20, "spacing": 1, "noise": 0.1}}}
//!     ]
//! }"#;
//! let a = parse_scene(ron, Format::Ron, "<doc.ron>")?;
//! let b = parse_scene(json, Format::Json, "<doc.json>")?;
//! assert_eq!(a.objects, b.objects);
//! assert_eq!(a.materials, b.materials);
//! let built = a.build(None, None)?;
//! assert_eq!(built.world().particles().len(), 400);
//! # Ok::<(), op_scene::SceneError>(())
//! ```
//!
//! The same in JSON: enum variants are objects with one key
//! (`{"HexSheet": {"nx": 20, ...}}`), unit variants strings (`"All"`).
//! In RON, `Option` fields may be written without `Some(...)`; newtype
//! variants such as `LennardJones((...))` take double parentheses (or
//! single ones with `#![enable(unwrap_variant_newtypes)]` at the top of the
//! file).
//!
//! Sections: [`Scene::world`] ([`WorldSettings`]), [`Scene::materials`]
//! (op-dynamics [`Material`]s by name), [`Scene::objects`]
//! ([`ObjectSpec`]: a [`Generator`], per-particle defaults and
//! [`Override`]s), [`Scene::forces`] ([`ForceSpec`]) and
//! [`Scene::outputs`] ([`Outputs`]). Validation: [`Scene::validate`];
//! building: [`Scene::build`].

pub(crate) mod checks;
pub mod fit;
mod footprint;
pub mod limits;
mod typed;
pub(crate) mod validate;
pub(crate) mod work;

pub use fit::FitSettings;
pub use limits::WorkLimits;
pub use work::WorkEstimate;

pub use validate::{MAX_COHESION_ALPHA_R0_SQUARED, MAX_COHESION_CUTOFF_OVER_R0};
use validate::{OBJECT_NAME_PATTERN, SCENE_NAME_PATTERN};

use std::collections::BTreeMap;

use op_dynamics::world::NeighbourParams;
use op_dynamics::{Material, ParticleType, Real, Scheme};
use serde::{Deserialize, Serialize};

use crate::creation::CreationSettings;
pub use crate::generators::{Generator, ListParticle};
use crate::outputs::Outputs;
use crate::skins::SkinSpec;

/// A scene: what to simulate, for how long, and what to write.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene name: the summary's `scene` field and the default output
    /// folder name. Non-empty; no path separators, no control characters,
    /// not `.` or `..`. Required.
    #[schemars(length(min = 1), regex(pattern = SCENE_NAME_PATTERN))]
    #[schemars(extend("not" = {"enum": [".", ".."]}))]
    pub name: String,
    /// Time stepping, neighbour lists and global external actions.
    /// Default: [`WorldSettings::default`].
    #[serde(default)]
    pub world: WorldSettings,
    /// Materials by name (op-dynamics [`Material`] as is). Only those used
    /// by some object go into the world. Default: none.
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    /// The objects, at least one. Each object is its own object id: its
    /// particles interact completely with each other and only repel other
    /// objects' (seed 002 §5). Required.
    pub objects: Vec<ObjectSpec>,
    /// Forces on particle sets over time windows. Default: none.
    #[serde(default)]
    pub forces: Vec<ForceSpec>,
    /// Tools: parry shapes with scripted motion acting as obstacles,
    /// attractors or movers (seed 000 §6). Skinned objects meet obstacle
    /// tools through their skins (seed 002 §6). Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tools: Vec<ToolSpec>,
    /// Optional features ([`crate::features`], [`crate::features::FeatureSpec`]
    /// lists them), each at most once. Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub features: Vec<crate::features::FeatureSpec>,
    /// What the runner writes. Default: [`Outputs::default`].
    #[serde(default)]
    pub outputs: Outputs,
    /// Particle creation rules (seed 000 §7; see [`crate::creation`]).
    /// Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub creation: Option<CreationSettings>,
    /// Where the scene came from (file path or a label such as
    /// `<demo>`), used in error messages. Not part of the file: set by
    /// [`crate::load_scene`] / [`crate::parse_scene`]. Default: empty
    /// (shown as `<scene>`).
    #[serde(skip)]
    pub origin: String,
    /// The work limits validation applies ([`WorkLimits`]). Not part of the
    /// file: set by the caller (`opsim --no-work-limits`). Default:
    /// [`WorkLimits::default`].
    #[serde(skip)]
    pub limits: WorkLimits,
    /// The frame count the runner was asked for (`opsim run --frames N`,
    /// [`Scene::set_frames`]), which set `world.duration`: named in the
    /// errors of a run too long. Not part of the file. Default: `None`.
    #[serde(skip)]
    pub frames_override: Option<usize>,
    /// The warnings the scene expects, from its file's header lines
    /// `// expect-warning: TEXT (why)` (the TEXT of each). A run whose
    /// object breaks into pieces is a divergence (exit 3) unless an
    /// expected warning begins its message (`object "sheet" broke into 2
    /// pieces`): tearing and cutting scenes declare their pieces so.
    /// Not part of the file's data: set by [`crate::load_scene`] /
    /// [`crate::parse_scene`]. Default: none.
    #[serde(skip)]
    pub expected_warnings: Vec<String>,
}

/// The TEXT of each `// expect-warning: TEXT (why)` line of a scene file
/// (see [`Scene::expected_warnings`]).
pub fn expected_warnings(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("// expect-warning: "))
        .map(|t| t.split(" (").next().unwrap_or(t).trim().to_string())
        .filter(|t| !t.is_empty())
        .collect()
}

impl Scene {
    /// The origin label used in messages (`<scene>` when unset).
    pub fn origin(&self) -> &str {
        if self.origin.is_empty() {
            "<scene>"
        } else {
            &self.origin
        }
    }
}

fn one_thousandth() -> Real {
    1e-3
}
fn one() -> Real {
    1.0
}
fn thirty() -> Real {
    30.0
}
fn infinity() -> Real {
    Real::INFINITY
}
fn million() -> Real {
    1e6
}
/// Infinite defaults are left out when serializing: JSON has no infinity.
fn is_infinite(v: &Real) -> bool {
    *v == Real::INFINITY
}

/// Time stepping, neighbour lists and global external actions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WorldSettings {
    /// Time integration scheme (`ExplicitEuler`, `SymplecticEuler`,
    /// `VelocityVerlet`, `Rk4`, `Adaptive((rtol: ...))`). Default:
    /// `VelocityVerlet`.
    #[serde(default = "default_scheme")]
    pub integrator: Scheme,
    /// Time step (fixed-step schemes), or initial and largest step
    /// (adaptive), > 0. Default: 1e-3.
    #[serde(default = "one_thousandth")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub dt: Real,
    /// Simulated duration, > 0 (after the settle phase). Default: 1.
    #[serde(default = "one")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub duration: Real,
    /// Settle phase, >= 0: the runner advances the scene by this duration
    /// before frame 0, every stage acting (tools, skin contact, creation)
    /// but no force window (every force window's
    /// `start` and `end` count from the end of the settle phase), and takes
    /// the settled positions as the rest shape (the reference of the rest
    /// shape error and its rest spacing). Generated shapes are close to, not
    /// exactly at, rest (docs/model.md §7: a spiral made from its analytic
    /// curvature); settling first makes the reference a true rest state.
    /// Times in `metrics.csv` and `summary.json` count from the end of the
    /// settle phase. Building a scene does not settle it; see
    /// [`crate::BuiltScene::settle`]. Default: 0 (no settle phase).
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub settle: Real,
    /// Frames written per unit of simulated time, > 0. Default: 30.
    #[serde(default = "thirty")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub frame_rate: Real,
    /// Neighbour-list settings. Default: [`NeighbourParams::default`].
    #[serde(default)]
    pub neighbours: NeighbourParams,
    /// Gravity acceleration. Default: zero.
    #[serde(default)]
    pub gravity: [Real; 3],
    /// Linear damping `β0` (force `-β0 v`): a number >= 0, or `"Critical"`
    /// (quoted, in RON and JSON) for the critical damping of the scene's
    /// slowest deformation mode (seed 002 §5), which also sets the angular
    /// damping and lengthens the settle phase and the run as that rule
    /// needs: see [`Damping::Critical`]. Default: 0.
    #[serde(default)]
    pub linear_damping: Damping,
    /// Angular damping `β1` (torque `-β1 ω`), >= 0. With `linear_damping:
    /// "Critical"` it follows the rule (`β1 = 2 ω1 I`) and must be left out
    /// (or 0). Default: 0.
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub angular_damping: Real,
    /// When a run is declared diverged. Default:
    /// [`DivergenceSettings::default`].
    #[serde(default)]
    pub divergence: DivergenceSettings,
    /// Arithmetic of the pair kernels (op-dynamics
    /// [`op_dynamics::Precision`]): `double`, or `mixed` for `f32` pair
    /// lanes with `f64` sums and integration in the kernels that have them
    /// (12-6 Lennard-Jones spacing of one material). Default: double.
    #[serde(default)]
    pub precision: op_dynamics::Precision,
    /// Heat conduction and cooling (op-dynamics [`op_dynamics::HeatParams`],
    /// seed 000 §6, §8), needed by heater and knife tools. Default: none
    /// (temperatures stay as set).
    #[serde(default)]
    pub heat: Option<op_dynamics::HeatParams>,
}

fn default_scheme() -> Scheme {
    Scheme::VelocityVerlet
}

impl Default for WorldSettings {
    fn default() -> Self {
        WorldSettings {
            integrator: default_scheme(),
            dt: one_thousandth(),
            duration: one(),
            settle: 0.0,
            frame_rate: thirty(),
            neighbours: NeighbourParams::default(),
            gravity: [0.0; 3],
            linear_damping: Damping::Value(0.0),
            angular_damping: 0.0,
            divergence: DivergenceSettings::default(),
            precision: op_dynamics::Precision::Double,
            heat: None,
        }
    }
}

impl WorldSettings {
    /// The world's parameters (op-dynamics [`op_dynamics::WorldParams`]):
    /// these settings with the force windows `forces`. A
    /// [`Damping::Critical`] linear damping counts as 0 here: building the
    /// scene resolves it to numbers first ([`crate::damping::resolve`]).
    pub fn params(&self, forces: Vec<op_dynamics::ForceWindow>) -> op_dynamics::WorldParams {
        op_dynamics::WorldParams {
            scheme: self.integrator,
            dt: self.dt,
            neighbours: self.neighbours.clone(),
            external: op_dynamics::ExternalParams {
                gravity: self.gravity,
                linear_damping: self.linear_damping.value().unwrap_or(0.0),
                angular_damping: self.angular_damping,
                forces,
            },
            divergence: op_dynamics::world::DivergenceParams {
                max_speed: self.divergence.max_speed,
            },
            precision: self.precision,
            heat: self.heat.clone(),
        }
    }

    /// The field of these settings (`world.<field>`) that the field
    /// `field` of [`WorldSettings::params`] comes from.
    pub(crate) fn field_of_param(field: &str) -> String {
        let field = field.strip_prefix("external.").unwrap_or(field);
        match field.strip_prefix("scheme") {
            Some(rest) => format!("world.integrator{rest}"),
            None => format!("world.{field}"),
        }
    }
}

/// The linear damping of a scene's world ([`WorldSettings::linear_damping`]):
/// a coefficient, or the rule that computes it.
///
/// RON: `linear_damping: 0.3` or `linear_damping: "Critical"`; JSON:
/// `"linear_damping": 0.3` or `"linear_damping": "Critical"`. The rule is
/// a quoted string in both (in RON a bare `Critical` is refused: ron 0.10
/// does not pass the name of a bare identifier on to a field that also
/// takes numbers).
#[derive(Copy, Clone, Debug, PartialEq, schemars::JsonSchema)]
pub enum Damping {
    /// Critical damping of the scene's slowest deformation mode (seed 002
    /// §5; the rule and its measurements are in the API documentation of
    /// [`crate::damping`]). Building the scene settles it, finds the
    /// angular frequency `ω1` of its slowest mode at rest and repeats with
    /// the damping of that `ω1` until `ω1` changes by less than 5%; then,
    /// with `τ = 1/ω1`:
    ///
    /// - linear damping `β0 = 2 ω1 m` and angular damping `β1 = 2 ω1 I` (`m`, `I`: the mass and moment of inertia that mode moves, a particle's own when all are equal): damping proportional to the masses damps that mode critically and leaves no mode decaying slower than `(1 + ω1 t) e^(-ω1 t)`;
    /// - the settle phase lasts at least 12 `τ` (the settled state is the reference of the rest shape error: it must be at rest);
    /// - when every force window ends before `duration`, the run lasts at least 20 `τ` after the last one ends, rounded up to a whole frame (the recovery window the shape-memory report measured).
    ///
    /// The times matter as much as the damping: 14-particle spirals that
    /// the fixed damping 0.3 leaves 0.016 to 0.024 from their shape after
    /// a settle of 40 and 40 time units of recovery (about 7 `τ` each)
    /// end 0.03 to 0.04 from it with the critical damping in the same
    /// times, and below 0.001 with the rule's.
    ///
    /// `opsim check` prints `ω1`, the damping and the times, `summary.json`
    /// holds them (`critical_damping`). Limits: the modes are computed
    /// densely, for at most 600 degrees of freedom (200 particles in a
    /// plane, 100 in space); in the plane `z = 0` for a scene whose motion
    /// stays there (every particle in it, turned about `z`, no force, tool,
    /// skin or creation to take it out), in space otherwise, where a
    /// mechanism (a chain's torsion, a free hinge: no stiffness) has no
    /// frequency and the rule cannot be applied: building such a scene is
    /// refused, as is one with a skinned object (skin contact acts outside
    /// the world's forces and cannot be part of the modes) or with creation
    /// rules (its particles change).
    Critical,
    /// The coefficient `β0` (force `-β0 v`), >= 0, in M/T.
    #[schemars(untagged)]
    Value(#[schemars(range(min = 0))] Real),
}

impl Default for Damping {
    fn default() -> Self {
        Damping::Value(0.0)
    }
}

impl Damping {
    /// The coefficient, when it is given as one.
    pub fn value(self) -> Option<Real> {
        match self {
            Damping::Value(v) => Some(v),
            Damping::Critical => None,
        }
    }

    /// Whether it is [`Damping::Critical`].
    pub fn is_critical(self) -> bool {
        self == Damping::Critical
    }
}

impl From<Real> for Damping {
    fn from(v: Real) -> Self {
        Damping::Value(v)
    }
}

/// Scaling a coefficient (dimensional analysis: `op_experiments`'
/// scaling); the rule scales itself.
impl std::ops::MulAssign<Real> for Damping {
    fn mul_assign(&mut self, s: Real) {
        if let Damping::Value(v) = self {
            *v *= s;
        }
    }
}

impl Serialize for Damping {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Damping::Value(v) => s.serialize_f64(*v),
            Damping::Critical => s.serialize_str("Critical"),
        }
    }
}

/// Reads a number or the string `"Critical"`. RON writes the rule quoted
/// too: with serde 1.0.220 and later, ron 0.10 hands a field that takes
/// numbers a bare name as a unit value without the name (ron-rs/ron#583,
/// fixed in ron 0.12), so a misspelt bare name could not be told from
/// `Critical`; a bare name is refused with a message saying so.
impl<'de> Deserialize<'de> for Damping {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Reader;
        impl serde::de::Visitor<'_> for Reader {
            type Value = Damping;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number >= 0 or \"Critical\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Damping, E> {
                Ok(Damping::Value(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Damping, E> {
                Ok(Damping::Value(v as Real))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Damping, E> {
                Ok(Damping::Value(v as Real))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Damping, E> {
                if v == "Critical" {
                    Ok(Damping::Critical)
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
            fn visit_unit<E: serde::de::Error>(self) -> Result<Damping, E> {
                Err(E::custom(
                    "expected a number >= 0 or \"Critical\" (quoted, in RON too: a bare name \
                     cannot be read here)",
                ))
            }
        }
        d.deserialize_any(Reader)
    }
}

/// When a run is declared diverged (besides NaN / infinite values, which
/// always are).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DivergenceSettings {
    /// Largest particle speed considered physical, > 0 (infinity disables
    /// the check). Default: infinity.
    #[serde(default = "infinity", skip_serializing_if = "is_infinite")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_speed: Real,
    /// The run is declared diverged when the kinetic energy exceeds this
    /// factor times the initial energy scale (see
    /// [`crate::BuiltScene::energy_growth`]), > 0 (infinity disables the
    /// check; JSON has no infinity literal: use a huge number there).
    /// Default: 1e6.
    #[serde(default = "million")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub energy_growth: Real,
    /// Opt-in check for passive scenes (no force window, zero gravity, no
    /// implicit contact: damping can only remove energy): the run is
    /// declared diverged when the total energy at a frame exceeds the
    /// lowest total energy of the earlier frames by more than this
    /// fraction of the initial energy scale (see
    /// [`crate::BuiltScene::energy_gain`]): the integrator put the energy
    /// in. Catches bounded instabilities that never reach NaN, a speed
    /// limit or runaway energy (`scenes/extreme/tight_curvature.ron`), > 0.
    /// Default: infinity (off; JSON: omit it).
    #[serde(default = "infinity", skip_serializing_if = "is_infinite")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub energy_gain: Real,
    /// Explosion threshold: the run is declared diverged (exit 3) when a
    /// particle gets this many scene sizes beyond the scene's bounds (the
    /// box of the particles at frame 0 and of the tools over the run,
    /// grown by the motion gravity, initial velocities and force windows
    /// can cause; see `op_scene::health`), > 0. Default: 1e4; infinity
    /// disables the check.
    #[serde(
        default = "extent_growth",
        skip_serializing_if = "is_default_extent_growth"
    )]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub extent_growth: Real,
}

fn extent_growth() -> Real {
    crate::health::DEFAULT_EXTENT_GROWTH
}
fn is_default_extent_growth(v: &Real) -> bool {
    *v == extent_growth()
}

impl Default for DivergenceSettings {
    fn default() -> Self {
        DivergenceSettings {
            max_speed: infinity(),
            energy_growth: million(),
            energy_gain: infinity(),
            extent_growth: extent_growth(),
        }
    }
}

fn default_inertia() -> [Real; 3] {
    [0.1; 3]
}
fn plus_z() -> [Real; 3] {
    [0.0, 0.0, 1.0]
}

/// Per-particle initial velocities of an object ([`ObjectSpec::velocities`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub enum Velocities {
    /// A points file (`.xyz`, `.ply`, `.obj`; relative to the scene file)
    /// whose `i`-th point is the velocity of the object's `i`-th particle in
    /// generation order; it holds exactly one point per particle. RON:
    /// `velocities: Some(File("v.xyz"))`.
    File(std::path::PathBuf),
    /// Maxwell-Boltzmann velocities at temperature `t` (`k_B = 1`, each
    /// particle's mass), drawn from `seed`, then, as LAMMPS' `velocity
    /// create`, the object's net momentum removed and the velocities scaled
    /// so its kinetic temperature (`3N - 3` degrees of freedom) is `t`
    /// exactly. RON: `velocities: Some(Temperature(t: 1.44, seed: 87287))`.
    Temperature {
        /// Temperature, >= 0.
        #[schemars(range(min = 0))]
        t: Real,
        /// Seed of the draw.
        seed: u64,
    },
}

/// One object: a set of particles made by a generator, sharing a material
/// and an object id.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Object name, unique in the scene (OBJ object name, summary).
    /// Non-empty, no control characters. Required.
    #[schemars(length(min = 1), regex(pattern = OBJECT_NAME_PATTERN))]
    pub name: String,
    /// Name of its material: a key of [`Scene::materials`], or the name of
    /// a preset ([`crate::presets`]: `cloth`, `elastic_shell`,
    /// `shape_memory_wire`, `plastic_clay`; see docs/units.md for the
    /// step and damping each was tested with). Required.
    pub material: String,
    /// How its particles are made. Required.
    pub generator: Generator,
    /// Mass of each particle, > 0. Default: 1.
    #[serde(default = "one")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub mass: Real,
    /// Principal moments of inertia (body frame), each > 0.
    /// Default: `[0.1, 0.1, 0.1]`.
    #[serde(default = "default_inertia")]
    #[schemars(transform = op_dynamics::schema_rules::positive_items)]
    pub inertia: [Real; 3],
    /// Body-frame normal axis `a` (normalized; the world normal is
    /// `R(q) a`). Default: +z.
    #[serde(default = "plus_z")]
    #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
    pub normal_axis: [Real; 3],
    /// Particle type of seed 002 §5 (`Standard(k)` or `Hinge`).
    /// Default: `Standard(0)`.
    #[serde(default)]
    pub kind: ParticleType,
    /// Initial velocity of every particle. Default: zero.
    #[serde(default)]
    pub velocity: [Real; 3],
    /// Initial angular velocity (world frame). Default: zero.
    #[serde(default)]
    pub angular_velocity: [Real; 3],
    /// Per-particle initial velocities, added to `velocity`: from a file
    /// or drawn at a temperature (to reproduce a peer's benchmark, e.g.
    /// LAMMPS' `velocity create`). Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocities: Option<Velocities>,
    /// Per-particle changes, applied in order after generation.
    /// Default: none.
    #[serde(default)]
    pub overrides: Vec<Override>,
    /// An implicit skin on its particles (seed 002 §6; see
    /// [`crate::skins`]): RON `skin: Some((primitive: Square(half_side:
    /// 0.5), radius: 1.2, cell_size: 0.2))`. Two skinned objects are in
    /// implicit contact. Default: none (nothing of op-implicit is built).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin: Option<SkinSpec>,
}

/// Which particles of an object (indices in generation order).
///
/// RON: `All`, `List([0, 5, 9])`, `Range(0, 10)`, `First(3)`, `Last(3)`.
/// JSON: `"All"`, `{"List": [0, 5, 9]}`, `{"Range": [0, 10]}`,
/// `{"First": 3}`, `{"Last": 3}`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub enum Selection {
    /// Every particle.
    #[default]
    All,
    /// These indices (each `< count`; a repeated index counts once).
    List(#[schemars(length(min = 1))] Vec<usize>),
    /// Indices `start..end` (half open, `start < end <= count`).
    Range(usize, usize),
    /// The first `n` particles (`1 <= n <= count`).
    First(#[schemars(range(min = 1))] usize),
    /// The last `n` particles (`1 <= n <= count`).
    Last(#[schemars(range(min = 1))] usize),
}

impl Selection {
    /// Checks the selection against an object of `count` particles; the
    /// error says what is allowed.
    pub fn check(&self, count: usize) -> Result<(), String> {
        match self {
            Selection::All => Ok(()),
            Selection::List(v) => {
                if v.is_empty() {
                    return Err("= List([]): selects no particle; give at least one index".into());
                }
                match v.iter().find(|&&i| i >= count) {
                    Some(bad) => Err(format!(
                        "= List([..]): index {bad} is out of range (valid indices: 0..{count}, the object has {count} particles)"
                    )),
                    None => Ok(()),
                }
            }
            Selection::Range(a, b) => {
                if a < b && *b <= count {
                    Ok(())
                } else {
                    Err(format!(
                        "= Range({a}, {b}): out of range (need start < end <= {count}; valid indices: 0..{count})"
                    ))
                }
            }
            Selection::First(n) | Selection::Last(n) => {
                if *n >= 1 && *n <= count {
                    Ok(())
                } else {
                    let which = if matches!(self, Selection::First(_)) {
                        "First"
                    } else {
                        "Last"
                    };
                    Err(format!(
                        "= {which}({n}): out of range (need 1 <= n <= {count}, the object has {count} particles)"
                    ))
                }
            }
        }
    }

    /// The selected indices for an object of `count` particles, ascending
    /// and without duplicates (a listed index counts once; out-of-range
    /// entries are dropped: [`Selection::check`] first).
    pub fn indices(&self, count: usize) -> Vec<usize> {
        match self {
            Selection::All => (0..count).collect(),
            Selection::List(v) => {
                let mut v: Vec<usize> = v.iter().copied().filter(|&i| i < count).collect();
                v.sort_unstable();
                v.dedup();
                v
            }
            Selection::Range(a, b) => (*a..(*b).min(count)).collect(),
            Selection::First(n) => (0..(*n).min(count)).collect(),
            Selection::Last(n) => (count.saturating_sub(*n)..count).collect(),
        }
    }
}

/// Changes to some particles of an object, applied after generation in the
/// order given. Unset fields leave the particles as they are.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Override {
    /// Which particles. Default: `All`.
    #[serde(default)]
    pub particles: Selection,
    /// Fix (true) or free (false) their positions. Default: unchanged.
    #[serde(default)]
    pub fixed_position: Option<bool>,
    /// Fix (true) or free (false) their orientations. Default: unchanged.
    #[serde(default)]
    pub fixed_orientation: Option<bool>,
    /// Make them unoriented (spacing forces only, seed 000 §6) or oriented.
    /// Default: unchanged.
    #[serde(default)]
    pub unoriented: Option<bool>,
    /// Set their particle type. Default: unchanged.
    #[serde(default)]
    pub kind: Option<ParticleType>,
    /// Set their rest curvature (finite). Default: unchanged.
    #[serde(default)]
    pub curvature: Option<Real>,
    /// Set their temperature (finite; heat, seed 000 §6, §8). Default:
    /// unchanged (0).
    #[serde(default)]
    pub temperature: Option<Real>,
    /// Set their mass (> 0). Default: unchanged.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub mass: Option<Real>,
}

/// A force on some particles of an object over a time window (op-dynamics
/// [`op_dynamics::ForceWindow`] over global particle ids).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// Name of the object. Required.
    pub object: String,
    /// Which of its particles (each gets the full force). Default: `All`.
    #[serde(default)]
    pub particles: Selection,
    /// The force vector at full magnitude (finite). Required.
    pub force: [Real; 3],
    /// Start time (finite). Default: 0.
    #[serde(default)]
    pub start: Real,
    /// End time, > start (infinity allowed). Default: infinity.
    #[serde(default = "infinity", skip_serializing_if = "is_infinite")]
    pub end: Real,
    /// Linear ramp at each end, >= 0 and at most half of `end - start`.
    /// Default: 0 (a step load).
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub ramp: Real,
}

/// A tool in a scene: op-modeling's [`op_modeling::ToolParams`] naming
/// the objects it acts on. Keyframe times and a mover's `release` count
/// from the end of the settle phase, like force windows.
pub type ToolSpec = op_modeling::ToolParams<String>;
