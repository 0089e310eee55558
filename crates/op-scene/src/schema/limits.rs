//! Work limits: every scene that validates runs in bounded time and memory.
//!
//! A scene's numbers are checked against these before anything is built
//! (`opsim check` and `opsim run` alike), each error naming the field, the
//! value and what is allowed. The limits are far beyond the shipped scenes;
//! `opsim run --no-work-limits` (and `check`) lifts them for a user who
//! means it ([`WorkLimits::unlimited`]). The length and precision bounds
//! ([`MAX_EXTENT_OVER_SPACING`], [`MAX_ROTATION`]) are not work limits and
//! always hold: beyond them a finite run is not possible in f64.

use op_dynamics::Real;

/// Largest distance of any coordinate of the scene from the origin, and
/// largest tool size, in units of the scene's length scale (its largest
/// generator or material spacing): beyond it positions lose the precision
/// the interactions need (f64 keeps 16 digits).
pub const MAX_EXTENT_OVER_SPACING: Real = 1e9;
/// Largest keyframe rotation angle of a tool path, in radians (a thousand
/// turns): beyond it the angle has no fractional precision left.
pub const MAX_ROTATION: Real = 2e3 * std::f64::consts::PI;
/// Largest number of grid nodes per axis of a skin's polygonization:
/// op-implicit's own limit ([`op_implicit::MAX_NODES_PER_AXIS`]).
pub const MAX_SKIN_NODES_PER_AXIS: Real = op_implicit::MAX_NODES_PER_AXIS as Real;
/// Largest `conduction * dt` of the heat settings: the heat update takes
/// about `2 conduction dt` times the neighbour weights sub-steps per step.
pub const MAX_CONDUCTION_STEP: Real = 100.0;

/// Pair interactions a particle-step may cost within the default limits:
/// a hexagonal sheet at its rest spacing with a cut-off of 2.5 spacings
/// has about 20 neighbours per particle.
pub const PAIRS_PER_PARTICLE_STEP: Real = 30.0;

/// Bounds on the work a scene may ask for.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkLimits {
    /// Largest number of time steps (settle phase and run; fixed-step
    /// schemes). Default: 1e8.
    pub max_steps: Real,
    /// Largest number of particle-steps (particles times steps). Default:
    /// 1e12 (about a day on this project's reference machine).
    pub max_particle_steps: Real,
    /// Largest estimated number of pair-steps (interacting pairs times
    /// steps): particles packed far closer than their material's cut-off
    /// each interact with many neighbours, so particle-steps alone do not
    /// bound the work. Estimated per object from its generator's spacing
    /// and dimension (chains 1, sheets and shells 2, solids 3) and its
    /// material's interaction range or bond radius, for points files and
    /// lists from a sample of their particles' neighbourhoods, plus the
    /// pairs between objects whose regions overlap. Skin field evaluations
    /// and triangulation pairs over the run are held to the same limit.
    /// Default: [`PAIRS_PER_PARTICLE_STEP`] times `max_particle_steps`.
    pub max_pair_steps: Real,
    /// Largest number of interacting pairs held at once (the neighbour
    /// list, bonds, triangulations: about 20 to 40 bytes each), estimated
    /// as for `max_pair_steps` and between objects whose regions overlap
    /// too. Default: 2e8.
    pub max_pairs: Real,
    /// Largest number of objects. Default: 1e4 (a scene's checks compare
    /// objects pairwise for overlaps).
    pub max_objects: Real,
    /// Largest number of frames. Default: 1e6.
    pub max_frames: Real,
    /// Largest `creation.max_particles`. Default: 1e7.
    pub max_created: Real,
}

impl Default for WorkLimits {
    fn default() -> Self {
        WorkLimits {
            max_steps: 1e8,
            max_particle_steps: 1e12,
            max_pair_steps: PAIRS_PER_PARTICLE_STEP * 1e12,
            max_pairs: 2e8,
            max_objects: 1e4,
            max_frames: 1e6,
            max_created: 1e7,
        }
    }
}

impl WorkLimits {
    /// These limits with `max_particle_steps` set to `n`, and the pair-step
    /// limit with it ([`PAIRS_PER_PARTICLE_STEP`] pairs per particle-step).
    pub fn with_particle_steps(mut self, n: Real) -> Self {
        self.max_particle_steps = n;
        self.max_pair_steps = PAIRS_PER_PARTICLE_STEP * n;
        self
    }

    /// No work limit (`--no-work-limits`): only what a finite run needs is
    /// checked.
    pub fn unlimited() -> Self {
        WorkLimits {
            max_steps: Real::INFINITY,
            max_particle_steps: Real::INFINITY,
            max_pair_steps: Real::INFINITY,
            max_pairs: Real::INFINITY,
            max_objects: Real::INFINITY,
            max_frames: Real::INFINITY,
            max_created: Real::INFINITY,
        }
    }
}
