//! Open data found by itself: the samples on a boundary of the sampled
//! surface (the rim of a sheet, the edge of a partial scan).
//!
//! Seen from a sample inside the surface, its nearest neighbours lie all
//! around it in its tangent plane; seen from one on a boundary, on one
//! side only. The largest angle between consecutive neighbours about the
//! sample, in its tangent plane, tells them apart (the angle criterion of
//! boundary detection in point clouds, as in Bendels et al. 2006): on a
//! straight rim the gap among the 12 nearest is half a turn, inside
//! randomly sampled data rarely over a quarter, except at the rims of the
//! gaps random sampling leaves by chance. A boundary is a chain of
//! samples past [`GAP`], joined as nearest neighbours, that spans more
//! than [`SPAN`] times the widest such chance gap: on random samples of
//! the closed shapes of [`super::shapes`] (500 to 20,000) the chains are
//! the rims of chance gaps (one of 10 samples on 5,000 samples of the
//! torus) and none is a boundary; the open saddle's rims are.

use std::collections::HashMap;

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::holes::sampling_gap_width;
use super::input::median_of;
use super::spacing::Knn;
use crate::disjoint_sets::DisjointSets;

/// Neighbours seen about a sample.
const NEIGHBOURS: usize = 12;

/// A sample whose neighbours leave a gap wider than this (radians) about
/// it in its tangent plane lies on a boundary: 150°, between the 90° or
/// less of a sample inside randomly sampled data and the 180° of one on a
/// straight rim.
const GAP: Real = 150.0 * std::f64::consts::PI / 180.0;

/// A chain of boundary samples is a boundary when it spans more than this
/// many times the widest gap random sampling leaves by chance at the
/// samples' density (`holes::sampling_gap_width`): the rim of a chance
/// gap spans about its width.
const SPAN: Real = 2.0;

/// Whether `seeds` (with unit `normals`) have a boundary: a chain of
/// boundary samples spanning more than [`SPAN`] chance gaps (module docs).
pub(super) fn has_boundary(seeds: &[Point3], normals: &[Vec3]) -> bool {
    let knn = Knn::new(seeds, NEIGHBOURS);
    if knn.k() < 6 {
        return false;
    }
    let r6 = median_of(knn.distances_to(6));
    widest_chain(seeds, normals, &knn) > SPAN * sampling_gap_width(seeds.len(), r6)
}

/// The span (bounding box diagonal) of the widest chain of boundary
/// samples: samples whose neighbours in `knn` leave a gap wider than
/// [`GAP`] about them and all face their way (a neighbour facing away is
/// the other side of a thin part: its rim has all its neighbours to one
/// side too, but it is no boundary), joined where one is among the
/// other's nearest.
fn widest_chain(seeds: &[Point3], normals: &[Vec3], knn: &Knn) -> Real {
    let on: Vec<bool> = (0..seeds.len())
        .into_par_iter()
        .map(|i| {
            let row = knn.neighbours(i);
            // Neighbours facing away: the other side of a part thinner
            // than the neighbourhood, whose rim is no boundary.
            let thin = row.iter().any(|&j| normals[j].dot(&normals[i]) < 0.0);
            !thin && widest_gap(seeds, normals[i], i, row) > GAP
        })
        .collect();
    // Chains: components of the boundary samples.
    let mut chains = DisjointSets::new(seeds.len());
    for i in (0..seeds.len()).filter(|&i| on[i]) {
        for &j in knn.neighbours(i) {
            if on[j] {
                chains.union(i, j);
            }
        }
    }
    let mut boxes: HashMap<usize, (Vec3, Vec3)> = HashMap::new();
    for i in (0..seeds.len()).filter(|&i| on[i]) {
        let r = chains.root(i);
        let p = seeds[i].coords;
        let b = boxes.entry(r).or_insert((p, p));
        *b = (b.0.inf(&p), b.1.sup(&p));
    }
    boxes
        .values()
        .map(|(lo, hi)| (hi - lo).norm())
        .fold(0.0, Real::max)
}

/// The widest angle between consecutive neighbours `row` of `seeds[i]`
/// about it, projected into its tangent plane (normal `normal`); a full
/// turn when fewer than two project off the sample.
fn widest_gap(seeds: &[Point3], normal: Vec3, i: usize, row: &[usize]) -> Real {
    let tau = std::f64::consts::TAU;
    // A frame of the tangent plane.
    let helper = if normal.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let e1 = normal.cross(&helper).normalize();
    let e2 = normal.cross(&e1);
    let mut angles: Vec<Real> = row
        .iter()
        .filter_map(|&j| {
            let d = seeds[j] - seeds[i];
            let (x, y) = (d.dot(&e1), d.dot(&e2));
            (x != 0.0 || y != 0.0).then(|| y.atan2(x))
        })
        .collect();
    if angles.len() < 2 {
        return tau;
    }
    angles.sort_by(Real::total_cmp);
    let wrap = angles[0] + tau - angles[angles.len() - 1];
    angles.windows(2).map(|w| w[1] - w[0]).fold(wrap, Real::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::normals::knn_normals;
    use crate::fit::shapes::Shape;

    /// The widest gap of a sample amid a ring of neighbours is the ring's
    /// step; on the edge of a half ring, half a turn.
    #[test]
    fn gaps_about_a_sample() {
        let ring: Vec<Point3> = std::iter::once(Point3::origin())
            .chain((0..8).map(|k| {
                let a = k as Real * std::f64::consts::TAU / 8.0;
                Point3::new(a.cos(), a.sin(), 0.0)
            }))
            .collect();
        let all: Vec<usize> = (1..9).collect();
        let gap = widest_gap(&ring, Vec3::z(), 0, &all);
        assert!((gap - std::f64::consts::FRAC_PI_4).abs() < 1e-12, "{gap}");
        let half: Vec<usize> = (1..6).collect();
        let gap = widest_gap(&ring, Vec3::z(), 0, &half);
        assert!((gap - std::f64::consts::PI).abs() < 1e-12, "{gap}");
    }

    /// Random samples of the closed shapes have no boundary; the open
    /// saddle with a hole has (its outer rim and its hole). Normals as the
    /// fit estimates them (local PCA).
    #[test]
    fn closed_shapes_have_no_boundary_and_the_saddle_has() {
        let open = |shape: Shape, n: usize| {
            let samples = shape.sample(n, 17).positions;
            let normals = knn_normals(&samples, &Knn::new(&samples, 12));
            has_boundary(&samples, &normals)
        };
        for shape in [Shape::Ellipsoid, Shape::Torus, Shape::DoubleTorus] {
            for n in [500, 5000, 20000] {
                assert!(!open(shape, n), "{} {n}", shape.name());
            }
        }
        for n in [500, 5000, 20000] {
            assert!(open(Shape::HoledSaddle, n), "saddle {n}");
        }
    }
}
