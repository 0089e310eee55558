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

use crate::contributors::{Contribution, Contributor, ContributorInput};
use crate::error::ParamError;
use crate::integrators::StateRef;
use crate::math::{Point3, Real, Vec3};
use crate::particles::{Attributes, Particles};

pub use path::{Keyframe, Path, ToolPose};
pub use roles::Role;
pub use shape::{parry_pose, ToolShape};

/// A tool's description.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ToolParams {
    /// Name (for messages and outputs). Default: empty.
    #[serde(default)]
    pub name: String,
    /// Shape in the tool frame.
    pub shape: ToolShape,
    /// Motion of the tool frame. Default: still at the origin.
    #[serde(default)]
    pub path: Path,
    /// What the tool does.
    pub role: Role,
    /// Object ids the tool acts on. Default (`None`): every object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objects: Option<Vec<u32>>,
}

impl ToolParams {
    /// Checks the path and role (the shape is checked when built).
    pub fn validate(&self) -> Result<(), ParamError> {
        self.path.validate().map_err(|e| e.within("path"))?;
        self.role.validate().map_err(|e| e.within("role"))
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
        params.validate()?;
        let shape = params.shape.build().map_err(|e| e.within("shape"))?;
        let mut tool = Tool {
            params: params.clone(),
            shape,
            grabbed: Vec::new(),
        };
        if let Role::Mover { .. } = params.role {
            let pose = params.path.pose(0.0);
            let frame = parry_pose(&pose.position, &pose.rotation);
            let objects = particles.objects();
            for (slot, x) in particles.positions().iter().enumerate() {
                if !tool.acts_on(objects[slot]) {
                    continue;
                }
                if tool.shape.contains_point(&frame, to_parry(&x.coords)) {
                    let local = pose.rotation.inverse() * (x.coords - pose.position);
                    tool.grabbed.push((particles.ids()[slot], local));
                }
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
                let u = crate::math::tangent_axis(&n) * plane_extent;
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
        let pose = self.pose(t);
        let frame = parry_pose(&pose.position, &pose.rotation);
        let objects = particles.objects();
        let mut ids: Vec<u32> = particles
            .positions()
            .iter()
            .enumerate()
            .filter(|&(slot, x)| {
                self.acts_on(objects[slot])
                    && self.shape.contains_point(&frame, to_parry(&x.coords))
            })
            .map(|(slot, _)| particles.ids()[slot])
            .collect();
        ids.sort_unstable();
        ids
    }

    /// Adds `dt` times the heating rate this tool gives each particle at
    /// time `t` ([`crate::heat::heating_rate`] of its signed distance) to
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
                let rate = signed_distance(shape, &frame, &x)
                    .map_or(power, |(sd, _)| crate::heat::heating_rate(power, reach, sd));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::ParticleDesc;

    /// An eraser ball sweeping along a row of still particles removes each
    /// one when its centre is inside, exactly those, in any thread count;
    /// a mover forgets the particles erased from its grip; survivors keep
    /// their ids.
    #[test]
    fn eraser_removes_the_particles_it_passes_over() {
        use crate::{Material, World, WorldParams};
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let mut p = Particles::new();
                    for k in 0..10 {
                        p.push(ParticleDesc::at(Point3::new(k as Real, 0.0, 0.0)))
                            .unwrap();
                    }
                    // Sweeps x from -1 to 4.5 over t in [0, 1]; radius 0.6
                    // reaches x <= 5.1 at the end: particles 0..=5.
                    let eraser = ToolParams {
                        name: "eraser".into(),
                        shape: ToolShape::Ball { radius: 0.6 },
                        path: Path {
                            keyframes: vec![
                                Keyframe {
                                    time: 0.0,
                                    position: [-1.0, 0.0, 0.0],
                                    rotation: [0.0; 3],
                                },
                                Keyframe {
                                    time: 1.0,
                                    position: [4.5, 0.0, 0.0],
                                    rotation: [0.0; 3],
                                },
                            ],
                        },
                        role: Role::Eraser,
                        objects: None,
                    };
                    // Holds particles 1 and 8 in place.
                    let holder = |x: Real| ToolParams {
                        name: "holder".into(),
                        shape: ToolShape::Ball { radius: 0.1 },
                        path: Path::fixed([x, 0.0, 0.0]),
                        role: Role::Mover {
                            stiffness: 10.0,
                            damping: 0.0,
                            release: Real::INFINITY,
                        },
                        objects: None,
                    };
                    let params = WorldParams {
                        dt: 0.01,
                        tools: vec![eraser, holder(1.0), holder(8.0)],
                        ..WorldParams::default()
                    };
                    let mut w = World::new(p, &[Material::empty()], params).unwrap();
                    assert!(w.enabled().contains(&"tool:eraser".to_string()));
                    let mut erased = Vec::new();
                    let mut count_when_first_erased = None;
                    while w.time() < 1.5 {
                        let now = w.step().unwrap().erased.clone();
                        if !now.is_empty() && count_when_first_erased.is_none() {
                            count_when_first_erased = Some(w.time());
                        }
                        erased.extend(now);
                    }
                    let grabbed: Vec<Vec<u32>> =
                        w.tools().iter().map(|t| t.grabbed().collect()).collect();
                    (
                        erased,
                        w.particles().ids().to_vec(),
                        grabbed,
                        count_when_first_erased,
                    )
                })
        };
        let (erased, mut ids, grabbed, first) = run(1);
        assert_eq!(erased, vec![0, 1, 2, 3, 4, 5]);
        ids.sort_unstable();
        assert_eq!(ids, vec![6, 7, 8, 9]);
        // The ball's surface reaches x = 0 at t = 0.4/5.5.
        let first = first.expect("something was erased");
        assert!((first - 0.4 / 5.5).abs() <= 0.011, "{first}");
        assert_eq!(grabbed, vec![vec![], vec![], vec![8]]);
        assert_eq!(run(2), run(1));
    }

    /// Two shaping balls closing along z on a row of still particles along
    /// z (fixed: only the trap rule acts) delete exactly the particles
    /// within both margins: those in the gap between them once it is
    /// narrower than two margins, none while the gap is wider, none near
    /// one ball only; the same ids at 1 and 2 threads. A single shaping
    /// tool deletes nothing (a world with one does not even look).
    #[test]
    fn shapers_delete_the_particles_trapped_between_them() {
        use crate::{Flags, Material, World, WorldParams};
        let shaper = |from: Real, to: Real| ToolParams {
            name: "shaper".into(),
            shape: ToolShape::Ball { radius: 1.0 },
            path: Path {
                keyframes: vec![
                    Keyframe {
                        time: 0.0,
                        position: [0.0, 0.0, from],
                        rotation: [0.0; 3],
                    },
                    Keyframe {
                        time: 1.0,
                        position: [0.0, 0.0, to],
                        rotation: [0.0; 3],
                    },
                ],
            },
            role: Role::Shaper {
                stiffness: 10.0,
                margin: 0.3,
                damping: 0.0,
            },
            objects: None,
        };
        // Particles at z = -2.0, -1.9, ..., 2.0 (ids 0..=40), held fixed.
        let row = || {
            let mut p = Particles::new();
            for k in 0..=40 {
                let mut d = ParticleDesc::at(Point3::new(0.0, 0.0, -2.0 + 0.1 * k as Real));
                d.flags = Flags::FIXED_POSITION | Flags::FIXED_ORIENTATION;
                p.push(d).unwrap();
            }
            p
        };
        let run = |threads: usize, tools: Vec<ToolParams>| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let params = WorldParams {
                        dt: 0.01,
                        tools,
                        ..WorldParams::default()
                    };
                    let mut w = World::new(row(), &[Material::empty()], params).unwrap();
                    let mut erased = Vec::new();
                    let mut first = None;
                    while w.time() < 1.0 - 1e-9 {
                        let now = w.step().unwrap().erased.clone();
                        if !now.is_empty() && first.is_none() {
                            first = Some(w.time());
                        }
                        erased.extend(now);
                    }
                    (erased, first, w.tools().len())
                })
        };
        // Ball surfaces at z = ±(2.5 - 1.0 - 1.25 t): the gap 2 (1.5 - 1.25
        // t) falls below two margins (0.6) at t = 0.96; at t = 1 the gap is
        // (-0.25, 0.25) and the particles within 0.3 of both surfaces are
        // those with |z| < 0.05.
        let closing = vec![shaper(2.5, 1.25), shaper(-2.5, -1.25)];
        let (erased, first, _) = run(1, closing.clone());
        assert_eq!(erased, vec![20], "only z = 0 lies within both margins");
        let first = first.expect("something was trapped");
        assert!(first >= 0.96 - 1e-9, "trapped too early: t = {first}");
        assert_eq!(
            run(2, closing),
            run(1, vec![shaper(2.5, 1.25), shaper(-2.5, -1.25)])
        );
        // Overlapping: the surfaces reach z = ∓0.25 at t = 1 (inside a
        // ball counts as within its margin), so every particle with
        // |z| < 0.55 is within 0.3 of both, and is deleted on the way.
        let (mut wide, _, _) = run(1, vec![shaper(2.5, 0.75), shaper(-2.5, -0.75)]);
        wide.sort_unstable();
        assert_eq!(wide, (15..=25).collect::<Vec<u32>>());
        // One shaper alone, pushed through the whole row, deletes nothing.
        let (alone, _, _) = run(1, vec![shaper(2.5, -2.5)]);
        assert!(alone.is_empty(), "{alone:?}");
        let one = Tools::new(&[shaper(2.5, -2.5)], &row()).unwrap();
        assert!(!one.removes_particles());
        assert!(Tools::new(&[shaper(2.5, 1.0), shaper(-2.5, -1.0)], &row())
            .unwrap()
            .removes_particles());
    }

    /// Every shape's output mesh is closed where the shape is, outward
    /// oriented (positive signed volume close to the shape's), and posed.
    #[test]
    fn surface_meshes_are_outward_and_posed() {
        let particles = {
            let mut p = Particles::new();
            p.push(ParticleDesc::at(Point3::new(9.0, 9.0, 9.0)))
                .unwrap();
            p
        };
        let shapes = [
            (
                ToolShape::Ball { radius: 1.0 },
                4.0 / 3.0 * std::f64::consts::PI,
            ),
            (
                ToolShape::Cuboid {
                    half_extents: [1.0, 2.0, 0.5],
                },
                8.0,
            ),
            (
                ToolShape::Cylinder {
                    half_height: 1.0,
                    radius: 0.5,
                },
                std::f64::consts::PI * 0.25 * 2.0,
            ),
        ];
        for (shape, volume) in shapes {
            let tool = Tool::new(
                &ToolParams {
                    name: String::new(),
                    shape: shape.clone(),
                    path: Path::fixed([1.0, 2.0, 3.0]),
                    role: Role::Obstacle {
                        stiffness: 1.0,
                        margin: 0.0,
                        damping: 0.0,
                    },
                    objects: None,
                },
                &particles,
            )
            .unwrap();
            let (v, t) = tool.surface_mesh(0.0, 1.0);
            let centre = Vec3::new(1.0, 2.0, 3.0);
            let signed: Real = t
                .iter()
                .map(|tri| {
                    let [a, b, c] = tri.map(|k| v[k as usize].coords - centre);
                    a.dot(&b.cross(&c)) / 6.0
                })
                .sum();
            assert!(
                signed > 0.0 && (signed - volume).abs() < 0.1 * volume,
                "{shape:?}: {signed} vs {volume}"
            );
        }
    }
}
