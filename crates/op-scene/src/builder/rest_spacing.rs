//! The rest spacing of an object: the mean nearest-neighbour distance of
//! its particles at rest.

use op_dynamics::neighbours::{search, PairList};
use op_dynamics::{NeighbourBackend, Point3, Real};

/// Mean nearest-neighbour distance of `positions`, or the pair `(i, j)` of
/// the first particle found to coincide with another. A single particle
/// gets `nominal` (or 1).
///
/// Radius searches start at 1.5 `nominal` (or a quarter of the bounding
/// box's largest side over `√n` when there is none) and double while more
/// than a few particles have no neighbour; the remaining ones are found by
/// brute force.
pub(crate) fn rest_spacing(
    positions: &[Point3],
    nominal: Option<Real>,
) -> Result<Real, (usize, usize)> {
    let n = positions.len();
    if n < 2 {
        return Ok(nominal.unwrap_or(1.0));
    }
    let mut radius = match nominal {
        Some(s) => 1.5 * s,
        None => {
            let (mut lo, mut hi) = (positions[0].coords, positions[0].coords);
            for p in positions {
                lo = lo.inf(&p.coords);
                hi = hi.sup(&p.coords);
            }
            0.25 * (hi - lo).max() / (n as Real).sqrt()
        }
    };
    let mut best = vec![(Real::INFINITY, usize::MAX); n];
    let mut list = PairList::new();
    for _ in 0..64 {
        search(NeighbourBackend::CellList, positions, radius, &mut list);
        for (i, j) in list.iter_pairs() {
            let d = (positions[j] - positions[i]).norm();
            if d < best[i].0 {
                best[i] = (d, j);
            }
            if d < best[j].0 {
                best[j] = (d, i);
            }
        }
        let missing = best.iter().filter(|b| b.0.is_infinite()).count();
        if missing == 0 {
            break;
        }
        if missing.saturating_mul(n) <= 20_000_000 || !radius.is_finite() || radius <= 0.0 {
            for i in 0..n {
                if best[i].0.is_infinite() {
                    for j in (0..n).filter(|&j| j != i) {
                        let d = (positions[j] - positions[i]).norm();
                        if d < best[i].0 {
                            best[i] = (d, j);
                        }
                    }
                }
            }
            break;
        }
        radius *= 2.0;
    }
    if let Some((i, b)) = best.iter().enumerate().find(|(_, b)| b.0 <= 0.0) {
        return Err((i, b.1));
    }
    Ok(best.iter().map(|b| b.0).sum::<Real>() / n as Real)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rest_spacing_of_a_line_and_outliers() {
        let line: Vec<Point3> = (0..10)
            .map(|i| Point3::new(i as Real * 0.5, 0.0, 0.0))
            .collect();
        assert!((rest_spacing(&line, Some(0.5)).unwrap() - 0.5).abs() < 1e-12);
        assert!((rest_spacing(&line, None).unwrap() - 0.5).abs() < 1e-12);
        // A far outlier: found by brute force, not by growing the radius.
        let mut pts = line.clone();
        pts.push(Point3::new(1000.0, 0.0, 0.0));
        let m = rest_spacing(&pts, Some(0.5)).unwrap();
        let expected = (10.0 * 0.5 + (1000.0 - 4.5)) / 11.0;
        assert!((m - expected).abs() < 1e-9, "{m} vs {expected}");
        assert_eq!(rest_spacing(&[Point3::origin()], Some(0.3)).unwrap(), 0.3);
        let same = vec![Point3::new(1.0, 1.0, 1.0); 3];
        assert!(rest_spacing(&same, None).is_err());
    }
}
