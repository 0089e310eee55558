//! # op-scene: scene files, validation, world building, running and export
//!
//! DESIGN §6. A scene file (RON or JSON) is read into one serde schema,
//! validated, and built into an op-dynamics [`op_dynamics::World`] that
//! contains only what the scene enables. The runner steps it and writes
//! OBJ frames, `metrics.csv` and `summary.json`; [`render`] draws pictures.
#![warn(missing_docs)]

pub mod built;
pub mod outputs;
pub mod render;

pub use built::{BuiltObject, BuiltScene};
pub use outputs::{Outputs, ParticleOutput};
