//! # op-dynamics: the oriented particle engine
//!
//! Oriented particles (Szeliski & Tonnesen 1992, seed 000) with the shape
//! memory extensions of Lombardo & Puech 1995 (seed 002): cohesion force,
//! form interaction with per-particle curvature, hinge/standard typing and
//! object membership.
//!
//! Entry points: build a [`Particles`] store from [`ParticleDesc`]s, describe
//! the interactions with [`Material`]s, and make a [`World`] with
//! [`WorldParams`] (integrator, time step, neighbour lists, external actions).
//! [`World::step`] advances it; [`World::diagnostics`] reports energies,
//! momenta and the oscillation measure. Other crates act on particles through
//! [`World::add_external_force`].
//!
//! Surface modeling (seed 000 §5, §7): [`World::insert_particles`] and
//! [`World::remove_particles`] edit the particle set between steps (ids stay
//! stable). The modeling side — tools, heat sources, creation rules, the
//! triangulation and point-set fitting — is the op-modeling crate; tools act
//! on a world through [`ToolSet`] ([`World::set_tools`]).
#![warn(missing_docs)]

/// Shortest run of particles (or pairs) a per-element parallel loop hands
/// to another thread: below it the loop runs on the calling thread. A
/// parallel iterator called from outside the pool otherwise injects its
/// job and waits for a pool thread at every call, even over ten particles:
/// a 10-particle world's force evaluation then spent most of its time in
/// futex waits (the uniform field's loop; `opsim check` of a small scene
/// took 8 s on a loaded machine, 1 s of it computing). Public for the
/// per-particle loops of the crates above (tools, features).
pub const MIN_PARALLEL_LEN: usize = 1024;

pub mod bond_memory;
pub mod bonds;
pub mod checkpoint;
pub mod contributors;
pub mod diagnostics;
pub mod driver;
pub mod error;
pub mod external;
pub mod flags;
pub(crate) mod forces;
pub mod heat;
pub mod integrators;
pub mod interactions;
pub(crate) mod lanes;
pub mod math;
pub mod neighbours;
pub mod particles;
pub mod plasticity;
pub mod prelude;
pub mod schema_rules;
pub mod tooling;
pub mod world;

pub use diagnostics::Diagnostics;
pub use error::ParamError;
pub use external::{ExternalParams, ForceWindow};
pub use flags::Flags;
pub use forces::Precision;
pub use heat::{HeatParams, HeatResponse};
pub use integrators::{AdaptiveParams, Scheme};
pub use interactions::Material;
pub use lanes::isa as simd_isa;
pub use math::{Mat3, Point3, Quat, Real, Vec3};
pub use neighbours::NeighbourBackend;
pub use particles::{ParticleDesc, ParticleType, Particles};
pub use tooling::ToolSet;
pub use world::{Divergence, Merge, NeighbourParams, World, WorldError, WorldParams};
