//! Where each object's particles lie and how densely: the part of the work
//! estimate ([`super::work`]) that counts interacting pairs, within an
//! object and between objects that overlap.
//!
//! A lattice generator is counted analytically from its count, spacing and
//! dimension; a points file or a list from a bounded sample of its
//! particles' neighbourhoods ([`sampled_neighbours`]), so a list of a
//! hundred thousand particles on one point is seen as the dense cloud it
//! is. Each object also has a bounding box, and two objects whose boxes
//! come within the interaction range of each other are counted as
//! overlapping: a particle of one sees the other's particles as densely as
//! the other's own do. Objects made by the same points file share one
//! footprint, read and sampled once ([`Footprints`]).

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

use op_dynamics::{Point3, Real, Vec3};

use crate::error::SceneError;
use crate::generators::Generator;

/// Particles of a points file or list whose neighbourhoods are counted
/// (evenly spread over the list).
pub const NEIGHBOURHOOD_SAMPLE: usize = 512;

/// A grid cell holding more particles than this is counted whole instead
/// of particle by particle (an upper bound that keeps the sample's work
/// linear in it).
const DENSE_CELL: usize = 64;

/// Where an object's particles lie and how densely.
#[derive(Clone)]
pub(crate) struct Footprint {
    /// Particles.
    pub count: Real,
    /// Lower corner of an axis-aligned box holding every particle.
    pub lo: Vec3,
    /// Upper corner of that box.
    pub hi: Vec3,
    /// A nominal spacing: the generator's, or for a cloud the median
    /// distance of its sampled particles to their nearest neighbour.
    pub spacing: Real,
    shape: Shape,
}

/// How an object's particles fill its region.
#[derive(Clone)]
enum Shape {
    /// A lattice of `dim` dimensions (curve 1, surface 2, solid 3) at the
    /// footprint's spacing.
    Lattice { dim: u8 },
    /// Given positions (a points file or list).
    Cloud(Vec<Point3>),
}

/// The half extents along x, y, z of a disc of radius `r` with normal `n`
/// (`r √(1 - n_i²)` for unit `n`; a ball's for a zero normal).
fn disc(r: Real, n: &[Real; 3]) -> Vec3 {
    match Vec3::from(*n).try_normalize(0.0) {
        Some(n) => n.map(|c| r * (1.0 - c * c).max(0.0).sqrt()),
        None => Vec3::repeat(r),
    }
}

impl Footprint {
    /// The footprint of generator `g` (at `path` in scene `file`); points
    /// files are read.
    pub fn of(
        g: &Generator,
        base_dir: Option<&Path>,
        file: &str,
        path: &str,
    ) -> Result<Footprint, SceneError> {
        let v = |a: &[Real; 3]| Vec3::from(*a);
        // A lattice around `center` within `half` along each axis.
        let lattice = |count: Real, center: Vec3, half: Vec3, spacing: Real, dim: u8| Footprint {
            count,
            lo: center - half,
            hi: center + half,
            spacing,
            shape: Shape::Lattice { dim },
        };
        Ok(match g {
            Generator::Spiral {
                count,
                spacing,
                center,
                normal,
                ..
            } => {
                let reach = *count as Real * spacing;
                lattice(*count as Real, v(center), disc(reach, normal), *spacing, 1)
            }
            Generator::Chain {
                count,
                spacing,
                start,
                direction,
                ..
            } => {
                let length = count.saturating_sub(1) as Real * spacing;
                let d = v(direction).try_normalize(0.0).unwrap_or_else(Vec3::x);
                let half = (d * (0.5 * length)).abs();
                lattice(
                    *count as Real,
                    v(start) + d * (0.5 * length),
                    half,
                    *spacing,
                    1,
                )
            }
            Generator::HexSheet {
                nx,
                ny,
                spacing,
                center,
                normal,
                noise,
                ..
            } => {
                // The disc through the corners of its rectangle (centred
                // on `center`, its rows in any direction of the plane).
                let (w, h) = g.sheet_extent().unwrap_or_default();
                let half = disc(0.5 * w.hypot(h), normal).add_scalar(*noise);
                lattice((nx * ny) as Real, v(center), half, *spacing, 2)
            }
            Generator::SphereShell {
                radius,
                spacing,
                center,
                ..
            } => lattice(
                crate::generators::sphere_count(*radius, *spacing),
                v(center),
                Vec3::repeat(*radius),
                *spacing,
                2,
            ),
            Generator::TorusShell {
                major,
                minor,
                spacing,
                center,
                axis,
            } => lattice(
                crate::generators::torus_estimate(*major, *minor, *spacing),
                v(center),
                disc(major + minor, axis).add_scalar(*minor),
                *spacing,
                2,
            ),
            Generator::SolidBall {
                radius,
                spacing,
                center,
            } => lattice(
                crate::generators::solid_ball_estimate(*radius, *spacing),
                v(center),
                Vec3::repeat(*radius),
                *spacing,
                3,
            ),
            Generator::Points { .. } | Generator::List { .. } => {
                let positions = g.generate(base_dir, file, path)?.positions;
                Footprint::cloud(positions)
            }
        })
    }

    /// The footprint of given positions (at least one).
    fn cloud(positions: Vec<Point3>) -> Footprint {
        let (lo, hi) = bounds(&positions);
        let spacing = nearest_spacing(&positions);
        Footprint {
            count: positions.len() as Real,
            lo,
            hi,
            spacing,
            shape: Shape::Cloud(positions),
        }
    }

    /// Half the diagonal of the object's box: the radius of a ball around
    /// it.
    pub fn radius(&self) -> Real {
        0.5 * (self.hi - self.lo).norm()
    }

    /// The mean number of other particles of this object within `range` of
    /// one of them: from the lattice's density for generators (a curve has
    /// `2 range / spacing`, a hexagonal surface `π range² / (0.866
    /// spacing²)`, the face-centred cubic solid `4/3 π range³ √2 /
    /// spacing³`), from the sample for clouds; at most the other
    /// particles.
    pub fn neighbours(&self, range: Real) -> Real {
        let n = match &self.shape {
            Shape::Lattice { dim } => {
                let ratio = range / self.spacing;
                match dim {
                    1 => 2.0 * ratio,
                    2 => std::f64::consts::PI * ratio * ratio / 0.866,
                    _ => 4.0 / 3.0 * std::f64::consts::PI * ratio.powi(3) * 2f64.sqrt(),
                }
            }
            Shape::Cloud(positions) => sampled_neighbours(positions, range),
        };
        n.min(self.count - 1.0).max(0.0)
    }

    /// Whether this object's box comes within `range` of `other`'s along
    /// every axis (a NaN gap counts as apart).
    pub fn near(&self, other: &Footprint, range: Real) -> bool {
        (0..3).all(|c| {
            let gap = (self.lo[c] - other.hi[c]).max(other.lo[c] - self.hi[c]);
            gap <= range
        })
    }

    /// Pairs within `range` between this object and `other`, given
    /// `neighbours = [self.neighbours(range), other.neighbours(range)]`
    /// (counted once per object by the caller, not once per pair of
    /// objects): none when their boxes are farther apart than `range`,
    /// otherwise as if each particle of the denser side saw the other
    /// object as densely as its own particles do (at most every particle
    /// of one with every particle of the other).
    pub fn pairs_with(&self, other: &Footprint, range: Real, neighbours: [Real; 2]) -> Real {
        if !self.near(other, range) {
            return 0.0;
        }
        (self.count * neighbours[1])
            .min(other.count * neighbours[0])
            .min(self.count * other.count)
    }
}

/// Pairs of objects whose boxes come within `range` of each other, each
/// pair once as `(a, b)` with `a < b`: a sweep along x over the boxes
/// sorted by their lower x, `O(n log n)` plus the pairs it finds.
pub(crate) fn near_pairs<F: std::ops::Deref<Target = Footprint>>(
    footprints: &[F],
    range: Real,
) -> Vec<(usize, usize)> {
    let mut order: Vec<usize> = (0..footprints.len()).collect();
    order.sort_by(|&a, &b| footprints[a].lo.x.total_cmp(&footprints[b].lo.x));
    let mut found = Vec::new();
    for (i, &a) in order.iter().enumerate() {
        let reach = footprints[a].hi.x + range;
        for &b in &order[i + 1..] {
            // Sorted by lower x: every later box starts beyond the reach.
            if footprints[b].lo.x > reach {
                break;
            }
            if footprints[a].near(&footprints[b], range) {
                found.push((a.min(b), a.max(b)));
            }
        }
    }
    found.sort_unstable();
    found
}

/// The footprints of a scene's objects, in their order: objects made by
/// the same points file share one (the file read and its neighbourhoods
/// sampled once, however many objects name it), and each footprint's
/// neighbour counts are kept per range.
pub(crate) struct Footprints {
    footprints: Vec<Rc<Footprint>>,
    /// For each object, the first object with the same footprint.
    first: Vec<usize>,
    /// Neighbour counts by first object and range (its bits).
    counted: RefCell<HashMap<(usize, u64), Real>>,
}

impl Footprints {
    /// The footprints of `objects` (generators with their field paths) of
    /// scene `file`, points files relative to `base_dir`.
    pub fn of<'a>(
        objects: impl Iterator<Item = (&'a Generator, String)>,
        base_dir: Option<&Path>,
        file: &str,
    ) -> Result<Footprints, SceneError> {
        let mut footprints: Vec<Rc<Footprint>> = Vec::new();
        let mut first = Vec::new();
        let mut by_path: HashMap<&Path, usize> = HashMap::new();
        for (k, (g, path)) in objects.enumerate() {
            if let Generator::Points { path: points } = g {
                if let Some(&j) = by_path.get(points.as_path()) {
                    footprints.push(footprints[j].clone());
                    first.push(j);
                    continue;
                }
                by_path.insert(points.as_path(), k);
            }
            footprints.push(Rc::new(Footprint::of(g, base_dir, file, &path)?));
            first.push(k);
        }
        Ok(Footprints {
            footprints,
            first,
            counted: RefCell::new(HashMap::new()),
        })
    }

    /// Object `k`'s footprint.
    pub fn get(&self, k: usize) -> &Footprint {
        &self.footprints[k]
    }

    /// Every object's footprint, in order.
    pub fn iter(&self) -> impl Iterator<Item = &Footprint> {
        self.footprints.iter().map(|f| &**f)
    }

    /// [`Footprint::neighbours`] of object `k` at `range`, counted once
    /// per footprint and range.
    pub fn neighbours(&self, k: usize, range: Real) -> Real {
        let key = (self.first[k], range.to_bits());
        if let Some(n) = self.counted.borrow().get(&key) {
            return *n;
        }
        let n = self.footprints[k].neighbours(range);
        self.counted.borrow_mut().insert(key, n);
        n
    }

    /// Object `k`'s own pairs within `range`, at least one per particle
    /// (the particle's own work).
    pub fn own_pairs(&self, k: usize, range: Real) -> Real {
        self.pairs_within(k, range).max(self.footprints[k].count)
    }

    /// Object `k`'s own pairs within `range`: half its particles'
    /// neighbours.
    pub fn pairs_within(&self, k: usize, range: Real) -> Real {
        0.5 * self.footprints[k].count * self.neighbours(k, range)
    }

    /// Pairs within `range` between objects `a` and `b`
    /// ([`Footprint::pairs_with`]).
    pub fn pairs_between(&self, a: usize, b: usize, range: Real) -> Real {
        let counts = [self.neighbours(a, range), self.neighbours(b, range)];
        self.footprints[a].pairs_with(&self.footprints[b], range, counts)
    }

    /// Pairs of objects whose boxes come within `range` ([`near_pairs`]).
    pub fn near_pairs(&self, range: Real) -> Vec<(usize, usize)> {
        near_pairs(&self.footprints, range)
    }
}

/// The mean number of other particles within `range` of a particle of
/// `positions`, counted for at most [`NEIGHBOURHOOD_SAMPLE`] of them
/// (evenly spread over the list) against all, in a grid of cells `range`
/// wide sorted by cell: `O(N log N)` for `N` positions, whatever their
/// density. A cell holding more than [`DENSE_CELL`] particles counts all
/// of them (an upper bound).
pub(crate) fn sampled_neighbours(positions: &[Point3], range: Real) -> Real {
    if positions.len() < 2 || range.is_nan() || range <= 0.0 {
        return 0.0;
    }
    let grid = Grid::new(positions, range);
    let stride = positions.len().div_ceil(NEIGHBOURHOOD_SAMPLE);
    let mut total = 0usize;
    let mut sampled = 0usize;
    for (i, p) in positions.iter().enumerate().step_by(stride) {
        sampled += 1;
        for members in grid.around(p) {
            if members.len() > DENSE_CELL {
                total += members.len();
            } else {
                total += members
                    .iter()
                    .filter(|&&j| j as usize != i && (positions[j as usize] - p).norm() <= range)
                    .count();
            }
        }
    }
    total as Real / sampled as Real
}

/// The median distance from a sample of `positions` to their nearest other
/// particle (1 for a single particle, or when all coincide, the smallest
/// positive distance found otherwise).
fn nearest_spacing(positions: &[Point3]) -> Real {
    if positions.len() < 2 {
        return 1.0;
    }
    let (lo, hi) = bounds(positions);
    // Cells sized for about one particle each in the bounding box's
    // volume (its largest sides for flat and thin sets).
    let sides = hi - lo;
    let largest = sides.max();
    if largest.is_nan() || largest <= 0.0 {
        return 1.0;
    }
    let mut found = Vec::new();
    let mut cell = largest / (positions.len() as Real).cbrt();
    let stride = positions.len().div_ceil(NEIGHBOURHOOD_SAMPLE);
    let samples = positions.len().div_ceil(stride);
    for _ in 0..60 {
        let grid = Grid::new(positions, cell);
        found.clear();
        let mut dense = 0;
        for (i, p) in positions.iter().enumerate().step_by(stride) {
            let mut best = Real::INFINITY;
            let mut crowded = false;
            for members in grid.around(p) {
                crowded |= members.len() > DENSE_CELL;
                for &j in members.iter().take(DENSE_CELL) {
                    let d = (positions[j as usize] - p).norm();
                    if j as usize != i && d > 0.0 && d < best {
                        best = d;
                    }
                }
            }
            if crowded {
                dense += 1;
            } else if best <= cell {
                found.push(best);
            }
        }
        // Cells crowded for most samples: smaller cells; most samples
        // without a neighbour within one cell: larger ones. Otherwise the
        // median is the samples' own.
        if dense * 2 > samples {
            cell *= 0.25;
        } else if found.len() * 2 <= samples {
            cell *= 2.0;
            if cell > 2.0 * largest {
                break;
            }
        } else {
            found.sort_by(Real::total_cmp);
            return found[found.len() / 2];
        }
        if cell.is_nan() || cell <= 0.0 {
            break;
        }
    }
    found
        .iter()
        .copied()
        .fold(Real::INFINITY, Real::min)
        .min(largest)
}

/// The corners of the axis-aligned box of `positions` (infinite and
/// reversed when there are none).
fn bounds(positions: &[Point3]) -> (Vec3, Vec3) {
    positions.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    )
}

/// Particles sorted by grid cell, for counting neighbourhoods.
struct Grid {
    size: Real,
    /// `(cell, index)`, sorted.
    sorted: Vec<([i64; 3], u32)>,
    /// The indices in the order of `sorted`.
    indices: Vec<u32>,
}

impl Grid {
    fn new(positions: &[Point3], size: Real) -> Grid {
        let mut sorted: Vec<([i64; 3], u32)> = Vec::with_capacity(positions.len());
        let mut grid = Grid {
            size,
            sorted: Vec::new(),
            indices: Vec::new(),
        };
        for (i, p) in positions.iter().enumerate() {
            sorted.push((grid.cell_of(p), i as u32));
        }
        sorted.sort_unstable();
        grid.indices = sorted.iter().map(|e| e.1).collect();
        grid.sorted = sorted;
        grid
    }

    /// The cell of `p` (coordinates beyond `i64` saturate: far particles
    /// share a cell, which only overcounts).
    fn cell_of(&self, p: &Point3) -> [i64; 3] {
        [0, 1, 2].map(|c| (p[c] / self.size).floor() as i64)
    }

    /// The particles of the 27 cells around `p`'s (its own included), cell
    /// by cell.
    fn around(&self, p: &Point3) -> impl Iterator<Item = &[u32]> + '_ {
        let c = self.cell_of(p);
        (0..27).map(move |k: i64| {
            let d = [k / 9 - 1, (k / 3) % 3 - 1, k % 3 - 1];
            self.members([0, 1, 2].map(|a| c[a].saturating_add(d[a])))
        })
    }

    /// The particles in `cell`.
    fn members(&self, cell: [i64; 3]) -> &[u32] {
        let start = self.sorted.partition_point(|e| e.0 < cell);
        let end = start + self.sorted[start..].partition_point(|e| e.0 == cell);
        &self.indices[start..end]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize, spacing: Real) -> Vec<Point3> {
        (0..n)
            .map(|i| Point3::new(i as Real * spacing, 0.0, 0.0))
            .collect()
    }

    #[test]
    fn a_line_has_its_neighbours_on_both_sides() {
        let p = line(10_000, 0.5);
        let n = sampled_neighbours(&p, 1.2);
        // Four within 1.2 (two each side), a little fewer at the ends.
        assert!((n - 4.0).abs() < 0.05, "{n}");
        assert!((nearest_spacing(&p) - 0.5).abs() < 1e-12);
    }

    /// The footprints of a scene of one object.
    fn alone(f: Footprint) -> Footprints {
        Footprints {
            footprints: vec![Rc::new(f)],
            first: vec![0],
            counted: RefCell::new(HashMap::new()),
        }
    }

    #[test]
    fn a_cloud_on_one_point_is_counted_whole_and_fast() {
        let p = vec![Point3::new(1.0, 2.0, 3.0); 100_000];
        let n = sampled_neighbours(&p, 1.0);
        assert!(n >= 99_999.0, "{n}");
        let f = Footprint::cloud(p);
        assert_eq!(f.neighbours(1.0), 99_999.0);
        assert!(alone(f).own_pairs(0, 1.0) > 4e9);
    }

    #[test]
    fn a_lattice_cloud_agrees_with_the_lattice_estimate() {
        // A square grid of spacing 1 against a 2-d lattice footprint: the
        // hexagonal density is 15% higher, so within 20%.
        let mut p = Vec::new();
        for i in 0..100 {
            for j in 0..100 {
                p.push(Point3::new(i as Real, j as Real, 0.0));
            }
        }
        let cloud = Footprint::cloud(p);
        assert!((cloud.spacing - 1.0).abs() < 1e-12);
        let g = Generator::HexSheet {
            nx: 100,
            ny: 100,
            spacing: 1.0,
            center: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            noise: 0.0,
            seed: 0,
        };
        let sheet = Footprint::of(&g, None, "t", "g").unwrap();
        let (a, b) = (cloud.neighbours(2.5), sheet.neighbours(2.5));
        assert!((a / b - 1.0).abs() < 0.2, "{a} against {b}");
    }

    #[test]
    fn overlapping_objects_pair_and_distant_ones_do_not() {
        let chain = |y: Real| Generator::Chain {
            count: 100,
            spacing: 1.0,
            start: [0.0, y, 0.0],
            direction: [1.0, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
        };
        let a = Footprint::of(&chain(0.0), None, "t", "a").unwrap();
        let b = Footprint::of(&chain(0.1), None, "t", "b").unwrap();
        let far = Footprint::of(&chain(1e3), None, "t", "c").unwrap();
        let near = |f: &Footprint, g: &Footprint| [f.neighbours(2.5), g.neighbours(2.5)];
        assert_eq!(a.pairs_with(&b, 2.5, near(&a, &b)), 100.0 * 5.0);
        assert_eq!(a.pairs_with(&far, 2.5, near(&a, &far)), 0.0);
        let all = [&a, &far, &b];
        assert_eq!(near_pairs(&all, 2.5), vec![(0, 2)]);
        assert_eq!(alone(a).own_pairs(0, 2.5), 250.0);
    }
}
