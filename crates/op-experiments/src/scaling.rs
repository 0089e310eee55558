//! Changing a scene's units by dimensional analysis (docs/model.md §3, §7).
//!
//! A scene expressed in units `(L, M, T)` describes the same motion in
//! units `(L/s, M/m, T/t)` when every parameter is multiplied by
//! `s^a m^b t^c` for its dimension `L^a M^b T^c`: positions, lengths and
//! cut-offs by `s`; curvatures by `1/s`; cohesion `α` by `1/s²`; masses by
//! `m`; moments of inertia by `m s²`; times (step, duration, settle, force
//! windows) by `t`; frame rates by `1/t`; velocities by `s/t`; forces by
//! `m s/t²`; energies (Lennard-Jones `ε`, repulsion strength, the weights
//! of the normalized, dimensionless orientation terms) by `m s²/t²`;
//! cohesion `E` (force = `E` length²) by `m/(s t²)`; linear damping and
//! friction (force per velocity) by `m/t`; angular damping (torque per
//! angular velocity) by `m s²/t`. The orientation weight's amplitude `K` is
//! dimensionless and kept. [`Scaling::scene`] applies the rule to every
//! field of a [`Scene`]; the scaled run is the original one with positions
//! times `s` and times times `t`, up to round-off (the rest shape error,
//! measured in rest spacings, is the same).
//!
//! Scaling only the geometry (every length, but not the forces, energies,
//! stiffnesses, masses and inertias: [`Scaling::geometry_only`]) changes
//! the physics: cohesion forces grow like `s²` (`E (r0 - r)³ / r`), the
//! orientation terms keep their energies over lengths `s` times larger,
//! inertias no longer match the masses' lever arms. It is not expected to
//! reproduce the motion, and the shape-memory report shows it does not.

use op_dynamics::interactions::{Spacing, SpinKind, WeightShape};
use op_dynamics::{Material, Real, Scheme};
use op_modeling::tools::{Role, ToolShape};
use op_scene::schema::{ToolSpec, Velocities};
use op_scene::{CreationSettings, Generator, Scene, SkinPrimitive, SkinSpec};

/// Scale factors of a change of units: lengths are multiplied by
/// `length`, masses by `mass`, times by `time`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Scaling {
    /// Factor `s` on lengths.
    pub length: Real,
    /// Factor `m` on masses.
    pub mass: Real,
    /// Factor `t` on times.
    pub time: Real,
}

impl Scaling {
    /// Lengths by `s`, masses and times unchanged (the rule used for the
    /// ×10 spiral: same time axis, so the force schedule is unchanged).
    pub fn length(s: Real) -> Scaling {
        Scaling {
            length: s,
            mass: 1.0,
            time: 1.0,
        }
    }

    fn energy(&self) -> Real {
        self.mass * self.length * self.length / (self.time * self.time)
    }

    fn force(&self) -> Real {
        self.mass * self.length / (self.time * self.time)
    }

    fn velocity(&self) -> Real {
        self.length / self.time
    }

    fn scale3(v: [Real; 3], k: Real) -> [Real; 3] {
        [v[0] * k, v[1] * k, v[2] * k]
    }

    /// The material in the new units.
    pub fn material(&self, m: &Material) -> Material {
        let (s, e) = (self.length, self.energy());
        let mut out = *m;
        out.spacing = m.spacing.map(|sp| match sp {
            Spacing::Cohesion(mut c) => {
                c.e *= self.mass / (s * self.time * self.time);
                c.r0 *= s;
                c.alpha /= s * s;
                c.cutoff = c.cutoff.map(|x| x * s);
                Spacing::Cohesion(c)
            }
            Spacing::LennardJones(mut l) => {
                l.epsilon *= e;
                l.r0 *= s;
                l.cutoff *= s;
                Spacing::LennardJones(l)
            }
        });
        out.weight.a *= s;
        out.weight.cutoff *= s;
        if let WeightShape::Anisotropic { b } = m.weight.shape {
            out.weight.shape = WeightShape::Anisotropic { b: b * s };
        }
        // Normalized terms are dimensionless, raw ones carry lengths.
        let raw = |power: i32| if m.normalized { e } else { e / s.powi(power) };
        out.coplanarity *= raw(2);
        out.conormality *= e;
        out.cocircularity *= raw(2);
        out.form *= raw(2);
        out.spin *= raw(match m.spin_kind {
            SpinKind::MinCurvature => 3,
            SpinKind::MinAbsCurvature => 4,
        });
        out.repulsion.strength *= e;
        out.repulsion.sigma *= s;
        out.repulsion.lambda *= s;
        out.repulsion.cutoff *= s;
        out.friction *= self.mass / self.time;
        if let Some(h) = &mut out.heat {
            // Melting and residual are a temperature and a ratio.
            h.cold_drag *= self.mass / self.time;
        }
        if let Some(b) = &mut out.bonds {
            b.radius *= s;
            b.break_length = b.break_length.map(|x| x * s);
        }
        if let Some(p) = &mut out.plasticity {
            p.yield_curvature /= s;
            p.rate /= self.time;
        }
        if let Some(b) = &mut out.bond_memory {
            b.stiffness *= self.mass / (self.time * self.time);
            if let Some(f) = &mut b.flow {
                f.yield_offset *= s;
                f.rate /= self.time;
            }
        }
        out
    }

    /// The generator in the new units, or a message for a points file
    /// (its coordinates cannot be scaled here).
    pub fn generator(&self, g: &Generator) -> Result<Generator, String> {
        let s = self.length;
        let p = |v: [Real; 3]| Self::scale3(v, s);
        Ok(match g.clone() {
            Generator::Spiral {
                count,
                spacing,
                curvature_start,
                curvature_end,
                law,
                center,
                normal,
            } => Generator::Spiral {
                count,
                spacing: spacing * s,
                curvature_start: curvature_start / s,
                curvature_end: curvature_end / s,
                law,
                center: p(center),
                normal,
            },
            Generator::HexSheet {
                nx,
                ny,
                spacing,
                center,
                normal,
                noise,
                seed,
            } => Generator::HexSheet {
                nx,
                ny,
                spacing: spacing * s,
                center: p(center),
                normal,
                noise: noise * s,
                seed,
            },
            Generator::Chain {
                count,
                spacing,
                start,
                direction,
                normal,
            } => Generator::Chain {
                count,
                spacing: spacing * s,
                start: p(start),
                direction,
                normal,
            },
            Generator::SphereShell {
                radius,
                spacing,
                center,
            } => Generator::SphereShell {
                radius: radius * s,
                spacing: spacing * s,
                center: p(center),
            },
            Generator::SolidBall {
                radius,
                spacing,
                center,
            } => Generator::SolidBall {
                radius: radius * s,
                spacing: spacing * s,
                center: p(center),
            },
            Generator::TorusShell {
                major,
                minor,
                spacing,
                center,
                axis,
            } => Generator::TorusShell {
                major: major * s,
                minor: minor * s,
                spacing: spacing * s,
                center: p(center),
                axis,
            },
            Generator::List { mut particles } => {
                for q in &mut particles {
                    q.position = p(q.position);
                    q.curvature = q.curvature.map(|k| k / s);
                }
                Generator::List { particles }
            }
            Generator::Points { path } => {
                return Err(format!(
                    "cannot scale the points file {}: scale its coordinates",
                    path.display()
                ))
            }
        })
    }

    /// The whole scene in the new units (see the module docs).
    ///
    /// # Errors
    ///
    /// When an object reads a points file.
    pub fn scene(&self, scene: &Scene) -> Result<Scene, String> {
        let (s, m, t) = (self.length, self.mass, self.time);
        let mut out = scene.clone();
        let w = &mut out.world;
        if let Scheme::Adaptive(a) = &mut w.integrator {
            a.atol_position *= s;
            a.atol_velocity *= self.velocity();
            a.atol_angular_velocity /= t;
            a.dt_min *= t;
            if a.dt_max != Real::MAX {
                a.dt_max *= t;
            }
        }
        w.dt *= t;
        w.duration *= t;
        w.settle *= t;
        w.frame_rate /= t;
        w.gravity = Self::scale3(w.gravity, s / (t * t));
        w.linear_damping *= m / t;
        w.angular_damping *= m * s * s / t;
        w.divergence.max_speed *= self.velocity();
        for mat in out.materials.values_mut() {
            *mat = self.material(mat);
        }
        for o in &mut out.objects {
            o.generator = self.generator(&o.generator)?;
            o.mass *= m;
            o.inertia = Self::scale3(o.inertia, m * s * s);
            o.velocity = Self::scale3(o.velocity, self.velocity());
            o.angular_velocity = Self::scale3(o.angular_velocity, 1.0 / t);
            for ov in &mut o.overrides {
                ov.curvature = ov.curvature.map(|k| k / s);
                ov.mass = ov.mass.map(|x| x * m);
            }
        }
        if let Some(h) = &mut w.heat {
            // The ambient temperature is a temperature: kept.
            h.conduction /= t;
            h.cooling /= t;
        }
        for o in &mut out.objects {
            if let Some(v) = &mut o.velocities {
                *v = self.velocities(v)?;
            }
            if let Some(skin) = &mut o.skin {
                *skin = self.skin(skin);
            }
        }
        for f in &mut out.forces {
            f.force = Self::scale3(f.force, self.force());
            f.start *= t;
            f.end *= t;
            f.ramp *= t;
        }
        for tool in &mut out.tools {
            *tool = self.tool(tool);
        }
        if let Some(c) = &mut out.creation {
            *c = self.creation(c);
        }
        Ok(out)
    }

    /// Initial velocities in the new units (a file's cannot be scaled here).
    fn velocities(&self, v: &Velocities) -> Result<Velocities, String> {
        match v {
            Velocities::File(path) => Err(format!(
                "velocities from {} cannot be scaled here",
                path.display()
            )),
            // `t` is an energy (k_B = 1).
            Velocities::Temperature { t, seed } => Ok(Velocities::Temperature {
                t: t * self.energy(),
                seed: *seed,
            }),
        }
    }

    /// A skin in the new units: lengths by `s`, the contact stiffness (a
    /// pressure per unit field excess: a sample's reaction is stiffness x
    /// excess x its area) by `m/(s t²)`.
    fn skin(&self, skin: &SkinSpec) -> SkinSpec {
        let s = self.length;
        let mut out = skin.clone();
        out.radius *= s;
        out.cell_size *= s;
        out.thickness = skin.thickness.map(|x| x * s);
        out.stiffness *= self.mass / (s * self.time * self.time);
        if let SkinPrimitive::Square { half_side } = &mut out.primitive {
            *half_side *= s;
        }
        out
    }

    /// A tool in the new units: its path (times by `t`, positions by `s`),
    /// its shape's lengths, and its role's stiffnesses (force per length,
    /// `m/t²`), dampings (`m/t`), lengths, release time and heating power
    /// (temperature per time, `1/t`).
    fn tool(&self, tool: &ToolSpec) -> ToolSpec {
        let (s, t) = (self.length, self.time);
        let mut out = tool.clone();
        for k in &mut out.path.keyframes {
            k.time *= t;
            k.position = Self::scale3(k.position, s);
        }
        out.shape = match &tool.shape {
            ToolShape::Plane { normal } => ToolShape::Plane { normal: *normal },
            ToolShape::Ball { radius } => ToolShape::Ball { radius: radius * s },
            ToolShape::Cuboid { half_extents } => ToolShape::Cuboid {
                half_extents: Self::scale3(*half_extents, s),
            },
            ToolShape::Cylinder {
                half_height,
                radius,
            } => ToolShape::Cylinder {
                half_height: half_height * s,
                radius: radius * s,
            },
            ToolShape::ConvexHull { points } => ToolShape::ConvexHull {
                points: points.iter().map(|p| Self::scale3(*p, s)).collect(),
            },
            ToolShape::TriMesh {
                vertices,
                triangles,
            } => ToolShape::TriMesh {
                vertices: vertices.iter().map(|p| Self::scale3(*p, s)).collect(),
                triangles: triangles.clone(),
            },
        };
        let (k, c) = (self.mass / (t * t), self.mass / t);
        out.role = match tool.role {
            Role::Obstacle {
                stiffness,
                margin,
                damping,
                friction,
            } => Role::Obstacle {
                stiffness: stiffness * k,
                margin: margin * s,
                damping: damping * c,
                // Dimensionless.
                friction,
            },
            Role::Attractor { strength, reach } => Role::Attractor {
                strength: strength * k,
                reach: reach * s,
            },
            Role::Mover {
                stiffness,
                damping,
                release,
            } => Role::Mover {
                stiffness: stiffness * k,
                damping: damping * c,
                release: release * t,
            },
            Role::Eraser => Role::Eraser,
            Role::Heater { power, reach } => Role::Heater {
                power: power / t,
                reach: reach * s,
            },
            Role::Knife {
                stiffness,
                margin,
                damping,
                power,
                reach,
            } => Role::Knife {
                stiffness: stiffness * k,
                margin: margin * s,
                damping: damping * c,
                power: power / t,
                reach: reach * s,
            },
            Role::Shaper {
                stiffness,
                margin,
                damping,
            } => Role::Shaper {
                stiffness: stiffness * k,
                margin: margin * s,
                damping: damping * c,
            },
        };
        out
    }

    /// Creation rules in the new units: the spacing by `s` and a fit's
    /// release time by `t`; every other length is a multiple of the rest
    /// spacing and the interval counts steps (whose length scales).
    fn creation(&self, c: &CreationSettings) -> CreationSettings {
        let mut out = c.clone();
        out.spacing = c.spacing.map(|x| x * self.length);
        if let Some(f) = &mut out.fit {
            f.release *= self.time;
        }
        out
    }

    /// Scales only the geometry by `s`: generator lengths and curvatures,
    /// and every length parameter of the materials (rest distances,
    /// cut-offs, weight widths, cohesion `α` by `1/s²`), but no force,
    /// energy, stiffness, mass, inertia or damping. The physics changes
    /// (see the module docs): this is the counter-example of the report.
    ///
    /// # Errors
    ///
    /// When an object reads a points file.
    pub fn geometry_only(scene: &Scene, s: Real) -> Result<Scene, String> {
        let g = Scaling::length(s);
        let mut out = scene.clone();
        for o in &mut out.objects {
            o.generator = g.generator(&o.generator)?;
            for ov in &mut o.overrides {
                ov.curvature = ov.curvature.map(|k| k / s);
            }
        }
        for mat in out.materials.values_mut() {
            if let Some(sp) = &mut mat.spacing {
                match sp {
                    Spacing::Cohesion(c) => {
                        c.r0 *= s;
                        c.alpha /= s * s;
                        c.cutoff = c.cutoff.map(|x| x * s);
                    }
                    Spacing::LennardJones(l) => {
                        l.r0 *= s;
                        l.cutoff *= s;
                    }
                }
            }
            mat.weight.a *= s;
            mat.weight.cutoff *= s;
            mat.repulsion.sigma *= s;
            mat.repulsion.lambda *= s;
            mat.repulsion.cutoff *= s;
        }
        Ok(out)
    }
}
