//! # op-implicit: implicit skins on oriented-particle skeletons
//!
//! Seed 002 §6: skeleton primitives posed in particle frames,
//! a compact-support field kernel (Wyvill 1986), the summed field with
//! analytic gradient, and polygonization of its iso-surface (narrow-band
//! marching cubes over blocks, in parallel).
//!
//! Entry points:
//! - [`Primitive`] (point, segment, rectangle/square, ellipsoid) in a
//!   particle's body frame, with its support radius;
//! - [`Skin::new`] attaches primitives to the particles of an
//!   `op_dynamics::World`; [`Skin::repose`] follows the particles;
//! - [`Field`] (from [`Skin::field`]) evaluates the field and gradient,
//!   one point or many in parallel;
//! - [`polygonize()`] turns a field into a closed, outward-oriented
//!   [`Mesh`] with analytic normals.
//!
//! - [`ObstacleContact`] is a skin pressed into a rigid parry collider:
//!   [`ObstacleContact::reactions`] gives its particles the forces and
//!   torques of one contact energy ([`ObstacleContact::energy`]), applied
//!   with [`Reactions::apply`] (`World::add_external_force`).
//!
//! - [`ContactPair`] is the contact between two implicit objects (Gascuel
//!   1993): [`ContactPair::deformed_a`] / [`ContactPair::deformed_b`]
//!   are the deformed fields (exact contact surface, optional
//!   propagation-region [`Bulge`]), polygonized with [`polygonize_field`];
//!   [`ContactPair::reactions`] gives both objects' particles the forces
//!   and torques of one contact energy ([`ContactPair::energy`]; they sum
//!   to zero), applied with [`PairReactions::apply`].
#![warn(missing_docs)]

pub mod contact;
pub mod contact_forces;
pub mod error;
pub mod field;
pub mod friction;
mod grid;
pub mod implicit_contact;
pub mod kernel;
pub mod object_skin;
pub mod polygonize;
pub mod primitives;
pub mod skin;
pub mod skin_stages;
pub mod stretch;

pub use contact::{ClippedField, Reaction, Reactions};
pub use error::{PolygonizeError, SkinError};
pub use field::{Field, ScalarField};
pub use implicit_contact::{
    deform, Bulge, ContactPair, ContactSample, DeformedField, ImplicitContactParams,
    ObstacleContact, PairReactions,
};
pub use kernel::{iso_radius, ISO};
pub use polygonize::{
    is_closed_oriented_manifold, polygonize, polygonize_clipped, polygonize_deformed,
    polygonize_field, polygonize_region, polygonize_with_stats, Mesh, PolygonizeParams,
    PolygonizeStats, MAX_NODES_PER_AXIS,
};
pub use primitives::{PosedPrimitive, Primitive, Skeleton};
pub use skin::{Skin, SkinState};
pub use stretch::StretchCompensation;
