//! The energy checks of a run's frames (divergence: runaway energy, the
//! energy gain of a passive scene).

use op_dynamics::{Diagnostics, Divergence, Real};

use crate::built_scene::BuiltScene;
use crate::error::short;

/// The energy checks of every frame (README "Running scenes"): runaway
/// kinetic energy against the energy scale, and the gain of a passive
/// scene over its lowest earlier total.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct EnergyWatch {
    /// The energy the scene's own inputs can give it
    /// ([`crate::health::energy_floor`]), at least its kinetic energy when
    /// the watch started.
    floor: Real,
    /// The watch started before a settle phase.
    settles: bool,
    /// The energy scale and the particle count it was taken at.
    scale: Option<(Real, usize)>,
    /// A damped, unforced scene (its energy may not rise).
    passive: bool,
    lowest_total: Real,
    /// The largest gain seen (in units of `gain_scale`).
    pub(super) gain_seen: Real,
    gain_scale: Option<Real>,
}

impl EnergyWatch {
    /// Starts watching `scene` in its current state, before its settle
    /// phase when `settles` (the runner starts there): the runaway scale
    /// is taken at the first check, never below `floor` nor below the
    /// kinetic energy now; after a settle phase the first check adds only
    /// its potential energy, not the kinetic energy a blow-up while
    /// settling would have put there. (The kinetic energy is read from the
    /// velocities: a force evaluation now would be one the run does not
    /// otherwise make, and tools and contact keep state across them.)
    pub(super) fn new(scene: &BuiltScene, floor: Real, settles: bool) -> Self {
        let d = op_dynamics::diagnostics::kinematic(scene.world.particles());
        EnergyWatch {
            floor: floor.max(d.kinetic_translational + d.kinetic_rotational),
            settles,
            scale: None,
            passive: scene.is_passive(),
            lowest_total: Real::INFINITY,
            gain_seen: 0.0,
            gain_scale: None,
        }
    }

    /// Checks the frame with diagnostics `d`; the divergence message when
    /// it fails.
    pub(super) fn check(&mut self, scene: &BuiltScene, d: &Diagnostics) -> Result<(), Divergence> {
        let count = scene.world.particles().len();
        let here = (d.kinetic_translational + d.kinetic_rotational).abs() + d.potential.abs();
        self.check_runaway(scene, d, count, here)?;
        // The gain of a passive scene is measured against its own energy at
        // frame 0 (a damped scene at rest holds only potential energy).
        let own_scale = *self
            .gain_scale
            .get_or_insert(here.max(1e-12 * count as Real));
        if self.passive && self.lowest_total.is_finite() {
            let gain = (d.total - self.lowest_total) / own_scale.max(Real::MIN_POSITIVE);
            if gain > scene.energy_gain {
                let reason = format!(
                    "energy gain: total energy {:.6e} exceeds the lowest of the earlier \
                     frames, {:.6e}, by more than divergence.energy_gain = {} x energy scale \
                     {own_scale:.3e}; a damped, unforced scene cannot gain energy: a step too \
                     large for the stiffness put it in (reduce dt or use the adaptive scheme), \
                     or a pair started at r = 0, where its energy is taken as 0",
                    d.total,
                    self.lowest_total,
                    short(scene.energy_gain)
                );
                return Err(divergence(scene, None, reason));
            }
            self.gain_seen = self.gain_seen.max(gain);
        }
        self.lowest_total = self.lowest_total.min(d.total);
        Ok(())
    }

    /// The runaway check alone: non-finite energy, or kinetic energy above
    /// `energy_growth` times the scale. The scale is taken at the first
    /// check (see [`EnergyWatch::new`]), and again (keeping the larger)
    /// whenever the creation rules changed the particle count: new
    /// particles bring energy the first check did not hold. `count` is the
    /// particle count and `here` the frame's `|kinetic| + |potential|`.
    fn check_runaway(
        &mut self,
        scene: &BuiltScene,
        d: &Diagnostics,
        count: usize,
        here: Real,
    ) -> Result<(), Divergence> {
        let scale = match self.scale {
            Some((s, c)) if c == count => s,
            Some((s, _)) => Real::max(s, here),
            None if self.settles => d.potential.abs().max(self.floor),
            None => here.max(self.floor),
        };
        self.scale = Some((scale, count));
        let kinetic = d.kinetic_translational + d.kinetic_rotational;
        if !d.total.is_finite() || kinetic > scene.energy_growth * scale {
            return Err(runaway(scene, kinetic, scale));
        }
        Ok(())
    }
}

/// A divergence detected by the runner at the world's current step.
pub(super) fn divergence(scene: &BuiltScene, particle: Option<u32>, reason: String) -> Divergence {
    Divergence {
        step: scene.world.steps(),
        time: scene.world.time(),
        particle,
        reason,
    }
}

/// The runaway-energy divergence, naming the fastest particle.
fn runaway(scene: &BuiltScene, kinetic: Real, scale: Real) -> Divergence {
    let p = scene.world.particles();
    let fastest = (0..p.len())
        .max_by(|&a, &b| {
            p.velocities()[a]
                .norm()
                .total_cmp(&p.velocities()[b].norm())
        })
        .map_or(0, |s| p.ids()[s]);
    let reason = format!(
        "runaway energy (kinetic {kinetic:.3e} > {} x energy scale {scale:.3e})",
        short(scene.energy_growth)
    );
    divergence(scene, Some(fastest), reason)
}
