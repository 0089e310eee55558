//! Implicit skins of scene objects and their contact (seed 002
//! §6 fig. 6).
//!
//! An object with a [`SkinSpec`] gets one op-implicit skeleton primitive
//! per particle ([`SkinPrimitive`]); the builder turns them into a
//! [`ObjectSkin`] (an op-implicit [`Skin`]). Nothing of op-implicit is built
//! for a scene without skins (see [`crate::BuiltScene::stages`]).
//!
//! **Two skins.** Contact acts on the skeleton's own skin, the plain
//! kernel of support `radius` ([`SkinSpec::contact_shape`]); the
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

use std::f64::consts::SQRT_2;

use op_dynamics::math::shortest_rotation;
use op_dynamics::{Point3, Real, Vec3, World};
pub use op_implicit::object_skin::{ContactError, ContactStats, ObjectSkin, SkinTool};
use op_implicit::{Primitive, Skin, SkinError, StretchCompensation};
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
        #[schemars(range(min = 0))]
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
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: Real,
    /// Cell size of polygonization and of contact sampling, > 0 (the pair
    /// uses the smaller of its two). Required.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub cell_size: Real,
    /// Contact pressure per unit removed field excess, >= 0 (a pair uses the
    /// mean of its two): the `k` of two skins' contact energy
    /// `k ∫ max(0, min(e_A, e_B)) dV`, whose gradient gives every
    /// particle's force and torque (op-implicit `implicit_contact`); where
    /// the skins meet flat its pressure is `k` times the excess Gascuel's
    /// deformation removes. Default: 100.
    #[serde(default = "hundred")]
    #[schemars(range(min = 0))]
    pub stiffness: Real,
    /// How far primitives blend in the displayed skin, in `[1, 4]`: its
    /// kernel's support is `smoothness · radius` (a square's support also
    /// reaches its half side further in its plane), so neighbours within
    /// it blend: a larger smoothness rounds a clump of particles and hides
    /// the rows of a sheet (polygonizing costs more as each field sample
    /// reaches more primitives). Above 1 a square is shown by the smooth
    /// ellipsoidal kernel of its support ([`SkinSpec::display_shape`]);
    /// the displayed skin's amplitude is matched on the object to the
    /// contact skin (the `skin_shape` module), so blending rounds the skin
    /// without changing its size. 1 is the plain kernel of Lombardo &
    /// Puech §6, on which contact always acts
    /// ([`SkinSpec::contact_shape`]). Default: [`DEFAULT_SMOOTHNESS`].
    #[serde(default = "default_smoothness")]
    #[schemars(range(min = 1, max = 4))]
    pub smoothness: Real,
    /// Distance from the skeleton to the skin, at least half the cell size
    /// and below 0.9 `radius` (the contact skin's support). The amplitude
    /// is chosen on the object as built: along every particle's normal
    /// axis, both ways, the contact field at this distance is the iso value
    /// for the median particle (the `skin_shape` module), so a cloth is
    /// `2 thickness` thick however many neighbours each particle has, and
    /// both skins keep their thickness as the object stretches
    /// (op-implicit `stretch`: each primitive's amplitude follows its
    /// neighbourhood's density). Default: `radius / 2` for squares (as
    /// thin as an isolated primitive: a cloth of squares of radius 0.8 is
    /// 0.8 thick); none for points, whose skin keeps the isolated
    /// primitive's size, `radius / 2` from each particle, so a clump of
    /// points is round.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub thickness: Option<Real>,
    /// Iterations of Taubin's volume-preserving smoothing applied to the
    /// skin's mesh in the written frames (op-implicit
    /// `polygonize::smoothing`), at most 100: it removes small bumps (half
    /// of seeded 2% noise in 10 iterations) without shrinking the skin;
    /// contact and the field are unchanged. Default: 0 (the exact iso
    /// surface).
    #[serde(default)]
    #[schemars(range(max = 100))]
    pub smoothing: u32,
}

/// Default [`SkinSpec::smoothness`]: 1.5, so a clump of particles looks
/// round, a sheet's rows do not show and a curved ribbon has no bumps.
///
/// Measured (`skin_shape` tests, cell size 0.05): the skin of four point
/// primitives of radius 1.2 in a tetrahedron of edge 1 (the ball of
/// `ball_vs_spiral`), its amplitude matched to the contact skin, is off
/// its best-fit sphere by 9.2% RMS of its radius at smoothness 1, 0.49% at
/// 1.5, 0.10% at 2; a hexagonal sheet of squares (half side 0.5, radius
/// 1.2) is flat within 0.24%, 0.38% and 0.81% r0 at thicknesses 0.25, 0.4
/// and 0.6; ring ribbons of 8 to 30 squares (half side 0.5,
/// radius 0.8, spacing 1) have bumps of 0.015-0.024 r0 peak-to-peak (0.10
/// to 0.25 with the plain kernel) and both faces within 0.05 of their
/// thickness. A wider blend rounds a clump further but thickens a
/// ribbon's concave side at its convex side's expense (at 2, the convex
/// face of a ring of 8 is 0.21 out instead of 0.4) and costs more to
/// polygonize (the evaluations grow as the support's cube). Contact does
/// not depend on it ([`SkinSpec::contact_shape`]): with the blended skin
/// in contact, `ball_vs_spiral`'s spiral, which the ball's wider skin kept
/// touching, ended at a rest shape error of 0.12 instead of below 0.02.
pub const DEFAULT_SMOOTHNESS: Real = 1.5;

/// The least in-plane reach of a square's displayed kernel, in rest
/// spacings ([`SkinSpec::display_shape`]): below it a sheet's rows show
/// through a thin skin, and squares small against the spacing leave holes
/// (half side 0.25, radius 0.4: the skin reached the sheet's plane between
/// particles; at 1.5 spacings it is flat within 0.4% r0). Wider, a tightly
/// curved ribbon gets bumps (a ring of 8 at 2 spacings: 0.041 r0).
const ROWS: Real = 1.5;

fn default_smoothness() -> Real {
    DEFAULT_SMOOTHNESS
}

impl SkinSpec {
    /// The distance from the skeleton at which the contact skin is placed
    /// ([`SkinSpec::thickness`]): the thickness asked for, else `radius / 2`
    /// for a square; `None` for a point without one (isolated size).
    fn offset(&self) -> Option<Real> {
        match (self.thickness, self.primitive) {
            (Some(t), _) => Some(t),
            (None, SkinPrimitive::Square { .. }) => Some(0.5 * self.radius),
            (None, SkinPrimitive::Point) => None,
        }
    }

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

    /// How far from its particle the displayed skin's field reaches: the
    /// support, plus a square's half side (in its plane).
    pub fn reach(&self) -> Real {
        match self.primitive {
            SkinPrimitive::Square { half_side } if self.smoothness > 1.0 => {
                half_side + self.support()
            }
            SkinPrimitive::Square { half_side } => half_side * SQRT_2 + self.radius,
            SkinPrimitive::Point => self.support(),
        }
    }

    /// The primitive of the contact skin in a particle's body frame, of
    /// unit amplitude: the plain kernel of Lombardo & Puech §6 (support
    /// `radius`) on the skeleton (`normal_axis`: the object's body-frame
    /// normal axis, a square's normal). Contact acts on this skeleton's
    /// own iso surface: the blending of [`SkinSpec::smoothness`] rounds
    /// what is shown but does not change where objects touch, nor the
    /// contact stiffness, which is per unit of removed excess of this
    /// field.
    pub fn contact_shape(&self, normal_axis: Vec3) -> Primitive {
        match self.primitive {
            SkinPrimitive::Square { half_side } => {
                Primitive::square(normal_axis, half_side, self.radius)
            }
            SkinPrimitive::Point => Primitive::point(Vec3::zeros(), self.radius),
        }
    }

    /// The primitive of the displayed skin, of unit amplitude: the
    /// contact one at smoothness 1; above, a kernel of support
    /// `b = smoothness · radius`: the point's own for a point, and for a
    /// square of half side `a` the ellipsoidal point kernel (seed 002 §6's
    /// anisotropic potential) of semi-axes `a + b` in its plane (at least
    /// 1.5 rest spacings `spacing`, so rows do not show) and `b` along its
    /// normal, the smooth kernel of the blended square's reach.
    /// The square's own distance is flat over the square and creased at
    /// its rim, so on a curved sheet or ribbon the blended squares leave a
    /// ridge between particles (a flat polygon's corners); the ellipsoid
    /// has neither, and a row of them at spacing below `b` sums to a
    /// nearly constant field (measured on a ring ribbon of 13 squares of
    /// half side 0.5, radius 0.8: bumps 0.13 r0 peak-to-peak with blended
    /// squares, 0.03 with the ellipsoids; `skin_shape` tests).
    pub fn display_shape(&self, normal_axis: Vec3, spacing: Real) -> Primitive {
        let b = self.support();
        match self.primitive {
            _ if self.smoothness <= 1.0 => self.contact_shape(normal_axis),
            SkinPrimitive::Square { half_side } => {
                let rotation = shortest_rotation(&Vec3::z(), &normal_axis);
                let wide = (half_side + b).max(ROWS * spacing) / b;
                Primitive::ellipsoid(Vec3::zeros(), rotation, Vec3::new(wide, wide, 1.0), b)
            }
            SkinPrimitive::Point => Primitive::point(Vec3::zeros(), b),
        }
    }
}

/// Probe rays from every particle of `object` on `world`: both ways along
/// each of `axes` (body frame when `body`, else world axes).
fn probe_rays(
    world: &World,
    object: &BuiltObject,
    axes: &[Vec3],
    body: bool,
) -> Vec<(Point3, Vec3)> {
    let p = world.particles();
    let mut rays = Vec::new();
    for &id in &object.ids {
        if let Some(k) = p.slot_of(id) {
            let q = p.orientations()[k];
            for a in axes {
                let u = if body { q * a } else { *a };
                rays.push((p.positions()[k], u));
                rays.push((p.positions()[k], -u));
            }
        }
    }
    rays
}

/// Builds the skin of `object` (index `index`) on `world` from its spec:
/// the contact skin of [`SkinSpec::contact_shape`] at the
/// [`SkinSpec::thickness`] and, when smoother, the displayed skin of
/// [`SkinSpec::display_shape`], as large as the contact skin (the
/// `skin_shape` module).
pub(crate) fn build_skin(
    world: &World,
    index: usize,
    object: &BuiltObject,
    spec: &SkinSpec,
    normal_axis: [Real; 3],
) -> Result<ObjectSkin, SkinError> {
    let axis = Vec3::from(normal_axis);
    let skin_of = |p: Primitive| Skin::new(world, object.ids.iter().map(|&id| (id, p)).collect());
    let normal_rays = probe_rays(world, object, &[axis], true);
    let unit = spec.contact_shape(axis);
    let weight = match spec.offset() {
        Some(t) => crate::skin_shape::offset_weight(skin_of(unit)?.field(), &normal_rays, t)
            .unwrap_or_else(|| Primitive::weight_for_iso_distance(t, spec.radius)),
        None => 1.0,
    };
    let prim = unit.with_weight(weight);
    // Both skins keep their thickness as the object stretches
    // (op_implicit::stretch): what is shown is where contact acts. A
    // sheet's skin has one thickness to its rim; a clump keeps its shape.
    let kept = |p: Primitive| {
        skin_of(p).map(|mut skin| {
            let compensation = match spec.primitive {
                SkinPrimitive::Square { .. } => StretchCompensation::uniform(skin.field()),
                SkinPrimitive::Point => StretchCompensation::per_particle(skin.field()),
            };
            skin.keep_thickness(compensation);
            skin
        })
    };
    let skin = kept(prim)?;
    let mut shown = prim;
    let mut display = None;
    if spec.smoothness > 1.0 {
        // The blended skin as large as the contact skin
        // (crate::skin_shape).
        let unit = spec.display_shape(axis, object.rest_spacing);
        let rays = match spec.primitive {
            SkinPrimitive::Square { .. } => normal_rays,
            SkinPrimitive::Point => {
                probe_rays(world, object, &[Vec3::x(), Vec3::y(), Vec3::z()], false)
            }
        };
        let reach = spec.radius * (1.0 + object.ids.len() as Real);
        let w = crate::skin_shape::matched_weight(
            skin.field(),
            skin_of(unit)?.field(),
            &rays,
            0.25 * spec.cell_size,
            reach,
        )
        .unwrap_or_else(|| {
            Primitive::weight_for_iso_distance(
                spec.offset().unwrap_or(0.5 * spec.radius),
                unit.radius,
            )
        });
        shown = unit.with_weight(w);
        display = Some(kept(shown)?);
    }
    Ok(ObjectSkin {
        object: index,
        rest_spacing: object.rest_spacing,
        name: format!("{}_skin", object.name),
        skin,
        display,
        cell_size: spec.cell_size,
        stiffness: spec.stiffness,
        surface_slope: surface_slope(spec),
        primitive: prim,
        display_primitive: shown,
        smoothing: spec.smoothing as usize,
    })
}

/// The slope of a skin's field at its surface: `ISO |f'(t)| / f(t)` for a
/// skin `t` from its skeleton (the amplitude puts the iso value there),
/// `19 / (12 R)` at the default `t = R / 2` (op-implicit `kernel`).
pub(crate) fn surface_slope(skin: &SkinSpec) -> Real {
    use op_implicit::kernel::{derivative, iso_radius, value, ISO};
    let t = skin.thickness.unwrap_or(iso_radius(skin.radius));
    let f = value(t, skin.radius);
    if f > 0.0 {
        ISO * derivative(t, skin.radius).abs() / f
    } else {
        0.0
    }
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
