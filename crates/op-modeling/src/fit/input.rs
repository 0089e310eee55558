//! Degenerate-input checks and the data frame: normalization to unit scale.

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::PointSet;
use super::{FitError, MAX_PARTICLES};

/// The data frame: a sample `p` is `2 (centre + scale q)` with `q` in
/// `[-1, 1]³` (halves first, so no step overflows at any finite scale).
pub(super) struct Frame {
    /// Half the bounding box's centre.
    centre: Vec3,
    /// Half the bounding box's largest side.
    scale: Real,
}

impl Frame {
    pub(super) fn to_local(&self, p: &Point3) -> Point3 {
        Point3::from((p.coords * 0.5 - self.centre) / self.scale)
    }

    pub(super) fn to_data(&self, q: &Point3) -> Point3 {
        Point3::from((self.centre + q.coords * self.scale) * 2.0)
    }

    pub(super) fn length_to_data(&self, d: Real) -> Real {
        d * self.scale * 2.0
    }

    pub(super) fn length_to_local(&self, d: Real) -> Real {
        d * 0.5 / self.scale
    }
}

/// Samples that passed the degenerate-input checks, mapped into the unit
/// box.
pub(super) struct Input {
    /// The data frame.
    pub(super) frame: Frame,
    /// The samples in the frame's local coordinates (within `[-1, 1]³`).
    pub(super) local: Vec<Point3>,
    /// The bounding box's diagonal in local units.
    pub(super) diagonal: Real,
    /// The distinct local samples (first occurrence kept, in order).
    pub(super) distinct: Vec<Point3>,
}

impl Input {
    /// Checks `data` (at least 3 finite samples, 3 distinct, at most
    /// [`MAX_PARTICLES`] distinct, as many normals as samples, a
    /// representable bounding box) and maps it into the unit box.
    pub(super) fn check(data: &PointSet) -> Result<Input, FitError> {
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
        Ok(Input {
            frame,
            local,
            diagonal,
            distinct,
        })
    }
}

/// The bits of a point's coordinates (`-0` as `+0`): equal for equal
/// points.
pub(super) fn bits(p: &Point3) -> [u64; 3] {
    [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits())
}

/// The points of `points` without exact repeats (first occurrence kept, in
/// order).
pub(super) fn distinct_points(points: &[Point3]) -> Vec<Point3> {
    let keys: Vec<[u64; 3]> = points.par_iter().map(bits).collect();
    let mut order: Vec<usize> = (0..points.len()).collect();
    // A total order (ties broken by index): the same at any thread count.
    order.par_sort_unstable_by(|&a, &b| keys[a].cmp(&keys[b]).then(a.cmp(&b)));
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
pub(super) fn median_of(mut v: Vec<Real>) -> Real {
    // `total_cmp` is a total order: equal values are equal bits, so the
    // parallel sort gives the serial sort's array.
    v.par_sort_unstable_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Whether the points all lie within `tolerance` of one line (the
/// principal axis through their mean): their largest distance from it if
/// so.
pub(super) fn collinear_within(points: &[Point3], tolerance: Real) -> Option<Real> {
    let (mean, cov) = super::normals::covariance(points.iter());
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
