//! # op-implicit: implicit skins on oriented-particle skeletons
//!
//! Seed 002 §6 and DESIGN §5: skeleton primitives posed in particle frames,
//! compact-support field kernels, polygonization with the `isosurface`
//! crate, and contact (against parry colliders and between implicit
//! objects, Gascuel's model) fed back to the particles through
//! `op_dynamics::World::add_external_force`.
//!
//! This crate holds no code yet: the skinning and contact work is tracked as
//! its own issue, and the workspace builds and tests without it.
#![warn(missing_docs)]
