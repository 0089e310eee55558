//! Scene validation: every value checked before anything is built, each
//! error naming the file, the field path, the bad value and what is
//! allowed.

use std::collections::HashMap;
use std::path::Path;

use op_dynamics::interactions::Spacing;
use op_dynamics::{Material, Real};

use super::checks::{self, direction, finite, finite3, non_negative, positive, positive3};
use super::{ForceSpec, ObjectSpec, Scene, ToolSpec, WorkEstimate, WorldSettings};
use crate::error::{short, SceneError};
use crate::generators::MAX_PARTICLES;

/// `objects[k] "name"`: how messages name an object.
pub(crate) fn object_path(k: usize, name: &str) -> String {
    format!("objects[{k}] {name:?}")
}

/// Names quoted and comma separated, for "defined: ..." lists
/// ([`crate::error::quoted_list`]: elided, at most a few).
fn quoted<'a>(names: impl Iterator<Item = &'a String>) -> String {
    crate::error::quoted_list(names.map(String::as_str))
}

/// Cohesion tables and integration panels grow with `cutoff / r0` and
/// `sqrt(alpha) r0`; absurd values would exhaust memory while the world is
/// prepared, so the scene layer bounds them (far beyond any useful value:
/// the defaults are `cutoff ≈ 2.08 r0`, `alpha r0² = 16`).
fn validate_cohesion_scale(file: &str, path: &str, m: &Material) -> Result<(), SceneError> {
    if let Some(Spacing::Cohesion(c)) = &m.spacing {
        let scale = c.alpha * c.r0 * c.r0;
        if scale > MAX_COHESION_ALPHA_R0_SQUARED {
            return Err(SceneError::value(
                file,
                format!("{path}.spacing.cohesion.alpha"),
                c.alpha,
                &format!(
                    "alpha r0^2 = {scale:e} must be at most {MAX_COHESION_ALPHA_R0_SQUARED:e}"
                ),
            ));
        }
        let cutoff = c.effective_cutoff();
        if cutoff.is_nan() || cutoff > MAX_COHESION_CUTOFF_OVER_R0 * c.r0 {
            return Err(SceneError::value(
                file,
                format!("{path}.spacing.cohesion.cutoff"),
                cutoff,
                &format!(
                    "the cut-off in use must be at most {MAX_COHESION_CUTOFF_OVER_R0} r0 = {} (lower cutoff, or raise alpha)",
                    MAX_COHESION_CUTOFF_OVER_R0 * c.r0
                ),
            ));
        }
    }
    Ok(())
}

/// The JSON Schema pattern of [`Scene::name`]: one or more characters,
/// none of them `/`, `\` or a control character (Unicode category Cc,
/// what `char::is_control` tests). The names `.` and `..`, which it lets
/// through, the schema refuses with a `not` beside it.
pub(crate) const SCENE_NAME_PATTERN: &str = r"^[^/\\\x00-\x1F\x7F-\x9F]+$";
/// The JSON Schema pattern of an object's name ([`ObjectSpec::name`]):
/// one or more characters, none of them a control character.
pub(crate) const OBJECT_NAME_PATTERN: &str = r"^[^\x00-\x1F\x7F-\x9F]+$";

/// Largest `alpha r0²` of a cohesion spacing the scene layer accepts.
pub const MAX_COHESION_ALPHA_R0_SQUARED: Real = 1e6;
/// Largest cohesion cut-off, in units of `r0`, the scene layer accepts.
pub const MAX_COHESION_CUTOFF_OVER_R0: Real = 1000.0;

impl Scene {
    /// Checks the whole scene: world settings, outputs, every material
    /// (`Material::validate`, reported under `materials."name"`), every
    /// object (unique names, known material, positive mass and inertia,
    /// generator parameters and particle count, override selections and
    /// values) and every force (known object, selection in range, finite
    /// force, a valid time window). Points files are read (relative to
    /// `base_dir`, the scene file's directory) to count their points.
    ///
    /// Errors name the file ([`Scene::origin`]), the field path (e.g.
    /// `objects[1] "sheet".generator.HexSheet.spacing`), the value and what
    /// is allowed. Returns the number of particles of each object.
    pub fn validate(&self, base_dir: Option<&Path>) -> Result<Vec<usize>, SceneError> {
        self.validate_estimated(base_dir).map(|(counts, _)| counts)
    }

    /// [`Scene::validate`], also returning the work estimate it checked
    /// against the limits ([`Scene::work_estimate`], made once: points
    /// files are read for it).
    ///
    /// # Errors
    ///
    /// As [`Scene::validate`].
    pub fn validate_estimated(
        &self,
        base_dir: Option<&Path>,
    ) -> Result<(Vec<usize>, WorkEstimate), SceneError> {
        let file = self.origin();
        self.validate_header(file)?;
        for (name, m) in &self.materials {
            let path = format!("materials.{name:?}");
            m.validate()
                .map_err(|e| SceneError::param(file, &path, e))?;
            validate_cohesion_scale(file, &path, m)?;
        }
        if self.objects.is_empty() {
            return Err(SceneError::invalid(
                file,
                "objects",
                "is empty: a scene needs at least one object",
            ));
        }
        let mut seen: HashMap<&str, usize> = HashMap::new();
        let mut counts = Vec::with_capacity(self.objects.len());
        let mut total = 0usize;
        for (k, o) in self.objects.iter().enumerate() {
            let path = object_path(k, &o.name);
            if let Some(first) = seen.insert(&o.name, k) {
                return Err(SceneError::invalid(
                    file,
                    format!("{path}.name"),
                    format!(
                        "duplicate object name (objects[{first}] has it too); names must be unique"
                    ),
                ));
            }
            let n = self.validate_object(o, &path, base_dir)?;
            total += n;
            if total > MAX_PARTICLES {
                return Err(SceneError::invalid(
                    file,
                    path,
                    format!("the scene has more than {MAX_PARTICLES} particles up to this object; that is the limit"),
                ));
            }
            counts.push(n);
        }
        for (k, f) in self.forces.iter().enumerate() {
            self.validate_force(k, f, &counts)?;
        }
        let estimate = self.validate_work(total, base_dir)?;
        for (k, t) in self.tools.iter().enumerate() {
            self.validate_tool(k, t)?;
        }
        for (k, f) in self.features.iter().enumerate() {
            let path = format!("features[{k}].{}", f.name());
            if let Some(first) = self.features[..k].iter().position(|g| g.name() == f.name()) {
                return Err(SceneError::invalid(
                    file,
                    path,
                    format!(
                        "{} is listed twice (features[{first}] has it too); each feature at most \
                         once: name all the objects it acts on in one entry",
                        f.name()
                    ),
                ));
            }
            f.feature().validate(self, &path)?;
        }
        if let Some(c) = &self.creation {
            c.validate(file)?;
            if let Some(fit) = &c.fit {
                fit.validate(self, c, file)?;
            }
        }
        Ok((counts, estimate))
    }

    fn validate_tool(&self, k: usize, t: &ToolSpec) -> Result<(), SceneError> {
        let file = self.origin();
        let path = format!("tools[{k}]");
        t.validate()
            .map_err(|e| SceneError::param(file, &path, e))?;
        if t.role.heating().is_some() && self.world.heat.is_none() {
            return Err(SceneError::value(
                file,
                format!("{path}.role"),
                format!("{:?}", t.role),
                "a heater or knife needs heat settings: add `heat: Some((conduction: 1, \
                 cooling: 0.1, ambient: 0))` to `world`",
            ));
        }
        self.check_object_names(&path, t.objects.as_deref())
    }

    /// Checks that every name in `names` is an object of the scene
    /// (`path.objects[j]` in messages): a tool's or a feature's `objects`.
    pub(crate) fn check_object_names(
        &self,
        path: &str,
        names: Option<&[String]>,
    ) -> Result<(), SceneError> {
        for (j, name) in names.into_iter().flatten().enumerate() {
            if !self.objects.iter().any(|o| &o.name == name) {
                return Err(SceneError::value(
                    self.origin(),
                    format!("{path}.objects[{j}]"),
                    format!("{name:?}"),
                    &format!(
                        "unknown object (defined objects: {})",
                        quoted(self.objects.iter().map(|o| &o.name))
                    ),
                ));
            }
        }
        Ok(())
    }

    fn validate_header(&self, file: &str) -> Result<(), SceneError> {
        let n = &self.name;
        if n.is_empty()
            || n == "."
            || n == ".."
            || n.chars().any(|c| c.is_control() || c == '/' || c == '\\')
        {
            return Err(SceneError::value(
                file,
                "name",
                format!("{n:?}"),
                "must be non-empty, without `/`, `\\` or control characters, and not `.` or `..` (it names the output folder)",
            ));
        }
        let w = &self.world;
        w.params(Vec::new())
            .validate(0)
            .map_err(|e| SceneError::param(file, "", e.renamed(WorldSettings::field_of_param)))?;
        if w.linear_damping.is_critical() && w.angular_damping != 0.0 {
            return Err(SceneError::value(
                file,
                "world.angular_damping",
                w.angular_damping,
                "with linear_damping: \"Critical\" the rule sets the angular damping too \
                 (β1 = 2 ω1 I, seed 002 §5): leave it out, or give both as numbers",
            ));
        }
        positive(file, "world.duration", w.duration)?;
        non_negative(file, "world.settle", w.settle)?;
        positive(file, "world.frame_rate", w.frame_rate)?;
        for (field, v) in [
            ("world.divergence.energy_growth", w.divergence.energy_growth),
            ("world.divergence.energy_gain", w.divergence.energy_gain),
            ("world.divergence.extent_growth", w.divergence.extent_growth),
        ] {
            if v.is_nan() || v <= 0.0 {
                return Err(SceneError::value(
                    file,
                    field,
                    v,
                    "must be > 0 (infinity disables the check)",
                ));
            }
        }
        positive(file, "outputs.glyph_size", self.outputs.glyph_size)?;
        positive(
            file,
            "outputs.triangulation_radius",
            self.outputs.triangulation_radius,
        )?;
        if let Some(v) = &self.outputs.view {
            direction(file, "outputs.view", v)?;
        }
        if let Some(u) = &self.outputs.up {
            direction(file, "outputs.up", u)?;
        }
        if let (Some(v), Some(u)) = (&self.outputs.view, &self.outputs.up) {
            let dot: Real = v.iter().zip(u).map(|(a, b)| a * b).sum();
            let norms = |x: &[Real; 3]| x.iter().map(|c| c * c).sum::<Real>().sqrt();
            if dot.abs() >= (1.0 - 1e-6) * norms(v) * norms(u) {
                return Err(SceneError::value(
                    file,
                    "outputs.up",
                    checks::fmt3(u),
                    "must not be parallel to outputs.view",
                ));
            }
        }
        Ok(())
    }

    /// Checks one object; returns its particle count.
    fn validate_object(
        &self,
        o: &ObjectSpec,
        path: &str,
        base_dir: Option<&Path>,
    ) -> Result<usize, SceneError> {
        let file = self.origin();
        let at = |field: &str| format!("{path}.{field}");
        if o.name.is_empty() || o.name.chars().any(char::is_control) {
            return Err(SceneError::value(
                file,
                at("name"),
                format!("{:?}", o.name),
                "must be non-empty, without control characters",
            ));
        }
        if !self.materials.contains_key(&o.material) {
            return Err(SceneError::value(
                file,
                at("material"),
                format!("{:?}", o.material),
                &format!(
                    "unknown material (defined materials: {}; presets: {})",
                    quoted(self.materials.keys()),
                    crate::presets::names()
                ),
            ));
        }
        positive(file, &at("mass"), o.mass)?;
        positive3(file, &at("inertia"), &o.inertia)?;
        direction(file, &at("normal_axis"), &o.normal_axis)?;
        finite3(file, &at("velocity"), &o.velocity)?;
        finite3(file, &at("angular_velocity"), &o.angular_velocity)?;
        let count = o.generator.count(base_dir, file, &at("generator"))?;
        if count == 0 {
            return Err(SceneError::invalid(
                file,
                at("generator"),
                "makes no particle: an object needs at least one",
            ));
        }
        match &o.velocities {
            None => {}
            Some(super::Velocities::Temperature { t, .. }) => {
                non_negative(file, &at("velocities.Temperature.t"), *t)?;
            }
            Some(super::Velocities::File(p)) => {
                let v =
                    crate::generators::read_velocities(base_dir, p, file, &at("velocities.File"))?;
                if v.len() != count {
                    return Err(SceneError::invalid(
                        file,
                        at("velocities.File"),
                        format!(
                            "holds {} velocities; the generator makes {count} particles",
                            v.len()
                        ),
                    ));
                }
            }
        }
        if let Some(skin) = &o.skin {
            skin.validate(file, &at("skin"))?;
        }
        for (j, ov) in o.overrides.iter().enumerate() {
            let op = format!("{path}.overrides[{j}]");
            ov.particles
                .check(count)
                .map_err(|m| SceneError::invalid(file, format!("{op}.particles"), m))?;
            if let Some(m) = ov.mass {
                positive(file, &format!("{op}.mass"), m)?;
            }
            if let Some(k) = ov.curvature {
                finite(file, &format!("{op}.curvature"), k)?;
            }
            if let Some(t) = ov.temperature {
                finite(file, &format!("{op}.temperature"), t)?;
            }
        }
        Ok(count)
    }

    fn validate_force(&self, k: usize, f: &ForceSpec, counts: &[usize]) -> Result<(), SceneError> {
        let file = self.origin();
        let path = format!("forces[{k}]");
        let at = |field: &str| format!("{path}.{field}");
        let Some(o) = self.objects.iter().position(|o| o.name == f.object) else {
            return Err(SceneError::value(
                file,
                at("object"),
                format!("{:?}", f.object),
                &format!(
                    "unknown object (defined objects: {})",
                    quoted(self.objects.iter().map(|o| &o.name))
                ),
            ));
        };
        f.particles
            .check(counts[o])
            .map_err(|m| SceneError::invalid(file, at("particles"), m))?;
        checks::finite3(file, &at("force"), &f.force)?;
        finite(file, &at("start"), f.start)?;
        if f.end.is_nan() || f.end <= f.start {
            return Err(SceneError::value(
                file,
                at("end"),
                f.end,
                &format!(
                    "must be greater than start = {} (or infinite)",
                    short(f.start)
                ),
            ));
        }
        let settle = self.world.settle;
        if f.end + settle <= f.start + settle {
            return Err(SceneError::value(
                file,
                "world.settle",
                settle,
                &format!(
                    "is too large for {path} (start {} and end {} become equal once shifted by the settle phase)",
                    short(f.start), short(f.end)
                ),
            ));
        }
        non_negative(file, &at("ramp"), f.ramp)?;
        let half: Real = 0.5 * (f.end - f.start);
        if f.ramp > half {
            return Err(SceneError::value(
                file,
                at("ramp"),
                f.ramp,
                &format!("must be at most half of end - start = {}", short(half)),
            ));
        }
        Ok(())
    }
}
