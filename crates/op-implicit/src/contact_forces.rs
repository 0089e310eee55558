//! Skin contact as a force contributor evaluated at every force evaluation
//! of a step (seed 002 §6): [`ContactForces`].
//!
//! The reactions of every pair of skins (the gradient of their contact
//! energy, [`crate::ContactPair::reactions`]) and of every skin against the
//! obstacle tools it meets ([`SkinTool`]) are computed from the state the
//! integrator evaluates, with the contact skins posed on it: velocity
//! Verlet takes its half kicks with the contact forces of the positions it
//! kicks from, so a scene with contact keeps the scheme's order (the
//! contact energy's Verlet test,
//! `implicit_contact::energy::tests::verlet_conserves_energy_with_contact_at_second_order`),
//! and the forces velocity Verlet computes at the end of a step serve the
//! next one. What changes between steps and not within one (the particles
//! that carry primitives, the stretch compensation's references) is a
//! snapshot the contact stage refreshes before each interval
//! ([`ContactForces::update`]); the stretch compensation's weights are held
//! at those references ([`crate::StretchCompensation::apply_held`]).

use std::sync::Mutex;

use rayon::prelude::*;

use op_dynamics::contributors::{Contribution, Contributor, ContributorInput};
use op_dynamics::{Point3, Quat, Real, Vec3, World, MIN_PARALLEL_LEN};

use crate::implicit_contact::common_box;
use crate::object_skin::{ContactError, ObjectSkin, SkinTool};
use crate::skin::SkinState;
use crate::{ContactPair, Field, ImplicitContactParams};

/// What the contact reads of one particle.
#[derive(Clone, Copy, Debug)]
pub struct ParticleState {
    /// Position.
    pub position: Point3,
    /// Orientation (body to world).
    pub orientation: Quat,
    /// Linear velocity.
    pub velocity: Vec3,
    /// Mass.
    pub mass: Real,
}

/// The contact skin of one skinned object, as the contributor poses it.
#[derive(Clone, Debug)]
struct ContactSkin {
    name: String,
    rest_spacing: Real,
    cell_size: Real,
    stiffness: Real,
    surface_slope: Real,
    state: SkinState,
}

/// The figures of one evaluation: the sum over pairs and tools of the
/// contact force's magnitude (on the second skin of a pair, on the skin
/// against a tool), and the deepest penetration in units of r0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactFigures {
    /// Sum of `|F|` over pairs and tools.
    pub force: Real,
    /// Deepest overlap of two skins or depth in a tool, in units of r0.
    pub max_penetration: Real,
}

/// What the last evaluation left for the contact stage.
#[derive(Debug, Default)]
struct Last {
    figures: ContactFigures,
    error: Option<ContactError>,
}

/// Skin contact, evaluated at every force evaluation (module doc).
#[derive(Debug, Default)]
pub struct ContactForces {
    skins: Vec<ContactSkin>,
    tools: Vec<SkinTool>,
    /// The interval friction is capped over (the world's step).
    friction_interval: Real,
    last: Mutex<Last>,
}

impl ContactForces {
    /// Takes the skins' attachments and stretch references (copied only
    /// when they changed), the tools (copied the first time: a scene's
    /// tools stay the same through a run) and the friction interval `dt`
    /// for the coming evaluations.
    pub fn update(&mut self, skins: &[ObjectSkin], tools: &[SkinTool], dt: Real) {
        self.friction_interval = dt;
        let same = self.skins.len() == skins.len()
            && self
                .skins
                .iter()
                .zip(skins)
                .all(|(c, s)| c.name == s.name && s.skin.has_state(&c.state));
        if !same {
            self.skins = skins
                .iter()
                .map(|s| ContactSkin {
                    name: s.name.clone(),
                    rest_spacing: s.rest_spacing,
                    cell_size: s.cell_size,
                    stiffness: s.stiffness,
                    surface_slope: s.surface_slope,
                    state: s.skin.state(),
                })
                .collect();
        }
        if self.tools.len() != tools.len() {
            self.tools = tools.to_vec();
        }
    }

    /// The figures of the last evaluation, and the error it met (taken).
    pub fn take_last(&self) -> (ContactFigures, Option<ContactError>) {
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        (last.figures, last.error.take())
    }

    /// The reactions at time `t` on the particles `state` gives by id,
    /// each passed to `add` (id, force, torque about the particle), and
    /// the figures. Errors: a skin that cannot be posed or sampled.
    pub fn evaluate(
        &self,
        t: Real,
        state: &(dyn Fn(u32) -> Option<ParticleState> + Sync),
        add: &mut dyn FnMut(u32, Vec3, Vec3),
    ) -> Result<ContactFigures, ContactError> {
        // Side by side only when the skins are large: a small one's posing
        // costs less than waking another thread.
        let large = self.skins.iter().map(|s| s.state.len()).sum::<usize>() >= MIN_PARALLEL_LEN;
        let mut fields = self
            .skins
            .par_iter()
            .with_min_len(if large { 1 } else { self.skins.len().max(1) })
            .map(|s| {
                s.state
                    .posed_unlisted(|id| state(id).map(|p| (p.position, p.orientation)))
                    .map_err(|source| ContactError::Pose {
                        skin: s.name.clone(),
                        source,
                    })
            })
            .collect::<Result<Vec<Field>, _>>()?;
        let regions = self.regions(t, &fields);
        fields
            .par_iter_mut()
            .with_min_len(if large { 1 } else { self.skins.len().max(1) })
            .zip(&self.skins)
            .zip(&regions)
            .for_each(|((field, skin), regions)| {
                field.list_within(regions.as_deref());
                skin.state.compensate(field, regions.as_deref());
            });
        let mut figures = ContactFigures::default();
        for tool in &self.tools {
            for &k in &tool.skins {
                let skin = &self.skins[k];
                let (force, depth) = tool.react(
                    &fields[k],
                    (
                        &skin.name,
                        skin.cell_size,
                        skin.rest_spacing,
                        skin.surface_slope,
                    ),
                    t,
                    self.friction_interval,
                    state,
                    add,
                )?;
                let r0 = skin.rest_spacing.max(Real::MIN_POSITIVE);
                figures.max_penetration = figures.max_penetration.max(depth / r0);
                figures.force += force.norm();
            }
        }
        for i in 0..self.skins.len() {
            for j in i + 1..self.skins.len() {
                let (a, b) = (&self.skins[i], &self.skins[j]);
                let (fa, fb) = (&fields[i], &fields[j]);
                let params = ImplicitContactParams::new(
                    0.5 * (a.stiffness + b.stiffness),
                    a.cell_size.min(b.cell_size),
                );
                let r = ContactPair::new(fa, fb)
                    .reactions(&params)
                    .map_err(|source| ContactError::Pair {
                        a: a.name.clone(),
                        b: b.name.clone(),
                        source,
                    })?;
                let Some((deepest, excess)) = r.peak() else {
                    continue;
                };
                let r0 = a.rest_spacing.min(b.rest_spacing).max(Real::MIN_POSITIVE);
                let ga = fa.value_and_gradient(&deepest).1.norm();
                let gb = fb.value_and_gradient(&deepest).1.norm();
                let depth = excess / ga.max(1e-12) + excess / gb.max(1e-12);
                figures.max_penetration = figures.max_penetration.max(depth / r0);
                figures.force += r.b().total_force().norm();
                for x in r.a().reactions().iter().chain(r.b().reactions()) {
                    add(x.particle, x.force, x.torque);
                }
            }
        }
        Ok(figures)
    }

    /// Per skin, the boxes where an evaluation at time `t` reads its
    /// field (`None`: everywhere): the sampling box of each tool it meets
    /// and the common box of the supports of each skin it overlaps, each
    /// padded by three cells (the sampling grids reach a cell beyond their
    /// box, and their blocks list the primitives a cell beyond their
    /// nodes). The stretch compensation is computed there only, and the
    /// pruning grid lists only the primitives near them
    /// ([`Field::list_within`]): elsewhere the field is never read.
    fn regions(&self, t: Real, fields: &[Field]) -> Vec<Option<Vec<(Point3, Point3)>>> {
        let mut regions: Vec<Option<Vec<(Point3, Point3)>>> = vec![Some(Vec::new()); fields.len()];
        // A box, padded; `None` or a non-finite box: everywhere.
        let mut add = |k: usize, region: Option<(Point3, Point3)>, h: Real| {
            let pad = Vec3::repeat(3.0 * h);
            let padded = region
                .map(|(lo, hi)| (lo - pad, hi + pad))
                .filter(|(lo, hi)| lo.iter().chain(hi.iter()).all(|x| x.is_finite()));
            match (&mut regions[k], padded) {
                (Some(boxes), Some(b)) => boxes.push(b),
                (slot, _) => *slot = None,
            }
        };
        for tool in &self.tools {
            for &k in &tool.skins {
                let h = self.skins[k].cell_size;
                add(k, Some(tool.region(t, h)), h);
            }
        }
        for i in 0..fields.len() {
            for j in i + 1..fields.len() {
                let h = self.skins[i].cell_size.min(self.skins[j].cell_size);
                // A non-finite box (an error): compensate everywhere, and
                // let the pair's reactions report it.
                let common = match common_box(&fields[i], &fields[j]) {
                    Ok(None) => continue,
                    Ok(Some(common)) => Some(common),
                    Err(_) => None,
                };
                add(i, common, h);
                add(j, common, h);
            }
        }
        regions
    }

    /// [`ContactForces::evaluate`] on `world`'s particles at its time.
    pub fn evaluate_on(
        &self,
        world: &World,
        add: &mut dyn FnMut(u32, Vec3, Vec3),
    ) -> Result<ContactFigures, ContactError> {
        let p = world.particles();
        let state = |id: u32| {
            p.slot_of(id).map(|s| ParticleState {
                position: p.positions()[s],
                orientation: p.orientations()[s],
                velocity: p.velocities()[s],
                mass: p.masses()[s],
            })
        };
        self.evaluate(world.time(), &state, add)
    }
}

impl Contributor for ContactForces {
    fn name(&self) -> &str {
        "skin contact"
    }

    /// Active when two skins or a skin and a tool can meet.
    fn is_active(&self) -> bool {
        self.skins.len() > 1 || !self.tools.is_empty()
    }

    fn adds_torque(&self) -> bool {
        true
    }

    /// A function of the evaluated state and time, with the snapshot the
    /// stage refreshes only when it changed.
    fn follows_state(&self) -> bool {
        true
    }

    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>) {
        let s = &input.state;
        let state = |id: u32| {
            input.slot(id).map(|k| ParticleState {
                position: s.positions[k],
                orientation: s.orientations[k],
                velocity: s.velocities[k],
                mass: input.attributes.masses[k],
            })
        };
        let mut add = |id: u32, force: Vec3, torque: Vec3| {
            if let Some(k) = input.slot(id) {
                out.forces[k] += force;
                out.torques[k] += torque;
            }
        };
        let result = self.evaluate(input.t, &state, &mut add);
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        match result {
            Ok(figures) => last.figures = figures,
            Err(e) => {
                last.figures = ContactFigures::default();
                last.error.get_or_insert(e);
            }
        }
    }
}
