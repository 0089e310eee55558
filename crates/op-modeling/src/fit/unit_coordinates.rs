//! The fit's unit-spacing coordinates: the samples about their centroid
//! with the spacing as unit length (module docs of [`super`]), the seeds
//! merged there, and the mapping of the fitted mesh back to the data.

use op_dynamics::{Point3, Real, Vec3};

use super::input::{collinear_within, Frame};
use super::spacing::merge_close;
use super::{FitError, SurfaceMesh, ThinFeature, MERGE};

/// The samples in unit-spacing coordinates and the seeds kept from them.
pub(super) struct UnitSamples {
    /// The samples' centroid (local units).
    pub(super) centroid: Vec3,
    /// Every sample, `(p - centroid) / h`.
    pub(super) unit: Vec<Point3>,
    /// Indices of the samples kept after merging those within [`MERGE`].
    pub(super) kept: Vec<usize>,
    /// The kept samples (unit coordinates).
    pub(super) seeds: Vec<Point3>,
}

/// The `n` samples `local` at spacing `h` (local units) in unit-spacing
/// coordinates about their centroid, and the seeds left after merging
/// those within a quarter spacing; refuses samples on a line and fewer
/// than 3 seeds (`spacing`, in data units, names the spacing in the
/// messages).
pub(super) fn unit_samples(
    local: &[Point3],
    n: usize,
    frame: &Frame,
    h: Real,
    spacing: Real,
) -> Result<UnitSamples, FitError> {
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
    Ok(UnitSamples {
        centroid,
        unit,
        kept,
        seeds,
    })
}

/// Maps the mesh (vertices and distances) and the thin features from unit
/// coordinates back to the data's; refuses a mesh that is not finite there
/// (`diagonal`: the samples' bounding box diagonal, local units).
pub(super) fn to_data(
    mesh: &mut SurfaceMesh,
    thin: Vec<ThinFeature>,
    frame: &Frame,
    h: Real,
    centroid: Vec3,
    diagonal: Real,
) -> Result<Vec<ThinFeature>, FitError> {
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
    Ok(thin
        .into_iter()
        .map(|t| ThinFeature {
            centre: to_data(&t.centre),
            thickness: frame.length_to_data(t.thickness * h),
            ..t
        })
        .collect())
}
