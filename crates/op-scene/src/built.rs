//! A scene turned into a world: what the runner needs and nothing more.

use std::path::PathBuf;

use op_dynamics::{Divergence, Point3, Real, Tool, World};

use crate::creation::CreationState;
use crate::outputs::{Outputs, ParticleOutput};
use crate::skins::{contact_step, BuiltSkin, ContactStats, SkinTool};

/// One object of a built scene.
#[derive(Clone, Debug)]
pub struct BuiltObject {
    /// Object name (unique in the scene; the OBJ object name).
    pub name: String,
    /// Stable particle ids of the object, in generation order.
    pub ids: Vec<u32>,
    /// Rest positions (in `ids` order): the reference of the rest shape
    /// error. The positions at build time, replaced by the settled ones
    /// when [`BuiltScene::settle`] runs a settle phase.
    pub rest: Vec<Point3>,
    /// Mean nearest-neighbour distance of `rest`: the `r0` that divides
    /// the rest shape error (DESIGN §6).
    pub rest_spacing: Real,
    /// Ids of the particles the creation rules added to the object, in
    /// creation order (see [`crate::creation`]); they have no rest
    /// position and do not count in the rest shape error.
    pub created: Vec<u32>,
}

impl BuiltObject {
    /// Every particle id of the object: the original ones, then the
    /// created ones.
    pub fn all_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.ids.iter().chain(&self.created).copied()
    }
}

/// A validated scene built into a world containing only what it enables.
pub struct BuiltScene {
    /// Scene name (summary `scene` field, default output folder name).
    pub name: String,
    /// The file it came from, if any.
    pub source: Option<PathBuf>,
    /// The world, ready to step.
    pub world: World,
    /// The objects, in scene order.
    pub objects: Vec<BuiltObject>,
    /// Simulated duration (after the settle phase).
    pub duration: Real,
    /// Duration of the settle phase run before frame 0 (`world.settle`;
    /// the force windows start counting at its end).
    pub settle: Real,
    /// True once the settle phase ran (or when there is none): see
    /// [`BuiltScene::settle`].
    pub settled: bool,
    /// Frames written per unit of simulated time.
    pub frame_rate: Real,
    /// What to write.
    pub outputs: Outputs,
    /// Runaway-energy threshold: the run is declared diverged when the
    /// kinetic energy exceeds `energy_growth` times the initial energy
    /// scale (|kinetic| + |potential| at t = 0, at least 1e-12 per
    /// particle). Default 1e6; infinity disables the check.
    pub energy_growth: Real,
    /// Explosion threshold: a particle this many scene sizes beyond the
    /// scene's bounds ends the run as diverged (see [`crate::health`]).
    pub extent_growth: Real,
    /// Warnings known before the run starts (a step above the estimated
    /// stable step, see [`crate::stability`]); the runner puts them first
    /// in the summary's `warnings`.
    pub step_warnings: Vec<String>,
    /// Energy-gain threshold of passive scenes (no force window, zero
    /// gravity, no contact): the run is declared diverged when a frame's
    /// total energy exceeds the lowest earlier one by more than
    /// `energy_gain` times the initial energy scale. Infinity (the
    /// default) disables the check.
    pub energy_gain: Real,
    /// The implicit skins of the skinned objects, in scene order (empty
    /// when no object has a skin: nothing of op-implicit is built).
    pub skins: Vec<BuiltSkin>,
    /// Every tool of the scene, in scene order (drawn in the frames as
    /// `tool_<name>`; the world and [`BuiltScene::skin_tools`] hold the
    /// ones that act).
    pub tools: Vec<Tool>,
    /// Obstacle tools met by skins (empty when no skinned object meets an
    /// obstacle).
    pub skin_tools: Vec<SkinTool>,
    /// Contact figures accumulated by [`BuiltScene::advance_to`].
    pub contact: ContactStats,
    /// The creation rules, when the scene has some (see
    /// [`crate::creation`]).
    pub creation: Option<CreationState>,
}

impl BuiltScene {
    /// Runs the settle phase once (the runner calls this before frame 0):
    /// advances the world to time [`BuiltScene::settle`] (no force window
    /// acts before it), then takes the settled positions as each object's
    /// rest shape and recomputes its rest spacing. Does nothing when there
    /// is no settle phase or it already ran.
    ///
    /// # Errors
    ///
    /// The divergence, if the world blew up while settling (the rest shapes
    /// are then left as built).
    pub fn settle(&mut self) -> Result<(), Divergence> {
        if self.settled {
            return Ok(());
        }
        self.world.advance_to(self.settle)?;
        self.settled = true;
        let p = self.world.particles();
        for o in &mut self.objects {
            // Eraser tools may have removed particles while settling: the
            // reference holds the survivors.
            o.ids.retain(|&id| p.slot_of(id).is_some());
            o.rest = o
                .ids
                .iter()
                .filter_map(|&id| p.slot_of(id).map(|s| p.positions()[s]))
                .collect();
            // Particles cannot coincide after a finite, non-divergent settle
            // phase unless the material lets them; keep the built spacing then.
            if let Ok(r0) = crate::build::rest_spacing(&o.rest, Some(o.rest_spacing)) {
                o.rest_spacing = r0;
            }
        }
        Ok(())
    }

    /// What the scene computes: the world's stages
    /// ([`World::enabled`]) followed by `skin` (skins are posed) and
    /// `polygonize` (skins are written in the frames) when some object has
    /// a skin, and `contact` when at least two have (implicit contact).
    pub fn stages(&self) -> Vec<String> {
        let mut stages = self.world.enabled();
        if !self.skins.is_empty() {
            stages.push("skin".into());
            if self.outputs.particles != ParticleOutput::None {
                stages.push("polygonize".into());
            }
        }
        if self.has_contact() {
            stages.push("contact".into());
        }
        if let Some(c) = &self.creation {
            stages.push("creation".into());
            if c.fit.is_some() {
                stages.push("fit".into());
            }
        }
        if self.outputs.triangulation {
            stages.push("triangulation".into());
        }
        stages
    }

    /// Whether nothing feeds energy into the scene or changes its energy
    /// function: no force window, zero gravity, no tool, no contact, no
    /// heat, no creation, no bonds, no plastic material and no spin term
    /// (a torque without a potential, seed 000 eq. 14-15). Only such a
    /// scene is checked for energy gain.
    pub fn is_passive(&self) -> bool {
        let w = &self.world;
        let e = &w.params().external;
        e.forces.is_empty()
            && e.gravity().iter().all(|g| *g == 0.0)
            && self.tools.is_empty()
            && !self.has_contact()
            && w.params().heat.is_none()
            && self.creation.is_none()
            && w.bonds().is_none()
            && w.materials()
                .iter()
                .all(|m| m.plasticity().is_none() && !m.enabled_terms().contains(&"spin"))
    }

    /// Whether skins are in contact: implicit contact (two or more skinned
    /// objects) or contact with obstacle tools.
    pub fn has_contact(&self) -> bool {
        self.skins.len() >= 2 || !self.skin_tools.is_empty()
    }

    /// Advances the world to world time `t_end`. Without contact this is
    /// [`World::advance_to`]; with contact the world advances by intervals
    /// of `dt`, the contact reactions computed at the start of each and
    /// held over it (over every step of it with the adaptive scheme), and [`BuiltScene::contact`] is updated (see
    /// [`crate::skins`]). Skins are re-posed at `t_end` either way.
    ///
    /// # Errors
    ///
    /// The divergence or contact sampling error, as a message.
    pub fn advance_to(&mut self, t_end: Real) -> Result<(), String> {
        if self.has_contact() {
            let dt = self.world.params().dt;
            loop {
                let remaining = t_end - self.world.time();
                if remaining <= 1e-12 * dt {
                    break;
                }
                let h = if remaining <= dt * (1.0 + 1e-6) {
                    remaining
                } else {
                    dt
                };
                contact_step(
                    &mut self.world,
                    &mut self.skins,
                    &self.skin_tools,
                    &self.objects,
                    h,
                    &mut self.contact,
                )?;
                let target = self.world.time() + h;
                self.world.hold_external_forces_until(target);
                self.world.advance_to(target).map_err(|d| d.to_string())?;
            }
        } else if self.creation.is_some() {
            self.advance_creating(t_end)?;
        } else {
            self.world.advance_to(t_end).map_err(|d| d.to_string())?;
        }
        for s in &mut self.skins {
            s.skin
                .repose(&self.world)
                .map_err(|e| format!("posing skin {}: {e}", s.name))?;
        }
        Ok(())
    }

    /// [`BuiltScene::advance_to`] with creation rules: advances at most to
    /// the step where the rules act next, applies them there, and repeats
    /// until `t_end`.
    fn advance_creating(&mut self, t_end: Real) -> Result<(), String> {
        let dt = self.world.params().dt;
        loop {
            let remaining = t_end - self.world.time();
            if remaining <= 1e-12 * dt {
                return Ok(());
            }
            let Some(state) = self.creation.as_mut() else {
                return self.world.advance_to(t_end).map_err(|d| d.to_string());
            };
            let mut release_time = Real::INFINITY;
            if let Some(fit) = state.fit.as_mut().filter(|f| !f.released) {
                if self.world.time() >= fit.release_time - 1e-12 * dt {
                    // Seed 000 §7: the samples are freed, creation stops.
                    fit.released = true;
                    // The surviving samples (an eraser may have removed
                    // some) keep their rest positions under their new ids.
                    let o = &mut self.objects[fit.object];
                    let p = self.world.particles();
                    let (ids, rest): (Vec<u32>, Vec<_>) = o
                        .ids
                        .iter()
                        .zip(&o.rest)
                        .filter(|(&id, _)| p.slot_of(id).is_some())
                        .unzip();
                    o.ids = crate::fit::release(&mut self.world, &ids)
                        .map_err(|e| format!("releasing the fit's samples: {e}"))?;
                    o.rest = rest;
                } else {
                    release_time = fit.release_time;
                }
            }
            if state.fit.as_ref().is_some_and(|f| f.released) {
                return self.world.advance_to(t_end).map_err(|d| d.to_string());
            }
            if self.world.steps() >= state.next_step {
                state.next_step = self.world.steps() + state.params.interval;
                let merges = state
                    .params
                    .merges(self.world.particles())
                    .map_err(|e| format!("creation: {e}"))?;
                self.world
                    .merge_particles(&merges)
                    .map_err(|e| format!("creation: {e}"))?;
                let mut descs = state
                    .params
                    .candidates(self.world.particles())
                    .map_err(|e| format!("creation: {e}"))?;
                if let Some(fit) = &state.fit {
                    descs.retain(|d| fit.near.contains(&d.position));
                }
                let ids = self
                    .world
                    .insert_particles(&descs)
                    .map_err(|e| format!("creation: {e}"))?;
                for (d, id) in descs.iter().zip(ids) {
                    if let Some(o) = self.objects.get_mut(d.object as usize) {
                        o.created.push(id);
                    }
                }
            }
            // Step by step up to the next application (or t_end).
            let steps_left = state_steps_left(self.creation.as_ref(), self.world.steps());
            let target = (self.world.time() + steps_left as Real * dt)
                .min(t_end)
                .min(release_time);
            let target = if t_end - target <= 1e-12 * dt {
                t_end
            } else {
                target
            };
            self.world.advance_to(target).map_err(|d| d.to_string())?;
        }
    }

    /// Scene time: the world's time minus the settle phase once it ran
    /// (frame 0 is at scene time 0; force windows are in scene time).
    pub fn scene_time(&self) -> Real {
        if self.settled {
            self.world.time() - self.settle
        } else {
            self.world.time()
        }
    }
}

/// Steps until the creation rules act next (at least 1).
fn state_steps_left(state: Option<&CreationState>, steps: u64) -> u64 {
    state.map_or(1, |s| s.next_step.saturating_sub(steps).max(1))
}
