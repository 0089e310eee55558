//! Implicit skins of scene objects and their contact (DESIGN §5, seed 002
//! §6 fig. 6).
//!
//! An object with a [`SkinSpec`] gets one op-implicit skeleton primitive
//! per particle ([`SkinPrimitive`]); the builder turns them into a
//! [`BuiltSkin`] (an op-implicit [`Skin`]). Nothing of op-implicit is built
//! for a scene without skins (see [`crate::BuiltScene::stages`]).
//!
//! **Runner.** Before every world step of the simulated duration (not the
//! settle phase, during which skins are neither posed nor in contact) the
//! skins are re-posed on the particles and, for every pair of skinned
//! objects, [`ContactPair::reactions`] (Gascuel's exact contact surface,
//! no bulge) is computed and applied to the world for that step
//! ([`op_implicit::PairReactions::apply`]): contact is explicit, one
//! evaluation per world step. With contact the world is therefore advanced
//! one step of `dt` at a time (with the adaptive scheme a step of `dt` may
//! be split; the reactions then act on its first sub-step only). Each written frame holds each skin polygonized
//! (undeformed field) as an extra OBJ object `<object>_skin` with vertex
//! normals from the analytic field gradient.
//!
//! **Figures** ([`ContactStats`], `summary.json` `contact`):
//! `total_impulse` is the sum over steps of `|F| dt`, `F` the total contact
//! force on the second object of each pair (summed over pairs);
//! `max_penetration` is the largest overlap of the two undeformed skins
//! over all contact samples and steps, in units of `r0` (the smaller rest
//! spacing of the pair): at a sample of the contact surface with common
//! excess `e`, the overlap thickness along the normal is, to first order,
//! `e / |grad f_A| + e / |grad f_B|` (how deep each undeformed skin reaches
//! past the contact surface, summed).

use op_dynamics::{Real, World};
use op_implicit::{
    polygonize, ContactPair, ImplicitContactParams, Mesh, PolygonizeParams, Primitive, Skin,
};
use serde::{Deserialize, Serialize};

use crate::built::BuiltObject;
use crate::error::SceneError;
use crate::schema::checks::positive;

/// The skeleton primitive attached to each particle of a skinned object.
///
/// RON: `Square(half_side: 0.5)`, `Point`. JSON: `{"Square": {"half_side":
/// 0.5}}`, `"Point"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SkinPrimitive {
    /// The square of seed 002 fig. 6: centred on the particle,
    /// perpendicular to its normal axis (the object's `normal_axis`).
    Square {
        /// Half side length, >= 0 (world units). Required.
        half_side: Real,
    },
    /// A point at the particle (an isotropic blob of radius `radius / 2`).
    Point,
}

fn hundred() -> Real {
    100.0
}

/// An object's implicit skin (seed 002 §6): one primitive per particle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkinSpec {
    /// The primitive attached to every particle. Required.
    pub primitive: SkinPrimitive,
    /// Support radius `R` of the field kernel, > 0: an isolated primitive's
    /// skin lies at `R / 2` from it. Required.
    pub radius: Real,
    /// Cell size of polygonization and of contact sampling, > 0 (the pair
    /// uses the smaller of its two). Required.
    pub cell_size: Real,
    /// Contact pressure per unit removed field excess, >= 0 (a pair uses the
    /// mean of its two). Default: 100.
    #[serde(default = "hundred")]
    pub stiffness: Real,
}

impl SkinSpec {
    /// Checks the numbers; `path` is the skin's scene path for messages.
    pub(crate) fn validate(&self, file: &str, path: &str) -> Result<(), SceneError> {
        positive(file, &format!("{path}.radius"), self.radius)?;
        positive(file, &format!("{path}.cell_size"), self.cell_size)?;
        if !(self.stiffness.is_finite() && self.stiffness >= 0.0) {
            return Err(SceneError::value(
                file,
                format!("{path}.stiffness"),
                self.stiffness,
                "must be finite and >= 0",
            ));
        }
        if let SkinPrimitive::Square { half_side } = self.primitive {
            if !(half_side.is_finite() && half_side >= 0.0) {
                return Err(SceneError::value(
                    file,
                    format!("{path}.primitive.Square.half_side"),
                    half_side,
                    "must be finite and >= 0",
                ));
            }
        }
        Ok(())
    }

    /// The primitive in a particle's body frame (`normal_axis`: the
    /// object's body-frame normal axis).
    pub fn primitive(&self, normal_axis: [Real; 3]) -> Primitive {
        match self.primitive {
            SkinPrimitive::Square { half_side } => {
                Primitive::square(normal_axis.into(), half_side, self.radius)
            }
            SkinPrimitive::Point => Primitive::point(Default::default(), self.radius),
        }
    }
}

/// A built skin: the op-implicit [`Skin`] of one object.
#[derive(Clone, Debug)]
pub struct BuiltSkin {
    /// Index of its object in [`crate::BuiltScene::objects`].
    pub object: usize,
    /// OBJ object name: `<object>_skin`.
    pub name: String,
    /// The skin, posed at the last [`Skin::repose`].
    pub skin: Skin,
    /// Polygonization and contact cell size.
    pub cell_size: Real,
    /// Contact stiffness.
    pub stiffness: Real,
}

impl BuiltSkin {
    /// Builds the skin of `object` (index `index`) on `world`.
    pub(crate) fn new(
        world: &World,
        index: usize,
        object: &BuiltObject,
        spec: &SkinSpec,
        normal_axis: [Real; 3],
    ) -> Result<BuiltSkin, op_implicit::SkinError> {
        let prim = spec.primitive(normal_axis);
        let skin = Skin::new(world, object.ids.iter().map(|&id| (id, prim)).collect())?;
        Ok(BuiltSkin {
            object: index,
            name: format!("{}_skin", object.name),
            skin,
            cell_size: spec.cell_size,
            stiffness: spec.stiffness,
        })
    }

    /// The skin's mesh at its current pose.
    pub fn mesh(&self) -> Result<Mesh, op_implicit::PolygonizeError> {
        polygonize(
            self.skin.field(),
            &PolygonizeParams::with_cell_size(self.cell_size),
        )
    }
}

/// Contact figures of a run (module doc): `summary.json` `contact`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ContactStats {
    /// Largest overlap of two undeformed skins, in units of r0.
    pub max_penetration: Real,
    /// Sum over steps of `|F| dt` on the second object of each pair.
    pub total_impulse: Real,
}

/// Re-poses `skins` on `world`, computes the contact reactions of every
/// pair, adds them to `world` for its next step (of length `dt`) and
/// updates `stats`. `objects` gives the rest spacings (r0).
pub fn contact_step(
    world: &mut World,
    skins: &mut [BuiltSkin],
    objects: &[BuiltObject],
    dt: Real,
    stats: &mut ContactStats,
) -> Result<(), String> {
    for s in skins.iter_mut() {
        s.skin
            .repose(world)
            .map_err(|e| format!("posing skin {}: {e}", s.name))?;
    }
    for i in 0..skins.len() {
        for j in i + 1..skins.len() {
            let (a, b) = (&skins[i], &skins[j]);
            let (fa, fb) = (a.skin.field(), b.skin.field());
            let params = ImplicitContactParams::new(
                0.5 * (a.stiffness + b.stiffness),
                a.cell_size.min(b.cell_size),
            );
            let r = ContactPair::new(fa, fb)
                .reactions(&params)
                .map_err(|e| format!("contact {} / {}: {e}", a.name, b.name))?;
            if r.samples().is_empty() {
                continue;
            }
            let r0 = objects[a.object]
                .rest_spacing
                .min(objects[b.object].rest_spacing)
                .max(Real::MIN_POSITIVE);
            for s in r.samples() {
                let ga = fa.value_and_gradient(&s.position).1.norm();
                let gb = fb.value_and_gradient(&s.position).1.norm();
                let depth = s.excess / ga.max(1e-12) + s.excess / gb.max(1e-12);
                stats.max_penetration = stats.max_penetration.max(depth / r0);
            }
            stats.total_impulse += r.b().total_force().norm() * dt;
            r.apply(world);
        }
    }
    Ok(())
}
