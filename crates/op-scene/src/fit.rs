//! Point-set interpolation with oriented particles (seed 000 §7, DESIGN §4
//! and §6 `opsim fit`).
//!
//! Entry point: [`fit`] with [`FitParams`]; [`write_obj`] writes the mesh.
//!
//! **Stages**, in units of the spacing `h` (every length below is a
//! multiple of `h`; the data are moved to their centroid and scaled by
//! `1/h`, so the material constants are those of a unit-spacing scene):
//!
//! 1. *Spacing*: `--spacing` or the median over the samples of the
//!    distance to the nearest other sample (robust to a few outliers).
//!    Samples within `h/4` of an earlier sample are merged into it (they
//!    would sit on top of each other as particles); all samples still count
//!    in the distance figures.
//! 2. *Normals*: from the file when it has them; otherwise by local PCA
//!    (the least-variance direction of the samples within `2.5 h`) and
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
    /// nearest-sample distance. Default: `None`.
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
    /// The particle world rejected a parameter.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The particle world failed (for example the relaxation diverged).
    #[error("the relaxation failed: {0}")]
    World(String),
}

impl From<WorldError> for FitError {
    fn from(e: WorldError) -> Self {
        FitError::World(e.to_string())
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

/// Fits a particle surface to `data` and triangulates it (see the module
/// documentation for the stages).
///
/// # Errors
/// Invalid parameters; fewer than 3 samples; a zero spacing estimate
/// (duplicate samples: pass a spacing); a sample whose normal cannot be
/// estimated (fewer than 2 neighbours within `2.5 h`: give normals in the
/// file); a relaxation that diverged.
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
    let centroid = data
        .positions
        .iter()
        .fold(Vec3::zeros(), |s, p| s + p.coords)
        / n as Real;
    let h = match params.spacing {
        Some(h) => h,
        None => median_nearest_distance(&data.positions)?,
    };
    // Unit-spacing coordinates.
    let unit: Vec<Point3> = data
        .positions
        .iter()
        .map(|p| Point3::from((p.coords - centroid) / h))
        .collect();
    let normals = match &data.normals {
        Some(v) => v.clone(),
        None => estimate_normals(&unit, 2.5)?,
    };
    let kept = merge_close(&unit, 0.25);
    let seeds: Vec<Point3> = kept.iter().map(|&k| unit[k]).collect();
    let seed_normals: Vec<Vec3> = kept.iter().map(|&k| normals[k]).collect();
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
    let mut world = World::new(particles, &[material], world_params)?;

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
    creation.max_particles = 20 * seeds.len() + 1000;
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

    // Triangulate and measure, back in data coordinates.
    let p = world.particles();
    let positions: Vec<Point3> = p
        .positions()
        .iter()
        .map(|q| Point3::from(q.coords * h + centroid))
        .collect();
    let pnormals: Vec<Vec3> = (0..p.len()).map(|s| p.normal(s)).collect();
    let mesh = SurfaceMesh::new(
        &positions,
        &pnormals,
        params.triangulation_radius * rest * h,
        &data.positions,
    )?;
    Ok(Fit {
        spacing: h,
        particles: positions.len(),
        mesh,
    })
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

/// Median over the points of the distance to the nearest other point.
pub(crate) fn median_nearest_distance(points: &[Point3]) -> Result<Real, FitError> {
    let (lo, hi) = points.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    );
    let diagonal = (hi - lo).norm();
    if diagonal.is_nan() || diagonal <= 0.0 {
        return Err(FitError::Input(
            "all samples coincide: no spacing can be estimated".into(),
        ));
    }
    // A surface of n samples at spacing h has an area of about n h²; start
    // at twice the size of a square patch's spacing and widen.
    let mut radius = 2.0 * diagonal / (points.len() as Real).sqrt();
    loop {
        let half = pairs(points, radius);
        let mut nearest = vec![Real::INFINITY; points.len()];
        for (i, j) in half.iter_pairs() {
            let d = (points[i] - points[j]).norm();
            nearest[i] = nearest[i].min(d);
            nearest[j] = nearest[j].min(d);
        }
        let found = nearest.iter().filter(|d| d.is_finite()).count();
        if 2 * found > points.len() || radius > diagonal {
            nearest.sort_by(|a, b| a.total_cmp(b));
            let h = nearest[points.len() / 2];
            if !(h.is_finite() && h > 0.0) {
                return Err(FitError::Input(format!(
                    "the median nearest-sample distance is {h} (duplicate samples?): pass --spacing"
                )));
            }
            return Ok(h);
        }
        radius *= 2.0;
    }
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
    if faces.is_empty() {
        return (Real::INFINITY, Real::INFINITY);
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
    let (mut sum, mut max) = (0.0, 0.0 as Real);
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
        sum += best * best;
        max = max.max(best);
    }
    ((sum / samples.len() as Real).sqrt(), max)
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
}
