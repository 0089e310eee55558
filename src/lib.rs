//! Facade: the engine ([`op_dynamics`]), the scene layer ([`op_scene`]),
//! and the shape-memory [`experiments`] of seed 002.
pub use op_dynamics;
pub use op_modeling;
pub use op_render;
pub use op_scene;

pub mod experiments;
