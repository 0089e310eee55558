//! Facade of oriented-particles: the engine ([`op_dynamics`]), modeling
//! (tools, creation rules, triangulation: [`op_modeling`]), the scene layer
//! ([`op_scene`]: schema, builder, runner, export) and the renderer
//! ([`op_render`]). The `opsim` command line is this package's binary.
pub use op_dynamics;
pub use op_modeling;
pub use op_render;
pub use op_scene;

/// The engine's and the scene layer's preludes in one import:
/// `use oriented_particles::prelude::*;`.
pub mod prelude {
    pub use op_dynamics::prelude::*;
    pub use op_scene::prelude::*;
}
