//! # op-scene: scene files, validation, world building, running and export
//!
//! README "Running scenes". A scene file (RON or JSON) is read into one serde schema,
//! validated, and built into an op-dynamics [`op_dynamics::World`] that
//! contains only what the scene enables. The runner steps it and writes
//! OBJ frames, `metrics.csv` and `summary.json`; the `op-render` crate draws pictures of them.
#![warn(missing_docs)]

pub mod built_scene;
pub mod creation;
pub mod damping;
pub mod export;
pub mod features;
pub mod fit;
pub mod health;
pub mod input;
pub mod modes;
pub mod outputs;
pub mod pointsets;
pub mod prelude;
pub mod presets;
pub mod reference;
pub mod run;
mod skin_shape;
pub mod skins;
pub mod stability;
pub mod stages;

pub use built_scene::{BuiltObject, BuiltScene};
pub use creation::CreationSettings;
pub use outputs::{Outputs, ParticleOutput};
pub use run::{run, run_with_stop, CheckpointEvery, RunError, RunOptions, Summary};
pub use skins::{ContactStats, ObjectSkin, SkinPrimitive, SkinSpec, SkinTool};

pub mod builder;
pub mod error;
pub mod generators;
pub mod load;
pub mod schema;

pub use error::SceneError;
pub use generators::{CurvatureLaw, Generator};
pub use load::{
    build_scene_file, load_scene, load_scene_estimated, load_scene_with, parse_scene, Format,
};
pub use schema::{
    Damping, DivergenceSettings, ForceSpec, ObjectSpec, Override, Scene, Selection, ToolSpec,
    WorkEstimate, WorkLimits, WorldSettings,
};
