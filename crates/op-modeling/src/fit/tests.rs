//! Tests of the fit: the spacing range and the inputs it refuses.

use super::*;

use crate::fit::shapes::scattered;

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
