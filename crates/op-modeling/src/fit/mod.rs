//! Point-set interpolation with oriented particles (seed 000 §7
//! and §6 `opsim fit`).
//!
//! Entry point: [`fit`] with [`FitParams`] (op-scene's `fit::write_obj`
//! writes the mesh, `opsim fit` reads the samples from files).
//!
//! **Stages**, in units of the spacing `h` (every length below is a
//! multiple of `h`). The data are first mapped into the unit box (the
//! bounding box's centre to the origin, its largest half-side to 1, halving
//! first so that no step overflows), then moved to their centroid and
//! scaled by `1/h`: the material constants are those of a unit-spacing
//! scene, and data of any finite scale and offset fit alike (a sphere of
//! radius 1e-100 or 1e155 gives the unit sphere's mesh, scaled). The mesh
//! is triangulated and measured at unit spacing and mapped back. The
//! samples are taken in Morton order (`locality.rs`): every stage queries
//! each sample's neighbours in sample order, and neighbours in space are
//! then neighbours in memory (a million random torus samples: 63 s in
//! their given order, 37 s in this one).
//!
//! 0. *Outliers and noise*: samples off their neighbours' surface, alone
//!    above a smooth patch of it or isolated in space are dropped
//!    (`outliers.rs`: statistical outlier
//!    removal, Rusu et al. 2008, with robust thresholds that keep uneven
//!    density, sharp edges and thin parts; [`FitParams::drop_outliers`],
//!    [`Fit::dropped_outliers`]); the rest are checked and mapped anew
//!    (their own bounding box) and every figure below is theirs. Their
//!    noise level is estimated from local quadric fits (`noise.rs`,
//!    [`Fit::noise_estimate`]). Samples whose noise exceeds a tenth of
//!    their spacing ([`FitParams::approximate`]), unless their spread is
//!    in layers (two sides of a thin part, with no samples between them)
//!    or detail (it grows over wider neighbourhoods, where noise stays),
//!    and samples so uneven that their sparse parts need more than 2.5
//!    times the default spacing (`uneven.rs`: a density step, scan lines;
//!    thinned to that spacing) are approximated rather
//!    than interpolated (`denoise.rs`, [`Fit::approximated`]): they are
//!    thinned to at least four noise levels apart and each kept one is
//!    moved onto a local quadric fit of its nearest samples (moving least
//!    squares, Levin 1998); the stages below run on these smoothed seeds,
//!    and the mesh's distances are still measured to the samples. Measured
//!    on 20,000 random samples of the ellipsoid and torus of [`shapes`]
//!    with Gaussian noise of 0.25%, 0.5% and 1% of the diagonal: one
//!    closed piece of the right Euler characteristic each (interpolated:
//!    up to 48 pieces), mesh vertices 0.4-1.9 per mille of the diagonal
//!    off the true surface, 0.17-0.2 noise levels (`reports/fitting.md`).
//! 1. *Spacing*: `--spacing` or 0.8 times the median over the distinct
//!    samples of the distance to the 6th nearest other sample (a local
//!    density, robust to uneven and random sampling and to a few
//!    outliers; kiddo k-d tree, O(n log n)). A given spacing must lie
//!    between the spacing that would need [`MAX_PARTICLES`] particles
//!    (estimated as the distinct samples times `(median / h)²`) and the
//!    bounding box's diagonal ([`FitError::Spacing`]).
//!    Samples within `h/4` of an earlier sample are merged into it (they
//!    would sit on top of each other as particles); all samples still count
//!    in the distance figures.
//! 2. *Normals*: from the file when it has them; otherwise
//!    by local PCA over the [`FitParams::neighbours`] nearest merged
//!    samples (kiddo k-d tree; independent of the spacing, no sample is
//!    refused for lack of neighbours) and oriented by propagation along
//!    the minimum spanning tree of `1 - |n_i . n_j|` over the symmetric
//!    k-nearest-neighbour graph (Hoppe et al. 1992 §3.3), started in each
//!    connected component at its sample of largest z with the normal made
//!    to point along +z. On a closed smooth surface the normal at the
//!    sample of largest z is +z, so the normals are outward.
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
//!    alternate with short relaxations (0.1 time units) of the new (free)
//!    particles until a round creates nothing (at most
//!    [`FitParams::max_rounds`]); a round relaxes only the new particles
//!    and the created ones within the cohesion cut-off of them, in a world
//!    of their own with the particles around them held fixed (`rounds.rs`),
//!    so its cost follows what it creates, not the surface's size.
//! 4. *Release* ([`release`]): the seeds are freed and the whole set relaxes for
//!    [`FitParams::relax_time`] (default 0: the samples are interpolated;
//!    a time smooths noisy samples) with damping under cohesion (seed 002 §3)
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
//!    the two sides of a feature thinner than that radius kept apart by
//!    their normals (no triangle joins particles facing more than 90°
//!    apart, nor does a particle facing away from a triangle empty it:
//!    [`crate::triangulation::TriangulationParams::separate_sides`]),
//!    and the figures: Euler characteristic, boundary loops, RMS and
//!    largest distance from the input samples to the mesh triangles.
//!    The samples' *thin features* (`thin.rs`: two sides within that
//!    radius, facing each other) are named in [`Fit::thin_features`].
//! 6. *Holes* (`holes.rs`): after the triangulation, the holes (boundary
//!    loops) narrower than [`FitParams::max_hole`] spacings (closed data)
//!    or, for open data, the wider of `d_max` (the stretching search
//!    range) and the widest gap uniformly random sampling leaves by chance
//!    at the samples' density (Miles 1970; 4.7 spacings on 5,000 samples)
//!    are closed with triangles, a new vertex at the centre of a large
//!    one; edges held by more than two triangles are dropped first, so
//!    every edge ends in at most two triangles, and the triangles are
//!    wound consistently, those of an edge where no winding agrees (a
//!    Möbius band across a thin rim) dropped so that the cut is filled as
//!    a hole. Pinched vertices (two fans
//!    meeting at a point) are split, and two pieces that touched only
//!    there are joined by one triangle across the wedge between their
//!    fans when it is narrower than the triangulation radius, and the
//!    slit beside it zipped (`pinches.rs`: a crease of a scan sharper
//!    than 90°, whose sides the
//!    side test keeps apart; CGAL's `hippo1` went from 7 pieces to the
//!    5 its samples make); pieces with fewer vertices than
//!    [`FitParams::neighbours`] are dropped. Without the chance-gap width, 9
//!    chance holes stay open on 5,000 random samples of the saddle
//!    (widths 3.7-5.6 spacings; its real hole: 29).
//!
//! **Limits** (measured before the hole pass and the k-nearest spacing
//! estimate, on 400 Fibonacci samples of the unit sphere, median sample
//! distance 0.168; current figures on random samples, scans and beside
//! Open3D are in `reports/fitting.md`): with the estimated spacing nothing is
//! created and the mesh is closed (χ = 2); with `--spacing` 0.084, 0.09
//! and 0.1 (1 768, 1 628, 1 465 particles) χ = 2, the samples within
//! 0.003 (RMS) of the mesh. With 0.08 one hole remains (χ = 0): a quad of
//! particles with sides 1.75-1.9 h and diagonals 2.6 h, which neither rule
//! opens (sides below `d_min`, diagonals beyond `d_max`, 90° corners below
//! the growing rule's 100° `min_gap`). With a triangulation radius of 1.7
//! instead of `d_min` (2.0), 0.08-0.1 all leave 2-6 such holes
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
//! [`FitParams::max_rounds`] creation rounds of 20 steps (each over the
//! new particles and their surroundings) and `relax_time / 5e-3`
//! relaxation steps of the whole set. [`fit_with_stages`] tells the time
//! of each stage.
//!
//! **Scenes**: [`DataNeighbourhood`] and [`release`] also serve a scene's
//! `creation.fit` (op-scene's `schema::fit` and `fit::SceneFit`), which runs these stages
//! frame by frame (`scenes/fig_10_interpolation.ron`); spacing, material
//! and normals are then the scene's.
//!
//! Deterministic: every stage is (the creation rules and the world are
//! deterministic at any thread count; a round's world is built from the
//! state in slot order; sums here are serial).

mod boundary;
mod denoise;
mod holes;
mod input;
mod locality;
mod mesh;
mod neighbourhood;
mod noise;
mod normals;
mod outliers;
pub(crate) use normals::covariance;
mod params;
mod pinches;
mod relaxation;
mod rounds;
pub mod shapes;
mod spacing;
mod thin;
mod uneven;
mod unit_coordinates;
mod winding;

use std::borrow::Cow;
use std::collections::HashSet;
use std::time::Instant;

use op_dynamics::{ParamError, Point3, Real, Vec3, WorldError};
use rayon::prelude::*;

use input::median_of;
use input::Input;
pub use mesh::{point_triangle_distance, sample_distances, SurfaceMesh};
pub use neighbourhood::DataNeighbourhood;
pub use normals::estimate_normals;
use normals::{curve_like_share, knn_normals};
pub use params::FitParams;
pub(crate) use relaxation::at_rest;
pub use relaxation::release;
use relaxation::{advance, Relaxation};
pub use spacing::median_nearest_distance;
use spacing::{first_ring_mean, nearest_distances, Knn, Nearest};
pub use thin::ThinFeature;
use unit_coordinates::{to_data, unit_samples, UnitSamples};

/// Samples of a surface, with normals when they are known (the input of
/// [`fit`]; op-scene reads them from `.xyz`, `.ply` and `.obj` files).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointSet {
    /// Sample positions.
    pub positions: Vec<Point3>,
    /// Unit normals, one per position, or `None` when there are none.
    pub normals: Option<Vec<Vec3>>,
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
    /// The particle world failed (a particle the fit made is missing).
    #[error("the relaxation failed: {0}")]
    World(String),
    /// The relaxation diverged (the world's report: step, time, particle,
    /// what was wrong).
    #[error("the relaxation failed: {0}")]
    Diverged(#[from] op_dynamics::Divergence),
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
    /// The features of the samples thinner than the triangulation radius
    /// (two sides facing each other within it: ears, fingers), largest
    /// first, in data coordinates. The triangulation keeps their sides
    /// apart by their normals; where the normals could not tell them apart
    /// (a rim turning within a spacing) the mesh may be open or joined
    /// there, and this says where to look (or to give a finer spacing).
    pub thin_features: Vec<ThinFeature>,
    /// Whether the samples' normals came with them (`false`: estimated,
    /// stage 2; a file whose normals include the zero vector has none).
    pub normals_given: bool,
    /// Number of samples dropped as outliers before seeding (stage 0;
    /// every copy of a repeated sample counts). The figures of the mesh
    /// (distances, coverage) are those of the samples kept.
    pub dropped_outliers: usize,
    /// The samples' noise level (stage 0), absolute (the samples' units,
    /// like [`Fit::spacing`]): the estimated standard deviation of the
    /// samples about their surface, from the residuals of local quadric
    /// fits over each kept sample's 16 nearest others (`noise.rs`). About
    /// `1e-5` of the bounding box's diagonal on clean samples; `NaN` when
    /// no neighbourhood spans a surface.
    pub noise_estimate: Real,
    /// Whether the fit approximates the samples rather than interpolating
    /// them ([`FitParams::approximate`]): its particles were seeded on a
    /// smoothed estimate of the surface (`denoise.rs`), and the mesh's
    /// distances are still measured to the samples.
    pub approximated: bool,
    /// Whether the data were fitted as open ([`FitParams::open`], or found
    /// open: a chain of samples whose nearest neighbours all lie to one
    /// side in their tangent plane, `boundary.rs`).
    pub open: bool,
}

impl Fit {
    /// The mesh's pieces: sets of triangles joined through shared
    /// vertices ([`crate::triangulation::vertex_components`]).
    pub fn pieces(&self) -> usize {
        let mut roots: Vec<u32> = crate::triangulation::vertex_components(&self.mesh.faces)
            .into_iter()
            .flatten()
            .collect();
        roots.par_sort_unstable();
        roots.dedup();
        roots.len()
    }

    /// Whether the mesh is closed: it has triangles and no boundary loop.
    pub fn closed(&self) -> bool {
        !self.mesh.faces.is_empty() && self.mesh.boundary_loops == 0
    }
}

/// Longest relaxation after release ([`FitParams::relax_time`], in
/// unit-spacing time units): `100 / STEP` = 20,000 steps of the whole
/// set, which bounds the relaxation's work with [`MAX_PARTICLES`] (an
/// unbounded one, such as `opsim fit --relax 1e4`, would run for hours).
pub const MAX_RELAX_TIME: Real = 100.0;

/// Largest number of particles of a fit: the distinct samples, the
/// particles the spacing would need (estimated as the distinct samples
/// times `(median sample distance / spacing)²`), and the particles the
/// filling rules create are all bounded by it. With at most
/// [`FitParams::max_rounds`] creation rounds of 20 steps and
/// `relax_time / 5e-3` relaxation steps, this bounds a fit's work.
pub const MAX_PARTICLES: usize = 1_000_000;

/// Time step of the relaxations (unit-spacing time units). Measured on
/// 5,000 random samples of the ellipsoid of [`shapes`]: the largest and
/// median displacement of each 0.1 of the relaxation after release agree
/// within 5e-4 spacings with the Dormand-Prince 5(4) reference at error
/// tolerance 1e-4 for steps 2e-3, 5e-3 and 1e-2; at 2e-2 the largest ones
/// grew by 65% and the mesh lost its topology (χ -1, one hole). Half the
/// step that still matched: the relaxation costs 2.5 times fewer force
/// evaluations than at 2e-3.
const STEP: Real = 5e-3;

/// Distance (in spacings) within which samples are merged, and below which
/// samples all within that distance of one line are collinear.
const MERGE: Real = 0.25;

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
/// quarter spacing of it); a
/// fit without a triangle; a mesh that cannot be represented at the data's
/// scale. [`FitError::Spacing`]: a spacing above the bounding box's
/// diagonal or needing more than [`MAX_PARTICLES`]. [`FitError::World`]: a
/// relaxation that diverged.
pub fn fit(data: &PointSet, params: &FitParams) -> Result<Fit, FitError> {
    fit_with_stages(data, params).map(|(f, _)| f)
}

/// [`fit`], with the wall-clock seconds of its stages in order (spacing and
/// normals, creation rounds, release and relaxation, triangulation, holes
/// and distances): where a fit spends its time.
///
/// # Errors
/// As [`fit`].
pub fn fit_with_stages(
    data: &PointSet,
    params: &FitParams,
) -> Result<(Fit, StageSeconds), FitError> {
    params.validate()?;
    let mut stages = Stages::start();
    // Neighbours in space next to each other in memory (`locality.rs`).
    let ordered = locality::in_curve_order(data);
    let data = ordered.as_ref().unwrap_or(data);
    let checked = Input::check(data)?;
    let (data, dropped_outliers, checked) = if params.drop_outliers {
        without_outliers(data, checked)?
    } else {
        (Cow::Borrowed(data), 0, checked)
    };
    let measured = data.as_ref();
    let Input {
        frame,
        local,
        diagonal,
        distinct,
    } = checked;
    // One tree over the samples for the noise, spacing and smoothing.
    let nearest = sample_tree(&distinct)?;
    let noise::Noise {
        level: noise,
        layered,
        detail,
    } = noise::noise_level(&nearest);
    let noise_estimate = frame.length_to_data(noise);
    let sample_spacing = match params.spacing {
        Some(value) => frame.length_to_local(value),
        None => default_spacing(&nearest),
    };
    // Uneven samples: the spacing their sparsest parts need.
    let coarse = match (params.spacing, params.approximate) {
        (None, None | Some(true)) => uneven::coarse_spacing(&nearest, sample_spacing),
        _ => None,
    };
    let approximated = params.approximate.unwrap_or_else(|| {
        coarse.is_some() || (!layered && !detail && denoise::is_noisy(noise, sample_spacing))
    });
    // Noisy or uneven samples: the fit runs on seeds thinned and smoothed
    // from them and is measured against them.
    // The nearest-sample distances' median, over these samples when the
    // fit interpolates them (the tree is theirs), else over the seeds below.
    let interpolated_median = (!approximated).then(|| median_of(nearest_distances(&nearest)));
    let smoothed = approximated.then(|| {
        let thinned = coarse.unwrap_or(sample_spacing);
        let (seeds, from) = denoise::smoothed_seeds(&nearest, noise, thinned);
        smoothed_point_set(measured, &frame, &local, &distinct, &seeds, &from)
    });
    let (
        data,
        Input {
            frame,
            local,
            diagonal,
            distinct,
        },
    ) = match smoothed {
        Some(set) => {
            let checked = Input::check(&set)?;
            (Cow::Owned(set), checked)
        }
        None => (
            Cow::Borrowed(measured),
            Input {
                frame,
                local,
                diagonal,
                distinct,
            },
        ),
    };
    let data = data.as_ref();
    // The default spacing and the median nearest distance of the smoothed
    // seeds when the fit approximates (the default spacing is unused when a
    // spacing is given).
    let (default_h, median) = match interpolated_median {
        Some(median) => (sample_spacing, median),
        None => {
            let seeds_tree = sample_tree(&distinct)?;
            let default_h = match params.spacing {
                None => default_spacing(&seeds_tree),
                Some(_) => sample_spacing,
            };
            (default_h, median_of(nearest_distances(&seeds_tree)))
        }
    };
    stages.lap("outliers, noise and smoothing");
    let smallest = median * (distinct.len() as Real / MAX_PARTICLES as Real).sqrt();
    let h = local_spacing(
        params, &frame, diagonal, &distinct, median, smallest, default_h,
    )?;
    let spacing = match params.spacing {
        Some(value) => value,
        None => frame.length_to_data(h),
    };
    let UnitSamples {
        centroid,
        unit,
        kept,
        seeds,
    } = unit_samples(&local, local.len(), &frame, h, spacing)?;
    // The samples the mesh is measured against, in unit coordinates: the
    // smoothed seeds' own samples when the fit approximates.
    let unit = if approximated {
        measured
            .positions
            .iter()
            .map(|p| Point3::from((frame.to_local(p).coords - centroid) / h))
            .collect()
    } else {
        unit
    };
    let n = unit.len();
    let seed_normals = seed_normals(data, params, &kept, &seeds)?;
    let open = params
        .open
        .unwrap_or_else(|| boundary::has_boundary(&seeds, &seed_normals));
    let rest = first_ring_mean(&seeds, 1.5);
    let thin = thin::thin_features(&seeds, &seed_normals, params.triangulation_radius * rest);
    stages.lap("spacing and normals");

    let relaxing = Relaxation::new(rest);
    let mut world = relaxing.seed_world(&seeds, &seed_normals).map_err(|e| {
        FitError::Input(format!(
            "the spacing {spacing:.3e} does not suit these samples: {e} (the cohesion rest distance is the mean distance between neighbouring samples, {rest:.3} spacings; give a spacing near the median distance between samples, {:.3e})",
            frame.length_to_data(median)
        ))
    })?;

    // Filling rounds (seed 000 §7).
    relaxing.fill(&mut world, params, open, &seeds, &seed_normals)?;
    stages.lap("creation rounds");
    // Release (the seeds are the first ids) and relax.
    let seed_ids: Vec<u32> = (0..seeds.len() as u32).collect();
    release(&mut world, &seed_ids)?;
    advance(&mut world, params.relax_time)?;
    stages.lap("release and relaxation");

    // Triangulate and measure at unit spacing, then map back.
    let p = world.particles();
    let pnormals: Vec<Vec3> = (0..p.len()).map(|s| p.normal(s)).collect();
    let (mut mesh, distances) = SurfaceMesh::with_distances(
        p.positions(),
        &pnormals,
        params.triangulation_radius * rest,
        &unit,
    )?;
    stages.lap("triangulation");
    // A surface covers its samples: most lie within a spacing of it.
    let covered = distances.iter().filter(|&&d| d <= 1.0).count();
    if 2 * covered <= n {
        return Err(FitError::Input(format!(
            "no surface: the {} particles grown from {} samples at spacing {spacing:.3e} gave {} triangle(s), within one spacing of only {covered} of the {n} samples (samples along a curve, or a spacing too coarse for them: the median distance between samples is {:.3e})",
            p.len(),
            seeds.len(),
            mesh.faces.len(),
            frame.length_to_data(median)
        )));
    }
    // The final pass: close the holes narrower than the open-surface
    // threshold.
    let before = (mesh.vertices.clone(), mesh.faces.clone());
    close_holes(&mut mesh, params, open, &seeds, &seed_normals, rest);
    mesh.measure_since(&unit, (&before.0, &before.1), &distances);
    stages.lap("holes and distances");
    let thin_features = to_data(&mut mesh, thin, &frame, h, centroid, diagonal)?;
    Ok((
        Fit {
            spacing,
            particles: p.len(),
            mesh,
            thin_features,
            normals_given: data.normals.is_some(),
            dropped_outliers,
            noise_estimate,
            approximated,
            open,
        },
        stages.laps,
    ))
}

/// `data` without its outlier samples ([`outliers`]: statistical outlier
/// removal after Rusu et al. 2008, on the distinct samples of `checked`;
/// every copy of an outlier goes), the number of samples dropped, and the
/// remaining samples checked and mapped anew (their own bounding box).
/// Borrows `data` when nothing is dropped.
///
/// # Errors
/// As [`Input::check`], for the samples left.
fn without_outliers(
    data: &PointSet,
    checked: Input,
) -> Result<(Cow<'_, PointSet>, usize, Input), FitError> {
    let flags = outliers::outliers(&checked.distinct);
    let gone: HashSet<[u64; 3]> = checked
        .distinct
        .iter()
        .zip(&flags)
        .filter(|(_, &f)| f)
        .map(|(p, _)| input::bits(p))
        .collect();
    if gone.is_empty() {
        return Ok((Cow::Borrowed(data), 0, checked));
    }
    let keep: Vec<bool> = checked
        .local
        .iter()
        .map(|p| !gone.contains(&input::bits(p)))
        .collect();
    let pick = |v: &[Point3]| -> Vec<Point3> {
        v.iter()
            .zip(&keep)
            .filter(|(_, &k)| k)
            .map(|(p, _)| *p)
            .collect()
    };
    let kept = PointSet {
        positions: pick(&data.positions),
        normals: data.normals.as_ref().map(|normals| {
            normals
                .iter()
                .zip(&keep)
                .filter(|(_, &k)| k)
                .map(|(v, _)| *v)
                .collect()
        }),
    };
    let dropped = data.positions.len() - kept.positions.len();
    let checked = Input::check(&kept)?;
    Ok((Cow::Owned(kept), dropped, checked))
}

/// The smoothed seeds of noisy samples ([`denoise::smoothed_seeds`] of
/// `distinct`, `from` the distinct sample each was made from) as a point
/// set in data coordinates, with the given normal of that sample when
/// `data` has normals (`local`: `data`'s samples in `frame`).
fn smoothed_point_set(
    data: &PointSet,
    frame: &input::Frame,
    local: &[Point3],
    distinct: &[Point3],
    seeds: &[Point3],
    from: &[usize],
) -> PointSet {
    let normals = data.normals.as_ref().map(|normals| {
        let mut first = std::collections::HashMap::new();
        for (k, p) in local.iter().enumerate() {
            first.entry(input::bits(p)).or_insert(k);
        }
        from.iter()
            .map(|&j| normals[first[&input::bits(&distinct[j])]])
            .collect()
    });
    PointSet {
        positions: seeds.iter().map(|p| frame.to_data(p)).collect(),
        normals,
    }
}

/// The spacing in local units (`--spacing` mapped to them, or `default`,
/// the [`default_spacing`] of `distinct`), checked against the samples'
/// bounding box and the particle limit.
fn local_spacing(
    params: &FitParams,
    frame: &input::Frame,
    diagonal: Real,
    distinct: &[Point3],
    median: Real,
    smallest: Real,
    default: Real,
) -> Result<Real, FitError> {
    Ok(match params.spacing {
        None => default,
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
    })
}

/// The seeds' normals: the samples' own when they have some, else by
/// local PCA over the nearest seeds, oriented over the whole set
/// (refused when most neighbourhoods lie along a curve).
fn seed_normals(
    data: &PointSet,
    params: &FitParams,
    kept: &[usize],
    seeds: &[Point3],
) -> Result<Vec<Vec3>, FitError> {
    Ok(match &data.normals {
        Some(v) => kept.iter().map(|&k| v[k]).collect(),
        None => {
            let knn = Knn::new(seeds, params.neighbours);
            let share = curve_like_share(seeds, &knn);
            if share > 0.5 {
                return Err(FitError::Input(format!(
                    "no surface: {:.0}% of the samples have neighbourhoods along a curve (their {} nearest samples spread in one direction only: samples along a curve, such as a circle)",
                    100.0 * share,
                    knn.k()
                )));
            }
            knn_normals(seeds, &knn)
        }
    })
}

/// Closes the mesh's holes narrower than the open-surface threshold
/// (`holes.rs`): `d_max` or the widest gap random sampling leaves by
/// chance for open data, [`FitParams::max_hole`] spacings for closed data.
fn close_holes(
    mesh: &mut SurfaceMesh,
    params: &FitParams,
    open: bool,
    seeds: &[Point3],
    seed_normals: &[Vec3],
    rest: Real,
) {
    let max_width = if open {
        // At least 3 seeds: k >= 2.
        let knn = Knn::new(seeds, 6);
        let r6 = median_of(knn.distances_to(knn.k()));
        (params.d_max * rest).max(holes::sampling_gap_width(seeds.len(), r6))
    } else {
        params.max_hole * rest
    };
    holes::fill_holes(
        mesh,
        max_width,
        params.triangulation_radius * rest,
        open,
        seeds,
        seed_normals,
        params.neighbours,
    );
}

/// The stages of a fit with their wall-clock seconds, in order.
pub type StageSeconds = Vec<(&'static str, f64)>;

/// Records [`StageSeconds`].
struct Stages {
    last: Instant,
    laps: StageSeconds,
}

impl Stages {
    fn start() -> Self {
        Stages {
            last: Instant::now(),
            laps: Vec::new(),
        }
    }

    fn lap(&mut self, stage: &'static str) {
        let now = Instant::now();
        self.laps.push((stage, (now - self.last).as_secs_f64()));
        self.last = now;
    }
}

/// The nearest-neighbour tree over the distinct samples.
///
/// # Errors
/// [`FitError::Input`] when none can be built (kiddo refuses the points).
fn sample_tree(distinct: &[Point3]) -> Result<Nearest<'_>, FitError> {
    Nearest::new(distinct).ok_or_else(|| {
        FitError::Input(format!(
            "no nearest-neighbour tree over the {} distinct samples could be built",
            distinct.len()
        ))
    })
}

/// The default spacing (local units) of the distinct samples the tree
/// `distinct` is built over: 0.8 times the median over them of the
/// distance to the 6th nearest other one. On a
/// regular (hexagonal) sampling that is 0.8 times the sample distance; on
/// uniformly random samples, where the nearest distances spread from 0 to
/// twice their median, about 1.05 `/√ρ` (`ρ` the samples per area): the
/// 6th neighbour measures the local density, not the chance closeness of
/// a pair (the nearest distance gave 3 times smaller spacings, 10 times
/// more particles, and 40-370 holes on 500-5,000 random samples of an
/// ellipsoid and a torus). Measured on random samples of the shapes of
/// [`shapes`] (500 and 5,000 points): factor 1.0 left 2 holes on the
/// torus, 0.65 gave a wrong genus on the 500-sample double torus and 44
/// loops on the 5,000-sample open saddle; 0.8 was the best of the three.
fn default_spacing(distinct: &Nearest) -> Real {
    let knn = Knn::over(distinct, 6);
    0.8 * median_of(knn.distances_to(knn.k()))
}

#[cfg(test)]
mod tests;
