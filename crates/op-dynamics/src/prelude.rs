//! What a program driving a world usually needs, in one import:
//! `use op_dynamics::prelude::*;`.

pub use crate::contributors::{Contribution, Contributor, ContributorInput};
pub use crate::driver::{Driver, Effects, Phase, Stage, StageError};
pub use crate::interactions::{CohesionParams, LennardJonesParams, Spacing, WeightParams};
pub use crate::world::{AfterStep, AfterStepContext, StepReport};
pub use crate::{
    Divergence, ExternalParams, Flags, ForceWindow, Material, ParticleDesc, ParticleType,
    Particles, Point3, Quat, Real, Scheme, Vec3, World, WorldError, WorldParams,
};
