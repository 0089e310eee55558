//! A world's state between two steps, saved and restored exactly: what a
//! checkpoint of a long run holds so that the run can continue after a
//! crash as if it had never stopped (op-scene `checkpoint`, `opsim run
//! --resume`).
//!
//! [`crate::World::state`] takes everything that changes as the world steps: the
//! particles (positions, velocities, orientations, angular velocities and
//! every per-particle attribute, in their current slot order), the
//! integrator's carried state (velocity Verlet's cached forces and angular
//! momenta, the adaptive controller's suggestion and its first-same-as-last
//! stage), the neighbour list (its reference positions and pairs: the same
//! pairs in the same order give the same sums to the last bit; worlds on
//! the cluster kernel hold no pairs, their cluster rows being searched
//! again from the reference positions), the bonds
//! and their remembered offsets, the pending external forces, the tools'
//! state ([`crate::ToolSet::save_state`]), the time, the step count and the
//! next step size. [`crate::World::restore`] puts it into a world built from the
//! same inputs (materials, parameters, tools): everything derived from the
//! particle set (kernel, neighbour radius, after-step stages) is derived
//! again, so a restored world steps bit for bit as the saved one would.
//!
//! The encoding ([`encode`], [`decode`]) is postcard's: compact, exact for
//! floats (their bits), and stable across postcard 1.x. It carries no
//! version of its own: its owner records one ([`STATE_VERSION`]) and
//! refuses what it does not know.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::bonds::Bonds;
use crate::external::ExternalAccumulator;
use crate::integrators::Integrator;
use crate::math::{Point3, Real, Vec3};
use crate::neighbours::NeighbourList;
use crate::particles::Particles;

/// Version of the layout of [`WorldState`]: bumped whenever a field of it,
/// or of the types it holds, changes, so that a checkpoint of another
/// layout is refused instead of misread. Version 4: the neighbour list
/// records whether it holds its particle rows (worlds on the cluster
/// kernel leave them unsearched, and their checkpoints without them).
pub const STATE_VERSION: u32 = 4;

/// Encodes `value` (postcard).
pub fn encode<T: Serialize>(value: &T) -> Vec<u8> {
    // Serializing into a vector fails only for types serde cannot encode
    // without a length (none of ours).
    postcard::to_stdvec(value).unwrap_or_else(|e| panic!("checkpoint encoding failed: {e}"))
}

/// [`encode`] of a world state in parts, encoded side by side (a large
/// world's state is mostly its particles, bonds and neighbour list, each
/// of tens of megabytes): the parts one after another are its encoding,
/// since postcard writes a struct as its fields one after another,
/// without lengths or tags. Left in parts, for a writer that needs no
/// copy of the whole. [`crate::World::encode_state`] gives the same parts
/// without taking the state.
pub fn encode_state(state: &WorldState) -> Vec<Vec<u8>> {
    let s = state;
    encode_parts(StateRef {
        particles: &s.particles,
        integrator: &s.integrator,
        neighbours: &s.neighbours,
        bonds: &s.bonds,
        tools: s.tools.clone(),
        accumulator: &s.accumulator,
        forces: &s.forces,
        torques: &s.torques,
        prev_positions: &s.prev_positions,
        scalars: (s.time, s.steps, s.dt_next, s.may_rotate, s.forced_in_a_row),
    })
}

/// A world state's fields, borrowed (the tools' state is made on demand):
/// what [`encode_parts`] writes.
pub(crate) struct StateRef<'a> {
    pub particles: &'a Particles,
    pub integrator: &'a Integrator,
    pub neighbours: &'a Option<NeighbourList>,
    pub bonds: &'a Option<Bonds>,
    pub tools: Option<Vec<u8>>,
    pub accumulator: &'a ExternalAccumulator,
    pub forces: &'a [Vec3],
    pub torques: &'a [Vec3],
    pub prev_positions: &'a [Point3],
    /// `time`, `steps`, `dt_next`, `may_rotate`, `forced_in_a_row`.
    pub scalars: (Real, u64, Real, bool, u32),
}

/// The parts of [`encode_state`], in [`WorldState`]'s field order.
pub(crate) fn encode_parts(s: StateRef<'_>) -> Vec<Vec<u8>> {
    use rayon::prelude::*;
    (0..6)
        .into_par_iter()
        .map(|k| match k {
            0 => encode(s.particles),
            1 => encode(s.integrator),
            2 => encode(s.neighbours),
            3 => encode(s.bonds),
            4 => encode(&(&s.tools, s.accumulator, s.forces, s.torques)),
            _ => encode(&(s.prev_positions, s.scalars)),
        })
        .collect()
}

/// Decodes what [`encode`] wrote; the whole input must be used.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, StateError> {
    let (value, rest) =
        postcard::take_from_bytes(bytes).map_err(|e| StateError(format!("cannot decode: {e}")))?;
    if !rest.is_empty() {
        return Err(StateError(format!(
            "{} bytes left over after the state",
            rest.len()
        )));
    }
    Ok(value)
}

/// The default restore of a part that keeps no state: only the empty
/// state is its own.
pub fn no_state(name: &str, state: &[u8]) -> Result<(), StateError> {
    if state.is_empty() {
        Ok(())
    } else {
        Err(StateError(format!(
            "{name} keeps no state, but the checkpoint holds {} bytes for it",
            state.len()
        )))
    }
}

/// Why a state could not be restored: it does not decode, or it does not
/// belong to this world (another particle count, materials, integrator).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct StateError(pub String);

/// Everything a world changes as it steps (module docs). Opaque: taken
/// with [`World::state`], put back with [`World::restore`], encoded with
/// [`encode`].
///
/// [`World::state`]: crate::World::state
/// [`World::restore`]: crate::World::restore
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WorldState {
    pub(crate) particles: Particles,
    pub(crate) integrator: Integrator,
    pub(crate) neighbours: Option<NeighbourList>,
    pub(crate) bonds: Option<Bonds>,
    pub(crate) tools: Option<Vec<u8>>,
    pub(crate) accumulator: ExternalAccumulator,
    pub(crate) forces: Vec<Vec3>,
    pub(crate) torques: Vec<Vec3>,
    pub(crate) prev_positions: Vec<Point3>,
    pub(crate) time: Real,
    pub(crate) steps: u64,
    pub(crate) dt_next: Real,
    pub(crate) may_rotate: bool,
    /// Adaptive steps forced through at `dt_min` in a row
    /// ([`crate::world::divergence::MAX_FORCED_STEPS`]).
    pub(crate) forced_in_a_row: u32,
}

impl WorldState {
    /// Simulation time of the state.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken up to the state.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The particles of the state.
    pub fn particles(&self) -> &Particles {
        &self.particles
    }
}
