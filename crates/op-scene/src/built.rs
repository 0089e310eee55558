//! A scene turned into a world: what the runner needs and nothing more.

use std::path::PathBuf;

use op_dynamics::{Point3, Real, World};

use crate::outputs::Outputs;

/// One object of a built scene.
#[derive(Clone, Debug)]
pub struct BuiltObject {
    /// Object name (unique in the scene; the OBJ object name).
    pub name: String,
    /// Stable particle ids of the object, in generation order.
    pub ids: Vec<u32>,
    /// Rest positions (positions at build time, in `ids` order): the
    /// reference of the rest shape error.
    pub rest: Vec<Point3>,
    /// Mean nearest-neighbour distance at rest: the `r0` that divides the
    /// rest shape error (DESIGN §6).
    pub rest_spacing: Real,
}

/// A validated scene built into a world containing only what it enables.
pub struct BuiltScene {
    /// Scene name (summary `scene` field, default output folder name).
    pub name: String,
    /// The file it came from, if any.
    pub source: Option<PathBuf>,
    /// The world, ready to step.
    pub world: World,
    /// The objects, in scene order.
    pub objects: Vec<BuiltObject>,
    /// Simulated duration.
    pub duration: Real,
    /// Frames written per unit of simulated time.
    pub frame_rate: Real,
    /// What to write.
    pub outputs: Outputs,
    /// Runaway-energy threshold: the run is declared diverged when the
    /// kinetic energy exceeds `energy_growth` times the initial energy
    /// scale (|kinetic| + |potential| at t = 0, at least 1e-12 per
    /// particle). Default 1e6; infinity disables the check.
    pub energy_growth: Real,
}
