//! Features: optional actions a scene lists in [`crate::Scene::features`],
//! each one file of this module behind the [`Feature`] trait and one line
//! of the registry below.
//!
//! A feature's settings deserialize straight into its own type (the scene
//! schema, the JSON schema and `docs/scenes.md` come from it), are checked
//! once by [`Feature::validate`] and made into a driver stage by
//! [`Feature::stage`] ([`Phase::Step`](op_dynamics::driver::Phase::Step)),
//! which the builder pushes into the scene's driver before the scene's own
//! stages. The stage lends the world's steps what the feature does
//! ([`Stage::lend`]): a force as an
//! op-dynamics [`Contributor`](op_dynamics::contributors::Contributor), an
//! action after every step as an
//! [`AfterStep`](op_dynamics::world::AfterStep). The driver then lists it
//! ([`crate::BuiltScene::stages`]), times it and asks it whether it may
//! add energy (passive scenes are checked for energy gain) and how fast it
//! can move particles (the explosion check's allowance). A scene that
//! lists no feature pays for none. Features act when the scene advances
//! through its driver ([`crate::BuiltScene::advance_to`], the runner, the
//! settle phase), not when a caller steps its world directly
//! ([`crate::BuiltScene::world_mut`]).
//!
//! Adding a feature: write `features/<name>.rs` with its settings type
//! (serde, schemars, a doc comment on every field), its `UNITS` (the unit
//! of each numeric field, for the scene reference) and its [`Feature`]
//! impl, then add one line `Name => module::Type,` to the `features!`
//! list below.

use op_dynamics::driver::Stage;
use op_dynamics::Real;

use crate::built_scene::BuiltObject;
use crate::error::SceneError;
use crate::schema::Scene;
use crate::stages::SceneState;

/// What [`Feature::stage`] reads of the built scene.
pub struct InstallContext<'a> {
    /// The scene's objects, in scene order (object `k` has object id `k`).
    pub objects: &'a [BuiltObject],
    /// World time at which scene time 0 falls (the settle phase's length):
    /// times in a feature's settings count from there.
    pub settle: Real,
}

/// A feature of [`crate::Scene::features`]; see the module docs.
pub trait Feature {
    /// Checks the settings against the scene, once, before building; `path`
    /// is the field path for messages (`features[2].Wind`).
    ///
    /// # Errors
    ///
    /// What is wrong and what would be valid, naming `path`.
    fn validate(&self, scene: &Scene, path: &str) -> Result<(), SceneError>;

    /// The feature as a driver stage, acting through what it lends the
    /// world's steps ([`Stage::lend`]); its name is unique in the scene's
    /// driver (a second feature of one kind is refused when the scene is
    /// built).
    fn stage(&self, ctx: &InstallContext<'_>) -> Box<dyn Stage<SceneState>>;
}

/// Declares the registered features: each line `Variant => module::Type`
/// adds a variant of [`FeatureSpec`] read from the scene file as
/// `Variant((...))` (RON) or `{"Variant": {...}}` (JSON).
macro_rules! features {
    ($($variant:ident => $module:ident :: $ty:ident,)*) => {
        $(pub mod $module; pub use $module::$ty;)*

        /// One entry of [`crate::Scene::features`].
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
        #[serde(deny_unknown_fields)]
        pub enum FeatureSpec {
            $(
                #[doc = concat!("The `", stringify!($variant), "` feature: [`", stringify!($ty), "`].")]
                $variant($ty),
            )*
        }

        $(
            impl From<$ty> for FeatureSpec {
                fn from(feature: $ty) -> FeatureSpec {
                    FeatureSpec::$variant(feature)
                }
            }
        )*

        impl FeatureSpec {
            /// The feature's variant name (as written in the scene file).
            pub fn name(&self) -> &'static str {
                match *self {
                    $(FeatureSpec::$variant(_) => stringify!($variant),)*
                }
            }

            /// The feature behind the entry.
            pub fn feature(&self) -> &dyn Feature {
                match *self {
                    $(FeatureSpec::$variant(ref f) => f,)*
                }
            }
        }

        /// The unit of every numeric field of the registered features, as
        /// [`crate::reference::units::UNITS`] gives those of the rest of
        /// the scene.
        pub fn units() -> impl Iterator<Item = (&'static str, &'static str)> {
            std::iter::empty()$(.chain($module::UNITS.iter().copied()))*
        }
    };
}

features! {
    Wind => wind::Wind,
    SpeedClamp => speed_clamp::SpeedClamp,
}

/// The object ids a feature acts on: those named in `names` (every
/// object when `None`), as a mask by object id. Names are checked by
/// [`check_objects`] first; unknown ones are left out.
pub fn object_mask(objects: &[BuiltObject], names: Option<&[String]>) -> Vec<bool> {
    objects
        .iter()
        .map(|o| names.is_none_or(|n| n.contains(&o.name)))
        .collect()
}

/// Checks that every name in `names` is an object of `scene`
/// (`path.objects[i]` in messages), as a tool's `objects` are checked.
pub fn check_objects(
    scene: &Scene,
    path: &str,
    names: Option<&[String]>,
) -> Result<(), SceneError> {
    scene.check_object_names(path, names)
}
