//! Tools (seed 000 §6): rigid parry shapes with scripted motion
//! that act on the particles near them — solid obstacles, attractors and
//! movers. Each acts through a potential energy of the particle position
//! ([`roles`]); the world adds the tool forces and energies in every force
//! evaluation, at the evaluation's time, so every integrator (including
//! the stages of Runge-Kutta schemes) sees the tool where it is.
//!
//! Erasers ([`Role::Eraser`]) exert no force: after each step the world
//! removes the particles inside them ([`Tools::erase`]). Shaping tools
//! ([`Role::Shaper`]) are obstacles that, two at a time, also delete the
//! particles trapped between them ([`Tools::trapped`]), after each step
//! as well; a world with fewer than two shaping tools does not look.
//!
//! Only worlds with tools pay for them: without tools the force pass has
//! no tool stage. Tools act at particle centres (forces, no torques).
//! Skinned objects meet tools through their skins instead (op-implicit);
//! [`ToolParams::objects`] restricts a tool to some objects.

pub mod path;
pub mod roles;
pub mod shape;

use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Vector;
use parry3d_f64::shape::{Shape, SharedShape};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use op_dynamics::checkpoint;
use op_dynamics::contributors::{Contribution, Contributor, ContributorInput};
use op_dynamics::error::ParamError;
use op_dynamics::integrators::StateRef;
use op_dynamics::math::{Point3, Real, Vec3};
use op_dynamics::particles::{Attributes, Particles};
use op_dynamics::tooling::ToolSet;

pub use path::{Keyframe, ToolPath, ToolPose};
pub use roles::Role;
pub use shape::{parry_pose, ToolShape};

/// A tool (seed 000 §6): a parry shape with scripted motion and a role.
/// In a scene file a tool names the objects it acts on, and its keyframe
/// times and a mover's `release` count from the end of the settle phase,
/// like force windows; a world's tools (`ToolParams<u32>`, the default)
/// hold object ids and world times instead. In a scene an obstacle acts on
/// the particles of the objects without a skin, and on the skins of
/// skinned objects (their skin samples inside the shape get a reaction
/// `stiffness x depth` along its normal, seed 002 §6); attractors and
/// movers act on particles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(rename = "ToolSpec")]
pub struct ToolParams<O = u32> {
    /// Name, for messages and outputs. Default: empty.
    #[serde(default)]
    pub name: String,
    /// Shape in the tool frame (`Plane`, `Ball`, `Cuboid`, `Cylinder`,
    /// `ConvexHull`, `TriMesh`).
    pub shape: ToolShape,
    /// Keyframes `(time, position, rotation)`, rotation as a rotation
    /// vector. Default: still at the origin.
    #[serde(default)]
    pub path: ToolPath,
    /// `Obstacle(stiffness, margin, damping, friction)`, `Attractor(strength, reach)`
    /// or `Mover(stiffness, damping, release)`.
    pub role: Role,
    /// The objects it acts on (ids in a world, names in a scene). Default
    /// (`None`): every object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objects: Option<Vec<O>>,
}

impl<O> ToolParams<O> {
    /// Checks the shape, the path and the role; errors name the field.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.shape.build().map_err(|e| e.within("shape"))?;
        self.validate_motion()
    }

    /// Checks the path and the role.
    fn validate_motion(&self) -> Result<(), ParamError> {
        self.path.validate().map_err(|e| e.within("path"))?;
        self.role.validate().map_err(|e| e.within("role"))
    }

    /// The same tool acting on the objects `objects` instead.
    pub fn acting_on<P>(&self, objects: Option<Vec<P>>) -> ToolParams<P> {
        ToolParams {
            name: self.name.clone(),
            shape: self.shape.clone(),
            path: self.path.clone(),
            role: self.role.clone(),
            objects,
        }
    }
}

/// A tool ready to act: its collider and, for a mover, the particles it
/// holds (stable id and position in the tool frame).
#[derive(Clone)]
pub struct Tool {
    params: ToolParams,
    shape: SharedShape,
    grabbed: Vec<(u32, Vec3)>,
}

impl std::fmt::Debug for Tool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tool")
            .field("params", &self.params)
            .field("grabbed", &self.grabbed.len())
            .finish()
    }
}

fn to_parry(p: &Vec3) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

fn from_parry(p: Vector) -> Vec3 {
    Vec3::new(p.x, p.y, p.z)
}

/// Signed distance from `p` to the surface of `shape` at `pose` (positive
/// outside) and the outward unit normal at the closest surface point;
/// `None` exactly on the surface, where the normal is not defined by the
/// projection (every role's force is zero or bounded there).
pub fn signed_distance(
    shape: &dyn Shape,
    pose: &parry3d_f64::math::Pose,
    p: &Vec3,
) -> Option<(Real, Vec3)> {
    let proj = shape.project_point(pose, to_parry(p), false);
    let d = p - from_parry(proj.point);
    let len = d.norm();
    if len == 0.0 || !len.is_finite() {
        return None;
    }
    if proj.is_inside {
        Some((-len, -d / len))
    } else {
        Some((len, d / len))
    }
}

impl Tool {
    /// Builds the tool; a mover grabs the particles inside it at time 0.
    pub fn new(params: &ToolParams, particles: &Particles) -> Result<Tool, ParamError> {
        params.validate_motion()?;
        let shape = params.shape.build().map_err(|e| e.within("shape"))?;
        let mut tool = Tool {
            params: params.clone(),
            shape,
            grabbed: Vec::new(),
        };
        if let Role::Mover { .. } = params.role {
            let pose = params.path.pose(0.0);
            for slot in tool.inside(0.0, particles) {
                let x = particles.positions()[slot].coords;
                let local = pose.rotation.inverse() * (x - pose.position);
                tool.grabbed.push((particles.ids()[slot], local));
            }
            tool.grabbed.sort_by_key(|g| g.0);
        }
        Ok(tool)
    }

    /// The description.
    pub fn params(&self) -> &ToolParams {
        &self.params
    }

    /// The collider in the tool frame.
    pub fn shape(&self) -> &dyn Shape {
        self.shape.as_ref()
    }

    /// Pose and velocity at time `t`.
    pub fn pose(&self, t: Real) -> ToolPose {
        self.params.path.pose(t)
    }

    /// A triangle mesh of the tool's surface at time `t`, for output:
    /// vertices (world frame) and triangles counter-clockwise seen from
    /// outside. Balls and cylinders are tessellated (24 x 12 and 32
    /// segments); a plane is drawn as a square of half side `plane_extent`
    /// about the tool origin.
    pub fn surface_mesh(&self, t: Real, plane_extent: Real) -> (Vec<Point3>, Vec<[u32; 3]>) {
        let s = self.shape.as_ref();
        let (local, triangles, convex): (Vec<Vec3>, Vec<[u32; 3]>, bool) =
            if let ToolShape::Plane { normal } = &self.params.shape {
                let n = Vec3::from(*normal).normalize();
                let u = op_dynamics::math::tangent_axis(&n) * plane_extent;
                let v = n.cross(&u);
                let corners = vec![-u - v, u - v, u + v, -u + v];
                (corners, vec![[0, 1, 2], [0, 2, 3]], false)
            } else {
                let (v, t, convex) = if let Some(b) = s.as_ball() {
                    let (v, t) = b.to_trimesh(24, 12);
                    (v, t, true)
                } else if let Some(c) = s.as_cuboid() {
                    let (v, t) = c.to_trimesh();
                    (v, t, true)
                } else if let Some(c) = s.as_cylinder() {
                    let (v, t) = c.to_trimesh(32);
                    (v, t, true)
                } else if let Some(c) = s.as_convex_polyhedron() {
                    let (v, t) = c.to_trimesh();
                    (v, t, true)
                } else if let Some(m) = s.as_trimesh() {
                    (m.vertices().to_vec(), m.indices().to_vec(), false)
                } else {
                    (Vec::new(), Vec::new(), false)
                };
                (v.into_iter().map(from_parry).collect(), t, convex)
            };
        let mut triangles = triangles;
        if convex {
            // Orient every face away from the centre of the convex shape.
            let centre = local.iter().sum::<Vec3>() / local.len().max(1) as Real;
            for tri in &mut triangles {
                let [a, b, c] = tri.map(|k| local[k as usize]);
                if (b - a).cross(&(c - a)).dot(&(a - centre)) < 0.0 {
                    tri.swap(1, 2);
                }
            }
        }
        let pose = self.pose(t);
        let world = local
            .iter()
            .map(|x| Point3::from(pose.position + pose.rotation * x))
            .collect();
        (world, triangles)
    }

    /// Stable ids of the particles a mover holds (empty for other roles).
    pub fn grabbed(&self) -> impl Iterator<Item = u32> + '_ {
        self.grabbed.iter().map(|g| g.0)
    }

    /// Whether the tool acts on particles of object `object`.
    pub fn acts_on(&self, object: u32) -> bool {
        self.params
            .objects
            .as_ref()
            .is_none_or(|list| list.contains(&object))
    }

    /// The tool's bounding box at `frame` grown by `reach`, or `None` for
    /// an unbounded shape (a plane): particles outside it are out of the
    /// tool's reach and skipped before the exact distance query.
    fn reach_box(&self, frame: &parry3d_f64::math::Pose, reach: Real) -> Option<Aabb> {
        (!self.params.shape.is_unbounded()).then(|| self.shape.compute_aabb(frame).loosened(reach))
    }

    /// Stable ids, in increasing order, of the particles (of the objects
    /// the tool acts on) strictly inside the tool's shape at time `t`; empty
    /// unless the tool is an eraser.
    pub fn erased(&self, t: Real, particles: &Particles) -> Vec<u32> {
        if self.params.role != Role::Eraser {
            return Vec::new();
        }
        let mut ids: Vec<u32> = self
            .inside(t, particles)
            .into_iter()
            .map(|slot| particles.ids()[slot])
            .collect();
        ids.sort_unstable();
        ids
    }

    /// Slots, in increasing order, of the particles (of the objects the
    /// tool acts on) strictly inside the tool's shape at time `t`, whatever
    /// its role: the particles a mover grabs at time 0 and an eraser
    /// removes.
    pub fn inside(&self, t: Real, particles: &Particles) -> Vec<usize> {
        let pose = self.pose(t);
        let frame = parry_pose(&pose.position, &pose.rotation);
        let objects = particles.objects();
        particles
            .positions()
            .iter()
            .enumerate()
            .filter(|&(slot, x)| {
                self.acts_on(objects[slot])
                    && self.shape.contains_point(&frame, to_parry(&x.coords))
            })
            .map(|(slot, _)| slot)
            .collect()
    }

    /// Adds `dt` times the heating rate this tool gives each particle at
    /// time `t` ([`op_dynamics::heat::heating_rate`] of its signed distance) to
    /// its temperature (by slot). Nothing unless the tool is a heater or a
    /// knife; particles of objects it does not act on are not heated.
    pub fn add_heat(
        &self,
        t: Real,
        dt: Real,
        positions: &[Point3],
        objects: &[u32],
        temperatures: &mut [Real],
    ) {
        let Some((power, reach)) = self.params.role.heating() else {
            return;
        };
        let pose = self.pose(t);
        let frame = parry_pose(&pose.position, &pose.rotation);
        let bound = self.reach_box(&frame, reach);
        let shape = self.shape.as_ref();
        temperatures
            .par_iter_mut()
            .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
            .enumerate()
            .for_each(|(i, temp)| {
                let x = positions[i].coords;
                if !self.acts_on(objects[i])
                    || bound.is_some_and(|b| !b.contains_local_point(to_parry(&x)))
                {
                    return;
                }
                // No signed distance exactly on the surface or where the
                // projection degenerates inside (a ball's centre): both get
                // the full power.
                let rate = signed_distance(shape, &frame, &x).map_or(power, |(sd, _)| {
                    op_dynamics::heat::heating_rate(power, reach, sd)
                });
                *temp += dt * rate;
            });
    }

    /// Adds this tool's forces to `forces` and energies to `energies` (by
    /// slot) for the state `s` at time `t`.
    fn add(
        &self,
        t: Real,
        s: StateRef<'_>,
        a: &Attributes<'_>,
        forces: &mut [Vec3],
        energies: &mut [Real],
    ) {
        let pose = self.pose(t);
        match self.params.role {
            Role::Mover {
                stiffness,
                damping,
                release,
            } => {
                if t >= release {
                    return;
                }
                // Few particles, each by id: serial, in id order. Removed
                // particles (World::remove_particles) are skipped.
                for &(id, local) in &self.grabbed {
                    let Some(&slot) = a.slot_of.get(id as usize) else {
                        continue;
                    };
                    if slot == Particles::REMOVED {
                        continue;
                    }
                    let i = slot as usize;
                    let target = pose.position + pose.rotation * local;
                    let stretch = s.positions[i].coords - target;
                    energies[i] += 0.5 * stiffness * stretch.norm_squared();
                    let relative = s.velocities[i] - pose.velocity_at(&target);
                    forces[i] -= stiffness * stretch + damping * relative;
                }
            }
            Role::Eraser | Role::Heater { .. } => {}
            Role::Obstacle { .. }
            | Role::Attractor { .. }
            | Role::Knife { .. }
            | Role::Shaper { .. } => {
                let frame = parry_pose(&pose.position, &pose.rotation);
                let reach = self.params.role.reach();
                let bound = self.reach_box(&frame, reach);
                let role = &self.params.role;
                let shape = self.shape.as_ref();
                forces
                    .par_iter_mut()
                    .zip(energies.par_iter_mut())
                    .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
                    .enumerate()
                    .for_each(|(i, (f, e))| {
                        if !self.acts_on(a.objects[i]) {
                            return;
                        }
                        let x = s.positions[i].coords;
                        if bound.is_some_and(|b| !b.contains_local_point(to_parry(&x))) {
                            return;
                        }
                        let Some((sd, n)) = signed_distance(shape, &frame, &x) else {
                            return;
                        };
                        let (energy, push) = match *role {
                            Role::Obstacle {
                                stiffness,
                                margin,
                                damping,
                                ..
                            }
                            | Role::Knife {
                                stiffness,
                                margin,
                                damping,
                                ..
                            }
                            | Role::Shaper {
                                stiffness,
                                margin,
                                damping,
                            } => {
                                let (energy, push) = roles::obstacle(stiffness, margin, sd);
                                if push == 0.0 {
                                    return;
                                }
                                // Damping may slow a separation but never
                                // pulls: contact only pushes.
                                let closing = (s.velocities[i] - pose.velocity_at(&x)).dot(&n);
                                (energy, (push - damping * closing).max(0.0))
                            }
                            Role::Attractor { strength, reach } => {
                                roles::attractor(strength, reach, sd)
                            }
                            Role::Mover { .. } | Role::Eraser | Role::Heater { .. } => return,
                        };
                        *e += energy;
                        *f += push * n;
                    });
            }
        }
    }
}

/// The tools of a world.
#[derive(Clone, Debug, Default)]
pub struct Tools {
    tools: Vec<Tool>,
}

impl Tools {
    /// Builds every tool (errors name the tool's index).
    pub fn new(params: &[ToolParams], particles: &Particles) -> Result<Tools, ParamError> {
        let tools = params
            .iter()
            .enumerate()
            .map(|(k, p)| Tool::new(p, particles).map_err(|e| e.within(&format!("tools[{k}]"))))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Tools { tools })
    }

    /// The tools, in the order given.
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }

    /// Whether there is no tool.
    pub fn is_empty(&self) -> bool {
        self.tools.is_empty()
    }

    /// Whether some tool is an eraser.
    pub fn has_eraser(&self) -> bool {
        self.tools.iter().any(|t| t.params.role == Role::Eraser)
    }

    /// The shaping tools ([`Role::Shaper`]), in order.
    fn shapers(&self) -> impl Iterator<Item = &Tool> + '_ {
        self.tools
            .iter()
            .filter(|t| matches!(t.params.role, Role::Shaper { .. }))
    }

    /// Whether the tools can delete particles: some eraser, or at least
    /// two shaping tools (the world asks [`Tools::erase`] after each step
    /// only then).
    pub fn removes_particles(&self) -> bool {
        self.has_eraser() || self.shapers().nth(1).is_some()
    }

    /// Stable ids, in increasing order, of the particles trapped between
    /// shaping tools at time `t` (the trap rule of [`Role::Shaper`]): those
    /// (of the objects the tools act on) within the margin of at least two
    /// shaping tools at once. Empty with fewer than two shaping tools.
    /// Particles are tested in parallel and collected in slot order: the
    /// result depends only on the positions, not on the thread count.
    pub fn trapped(&self, t: Real, particles: &Particles) -> Vec<u32> {
        let shapers: Vec<_> = self
            .shapers()
            .map(|tool| {
                let pose = tool.pose(t);
                let frame = parry_pose(&pose.position, &pose.rotation);
                let margin = tool.params.role.reach();
                let bound = tool.reach_box(&frame, margin);
                (tool, frame, margin, bound)
            })
            .collect();
        if shapers.len() < 2 {
            return Vec::new();
        }
        let objects = particles.objects();
        let ids = particles.ids();
        let mut trapped: Vec<u32> = particles
            .positions()
            .par_iter()
            .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
            .enumerate()
            .filter_map(|(slot, x)| {
                let x = x.coords;
                let pressing = shapers
                    .iter()
                    .filter(|(tool, frame, margin, bound)| {
                        tool.acts_on(objects[slot])
                            && bound.is_none_or(|b| b.contains_local_point(to_parry(&x)))
                            // Exactly on the surface (no normal): s = 0 < margin.
                            && signed_distance(tool.shape(), frame, &x)
                                .is_none_or(|(s, _)| s < *margin)
                    })
                    .take(2)
                    .count();
                (pressing >= 2).then_some(ids[slot])
            })
            .collect();
        trapped.sort_unstable();
        trapped
    }

    /// Ids, in increasing order and without repeats, of the particles
    /// inside any eraser at time `t` (see [`Role::Eraser`]) or trapped
    /// between shaping tools ([`Tools::trapped`]); movers forget the ones
    /// they held. The caller removes them from the world. The result
    /// depends only on the positions, not on the thread count.
    pub fn erase(&mut self, t: Real, particles: &Particles) -> Vec<u32> {
        let mut ids: Vec<u32> = self
            .tools
            .iter()
            .flat_map(|tool| tool.erased(t, particles))
            .chain(self.trapped(t, particles))
            .collect();
        ids.sort_unstable();
        ids.dedup();
        if !ids.is_empty() {
            for tool in &mut self.tools {
                tool.grabbed.retain(|g| ids.binary_search(&g.0).is_err());
            }
        }
        ids
    }

    /// Adds every tool's forces and energies (by slot) at state `s`, time
    /// `t`, tool after tool (the same bits at any thread count: each
    /// particle's sum is formed in tool order).
    fn add_forces(
        &self,
        t: Real,
        s: StateRef<'_>,
        a: &Attributes<'_>,
        forces: &mut [Vec3],
        energies: &mut [Real],
    ) {
        for tool in &self.tools {
            tool.add(t, s, a, forces, energies);
        }
    }
}

impl Contributor for Tools {
    fn name(&self) -> &str {
        "tools"
    }

    fn is_active(&self) -> bool {
        !self.tools.is_empty()
    }

    /// Every tool's forces and energies, tool after tool.
    fn contribute(&self, input: &ContributorInput<'_>, out: &mut Contribution<'_>) {
        self.add_forces(
            input.t,
            input.state,
            input.attributes,
            out.forces,
            out.energies,
        );
    }
}

impl ToolSet for Tools {
    fn heats(&self) -> bool {
        self.tools.iter().any(|t| t.params.role.heating().is_some())
    }

    /// Every heating tool's heat, tool after tool ([`Tool::add_heat`]).
    fn add_heat(
        &self,
        t: Real,
        dt: Real,
        positions: &[Point3],
        objects: &[u32],
        temperatures: &mut [Real],
    ) {
        for tool in &self.tools {
            tool.add_heat(t, dt, positions, objects, temperatures);
        }
    }

    fn removes_particles(&self) -> bool {
        Tools::removes_particles(self)
    }

    fn erase(&mut self, t: Real, particles: &Particles) -> Vec<u32> {
        Tools::erase(self, t, particles)
    }

    fn roles(&self) -> Vec<&'static str> {
        self.tools.iter().map(|t| t.params.role.name()).collect()
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    /// The particles each grabbing tool holds, with their offsets in the
    /// tool's frame: the only part of a tool that changes during a run
    /// (erasers drop the particles they remove).
    fn save_state(&self) -> Vec<u8> {
        let grabbed: Vec<&[(u32, Vec3)]> = self.tools.iter().map(|t| &t.grabbed[..]).collect();
        checkpoint::encode(&grabbed)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), checkpoint::StateError> {
        let grabbed: Vec<Vec<(u32, Vec3)>> = checkpoint::decode(state)?;
        if grabbed.len() != self.tools.len() {
            return Err(checkpoint::StateError(format!(
                "the checkpoint has {} tools, the world {}",
                grabbed.len(),
                self.tools.len()
            )));
        }
        for (tool, g) in self.tools.iter_mut().zip(grabbed) {
            tool.grabbed = g;
        }
        Ok(())
    }
}

impl Tools {
    /// The tools of `world`, when they are a [`Tools`]
    /// ([`op_dynamics::World::set_tools`]).
    pub fn of(world: &op_dynamics::World) -> Option<&Tools> {
        world.tools()?.as_any().downcast_ref::<Tools>()
    }

    /// A world of `particles` and `materials` with `params`
    /// ([`op_dynamics::World::new`]) and the tools of `tools`
    /// ([`Tools::equip`]).
    pub fn world(
        particles: op_dynamics::Particles,
        materials: &[op_dynamics::Material],
        params: op_dynamics::WorldParams,
        tools: &[ToolParams],
    ) -> Result<op_dynamics::World, ToolError> {
        let mut world = op_dynamics::World::new(particles, materials, params)?;
        Tools::equip(&mut world, tools)?;
        Ok(world)
    }

    /// Builds the tools of `params` for `world`'s particles (movers grab
    /// the particles they start on) and gives them to it. Without tools the
    /// world is left as it is (it pays for no tool stage).
    pub fn equip(world: &mut op_dynamics::World, params: &[ToolParams]) -> Result<(), ToolError> {
        if params.is_empty() {
            return Ok(());
        }
        if world.params().heat.is_none() {
            if let Some(k) = params.iter().position(|t| t.role.heating().is_some()) {
                return Err(ParamError::Invalid {
                    field: format!("tools[{k}].role"),
                    message: "a heater or knife needs the world's heat settings \
                              (heat: conduction, cooling, ambient)"
                        .into(),
                }
                .into());
            }
        }
        let tools = Tools::new(params, world.particles())?;
        world.set_tools(Box::new(tools))?;
        Ok(())
    }
}

/// Why tools could not be given to a world.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ToolError {
    /// A tool's description is invalid.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The world refused them (a heating tool in a world without heat).
    #[error(transparent)]
    World(#[from] op_dynamics::WorldError),
}

#[cfg(test)]
mod tests;
