//! # op-modeling: shaping surfaces made of oriented particles
//!
//! The modeling side of Szeliski & Tonnesen's oriented particle systems
//! (seed 000 §5-7), on top of the op-dynamics engine:
//!
//! - [`tools`] (seed 000 §6): rigid shapes with scripted motion that act on
//!   the particles — obstacles, attractors, movers, erasers, knives,
//!   heaters (the heat sources of op-dynamics' heat stage) and shapers.
//!   [`tools::Tools`] is the world's [`op_dynamics::ToolSet`]: give it to a
//!   world with [`op_dynamics::World::set_tools`].
//! - [`creation`] (seed 000 §7): the stretching and growing rules that add
//!   particles where a surface opens up, and the merging rule.
//! - [`fit`] (seed 000 §7): a surface of oriented particles through a
//!   point set (normals, spacing, seeds, filling by the creation rules,
//!   release, triangulation, holes).
//! - [`triangulation`] (seed 000 §5): particles to triangles for rendering,
//!   with the topology checks (Euler characteristic, boundary loops,
//!   manifold).
#![warn(missing_docs)]

pub mod cell_map;
pub mod creation;
pub mod disjoint_sets;
pub mod fit;
pub mod tools;
pub mod triangulation;

pub use tools::{Keyframe, Role, Tool, ToolParams, ToolShape, Tools};
