//! Noisy samples: seeds on a smoothed estimate of the surface, so that the
//! fit approximates the samples within their noise instead of passing
//! through every one.
//!
//! The particles of a fit are seeded on the samples (seed 000 §7,
//! "surface interpolation"). Samples scattered about their surface by a
//! noise comparable to their spacing then give a crumpled sheet whose
//! neighbouring particles face every way: measured on 5,000 random
//! samples of an ellipsoid with Gaussian noise of 0.5% of the diagonal
//! (0.31 spacings), 3 pieces and Euler characteristic -8 instead of 1 and
//! 2. Seed 000 §7 smooths noisy data by relaxing the released particles,
//! but particles seeded a noise apart shatter before they smooth.
//!
//! Here the samples are first thinned to a spacing well above the noise
//! ([`smoothed_seeds`]: `max(h, THIN σ)`, `h` the spacing of the samples),
//! and each sample kept is moved onto a local polynomial fit of the
//! samples around it: the weighted least-squares quadric height field over
//! their weighted principal plane (moving least squares, Levin 1998;
//! Alexa et al. 2003, who project with a plane and a polynomial the same
//! way). Each fit takes the most of a seed's 32 to 512 nearest samples
//! that its quadric still follows (a residual the noise explains), so the
//! seeds' own noise is several times smaller than the samples' while the
//! quadric follows the curvature: measured on 20,000 random samples of an
//! ellipsoid and a torus with Gaussian noise of 0.25-1% of the diagonal,
//! the mesh's vertices lie 0.17-0.2 noise levels (RMS) off the true
//! surface (`reports/fitting.md`). The rest of the fit runs on these
//! seeds as on clean samples.

use nalgebra::{SMatrix, SVector};
use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::normals::weighted_covariance;
use super::spacing::{merge_close, Nearest};

/// Samples are smoothed when their noise level exceeds this share of
/// their spacing. Clean samples of the analytic shapes measure below
/// `1e-3` spacings (the quadric's residual on the curvature); Gaussian
/// noise of 0.25% of the diagonal on 5,000 samples of them 0.17.
pub(super) const NOISY: Real = 0.1;

/// The smoothed seeds' spacing in noise levels: a seed's neighbours are at
/// least this many standard deviations of the noise away, so the noise
/// that is left (a fraction of one) tilts their normals by a few degrees.
const THIN: Real = 4.0;

/// Coefficients of the local quadric `a + b u + c v + d u² + e uv + f v²`.
const COEFFICIENTS: usize = 6;

/// Whether samples with noise level `sigma` and spacing `h` are noisy
/// ([`NOISY`]).
pub(super) fn is_noisy(sigma: Real, h: Real) -> bool {
    sigma.is_finite() && h > 0.0 && sigma > NOISY * h
}

/// The seeds of noisy samples (module docs): the points of `tree`
/// (distinct) thinned
/// so that no two kept ones are closer than `0.75 max(h, THIN sigma)`,
/// each kept one moved onto a local quadric fit of its nearest samples
/// ([`smoothed`]). Returns the smoothed positions and, for each, the index
/// of the sample it was made from. A sample whose neighbourhood spans no
/// surface is kept where it is.
pub(super) fn smoothed_seeds(tree: &Nearest, sigma: Real, h: Real) -> (Vec<Point3>, Vec<usize>) {
    let points = tree.points();
    // No estimate (no neighbourhood spans a surface): no noise to take off.
    let sigma = if sigma.is_finite() { sigma } else { 0.0 };
    let spacing = h.max(THIN * sigma);
    let kept = merge_close(points, 0.75 * spacing);
    let most = NEAREST[NEAREST.len() - 1];
    let smoothed = kept
        .par_iter()
        .map(|&k| {
            let q = points[k];
            // The sample itself and its nearest others, in a deterministic
            // order for the sums.
            let near: Vec<(Real, usize)> = std::iter::once((0.0, k))
                .chain(tree.others(k, most - 1))
                .collect();
            smoothed(points, &near, &q, sigma).unwrap_or(q)
        })
        .collect();
    (smoothed, kept)
}

/// `q` on the quadric fit ([`LocalFit`]) of the most of its nearest
/// samples `near` (distance, index; nearest first) that the quadric still
/// follows: of the neighbourhoods of [`NEAREST`] samples, the largest
/// whose fit leaves a residual within [`LocalFit::follows`] times the noise `sigma`
/// (a larger one that spans a curvature the quadric cannot follow, such as
/// both sides of a thin tube, leaves more). The more samples a fit
/// averages, the less of the noise is left at its centre. `None` when even
/// the smallest spans no surface.
fn smoothed(points: &[Point3], near: &[(Real, usize)], q: &Point3, sigma: Real) -> Option<Point3> {
    let mut best = None;
    for &count in &NEAREST {
        if count > near.len() {
            break;
        }
        let Some(fit) = LocalFit::new(points, &near[..count]) else {
            break;
        };
        if best.is_some() && fit.residual > fit.follows() * sigma {
            break;
        }
        best = Some(fit.project(q));
    }
    best.flatten()
}

/// Sizes of the neighbourhoods [`smoothed`] tries, smallest first.
const NEAREST: [usize; 5] = [32, 64, 128, 256, 512];

/// The weighted least-squares quadric height field of some samples over
/// their weighted principal plane (moving least squares, Levin 1998),
/// Gaussian weights of standard deviation half the farthest sample's
/// distance.
struct LocalFit {
    mean: Vec3,
    frame: [Vec3; 3],
    radius: Real,
    coefficients: SVector<Real, COEFFICIENTS>,
    /// Weighted RMS residual of the samples, corrected for the
    /// coefficients fitted.
    residual: Real,
    /// The effective number of samples, `(Σw)² / Σw²`.
    effective: Real,
}

impl LocalFit {
    /// The fit of `near` (distance to the centre, index into `points`;
    /// farthest last); `None` when the samples span no surface or the
    /// normal equations are singular.
    fn new(points: &[Point3], near: &[(Real, usize)]) -> Option<LocalFit> {
        let radius = near.last()?.0;
        if !(radius > 0.0 && radius.is_finite()) {
            return None;
        }
        let spread = 0.5 * radius;
        let weight = |d: Real| (-(d / spread).powi(2)).exp();
        let (mean, cov) = weighted_covariance(near.iter().map(|&(d, j)| (weight(d), &points[j])));
        let eig = cov.symmetric_eigen();
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let (second, first) = (eig.eigenvalues[order[1]], eig.eigenvalues[order[2]]);
        if second.is_nan() || second <= 1e-6 * first {
            return None;
        }
        let axis = |k: usize| -> Vec3 { eig.eigenvectors.column(order[k]).into_owned() };
        let mut fit = LocalFit {
            mean,
            frame: [axis(2), axis(1), axis(0)],
            radius,
            coefficients: SVector::zeros(),
            residual: 0.0,
            effective: 0.0,
        };
        let mut ata = SMatrix::<Real, COEFFICIENTS, COEFFICIENTS>::zeros();
        let mut atb = SVector::<Real, COEFFICIENTS>::zeros();
        for &(d, j) in near {
            let (b, height) = fit.coordinates(&points[j]);
            let w = weight(d);
            ata += b * b.transpose() * w;
            atb += b * (height * w);
        }
        fit.coefficients = ata.cholesky()?.solve(&atb);
        let (mut rss, mut total, mut squares) = (0.0, 0.0, 0.0);
        for &(d, j) in near {
            let (b, height) = fit.coordinates(&points[j]);
            let w = weight(d);
            rss += w * (height - b.dot(&fit.coefficients)).powi(2);
            total += w;
            squares += w * w;
        }
        fit.effective = total * total / squares;
        let dof = (fit.effective - COEFFICIENTS as Real).max(1.0);
        fit.residual = (rss / total * fit.effective / dof).sqrt();
        fit.residual.is_finite().then_some(fit)
    }

    /// The largest ratio of [`LocalFit::residual`] to the noise level at
    /// which the quadric still follows its samples: two standard
    /// deviations of the residual's estimate above 1 (the residual of
    /// pure noise, with `ν` degrees of freedom, spreads by about
    /// `1 / √(2ν)` of itself), so that a fit whose residual exceeds it
    /// leaves a bias the noise does not explain.
    fn follows(&self) -> Real {
        let dof = (self.effective - COEFFICIENTS as Real).max(1.0);
        1.0 + 3.0 / (2.0 * dof).sqrt()
    }

    /// The quadric's basis at `p`'s tangent coordinates (scaled by the
    /// radius, so the normal equations stay well conditioned at any
    /// scale) and `p`'s height over the plane.
    fn coordinates(&self, p: &Point3) -> (SVector<Real, COEFFICIENTS>, Real) {
        let d = p.coords - self.mean;
        let [e1, e2, normal] = &self.frame;
        let (u, v) = (d.dot(e1) / self.radius, d.dot(e2) / self.radius);
        (
            SVector::from([1.0, u, v, u * u, u * v, v * v]),
            d.dot(normal),
        )
    }

    /// `q` moved along the normal onto the quadric over its tangent
    /// coordinates; `None` when not finite.
    fn project(&self, q: &Point3) -> Option<Point3> {
        let (b, height) = self.coordinates(q);
        let moved = q.coords + self.frame[2] * (b.dot(&self.coefficients) - height);
        moved
            .iter()
            .all(|x| x.is_finite())
            .then_some(Point3::from(moved))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples of the plane `z = 0` on a jittered unit grid with heights
    /// alternating `±s` (`s` half the grid step): the seeds are thinned
    /// (their spacing is `4 s`, twice the grid's), lie far closer to the
    /// plane than the samples, and no two are closer than the thinning
    /// distance.
    #[test]
    fn smoothing_takes_the_noise_off_a_plane() {
        let s = 0.5;
        let mut points = Vec::new();
        for i in 0..60 {
            for j in 0..60 {
                let jitter = ((i * 7 + j * 13) % 10) as Real * 0.03;
                let height = if (i * 31 + j * 17) % 2 == 0 { s } else { -s };
                points.push(Point3::new(i as Real + jitter, j as Real - jitter, height));
            }
        }
        let (seeds, kept) = smoothed_seeds(&Nearest::new(&points).unwrap(), s, 1.0);
        assert_eq!(seeds.len(), kept.len());
        assert!(seeds.len() < points.len() / 2, "{} seeds", seeds.len());
        let worst = seeds.iter().map(|p| p.z.abs()).fold(0.0, Real::max);
        assert!(worst < 0.2 * s, "largest height {worst}");
        for (a, &k) in kept.iter().enumerate() {
            for &l in &kept[a + 1..] {
                assert!((points[k] - points[l]).norm() >= 0.75 * THIN * s);
            }
        }
    }

    /// A sample with too few neighbours is kept where it is.
    #[test]
    fn lonely_samples_stay() {
        let points = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(100.0, 0.0, 0.0),
            Point3::new(0.0, 100.0, 0.0),
        ];
        let (seeds, _) = smoothed_seeds(&Nearest::new(&points).unwrap(), 0.1, 1.0);
        assert_eq!(seeds, points);
    }
}
