//! Validation that a scene asks for a finite run of bounded work (see
//! [`super::limits`]): steps, frames, heat sub-steps, created particles,
//! skin grids, and every length relative to the scene's length scale.

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use op_dynamics::Real;

use super::footprint::{near_pairs, Footprint, Footprints};
use super::limits::{
    MAX_CONDUCTION_STEP, MAX_EXTENT_OVER_SPACING, MAX_ROTATION, MAX_SKIN_NODES_PER_AXIS,
};
use super::validate::object_path;
use super::{ObjectSpec, Scene, ToolSpec};
use crate::error::{short, SceneError};
use crate::generators::Generator;
use crate::skins::SkinSpec;

/// Smallest stretching `d_min` and growing `radius` of the creation rules,
/// in rest spacings: closer candidates would overlap their neighbours, and
/// the rules' search grids grow as their inverse cube.
pub const MIN_CREATION_DISTANCE: Real = 0.5;

impl Scene {
    /// The scene's length scale: the largest generator spacing or material
    /// rest distance (1 when there is none).
    pub(crate) fn length_scale(&self) -> Real {
        let generators = self
            .objects
            .iter()
            .filter_map(|o| o.generator.nominal_spacing());
        let materials = self.materials.values().filter_map(|m| match &m.spacing {
            Some(op_dynamics::interactions::Spacing::Cohesion(c)) => Some(c.r0),
            Some(op_dynamics::interactions::Spacing::LennardJones(l)) => Some(l.r0),
            None => None,
        });
        let l = generators
            .chain(materials)
            .filter(|r| r.is_finite() && *r > 0.0)
            .fold(0.0, Real::max);
        if l > 0.0 {
            l
        } else {
            1.0
        }
    }

    /// The most steps a run of `particles` particles may take within the
    /// work limits (`max_steps`, and `max_particle_steps / particles`):
    /// the world's step budget ([`op_dynamics::World::set_step_budget`]),
    /// which stops an adaptive run whose step collapses toward `dt_min`
    /// as diverged instead of letting it run past its work. Unbounded
    /// without work limits.
    pub(crate) fn step_budget(&self, particles: usize) -> u64 {
        let lim = &self.limits;
        let steps = lim
            .max_steps
            .min(lim.max_particle_steps / particles.max(1) as Real);
        if steps.is_finite() {
            steps as u64
        } else {
            u64::MAX
        }
    }

    /// `" (set by --frames N)"` when the runner's frame count set
    /// `world.duration` ([`Scene::set_frames`]), else nothing: what the
    /// errors of a run too long add to the duration they name.
    pub(crate) fn set_by_frames(&self) -> String {
        self.frames_override
            .map_or(String::new(), |n| format!(" (set by --frames {n})"))
    }

    /// The particles each object's generator makes, in order: its
    /// generator checked and counted (points files read), the rest of the
    /// scene not validated; what a caller that has validated the scene
    /// needs of it without a second validation.
    ///
    /// # Errors
    ///
    /// A generator's errors ([`Generator::count`]).
    pub fn particle_counts(&self, base_dir: Option<&Path>) -> Result<Vec<usize>, SceneError> {
        let file = self.origin();
        self.objects
            .iter()
            .enumerate()
            .map(|(k, o)| {
                let path = format!("{}.generator", object_path(k, &o.name));
                o.generator.count(base_dir, file, &path)
            })
            .collect()
    }

    /// The most particles the creation rules may add to a scene of
    /// `particles`: up to `creation.max_particles` in all when a rule
    /// creates (stretching or growing; merging only removes), else none.
    pub(crate) fn creation_headroom(&self, particles: Real) -> Real {
        self.creation
            .as_ref()
            .filter(|c| c.stretching.is_some() || c.growing.is_some())
            .map_or(0.0, |c| (c.max_particles as Real - particles).max(0.0))
    }

    /// Checks the run's size against [`Scene::limits`] and the lengths
    /// against the scene's length scale; `total` is the particle count.
    /// Returns the work estimate checked.
    pub(crate) fn validate_work(
        &self,
        total: usize,
        base_dir: Option<&Path>,
    ) -> Result<WorkEstimate, SceneError> {
        let file = self.origin();
        let w = &self.world;
        let lim = &self.limits;
        let flag = "(opsim --no-work-limits lifts this limit)";
        let interval = 1.0 / w.frame_rate;
        if w.dt > interval * (1.0 + 1e-9) {
            return Err(SceneError::value(
                file,
                "world.dt",
                short(w.dt),
                &format!(
                    "must be at most the frame interval 1 / world.frame_rate = {} (a step \
                     longer than a frame would be cut short, not taken)",
                    short(interval)
                ),
            ));
        }
        let frames = w.duration * w.frame_rate + 1.0;
        if frames < 1.5 {
            return Err(SceneError::value(
                file,
                "world.frame_rate",
                short(w.frame_rate),
                &format!(
                    "with world.duration = {} gives no frame after frame 0: frame_rate must be at \
                     least 1 / duration = {}",
                    short(w.duration),
                    short(1.0 / w.duration)
                ),
            ));
        }
        if frames > lim.max_frames {
            return Err(SceneError::value(
                file,
                "world.frame_rate",
                short(w.frame_rate),
                &format!(
                    "with world.duration = {}{} gives {} frames, more than the limit of {} {flag}",
                    short(w.duration),
                    self.set_by_frames(),
                    short(frames.round()),
                    short(lim.max_frames)
                ),
            ));
        }
        let estimate = self.validate_run_size(total, base_dir)?;
        self.validate_heat_and_creation()?;
        self.validate_lengths(base_dir)?;
        Ok(estimate)
    }

    /// What the run is estimated to cost ([`WorkEstimate`]): its steps and
    /// frames, its particles, the interacting pairs its objects hold
    /// (within each object at its material's range, between objects whose
    /// regions overlap at the scene's largest range:
    /// `schema::footprint`), its skins' field evaluations and its
    /// triangulations' pairs. Points files are read.
    ///
    /// # Errors
    ///
    /// A points file that cannot be read.
    pub fn work_estimate(&self, base_dir: Option<&Path>) -> Result<WorkEstimate, SceneError> {
        let file = self.origin();
        let w = &self.world;
        let generators = self.objects.iter().enumerate().map(|(k, o)| {
            let path = format!("{}.generator", object_path(k, &o.name));
            (&o.generator, path)
        });
        let footprints = Footprints::of(generators, base_dir, file)?;
        // Each material's cut-off and bond radius (0 without bonds),
        // prepared once each: the neighbour pairs within the cut-off and
        // the bonds within the bond radius are evaluated every step, each
        // its own list (a bonded pair interacts completely, however far).
        let material_ranges: HashMap<&str, (Real, Real)> = self
            .materials
            .iter()
            .map(|(name, m)| {
                let ranges = m.prepare().ok().map_or((0.0, 0.0), |m| {
                    (m.cutoff(), m.bonds().map_or(0.0, |b| b.radius))
                });
                (name.as_str(), ranges)
            })
            .collect();
        let ranges: Vec<(Real, Real)> = self
            .objects
            .iter()
            .map(|o| {
                material_ranges
                    .get(o.material.as_str())
                    .copied()
                    .unwrap_or((0.0, 0.0))
            })
            .collect();
        // Bonds join particles of one object, but the search that finds
        // them when the world is built sees every object's particles
        // within the bond radius: objects meet within the largest range.
        let largest = ranges.iter().map(|r| r.0.max(r.1)).fold(0.0, Real::max);
        let mut per_object: Vec<Real> = ranges
            .iter()
            .enumerate()
            .map(|(k, &(cutoff, bond_radius))| {
                let bonds = if bond_radius > 0.0 {
                    footprints.pairs_within(k, bond_radius)
                } else {
                    0.0
                };
                footprints.own_pairs(k, cutoff) + bonds
            })
            .collect();
        // Pairs between objects whose boxes come within the largest range,
        // each half to either side. Each object's neighbours at that range
        // are counted once per footprint (a cloud's from its sample); the
        // objects that overlap are found by a sweep, whose cost grows with
        // the pairs of objects it finds: skipped without a pair limit.
        if self.limits.max_pairs.is_finite() || self.limits.max_pair_steps.is_finite() {
            for (a, b) in footprints.near_pairs(largest) {
                let shared = footprints.pairs_between(a, b, largest);
                per_object[a] += 0.5 * shared;
                per_object[b] += 0.5 * shared;
            }
        }
        let (densest, pairs) = per_object
            .iter()
            .enumerate()
            .fold((0, 0.0), |(k, total), (j, p)| {
                (if *p > per_object[k] { j } else { k }, total + p)
            });
        let particles: Real = footprints.iter().map(|f| f.count).sum();
        let created = self.creation_headroom(particles);
        // Created particles fill in at the spacing of those around them:
        // each counted at the scene's mean pairs per particle.
        let pairs = pairs * (1.0 + created / particles.max(1.0));
        let frames = w.duration * w.frame_rate + 1.0;
        let steps = (w.settle + w.duration) / w.dt;
        let (skin_per_frame, contact_per_step, costliest_skin) =
            self.skin_work(&footprints, frames, steps);
        let mut triangulation = 0.0;
        if self.outputs.triangulation {
            for (k, f) in footprints.iter().enumerate() {
                triangulation +=
                    footprints.own_pairs(k, self.outputs.triangulation_radius * f.spacing);
            }
        }
        Ok(WorkEstimate {
            frames,
            steps,
            particles,
            created,
            pairs,
            densest: object_path(densest, &self.objects[densest].name),
            skin_evaluations_per_frame: skin_per_frame,
            contact_evaluations_per_step: contact_per_step,
            triangulation_pairs_per_frame: triangulation,
            costliest_skin,
        })
    }

    /// Field evaluations of the skins: polygonizing them, per frame, and
    /// their contact, per step. Each primitive reaches the grid nodes
    /// within its support (at most every node of its object's grid); in
    /// contact it is evaluated once for each partner its object meets: the
    /// tools, and the skinned objects whose supports overlap it at the
    /// start, at least one (objects apart at the start meet later).
    /// Also returns the object whose skin costs the most over the run
    /// (`frames` and `steps`), with its skin's radius and cell size and
    /// the other skins it overlaps (for the error that names it).
    fn skin_work(
        &self,
        footprints: &Footprints,
        frames: Real,
        steps: Real,
    ) -> (Real, Real, Option<(String, String)>) {
        let skinned: Vec<(usize, &SkinSpec)> = self
            .objects
            .iter()
            .enumerate()
            .filter_map(|(k, o)| o.skin.as_ref().map(|s| (k, s)))
            .collect();
        let contact = skinned.len() >= 2 || (!skinned.is_empty() && !self.tools.is_empty());
        // Skinned objects whose supports overlap: boxes within both radii
        // (a sweep whose cost grows with the pairs it finds: skipped
        // without a pair limit, like the pairs between objects).
        let mut partners = vec![self.tools.len() as Real; skinned.len()];
        if contact && self.limits.max_pair_steps.is_finite() {
            let boxes: Vec<&Footprint> = skinned.iter().map(|(k, _)| footprints.get(*k)).collect();
            let largest = skinned.iter().map(|(_, s)| s.radius).fold(0.0, Real::max);
            for (a, b) in near_pairs(&boxes, 2.0 * largest) {
                partners[a] += 1.0;
                partners[b] += 1.0;
            }
        }
        let mut per_frame = 0.0;
        let mut per_step = 0.0;
        let mut costliest = (Real::NEG_INFINITY, None);
        for (&(k, skin), partners) in skinned.iter().zip(partners) {
            let f = footprints.get(k);
            let nodes = |reach: Real| {
                let own = (2.0 * reach / skin.cell_size).powi(3);
                let grid = ((2.0 * (f.radius() + reach)) / skin.cell_size + 3.0).powi(3);
                own.min(grid)
            };
            let frame = f.count * nodes(skin.reach());
            let step = if contact {
                f.count * nodes(skin.radius) * partners.max(1.0)
            } else {
                0.0
            };
            per_frame += frame;
            per_step += step;
            let cost = frames * frame + steps * step;
            if cost > costliest.0 {
                let skins = partners - self.tools.len() as Real;
                let overlapping = if skins > 0.0 {
                    format!(", overlapping {} other skin(s) at the start", short(skins))
                } else {
                    String::new()
                };
                let o = &self.objects[k];
                let value = format!(
                    "radius {}, cell_size {}{overlapping}",
                    short(skin.radius),
                    short(skin.cell_size)
                );
                costliest = (
                    cost,
                    Some((format!("{}.skin", object_path(k, &o.name)), value)),
                );
            }
        }
        (per_frame, per_step, costliest.1)
    }

    /// The run's objects, steps, particle-steps, pairs, pair-steps and
    /// field evaluations within [`Scene::limits`]; `total` is the particle
    /// count.
    fn validate_run_size(
        &self,
        total: usize,
        base_dir: Option<&Path>,
    ) -> Result<WorkEstimate, SceneError> {
        let steps = self.validate_step_work(total)?;
        self.validate_pair_work(steps, base_dir)
    }

    /// The run's objects, steps and particle-steps within
    /// [`Scene::limits`] (`total` particles); returns the steps.
    fn validate_step_work(&self, total: usize) -> Result<Real, SceneError> {
        let file = self.origin();
        let w = &self.world;
        let lim = &self.limits;
        let flag = "(opsim --no-work-limits lifts this limit)";
        let objects = self.objects.len() as Real;
        if objects > lim.max_objects {
            return Err(SceneError::value(
                file,
                "objects",
                format!("{} objects", self.objects.len()),
                &format!("must be at most {} {flag}", short(lim.max_objects)),
            ));
        }
        let steps = (w.settle + w.duration) / w.dt;
        if steps > lim.max_steps {
            return Err(SceneError::value(
                file,
                "world.dt",
                short(w.dt),
                &format!(
                    "makes (world.settle + world.duration{}) / dt = {} steps, more than the \
                     limit of {} {flag}",
                    self.set_by_frames(),
                    short(steps.ceil()),
                    short(lim.max_steps)
                ),
            ));
        }
        let created = self.creation_headroom(total as Real);
        let particle_steps = steps * (total as Real + created);
        if particle_steps > lim.max_particle_steps {
            let particles = if created > 0.0 {
                format!(
                    "up to {} particles ({total} and those creation.max_particles allows)",
                    short(total as Real + created)
                )
            } else {
                format!("{total} particles")
            };
            return Err(SceneError::value(
                file,
                "world.duration",
                format!("{}{}", short(w.duration), self.set_by_frames()),
                &format!(
                    "makes {} steps of {particles}, {} particle-steps, more than the limit of \
                     {} {flag}",
                    short(steps.ceil()),
                    short(particle_steps),
                    short(lim.max_particle_steps)
                ),
            ));
        }
        Ok(steps)
    }

    /// The run's pairs, pair-steps, triangulation pairs and field
    /// evaluations within [`Scene::limits`], over `steps` steps.
    fn validate_pair_work(
        &self,
        steps: Real,
        base_dir: Option<&Path>,
    ) -> Result<WorkEstimate, SceneError> {
        let file = self.origin();
        let w = &self.world;
        let lim = &self.limits;
        let flag = "(opsim --no-work-limits lifts this limit)";
        let e = self.work_estimate(base_dir)?;
        let densely = "(particles packed closely for their material's cut-off or bond radius, \
                       or objects overlapping)";
        if e.pairs > lim.max_pairs {
            return Err(SceneError::value(
                file,
                e.densest.clone(),
                format!(
                    "about {} interacting pairs in the scene",
                    short(e.pairs.round())
                ),
                &format!(
                    "the scene's objects hold at most {} pairs at once {densely}; this object \
                     holds the most {flag}",
                    short(lim.max_pairs)
                ),
            ));
        }
        let pair_steps = e.pair_steps();
        if pair_steps > lim.max_pair_steps {
            return Err(SceneError::value(
                file,
                "world.duration",
                format!("{}{}", short(w.duration), self.set_by_frames()),
                &format!(
                    "makes {} steps of about {} interacting pairs {densely}, {} pair-steps, \
                     more than the limit of {} {flag}",
                    short(steps.ceil()),
                    short(e.pairs.round()),
                    short(pair_steps),
                    short(lim.max_pair_steps)
                ),
            ));
        }
        if e.triangulation_pairs_per_frame > lim.max_pairs {
            return Err(SceneError::value(
                file,
                "outputs.triangulation_radius",
                short(self.outputs.triangulation_radius),
                &format!(
                    "makes about {} triangulation pairs per frame, more than the limit of {} \
                     pairs held at once {flag}",
                    short(e.triangulation_pairs_per_frame.round()),
                    short(lim.max_pairs)
                ),
            ));
        }
        let evaluations = e.field_evaluations();
        if evaluations > lim.max_pair_steps {
            let (field, value) = e.costliest_output(self);
            return Err(SceneError::value(
                file,
                field,
                value,
                &format!(
                    "makes about {} skin field evaluations and triangulation pairs over the \
                     run ({} per frame in skins, {} per step in skin contact, {} per frame in \
                     triangulations), more than the limit of {} {flag}",
                    short(evaluations),
                    short(e.skin_evaluations_per_frame),
                    short(e.contact_evaluations_per_step),
                    short(e.triangulation_pairs_per_frame),
                    short(lim.max_pair_steps)
                ),
            ));
        }
        Ok(e)
    }

    /// Heat conduction per step and the creation rules' limits.
    fn validate_heat_and_creation(&self) -> Result<(), SceneError> {
        let file = self.origin();
        let w = &self.world;
        let lim = &self.limits;
        let flag = "(opsim --no-work-limits lifts this limit)";
        if let Some(h) = &w.heat {
            if h.conduction * w.dt > MAX_CONDUCTION_STEP {
                return Err(SceneError::value(
                    file,
                    "world.heat.conduction",
                    short(h.conduction),
                    &format!(
                        "times world.dt must be at most {MAX_CONDUCTION_STEP} (each step takes \
                         about 2 conduction dt times the neighbour count heat sub-steps): at most \
                         {}",
                        short(MAX_CONDUCTION_STEP / w.dt)
                    ),
                ));
            }
        }
        if let Some(c) = &self.creation {
            if c.max_particles as Real > lim.max_created {
                return Err(SceneError::value(
                    file,
                    "creation.max_particles",
                    c.max_particles,
                    &format!("must be at most {} {flag}", short(lim.max_created)),
                ));
            }
            let distances = [
                (
                    "creation.stretching.d_min",
                    c.stretching.as_ref().map(|s| s.d_min),
                ),
                (
                    "creation.growing.radius",
                    c.growing.as_ref().map(|g| g.radius),
                ),
            ];
            for (field, d) in distances {
                if let Some(d) = d.filter(|d| *d < MIN_CREATION_DISTANCE) {
                    return Err(SceneError::value(
                        file,
                        field,
                        short(d),
                        &format!("must be at least {MIN_CREATION_DISTANCE} rest spacings"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Every coordinate, tool size and object size within
    /// [`MAX_EXTENT_OVER_SPACING`] length scales; tool rotations within
    /// [`MAX_ROTATION`]; skins within [`MAX_SKIN_NODES_PER_AXIS`] grid
    /// nodes per axis.
    fn validate_lengths(&self, base_dir: Option<&Path>) -> Result<(), SceneError> {
        let file = self.origin();
        let scale = self.length_scale();
        let max = MAX_EXTENT_OVER_SPACING * scale;
        let allowed = format!(
            "must be within {} of the origin ({} times the scene's length scale {}, its largest \
             generator or material spacing)",
            short(max),
            short(MAX_EXTENT_OVER_SPACING),
            short(scale)
        );
        let bound = LengthBound {
            file,
            max,
            allowed,
            extents: RefCell::new(HashMap::new()),
        };
        for (k, o) in self.objects.iter().enumerate() {
            bound.object(k, o, base_dir)?;
        }
        for (k, t) in self.tools.iter().enumerate() {
            bound.tool(k, t)?;
        }
        Ok(())
    }
}

/// The bound of [`Scene::validate_lengths`]: lengths at most `max`, and
/// what a coordinate beyond it is told (`allowed`), in scene `file`.
struct LengthBound<'a> {
    file: &'a str,
    /// The extent of each points file read so far: objects made by the
    /// same file read it once.
    extents: RefCell<HashMap<PathBuf, Real>>,
    max: Real,
    allowed: String,
}

impl LengthBound<'_> {
    /// Refuses a point `v` (at `path`) farther than `max` from the origin.
    fn check(&self, path: String, v: &[Real; 3]) -> Result<(), SceneError> {
        let norm = v.iter().map(|c| c * c).sum::<Real>().sqrt();
        if norm <= self.max {
            Ok(())
        } else {
            Err(SceneError::value(
                self.file,
                path,
                format!("[{}, {}, {}]", short(v[0]), short(v[1]), short(v[2])),
                &self.allowed,
            ))
        }
    }

    /// Object `k`: its generator's positions, its extent and its skin's
    /// grid.
    fn object(&self, k: usize, o: &ObjectSpec, base_dir: Option<&Path>) -> Result<(), SceneError> {
        let (file, max) = (self.file, self.max);
        let path = object_path(k, &o.name);
        self.generator_positions(&path, &o.generator)?;
        let extent = match &o.generator {
            Generator::Points { path: points } => {
                let known = self.extents.borrow().get(points).copied();
                match known {
                    Some(extent) => extent,
                    None => {
                        let field = format!("{path}.generator");
                        let extent = object_extent(&o.generator, base_dir, file, &field)?;
                        self.extents.borrow_mut().insert(points.clone(), extent);
                        extent
                    }
                }
            }
            g => object_extent(g, base_dir, file, &format!("{path}.generator"))?,
        };
        if extent > max {
            return Err(SceneError::value(
                file,
                format!("{path}.generator"),
                format!("an object {} across", short(extent)),
                &format!(
                    "objects must be at most {} across ({} times the scene's length scale)",
                    short(max),
                    short(MAX_EXTENT_OVER_SPACING)
                ),
            ));
        }
        if let Some(skin) = &o.skin {
            self.skin_grid(&path, skin, extent)?;
        }
        Ok(())
    }

    /// The positions a generator places its object at (centre, start or
    /// listed particles) of the object at `path`.
    fn generator_positions(&self, path: &str, g: &Generator) -> Result<(), SceneError> {
        let at = |f: &str| format!("{path}.generator.{}.{f}", g.name());
        match g {
            Generator::Spiral { center, .. }
            | Generator::HexSheet { center, .. }
            | Generator::SphereShell { center, .. }
            | Generator::SolidBall { center, .. }
            | Generator::TorusShell { center, .. } => self.check(at("center"), center)?,
            Generator::Chain { start, .. } => self.check(at("start"), start)?,
            Generator::List { particles } => {
                for (j, p) in particles.iter().enumerate() {
                    self.check(at(&format!("particles[{j}].position")), &p.position)?;
                }
            }
            Generator::Points { .. } => {}
        }
        Ok(())
    }

    /// The skin of the object at `path`, `extent` across: within
    /// [`MAX_SKIN_NODES_PER_AXIS`] grid nodes per axis.
    fn skin_grid(&self, path: &str, skin: &SkinSpec, extent: Real) -> Result<(), SceneError> {
        let nodes = (extent + 2.0 * skin.reach()) / skin.cell_size + 3.0;
        if nodes.is_nan() || nodes > MAX_SKIN_NODES_PER_AXIS {
            return Err(SceneError::value(
                self.file,
                format!("{path}.skin.cell_size"),
                short(skin.cell_size),
                &format!(
                    "the skin of an object {} across with support {} needs about {} grid \
                     nodes per axis at this cell size, more than the polygonizer's {}: \
                     use a cell size of at least {}",
                    short(extent),
                    short(skin.reach()),
                    short(nodes.ceil()),
                    MAX_SKIN_NODES_PER_AXIS,
                    short((extent + 2.0 * skin.reach()) / (MAX_SKIN_NODES_PER_AXIS - 3.0))
                ),
            ));
        }
        Ok(())
    }

    /// Tool `k`: its size (unless unbounded), its keyframes' positions and
    /// rotation angles.
    fn tool(&self, k: usize, t: &ToolSpec) -> Result<(), SceneError> {
        let (file, max) = (self.file, self.max);
        if let Ok(shape) = t.shape.build() {
            let aabb = shape.compute_local_aabb();
            let size = (aabb.maxs - aabb.mins).length() as Real;
            if !t.shape.is_unbounded() && (size.is_nan() || size > max) {
                return Err(SceneError::value(
                    file,
                    format!("tools[{k}].shape"),
                    format!("a shape {} across", short(size)),
                    &format!(
                        "tools must be at most {} across ({} times the scene's length scale)",
                        short(max),
                        short(MAX_EXTENT_OVER_SPACING)
                    ),
                ));
            }
        }
        for (j, f) in t.path.keyframes.iter().enumerate() {
            self.check(format!("tools[{k}].path[{j}].position"), &f.position)?;
            let angle = f.rotation.iter().map(|c| c * c).sum::<Real>().sqrt();
            if angle.is_nan() || angle > MAX_ROTATION {
                return Err(SceneError::value(
                    file,
                    format!("tools[{k}].path[{j}].rotation"),
                    short(angle),
                    &format!(
                        "rotation angles must be at most {} rad (a thousand turns)",
                        short(MAX_ROTATION)
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The size of the object a generator makes (an upper bound for lattices,
/// the bounding-box diagonal for points and lists).
fn object_extent(
    g: &Generator,
    base_dir: Option<&Path>,
    file: &str,
    path: &str,
) -> Result<Real, SceneError> {
    Ok(match g {
        Generator::Spiral { count, spacing, .. } | Generator::Chain { count, spacing, .. } => {
            count.saturating_sub(1) as Real * spacing
        }
        Generator::HexSheet {
            nx, ny, spacing, ..
        } => (*nx.max(ny)) as Real * spacing,
        Generator::SphereShell { radius, .. } | Generator::SolidBall { radius, .. } => 2.0 * radius,
        Generator::TorusShell { major, minor, .. } => 2.0 * (major + minor),
        Generator::List { .. } | Generator::Points { .. } => {
            let positions = g.generate(base_dir, file, path)?.positions;
            let mut lo = [Real::INFINITY; 3];
            let mut hi = [Real::NEG_INFINITY; 3];
            for p in &positions {
                for c in 0..3 {
                    lo[c] = lo[c].min(p[c]);
                    hi[c] = hi[c].max(p[c]);
                }
            }
            (0..3)
                .map(|c| (hi[c] - lo[c]).max(0.0).powi(2))
                .sum::<Real>()
                .sqrt()
        }
    })
}

/// What a scene's run is estimated to cost ([`Scene::work_estimate`]):
/// what the work limits are checked against and `opsim check` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkEstimate {
    /// Frames written, frame 0 included.
    pub frames: Real,
    /// Time steps (settle phase and run; fixed-step schemes).
    pub steps: Real,
    /// Particles at the start (lattice generators estimated from their
    /// size).
    pub particles: Real,
    /// Particles the creation rules may add at most, up to
    /// `creation.max_particles` in all (0 without a rule that creates).
    pub created: Real,
    /// Interacting pairs held at once: within each object at its
    /// material's cut-off or bond radius, and between objects whose
    /// regions come within the scene's largest such range; created
    /// particles at the scene's mean pairs per particle.
    pub pairs: Real,
    /// The object with the most pairs (its own and its half of those
    /// shared with objects it overlaps), as a field path.
    pub densest: String,
    /// Field evaluations of polygonizing the skins, per frame (each
    /// primitive at the grid nodes within its support).
    pub skin_evaluations_per_frame: Real,
    /// Field evaluations of skin contact, per step (each primitive at the
    /// nodes within its contact support; 0 without contact).
    pub contact_evaluations_per_step: Real,
    /// Pairs of the triangulations written with each frame (0 without).
    pub triangulation_pairs_per_frame: Real,
    /// The skin that costs the most field evaluations over the run, as its
    /// field path and what sets its cost (its radius and cell size, the
    /// other skins it overlaps); `None` without skins.
    pub costliest_skin: Option<(String, String)>,
}

impl WorkEstimate {
    /// Pairs evaluated over the run: pairs times steps.
    pub fn pair_steps(&self) -> Real {
        self.pairs * self.steps
    }

    /// Skin field evaluations and triangulation pairs over the run.
    pub fn field_evaluations(&self) -> Real {
        self.frames * (self.skin_evaluations_per_frame + self.triangulation_pairs_per_frame)
            + self.steps * self.contact_evaluations_per_step
    }

    /// The field and value that set the largest part of
    /// [`WorkEstimate::field_evaluations`] in `scene`: a skin's cell size
    /// or the triangulation radius.
    fn costliest_output(&self, scene: &Scene) -> (String, String) {
        let triangulation = self.frames * self.triangulation_pairs_per_frame;
        if triangulation >= self.field_evaluations() - triangulation {
            return (
                "outputs.triangulation_radius".into(),
                short(scene.outputs.triangulation_radius),
            );
        }
        self.costliest_skin
            .clone()
            .unwrap_or_else(|| ("objects".into(), String::new()))
    }
}
