//! Validation that a scene asks for a finite run of bounded work (see
//! [`super::limits`]): steps, frames, heat sub-steps, created particles,
//! skin grids, and every length relative to the scene's length scale.

use std::path::Path;

use op_dynamics::Real;

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

    /// Interacting pairs (each counted once) estimated from each lattice
    /// generator's count, spacing and dimension and its material's
    /// interaction range: a chain has `range / spacing` neighbours per
    /// particle on each side, a hexagonal sheet or shell
    /// `π range² / (0.866 spacing²)` within the range. Points files and
    /// lists count one pair per particle.
    pub(crate) fn estimated_pairs(&self) -> Real {
        self.objects
            .iter()
            .map(|o| {
                let range = self
                    .materials
                    .get(&o.material)
                    .and_then(|m| m.prepare().ok())
                    .map_or(0.0, |m| m.cutoff());
                let (count, spacing, dim) = match &o.generator {
                    Generator::Spiral { count, spacing, .. }
                    | Generator::Chain { count, spacing, .. } => (*count as Real, *spacing, 1),
                    Generator::HexSheet {
                        nx, ny, spacing, ..
                    } => ((nx * ny) as Real, *spacing, 2),
                    Generator::SphereShell {
                        radius, spacing, ..
                    } => (
                        4.0 * std::f64::consts::PI * (radius / spacing).powi(2),
                        *spacing,
                        2,
                    ),
                    Generator::TorusShell {
                        major,
                        minor,
                        spacing,
                        ..
                    } => (
                        4.0 * std::f64::consts::PI.powi(2) * major * minor / spacing.powi(2),
                        *spacing,
                        2,
                    ),
                    Generator::SolidBall {
                        radius, spacing, ..
                    } => (
                        crate::generators::solid_ball_estimate(*radius, *spacing),
                        *spacing,
                        3,
                    ),
                    Generator::Points { .. } | Generator::List { .. } => return 0.0,
                };
                let ratio = range / spacing;
                let per_particle = match dim {
                    1 => ratio,
                    2 => 0.5 * std::f64::consts::PI * ratio * ratio / 0.866,
                    // Half the face-centred cubic packing's particles
                    // within the range: 2/3 π ratio³ √2.
                    _ => 2.0 / 3.0 * std::f64::consts::PI * ratio.powi(3) * 2f64.sqrt(),
                };
                count * per_particle.max(1.0)
            })
            .sum()
    }

    /// Checks the run's size against [`Scene::limits`] and the lengths
    /// against the scene's length scale; `total` is the particle count.
    pub(crate) fn validate_work(
        &self,
        total: usize,
        base_dir: Option<&Path>,
    ) -> Result<(), SceneError> {
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
                    "with world.duration = {} gives {} frames, more than the limit of {} {flag}",
                    short(w.duration),
                    short(frames.round()),
                    short(lim.max_frames)
                ),
            ));
        }
        self.validate_run_size(total)?;
        self.validate_heat_and_creation()?;
        self.validate_lengths(base_dir)
    }

    /// The run's steps, particle-steps and pair-steps within
    /// [`Scene::limits`]; `total` is the particle count.
    fn validate_run_size(&self, total: usize) -> Result<(), SceneError> {
        let file = self.origin();
        let w = &self.world;
        let lim = &self.limits;
        let flag = "(opsim --no-work-limits lifts this limit)";
        let steps = (w.settle + w.duration) / w.dt;
        if steps > lim.max_steps {
            return Err(SceneError::value(
                file,
                "world.dt",
                short(w.dt),
                &format!(
                    "makes (world.settle + world.duration) / dt = {} steps, more than the limit \
                     of {} {flag}",
                    short(steps.ceil()),
                    short(lim.max_steps)
                ),
            ));
        }
        let particle_steps = steps * total as Real;
        if particle_steps > lim.max_particle_steps {
            return Err(SceneError::value(
                file,
                "world.duration",
                short(w.duration),
                &format!(
                    "makes {} steps of {total} particles, {} particle-steps, more than the \
                     limit of {} {flag}",
                    short(steps.ceil()),
                    short(particle_steps),
                    short(lim.max_particle_steps)
                ),
            ));
        }
        let pair_steps = steps * self.estimated_pairs();
        if pair_steps > lim.max_pair_steps {
            return Err(SceneError::value(
                file,
                "world.duration",
                short(w.duration),
                &format!(
                    "makes {} steps of about {} interacting pairs (particles packed closely \
                     for their material's cut-off), {} pair-steps, more than the limit of {} \
                     {flag}",
                    short(steps.ceil()),
                    short(self.estimated_pairs().round()),
                    short(pair_steps),
                    short(lim.max_pair_steps)
                ),
            ));
        }
        Ok(())
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
        let bound = LengthBound { file, max, allowed };
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
        let extent = object_extent(&o.generator, base_dir, file, &format!("{path}.generator"))?;
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
