//! Particle generators: where an object's particles start, with their world
//! normals and rest curvatures (the `generator` field of an object).
//!
//! Every generator returns a [`Generated`] set: positions, unit world
//! normals and rest curvatures `κ` of the form term (seed 002 §4). The
//! builder orients each particle by the shortest rotation taking the
//! object's body `normal_axis` to the generated normal
//! ([`op_dynamics::ParticleDesc::with_normal`]).
//!
//! **Curvature sign convention.** The form term has zero energy when the
//! centre of curvature of particle `i` is `p_i - n_i / κ_i`: on a circle of
//! radius `1/κ` with outward normals. Generators with curvature
//! (spiral, sphere and torus shells) therefore emit *outward* normals and
//! positive curvature for convex shapes.

mod points;
mod shapes;
mod solid;

use std::path::{Path, PathBuf};

use op_dynamics::{Point3, Real, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::schema::checks;

pub use points::resolve;
pub(crate) use shapes::{sphere_count, torus_estimate};
pub(crate) use solid::solid_ball_estimate;

/// Largest number of particles a scene may generate (all objects
/// together). Larger requests are rejected before anything is allocated.
pub const MAX_PARTICLES: usize = 10_000_000;

/// Particles made by a generator: positions, unit world normals and rest
/// curvatures, all of the same length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Generated {
    /// Positions.
    pub positions: Vec<Point3>,
    /// Unit world normals.
    pub normals: Vec<Vec3>,
    /// Rest curvatures `κ` (0 = flat).
    pub curvatures: Vec<Real>,
}

impl Generated {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when no particle was generated.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
}

/// One explicit particle of [`Generator::List`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ListParticle {
    /// Position. Required.
    pub position: [Real; 3],
    /// World normal (normalized; non-zero). Default: +z.
    #[serde(default)]
    #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
    pub normal: Option<[Real; 3]>,
    /// Rest curvature. Default: 0.
    #[serde(default)]
    pub curvature: Option<Real>,
}

fn zero3() -> [Real; 3] {
    [0.0; 3]
}
fn plus_x() -> [Real; 3] {
    [1.0, 0.0, 0.0]
}
fn plus_z() -> [Real; 3] {
    [0.0, 0.0, 1.0]
}

/// How the rest curvature of a [`Generator::Spiral`] varies along it, from
/// `curvature_start` at the first particle to `curvature_end` at the last.
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum CurvatureLaw {
    /// Linear in arc length: `κ(s) = κ_start + (κ_end - κ_start) s/L`.
    #[default]
    Linear,
    /// Geometric in arc length: `κ(s) = κ_start (κ_end/κ_start)^(s/L)`
    /// (a constant relative growth per unit length, as along a logarithmic
    /// spiral). Both curvatures must be nonzero and of the same sign.
    Geometric,
    /// Quadratic in arc length, flat at the start:
    /// `κ(s) = κ_start + (κ_end - κ_start) (s/L)²`.
    Quadratic,
    /// A quarter sine in arc length, steepest at the start and flat at the
    /// end: `κ(s) = κ_start + (κ_end - κ_start) sin(π s / 2L)`.
    Sine,
}

/// How an object's particles are made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub enum Generator {
    /// A planar curve integrated in arc length, `θ'(s) = κ(s)`, with the
    /// curvature going from `curvature_start` to `curvature_end` along the
    /// curve by `law` (linear by default; each particle's rest curvature is
    /// its analytic `κ_i`). Positive curvature turns left about `normal`; particle
    /// normals lie in the plane, `n = t × normal` (`t` the tangent), which
    /// points away from the centre of curvature where `κ > 0` (the centre
    /// is `p_i - n_i/κ_i` for either sign). Its centroid is `center`.
    ///
    /// The total turning is `(κ_start + κ_end)/2 · (count-1) spacing`;
    /// more than one turn (2π) makes successive turns come close and
    /// interact, which is rarely what is wanted. The analytic shape is
    /// close to, not exactly at, the rest shape of the form term (docs/model.md
    /// §7): settle first if a reference is needed.
    Spiral {
        /// Number of particles, >= 2.
        #[schemars(range(min = 2, max = MAX_PARTICLES))]
        count: usize,
        /// Arc length between neighbours, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Real,
        /// Curvature of the first particle (1/length, finite,
        /// `|curvature_start| * spacing <= 1`: at most one radian of turning
        /// between neighbours).
        curvature_start: Real,
        /// Curvature of the last particle (1/length, finite,
        /// `|curvature_end| * spacing <= 1`).
        curvature_end: Real,
        /// How the curvature varies in between. Default: `Linear`.
        #[serde(default)]
        law: CurvatureLaw,
        /// Centroid. Default: origin.
        #[serde(default = "zero3")]
        center: [Real; 3],
        /// Normal of the plane of the curve. Default: +z.
        #[serde(default = "plus_z")]
        #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
        normal: [Real; 3],
    },
    /// A hexagonal lattice of `nx` x `ny` particles (rows `spacing √3/2`
    /// apart, odd rows shifted half a spacing), centroid at `center`,
    /// normals all equal to the sheet normal, curvature 0.
    ///
    /// The sheet is `(nx - 1/2) spacing` wide (`(nx - 1) spacing` for one
    /// row) and `(ny - 1) spacing √3/2` long, so `nx = ny` is not square
    /// (20 x 20 at spacing 1: 19.5 x 16.5); a square sheet takes
    /// `ny ≈ 1.155 nx` ([`Generator::sheet_extent`]; `opsim check` prints
    /// the extent of a sheet that is not square).
    HexSheet {
        /// Particles per row, >= 1.
        #[schemars(range(min = 1, max = MAX_PARTICLES))]
        nx: usize,
        /// Rows, >= 1.
        #[schemars(range(min = 1, max = MAX_PARTICLES))]
        ny: usize,
        /// Distance between neighbours, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Real,
        /// Centroid (before noise). Default: origin.
        #[serde(default = "zero3")]
        center: [Real; 3],
        /// Sheet normal. Default: +z.
        #[serde(default = "plus_z")]
        #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
        normal: [Real; 3],
        /// Amplitude (length) of a uniform random displacement in
        /// `[-noise, noise]` along each of the sheet's three axes, in
        /// `[0, spacing/4]` (so particles never coincide). Default: 0.
        #[serde(default)]
        #[schemars(range(min = 0))]
        noise: Real,
        /// Seed of the noise. Default: 0.
        #[serde(default)]
        seed: u64,
    },
    /// `count` particles on a line from `start` along `direction`,
    /// `spacing` apart, all with the given normal, curvature 0.
    Chain {
        /// Number of particles, >= 1.
        #[schemars(range(min = 1, max = MAX_PARTICLES))]
        count: usize,
        /// Distance between neighbours, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Real,
        /// First particle. Default: origin.
        #[serde(default = "zero3")]
        start: [Real; 3],
        /// Direction of the line (normalized). Default: +x.
        #[serde(default = "plus_x")]
        #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
        direction: [Real; 3],
        /// Normal of every particle (normalized). Default: +z.
        #[serde(default = "plus_z")]
        #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
        normal: [Real; 3],
    },
    /// A Fibonacci sphere: `round(4πR² / (√3/2 spacing²))` particles (the
    /// count of a hexagonal lattice of that spacing covering the area),
    /// outward normals, curvature `1/radius`.
    SphereShell {
        /// Radius, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: Real,
        /// Target distance between neighbours, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Real,
        /// Centre. Default: origin.
        #[serde(default = "zero3")]
        center: [Real; 3],
    },
    /// A solid ball: the face-centred cubic packing (every interior
    /// particle has twelve neighbours at `spacing`, the next ones at
    /// `spacing √2`) of the points within `radius` of the centre, about
    /// `4/3 π (radius/spacing)³ √2` particles. Normals point away from the
    /// centre, curvature 0. Give its material a spacing cut-off (or bond
    /// radius) between `spacing` and `spacing √2`, so that each particle
    /// keeps the same twelve partners: an elastic solid.
    SolidBall {
        /// Radius, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: Real,
        /// Distance between nearest neighbours, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Real,
        /// Centre (a particle sits there). Default: origin.
        #[serde(default = "zero3")]
        center: [Real; 3],
    },
    /// A ring torus about `axis`: rings of constant tube angle `v` about
    /// `spacing √3/2` apart, each holding about `2π(R + r cos v)/spacing`
    /// particles, alternate rings shifted half a step. Outward normals;
    /// rest curvature is the **mean curvature**
    /// `H = (R + 2r cos v) / (2r (R + r cos v))` (`1/r` and `cos v/(R + r
    /// cos v)` averaged; negative on the inner side when `r < R < 2r`,
    /// positive elsewhere). The form term holds one isotropic curvature,
    /// so a torus is only approximately at rest.
    TorusShell {
        /// Major radius `R` (axis to tube centre), > minor.
        #[schemars(extend("exclusiveMinimum" = 0))]
        major: Real,
        /// Minor (tube) radius `r`, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        minor: Real,
        /// Target distance between neighbours, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Real,
        /// Centre. Default: origin.
        #[serde(default = "zero3")]
        center: [Real; 3],
        /// Axis of revolution. Default: +z.
        #[serde(default = "plus_z")]
        #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
        axis: [Real; 3],
    },
    /// Points read from a file by [`crate::pointsets::read_point_set`]'s
    /// reader: `.xyz` text (`x y z [nx ny nz]` per line, normals for every
    /// point or none, `#` comments, blank lines skipped; CGAL's `.pwn` is
    /// the same text), `.ply` (ascii or
    /// binary little-endian) or `.obj` (`v` / `vn` lines). Normals default
    /// to +z (a fit estimates them instead: [`crate::schema::fit`]),
    /// curvature 0.
    Points {
        /// The file, relative to the scene file's directory (or absolute).
        path: PathBuf,
    },
    /// Explicit particles.
    List {
        /// The particles (at least one).
        #[schemars(length(min = 1, max = MAX_PARTICLES))]
        particles: Vec<ListParticle>,
    },
}

impl Generator {
    /// The variant name, as written in scene files (`"Spiral"`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Generator::Spiral { .. } => "Spiral",
            Generator::HexSheet { .. } => "HexSheet",
            Generator::Chain { .. } => "Chain",
            Generator::SphereShell { .. } => "SphereShell",
            Generator::SolidBall { .. } => "SolidBall",
            Generator::TorusShell { .. } => "TorusShell",
            Generator::Points { .. } => "Points",
            Generator::List { .. } => "List",
        }
    }

    /// The width (along its rows) and length (across them) of a
    /// [`Generator::HexSheet`] before noise; `None` for other generators.
    pub fn sheet_extent(&self) -> Option<(Real, Real)> {
        match self {
            Generator::HexSheet {
                nx, ny, spacing, ..
            } => {
                let shift = if *ny > 1 { 0.5 } else { 0.0 };
                Some((
                    (nx.saturating_sub(1) as Real + shift) * spacing,
                    ny.saturating_sub(1) as Real * spacing * 3f64.sqrt() / 2.0,
                ))
            }
            _ => None,
        }
    }

    /// The nominal distance between neighbours, when the generator has one.
    pub fn nominal_spacing(&self) -> Option<Real> {
        match self {
            Generator::Spiral { spacing, .. }
            | Generator::HexSheet { spacing, .. }
            | Generator::Chain { spacing, .. }
            | Generator::SphereShell { spacing, .. }
            | Generator::SolidBall { spacing, .. }
            | Generator::TorusShell { spacing, .. } => Some(*spacing),
            Generator::Points { .. } | Generator::List { .. } => None,
        }
    }

    /// Checks the parameters without generating (a points file must exist,
    /// it is not read). `file` names the scene in messages, `path` is the
    /// generator's field path (e.g. `objects[0] "sheet".generator`).
    pub fn validate(
        &self,
        base_dir: Option<&Path>,
        file: &str,
        path: &str,
    ) -> Result<(), SceneError> {
        let at = |field: &str| format!("{path}.{}.{field}", self.name());
        match self {
            Generator::Spiral {
                count,
                spacing,
                curvature_start,
                curvature_end,
                law,
                center,
                normal,
            } => check_spiral(
                file,
                &at,
                *count,
                *spacing,
                (*curvature_start, *curvature_end),
                *law,
                center,
                normal,
            ),
            Generator::HexSheet {
                nx,
                ny,
                spacing,
                center,
                normal,
                noise,
                seed: _,
            } => check_hex_sheet(file, &at, (*nx, *ny), *spacing, center, normal, *noise),
            Generator::Chain {
                count,
                spacing,
                start,
                direction,
                normal,
            } => check_chain(file, &at, *count, *spacing, start, direction, normal),
            Generator::SphereShell {
                radius,
                spacing,
                center,
            } => check_sphere_shell(file, &at, *radius, *spacing, center),
            Generator::SolidBall {
                radius,
                spacing,
                center,
            } => check_ball(
                file,
                &at,
                *radius,
                *spacing,
                center,
                solid::solid_ball_estimate(*radius, *spacing),
            ),
            Generator::TorusShell {
                major,
                minor,
                spacing,
                center,
                axis,
            } => check_torus(file, &at, (*major, *minor), *spacing, center, axis),
            Generator::Points { path: p } => {
                let resolved = resolve(base_dir, p);
                if resolved.is_file() {
                    Ok(())
                } else {
                    Err(points::missing(file, &at("path"), p, &resolved))
                }
            }
            Generator::List { particles } => check_list(file, &at, particles),
        }
    }

    /// Number of particles it makes (validates first; reads a points file).
    pub fn count(
        &self,
        base_dir: Option<&Path>,
        file: &str,
        path: &str,
    ) -> Result<usize, SceneError> {
        self.validate(base_dir, file, path)?;
        Ok(match self {
            Generator::Spiral { count, .. } | Generator::Chain { count, .. } => *count,
            Generator::HexSheet { nx, ny, .. } => nx * ny,
            Generator::SphereShell {
                radius, spacing, ..
            } => shapes::sphere_count(*radius, *spacing) as usize,
            Generator::SolidBall {
                radius, spacing, ..
            } => solid::solid_ball_count(*radius, *spacing),
            Generator::TorusShell {
                major,
                minor,
                spacing,
                ..
            } => shapes::torus_rings(*major, *minor, *spacing)
                .iter()
                .map(|r| r.1)
                .sum(),
            Generator::Points { .. } => self.generate(base_dir, file, path)?.len(),
            Generator::List { particles } => particles.len(),
        })
    }

    /// Whether the generated normals are the shape's own: false only for a
    /// points file without normals (whose particles face +z). Reads the
    /// file.
    pub fn has_normals(
        &self,
        base_dir: Option<&Path>,
        file: &str,
        path: &str,
    ) -> Result<bool, SceneError> {
        match self {
            Generator::Points { path: p } => {
                Ok(read_points(p, base_dir, file, path)?.normals.is_some())
            }
            _ => Ok(true),
        }
    }

    /// Makes the particles (validates first). A points file that holds no
    /// point is an error.
    pub fn generate(
        &self,
        base_dir: Option<&Path>,
        file: &str,
        path: &str,
    ) -> Result<Generated, SceneError> {
        self.validate(base_dir, file, path)?;
        Ok(match self {
            Generator::Spiral {
                count,
                spacing,
                curvature_start,
                curvature_end,
                law,
                center,
                normal,
            } => shapes::spiral(
                *count,
                *spacing,
                (*curvature_start, *curvature_end, *law),
                center,
                normal,
            ),
            Generator::HexSheet {
                nx,
                ny,
                spacing,
                center,
                normal,
                noise,
                seed,
            } => shapes::hex_sheet(&shapes::HexSheet {
                nx: *nx,
                ny: *ny,
                spacing: *spacing,
                center,
                normal,
                noise: *noise,
                seed: *seed,
            }),
            Generator::Chain {
                count,
                spacing,
                start,
                direction,
                normal,
            } => shapes::chain(*count, *spacing, start, direction, normal),
            Generator::SphereShell {
                radius,
                spacing,
                center,
            } => shapes::sphere_shell(
                shapes::sphere_count(*radius, *spacing) as usize,
                *radius,
                center,
            ),
            Generator::SolidBall {
                radius,
                spacing,
                center,
            } => solid::solid_ball(*radius, *spacing, center),
            Generator::TorusShell {
                major,
                minor,
                spacing,
                center,
                axis,
            } => shapes::torus_shell(*major, *minor, *spacing, center, axis),
            Generator::Points { path: p } => {
                let at = format!("{path}.Points.path");
                let g = points::generated(read_points(p, base_dir, file, path)?);
                if g.is_empty() {
                    return Err(SceneError::value(
                        file,
                        at,
                        format!("{:?}", p.display().to_string()),
                        "the points file holds no point (an object needs at least one particle)",
                    ));
                }
                g
            }
            Generator::List { particles } => points::list(particles),
        })
    }
}

/// Checks a [`Generator::Chain`]: count within [`MAX_PARTICLES`],
/// positive spacing, finite start, direction and normal usable as
/// directions ([`checks::direction`]).
fn check_chain(
    file: &str,
    at: &dyn Fn(&str) -> String,
    count: usize,
    spacing: Real,
    start: &[Real; 3],
    direction: &[Real; 3],
    normal: &[Real; 3],
) -> Result<(), SceneError> {
    let max = MAX_PARTICLES;
    if count < 1 || count > max {
        return Err(SceneError::value(
            file,
            at("count"),
            count,
            &format!("must be in 1..={max}"),
        ));
    }
    checks::positive(file, &at("spacing"), spacing)?;
    checks::finite3(file, &at("start"), start)?;
    checks::direction(file, &at("direction"), direction)?;
    checks::direction(file, &at("normal"), normal)
}

/// Checks a [`Generator::SphereShell`]: as [`check_ball`], and a spacing
/// that puts at least one particle on the sphere.
fn check_sphere_shell(
    file: &str,
    at: &dyn Fn(&str) -> String,
    radius: Real,
    spacing: Real,
    center: &[Real; 3],
) -> Result<(), SceneError> {
    let n = shapes::sphere_count(radius, spacing);
    check_ball(file, at, radius, spacing, center, n)?;
    if n < 1.0 {
        return Err(SceneError::value(
            file,
            at("spacing"),
            spacing,
            &format!(
                "gives no particle on a sphere of radius {radius}; must be below {:.4}",
                radius * (16.0 * std::f64::consts::PI / 3f64.sqrt()).sqrt()
            ),
        ));
    }
    Ok(())
}

/// Checks a [`Generator::List`] (`at` gives a field's path).
fn check_list(
    file: &str,
    at: &dyn Fn(&str) -> String,
    particles: &[ListParticle],
) -> Result<(), SceneError> {
    let max = MAX_PARTICLES;
    if particles.is_empty() {
        return Err(SceneError::invalid(
            file,
            at("particles"),
            "is empty: give at least one particle",
        ));
    }
    if particles.len() > max {
        return Err(SceneError::invalid(
            file,
            at("particles"),
            format!("at most {max} particles"),
        ));
    }
    points::validate_list(particles, file, &at("particles"))
}

/// Checks a [`Generator::Spiral`] (`at` gives a field's path).
#[allow(clippy::too_many_arguments)]
fn check_spiral(
    file: &str,
    at: &dyn Fn(&str) -> String,
    count: usize,
    spacing: Real,
    (curvature_start, curvature_end): (Real, Real),
    law: CurvatureLaw,
    center: &[Real; 3],
    normal: &[Real; 3],
) -> Result<(), SceneError> {
    let max = MAX_PARTICLES;
    if count < 2 || count > max {
        return Err(SceneError::value(
            file,
            at("count"),
            count,
            &format!("must be in 2..={max}"),
        ));
    }
    checks::positive(file, &at("spacing"), spacing)?;
    for (name, k) in [
        ("curvature_start", &curvature_start),
        ("curvature_end", &curvature_end),
    ] {
        checks::finite(file, &at(name), *k)?;
        if k.abs() * spacing > 1.0 {
            return Err(SceneError::value(
                file,
                at(name),
                k,
                &format!(
                    "turns the curve by more than one radian between neighbours: |curvature| * spacing must be <= 1, so |curvature| <= {}",
                    1.0 / spacing
                ),
            ));
        }
    }
    if law == CurvatureLaw::Geometric && curvature_start * curvature_end <= 0.0 {
        return Err(SceneError::value(
            file,
            at("law"),
            "Geometric",
            &format!(
                "needs curvature_start and curvature_end nonzero and of the same sign (they are {curvature_start} and {curvature_end})"
            ),
        ));
    }
    checks::finite3(file, &at("center"), center)?;
    checks::direction(file, &at("normal"), normal)
}

/// Checks a [`Generator::HexSheet`] (`at` gives a field's path).
fn check_hex_sheet(
    file: &str,
    at: &dyn Fn(&str) -> String,
    (nx, ny): (usize, usize),
    spacing: Real,
    center: &[Real; 3],
    normal: &[Real; 3],
    noise: Real,
) -> Result<(), SceneError> {
    let max = MAX_PARTICLES;
    for (name, n) in [("nx", nx), ("ny", ny)] {
        if n < 1 {
            return Err(SceneError::value(
                file,
                at(name),
                n,
                "must be >= 1 (an empty sheet has no particle)",
            ));
        }
    }
    if nx.checked_mul(ny).is_none_or(|n| n > max) {
        return Err(SceneError::invalid(
            file,
            at("nx"),
            format!("nx * ny = {nx} * {ny} particles; at most {max} are allowed"),
        ));
    }
    checks::positive(file, &at("spacing"), spacing)?;
    checks::finite3(file, &at("center"), center)?;
    checks::direction(file, &at("normal"), normal)?;
    if !(noise.is_finite() && noise >= 0.0 && noise <= 0.25 * spacing) {
        return Err(SceneError::value(
            file,
            at("noise"),
            noise,
            &format!("must be in [0, spacing/4] = [0, {}]", 0.25 * spacing),
        ));
    }
    Ok(())
}

/// Checks a [`Generator::TorusShell`] (`at` gives a field's path).
fn check_torus(
    file: &str,
    at: &dyn Fn(&str) -> String,
    (major, minor): (Real, Real),
    spacing: Real,
    center: &[Real; 3],
    axis: &[Real; 3],
) -> Result<(), SceneError> {
    let max = MAX_PARTICLES;
    checks::positive(file, &at("minor"), minor)?;
    checks::positive(file, &at("major"), major)?;
    if major <= minor {
        return Err(SceneError::value(
            file,
            at("major"),
            major,
            &format!("must be greater than minor = {minor} (a ring torus)"),
        ));
    }
    checks::positive(file, &at("spacing"), spacing)?;
    checks::finite3(file, &at("center"), center)?;
    checks::direction(file, &at("axis"), axis)?;
    let n = shapes::torus_estimate(major, minor, spacing);
    checks::count_at_most(file, &at("spacing"), n, max, "these radii and spacing")?;
    Ok(())
}

/// Checks a sphere or ball generator: positive `radius` and `spacing`, a
/// finite `center`, and at most [`MAX_PARTICLES`] particles (`count`, the
/// generator's estimate); `at` names a field.
fn check_ball(
    file: &str,
    at: &dyn Fn(&str) -> String,
    radius: Real,
    spacing: Real,
    center: &[Real; 3],
    count: Real,
) -> Result<(), SceneError> {
    checks::positive(file, &at("radius"), radius)?;
    checks::positive(file, &at("spacing"), spacing)?;
    checks::finite3(file, &at("center"), center)?;
    let limit = MAX_PARTICLES;
    checks::count_at_most(
        file,
        &at("spacing"),
        count,
        limit,
        "this radius and spacing",
    )?;
    Ok(())
}

/// The velocities file `p` of [`crate::schema::Velocities::File`] at field
/// path `path`: its points, as vectors, finite.
pub(crate) fn read_velocities(
    base_dir: Option<&Path>,
    p: &Path,
    file: &str,
    path: &str,
) -> Result<Vec<op_dynamics::Vec3>, SceneError> {
    let set = points::read_points(&resolve(base_dir, p), file, path, p, MAX_PARTICLES)?;
    let v: Vec<op_dynamics::Vec3> = set.positions.iter().map(|q| q.coords).collect();
    if let Some(k) = v.iter().position(|x| !x.iter().all(|c| c.is_finite())) {
        return Err(SceneError::invalid(
            file,
            path,
            format!("velocity {k} is not finite"),
        ));
    }
    Ok(v)
}

/// The points file `p` of a `Points` generator at field path `path`.
fn read_points(
    p: &Path,
    base_dir: Option<&Path>,
    file: &str,
    path: &str,
) -> Result<crate::pointsets::PointSet, SceneError> {
    let at = format!("{path}.Points.path");
    points::read_points(&resolve(base_dir, p), file, &at, p, MAX_PARTICLES)
}
