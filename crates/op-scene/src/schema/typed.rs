//! Building a scene in code: constructors and `with_*` methods on the
//! schema's own types, so a Rust program writes a scene as typed values
//! (no RON or JSON text) and gets the same validation as a file
//! ([`Scene::build`] validates).
//!
//! ```
//! use op_dynamics::interactions::{LennardJonesParams, Spacing};
//! use op_dynamics::Material;
//! use op_scene::features::Wind;
//! use op_scene::{Generator, ObjectSpec, Scene};
//!
//! let sheet = Material {
//!     spacing: Some(Spacing::LennardJones(LennardJonesParams {
//!         cutoff: 1.5,
//!         ..LennardJonesParams::default()
//!     })),
//!     coplanarity: 1.0,
//!     ..Material::empty()
//! };
//! let scene = Scene::new("breeze")
//!     .with_world(|w| {
//!         w.dt = 5e-3;
//!         w.duration = 1.0;
//!     })
//!     .with_material("sheet", sheet)
//!     .with_object(ObjectSpec::new(
//!         "sheet",
//!         "sheet",
//!         Generator::HexSheet {
//!             nx: 8,
//!             ny: 8,
//!             spacing: 1.0,
//!             center: [0.0; 3],
//!             normal: [0.0, 0.0, 1.0],
//!             noise: 0.0,
//!             seed: 0,
//!         },
//!     ))
//!     .with_feature(Wind {
//!         velocity: [1.0, 0.0, 0.0],
//!         drag: 0.2,
//!         gusts: Vec::new(),
//!         objects: None,
//!     });
//! let mut built = scene.build(None, None)?;
//! built.advance_to(0.5).expect("steps");
//! assert_eq!(built.world().particles().len(), 64);
//! # Ok::<(), op_scene::SceneError>(())
//! ```

use op_dynamics::{Material, Real};

use super::{ObjectSpec, Scene, ToolSpec, WorldSettings};
use crate::features::FeatureSpec;
use crate::generators::Generator;
use crate::outputs::Outputs;
use crate::skins::{SkinPrimitive, SkinSpec};

impl Scene {
    /// An empty scene named `name` with the default world settings
    /// ([`WorldSettings::default`]): add at least one object.
    pub fn new(name: impl Into<String>) -> Scene {
        Scene {
            name: name.into(),
            world: WorldSettings::default(),
            materials: Default::default(),
            objects: Vec::new(),
            forces: Vec::new(),
            tools: Vec::new(),
            features: Vec::new(),
            outputs: Outputs::default(),
            creation: None,
            origin: String::new(),
            limits: Default::default(),
            frames_override: None,
            expected_warnings: Vec::new(),
        }
    }

    /// Changes the world settings (`dt`, `duration`, gravity, ...).
    pub fn with_world(mut self, change: impl FnOnce(&mut WorldSettings)) -> Scene {
        change(&mut self.world);
        self
    }

    /// Adds (or replaces) the material `name`.
    pub fn with_material(mut self, name: impl Into<String>, material: Material) -> Scene {
        self.materials.insert(name.into(), material);
        self
    }

    /// Adds an object. A material it names that the scene does not define
    /// and that is a preset ([`crate::presets`]: `cloth`, ...) is added, as
    /// when a scene file is read.
    pub fn with_object(mut self, object: ObjectSpec) -> Scene {
        self.objects.push(object);
        crate::presets::resolve(&mut self);
        self
    }

    /// Adds a tool.
    pub fn with_tool(mut self, tool: ToolSpec) -> Scene {
        self.tools.push(tool);
        self
    }

    /// Adds a feature ([`crate::features`]: a `Wind`, a `SpeedClamp`).
    pub fn with_feature(mut self, feature: impl Into<FeatureSpec>) -> Scene {
        self.features.push(feature.into());
        self
    }

    /// Sets what the runner writes.
    pub fn with_outputs(mut self, outputs: Outputs) -> Scene {
        self.outputs = outputs;
        self
    }
}

impl ObjectSpec {
    /// An object `name` of material `material` (a key of the scene's
    /// materials or a preset's name) made by `generator`, every other
    /// setting at its default (mass 1, at rest, no skin).
    pub fn new(name: impl Into<String>, material: impl Into<String>, generator: Generator) -> Self {
        ObjectSpec {
            name: name.into(),
            material: material.into(),
            generator,
            mass: 1.0,
            inertia: [0.1; 3],
            normal_axis: [0.0, 0.0, 1.0],
            kind: Default::default(),
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            velocities: None,
            overrides: Vec::new(),
            skin: None,
        }
    }

    /// Gives the object an implicit skin.
    pub fn with_skin(mut self, skin: SkinSpec) -> Self {
        self.skin = Some(skin);
        self
    }

    /// Sets every particle's initial velocity.
    pub fn with_velocity(mut self, velocity: [Real; 3]) -> Self {
        self.velocity = velocity;
        self
    }
}

impl SkinSpec {
    /// A skin of `primitive`s with support radius `radius`, polygonized
    /// and sampled for contact at `cell_size`; every other setting at its
    /// default.
    pub fn new(primitive: SkinPrimitive, radius: Real, cell_size: Real) -> Self {
        SkinSpec {
            primitive,
            radius,
            cell_size,
            stiffness: 100.0,
            smoothness: crate::skins::DEFAULT_SMOOTHNESS,
            thickness: None,
            smoothing: 0,
        }
    }
}
