//! Scene → world: generate particles, apply overrides, map names to
//! indices, and build an op-dynamics [`World`] holding only what the scene
//! uses (README "Running scenes").

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use op_dynamics::driver::{Driver, Stage};
use op_dynamics::{
    Flags, ForceWindow, Material, ParticleDesc, Particles, Point3, Real, Vec3, World,
};
use op_modeling::{Role, Tool, ToolParams};

use crate::built_scene::{BuiltObject, BuiltScene};
use crate::creation::CreationState;
use crate::damping::CriticalDamping;
use crate::error::SceneError;
use crate::fit::{DataNeighbourhood, SceneFit};
use crate::generators::Generated;
use crate::schema::validate::object_path;
use crate::schema::{ObjectSpec, Override, Scene};
use crate::skins::{ContactStats, ObjectSkin, SkinTool};
use crate::stages::SceneState;

mod rest_spacing;
mod velocities;
pub(crate) use rest_spacing::rest_spacing;
use velocities::add_velocities;

impl Scene {
    /// Validates the scene ([`Scene::validate`]; points files relative to
    /// `base_dir`) and builds it:
    ///
    /// 1. generates each object's particles and orients them (shortest
    ///    rotation from the object's `normal_axis` to the generated
    ///    normal); object `k` gets object id `k`;
    /// 2. applies the overrides in order;
    /// 3. puts into the world only the materials some object uses (sorted
    ///    by name), so nothing unused is prepared or evaluated;
    /// 4. maps forces to [`ForceWindow`]s over global particle ids (objects
    ///    are numbered consecutively in scene order), their times shifted by
    ///    the settle phase (`world.settle`) so they count from its end;
    /// 5. builds [`op_dynamics::WorldParams`] and the [`World`].
    ///
    /// Each [`BuiltObject`] records its ids, rest positions and rest
    /// spacing (mean nearest-neighbour distance within the object; the
    /// generator's spacing, or 1, for a single particle) at build time; a
    /// scene with a settle phase replaces them with the settled ones when
    /// [`BuiltScene::settle`] runs (the runner does it first). Coincident
    /// particles within an object are an error. `source` is stored in the
    /// result.
    ///
    /// A scene with `linear_damping: "Critical"` is resolved first
    /// ([`Scene::resolved`]): settled in trial builds until its slowest
    /// mode is known, then built with the numbers of the rule
    /// ([`BuiltScene::critical_damping`]).
    pub fn build(
        &self,
        base_dir: Option<&Path>,
        source: Option<PathBuf>,
    ) -> Result<BuiltScene, SceneError> {
        let clock = Instant::now();
        let (scene, critical) = self.resolved(base_dir)?;
        let seconds = clock.elapsed().as_secs_f64();
        let mut built = scene.build_world(base_dir, source)?;
        built.set_critical_damping(critical, seconds);
        Ok(built)
    }

    /// This scene as it runs: itself, or, with `linear_damping: "Critical"`
    /// ([`crate::schema::Damping::Critical`]), the scene with the damping,
    /// settle phase and duration of the rule ([`crate::damping::resolve`])
    /// and what the rule found. Validates the scene as written first.
    ///
    /// # Errors
    ///
    /// The scene's validation and build errors, a divergence while
    /// settling, or no slowest mode to damp.
    pub fn resolved(
        &self,
        base_dir: Option<&Path>,
    ) -> Result<(Cow<'_, Scene>, Option<CriticalDamping>), SceneError> {
        if !self.world.linear_damping.is_critical() {
            return Ok((Cow::Borrowed(self), None));
        }
        self.validate(base_dir)?;
        let (scene, critical) = crate::damping::resolve(self, base_dir)?;
        Ok((Cow::Owned(scene), Some(critical)))
    }

    /// [`Scene::build`], then the stable-step estimate
    /// ([`crate::stability`], kept in [`BuiltScene::step_estimate`]): a
    /// `dt` above the recommended step becomes the first of the run's
    /// warnings ([`BuiltScene::step_warnings`]), and `precision: mixed` on
    /// a world that runs in double precision another. What `opsim run`
    /// uses. The estimate is advice: a sample that cannot be built (the
    /// full scene could) only means there is no estimate.
    pub fn build_for_run(
        &self,
        base_dir: Option<&Path>,
        source: Option<PathBuf>,
    ) -> Result<BuiltScene, SceneError> {
        let clock = Instant::now();
        let (scene, critical) = self.resolved(base_dir)?;
        let seconds = clock.elapsed().as_secs_f64();
        let mut built = scene.build_world(base_dir, source)?;
        built.set_critical_damping(critical, seconds);
        let clock = Instant::now();
        if let Ok(estimate) = crate::stability::estimate(&scene, base_dir) {
            built.step_warnings = estimate
                .warning(self.world.dt, &self.world.integrator)
                .into_iter()
                .collect();
            built.step_estimate = Some(estimate);
        }
        built
            .setup_seconds
            .push(("estimate".into(), clock.elapsed().as_secs_f64()));
        if self.world.precision == op_dynamics::Precision::Mixed
            && !built.world().runs_mixed_precision()
        {
            built.step_warnings.push(
                "world.precision: mixed has no effect on this scene, which runs in double \
                 precision: mixed precision computes the pairs of spacing-only worlds of one \
                 12-6 Lennard-Jones material (no orientation terms, heat, bonds or other \
                 materials)"
                    .into(),
            );
        }
        Ok(built)
    }

    /// The build of [`Scene::build`] (the stable-step estimate builds its
    /// sample of the scene through this), without resolving
    /// `linear_damping: "Critical"` (which counts as 0 here).
    pub(crate) fn build_world(
        &self,
        base_dir: Option<&Path>,
        source: Option<PathBuf>,
    ) -> Result<BuiltScene, SceneError> {
        let clock = Instant::now();
        let counts = self.validate(base_dir)?;
        let used = self.used_materials()?;
        let placed = self.place_objects(base_dir, &counts, &used)?;
        let (tools, skin_tool_params, all_tools) = self.tool_params();
        let mut world =
            self.make_world(placed.particles, &used, &counts, &placed.offsets, &tools)?;
        world.set_step_budget(self.step_budget(counts.iter().sum()));
        let objects = placed.objects;
        let file = self.origin();
        let mut skins = Vec::new();
        for (k, o) in self.objects.iter().enumerate() {
            let Some(spec) = &o.skin else { continue };
            let skin = crate::skins::build_skin(&world, k, &objects[k], spec, o.normal_axis)
                .map_err(|e| SceneError::Build {
                    file: file.to_string(),
                    message: format!("{}.skin: {e}", object_path(k, &o.name)),
                })?;
            skins.push(skin);
        }
        let skin_tools = skin_tool_params
            .into_iter()
            .map(|(k, params, objects, (stiffness, friction, damping))| {
                let tool = Tool::new(&params, world.particles())
                    .map_err(|e| SceneError::param(file, &format!("tools[{k}]"), e))?;
                let skins = skins
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| objects.contains(&s.object))
                    .map(|(i, _)| i)
                    .collect();
                Ok(SkinTool {
                    tool,
                    skins,
                    stiffness,
                    friction,
                    damping,
                })
            })
            .collect::<Result<Vec<_>, SceneError>>()?;
        let tools = all_tools
            .iter()
            .enumerate()
            .map(|(k, p)| {
                Tool::new(p, world.particles())
                    .map_err(|e| SceneError::param(file, &format!("tools[{k}]"), e))
            })
            .collect::<Result<Vec<_>, SceneError>>()?;
        let creation = self.creation_state(&objects, placed.fitted, placed.seeds.as_ref());
        let install = crate::features::InstallContext {
            objects: &objects,
            settle: self.world.settle,
        };
        let features = self.features.iter().enumerate().map(|(k, f)| {
            let path = format!("features[{k}].{}", f.name());
            (path, f.feature().stage(&install))
        });
        let driver =
            stage_driver(features, creation.as_ref(), &skins, &skin_tools).map_err(|message| {
                SceneError::Build {
                    file: file.to_string(),
                    message,
                }
            })?;
        let w = &self.world;
        Ok(BuiltScene {
            driver,
            skins,
            skin_tools,
            tools,
            contact: ContactStats::default(),
            name: self.name.clone(),
            source,
            world,
            objects,
            duration: w.duration,
            settle: w.settle,
            settled: w.settle == 0.0,
            frame_rate: w.frame_rate,
            outputs: self.outputs.clone(),
            energy_growth: w.divergence.energy_growth,
            energy_gain: w.divergence.energy_gain,
            extent_growth: w.divergence.extent_growth,
            step_warnings: Vec::new(),
            creation,
            setup_seconds: vec![("build".into(), clock.elapsed().as_secs_f64())],
            expected_warnings: self.expected_warnings.clone(),
            breakup_accepted: false,
            step_estimate: None,
            inputs: crate::run::checkpoint::fnv1a(&serde_json::to_vec(self).unwrap_or_default()),
            critical_damping: None,
        })
    }

    /// The names of the materials some object uses, in the scene's order
    /// (the world holds only these; index = material index).
    fn used_materials(&self) -> Result<Vec<&String>, SceneError> {
        let used: Vec<&String> = self
            .materials
            .keys()
            .filter(|name| self.objects.iter().any(|o| &o.material == *name))
            .collect();
        if used.len() > usize::from(u16::MAX) + 1 {
            return Err(SceneError::Build {
                file: self.origin().to_string(),
                message: format!(
                    "{} materials are used; at most 65536 are supported",
                    used.len()
                ),
            });
        }
        Ok(used)
    }

    /// Generates every object's particles (`counts` as validated), applies
    /// overrides and initial velocities, and records each object's rest
    /// shape and spacing.
    fn place_objects(
        &self,
        base_dir: Option<&Path>,
        counts: &[usize],
        used: &[&String],
    ) -> Result<Placed, SceneError> {
        let index: HashMap<&str, u16> = used
            .iter()
            .enumerate()
            .map(|(k, name)| (name.as_str(), k as u16))
            .collect();
        let fit = self.creation.as_ref().and_then(|c| c.fit.as_ref());
        let mut placed = Placed {
            particles: Particles::new(),
            objects: Vec::with_capacity(self.objects.len()),
            offsets: Vec::with_capacity(self.objects.len()),
            fitted: fit.map(|f| f.object_index(self)),
            seeds: None,
        };
        for (k, o) in self.objects.iter().enumerate() {
            let material = index.get(o.material.as_str()).copied().unwrap_or(0);
            self.place_object(base_dir, k, o, counts[k], material, &mut placed)?;
        }
        Ok(placed)
    }

    /// Generates and adds object `k` (see [`Scene::place_objects`]).
    fn place_object(
        &self,
        base_dir: Option<&Path>,
        k: usize,
        o: &ObjectSpec,
        count: usize,
        material: u16,
        placed: &mut Placed,
    ) -> Result<(), SceneError> {
        let file = self.origin();
        let path = object_path(k, &o.name);
        let generator_path = format!("{path}.generator");
        let mut g = o.generator.generate(base_dir, file, &generator_path)?;
        let fitted = placed.fitted == Some(k);
        if fitted {
            placed.seeds = Some(self.fit_seeds(&mut g, base_dir, &generator_path)?);
        }
        if g.len() != count {
            return Err(SceneError::Build {
                file: file.to_string(),
                message: format!(
                    "{generator_path}: made {} particles, {count} when validated (did the points file change?)",
                    g.len(),
                ),
            });
        }
        let mut descs: Vec<ParticleDesc> = (0..g.len())
            .map(|i| {
                particle(o, k as u32, material, g.positions[i], g.curvatures[i])
                    .with_normal(g.normals[i])
            })
            .collect();
        for ov in &o.overrides {
            apply(ov, &mut descs);
        }
        add_velocities(o, &mut descs, base_dir, file, &path)?;
        if fitted {
            // The samples are fixed seeds until the release.
            for d in &mut descs {
                d.flags.insert(Flags::FIXED_POSITION);
                d.flags.insert(Flags::FIXED_ORIENTATION);
            }
        }
        let offset = placed.particles.len();
        placed.offsets.push(offset);
        let mut ids = Vec::with_capacity(descs.len());
        for (i, d) in descs.into_iter().enumerate() {
            let id = placed
                .particles
                .push(d)
                .map_err(|e| SceneError::param(file, &format!("{path}.particles[{i}]"), e))?;
            ids.push(id);
        }
        let rest: Vec<Point3> = placed.particles.positions()[offset..].to_vec();
        let fit_spacing = placed.seeds.as_ref().filter(|_| fitted).map(|s| s.2);
        let rest_spacing = rest_spacing(&rest, o.generator.nominal_spacing()).map_err(|(i, j)| {
            SceneError::Build {
                file: file.to_string(),
                message: format!(
                    "{path}: particles {i} and {j} coincide at {:?}; particles of an object must be apart",
                    rest[i].coords.as_slice()
                ),
            }
        })?;
        placed.objects.push(BuiltObject {
            name: o.name.clone(),
            ids,
            rest,
            // A fitted object's spacing is the fit's, not the samples'.
            rest_spacing: fit_spacing.unwrap_or(rest_spacing),
            created: Vec::new(),
        });
        Ok(())
    }

    /// The scene's force windows on global particle ids (`offsets`: each
    /// object's first slot), shifted by the settle phase.
    fn force_windows(&self, counts: &[usize], offsets: &[usize]) -> Vec<ForceWindow> {
        self.forces
            .iter()
            .map(|f| {
                let k = self
                    .objects
                    .iter()
                    .position(|o| o.name == f.object)
                    .unwrap_or(0);
                let (start, end) = (f.start + self.world.settle, f.end + self.world.settle);
                ForceWindow {
                    particles: f
                        .particles
                        .indices(counts[k])
                        .into_iter()
                        .map(|i| (offsets[k] + i) as u32)
                        .collect(),
                    force: f.force,
                    start,
                    end,
                    // Shifting may round `end - start` down by an ulp.
                    ramp: f.ramp.min(0.5 * (end - start)),
                }
            })
            .collect()
    }

    /// The world of `particles` with the used materials, the scene's world
    /// settings and force windows, and the world's tools (errors name the
    /// materials by their scene names).
    fn make_world(
        &self,
        particles: Particles,
        used: &[&String],
        counts: &[usize],
        offsets: &[usize],
        tools: &[ToolParams],
    ) -> Result<World, SceneError> {
        let w = &self.world;
        let materials: Vec<Material> = used.iter().map(|name| self.materials[*name]).collect();
        let params = w.params(self.force_windows(counts, offsets));
        op_modeling::Tools::world(particles, &materials, params, tools).map_err(|e| {
            let mut message = format!("building the world: {e}");
            for (k, name) in used.iter().enumerate() {
                message =
                    message.replace(&format!("materials[{k}]"), &format!("materials.{name:?}"));
            }
            SceneError::Build {
                file: self.origin().to_string(),
                message,
            }
        })
    }

    /// The creation rules' state, when the scene has creation rules (with
    /// the fit of `creation.fit` on object `fitted` from `seeds`).
    fn creation_state(
        &self,
        objects: &[BuiltObject],
        fitted: Option<usize>,
        seeds: Option<&FitSeeds>,
    ) -> Option<CreationState> {
        let c = self.creation.as_ref()?;
        let default_r0 = match fitted {
            Some(k) => objects[k].rest_spacing,
            None => objects.first().map_or(1.0, |o| o.rest_spacing),
        };
        let params = c.params(default_r0);
        let fit = c.fit.as_ref().zip(seeds).map(|(f, (p, n, _))| {
            let d_max = params.stretching.as_ref().map_or(2.5, |s| s.d_max);
            SceneFit {
                object: fitted.unwrap_or(0),
                near: DataNeighbourhood::new(p, n, params.r0, d_max, f.open),
                release_time: self.world.settle + f.release,
                released: false,
            }
        });
        Some(CreationState {
            params,
            next_step: 0,
            fit,
        })
    }
}

/// The seeds of `creation.fit`: positions, normals, fit spacing.
type FitSeeds = (Vec<Point3>, Vec<Vec3>, Real);

/// The particles of a scene's objects as generated, before the world.
struct Placed {
    particles: Particles,
    objects: Vec<BuiltObject>,
    /// Each object's first slot.
    offsets: Vec<usize>,
    /// The object `creation.fit` fits, if any.
    fitted: Option<usize>,
    seeds: Option<FitSeeds>,
}

/// The driver with only the stages the scene uses: its features' (each
/// with its field path, for errors), then those of [`crate::stages`], in
/// their order. Stage names must differ from each other, from the world's
/// own ([`op_dynamics::driver::RESERVED`]) and from the runner's timing
/// names, as every stage's time is reported by name.
fn stage_driver(
    features: impl Iterator<Item = (String, Box<dyn Stage<SceneState>>)>,
    creation: Option<&CreationState>,
    skins: &[ObjectSkin],
    skin_tools: &[SkinTool],
) -> Result<Driver<SceneState>, String> {
    use crate::stages::{ContactStage, Creation, FitRelease, SkinStage};
    type Boxed = Box<dyn Stage<SceneState>>;
    let mut stages: Vec<(String, Boxed)> = features.collect();
    let mut own: Vec<Boxed> = Vec::new();
    if let Some(c) = creation {
        if c.fit.is_some() {
            own.push(Box::new(FitRelease));
        }
        own.push(Box::new(Creation));
    }
    if skins.len() >= 2 || !skin_tools.is_empty() {
        own.push(Box::new(ContactStage::default()));
    }
    if !skins.is_empty() {
        own.push(Box::new(SkinStage));
    }
    stages.extend(own.into_iter().map(|s| (s.name().to_string(), s)));
    let mut driver = Driver::new();
    for (path, stage) in stages {
        let name = stage.name().to_string();
        if crate::run::RUNNER_STAGES.contains(&name.as_str()) {
            return Err(format!(
                "{path}: stage {name:?} is named like a stage of the runner"
            ));
        }
        driver
            .push(stage)
            .map_err(|e| format!("{path}: {}", e.message))?;
    }
    Ok(driver)
}

impl Scene {
    /// The seeds of `creation.fit` (`g` is the fitted object's generated
    /// set): their positions, their normals (estimated as `opsim fit` does,
    /// over 2.5 spacings, when a points file gives none; `g`'s normals are
    /// replaced then) and the fit spacing (`creation.spacing`, else the
    /// median nearest-sample distance).
    fn fit_seeds(
        &self,
        g: &mut Generated,
        base_dir: Option<&Path>,
        generator_path: &str,
    ) -> Result<FitSeeds, SceneError> {
        let file = self.origin();
        let k = self
            .creation
            .as_ref()
            .and_then(|c| c.fit.as_ref())
            .map_or(0, |f| f.object_index(self));
        let fail = |e: crate::fit::FitError| SceneError::Build {
            file: file.to_string(),
            message: format!("{generator_path}: the samples of creation.fit: {e}"),
        };
        let r0 = match self.creation.as_ref().and_then(|c| c.spacing) {
            Some(r0) => r0,
            None => crate::fit::median_nearest_distance(&g.positions).map_err(fail)?,
        };
        if !self.objects[k]
            .generator
            .has_normals(base_dir, file, generator_path)?
        {
            g.normals = crate::fit::estimate_normals(&g.positions, 2.5 * r0).map_err(fail)?;
        }
        Ok((g.positions.clone(), g.normals.clone(), r0))
    }
}

/// One tool met by skins: (scene index, shifted params, skinned objects,
/// (contact stiffness, friction coefficient, normal damping)).
type SkinToolParams = (usize, ToolParams, Vec<usize>, (Real, Real, Real));

impl Scene {
    /// The world's tools, the obstacle tools skins meet, and every tool (for
    /// output). Keyframe times
    /// and a mover's release shift by the settle phase (they count in
    /// scene time). An obstacle acts on the particles of the unskinned
    /// objects it selects and on the skins of the skinned ones; a tool
    /// left with no particle to act on is not given to the world.
    pub(crate) fn tool_params(&self) -> (Vec<ToolParams>, Vec<SkinToolParams>, Vec<ToolParams>) {
        let settle = self.world.settle;
        let mut world_tools = Vec::new();
        let mut skin_tools = Vec::new();
        let mut all = Vec::new();
        for (k, t) in self.tools.iter().enumerate() {
            let selected: Vec<usize> = match &t.objects {
                None => (0..self.objects.len()).collect(),
                Some(names) => (0..self.objects.len())
                    .filter(|&o| names.contains(&self.objects[o].name))
                    .collect(),
            };
            let mut params: ToolParams = t.acting_on(None);
            for f in &mut params.path.keyframes {
                f.time += settle;
            }
            if let Role::Mover { release, .. } = &mut params.role {
                *release += settle;
            }
            let (skinned, bare): (Vec<usize>, Vec<usize>) = match params.role {
                Role::Obstacle { .. } => selected
                    .into_iter()
                    .partition(|&o| self.objects[o].skin.is_some()),
                _ => (Vec::new(), selected),
            };
            all.push(params.clone());
            params.objects = Some(bare.iter().map(|&o| o as u32).collect());
            if let (
                false,
                Role::Obstacle {
                    stiffness,
                    friction,
                    damping,
                    ..
                },
            ) = (skinned.is_empty(), &params.role)
            {
                skin_tools.push((
                    k,
                    params.clone(),
                    skinned,
                    (*stiffness, *friction, *damping),
                ));
            }
            if !bare.is_empty() {
                world_tools.push(params);
            }
        }
        (world_tools, skin_tools, all)
    }
}

/// A particle of object `o` (id `object`) at `position`, before its
/// orientation is set.
fn particle(
    o: &ObjectSpec,
    object: u32,
    material: u16,
    position: Point3,
    curvature: Real,
) -> ParticleDesc {
    let mut d = ParticleDesc::at(position);
    d.velocity = Vec3::from(o.velocity);
    d.angular_velocity = Vec3::from(o.angular_velocity);
    d.mass = o.mass;
    d.inertia = Vec3::from(o.inertia);
    d.normal_axis = Vec3::from(o.normal_axis).normalize();
    d.object = object;
    d.kind = o.kind;
    d.material = material;
    d.curvature = curvature;
    d
}
/// Applies one override to the selected particles.
fn apply(ov: &Override, descs: &mut [ParticleDesc]) {
    let set = |flags: &mut Flags, flag: Flags, on: Option<bool>| match on {
        Some(true) => flags.insert(flag),
        Some(false) => flags.remove(flag),
        None => {}
    };
    for i in ov.particles.indices(descs.len()) {
        let d = &mut descs[i];
        set(&mut d.flags, Flags::FIXED_POSITION, ov.fixed_position);
        set(&mut d.flags, Flags::FIXED_ORIENTATION, ov.fixed_orientation);
        set(&mut d.flags, Flags::UNORIENTED, ov.unoriented);
        if let Some(kind) = ov.kind {
            d.kind = kind;
        }
        if let Some(k) = ov.curvature {
            d.curvature = k;
        }
        if let Some(t) = ov.temperature {
            d.temperature = t;
        }
        if let Some(m) = ov.mass {
            d.mass = m;
        }
    }
}
