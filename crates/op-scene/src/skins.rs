//! Implicit skins of scene objects and their contact (seed 002
//! §6 fig. 6).
//!
//! An object with a [`SkinSpec`] gets one op-implicit skeleton primitive
//! per particle ([`SkinPrimitive`]); the builder turns them into a
//! [`ObjectSkin`] (an op-implicit [`Skin`]). Nothing of op-implicit is built
//! for a scene without skins (see [`crate::BuiltScene::stages`]).
//!
//! **Two skins.** Contact acts on the skeleton's own skin, the plain
//! kernel of support `radius` ([`SkinSpec::contact_primitive`]); the
//! frames show the blended skin of [`SkinSpec::smoothness`] (the same when
//! it is 1), deformed and clipped with the same contact surfaces.
//!
//! **Runner.** The skins, the obstacle tools they meet and the contact
//! between them are op-implicit's ([`op_implicit::object_skin`]); their
//! stages ([`op_implicit::skin_stages`]) run on the scene's state
//! ([`crate::stages::SceneState`]). Each written frame holds each skin
//! polygonized as an extra OBJ object `<object>_skin` with vertex normals
//! from the analytic field gradient; where two skins' supports overlap,
//! the exported field is the deformed one ([`ObjectSkin::mesh_in`]), so
//! skins in contact meet on the exact contact surface.

use op_dynamics::{Point3, Real, Vec3, World};
pub use op_implicit::object_skin::{
    contact_step, ContactError, ContactStats, ObjectSkin, SkinTool,
};
use op_implicit::{Primitive, Skin, SkinError};
use serde::{Deserialize, Serialize};

use crate::built_scene::BuiltObject;
use crate::error::SceneError;
use crate::schema::checks::positive;

/// The skeleton primitive attached to each particle of a skinned object.
///
/// RON: `Square(half_side: 0.5)`, `Point`. JSON: `{"Square": {"half_side":
/// 0.5}}`, `"Point"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
    /// How far primitives blend in the displayed skin, in `[1, 4]`: the
    /// kernel's support is `smoothness · radius` and its amplitude is
    /// lowered so that an isolated primitive's skin stays at `radius / 2`;
    /// neighbours within the support blend, so a larger smoothness rounds
    /// a clump of particles and hides the rows of a sheet (polygonizing
    /// costs more as each field sample reaches more primitives). 1 is the
    /// plain kernel of Lombardo & Puech §6, on which contact always acts
    /// ([`SkinSpec::contact_primitive`]). Default: [`DEFAULT_SMOOTHNESS`].
    #[serde(default = "default_smoothness")]
    pub smoothness: Real,
    /// Distance from a flat layer of the object's primitives (hexagonal, at
    /// its rest spacing) to its skin, at least half the cell size and below
    /// 0.9 `radius` (the contact skin's support): when set,
    /// the amplitude is chosen for it instead of for the isolated size, so
    /// a cloth can be as thin as asked whatever its blending (a sheet's
    /// skin is then `2 thickness` thick). Default: none: the contact skin
    /// has the isolated primitive's size (`radius / 2`) and the displayed
    /// skin is matched to it on the object (`skin_shape` module).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<Real>,
    /// Iterations of Taubin's volume-preserving smoothing applied to the
    /// skin's mesh in the written frames (op-implicit
    /// `polygonize::smoothing`), at most 100: it removes small bumps (half
    /// of seeded 2% noise in 10 iterations) without shrinking the skin;
    /// contact and the field are unchanged. Default: 0 (the exact iso
    /// surface).
    #[serde(default)]
    pub smoothing: u32,
}

/// Default [`SkinSpec::smoothness`]: 2, so a clump of particles looks
/// round and a sheet's rows do not show.
///
/// Measured (`skin_shape` tests, cell size 0.05): the skin of four point
/// primitives of radius 1.2 in a tetrahedron of edge 1 (the ball of
/// `ball_vs_spiral`), its amplitude matched to the contact skin, is off
/// its best-fit sphere by 9.2% RMS of its radius at smoothness 1, 0.49% at
/// 1.5, 0.10% at 2; a hexagonal sheet of square primitives (half side 0.5,
/// radius 1.2) with a `thickness` of 0.25 (0.4) is flat within 0.84% r0
/// (0.66%) at smoothness 2; a ring ribbon of squares (half side 0.5,
/// radius 0.8, spacing 1) keeps bumps of 0.13 r0 peak-to-peak (0.14 with
/// the plain kernel). Contact does not depend on it
/// ([`SkinSpec::contact_primitive`]): with the blended skin in contact,
/// `ball_vs_spiral`'s spiral, which the ball's wider skin kept touching,
/// ended at a rest shape error of 0.12 instead of below 0.02.
pub const DEFAULT_SMOOTHNESS: Real = 2.0;

fn default_smoothness() -> Real {
    DEFAULT_SMOOTHNESS
}

impl SkinSpec {
    /// Checks the numbers; `path` is the skin's scene path for messages.
    pub(crate) fn validate(&self, file: &str, path: &str) -> Result<(), SceneError> {
        positive(file, &format!("{path}.radius"), self.radius)?;
        positive(file, &format!("{path}.cell_size"), self.cell_size)?;
        if self.radius < self.cell_size {
            return Err(SceneError::value(
                file,
                format!("{path}.radius"),
                crate::error::short(self.radius),
                &format!(
                    "must be at least the cell size {} (a skin thinner than a cell \
                     cannot be polygonized)",
                    crate::error::short(self.cell_size)
                ),
            ));
        }
        if !(self.smoothness.is_finite() && (1.0..=4.0).contains(&self.smoothness)) {
            return Err(SceneError::value(
                file,
                format!("{path}.smoothness"),
                self.smoothness,
                "must be in [1, 4]",
            ));
        }
        if let Some(t) = self.thickness {
            // The contact skin's support is `radius` (unblended).
            let support = self.radius;
            if !(t.is_finite() && t >= 0.5 * self.cell_size && t < 0.9 * support) {
                return Err(SceneError::value(
                    file,
                    format!("{path}.thickness"),
                    t,
                    &format!(
                        "must be at least half the cell size ({}) and below 0.9 times the \
                         radius ({})",
                        crate::error::short(0.5 * self.cell_size),
                        crate::error::short(0.9 * support)
                    ),
                ));
            }
        }
        if self.smoothing > 100 {
            return Err(SceneError::value(
                file,
                format!("{path}.smoothing"),
                self.smoothing,
                "must be at most 100 iterations",
            ));
        }
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

    /// The kernel's support radius of the displayed skin,
    /// `smoothness · radius`.
    pub fn support(&self) -> Real {
        self.smoothness * self.radius
    }

    /// The primitive of the displayed skin in a particle's body frame
    /// (`normal_axis`: the object's body-frame normal axis; `spacing`: its
    /// rest spacing, for [`SkinSpec::thickness`]), with the support and
    /// amplitude of [`SkinSpec::smoothness`] and [`SkinSpec::thickness`].
    pub fn primitive(&self, normal_axis: [Real; 3], spacing: Real) -> Primitive {
        self.primitive_with_support(normal_axis, spacing, self.support())
    }

    /// The primitive of the contact skin: the plain kernel of Lombardo &
    /// Puech §6 (support `radius`, no blending), with the amplitude that
    /// puts an isolated primitive's skin at `radius / 2` (1) or a flat layer's
    /// at the [`SkinSpec::thickness`]. Contact acts on the skeleton's own
    /// iso distance: the blending of [`SkinSpec::smoothness`] rounds what is
    /// shown (a clump of four particles grows about 10% wider with it) but
    /// does not change where objects touch, nor the contact stiffness,
    /// which is per unit of removed excess of this field.
    pub fn contact_primitive(&self, normal_axis: [Real; 3], spacing: Real) -> Primitive {
        self.primitive_with_support(normal_axis, spacing, self.radius)
    }

    fn primitive_with_support(
        &self,
        normal_axis: [Real; 3],
        spacing: Real,
        support: Real,
    ) -> Primitive {
        let unit = match self.primitive {
            SkinPrimitive::Square { half_side } => {
                Primitive::square(normal_axis.into(), half_side, support)
            }
            SkinPrimitive::Point => Primitive::point(Default::default(), support),
        };
        let weight = match self.thickness {
            Some(t) => op_implicit::ISO / layer_field(&unit, normal_axis.into(), spacing, t),
            None => Primitive::weight_for_iso_distance(0.5 * self.radius, support),
        };
        unit.with_weight(weight)
    }
}

/// The field of `primitive` (weight 1) at distance `height` above the
/// centre of a flat hexagonal layer of such primitives at spacing
/// `spacing`, the layer perpendicular to `normal_axis` (the primitives'
/// normal axis), wide enough to cover the support (up to 64 rings).
fn layer_field(primitive: &Primitive, normal_axis: Vec3, spacing: Real, height: Real) -> Real {
    let n = normal_axis.normalize();
    let u = n.cross(&Vec3::x());
    let u = if u.norm() < 1e-6 {
        n.cross(&Vec3::y())
    } else {
        u
    }
    .normalize();
    let v = n.cross(&u);
    // Two rings beyond the support; at most 64 (a support of more than 62
    // spacings is truncated there, which thickens the skin a little).
    let rings = ((primitive.radius / spacing).ceil() as i64 + 2).min(64);
    let probe = Point3::from(n * height);
    let mut sum = 0.0;
    for j in -rings..=rings {
        for i in -rings..=rings {
            let x = (i as Real + 0.5 * (j.rem_euclid(2)) as Real) * spacing;
            let y = j as Real * spacing * (0.75 as Real).sqrt();
            let at = Point3::from(u * x + v * y);
            sum += primitive
                .posed(0, &at, &op_dynamics::Quat::identity())
                .field(&probe);
        }
    }
    sum
}

/// Builds the skin of `object` (index `index`) on `world` from its spec:
/// the contact skin of [`SkinSpec::contact_primitive`] and, when it differs,
/// the displayed skin of [`SkinSpec::primitive`], as large as the contact
/// skin ([`crate::skin_shape`]).
pub(crate) fn build_skin(
    world: &World,
    index: usize,
    object: &BuiltObject,
    spec: &SkinSpec,
    normal_axis: [Real; 3],
) -> Result<ObjectSkin, SkinError> {
    let prim = spec.contact_primitive(normal_axis, object.rest_spacing);
    let mut shown = spec.primitive(normal_axis, object.rest_spacing);
    let skin_of = |p: Primitive| Skin::new(world, object.ids.iter().map(|&id| (id, p)).collect());
    let skin = skin_of(prim)?;
    if spec.thickness.is_none() && shown != prim {
        // The blended skin as large as the contact skin
        // (crate::skin_shape).
        let unit = skin_of(shown.with_weight(1.0))?;
        let p = world.particles();
        let axes: Vec<Vec3> = match spec.primitive {
            SkinPrimitive::Square { .. } => vec![Vec3::from(normal_axis)],
            SkinPrimitive::Point => vec![Vec3::x(), Vec3::y(), Vec3::z()],
        };
        let mut rays = Vec::new();
        for &id in &object.ids {
            if let Some(k) = p.slot_of(id) {
                let q = p.orientations()[k];
                for a in &axes {
                    let u = match spec.primitive {
                        SkinPrimitive::Square { .. } => q * a,
                        SkinPrimitive::Point => *a,
                    };
                    rays.push((p.positions()[k], u));
                    rays.push((p.positions()[k], -u));
                }
            }
        }
        let reach = spec.radius * (1.0 + object.ids.len() as Real);
        if let Some(w) = crate::skin_shape::matched_weight(
            skin.field(),
            unit.field(),
            &rays,
            0.25 * spec.cell_size,
            reach,
        ) {
            shown = shown.with_weight(w);
        }
    }
    let display = if shown == prim {
        None
    } else {
        Some(skin_of(shown)?)
    };
    Ok(ObjectSkin {
        object: index,
        rest_spacing: object.rest_spacing,
        name: format!("{}_skin", object.name),
        skin,
        display,
        cell_size: spec.cell_size,
        stiffness: spec.stiffness,
        primitive: prim,
        display_primitive: shown,
        smoothing: spec.smoothing as usize,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_dynamics::{Material, ParticleDesc, Particles, WorldParams};
    use op_implicit::Mesh;

    /// Two point skins of radius 2 (skins of radius 1) whose centres are
    /// `gap` apart, as two objects.
    fn pair(gap: Real) -> (World, Vec<ObjectSkin>) {
        let mut p = Particles::new();
        for (k, x) in [0.0, gap].into_iter().enumerate() {
            let mut d = ParticleDesc::at(Point3::new(x, 0.0, 0.0));
            d.object = k as u32;
            p.push(d).unwrap();
        }
        let world = World::new(p, &[Material::empty()], WorldParams::default()).unwrap();
        let spec = SkinSpec {
            primitive: SkinPrimitive::Point,
            radius: 2.0,
            cell_size: 0.1,
            stiffness: 100.0,
            smoothness: 1.0,
            thickness: None,
            smoothing: 0,
        };
        let skins = (0..2u32)
            .map(|k| {
                let object = BuiltObject {
                    name: format!("o{k}"),
                    ids: vec![k],
                    rest: vec![Point3::origin()],
                    rest_spacing: 1.0,
                    created: Vec::new(),
                };
                build_skin(&world, k as usize, &object, &spec, [0.0, 0.0, 1.0]).unwrap()
            })
            .collect();
        (world, skins)
    }

    /// Apart, the exported skin is the undeformed one; overlapping, it is
    /// the deformed one: no vertex of either skin lies inside the other's
    /// deformed skin, and both reach the mid-plane (the contact surface)
    /// instead of crossing it.
    #[test]
    fn skins_in_contact_export_the_deformed_surface() {
        let (_, apart) = pair(5.0);
        let plain = apart[0].mesh().unwrap();
        let exported = apart[0].mesh_in(&apart, &[], 0.0).unwrap();
        assert_eq!(plain.positions().len(), exported.positions().len());
        let (_, touching) = pair(1.5);
        let plain = touching[0].mesh().unwrap();
        let deformed = touching[0].mesh_in(&touching, &[], 0.0).unwrap();
        let max_x = |m: &Mesh| m.positions().iter().map(|p| p.x).fold(Real::MIN, Real::max);
        // Undeformed skin of radius 1 at x = 0 reaches x = 1, past the
        // mid-plane x = 0.75; the deformed one stops at the contact plane.
        assert!(max_x(&plain) > 0.95, "{}", max_x(&plain));
        assert!(
            (max_x(&deformed) - 0.75).abs() < 0.02,
            "{}",
            max_x(&deformed)
        );
        let other = touching[1].mesh_in(&touching, &[], 0.0).unwrap();
        let min_x = other
            .positions()
            .iter()
            .map(|p| p.x)
            .fold(Real::MAX, Real::min);
        assert!((min_x - 0.75).abs() < 0.02, "{min_x}");
    }
}
