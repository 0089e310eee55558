//! The particle store: a structure of arrays with private fields and slice
//! accessors (docs/model.md §2).
//!
//! Each particle is a full frame (seed 002 §5): position `p`, velocity `v`,
//! unit quaternion `q`, world angular velocity `w`, mass, diagonal body
//! inertia, a body-frame normal axis `a` (world normal `n = R(q) a`), flags,
//! object id, type (standard(k) / hinge), material index and rest curvature.
//!
//! Particles keep a stable *id* (their insertion index: ids are never
//! reused, so removing particles leaves gaps) while their storage *slot* may
//! change: the world re-sorts particles in spatial order when it rebuilds
//! neighbour lists, because memory order dominates speed, and removal
//! compacts the survivors (keeping their relative slot order).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{self, ParamError};
use crate::flags::Flags;
use crate::integrators::{Bodies, StateMut, StateRef};
use crate::math::{shortest_rotation, tangent_axis, Point3, Quat, Real, Vec3};

/// Particle type of seed 002 §5.
///
/// A hinge interacts completely with every standard particle; a standard
/// particle of type `k` interacts completely with standard particles of the
/// same `k` and with hinges; every other pair of the same object only repels.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
pub enum ParticleType {
    /// A standard particle of the given part number.
    Standard(u16),
    /// A hinge joining parts.
    Hinge,
}

impl Default for ParticleType {
    fn default() -> Self {
        ParticleType::Standard(0)
    }
}

impl ParticleType {
    /// True when two particles of these types interact completely (seed
    /// 002 §5 rules; object membership is checked separately).
    #[inline]
    pub fn complete_with(self, other: ParticleType) -> bool {
        match (self, other) {
            (ParticleType::Standard(a), ParticleType::Standard(b)) => a == b,
            (ParticleType::Hinge, ParticleType::Standard(_))
            | (ParticleType::Standard(_), ParticleType::Hinge) => true,
            (ParticleType::Hinge, ParticleType::Hinge) => false,
        }
    }
}

/// Smallest norm of a [`ParticleDesc::orientation`] quaternion: below it
/// (or for a non-finite one) the normalization on creation is undefined or
/// dominated by round-off.
pub const MIN_ORIENTATION_NORM: Real = 1e-6;

/// Everything needed to create one particle. Start from
/// [`ParticleDesc::at`] and override what differs from the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleDesc {
    /// Position. No default (see [`ParticleDesc::at`]).
    pub position: Point3,
    /// Velocity. Default: zero.
    pub velocity: Vec3,
    /// Orientation (full frame). Default: identity.
    pub orientation: Quat,
    /// Angular velocity in the world frame. Default: zero.
    pub angular_velocity: Vec3,
    /// Mass, > 0. Default: 1.
    pub mass: Real,
    /// Principal moments of inertia in the body frame, each > 0.
    /// Default: (0.1, 0.1, 0.1) (a sphere of radius ~0.5 r0 for unit mass).
    pub inertia: Vec3,
    /// Body-frame normal axis, normalized on creation. Default: +z.
    pub normal_axis: Vec3,
    /// Flags. Default: none.
    pub flags: Flags,
    /// Object id: complete interactions only within an object. Default: 0.
    pub object: u32,
    /// Particle type. Default: `Standard(0)`.
    pub kind: ParticleType,
    /// Index into the world's material table. Default: 0.
    pub material: u16,
    /// Rest curvature `kappa = 1/R` of the form interaction (seed 002 §4).
    /// Default: 0 (flat).
    pub curvature: Real,
    /// Temperature (seed 000 §6, §8; [`crate::heat`]). Default: 0.
    pub temperature: Real,
}

impl ParticleDesc {
    /// A particle at `position` with every other attribute at its default.
    pub fn at(position: Point3) -> Self {
        ParticleDesc {
            position,
            velocity: Vec3::zeros(),
            orientation: Quat::identity(),
            angular_velocity: Vec3::zeros(),
            mass: 1.0,
            inertia: Vec3::repeat(0.1),
            normal_axis: Vec3::z(),
            flags: Flags::empty(),
            object: 0,
            kind: ParticleType::default(),
            material: 0,
            curvature: 0.0,
            temperature: 0.0,
        }
    }

    /// Orients the particle so that its world normal is `normal` (the
    /// shortest rotation from the body normal axis, exact for a normal
    /// opposite to it: [`shortest_rotation`]).
    pub fn with_normal(mut self, normal: Vec3) -> Self {
        self.orientation = shortest_rotation(&self.normal_axis, &normal);
        self
    }

    /// Checks every field: finite values, positive mass and inertia, a
    /// non-zero normal axis, a finite curvature.
    pub fn validate(&self) -> Result<(), ParamError> {
        for k in 0..3 {
            error::finite("position", self.position[k])?;
            error::finite("velocity", self.velocity[k])?;
            error::finite("angular_velocity", self.angular_velocity[k])?;
            error::positive("inertia", self.inertia[k])?;
            error::finite("normal_axis", self.normal_axis[k])?;
        }
        error::positive("mass", self.mass)?;
        error::check(
            "normal_axis",
            self.normal_axis.norm(),
            self.normal_axis.norm() > 1e-12,
            "must be a non-zero vector",
        )?;
        error::finite("curvature", self.curvature)?;
        error::finite("temperature", self.temperature)?;
        // The orientation is normalized on creation, so any finite
        // quaternion of a reasonable norm is a frame; a zero (or vanishing)
        // one has no direction and would normalize to NaN.
        let q = self.orientation.quaternion();
        let norm = q.norm();
        error::check(
            "orientation",
            norm,
            q.coords.iter().all(|c| c.is_finite())
                && norm.is_finite()
                && norm >= MIN_ORIENTATION_NORM,
            "must be a finite quaternion of norm >= 1e-6 (it is normalized on creation; \
             a zero quaternion is no rotation)",
        )
    }
}

/// Static per-particle attributes the force evaluation reads (borrowed
/// while the integrator mutates the state).
#[derive(Clone, Copy)]
pub struct Attributes<'a> {
    /// Stable ids, by slot.
    pub ids: &'a [u32],
    /// Slot of each id (the inverse permutation of `ids`), indexed by id;
    /// [`Particles::REMOVED`] for ids whose particle was removed.
    pub slot_of: &'a [u32],
    /// Body-frame normal axes.
    pub normal_axes: &'a [Vec3],
    /// Body-frame tangent axes ("local x").
    pub tangent_axes: &'a [Vec3],
    /// Flags.
    pub flags: &'a [Flags],
    /// Object ids.
    pub objects: &'a [u32],
    /// Particle types.
    pub kinds: &'a [ParticleType],
    /// Material indices.
    pub materials: &'a [u16],
    /// Rest curvatures.
    pub curvatures: &'a [Real],
    /// Temperatures ([`crate::heat`]).
    pub temperatures: &'a [Real],
    /// Masses.
    pub masses: &'a [Real],
}

/// The slot of particle `id` in a slot table indexed by id
/// ([`Attributes::slot_of`]), `None` for ids never given or removed.
#[inline]
pub(crate) fn live_slot(slot_of: &[u32], id: u32) -> Option<usize> {
    slot_of
        .get(id as usize)
        .filter(|&&s| s != Particles::REMOVED)
        .map(|&s| s as usize)
}

/// Structure-of-arrays particle store. All arrays have the same length,
/// which only the store's methods can change.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Particles {
    positions: Vec<Point3>,
    velocities: Vec<Vec3>,
    orientations: Vec<Quat>,
    angular_velocities: Vec<Vec3>,
    statics: AttributeArrays,
}

/// The arrays the integrator does not advance.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct AttributeArrays {
    ids: Vec<u32>,
    slot_of: Vec<u32>,
    masses: Vec<Real>,
    inv_masses: Vec<Real>,
    inertias: Vec<Vec3>,
    normal_axes: Vec<Vec3>,
    tangent_axes: Vec<Vec3>,
    flags: Vec<Flags>,
    objects: Vec<u32>,
    kinds: Vec<ParticleType>,
    materials: Vec<u16>,
    curvatures: Vec<Real>,
    temperatures: Vec<Real>,
}

impl AttributeArrays {
    fn view(&self) -> Attributes<'_> {
        Attributes {
            ids: &self.ids,
            slot_of: &self.slot_of,
            normal_axes: &self.normal_axes,
            tangent_axes: &self.tangent_axes,
            flags: &self.flags,
            objects: &self.objects,
            kinds: &self.kinds,
            materials: &self.materials,
            curvatures: &self.curvatures,
            temperatures: &self.temperatures,
            masses: &self.masses,
        }
    }
}

macro_rules! slice_accessors {
    (state; $($(#[$doc:meta])* $name:ident : $t:ty),* $(,)?) => {
        $( $(#[$doc])* #[inline] pub fn $name(&self) -> &[$t] { &self.$name } )*
    };
    (statics; $($(#[$doc:meta])* $name:ident : $t:ty),* $(,)?) => {
        $( $(#[$doc])* #[inline] pub fn $name(&self) -> &[$t] { &self.statics.$name } )*
    };
}

impl Particles {
    /// An empty store.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of particles.
    #[inline]
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when the store holds no particle.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The `slot_of` entry of a removed id.
    pub const REMOVED: u32 = u32::MAX;

    /// One past the largest id ever given: the length of the id-indexed
    /// tables ([`Attributes::slot_of`], the world's external accumulator).
    /// Equal to [`len`](Self::len) until a particle is removed.
    #[inline]
    pub fn id_bound(&self) -> usize {
        self.statics.slot_of.len()
    }

    /// Whether the store is well formed (a store read back from a
    /// checkpoint is checked before use): every array of one length, and
    /// ids and slots that map to each other.
    pub(crate) fn is_consistent(&self) -> bool {
        let n = self.len();
        let a = &self.statics;
        let lengths = [
            self.velocities.len(),
            self.orientations.len(),
            self.angular_velocities.len(),
            a.ids.len(),
            a.masses.len(),
            a.inv_masses.len(),
            a.inertias.len(),
            a.normal_axes.len(),
            a.tangent_axes.len(),
            a.flags.len(),
            a.objects.len(),
            a.kinds.len(),
            a.materials.len(),
            a.curvatures.len(),
            a.temperatures.len(),
        ];
        lengths.iter().all(|&l| l == n)
            && a.ids
                .iter()
                .enumerate()
                .all(|(s, &id)| a.slot_of.get(id as usize).map(|&t| t as usize) == Some(s))
            && a.slot_of
                .iter()
                .all(|&s| s == Self::REMOVED || (s as usize) < n)
    }

    /// Adds a particle after validating it; returns its stable id (the
    /// next unused id: ids of removed particles are not reused).
    pub fn push(&mut self, d: ParticleDesc) -> Result<u32, ParamError> {
        d.validate()?;
        let id = u32::try_from(self.id_bound())
            .ok()
            .filter(|&id| id < Self::REMOVED)
            .ok_or_else(|| ParamError::Invalid {
                field: "particles".into(),
                message: "at most 2^32 - 2 particle ids".into(),
            })?;
        let slot = self.len() as u32;
        let fixed_pos = d.flags.contains(Flags::FIXED_POSITION);
        let fixed_rot = d.flags.contains(Flags::FIXED_ORIENTATION);
        let a = d.normal_axis.normalize();
        self.statics.ids.push(id);
        self.statics.slot_of.push(slot);
        self.positions.push(d.position);
        self.velocities
            .push(if fixed_pos { Vec3::zeros() } else { d.velocity });
        self.orientations
            .push(Quat::new_normalize(*d.orientation.quaternion()));
        self.angular_velocities.push(if fixed_rot {
            Vec3::zeros()
        } else {
            d.angular_velocity
        });
        self.statics.masses.push(d.mass);
        self.statics
            .inv_masses
            .push(if fixed_pos { 0.0 } else { 1.0 / d.mass });
        self.statics.inertias.push(d.inertia);
        self.statics.normal_axes.push(a);
        self.statics.tangent_axes.push(tangent_axis(&a));
        self.statics.flags.push(d.flags);
        self.statics.objects.push(d.object);
        self.statics.kinds.push(d.kind);
        self.statics.materials.push(d.material);
        self.statics.curvatures.push(d.curvature);
        self.statics.temperatures.push(d.temperature);
        Ok(id)
    }

    slice_accessors! { state;
        /// Positions.
        positions: Point3,
        /// Velocities.
        velocities: Vec3,
        /// Orientations (unit quaternions).
        orientations: Quat,
        /// Angular velocities, world frame.
        angular_velocities: Vec3,
    }

    slice_accessors! { statics;
        /// Stable id of the particle in each slot.
        ids: u32,
        /// Masses.
        masses: Real,
        /// Inverse masses (0 for fixed-position particles).
        inv_masses: Real,
        /// Principal moments of inertia, body frame.
        inertias: Vec3,
        /// Body-frame normal axes `a`.
        normal_axes: Vec3,
        /// Body-frame tangent axes ("local x").
        tangent_axes: Vec3,
        /// Flags.
        flags: Flags,
        /// Object ids.
        objects: u32,
        /// Particle types.
        kinds: ParticleType,
        /// Material indices.
        materials: u16,
        /// Rest curvatures.
        curvatures: Real,
        /// Temperatures ([`crate::heat`]).
        temperatures: Real,
    }

    /// The slot currently holding particle `id`, if any (`None` for ids
    /// never given or removed).
    #[inline]
    pub fn slot_of(&self, id: u32) -> Option<usize> {
        live_slot(&self.statics.slot_of, id)
    }

    /// The particle in `slot` as a description: every attribute and its
    /// state (pushing it gives the same particle under a new id).
    pub fn desc(&self, slot: usize) -> ParticleDesc {
        ParticleDesc {
            position: self.positions()[slot],
            velocity: self.velocities()[slot],
            orientation: self.orientations()[slot],
            angular_velocity: self.angular_velocities()[slot],
            mass: self.masses()[slot],
            inertia: self.inertias()[slot],
            normal_axis: self.normal_axes()[slot],
            flags: self.flags()[slot],
            object: self.objects()[slot],
            kind: self.kinds()[slot],
            material: self.materials()[slot],
            curvature: self.curvatures()[slot],
            temperature: self.temperatures()[slot],
        }
    }

    /// World normal `n = R(q) a` of the particle in `slot`.
    #[inline]
    pub fn normal(&self, slot: usize) -> Vec3 {
        self.orientations[slot] * self.statics.normal_axes[slot]
    }

    /// Sets the velocity of the particle in `slot` (ignored for fixed
    /// positions).
    pub fn set_velocity(&mut self, slot: usize, v: Vec3) {
        if !self.statics.flags[slot].contains(Flags::FIXED_POSITION) {
            self.velocities[slot] = v;
        }
    }

    /// Moves the particle in `slot` (used by scripted tools and tests).
    pub fn set_position(&mut self, slot: usize, p: Point3) {
        self.positions[slot] = p;
    }

    /// Sets the orientation of the particle in `slot`.
    pub fn set_orientation(&mut self, slot: usize, q: Quat) {
        self.orientations[slot] = q;
    }

    /// Sets the rest curvature of the particle in `slot`.
    pub fn set_curvature(&mut self, slot: usize, kappa: Real) {
        self.statics.curvatures[slot] = kappa;
    }

    /// Sets the temperature of the particle in `slot`.
    pub fn set_temperature(&mut self, slot: usize, temperature: Real) {
        self.statics.temperatures[slot] = temperature;
    }

    /// Positions and object ids to read beside the temperatures to write
    /// (the heat update of [`crate::heat`]), by slot.
    pub(crate) fn heat_view(&mut self) -> (&[Point3], &[u32], &mut [Real]) {
        (
            &self.positions,
            &self.statics.objects,
            &mut self.statics.temperatures,
        )
    }

    /// The state seen by the integrator.
    pub fn state(&self) -> StateRef<'_> {
        StateRef {
            positions: &self.positions,
            velocities: &self.velocities,
            orientations: &self.orientations,
            angular_velocities: &self.angular_velocities,
        }
    }

    /// Splits the store into the mutable dynamic state, the mass properties
    /// and the static attributes, so the integrator can advance the state
    /// while the force field reads the attributes.
    pub fn split(&mut self) -> (StateMut<'_>, Bodies<'_>, Attributes<'_>) {
        (
            StateMut {
                positions: &mut self.positions,
                velocities: &mut self.velocities,
                orientations: &mut self.orientations,
                angular_velocities: &mut self.angular_velocities,
            },
            Bodies {
                inv_mass: &self.statics.inv_masses,
                inertia: &self.statics.inertias,
            },
            self.statics.view(),
        )
    }

    /// The static attributes alone.
    pub fn attributes(&self) -> Attributes<'_> {
        self.statics.view()
    }

    /// Reorders every array so that new slot `s` holds the particle that was
    /// in slot `order[s]`. `order` must be a permutation of `0..len`.
    pub fn permute(&mut self, order: &[u32]) {
        assert_eq!(order.len(), self.len(), "permutation length");
        self.select(order);
    }

    /// Removes the particles with the given ids; the survivors keep their
    /// ids and their relative slot order. Unknown or already removed ids,
    /// and repeated ids, are ignored. Returns the slots (before removal) of
    /// the survivors, in their new order.
    pub fn remove(&mut self, ids: &[u32]) -> Vec<u32> {
        let mut gone = vec![false; self.len()];
        for &id in ids {
            if let Some(s) = self.slot_of(id) {
                gone[s] = true;
            }
        }
        let keep: Vec<u32> = (0..self.len() as u32)
            .filter(|&s| !gone[s as usize])
            .collect();
        for (s, g) in gone.iter().enumerate() {
            if *g {
                let id = self.statics.ids[s] as usize;
                self.statics.slot_of[id] = Self::REMOVED;
            }
        }
        self.select(&keep);
        keep
    }

    /// Keeps only the slots in `order`, new slot `s` holding old slot
    /// `order[s]` (distinct, in range), and updates `slot_of` for them.
    fn select(&mut self, order: &[u32]) {
        // A gather per array, in parallel (an indexed collect: the same
        // array at any thread count); the world re-sorts at every
        // neighbour-list rebuild.
        fn apply<T: Clone + Send + Sync>(v: &mut Vec<T>, order: &[u32]) {
            let new: Vec<T> = order
                .par_iter()
                .with_min_len(4096)
                .map(|&o| v[o as usize].clone())
                .collect();
            *v = new;
        }
        apply(&mut self.statics.ids, order);
        apply(&mut self.positions, order);
        apply(&mut self.velocities, order);
        apply(&mut self.orientations, order);
        apply(&mut self.angular_velocities, order);
        apply(&mut self.statics.masses, order);
        apply(&mut self.statics.inv_masses, order);
        apply(&mut self.statics.inertias, order);
        apply(&mut self.statics.normal_axes, order);
        apply(&mut self.statics.tangent_axes, order);
        apply(&mut self.statics.flags, order);
        apply(&mut self.statics.objects, order);
        apply(&mut self.statics.kinds, order);
        apply(&mut self.statics.materials, order);
        apply(&mut self.statics.curvatures, order);
        apply(&mut self.statics.temperatures, order);
        for (slot, &id) in self.statics.ids.iter().enumerate() {
            self.statics.slot_of[id as usize] = slot as u32;
        }
    }

    /// Renormalizes every orientation quaternion (a guard against round-off
    /// drift accumulated over very long runs; the integrators already move
    /// on the unit sphere).
    pub fn renormalize_orientations(&mut self) {
        for q in &mut self.orientations {
            q.renormalize();
        }
    }

    /// Bytes of storage per particle (the sum of the element sizes of every
    /// array of the store).
    pub const BYTES_PER_PARTICLE: usize = 2 * std::mem::size_of::<u32>()
        + std::mem::size_of::<Point3>()
        + 2 * std::mem::size_of::<Vec3>()
        + std::mem::size_of::<Quat>()
        + 2 * std::mem::size_of::<Real>()
        + 3 * std::mem::size_of::<Vec3>()
        + std::mem::size_of::<Flags>()
        + std::mem::size_of::<u32>()
        + std::mem::size_of::<ParticleType>()
        + std::mem::size_of::<u16>()
        + std::mem::size_of::<Real>();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A normal opposite to the normal axis gets an exact half turn: the
    /// normal is exactly `-axis`, and a particle of a planar object (axis
    /// `+x`, normals in the plane z = 0) keeps its normal exactly in the
    /// plane as it turns about z.
    #[test]
    fn a_normal_opposite_to_the_axis_is_exact() {
        for axis in [Vec3::x(), Vec3::y(), Vec3::z(), Vec3::new(1.0, -2.0, 0.5)] {
            let mut d = ParticleDesc::at(Point3::origin());
            d.normal_axis = axis;
            let d = d.with_normal(-axis);
            let a = axis.normalize();
            assert!(d.orientation.w == 0.0, "scalar part {}", d.orientation.w);
            assert!((d.orientation * a + a).norm() < 1e-15, "{axis:?}");
        }
        let mut d = ParticleDesc::at(Point3::origin());
        d.normal_axis = Vec3::x();
        let d = d.with_normal(-Vec3::x());
        assert_eq!(d.orientation * Vec3::x(), -Vec3::x());
        for k in 1..50 {
            let turn = Quat::from_scaled_axis(Vec3::z() * (0.1 * k as Real));
            assert_eq!((turn * d.orientation * Vec3::x()).z, 0.0, "turn {k}");
        }
    }

    #[test]
    fn typing_rules_of_seed_002() {
        use ParticleType::*;
        assert!(Standard(1).complete_with(Standard(1)));
        assert!(!Standard(1).complete_with(Standard(2)));
        assert!(Hinge.complete_with(Standard(7)));
        assert!(Standard(7).complete_with(Hinge));
        assert!(!Hinge.complete_with(Hinge));
    }

    #[test]
    fn push_validates() {
        let mut p = Particles::new();
        let mut d = ParticleDesc::at(Point3::origin());
        d.mass = -1.0;
        let e = p.push(d).unwrap_err().to_string();
        assert!(e.contains("mass"), "{e}");
        let mut d = ParticleDesc::at(Point3::new(Real::NAN, 0.0, 0.0));
        d.mass = 1.0;
        assert!(p.push(d).is_err());
        assert!(p.is_empty());
    }

    /// A zero or non-finite orientation was accepted and normalized to NaN.
    #[test]
    fn degenerate_orientations_are_refused() {
        use nalgebra::Quaternion;
        let bad = [
            Quaternion::new(0.0, 0.0, 0.0, 0.0),
            Quaternion::new(1e-9, 0.0, 0.0, 0.0),
            Quaternion::new(Real::NAN, 0.0, 0.0, 0.0),
            Quaternion::new(1.0, Real::INFINITY, 0.0, 0.0),
            Quaternion::new(1e300, 1e300, 0.0, 0.0),
        ];
        for q in bad {
            let mut d = ParticleDesc::at(Point3::origin());
            d.orientation = Quat::new_unchecked(q);
            let e = d.validate().unwrap_err().to_string();
            assert!(
                e.contains("orientation") && e.contains("norm >= 1e-6"),
                "{e}"
            );
            assert!(Particles::new().push(d).is_err());
        }
        // A finite non-unit quaternion is a valid frame, normalized on
        // creation.
        let mut d = ParticleDesc::at(Point3::origin());
        d.orientation = Quat::new_unchecked(Quaternion::new(2.0, 0.0, 0.0, 2.0));
        let mut p = Particles::new();
        p.push(d).unwrap();
        let q = p.orientations()[0];
        assert!((q.quaternion().norm() - 1.0).abs() < 1e-15);
        assert!((q.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn permute_keeps_ids_consistent() {
        let mut p = Particles::new();
        for k in 0..5 {
            let mut d = ParticleDesc::at(Point3::new(k as Real, 0.0, 0.0));
            d.curvature = k as Real;
            p.push(d).unwrap();
        }
        p.permute(&[4, 2, 0, 1, 3]);
        for id in 0..5u32 {
            let s = p.slot_of(id).unwrap();
            assert_eq!(p.ids()[s], id);
            assert_eq!(p.positions()[s].x, id as Real);
            assert_eq!(p.curvatures()[s], id as Real);
        }
    }

    #[test]
    fn remove_keeps_survivor_ids_and_never_reuses_ids() {
        let mut p = Particles::new();
        for k in 0..5 {
            let mut d = ParticleDesc::at(Point3::new(k as Real, 0.0, 0.0));
            d.curvature = k as Real;
            p.push(d).unwrap();
        }
        p.permute(&[4, 2, 0, 1, 3]);
        let keep = p.remove(&[2, 2, 9, 0]);
        assert_eq!(keep, vec![0, 3, 4]);
        assert_eq!(p.ids(), &[4, 1, 3]);
        assert_eq!(p.slot_of(2), None);
        assert_eq!(p.slot_of(0), None);
        for id in [1u32, 3, 4] {
            let s = p.slot_of(id).unwrap();
            assert_eq!(p.positions()[s].x, id as Real);
            assert_eq!(p.curvatures()[s], id as Real);
        }
        assert_eq!(p.push(ParticleDesc::at(Point3::origin())).unwrap(), 5);
        assert_eq!((p.len(), p.id_bound()), (4, 6));
        assert_eq!(p.slot_of(5), Some(3));
    }

    #[test]
    fn with_normal_points_the_normal() {
        let n = Vec3::new(0.3, -0.4, 0.8).normalize();
        let d = ParticleDesc::at(Point3::origin()).with_normal(n);
        assert!((d.orientation * d.normal_axis - n).norm() < 1e-12);
        let d = ParticleDesc::at(Point3::origin()).with_normal(-Vec3::z());
        assert!((d.orientation * d.normal_axis + Vec3::z()).norm() < 1e-12);
    }
}
