//! # op-dynamics: the oriented particle engine
//!
//! Oriented particles (Szeliski & Tonnesen 1992, seed 000) with the shape
//! memory extensions of Lombardo & Puech 1995 (seed 002): cohesion force,
//! form interaction with per-particle curvature, hinge/standard typing and
//! object membership.
#![warn(missing_docs)]

pub mod error;
pub mod flags;
pub mod integrators;
pub mod interactions;
pub mod math;
pub mod neighbours;

pub use error::ParamError;
pub use flags::Flags;
pub use math::{Mat3, Point3, Quat, Real, Vec3};
