//! Point-set interpolation with oriented particles (seed 000 §7, DESIGN §4
//! and §6 `opsim fit`).
//!
//! Entry point: [`fit`] with [`FitParams`]; [`write_obj`] writes the mesh.
//!
//! **Stages**, in units of the spacing `h` (every length below is a
//! multiple of `h`). The data are first mapped into the unit box (the
//! bounding box's centre to the origin, its largest half-side to 1, halving
//! first so that no step overflows), then moved to their centroid and
//! scaled by `1/h`: the material constants are those of a unit-spacing
//! scene, and data of any finite scale and offset fit alike (a sphere of
//! radius 1e-100 or 1e155 gives the unit sphere's mesh, scaled). The mesh
//! is triangulated and measured at unit spacing and mapped back.
//!
//! 1. *Spacing*: `--spacing` or the median over the distinct samples of the
//!    distance to the nearest other sample (robust to a few outliers; a
//!    k-d tree, O(n log n) for any distribution). A given spacing must lie
//!    between the spacing that would need [`MAX_PARTICLES`] particles
//!    (estimated as the distinct samples times `(median / h)²`) and the
//!    bounding box's diagonal ([`FitError::Spacing`]).
//!    Samples within `h/4` of an earlier sample are merged into it (they
//!    would sit on top of each other as particles); all samples still count
//!    in the distance figures.
//! 2. *Normals*: from the file when it has them; otherwise by local PCA
//!    (the least-variance direction of the merged samples within `2.5 h`) and
//!    oriented by propagation over that neighbour graph along its maximum
//!    spanning tree of `|n_i . n_j|` (Hoppe et al. 1992), started in each
//!    connected component at its sample of largest x with the normal's
//!    largest component made positive. On a closed smooth surface the
//!    normal at the sample of largest x is +x, so the normals are outward.
//! 3. *Seeds and filling* (seed 000 §7): one particle per sample, position
//!    and orientation fixed. Closed data: the stretching rule and the
//!    growing rule (interior gaps only: `max_gap` 170°, so nothing grows
//!    past an edge) add particles between the samples, each kept only
//!    within `d_max / √3` of a sample (the farthest a point of a triangle
//!    of samples at most `d_max` apart lies from its corners: growth never
//!    runs away from the data) and within `h / 2` of that sample's tangent
//!    plane (nor off it: [`DataNeighbourhood`]); open data (`--open`): stretching only, and
//!    a candidate is kept only within `d_max / 2` of a sample, so every gap
//!    up to the search range `d_max` closes and a gap wider than it keeps
//!    a hole. Rounds of creation
//!    alternate with short relaxations of the new (free) particles until a
//!    round creates nothing (at most [`FitParams::max_rounds`]).
//! 4. *Release* ([`release`]): the seeds are freed and the whole set relaxes for
//!    [`FitParams::relax_time`] with damping under cohesion (seed 002 §3)
//!    and co-circularity (seed 000 eq. 8). Co-circularity rather than
//!    co-planarity: both vanish on a plane, but co-circularity also
//!    vanishes on a sphere, so relaxing does not flatten curved data. The
//!    cohesion rest distance is the mean distance between samples and
//!    their first-ring neighbours (within `1.5 h`), so the data's own pairs
//!    start at rest and the released surface does not shrink; when fewer
//!    than half of the samples have such a neighbour (samples farther
//!    apart than the spacing, filled by creation), it is `h`: the few close
//!    pairs made it up to 1.45 h on unevenly spaced samples, and the rules,
//!    scaled by it, then created little.
//! 5. *Triangulation* (seed 000 §5, [`SurfaceMesh`]) with
//!    mutual-neighbour radius [`FitParams::triangulation_radius`] (`d_min`),
//!    and the figures: Euler characteristic, boundary loops, RMS and
//!    largest distance from the input samples to the mesh triangles.
//!
//! **Limits** (measured on 400 Fibonacci samples of the unit sphere,
//! median sample distance 0.168): with the estimated spacing nothing is
//! created and the mesh is closed (χ = 2); with `--spacing` 0.084, 0.09
//! and 0.1 (1 768, 1 628, 1 465 particles) χ = 2, the samples within
//! 0.003 (RMS) of the mesh. With 0.08 one hole remains (χ = 0): a quad of
//! particles with sides 1.75-1.9 h and diagonals 2.6 h, which neither rule
//! opens (sides below `d_min`, diagonals beyond `d_max`, 90° corners below
//! the growing rule's 100° `min_gap`). Until the triangulation radius was
//! raised from 1.7 to `d_min` (2.0), 0.08-0.1 all left 2-6 such holes
//! (χ -4 to -2), with diagonals between 1.7 and 2.0. Samples spread
//! unevenly (a blob along 260 Fibonacci directions, nearest samples
//! 1.5-1.9 h apart, `tests/fit.rs`) are filled (972 particles, sample RMS
//! 0.07 h) but keep holes and non-manifold edges (χ 4, 2 loops): the cohesion core is soft
//! (its repulsion vanishes as `exp(-α (r0 - r)²)` for `r` well below
//! `r0`), so created particles squeezed between fixed seeds merge (a pair
//! went from 0.93 to 0.07 h within 1.5 time units). Longer relaxation
//! does not close holes and lets the sphere drift (sample RMS 0.0022 at
//! `relax_time` 1, 0.018 at 10, for h = 0.08).
//!
//! **Refused inputs** ([`FitError::Input`]): fewer than 3 samples or 3
//! distinct ones (all coinciding), fewer than 3 left after merging, more
//! than [`MAX_PARTICLES`] distinct samples, samples all within `h/4` of one
//! line (collinear: no surface spans them), a spacing for which cohesion
//! has no valid cut-off (far coarser than the samples), and a fit that is
//! no surface: half of the samples or more farther than `h` from its
//! triangles (0 triangles; samples along a curve, such as a circle).
//!
//! **Bounded work**: at most [`MAX_PARTICLES`] (1 000 000) particles, of
//! which the filling rules create at most `20 × seeds + 1000`;
//! [`FitParams::max_rounds`] creation rounds of 50 steps and
//! `relax_time / 2e-3` relaxation steps.
//!
//! **Scenes**: [`DataNeighbourhood`] and [`release`] also serve a scene's
//! `creation.fit` ([`crate::schema::fit`]), which runs these stages
//! frame by frame (`scenes/fig_10_interpolation.ron`); spacing, material
//! and normals are then the scene's.
//!
//! Deterministic: every stage is (the creation rules and the world are
//! deterministic at any thread count; sums here are serial).

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};
use std::io::Write;
use std::path::Path;

use op_dynamics::creation::{CreationParams, GrowingParams, StretchingParams};
use op_dynamics::interactions::spacing::Spacing;
use op_dynamics::interactions::CohesionParams;
use op_dynamics::neighbours::{search, NeighbourBackend, PairList};
use op_dynamics::triangulation::{triangulate_points, Triangulation, TriangulationParams};
use op_dynamics::{
    ExternalParams, Flags, Material, ParamError, ParticleDesc, Particles, Point3, Real, Scheme,
    Vec3, World, WorldError, WorldParams,
};

use crate::pointsets::PointSet;

/// Settings of [`fit`]; lengths in units of the spacing unless said.
#[derive(Clone, Debug, PartialEq)]
pub struct FitParams {
    /// Sample spacing `h` (absolute length, > 0), or `None` for the median
    /// nearest-sample distance. [`fit`] refuses one above the diagonal of
    /// the samples' bounding box, or so small that the surface would need
    /// more than [`MAX_PARTICLES`] particles ([`FitError::Spacing`] gives
    /// the range). Default: `None`.
    pub spacing: Option<Real>,
    /// Open data: stretching only, holes wider than `d_max` stay. Default:
    /// false (closed data).
    pub open: bool,
    /// Stretching range `[d_min, d_max]` (the search range). Default:
    /// 2.0 and 2.5 (seed 000 §7).
    pub d_min: Real,
    /// See `d_min`.
    pub d_max: Real,
    /// Largest number of creation rounds. Default: 20.
    pub max_rounds: usize,
    /// Relaxation time after release (unit-spacing time units, >= 0).
    /// Default: 1.
    pub relax_time: Real,
    /// Mutual-neighbour radius of the triangulation, > 0; keep it at
    /// least `d_min`. Default: 2.0 (the default `d_min`): a pair closer
    /// than `d_min` is no gap for the stretching rule, so nothing is
    /// created between them and the triangulation must bridge them. With
    /// the 1.7 of sheets, holes whose diagonals fall between 1.7 and
    /// `d_min` (quads of sides 1.1-1.7 with 90° corners, which the growing
    /// rule's 100° `min_gap` does not fill either) stayed open.
    pub triangulation_radius: Real,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            spacing: None,
            open: false,
            d_min: 2.0,
            d_max: 2.5,
            max_rounds: 20,
            relax_time: 1.0,
            triangulation_radius: 2.0,
        }
    }
}

/// A fit could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// The parameters or the data are unusable; the message says why.
    #[error("{0}")]
    Input(String),
    /// The spacing is outside the range these samples allow (absolute
    /// lengths). Fix: give a spacing in `[min, max]`, or none.
    #[error(
        "spacing {value:e}: must be between {min:.3e} and {max:.3e} for these samples ({why})"
    )]
    Spacing {
        /// The spacing given.
        value: Real,
        /// The smallest spacing: below it the surface would need more
        /// than [`MAX_PARTICLES`] particles.
        min: Real,
        /// The largest spacing: the diagonal of the samples' bounding box.
        max: Real,
        /// Which bound it breaks.
        why: String,
    },
    /// The particle world rejected a parameter.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The particle world failed (for example the relaxation diverged).
    #[error("the relaxation failed: {0}")]
    World(String),
}

impl From<WorldError> for FitError {
    fn from(e: WorldError) -> Self {
        match e {
            WorldError::Param(p) => FitError::Param(p),
            e => FitError::World(e.to_string()),
        }
    }
}

/// The result of [`fit`]: the particles and their triangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The spacing used (absolute).
    pub spacing: Real,
    /// Number of particles (samples after merging, plus created ones).
    pub particles: usize,
    /// The triangulated particles, in data coordinates, and their
    /// distances to the input samples (absolute).
    pub mesh: SurfaceMesh,
}

impl FitParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), FitError> {
        let bad = |f: &str, v: Real, m: &str| Err(FitError::Input(format!("{f} = {v}: {m}")));
        if let Some(h) = self.spacing {
            if !(h.is_finite() && h > 0.0) {
                return bad("spacing", h, "must be finite and > 0");
            }
        }
        if !(self.d_min.is_finite() && self.d_min > 0.0) {
            return bad("d_min", self.d_min, "must be finite and > 0");
        }
        if !(self.d_max.is_finite() && self.d_max >= self.d_min) {
            return bad("d_max", self.d_max, "must be finite and >= d_min");
        }
        if !(self.relax_time.is_finite() && self.relax_time >= 0.0) {
            return bad("relax_time", self.relax_time, "must be finite and >= 0");
        }
        if !(self.triangulation_radius.is_finite() && self.triangulation_radius > 0.0) {
            return bad(
                "triangulation_radius",
                self.triangulation_radius,
                "must be finite and > 0",
            );
        }
        Ok(())
    }
}

/// Largest number of particles of a fit: the distinct samples, the
/// particles the spacing would need (estimated as the distinct samples
/// times `(median sample distance / spacing)²`), and the particles the
/// filling rules create are all bounded by it. With at most
/// [`FitParams::max_rounds`] creation rounds of 50 steps and
/// `relax_time / 2e-3` relaxation steps, this bounds a fit's work.
pub const MAX_PARTICLES: usize = 1_000_000;

/// Distance (in spacings) within which samples are merged, and below which
/// samples all within that distance of one line are collinear.
const MERGE: Real = 0.25;

/// The data frame: a sample `p` is `2 (centre + scale q)` with `q` in
/// `[-1, 1]³` (halves first, so no step overflows at any finite scale).
struct Frame {
    /// Half the bounding box's centre.
    centre: Vec3,
    /// Half the bounding box's largest side.
    scale: Real,
}

impl Frame {
    fn to_local(&self, p: &Point3) -> Point3 {
        Point3::from((p.coords * 0.5 - self.centre) / self.scale)
    }

    fn to_data(&self, q: &Point3) -> Point3 {
        Point3::from((self.centre + q.coords * self.scale) * 2.0)
    }

    fn length_to_data(&self, d: Real) -> Real {
        d * self.scale * 2.0
    }

    fn length_to_local(&self, d: Real) -> Real {
        d * 0.5 / self.scale
    }
}

/// Fits a particle surface to `data` and triangulates it (see the module
/// documentation for the stages).
///
/// The samples are first mapped to the unit box (any finite scale and
/// offset fit alike), then to unit spacing; the mesh is mapped back.
///
/// # Errors
/// [`FitError::Input`]: invalid parameters; fewer than 3 samples, or fewer
/// than 3 distinct ones (all coinciding), or fewer than 3 left after
/// merging at the spacing; a non-finite sample; more than
/// [`MAX_PARTICLES`] distinct samples; samples on a line (all within a
/// quarter spacing of it); a sample whose normal cannot be estimated
/// (fewer than 2 neighbours within `2.5 h`: give normals in the file); a
/// fit without a triangle; a mesh that cannot be represented at the data's
/// scale. [`FitError::Spacing`]: a spacing above the bounding box's
/// diagonal or needing more than [`MAX_PARTICLES`]. [`FitError::World`]: a
/// relaxation that diverged.
pub fn fit(data: &PointSet, params: &FitParams) -> Result<Fit, FitError> {
    params.validate()?;
    let n = data.positions.len();
    if n < 3 {
        return Err(FitError::Input(format!(
            "{n} samples: at least 3 are needed"
        )));
    }
    if let Some(normals) = &data.normals {
        if normals.len() != n {
            return Err(FitError::Input(format!(
                "{} normals for {n} samples",
                normals.len()
            )));
        }
    }
    if let Some(k) = data
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(FitError::Input(format!(
            "sample {} has a non-finite coordinate",
            k + 1
        )));
    }
    let (lo, hi) = data.positions.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    );
    let frame = Frame {
        centre: lo * 0.25 + hi * 0.25,
        scale: (hi * 0.5 - lo * 0.5).max(),
    };
    if lo == hi {
        return Err(FitError::Input(format!(
            "all {n} samples coincide at ({}, {}, {}): a surface needs samples spread over it",
            lo.x, lo.y, lo.z
        )));
    }
    if frame.scale == 0.0 {
        return Err(FitError::Input(format!(
            "the samples' bounding box ({:e} to {:e}) is too small to be represented once halved (subnormal coordinates): scale the samples up",
            lo.min(),
            hi.max()
        )));
    }
    let local: Vec<Point3> = data.positions.iter().map(|p| frame.to_local(p)).collect();
    // The bounding box's diagonal in local units (half the data's, over
    // the scale).
    let diagonal = (hi * 0.5 - lo * 0.5).map(|c| c / frame.scale).norm();

    // Spacing (in local units), bounded by the diagonal and the particle
    // limit.
    let distinct = distinct_points(&local);
    if distinct.len() < 3 {
        return Err(FitError::Input(format!(
            "the {n} samples are at {} distinct positions: at least 3 are needed",
            distinct.len()
        )));
    }
    if distinct.len() > MAX_PARTICLES {
        return Err(FitError::Input(format!(
            "{} distinct samples: at most {MAX_PARTICLES} can be fitted",
            distinct.len()
        )));
    }
    let median = median_of(nearest_distances(&distinct));
    let smallest = median * (distinct.len() as Real / MAX_PARTICLES as Real).sqrt();
    let h = match params.spacing {
        None => median,
        Some(value) => {
            let h = frame.length_to_local(value);
            let range = |why: String| FitError::Spacing {
                value,
                min: frame.length_to_data(smallest),
                max: frame.length_to_data(diagonal),
                why,
            };
            if h > diagonal {
                return Err(range(
                    "it exceeds the diagonal of the samples' bounding box".into(),
                ));
            }
            if h < smallest {
                let needed = distinct.len() as Real * (median / h).powi(2);
                let needed = if needed.is_finite() {
                    format!("about {needed:.3e}")
                } else {
                    "more than 1e308".into()
                };
                return Err(range(format!(
                    "below {:.3e} the surface would need more than the limit of {MAX_PARTICLES} particles: {needed} at this spacing",
                    frame.length_to_data(smallest)
                )));
            }
            h
        }
    };
    let spacing = match params.spacing {
        Some(value) => value,
        None => frame.length_to_data(h),
    };
    // Unit-spacing coordinates about the samples' centroid.
    let centroid = local.iter().fold(Vec3::zeros(), |s, p| s + p.coords) / n as Real;
    let unit: Vec<Point3> = local
        .iter()
        .map(|p| Point3::from((p.coords - centroid) / h))
        .collect();
    if let Some(off) = collinear_within(&unit, MERGE) {
        return Err(FitError::Input(format!(
            "the samples lie on a line (all within {:.3e} of it, less than a quarter of the spacing {spacing:.3e}): a surface needs samples spread in two directions",
            frame.length_to_data(off * h)
        )));
    }
    let kept = merge_close(&unit, MERGE);
    if kept.len() < 3 {
        return Err(FitError::Input(format!(
            "{} samples are left after merging those within a quarter of the spacing {spacing:.3e}: at least 3 are needed (give a smaller spacing)",
            kept.len()
        )));
    }
    let seeds: Vec<Point3> = kept.iter().map(|&k| unit[k]).collect();
    let seed_normals: Vec<Vec3> = match &data.normals {
        Some(v) => kept.iter().map(|&k| v[k]).collect(),
        None => estimate_normals(&seeds, 2.5)?,
    };
    let rest = first_ring_mean(&seeds, 1.5);

    let material = Material {
        spacing: Some(Spacing::Cohesion(CohesionParams {
            r0: rest,
            cutoff: Some(1.5 * rest),
            ..CohesionParams::default()
        })),
        cocircularity: 5.0,
        ..Material::empty()
    };
    let world_params = WorldParams {
        scheme: Scheme::VelocityVerlet,
        dt: 2e-3,
        external: ExternalParams {
            linear_damping: 2.0,
            angular_damping: 0.2,
            ..ExternalParams::default()
        },
        ..WorldParams::default()
    };
    let mut particles = Particles::new();
    for (p, nrm) in seeds.iter().zip(&seed_normals) {
        let mut d = ParticleDesc::at(*p).with_normal(*nrm);
        d.flags = Flags::FIXED_POSITION.union(Flags::FIXED_ORIENTATION);
        particles.push(d)?;
    }
    let mut world = World::new(particles, &[material], world_params).map_err(|e| {
        FitError::Input(format!(
            "the spacing {spacing:.3e} does not suit these samples: {e} (the cohesion rest distance is the mean distance between neighbouring samples, {rest:.3} spacings; give a spacing near the median distance between samples, {:.3e})",
            frame.length_to_data(median)
        ))
    })?;

    // Filling rounds (seed 000 §7).
    let mut creation = CreationParams::new(rest);
    creation.stretching = Some(StretchingParams {
        d_min: params.d_min,
        d_max: params.d_max,
        reach: (0.6 * params.d_max).max(1.5),
        ..StretchingParams::default()
    });
    if !params.open {
        creation.growing = Some(GrowingParams {
            max_gap: 170f64.to_radians(),
            ..GrowingParams::default()
        });
    }
    creation.max_particles = (20 * seeds.len() + 1000).min(MAX_PARTICLES);
    let near = DataNeighbourhood::new(&seeds, &seed_normals, rest, params.d_max, params.open);
    for _ in 0..params.max_rounds {
        let mut descs = creation.candidates(world.particles())?;
        descs.retain(|d| near.contains(&d.position));
        if descs.is_empty() {
            break;
        }
        world.insert_particles(&descs)?;
        advance(&mut world, 0.1)?;
    }

    // Release (the seeds are the first ids) and relax.
    let seed_ids: Vec<u32> = (0..seeds.len() as u32).collect();
    release(&mut world, &seed_ids)?;
    advance(&mut world, params.relax_time)?;

    // Triangulate and measure at unit spacing, then map back.
    let p = world.particles();
    let pnormals: Vec<Vec3> = (0..p.len()).map(|s| p.normal(s)).collect();
    let mut mesh = SurfaceMesh::new(
        p.positions(),
        &pnormals,
        params.triangulation_radius * rest,
        &unit,
    )?;
    // A surface covers its samples: most lie within a spacing of it.
    let covered = sample_distances(&unit, &mesh.vertices, &mesh.faces)
        .iter()
        .filter(|&&d| d <= 1.0)
        .count();
    if 2 * covered <= n {
        return Err(FitError::Input(format!(
            "no surface: the {} particles grown from {} samples at spacing {spacing:.3e} gave {} triangle(s), within one spacing of only {covered} of the {n} samples (samples along a curve, or a spacing too coarse for them: the median distance between samples is {:.3e})",
            p.len(),
            seeds.len(),
            mesh.faces.len(),
            frame.length_to_data(median)
        )));
    }
    let to_data = |q: &Point3| frame.to_data(&Point3::from(q.coords * h + centroid));
    mesh.vertices.iter_mut().for_each(|v| *v = to_data(v));
    mesh.rms_distance = frame.length_to_data(mesh.rms_distance * h);
    mesh.max_distance = frame.length_to_data(mesh.max_distance * h);
    if !(mesh
        .vertices
        .iter()
        .all(|v| v.iter().all(|c| c.is_finite()))
        && mesh.max_distance.is_finite())
    {
        return Err(FitError::Input(format!(
            "the mesh cannot be represented in 64-bit floating point at the samples' scale (bounding box diagonal {:.3e})",
            frame.length_to_data(diagonal)
        )));
    }
    Ok(Fit {
        spacing,
        particles: p.len(),
        mesh,
    })
}

/// The bits of a point's coordinates (`-0` as `+0`): equal for equal
/// points.
fn bits(p: &Point3) -> [u64; 3] {
    [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits())
}

/// The points of `points` without exact repeats (first occurrence kept, in
/// order).
fn distinct_points(points: &[Point3]) -> Vec<Point3> {
    let keys: Vec<[u64; 3]> = points.iter().map(bits).collect();
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| keys[a].cmp(&keys[b]).then(a.cmp(&b)));
    let mut keep = vec![false; points.len()];
    for (k, &i) in order.iter().enumerate() {
        keep[i] = k == 0 || keys[order[k - 1]] != keys[i];
    }
    (0..points.len())
        .filter(|&i| keep[i])
        .map(|i| points[i])
        .collect()
}

/// The median of `v` (not empty).
fn median_of(mut v: Vec<Real>) -> Real {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Whether the points all lie within `tolerance` of one line (the
/// principal axis through their mean): their largest distance from it if
/// so.
fn collinear_within(points: &[Point3], tolerance: Real) -> Option<Real> {
    let mean = points.iter().fold(Vec3::zeros(), |s, p| s + p.coords) / points.len() as Real;
    let mut cov = op_dynamics::Mat3::zeros();
    for p in points {
        let d = p.coords - mean;
        cov += d * d.transpose();
    }
    let eig = cov.symmetric_eigen();
    let (k, _) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))?;
    let axis = eig.eigenvectors.column(k).normalize();
    let off = points
        .iter()
        .map(|p| {
            let d = p.coords - mean;
            (d - axis * axis.dot(&d)).norm()
        })
        .fold(0.0, Real::max);
    (off <= tolerance).then_some(off)
}

/// For each of the (distinct) `points`, the distance to its nearest other
/// point, by a k-d tree (each node split at the median of its widest
/// axis): O(n log n) for any distribution.
fn nearest_distances(points: &[Point3]) -> Vec<Real> {
    let mut index: Vec<usize> = (0..points.len()).collect();
    let mut axes = vec![0u8; points.len()];
    build_kd(points, &mut index, &mut axes);
    let tree = KdTree {
        points,
        index: &index,
        axes: &axes,
    };
    (0..points.len())
        .map(|i| {
            let mut best = Real::INFINITY;
            tree.nearest(0, points.len(), &points[i], i, &mut best);
            best
        })
        .collect()
}

/// Orders `index` as an implicit k-d tree: the median of each range at its
/// middle, split on the axis stored at the same place of `axes`.
fn build_kd(points: &[Point3], index: &mut [usize], axes: &mut [u8]) {
    if index.len() <= 1 {
        return;
    }
    let (lo, hi) = index.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), &i| (lo.inf(&points[i].coords), hi.sup(&points[i].coords)),
    );
    let axis = (hi - lo).imax();
    let mid = index.len() / 2;
    index.select_nth_unstable_by(mid, |&a, &b| points[a][axis].total_cmp(&points[b][axis]));
    axes[mid] = axis as u8;
    let (left, right) = index.split_at_mut(mid);
    let (left_axes, right_axes) = axes.split_at_mut(mid);
    build_kd(points, left, left_axes);
    build_kd(points, &mut right[1..], &mut right_axes[1..]);
}

/// An implicit k-d tree over `points` built by [`build_kd`].
struct KdTree<'a> {
    points: &'a [Point3],
    index: &'a [usize],
    axes: &'a [u8],
}

impl KdTree<'_> {
    /// Lowers `best` to the distance from `q` to the nearest point of the
    /// range `start..end` other than the point `skip`.
    fn nearest(&self, start: usize, end: usize, q: &Point3, skip: usize, best: &mut Real) {
        if start >= end {
            return;
        }
        let mid = start + (end - start) / 2;
        let i = self.index[mid];
        if i != skip {
            *best = best.min((self.points[i] - q).norm());
        }
        if end - start == 1 {
            return;
        }
        let axis = self.axes[mid] as usize;
        let diff = q[axis] - self.points[i][axis];
        let (near, far) = if diff < 0.0 {
            ((start, mid), (mid + 1, end))
        } else {
            ((mid + 1, end), (start, mid))
        };
        self.nearest(near.0, near.1, q, skip, best);
        if diff.abs() < *best {
            self.nearest(far.0, far.1, q, skip, best);
        }
    }
}

/// A triangulated particle surface (seed 000 §5) and its distance to the
/// data it interpolates: what [`fit`] reports, and what the fit scenes'
/// figure tests measure on a run's final particles.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMesh {
    /// Mesh vertices: the particles used by some triangle.
    pub vertices: Vec<Point3>,
    /// Unit normals of the vertices (the particle normals).
    pub normals: Vec<Vec3>,
    /// Triangles as indices into `vertices`, wound along the normals.
    pub faces: Vec<[u32; 3]>,
    /// `V - E + F` of the mesh.
    pub euler_characteristic: i64,
    /// Number of boundary loops of the mesh.
    pub boundary_loops: usize,
    /// RMS distance from the samples to the triangles (infinite without
    /// a triangle).
    pub rms_distance: Real,
    /// Largest distance from a sample to the triangles.
    pub max_distance: Real,
}

impl SurfaceMesh {
    /// Triangulates particles at `positions` with unit `normals`
    /// ([`triangulate_points`], mutual-neighbour distance `radius`) and
    /// measures the distances from `samples` to the triangles.
    ///
    /// # Errors
    /// An invalid radius (not finite or not > 0).
    pub fn new(
        positions: &[Point3],
        normals: &[Vec3],
        radius: Real,
        samples: &[Point3],
    ) -> Result<Self, FitError> {
        let triangles = triangulate_points(
            positions,
            normals,
            &TriangulationParams::with_radius(radius),
        )?;
        let mesh = Triangulation {
            triangles: triangles.clone(),
        };
        let mut index = vec![u32::MAX; positions.len()];
        let mut vertices = Vec::new();
        let mut normals_out = Vec::new();
        let faces: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    let v = v as usize;
                    if index[v] == u32::MAX {
                        index[v] = vertices.len() as u32;
                        vertices.push(positions[v]);
                        normals_out.push(normals[v]);
                    }
                    index[v]
                })
            })
            .collect();
        let (rms_distance, max_distance) = distances(samples, &vertices, &faces);
        Ok(SurfaceMesh {
            euler_characteristic: mesh.euler_characteristic(),
            boundary_loops: mesh.boundary_loops(),
            vertices,
            normals: normals_out,
            faces,
            rms_distance,
            max_distance,
        })
    }
}

/// Where the filling rules of a fit may create particles (seed 000 §7):
/// near the data, so growth never runs away from it. A candidate is kept
/// within `reach` of a sample and within half a spacing of that sample's
/// tangent plane; `reach` is `d_max / 2` spacings for open data (every gap
/// up to the search range `d_max` closes, a wider one keeps a hole) and
/// `d_max / √3` for closed data (the farthest a point of a triangle of
/// samples at most `d_max` apart lies from its corners).
#[derive(Clone, Debug)]
pub struct DataNeighbourhood {
    grid: Grid,
    seeds: Vec<Point3>,
    normals: Vec<Vec3>,
    reach: Real,
    tolerance: Real,
}

impl DataNeighbourhood {
    /// The neighbourhood of the samples `seeds` with unit `normals`, for
    /// spacing `r0` and a search range `d_max` (in units of `r0`).
    pub fn new(seeds: &[Point3], normals: &[Vec3], r0: Real, d_max: Real, open: bool) -> Self {
        let reach = d_max * r0 * if open { 0.5 } else { 1.0 / 3f64.sqrt() };
        DataNeighbourhood {
            grid: Grid::new(seeds, reach),
            seeds: seeds.to_vec(),
            normals: normals.to_vec(),
            reach,
            tolerance: 0.5 * r0,
        }
    }

    /// Whether a particle may be created at `p`.
    pub fn contains(&self, p: &Point3) -> bool {
        self.grid
            .nearest_within(p, self.reach)
            .is_some_and(|s| self.normals[s].dot(&(p - self.seeds[s])).abs() <= self.tolerance)
    }
}

/// A fit running in a scene (`creation.fit`, [`crate::schema::fit`]): the
/// creation rules act only in [`SceneFit::near`] and only before
/// [`SceneFit::release_time`], when the seeds are freed.
#[derive(Clone, Debug)]
pub struct SceneFit {
    /// Index of the object holding the samples.
    pub object: usize,
    /// Where particles may be created.
    pub near: DataNeighbourhood,
    /// World time of the release (after the settle phase, if any).
    pub release_time: Real,
    /// True once the seeds were released.
    pub released: bool,
}

/// Releases the seeds (seed 000 §7): the particles with the given ids are
/// removed and inserted again with their fixed flags cleared, at rest, in
/// the order given (op-dynamics fixes a particle's flags when it is
/// inserted). Returns their new ids, in the order of `ids`.
///
/// # Errors
/// An id that names no live particle (nothing is changed then).
pub fn release(world: &mut World, ids: &[u32]) -> Result<Vec<u32>, WorldError> {
    let p = world.particles();
    let mut descs = Vec::with_capacity(ids.len());
    for &id in ids {
        let Some(s) = p.slot_of(id) else {
            return Err(WorldError::from(ParamError::Invalid {
                field: "ids".into(),
                message: format!("particle id {id} does not exist"),
            }));
        };
        let mut d = ParticleDesc::at(p.positions()[s]);
        d.orientation = p.orientations()[s];
        d.mass = p.masses()[s];
        d.inertia = p.inertias()[s];
        d.normal_axis = p.normal_axes()[s];
        d.object = p.objects()[s];
        d.kind = p.kinds()[s];
        d.material = p.materials()[s];
        d.curvature = p.curvatures()[s];
        let mut flags = p.flags()[s];
        flags.remove(Flags::FIXED_POSITION);
        flags.remove(Flags::FIXED_ORIENTATION);
        d.flags = flags;
        descs.push(d);
    }
    world.remove_particles(ids)?;
    world.insert_particles(&descs)
}

/// Advances `world` by `t` (a divergence is an error).
fn advance(world: &mut World, t: Real) -> Result<(), FitError> {
    let end = world.time() + t;
    world
        .advance_to(end)
        .map_err(|d| FitError::World(d.to_string()))
}

/// Half pair list of `points` within `radius`.
fn pairs(points: &[Point3], radius: Real) -> PairList {
    let mut half = PairList::new();
    search(NeighbourBackend::CellList, points, radius, &mut half);
    half
}

/// Median over the points of the distance to the nearest other point (0
/// for a point with a duplicate), by a k-d tree over the distinct points.
pub(crate) fn median_nearest_distance(points: &[Point3]) -> Result<Real, FitError> {
    let distinct = distinct_points(points);
    if distinct.len() < 2 {
        return Err(FitError::Input(
            "all samples coincide: no spacing can be estimated".into(),
        ));
    }
    let nearest = nearest_distances(&distinct);
    let mut count: HashMap<[u64; 3], usize> = HashMap::new();
    for p in points {
        *count.entry(bits(p)).or_default() += 1;
    }
    let all: Vec<Real> = distinct
        .iter()
        .zip(nearest)
        .flat_map(|(p, d)| {
            let k = count.get(&bits(p)).copied().unwrap_or(1);
            std::iter::once(if k > 1 { 0.0 } else { d }).chain(std::iter::repeat_n(0.0, k - 1))
        })
        .collect();
    let h = median_of(all);
    if !(h.is_finite() && h > 0.0) {
        return Err(FitError::Input(format!(
            "the median nearest-sample distance is {h} (duplicate samples?): pass a spacing"
        )));
    }
    Ok(h)
}

/// Indices of the points kept when each point within `dist` of an earlier
/// kept point is merged into it.
fn merge_close(points: &[Point3], dist: Real) -> Vec<usize> {
    let mut grid = Grid::new(&[], dist);
    let mut kept = Vec::new();
    for (k, p) in points.iter().enumerate() {
        if grid.nearest_within(p, dist).is_none() {
            grid.insert(*p);
            kept.push(k);
        }
    }
    kept
}

/// Mean distance between points and their neighbours within `ring`, when
/// at least half of the points have one; otherwise 1 (the points are
/// farther apart than the unit spacing, and the few close pairs would bias
/// the mean up to `ring`).
fn first_ring_mean(points: &[Point3], ring: Real) -> Real {
    let half = pairs(points, ring);
    let mut has = vec![false; points.len()];
    let (sum, count) = half.iter_pairs().fold((0.0, 0usize), |(s, c), (i, j)| {
        has[i] = true;
        has[j] = true;
        (s + (points[i] - points[j]).norm(), c + 1)
    });
    if 2 * has.iter().filter(|&&h| h).count() < points.len() {
        1.0
    } else {
        sum / count as Real
    }
}

/// Unit normals by local PCA over the points within `radius`, oriented by
/// propagation along the maximum spanning tree of `|n_i . n_j|`.
pub(crate) fn estimate_normals(points: &[Point3], radius: Real) -> Result<Vec<Vec3>, FitError> {
    let n = points.len();
    let half = pairs(points, radius);
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, j) in half.iter_pairs() {
        rows[i].push(j);
        rows[j].push(i);
    }
    rows.iter_mut().for_each(|r| r.sort_unstable());
    let mut normals = Vec::with_capacity(n);
    for (i, row) in rows.iter().enumerate() {
        if row.len() < 2 {
            return Err(FitError::Input(format!(
                "sample {} has {} neighbours within {radius} spacings: cannot estimate its normal (give normals in the file, or a larger spacing)",
                i + 1,
                row.len()
            )));
        }
        let mean = row
            .iter()
            .fold(points[i].coords, |s, &j| s + points[j].coords)
            / (row.len() + 1) as Real;
        let mut cov = op_dynamics::Mat3::zeros();
        for &k in std::iter::once(&i).chain(row) {
            let d = points[k].coords - mean;
            cov += d * d.transpose();
        }
        let eig = cov.symmetric_eigen();
        let (k, _) = eig
            .eigenvalues
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1).then(a.0.cmp(&b.0)))
            .unwrap_or((0, &0.0));
        normals.push(eig.eigenvectors.column(k).normalize());
    }
    // Orientation: Prim's maximum spanning tree from each component's
    // sample of largest x (ties by index).
    let mut done = vec![false; n];
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].x.total_cmp(&points[a].x).then(a.cmp(&b)));
    for &start in &order {
        if done[start] {
            continue;
        }
        let s = normals[start];
        let big = (0..3)
            .max_by(|&a, &b| s[a].abs().total_cmp(&s[b].abs()).then(b.cmp(&a)))
            .unwrap_or(0);
        if s[big] < 0.0 {
            normals[start] = -s;
        }
        done[start] = true;
        let mut heap = BinaryHeap::new();
        let push = |heap: &mut BinaryHeap<Edge>, normals: &[Vec3], i: usize| {
            for &j in &rows[i] {
                heap.push(Edge {
                    weight: normals[i].dot(&normals[j]).abs(),
                    from: i,
                    to: j,
                });
            }
        };
        push(&mut heap, &normals, start);
        while let Some(e) = heap.pop() {
            if done[e.to] {
                continue;
            }
            done[e.to] = true;
            if normals[e.from].dot(&normals[e.to]) < 0.0 {
                normals[e.to] = -normals[e.to];
            }
            push(&mut heap, &normals, e.to);
        }
    }
    Ok(normals)
}

/// An edge of the orientation graph, ordered by weight then indices.
#[derive(PartialEq)]
struct Edge {
    weight: Real,
    from: usize,
    to: usize,
}

impl Eq for Edge {}

impl Ord for Edge {
    fn cmp(&self, other: &Self) -> Ordering {
        self.weight
            .total_cmp(&other.weight)
            .then(other.from.cmp(&self.from))
            .then(other.to.cmp(&self.to))
    }
}

impl PartialOrd for Edge {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// A hash grid of points for "is there one within `cell`" queries.
#[derive(Clone, Debug)]
struct Grid {
    cell: Real,
    map: HashMap<[i64; 3], Vec<(Point3, usize)>>,
    len: usize,
}

impl Grid {
    fn new(points: &[Point3], cell: Real) -> Self {
        let mut g = Grid {
            cell,
            map: HashMap::new(),
            len: 0,
        };
        points.iter().for_each(|p| g.insert(*p));
        g
    }

    fn key(&self, p: &Point3) -> [i64; 3] {
        [p.x, p.y, p.z].map(|c| (c / self.cell).floor() as i64)
    }

    /// Inserts `p` with the next index (0, 1, ...).
    fn insert(&mut self, p: Point3) {
        let k = self.key(&p);
        self.map.entry(k).or_default().push((p, self.len));
        self.len += 1;
    }

    /// The index of the nearest point within `dist` (at most the cell
    /// size) of `p` (the smallest index among equals).
    fn nearest_within(&self, p: &Point3, dist: Real) -> Option<usize> {
        let k = self.key(p);
        let mut best: Option<(Real, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(v) = self.map.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                        continue;
                    };
                    for &(q, i) in v {
                        let d = (q - p).norm();
                        if d <= dist && best.is_none_or(|(b, j)| d < b || (d == b && i < j)) {
                            best = Some((d, i));
                        }
                    }
                }
            }
        }
        best.map(|(_, q)| q)
    }
}

/// RMS and largest distance from `samples` to the triangles (infinite when
/// there is no triangle).
fn distances(samples: &[Point3], vertices: &[Point3], faces: &[[u32; 3]]) -> (Real, Real) {
    let d = sample_distances(samples, vertices, faces);
    let sum: Real = d.iter().map(|x| x * x).sum();
    (
        (sum / samples.len() as Real).sqrt(),
        d.into_iter().fold(0.0, Real::max),
    )
}

/// Distance from each of `samples` to the triangles (infinite when there is
/// no triangle).
fn sample_distances(samples: &[Point3], vertices: &[Point3], faces: &[[u32; 3]]) -> Vec<Real> {
    if faces.is_empty() {
        return vec![Real::INFINITY; samples.len()];
    }
    // Triangles binned by their bounding boxes in a grid of the longest
    // edge; a sample looks in its cell's 27 cells first, all triangles when
    // that finds none.
    let cell = faces
        .iter()
        .flat_map(|f| {
            (0..3)
                .map(move |k| (vertices[f[k] as usize] - vertices[f[(k + 1) % 3] as usize]).norm())
        })
        .fold(0.0, Real::max)
        .max(1e-12);
    let key = |p: &Vec3| [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64);
    let mut bins: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (t, f) in faces.iter().enumerate() {
        let c = f
            .iter()
            .fold(Vec3::zeros(), |s, &v| s + vertices[v as usize].coords)
            / 3.0;
        bins.entry(key(&c)).or_default().push(t);
    }
    let tri_distance = |p: &Point3, t: usize| {
        let f = faces[t];
        point_triangle_distance(
            p,
            &vertices[f[0] as usize],
            &vertices[f[1] as usize],
            &vertices[f[2] as usize],
        )
    };
    let mut out = Vec::with_capacity(samples.len());
    for p in samples {
        let k = key(&p.coords);
        let mut best = Real::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = bins.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &t in v {
                            best = best.min(tri_distance(p, t));
                        }
                    }
                }
            }
        }
        // A triangle whose centroid is outside the 27 cells has it at least
        // `cell` from p, and its points within 2/3 of its longest edge
        // (<= cell) of the centroid: at least `cell / 3` from p. Below
        // that the nearest found is exact; otherwise check all.
        if best > cell / 3.0 {
            best = (0..faces.len())
                .map(|t| tri_distance(p, t))
                .fold(best, Real::min);
        }
        out.push(best);
    }
    out
}

/// Distance from `p` to the triangle `abc` (closest point by region,
/// Ericson, Real-Time Collision Detection §5.1.5).
pub fn point_triangle_distance(p: &Point3, a: &Point3, b: &Point3, c: &Point3) -> Real {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm();
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).norm();
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).norm();
    }
    let denom = va + vb + vc;
    if denom == 0.0 || denom.is_nan() {
        // Degenerate triangle: the nearest of its edges' end points.
        return ap.norm().min(bp.norm()).min(cp.norm());
    }
    let v = vb / denom;
    let w = vc / denom;
    (p - (a + ab * v + ac * w)).norm()
}

/// Writes the mesh as OBJ (`v`, `vn`, `f v//vn`), atomically.
pub fn write_obj(path: &Path, fit: &Fit) -> std::io::Result<()> {
    let mesh = &fit.mesh;
    crate::export::write_atomically(path, |w: &mut dyn Write| {
        writeln!(
            w,
            "# opsim fit: {} vertices, {} faces, spacing {}",
            mesh.vertices.len(),
            mesh.faces.len(),
            fit.spacing
        )?;
        for v in &mesh.vertices {
            writeln!(w, "v {} {} {}", v.x, v.y, v.z)?;
        }
        for n in &mesh.normals {
            writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
        }
        for f in &mesh.faces {
            let [a, b, c] = f.map(|k| k + 1);
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_triangle_distance_regions() {
        let (a, b, c) = (
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        );
        let d =
            |x: Real, y: Real, z: Real| point_triangle_distance(&Point3::new(x, y, z), &a, &b, &c);
        assert!((d(0.2, 0.2, 0.5) - 0.5).abs() < 1e-12);
        assert!((d(-1.0, -1.0, 0.0) - 2f64.sqrt()).abs() < 1e-12);
        assert!((d(0.5, -2.0, 0.0) - 2.0).abs() < 1e-12);
        assert!((d(1.0, 1.0, 0.0) - 0.5f64.sqrt()).abs() < 1e-12);
        assert!((d(3.0, 0.0, 4.0) - 20f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn median_spacing_of_a_grid() {
        let pts: Vec<Point3> = (0..100)
            .map(|k| Point3::new((k % 10) as Real * 0.3, (k / 10) as Real * 0.3, 0.0))
            .collect();
        assert!((median_nearest_distance(&pts).unwrap() - 0.3).abs() < 1e-12);
    }

    #[test]
    fn pca_normals_of_a_plane_are_oriented_consistently() {
        let pts: Vec<Point3> = (0..100)
            .map(|k| {
                Point3::new(
                    (k % 10) as Real,
                    (k / 10) as Real,
                    0.01 * ((k * 7) % 3) as Real,
                )
            })
            .collect();
        let n = estimate_normals(&pts, 2.5).unwrap();
        assert!(n.iter().all(|v| v.z > 0.99), "{n:?}");
    }

    /// Pseudo-random points (a fixed LCG) in a box of side `size`.
    fn scattered(n: usize, size: Real) -> Vec<Point3> {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as Real / (1u64 << 53) as Real * size
        };
        (0..n)
            .map(|_| Point3::new(next(), next(), next()))
            .collect()
    }

    /// The k-d tree's nearest distances equal brute force, also on planar
    /// data (ties on one axis) and with a far outlier.
    #[test]
    fn kd_tree_nearest_distances_match_brute_force() {
        let mut sets = vec![scattered(500, 1.0)];
        let mut plane = scattered(300, 1.0);
        plane.iter_mut().for_each(|p| p.z = 0.0);
        sets.push(plane);
        let mut outlier = scattered(100, 1e-3);
        outlier.push(Point3::new(1e3, 0.0, 0.0));
        sets.push(outlier);
        for pts in sets {
            let fast = nearest_distances(&pts);
            for (i, p) in pts.iter().enumerate() {
                let slow = pts
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, q)| (q - p).norm())
                    .fold(Real::INFINITY, Real::min);
                assert_eq!(fast[i], slow, "point {i}");
            }
        }
    }

    /// Duplicates count as nearest distance 0 in the scene's spacing
    /// estimate; `-0` equals `+0`; all coincident is an error.
    #[test]
    fn distinct_points_and_duplicates() {
        let pts = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(-0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(3.0, 0.0, 0.0),
        ];
        assert_eq!(distinct_points(&pts).len(), 3);
        // Nearest: 0, 0, 1, 2: median (index 2 of 4) is 1.
        assert_eq!(median_nearest_distance(&pts).unwrap(), 1.0);
        let same = vec![Point3::new(1.0, 2.0, 3.0); 5];
        assert!(median_nearest_distance(&same).is_err());
    }

    #[test]
    fn collinear_samples_are_detected() {
        let line: Vec<Point3> = (0..20)
            .map(|k| Point3::new(k as Real, 2.0 * k as Real, 0.1 * ((k % 2) as Real)))
            .collect();
        let off = collinear_within(&line, 0.25).expect("collinear");
        assert!(off > 0.04 && off < 0.06, "{off}");
        let grid: Vec<Point3> = (0..20)
            .map(|k| Point3::new((k % 10) as Real, (k / 10) as Real, 0.0))
            .collect();
        assert!(collinear_within(&grid, 0.25).is_none());
    }

    /// A spacing is bounded by the diagonal and by the particle limit, and
    /// the error names both bounds.
    #[test]
    fn spacing_out_of_range_is_an_error_with_the_range() {
        let data = PointSet {
            positions: scattered(200, 1.0)
                .into_iter()
                .map(|p| Point3::from(p.coords.normalize()))
                .collect(),
            normals: None,
        };
        for h in [1e300, 10.0, 1e-5, 1e-300] {
            let params = FitParams {
                spacing: Some(h),
                ..FitParams::default()
            };
            match fit(&data, &params) {
                Err(FitError::Spacing {
                    value, min, max, ..
                }) => {
                    assert_eq!(value, h);
                    assert!(
                        min > 1e-4 && min < 1e-2 && max > 1.5 && max <= 3f64.sqrt(),
                        "{min} {max} (the samples' box is within [0, 1]³)"
                    );
                }
                other => panic!("spacing {h}: {other:?}"),
            }
        }
    }

    /// Degenerate data: coincident, too few distinct, collinear, a curve
    /// (no surface); each a clear input error, none a panic or a mesh.
    #[test]
    fn degenerate_samples_are_input_errors() {
        let fit_of = |positions: Vec<Point3>| {
            fit(
                &PointSet {
                    positions,
                    normals: None,
                },
                &FitParams::default(),
            )
        };
        let message = |r: Result<Fit, FitError>| match r {
            Err(FitError::Input(m)) => m,
            other => panic!("{other:?}"),
        };
        let m = message(fit_of(vec![Point3::new(1.0, 2.0, 3.0); 10]));
        assert!(m.contains("all 10 samples coincide"), "{m}");
        let mut two = vec![Point3::origin(); 5];
        two.push(Point3::new(1.0, 0.0, 0.0));
        let m = message(fit_of(two));
        assert!(m.contains("2 distinct positions"), "{m}");
        let line = (0..30).map(|k| Point3::new(k as Real, 0.0, 0.0)).collect();
        let m = message(fit_of(line));
        assert!(m.contains("lie on a line"), "{m}");
        let circle = (0..63)
            .map(|k| Point3::new((0.1 * k as Real).cos(), (0.1 * k as Real).sin(), 0.0))
            .collect();
        let m = message(fit_of(circle));
        assert!(m.starts_with("no surface"), "{m}");
        let bad = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, Real::INFINITY, 0.0),
        ];
        let m = message(fit_of(bad));
        assert!(m.contains("sample 3"), "{m}");
        let tiny = vec![
            Point3::origin(),
            Point3::new(5e-324, 0.0, 0.0),
            Point3::new(0.0, 5e-324, 0.0),
        ];
        let m = message(fit_of(tiny));
        assert!(m.contains("too small to be represented"), "{m}");
    }
}
