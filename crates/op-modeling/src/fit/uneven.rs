//! Uneven samples: the spacing their sparsest parts need.
//!
//! The default spacing follows the median sample distance, so where the
//! samples are much sparser than the median (half a scan taken from
//! farther away, the gaps between the lines of a line scanner) the
//! creation rules cannot bridge them: measured on 20,000 random samples of
//! a torus made ten times sparser where x > 0, 23 pieces and Euler
//! characteristic 44; on samples along scan lines ten times denser along
//! a line than across, "no surface" (their 12 nearest lie along one line).
//!
//! [`coarse_spacing`] measures each sample's *coverage distance*: the
//! distance to its `k`-th nearest sample for the smallest `k` of 6, 12,
//! 24, ... whose neighbourhood spans a surface rather than a curve (on
//! random samples the 6th, as for the default spacing; on a scan line the
//! distance to the next line). Samples that are uneven get a spacing
//! from the area those distances cover, not from the number of samples:
//! the 75th percentile of the coverage distance weighted by its square
//! (the area a sample stands for), so that a sparse half of the surface
//! counts by its area although it holds a tenth of the samples. When
//! that spacing exceeds [`UNEVEN`] times the default, the fit thins the
//! samples to it and approximates them (`denoise.rs`): one spacing for
//! the whole surface, the dense parts at the sparse parts' resolution.

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::normals::covariance;
use super::spacing::Nearest;

/// Neighbourhood sizes tried for a sample's coverage distance, smallest
/// first.
const SIZES: [usize; 6] = [6, 12, 24, 48, 96, 192];

/// Most samples whose coverage distance is measured (spread through the
/// set): the percentile over that many is as good as over all.
const CENTRES: usize = 20_000;

/// Samples are uneven when their coverage spacing exceeds this many
/// default spacings. Measured: 1.30 on 20,000 random samples of the
/// torus (about 1.23 in theory: the area-weighted 75th percentile of the
/// 6th-neighbour distance against its median, Gamma(7) against Gamma(6));
/// 1.09-1.83 on CGAL's scanned kitten, armadillo vertices, hippo1 and
/// oni; 3.2-3.5 with a 10:1 density step over half the torus, 4.2-5.4
/// along scan lines 10 times denser along than across, 12.4 on CGAL's
/// radar scan.
pub(super) const UNEVEN: Real = 2.5;

/// The spacing the uneven points of `tree` need (see the module docs) when it exceeds
/// [`UNEVEN`] times `h`, the default spacing; `None` for even samples or
/// when no neighbourhood spans a surface.
pub(super) fn coarse_spacing(tree: &Nearest, h: Real) -> Option<Real> {
    let points = tree.points();
    let stride = points.len().div_ceil(CENTRES).max(1);
    let centres: Vec<usize> = (0..points.len()).step_by(stride).collect();
    let mut coverage: Vec<Real> = centres
        .par_iter()
        .filter_map(|&i| coverage_distance(points, i, &tree.others(i, SIZES[SIZES.len() - 1])))
        .collect();
    if coverage.is_empty() {
        return None;
    }
    coverage.sort_by(Real::total_cmp);
    let total: Real = coverage.iter().map(|r| r * r).sum();
    let mut sum = 0.0;
    let at = coverage.iter().copied().find(|r| {
        sum += r * r;
        sum >= 0.75 * total
    })?;
    let coarse = 0.8 * at;
    // A spacing a tenth of the samples' extent or more resolves no
    // surface (samples along one curve, such as a circle, whose
    // neighbourhoods span a plane only once they span the curve).
    let (lo, hi) = points.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    );
    (coarse > UNEVEN * h && coarse < 0.1 * (hi - lo).norm()).then_some(coarse)
}

/// The distance from `points[i]` to its `k`-th nearest (`near`: distance,
/// index; nearest first) for the smallest `k` of [`SIZES`]
/// whose neighbourhood spans a surface: its second principal variance at
/// least a tenth of the first (as for the normals' curve test). `None`
/// for a sample on a boundary, whose neighbours lie to one side (their
/// mean farther than [`ONE_SIDED`] of that distance from it): its
/// neighbourhood reaches farther for the same density.
fn coverage_distance(points: &[Point3], i: usize, near: &[(Real, usize)]) -> Option<Real> {
    let k = *SIZES.iter().filter(|&&k| k <= near.len()).find(|&&k| {
        let row = &near[..k];
        let (_, cov) =
            covariance(std::iter::once(&points[i]).chain(row.iter().map(|&(_, j)| &points[j])));
        let mut e: Vec<Real> = cov.symmetric_eigen().eigenvalues.iter().copied().collect();
        e.sort_by(|a, b| b.total_cmp(a));
        e[1] >= 0.1 * e[0]
    })?;
    let row = &near[..k];
    let reach = row[k - 1].0;
    let (mean, _) = covariance(row.iter().map(|&(_, j)| &points[j]));
    ((mean - points[i].coords).norm() <= ONE_SIDED * reach).then_some(reach)
}

/// A sample whose neighbours' mean lies farther than this share of their
/// reach from it is on a boundary: about 0.4 for neighbours filling a
/// half disc, little for a full one.
const ONE_SIDED: Real = 0.25;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::shapes::Shape;

    /// Random samples of the torus are even; the same made ten times
    /// sparser over half of it are uneven, and so are samples along lines
    /// five times denser along than across.
    #[test]
    fn uneven_samples_are_told_from_even_ones() {
        let torus = Shape::Torus.sample(20_000, 17).positions;
        let h = |p: &[Point3]| {
            let knn = super::super::spacing::Knn::new(p, 6);
            0.8 * super::super::input::median_of(knn.distances_to(6))
        };
        assert_eq!(
            coarse_spacing(&Nearest::new(&torus).unwrap(), h(&torus)),
            None
        );
        let step: Vec<Point3> = torus
            .iter()
            .enumerate()
            .filter(|(k, p)| p.x <= 0.0 || k % 10 == 0)
            .map(|(_, p)| *p)
            .collect();
        let coarse = coarse_spacing(&Nearest::new(&step).unwrap(), h(&step)).expect("uneven");
        assert!(coarse > 2.5 * h(&step), "{coarse} {}", h(&step));
        let dense = Shape::Torus.sample(200_000, 17).positions;
        let d = 0.1;
        let lines: Vec<Point3> = dense
            .into_iter()
            .filter(|p| (p.y - (p.y / d).round() * d).abs() < 0.0025)
            .collect();
        assert!(coarse_spacing(&Nearest::new(&lines).unwrap(), h(&lines)).is_some());
    }
}
