//! The skins of a scene's objects and their contact (seed 002 §6, fig. 6):
//! each skinned object carries an [`ObjectSkin`] (the skin contact acts on
//! and, when smoother, the one shown), obstacle tools meet skins as
//! [`SkinTool`]s, and [`crate::contact_forces::ContactForces`] computes the reactions of every
//! pair of skins (the gradient of Gascuel's contact energy) and of every
//! skin against the tools it meets, at every force evaluation, as a force
//! contributor ([`op_dynamics::contributors`]). The stages that run them
//! are in [`crate::skin_stages`].
//!
//! **Figures** ([`ContactStats`], `summary.json` `contact`):
//! `total_impulse` is the sum over steps of `|F| dt`, `F` the total contact
//! force on the second object of each pair (summed over pairs);
//! `max_penetration` is the largest overlap of the two undeformed skins
//! over all steps, in units of `r0` (the smaller rest spacing of the
//! pair): at the deepest quadrature point of the contact energy, of common
//! excess `e = min(e_A, e_B)`, the overlap thickness along the normal is, to first order,
//! `e / |grad f_A| + e / |grad f_B|` (how deep each undeformed skin reaches
//! past the contact surface, summed).

use op_dynamics::{Point3, Real, Vec3, World};
use op_modeling::tools::parry_pose;
use op_modeling::Tool;
use parry3d_f64::math::Pose;
use parry3d_f64::shape::Shape;
use serde::{Deserialize, Serialize};

use crate::contact_forces::ParticleState;
use crate::{
    polygonize, polygonize_clipped, polygonize_deformed, ImplicitContactParams, Mesh,
    ObstacleContact, PolygonizeError, PolygonizeParams, Primitive, Skin, SkinError,
};

/// The skin of one object: the [`Skin`] contact acts on and the one shown.
#[derive(Clone, Debug)]
pub struct ObjectSkin {
    /// Index of its object (the particles' object id in the world).
    pub object: usize,
    /// The object's rest spacing `r0` (contact depths are in its units).
    pub rest_spacing: Real,
    /// OBJ object name: `<object>_skin`.
    pub name: String,
    /// The contact skin (the plain kernel of the skeleton), posed at the
    /// last [`ObjectSkin::repose`].
    pub skin: Skin,
    /// The displayed skin, when it differs from the contact skin (a
    /// blended skin, smoother).
    pub display: Option<Skin>,
    /// Polygonization and contact cell size.
    pub cell_size: Real,
    /// Contact stiffness.
    pub stiffness: Real,
    /// The slope `|∇f|` of the contact skin's field at its surface, as its
    /// kernel gives it for one primitive: converts an obstacle's spring
    /// per particle into its contact energy's stiffness
    /// ([`SkinTool::stiffness`]).
    pub surface_slope: Real,
    /// The primitive each particle of the object carries in the contact
    /// skin (in its body frame).
    pub primitive: Primitive,
    /// The primitive each particle carries in the displayed skin.
    pub display_primitive: Primitive,
    /// Taubin iterations of the exported mesh ([`Mesh::taubin_smooth`]).
    pub smoothing: usize,
}

impl ObjectSkin {
    /// The skins of this object: the contact one, then the displayed one
    /// when it differs.
    pub(crate) fn skins_mut(&mut self) -> impl Iterator<Item = (&mut Skin, Primitive)> {
        std::iter::once((&mut self.skin, self.primitive))
            .chain(self.display.as_mut().map(|d| (d, self.display_primitive)))
    }

    /// The field shown ([`ObjectSkin::display`], else the contact field).
    pub fn display_field(&self) -> &crate::Field {
        self.display.as_ref().unwrap_or(&self.skin).field()
    }

    /// The states of its skins ([`Skin::state`]): the contact skin, then
    /// the display skin when it has one.
    pub fn state(&self) -> Vec<crate::skin::SkinState> {
        std::iter::once(&self.skin)
            .chain(self.display.as_ref())
            .map(Skin::state)
            .collect()
    }

    /// Puts back the states [`ObjectSkin::state`] returned and poses the
    /// skins on `particles`.
    pub fn restore(
        &mut self,
        states: Vec<crate::skin::SkinState>,
        particles: &op_dynamics::Particles,
    ) -> Result<(), crate::SkinError> {
        let skins = 1 + usize::from(self.display.is_some());
        if states.len() != skins {
            return Err(crate::SkinError::State(format!(
                "skin {:?} has {skins} fields, the checkpoint {}",
                self.name,
                states.len()
            )));
        }
        let mut states = states.into_iter();
        for (skin, _) in self.skins_mut() {
            if let Some(s) = states.next() {
                skin.restore(s, particles)?;
            }
        }
        Ok(())
    }

    /// Re-poses the skins on the particles of `world`.
    pub fn repose(&mut self, world: &World) -> Result<(), crate::SkinError> {
        for (skin, _) in self.skins_mut() {
            skin.repose(world)?;
        }
        Ok(())
    }

    /// Attaches the object's primitive to the particles `ids` (created by
    /// the creation rules); posed at the next re-pose.
    pub fn attach(&mut self, ids: &[u32]) {
        for (skin, prim) in self.skins_mut() {
            let new: Vec<(u32, Primitive)> = ids.iter().map(|&id| (id, prim)).collect();
            // The primitive was valid when the skin was built.
            let _ = skin.attach(&new);
        }
    }

    /// Drops the primitives of the particles `ids` (merged, released or
    /// erased).
    pub fn detach(&mut self, ids: &[u32]) {
        if !ids.is_empty() {
            let gone: std::collections::HashSet<u32> = ids.iter().copied().collect();
            for (skin, _) in self.skins_mut() {
                skin.retain(|id| !gone.contains(&id));
            }
        }
    }

    /// The skin's mesh at its current pose.
    pub fn mesh(&self) -> Result<Mesh, crate::PolygonizeError> {
        polygonize(
            self.display_field(),
            &PolygonizeParams::with_cell_size(self.cell_size),
        )
    }

    /// The cell size the skin is exported at: its own, or, when its support
    /// box has grown beyond what [`PolygonizeParams::max_nodes_per_axis`]
    /// nodes of that size cover (particles flung apart), the smallest cell
    /// that fits, so a skin that outgrew its grid is written coarser rather
    /// than not at all. The polygonizer's grid spans the support box and a
    /// cell of margin on each side: `ceil(extent / h) + 3` nodes.
    pub fn export_cell_size(&self) -> Real {
        let max = PolygonizeParams::with_cell_size(self.cell_size).max_nodes_per_axis;
        let Some((lo, hi)) = self.display_field().support_box() else {
            return self.cell_size;
        };
        let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, Real::max);
        // `ceil(extent / h) + 3` nodes: `extent / h <= max - 3` fits (with
        // a hair of margin for the rounding of the division).
        let fitting = extent / (max as Real - 3.0) * (1.0 + 1e-9);
        if fitting.is_finite() && extent / self.cell_size > max as Real - 3.0 {
            fitting
        } else {
            self.cell_size
        }
    }

    /// The skin's mesh at its current pose, deformed by contact (Gascuel,
    /// seed 002 §6): when another skin of `skins` overlaps its support, the
    /// exported surface is the deformed field's, so two skins in contact
    /// meet on one contact surface (no gap, no overlap); with several
    /// overlapping skins, the first one in scene order deforms it. Then
    /// the obstacle tools of `tools` that touch this skin at world time `t`
    /// clip it ([`crate::ClippedField`]): a skin pressed on a rigid
    /// collider is exported lying on its surface. The cell size is
    /// [`ObjectSkin::export_cell_size`].
    pub fn mesh_in(
        &self,
        skins: &[ObjectSkin],
        tools: &[SkinTool],
        t: Real,
    ) -> Result<Mesh, crate::PolygonizeError> {
        let own = self.display_field();
        let params = PolygonizeParams::with_cell_size(self.export_cell_size());
        let index = skins.iter().position(|s| s.object == self.object);
        let poses: Vec<(&Tool, Pose)> = tools
            .iter()
            .filter(|tool| index.is_some_and(|i| tool.skins.contains(&i)))
            .map(|tool| {
                let pose = tool.tool.pose(t);
                (&tool.tool, parry_pose(&pose.position, &pose.rotation))
            })
            .collect();
        let colliders: Vec<(&dyn Shape, Pose)> = poses
            .iter()
            .map(|(tool, pose)| (tool.shape(), *pose))
            .collect();
        let slope = crate::ISO / self.cell_size;
        let other = skins.iter().find(|o| {
            o.object != self.object
                && boxes_overlap(own.support_box(), o.display_field().support_box())
        });
        let other = other.map(|o| o.display_field());
        let mut mesh = match (other, colliders.is_empty()) {
            (Some(o), true) => polygonize_deformed(own, o, &params),
            (None, true) => polygonize(own, &params),
            (other, false) => polygonize_clipped(own, other, colliders, slope, &params),
        }?;
        mesh.taubin_smooth(self.smoothing);
        Ok(mesh)
    }
}

/// True when two axis-aligned boxes (lower, upper corners) intersect.
fn boxes_overlap(a: Option<(Point3, Point3)>, b: Option<(Point3, Point3)>) -> bool {
    match (a, b) {
        (Some((alo, ahi)), Some((blo, bhi))) => {
            (0..3).all(|k| alo[k] <= bhi[k] && blo[k] <= ahi[k])
        }
        _ => false,
    }
}

/// Contact figures of a run (module doc): `summary.json` `contact`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactStats {
    /// Largest overlap of two undeformed skins, or depth of a skin inside
    /// an obstacle tool, in units of r0.
    pub max_penetration: Real,
    /// Sum over steps of `|F| dt` on the second object of each pair.
    pub total_impulse: Real,
}

/// An obstacle tool that skinned objects meet through their skins: each
/// skin's particles get the gradient of the contact energy
/// `k_E ∫ max(0, f - ISO) dV` over the tool's interior, `k_E` from
/// [`SkinTool::stiffness`] ([`crate::ObstacleContact`]; seed 002 §6 with
/// only the skin compressed), integrated on a lattice of the skin's cell
/// size.
#[derive(Clone, Debug)]
pub struct SkinTool {
    /// The tool (shape and path; its role is an obstacle).
    pub tool: Tool,
    /// Indices (in the scene's list of skins) of the skins it touches.
    pub skins: Vec<usize>,
    /// Spring per particle, force per unit depth (as the tool pushes a
    /// bare particle). A skin of field slope `g` at its surface
    /// ([`ObjectSkin::surface_slope`]) and rest spacing `r0` meets the
    /// tool with the contact energy's stiffness `stiffness / (g r0^2)`
    /// ([`crate::ObstacleContact`]): where it meets a flat face at depth
    /// `d`, the pressure `k g d` over a particle's footprint `r0^2` is
    /// `stiffness d`.
    pub stiffness: Real,
    /// Coulomb friction coefficient of the skinned particles on the tool
    /// ([`crate::friction`]), >= 0.
    pub friction: Real,
    /// Damping of the normal velocity of the skinned particles it presses,
    /// relative to the tool, >= 0 ([`crate::friction::normal_damping`]).
    pub damping: Real,
}

impl SkinTool {
    /// The box a skin of cell `cell_size` is sampled in against the tool
    /// at world time `t` ([`SkinTool::react`]): the tool's bounding box, a
    /// cell wider.
    pub(crate) fn region(&self, t: Real, cell_size: Real) -> (Point3, Point3) {
        let pose = self.tool.pose(t);
        let (lo, hi) = crate::contact::shape_box(
            self.tool.shape(),
            &parry_pose(&pose.position, &pose.rotation),
        );
        let pad = Vec3::repeat(cell_size);
        (lo - pad, hi + pad)
    }

    /// The reactions at world time `t` on the skin of field `field` (given
    /// its name, cell size, rest spacing and surface slope), each
    /// passed to `add` (particle id, force, torque), and (total reaction
    /// force, deepest penetration).
    /// Each particle the reaction presses also gets its Coulomb friction
    /// over the interval `interval` and the damping of its normal velocity
    /// ([`crate::friction`]), from its velocity relative to the tool in
    /// `state`.
    pub(crate) fn react(
        &self,
        field: &crate::Field,
        (name, cell_size, r0, slope): (&str, Real, Real, Real),
        t: Real,
        interval: Real,
        state: &(dyn Fn(u32) -> Option<ParticleState> + Sync),
        add: &mut dyn FnMut(u32, Vec3, Vec3),
    ) -> Result<(Vec3, Real), ContactError> {
        let pose = self.tool.pose(t);
        let frame = parry_pose(&pose.position, &pose.rotation);
        let k = self.stiffness / (slope * r0 * r0).max(Real::MIN_POSITIVE);
        let params = ImplicitContactParams::new(k, cell_size);
        let r = ObstacleContact::new(field, self.tool.shape(), &frame)
            .reactions(&params)
            .map_err(|source| ContactError::Sample {
                skin: name.to_string(),
                source,
            })?;
        let dissipative = self.friction > 0.0 || self.damping > 0.0;
        for reaction in r.reactions() {
            add(reaction.particle, reaction.force, reaction.torque);
            let Some(p) = dissipative.then(|| state(reaction.particle)).flatten() else {
                continue;
            };
            let v = p.velocity - pose.velocity_at(&p.position.coords);
            let f = crate::friction::coulomb(reaction.force, v, p.mass, self.friction, interval);
            let d = crate::friction::normal_damping(reaction.force, v, self.damping);
            add(reaction.particle, f + d, Vec3::zeros());
        }
        Ok((r.total_force(), r.max_depth()))
    }
}

/// Why skin contact could not be computed
/// ([`crate::contact_forces::ContactForces::evaluate`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ContactError {
    /// A skin could not follow its particles.
    #[error("posing skin {skin}: {source}")]
    Pose {
        /// The skin's name.
        skin: String,
        /// Why.
        source: SkinError,
    },
    /// A skin's contact energy against a tool could not be integrated:
    /// its lattice near the tool could not be sampled.
    #[error("sampling skin {skin}: {source}")]
    Sample {
        /// The skin's name.
        skin: String,
        /// Why.
        source: PolygonizeError,
    },
    /// The contact surface of two skins could not be sampled.
    #[error("contact {a} / {b}: {source}")]
    Pair {
        /// The first skin's name.
        a: String,
        /// The second skin's name.
        b: String,
        /// Why.
        source: PolygonizeError,
    },
}
