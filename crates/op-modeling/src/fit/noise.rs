//! The samples' noise level: the spread of the samples about the surface
//! they sample, estimated from the samples alone.
//!
//! Each sample's [`NEIGHBOURS`] nearest others and itself (of at most
//! [`CENTRES`] samples spread through the set) are fitted by a
//! quadratic height field over their least-squares plane (a local
//! polynomial fit, as in moving least squares, Levin 1998; Alexa et al.
//! 2003): unlike a plane fit, whose residual on clean data is the
//! curvature's sagitta (on 500 samples of a torus, a third of the noise
//! of 0.5% of the diagonal), the quadric follows the curvature and leaves
//! the noise. The residual variance of one fit, the residual sum of
//! squares over its degrees of freedom (points less the 6 coefficients),
//! estimates the variance of the noise along the normal; the estimate is
//! the square root of the median of those variances, corrected for the
//! median of a χ² variable with that many degrees of freedom (Wilson and
//! Hilferty 1931), so that Gaussian noise of standard deviation `σ` per
//! coordinate gives about `σ`. The median ignores the fits across sharp
//! edges, thin parts and outliers as long as they are fewer than half.

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::input::median_of;
use super::normals::covariance;
use super::spacing::Nearest;

/// Neighbours of each local fit: 16, so that a fit of the 6 coefficients
/// of a quadric has 11 degrees of freedom.
const NEIGHBOURS: usize = 16;

/// Coefficients of the local quadric `a + b u + c v + d u² + e uv + f v²`.
const COEFFICIENTS: usize = 6;

/// The noise level of the points of `tree` (distinct, any units; module
/// docs): the
/// median residual standard deviation of local quadric fits over
/// [`CENTRES`] points spread through the set (every point of a smaller
/// set) and their [`NEIGHBOURS`] nearest others (moving least squares,
/// Levin 1998), in the points' units. `NaN` when there are too few points
/// for a fit or no neighbourhood spans a surface.
pub(crate) fn noise_level(tree: &Nearest) -> Noise {
    let points = tree.points();
    // Neighbourhoods within a few noise levels fit the noise itself: the
    // estimate comes out low (0.7 of the noise of 1% of the diagonal on
    // 20,000 samples of an ellipsoid, whose 16 nearest lie within 1.4 noise
    // levels; 0.69 of 0.5% on 200,000 samples of a torus). They are
    // widened until they reach [`WIDTH`] noise levels: the wider ones
    // measure more of the noise, so this takes a few rounds.
    let mut k = NEIGHBOURS;
    let mut noise = loop {
        let (noise, reach) = noise_level_over(
            points,
            tree,
            k,
            if k == NEIGHBOURS {
                CENTRES
            } else {
                WIDE_CENTRES
            },
        );
        if !noise.level.is_finite() || noise.layered || reach >= WIDTH * noise.level {
            break noise;
        }
        let wider = (k as Real * (WIDTH * noise.level / reach).powi(2)).ceil() as usize;
        if k >= MOST_NEIGHBOURS || wider <= k {
            break noise;
        }
        k = wider.min(MOST_NEIGHBOURS);
    };
    // Noise leaves the same residual over four times the neighbours;
    // detail the quadric follows only over few leaves more.
    if noise.level.is_finite() && !noise.layered {
        let wider = noise_level_over(points, tree, (4 * k).min(MOST_NEIGHBOURS), DETAIL_CENTRES).0;
        noise.detail = wider.level > DETAIL * noise.level;
    }
    noise
}

/// Residual over four times the neighbours, in residuals over the
/// neighbours of the estimate, above which the spread is detail rather
/// than noise. Measured: 1.02-1.17 on random samples of the ellipsoid
/// and torus of [`crate::fit::shapes`] with Gaussian noise of 0.25-1% of
/// the diagonal (5,000 and 20,000), 1.0 on CGAL's scanned sheet
/// `fin90`; 4.7 on CGAL's figurine `oni.pwn` and 6.5 on its `kitten`,
/// whose residual is their shape's detail.
const DETAIL: Real = 1.5;

/// Radius, in noise levels, that a local fit's neighbourhood should reach
/// for its residual to measure the noise.
const WIDTH: Real = 5.0;

/// Most neighbours of a widened local fit.
const MOST_NEIGHBOURS: usize = 2048;

/// Most local fits of an estimate: a median over this many is as good as
/// over all (its relative spread about `1 / √CENTRES`), and the estimate's
/// cost stays bounded on a million samples.
const CENTRES: usize = 20_000;

/// Local fits of a widened estimate: a quarter as many (over more
/// neighbours each, the median of 5,000 is within about 2%).
const WIDE_CENTRES: usize = 5_000;

/// Local fits of the detail test ([`DETAIL`]): over four times the
/// neighbours each, a tenth as many (a ratio of two medians, each within a
/// few percent over 2,000 fits, against a threshold 30% above noise's).
const DETAIL_CENTRES: usize = 2_000;

/// [`noise_level`] with `neighbours` nearest others in each local fit
/// (found in `tree`, over `points`) about at most `centres` points spread
/// through the set, and the median distance to the farthest of them.
fn noise_level_over(
    points: &[Point3],
    tree: &Nearest,
    neighbours: usize,
    centres: usize,
) -> (Noise, Real) {
    let k = neighbours.min(points.len().saturating_sub(1));
    if k < COEFFICIENTS {
        return (Noise::NONE, Real::NAN);
    }
    let stride = points.len().div_ceil(centres).max(1);
    let centres: Vec<usize> = (0..points.len()).step_by(stride).collect();
    let fits: Vec<(Real, Real, Real)> = centres
        .par_iter()
        .filter_map(|&i| {
            let row = tree.others(i, k);
            let reach = row.last()?.0;
            let row: Vec<usize> = row.into_iter().map(|(_, j)| j).collect();
            quadric_residuals(points, i, &row).map(|(v, shape)| (v, shape, reach))
        })
        .collect();
    if fits.is_empty() {
        return (Noise::NONE, Real::NAN);
    }
    let dof = (k + 1 - COEFFICIENTS) as Real;
    // Median of χ²_ν / ν (Wilson and Hilferty 1931).
    let chi2_median = (1.0 - 2.0 / (9.0 * dof)).powi(3);
    let variances = fits.iter().map(|f| f.0).collect();
    let shapes = fits.iter().map(|f| f.1).collect();
    let reach = median_of(fits.iter().map(|f| f.2).collect());
    (
        Noise {
            level: (median_of(variances) / chi2_median).sqrt(),
            layered: median_of(shapes) > LAYERED,
            detail: false,
        },
        reach,
    )
}

/// The samples' spread about their surface ([`noise_level`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Noise {
    /// The estimated standard deviation along the normal (`NaN` when no
    /// neighbourhood spans a surface).
    pub(crate) level: Real,
    /// Whether the spread is in layers rather than noise: in most local
    /// fits the residuals are all about as large as their RMS (the median
    /// absolute residual above [`LAYERED`] of it), as when the fits span
    /// both sides of a part thinner than the neighbourhood (a coin, an
    /// ear) with no sample between them. Noise puts most samples near
    /// the surface: for Gaussian noise the ratio is about 0.68.
    pub(crate) layered: bool,
    /// Whether the spread is detail rather than noise: the residual of
    /// fits over four times the neighbours exceeds [`DETAIL`] times the
    /// estimate (a surface whose detail the quadric follows only over a
    /// few samples, such as a scanned figurine's face). Noise leaves the
    /// same residual at any scale.
    pub(crate) detail: bool,
}

impl Noise {
    /// No estimate: no neighbourhood spans a surface.
    const NONE: Noise = Noise {
        level: Real::NAN,
        layered: false,
        detail: false,
    };
}

/// Median absolute residual over RMS residual (the median over the local
/// fits) above which the samples lie in layers. Measured: 0.68-0.69 on
/// random samples of the ellipsoid and torus of [`crate::fit::shapes`]
/// with Gaussian noise of 0.25-1% of the diagonal; 0.79-0.81 on clean
/// samples of two sides 0.6 and 0.75 spacings apart (a plate, a coin:
/// two layers alone would give 1, the quadric takes up part of them).
/// Uniform noise, whose ratio is 0.87 before the fit, would count as
/// layers (not measured).
const LAYERED: Real = 0.75;

/// The residual variance (sum of squares over degrees of freedom) and the
/// median absolute residual over the RMS residual of the
/// least-squares quadric height field over `points[i]` and `points[row]`
/// in the frame of their principal directions (normal: the least; Hoppe
/// et al. 1992), or `None` when the points lie along a curve (their second
/// principal variance below 1e-6 of the first) or the normal equations
/// are singular.
fn quadric_residuals(points: &[Point3], i: usize, row: &[usize]) -> Option<(Real, Real)> {
    let all = || std::iter::once(&i).chain(row).map(|&k| &points[k]);
    let (mean, cov) = covariance(all());
    let eig = cov.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let axis = |k: usize| -> Vec3 { eig.eigenvectors.column(order[k]).into_owned() };
    // A neighbourhood along a curve spans no surface: no quadric.
    let (second, first) = (eig.eigenvalues[order[1]], eig.eigenvalues[order[2]]);
    if second.is_nan() || second <= 1e-6 * first {
        return None;
    }
    let (normal, e1, e2) = (axis(0), axis(2), axis(1));
    // Tangent coordinates scaled by the neighbourhood's radius: the
    // normal equations stay well conditioned at any scale.
    let radius = all().map(|p| (p.coords - mean).norm()).fold(0.0, Real::max);
    if !(radius.is_finite() && radius > 0.0) {
        return None;
    }
    let mut ata = nalgebra::SMatrix::<Real, COEFFICIENTS, COEFFICIENTS>::zeros();
    let mut atb = nalgebra::SVector::<Real, COEFFICIENTS>::zeros();
    let rows: Vec<(nalgebra::SVector<Real, COEFFICIENTS>, Real)> = all()
        .map(|p| {
            let d = p.coords - mean;
            let (u, v) = (d.dot(&e1) / radius, d.dot(&e2) / radius);
            let basis =
                nalgebra::SVector::<Real, COEFFICIENTS>::from([1.0, u, v, u * u, u * v, v * v]);
            (basis, d.dot(&normal))
        })
        .collect();
    for (basis, h) in &rows {
        ata += basis * basis.transpose();
        atb += basis * *h;
    }
    let coefficients = ata.cholesky()?.solve(&atb);
    let mut residuals: Vec<Real> = rows
        .iter()
        .map(|(basis, h)| (h - basis.dot(&coefficients)).abs())
        .collect();
    let rss: Real = residuals.iter().map(|r| r * r).sum();
    let dof = (rows.len() - COEFFICIENTS) as Real;
    let variance = rss / dof;
    let rms = (rss / rows.len() as Real).sqrt();
    residuals.sort_by(Real::total_cmp);
    let shape = residuals[residuals.len() / 2] / rms;
    (variance.is_finite() && shape.is_finite()).then_some((variance, shape))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::shapes::Shape;
    use op_test_support::Rng;

    /// [`noise_level`] of `points`.
    fn noise_of(points: &[Point3]) -> Noise {
        Nearest::new(points).map_or(Noise::NONE, |tree| noise_level(&tree))
    }

    /// A standard normal variable (Box-Muller).
    fn gaussian(rng: &mut Rng) -> Real {
        let u = rng.uniform(Real::MIN_POSITIVE, 1.0);
        let v = rng.uniform(0.0, 1.0);
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    /// The diagonals of the bounding boxes of the ellipsoid (semi-axes 1,
    /// 0.7, 0.5) and the torus (major radius 1, minor 0.4).
    fn diagonal(shape: Shape) -> Real {
        match shape {
            Shape::Ellipsoid => 2.0 * (1.0f64 + 0.49 + 0.25).sqrt(),
            _ => (2.8f64 * 2.8 * 2.0 + 0.8 * 0.8).sqrt(),
        }
    }

    /// 5,000 random samples of the ellipsoid and the torus: clean, the
    /// estimate is below 1e-4 of the diagonal (measured 1e-5 and 3e-5: the
    /// quadric's residual on the curvature); with Gaussian noise of
    /// standard deviation 0.5% of the diagonal on each coordinate, within
    /// 30% of it (measured 0.47% on both: the nearest neighbours, chosen
    /// in space, cut the spread across the surface a little).
    #[test]
    fn noise_of_clean_and_noisy_samples() {
        for shape in [Shape::Ellipsoid, Shape::Torus] {
            let clean = shape.sample(5000, 17).positions;
            let d = diagonal(shape);
            let zero = noise_of(&clean).level / d;
            assert!(zero < 1e-4, "{}: clean {zero}", shape.name());
            let mut rng = Rng::new(11);
            let sigma = 0.005 * d;
            let noisy: Vec<Point3> = clean
                .iter()
                .map(|p| {
                    let e = Vec3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng));
                    p + e * sigma
                })
                .collect();
            let noise = noise_of(&noisy);
            assert!(!noise.layered, "{}", shape.name());
            let ratio = noise.level / sigma;
            assert!(
                (0.7..1.3).contains(&ratio),
                "{}: estimate {ratio} times the noise",
                shape.name()
            );
        }
    }

    /// Two sides of a thin part, clean (two random layers of a plate
    /// 0.6 sample distances thick): their local fits span both, so the
    /// estimate is about half the thickness, but the spread is in layers,
    /// not noise; one layer with Gaussian noise of the same estimate is
    /// not layered.
    #[test]
    fn two_sides_of_a_thin_part_are_layers() {
        let mut rng = Rng::new(3);
        let side = 40.0;
        let plate: Vec<Point3> = (0..3200)
            .map(|k| {
                let z = if k % 2 == 0 { 0.3 } else { -0.3 };
                Point3::new(rng.uniform(0.0, side), rng.uniform(0.0, side), z)
            })
            .collect();
        let noise = noise_of(&plate);
        assert!(noise.layered && noise.level > 0.1, "{noise:?}");
        let noisy: Vec<Point3> = (0..3200)
            .map(|_| {
                let z = 0.3 * gaussian(&mut rng);
                Point3::new(rng.uniform(0.0, side), rng.uniform(0.0, side), z)
            })
            .collect();
        let noise = noise_of(&noisy);
        assert!(!noise.layered && noise.level > 0.1, "{noise:?}");
    }

    /// Too few points for a quadric, points along a line: `NaN`, no panic.
    #[test]
    fn no_surface_no_estimate() {
        let few: Vec<Point3> = (0..5)
            .map(|k| Point3::new(k as Real, (k * k) as Real, 1.0 / (1.0 + k as Real)))
            .collect();
        assert!(noise_of(&few).level.is_nan());
        let line: Vec<Point3> = (0..50).map(|k| Point3::new(k as Real, 0.0, 0.0)).collect();
        assert!(noise_of(&line).level.is_nan());
        assert!(noise_of(&[]).level.is_nan());
    }
}
