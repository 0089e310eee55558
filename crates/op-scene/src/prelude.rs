//! What a program building and running scenes usually needs, in one
//! import: `use op_scene::prelude::*;`.

pub use crate::export::FrameFormat;
pub use crate::features::{SpeedClamp, Wind};
pub use crate::skins::{SkinPrimitive, SkinSpec};
pub use crate::{
    load_scene, run, BuiltScene, Damping, Generator, ObjectSpec, Outputs, ParticleOutput,
    RunOptions, Scene, SceneError, Summary, ToolSpec, WorldSettings,
};
