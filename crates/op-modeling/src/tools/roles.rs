//! What a tool does to the particles near it (seed 000 §6): each role is
//! a potential energy of the particle's position relative to the tool's
//! surface or frame, and the force is its negative gradient (checked
//! against finite differences in the tests). Optional damping terms are
//! dissipative by design and say so.
//!
//! With `s` the signed distance from the particle to the tool's surface
//! (positive outside) and `n` the outward normal at the closest surface
//! point, `∇s = n` away from the medial axis, so a role energy `E(s)` gives
//! the force `-E'(s) n`.

use serde::{Deserialize, Serialize};

use op_dynamics::error::{self, ParamError};
use op_dynamics::math::Real;

/// A tool's role.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub enum Role {
    /// A solid obstacle: a penalty `E = k d² / 2` on the penetration
    /// `d = max(0, margin - s)`, so the force `k d n` pushes the particle
    /// out along the outward normal, growing with depth. A skinned object
    /// meets it through its skin (seed 002 §6): its particles get the
    /// gradient of the contact energy `k_E ∫ max(0, f - ISO) dV` over the
    /// obstacle's interior, `k_E = k / (g r0²)` (`g` the skin's field slope
    /// at its surface, `r0` the object's spacing), so that a particle's
    /// footprint pressed `d` deep feels the same `k d`
    /// (`op_implicit::ObstacleContact`).
    Obstacle {
        /// Penalty stiffness `k`, > 0 (force per unit depth, per particle).
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: Real,
        /// Contact offset from the surface (a particle radius), >= 0.
        /// Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        margin: Real,
        /// Damping of the normal relative velocity while in contact,
        /// `-c ((v - v_tool) · n) n`, >= 0 (dissipative, not from an
        /// energy; the total normal force is kept >= 0: contact never
        /// pulls). Skinned particles pressed on the obstacle through their
        /// skin are damped the same way (`op_implicit::friction`).
        /// Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        damping: Real,
        /// Coulomb friction coefficient `μ` (at least 0) of skins meeting
        /// the obstacle (dissipative): each skinned particle pressed on it
        /// by the skin contact reaction `N` (seed 002 §6) gets a tangential
        /// force against its sliding of at most `μ |N|`
        /// (`op_implicit::friction`). Particles meeting the obstacle
        /// without a skin feel no friction. Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        friction: Real,
    },
    /// An attractor (seed 000 §6: "attract particles to its surface"): a
    /// smooth well of depth `k R² / 2` and width `R` on both sides of the
    /// surface, `E = -(k R² / 2) (1 - s²/R²)²` for `|s| < R`, zero beyond;
    /// force `-2 k s (1 - s²/R²) n`, zero at the surface and at the reach.
    Attractor {
        /// Strength `k`, > 0 (the well's stiffness at the surface is `2k`).
        #[schemars(extend("exclusiveMinimum" = 0))]
        strength: Real,
        /// Reach `R`, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        reach: Real,
    },
    /// A mover (seed 000 §6: grabs the particles inside it and carries
    /// them): every particle inside the tool when the world is built is
    /// tied to its point in the tool frame by a spring `E = k |x - T(t) x_0|²
    /// / 2` until `release`. It holds them from the start, through a
    /// scene's settle phase too: the shape settled under its hold is the
    /// object's rest shape (what the rest shape error is measured from).
    Mover {
        /// Spring stiffness `k`, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: Real,
        /// Damping of the velocity relative to the carried point, >= 0
        /// (dissipative). Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        damping: Real,
        /// Time the tool lets go. Default: never.
        #[serde(default = "infinity", skip_serializing_if = "is_infinite")]
        release: Real,
    },
    /// An eraser (seed 000 §6, fig. 7: tools that cut a surface; here the
    /// cut removes material): every particle inside the tool's shape at the
    /// end of a step is deleted from the world
    /// ([`op_dynamics::World::remove_particles`]). No force and no energy: the
    /// removal is an edit of the particle set between steps, not a
    /// potential, so energy is not conserved across it.
    Eraser,
    /// A heater (seed 000 §8, fig. 13: "heating the surface near the
    /// tool"): no force; raises the temperature of the particles within
    /// `reach` of its surface at `power (1 - max(s, 0) / reach)` per unit
    /// time ([`op_dynamics::heat`]). Needs the world's `heat` settings.
    Heater {
        /// Heating rate at and inside the surface, > 0 (temperature per
        /// unit time).
        #[schemars(extend("exclusiveMinimum" = 0))]
        power: Real,
        /// How far outside the surface it heats, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        reach: Real,
    },
    /// A hot knife (seed 000 §6, fig. 7: "we use the heat of the cutting
    /// tool to weaken the inter-particle bonds"): a solid obstacle (the
    /// penalty of [`Role::Obstacle`]) that also heats like a
    /// [`Role::Heater`]. Needs the world's `heat` settings.
    Knife {
        /// Penalty stiffness `k`, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: Real,
        /// Contact offset from the surface, >= 0. Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        margin: Real,
        /// Normal damping in contact, >= 0. Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        damping: Real,
        /// Heating rate at and inside the surface, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        power: Real,
        /// How far outside the surface it heats, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        reach: Real,
    },
    /// A shaping tool (seed 000 §8, fig. 14: a sphere is pushed into a
    /// torus by two spherical shaping tools, and "some old sphere particles
    /// are deleted when trapped between the two shaping tools"): a solid
    /// obstacle with the [`Role::Obstacle`] penalty and damping which, with
    /// at least one other shaping tool, also deletes the particles it traps.
    ///
    /// **Trap rule.** At the end of each step, a particle lying within the
    /// contact margin of two (or more) shaping tools at once (signed
    /// distance `s < margin` to each, each tool with its own margin) is
    /// deleted from the world, like an eraser's particles
    /// ([`op_dynamics::world::StepReport::erased`]). The margin is the particle's
    /// contact radius: such a particle is pressed by two tool surfaces
    /// whose gap there is narrower than the two margins together, so it
    /// cannot stay in the surface between them; a single tool only pushes
    /// (the region exists only where two tools come within `2 margin` of
    /// each other). The deletion is an edit of the particle set between
    /// steps, not a potential (energy is not conserved across it).
    Shaper {
        /// Penalty stiffness `k`, > 0 (as [`Role::Obstacle`]).
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: Real,
        /// Contact offset from the surface (a particle radius), > 0: the
        /// reach of the penalty and of the trap rule.
        #[schemars(extend("exclusiveMinimum" = 0))]
        margin: Real,
        /// Damping of the normal relative velocity while in contact, >= 0
        /// (as [`Role::Obstacle`]). Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        damping: Real,
    },
}

fn infinity() -> Real {
    Real::INFINITY
}
fn is_infinite(v: &Real) -> bool {
    *v == Real::INFINITY
}

impl Role {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Role::Obstacle {
                stiffness,
                margin,
                damping,
                friction,
            } => {
                error::positive("Obstacle.stiffness", *stiffness)?;
                error::non_negative("Obstacle.margin", *margin)?;
                error::non_negative("Obstacle.damping", *damping)?;
                error::non_negative("Obstacle.friction", *friction)
            }
            Role::Attractor { strength, reach } => {
                error::positive("Attractor.strength", *strength)?;
                error::positive("Attractor.reach", *reach)
            }
            Role::Mover {
                stiffness,
                damping,
                release,
            } => {
                error::positive("Mover.stiffness", *stiffness)?;
                error::non_negative("Mover.damping", *damping)?;
                error::check(
                    "Mover.release",
                    *release,
                    !release.is_nan(),
                    "must be a time (or infinite)",
                )
            }
            Role::Eraser => Ok(()),
            Role::Heater { power, reach } => {
                error::positive("Heater.power", *power)?;
                error::positive("Heater.reach", *reach)
            }
            Role::Knife {
                stiffness,
                margin,
                damping,
                power,
                reach,
            } => {
                error::positive("Knife.stiffness", *stiffness)?;
                error::non_negative("Knife.margin", *margin)?;
                error::non_negative("Knife.damping", *damping)?;
                error::positive("Knife.power", *power)?;
                error::positive("Knife.reach", *reach)
            }
            Role::Shaper {
                stiffness,
                margin,
                damping,
            } => {
                error::positive("Shaper.stiffness", *stiffness)?;
                error::positive("Shaper.margin", *margin)?;
                error::non_negative("Shaper.damping", *damping)
            }
        }
    }

    /// The role's name in lower case (`obstacle`, `mover`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Role::Obstacle { .. } => "obstacle",
            Role::Attractor { .. } => "attractor",
            Role::Mover { .. } => "mover",
            Role::Eraser => "eraser",
            Role::Heater { .. } => "heater",
            Role::Knife { .. } => "knife",
            Role::Shaper { .. } => "shaper",
        }
    }

    /// Heating power and reach of a heater or knife, `None` otherwise.
    pub fn heating(&self) -> Option<(Real, Real)> {
        match *self {
            Role::Heater { power, reach } | Role::Knife { power, reach, .. } => {
                Some((power, reach))
            }
            _ => None,
        }
    }

    /// How far outside the surface the role acts (particles farther away
    /// are skipped by a bounding-box test). Movers act on their grabbed
    /// particles wherever they are; erasers and heaters exert no force (0).
    pub fn reach(&self) -> Real {
        match self {
            Role::Obstacle { margin, .. }
            | Role::Knife { margin, .. }
            | Role::Shaper { margin, .. } => *margin,
            Role::Attractor { reach, .. } => *reach,
            Role::Mover { .. } => Real::INFINITY,
            Role::Eraser | Role::Heater { .. } => 0.0,
        }
    }
}

/// Obstacle penalty: energy and `-dE/ds` (the force magnitude along `n`)
/// at signed distance `s`.
pub fn obstacle(stiffness: Real, margin: Real, s: Real) -> (Real, Real) {
    let d = margin - s;
    if d <= 0.0 {
        return (0.0, 0.0);
    }
    (0.5 * stiffness * d * d, stiffness * d)
}

/// Attractor well: energy and `-dE/ds` at signed distance `s`.
pub fn attractor(strength: Real, reach: Real, s: Real) -> (Real, Real) {
    if s.abs() >= reach {
        return (0.0, 0.0);
    }
    let u = 1.0 - s * s / (reach * reach);
    (
        -0.5 * strength * reach * reach * u * u,
        -2.0 * strength * s * u,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_derivative(f: impl Fn(Real) -> (Real, Real), samples: &[Real]) {
        let h = 1e-6;
        for &s in samples {
            let fd = -(f(s + h).0 - f(s - h).0) / (2.0 * h);
            let (_, force) = f(s);
            assert!(
                (fd - force).abs() <= 1e-6 * (1.0 + force.abs()),
                "s = {s}: fd {fd} vs {force}"
            );
        }
    }

    #[test]
    fn obstacle_force_is_minus_the_energy_slope() {
        check_derivative(
            |s| obstacle(50.0, 0.2, s),
            &[-1.0, -0.1, 0.0, 0.1, 0.19, 0.5],
        );
        assert_eq!(obstacle(50.0, 0.2, 0.3), (0.0, 0.0));
        assert!(
            obstacle(50.0, 0.0, -0.1).1 > 0.0,
            "pushes outward when inside"
        );
    }

    #[test]
    fn attractor_force_is_minus_the_energy_slope_and_pulls_to_the_surface() {
        check_derivative(
            |s| attractor(3.0, 0.5, s),
            &[-0.4, -0.1, 0.0, 0.1, 0.3, 0.49],
        );
        assert!(attractor(3.0, 0.5, 0.2).1 < 0.0, "pulled in from outside");
        assert!(attractor(3.0, 0.5, -0.2).1 > 0.0, "pushed out from inside");
        assert_eq!(attractor(3.0, 0.5, 0.6), (0.0, 0.0));
        // C1 at the reach: the force vanishes there.
        assert!(attractor(3.0, 0.5, 0.5 - 1e-9).1.abs() < 1e-7);
    }
}
