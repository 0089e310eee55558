//! The samples' noise level: the spread of the samples about the surface
//! they sample, estimated from the samples alone.
//!
//! Each sample's [`NEIGHBOURS`] nearest others and itself are fitted by a
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
use super::spacing::Knn;

/// Neighbours of each local fit: 16, so that a fit of the 6 coefficients
/// of a quadric has 11 degrees of freedom.
const NEIGHBOURS: usize = 16;

/// Coefficients of the local quadric `a + b u + c v + d u² + e uv + f v²`.
const COEFFICIENTS: usize = 6;

/// The noise level of `points` (distinct, any units; module docs): the
/// median residual standard deviation of local quadric fits over each
/// point and its [`NEIGHBOURS`] nearest others (moving least squares,
/// Levin 1998), in the points' units. `NaN` when there are too few points
/// for a fit or no neighbourhood spans a surface.
pub(crate) fn noise_level(points: &[Point3]) -> Real {
    let knn = Knn::new(points, NEIGHBOURS);
    let k = knn.k();
    if k < COEFFICIENTS {
        return Real::NAN;
    }
    let variances: Vec<Real> = (0..points.len())
        .into_par_iter()
        .filter_map(|i| quadric_residual_variance(points, i, knn.neighbours(i)))
        .collect();
    if variances.is_empty() {
        return Real::NAN;
    }
    let dof = (k + 1 - COEFFICIENTS) as Real;
    // Median of χ²_ν / ν (Wilson and Hilferty 1931).
    let chi2_median = (1.0 - 2.0 / (9.0 * dof)).powi(3);
    (median_of(variances) / chi2_median).sqrt()
}

/// The residual variance (sum of squares over degrees of freedom) of the
/// least-squares quadric height field over `points[i]` and `points[row]`
/// in the frame of their principal directions (normal: the least; Hoppe
/// et al. 1992), or `None` when the points lie along a curve (their second
/// principal variance below 1e-6 of the first) or the normal equations
/// are singular.
fn quadric_residual_variance(points: &[Point3], i: usize, row: &[usize]) -> Option<Real> {
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
    let rss: Real = rows
        .iter()
        .map(|(basis, h)| (h - basis.dot(&coefficients)).powi(2))
        .sum();
    let dof = (rows.len() - COEFFICIENTS) as Real;
    let variance = rss / dof;
    variance.is_finite().then_some(variance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::shapes::Shape;
    use op_test_support::Rng;

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
            let zero = noise_level(&clean) / d;
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
            let ratio = noise_level(&noisy) / sigma;
            assert!(
                (0.7..1.3).contains(&ratio),
                "{}: estimate {ratio} times the noise",
                shape.name()
            );
        }
    }

    /// Too few points for a quadric, points along a line: `NaN`, no panic.
    #[test]
    fn no_surface_no_estimate() {
        let few: Vec<Point3> = (0..5)
            .map(|k| Point3::new(k as Real, (k * k) as Real, 1.0 / (1.0 + k as Real)))
            .collect();
        assert!(noise_level(&few).is_nan());
        let line: Vec<Point3> = (0..50).map(|k| Point3::new(k as Real, 0.0, 0.0)).collect();
        assert!(noise_level(&line).is_nan());
        assert!(noise_level(&[]).is_nan());
    }
}
