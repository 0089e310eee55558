//! The triangulated surface and its distance to the samples.

use rayon::prelude::*;

use crate::cell_map::CellMap;
use crate::triangulation::{triangulate_points, EdgeTable, Triangulation, TriangulationParams};
use op_dynamics::{Point3, Real, Vec3};

use super::FitError;

/// A triangulated particle surface (seed 000 §5) and its distance to the
/// data it interpolates: what [`super::fit`] reports, and what the fit scenes'
/// figure tests measure on a run's final particles.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMesh {
    /// Mesh vertices: the particles used by some triangle.
    pub vertices: Vec<Point3>,
    /// Unit normals of the vertices (the particle normals).
    pub normals: Vec<Vec3>,
    /// Triangles as indices into `vertices`, wound along the normals.
    pub faces: Vec<[u32; 3]>,
    /// `V - E + F` of the mesh.
    pub euler_characteristic: i64,
    /// Number of boundary loops of the mesh.
    pub boundary_loops: usize,
    /// RMS distance from the samples to the triangles (infinite without
    /// a triangle).
    pub rms_distance: Real,
    /// Largest distance from a sample to the triangles.
    pub max_distance: Real,
}

impl SurfaceMesh {
    /// Triangulates particles at `positions` with unit `normals`
    /// ([`triangulate_points`], mutual-neighbour distance `radius`, the
    /// two sides of thin features kept apart:
    /// [`TriangulationParams::separate_sides`]) and
    /// measures the distances from `samples` to the triangles.
    ///
    /// # Errors
    /// An invalid radius (not finite or not > 0).
    pub fn new(
        positions: &[Point3],
        normals: &[Vec3],
        radius: Real,
        samples: &[Point3],
    ) -> Result<Self, FitError> {
        Self::with_distances(positions, normals, radius, samples).map(|(mesh, _)| mesh)
    }

    /// [`Self::new`], with the distance from each of `samples` to the
    /// triangles ([`sample_distances`]).
    ///
    /// # Errors
    /// As [`Self::new`].
    pub(super) fn with_distances(
        positions: &[Point3],
        normals: &[Vec3],
        radius: Real,
        samples: &[Point3],
    ) -> Result<(Self, Vec<Real>), FitError> {
        let triangles = triangulate_points(
            positions,
            normals,
            &TriangulationParams {
                separate_sides: true,
                ..TriangulationParams::with_radius(radius)
            },
        )?;
        let mesh = Triangulation {
            triangles: triangles.clone(),
        };
        let mut index = vec![u32::MAX; positions.len()];
        let mut vertices = Vec::new();
        let mut normals_out = Vec::new();
        let faces: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    let v = v as usize;
                    if index[v] == u32::MAX {
                        index[v] = vertices.len() as u32;
                        vertices.push(positions[v]);
                        normals_out.push(normals[v]);
                    }
                    index[v]
                })
            })
            .collect();
        let d = sample_distances(samples, &vertices, &faces);
        let (rms_distance, max_distance) = rms_and_max(&d);
        let edges = EdgeTable::new(&mesh.triangles);
        let mesh = SurfaceMesh {
            euler_characteristic: mesh.euler_characteristic_with(&edges),
            boundary_loops: Triangulation::boundary_loops_of(&edges),
            vertices,
            normals: normals_out,
            faces,
            rms_distance,
            max_distance,
        };
        Ok((mesh, d))
    }

    /// Root mean square over the vertices of `distance`, a distance to the
    /// surface the samples came from (known for synthetic data): how close
    /// the particles lie to it. NaN without a vertex.
    pub fn vertex_rms(&self, distance: impl Fn(&Point3) -> Real) -> Real {
        let sum: Real = self.vertices.iter().map(|v| distance(v).powi(2)).sum();
        (sum / self.vertices.len() as Real).sqrt()
    }

    /// Drops the vertices no face uses any more (the faces of a Möbius
    /// band's cut or of a speck were dropped), keeping the order of the
    /// others: every vertex is then a particle used by some triangle, and
    /// an exported OBJ has no loose vertices (ten on the scanned
    /// armadillo). Returns how many were dropped.
    pub(super) fn drop_unused_vertices(&mut self) -> usize {
        let mut index = vec![u32::MAX; self.vertices.len()];
        for f in &self.faces {
            for &v in f {
                index[v as usize] = 0;
            }
        }
        let mut kept = 0u32;
        for slot in index.iter_mut().filter(|slot| **slot == 0) {
            *slot = kept;
            kept += 1;
        }
        let dropped = self.vertices.len() - kept as usize;
        if dropped > 0 {
            let keep = |k: &usize| index[*k] != u32::MAX;
            self.vertices = (0..self.vertices.len())
                .filter(keep)
                .map(|k| self.vertices[k])
                .collect();
            self.normals = (0..self.normals.len())
                .filter(keep)
                .map(|k| self.normals[k])
                .collect();
            for f in &mut self.faces {
                *f = f.map(|v| index[v as usize]);
            }
        }
        dropped
    }

    /// Recomputes the Euler characteristic, the boundary loops and the
    /// distances from `samples` after the faces changed (the fit knows the
    /// distances before: [`Self::measure_since`]).
    #[cfg(test)]
    pub(super) fn measure(&mut self, samples: &[Point3]) {
        self.measure_topology();
        let d = sample_distances(samples, &self.vertices, &self.faces);
        (self.rms_distance, self.max_distance) = rms_and_max(&d);
    }

    /// [`Self::measure`] for a mesh that had the triangles `before`
    /// (vertices, faces), from which `samples` lay at `distances`: only
    /// what the change touched is searched ([`sample_distances_after`]),
    /// with the same figures.
    pub(super) fn measure_since(
        &mut self,
        samples: &[Point3],
        before: (&[Point3], &[[u32; 3]]),
        distances: &[Real],
    ) {
        self.measure_topology();
        let d = sample_distances_after(samples, distances, before, (&self.vertices, &self.faces));
        debug_assert!(
            d.iter().map(|x| x.to_bits()).eq(sample_distances(
                samples,
                &self.vertices,
                &self.faces
            )
            .iter()
            .map(|x| x.to_bits())),
            "the distances after the change are a fresh search's"
        );
        (self.rms_distance, self.max_distance) = rms_and_max(&d);
    }

    /// The Euler characteristic and boundary loops of the faces.
    fn measure_topology(&mut self) {
        let t = Triangulation {
            triangles: self.faces.clone(),
        };
        let edges = EdgeTable::new(&t.triangles);
        self.euler_characteristic = t.euler_characteristic_with(&edges);
        self.boundary_loops = Triangulation::boundary_loops_of(&edges);
    }
}

/// RMS and largest of the distances `d` (NaN RMS when there is none).
fn rms_and_max(d: &[Real]) -> (Real, Real) {
    let sum: Real = d.iter().map(|x| x * x).sum();
    (
        (sum / d.len() as Real).sqrt(),
        d.iter().copied().fold(0.0, Real::max),
    )
}

/// Distance from each of `samples` to the triangles (infinite when there is
/// no triangle).
///
/// The triangles are binned by their centroids in grids (`Bins`): most
/// in a grid of the longest edge of all but the longest hundredth
/// (`SMALL_SHARE`), the rest (the fans that close holes, a few times
/// longer) in a grid of the longest edge of all. A sample looks through
/// each grid's cells in shells about its own until no triangle binned
/// farther out can be nearer than the nearest found (`Bins::bound`):
/// exact, and a sample off the mesh (noise, an outlier kept, a hole left
/// open) costs shells, not every triangle. One grid of the longest edge
/// made each sample test a few hundred triangles on a million random
/// samples of the torus (cells 4.3 times the median longest edge: 41 s of
/// its 92 s).
pub fn sample_distances(samples: &[Point3], vertices: &[Point3], faces: &[[u32; 3]]) -> Vec<Real> {
    if faces.is_empty() || samples.is_empty() {
        return vec![Real::INFINITY; samples.len()];
    }
    let longest: Vec<Real> = faces
        .par_iter()
        .map(|f| longest_edge(vertices, f))
        .collect();
    let mut sorted = longest.clone();
    sorted.par_sort_unstable_by(Real::total_cmp);
    let small_cell = sorted[((sorted.len() - 1) as Real * SMALL_SHARE) as usize].max(1e-12);
    let (small, big): (Vec<u32>, Vec<u32>) =
        (0..faces.len() as u32).partition(|&t| longest[t as usize] <= small_cell);
    let cell_of = |set: &[u32]| {
        set.iter()
            .map(|&t| longest[t as usize])
            .fold(1e-12, Real::max)
    };
    let grids = [
        Bins::new(vertices, faces, small, cell_of),
        Bins::new(vertices, faces, big, cell_of),
    ];
    // Each sample on its own: in parallel, the same at any thread count.
    samples
        .par_iter()
        .map(|p| nearest_below(&grids, (vertices, faces), p, Real::INFINITY))
        .collect()
}

/// The distance from each of `samples` to the triangles `after` (vertices,
/// faces), given `distances`, theirs to the triangles `before`: the
/// figures of [`sample_distances`] of `after`, searching only what changed.
///
/// The triangles are matched by their corners' coordinates (bits, in
/// order), so renumbered vertices and reordered faces count as unchanged.
/// A sample's distance is the least over the triangles; when none of the
/// triangles that went lies as near as its distance before, one at that
/// distance stayed, and its distance now is the lesser of that and its
/// distance to the triangles that came; otherwise (the nearest went) it
/// is searched afresh among all of `after`. Closing the holes of a fit
/// changes few of its triangles (none of the two million of a million
/// samples of the torus, where the full search took 2.3 s of the 4.1 s of
/// holes and distances at one thread, and matching the faces 0.25 s).
pub(super) fn sample_distances_after(
    samples: &[Point3],
    distances: &[Real],
    before: (&[Point3], &[[u32; 3]]),
    after: (&[Point3], &[[u32; 3]]),
) -> Vec<Real> {
    let (gone, came) = changed_faces(before, after);
    let grid = |(vertices, faces): (&[Point3], &[[u32; 3]]), set: Vec<u32>| {
        let longest = |set: &[u32]| {
            set.iter()
                .map(|&t| longest_edge(vertices, &faces[t as usize]))
                .fold(1e-12, Real::max)
        };
        [Bins::new(vertices, faces, set, longest)]
    };
    let (gone, came) = (grid(before, gone), grid(after, came));
    // `None`: the sample's nearest triangle went.
    let kept: Vec<Option<Real>> = samples
        .par_iter()
        .zip(distances)
        .map(|(p, &d)| {
            let went =
                !gone[0].binned.is_empty() && nearest_below(&gone, before, p, d.next_up()) <= d;
            (!went).then(|| nearest_below(&came, after, p, d))
        })
        .collect();
    let lost: Vec<Point3> = samples
        .iter()
        .zip(&kept)
        .filter(|(_, d)| d.is_none())
        .map(|(p, _)| *p)
        .collect();
    let mut afresh = sample_distances(&lost, after.0, after.1).into_iter();
    kept.into_iter()
        .map(|d| d.or_else(|| afresh.next()).unwrap_or(Real::INFINITY))
        .collect()
}

/// The faces of `before` that are not in `after` and those of `after` not
/// in `before` (indices), as multisets of triangles by their corners'
/// coordinate bits, in order. Faces are paired by fingerprints (of their
/// corners' fingerprints) sorted side by side, the k-th of a run of equal
/// fingerprints in `before` with the k-th in `after`; each pair is then
/// compared in full, in `before`'s order (faces kept stay in order, so
/// both reads run through memory), and a pair whose corners differ (a
/// fingerprint collision) counts as one face gone and one come, which
/// the caller searches as changed: never a change missed.
fn changed_faces(
    before: (&[Point3], &[[u32; 3]]),
    after: (&[Point3], &[[u32; 3]]),
) -> (Vec<u32>, Vec<u32>) {
    let mix = |h: u64, x: u64| (h ^ x).wrapping_mul(0x9e37_79b9_7f4a_7c15).rotate_left(29);
    let fingerprints = |(vertices, faces): (&[Point3], &[[u32; 3]])| {
        let corner: Vec<u64> = vertices
            .par_iter()
            .map(|p| [p.x, p.y, p.z].iter().fold(0, |h, c| mix(h, c.to_bits())))
            .collect();
        let mut f: Vec<(u64, u32)> = faces
            .par_iter()
            .enumerate()
            .map(|(t, f)| {
                (
                    f.iter().fold(0, |h, &v| mix(h, corner[v as usize])),
                    t as u32,
                )
            })
            .collect();
        f.par_sort_unstable();
        f
    };
    let (a, b) = (fingerprints(before), fingerprints(after));
    // The face of `after` paired with each face of `before`.
    let mut pair = vec![u32::MAX; before.1.len()];
    let mut came = Vec::new();
    let (mut i, mut j) = (0, 0);
    while let Some(next) = a.get(i).into_iter().chain(b.get(j)).map(|x| x.0).min() {
        let run =
            |v: &[(u64, u32)], k: usize| k + v[k..].iter().take_while(|x| x.0 == next).count();
        let (ie, je) = (run(&a, i), run(&b, j));
        for (x, y) in a[i..ie].iter().zip(&b[j..je]) {
            pair[x.1 as usize] = y.1;
        }
        let paired = (ie - i).min(je - j);
        came.extend(b[j + paired..je].iter().map(|y| y.1));
        (i, j) = (ie, je);
    }
    let corners = |(vertices, faces): (&[Point3], &[[u32; 3]]), t: u32| {
        faces[t as usize].map(|v| vertices[v as usize].coords.map(Real::to_bits))
    };
    let collided: Vec<(u32, u32)> = pair
        .par_iter()
        .enumerate()
        .filter(|&(t, &u)| u == u32::MAX || corners(before, t as u32) != corners(after, u))
        .map(|(t, &u)| (t as u32, u))
        .collect();
    let gone = collided.iter().map(|&(t, _)| t).collect();
    came.extend(collided.iter().map(|&(_, u)| u).filter(|&u| u != u32::MAX));
    (gone, came)
}

/// The longest edge of the triangle `f`.
fn longest_edge(vertices: &[Point3], f: &[u32; 3]) -> Real {
    (0..3)
        .map(|k| (vertices[f[k] as usize] - vertices[f[(k + 1) % 3] as usize]).norm())
        .fold(0.0, Real::max)
}

/// The distance from `p` to the nearest triangle of `mesh` (vertices,
/// faces) binned in `grids`, or `start` when none is nearer: each grid's
/// cells in shells about `p`'s (its own cell first), until no triangle
/// binned farther out can be nearer ([`Bins::bound`]); past as many cells
/// as the grid has triangles, all of them. A triangle whose bounding box
/// is farther than the best so far is skipped (squared: a best of zero
/// still reads the triangles its box touches).
fn nearest_below(
    grids: &[Bins],
    (vertices, faces): (&[Point3], &[[u32; 3]]),
    p: &Point3,
    start: Real,
) -> Real {
    let closer = |best: Real, t: usize| {
        let [a, b, c] = faces[t].map(|v| &vertices[v as usize]);
        let outside = (0..3)
            .map(|k| {
                let (lo, hi) = (a[k].min(b[k]).min(c[k]), a[k].max(b[k]).max(c[k]));
                (lo - p[k]).max(p[k] - hi).max(0.0)
            })
            .fold(0.0, |s, d| s + d * d);
        if outside > best * best {
            best
        } else {
            best.min(point_triangle_distance(p, a, b, c))
        }
    };
    let mut best = start;
    for g in grids {
        for r in 0i64.. {
            if g.binned.is_empty() {
                break;
            }
            if (2 * r + 1).pow(3) as usize > g.binned.len() {
                best = g
                    .binned
                    .iter()
                    .fold(best, |b, &(_, t)| closer(b, t as usize));
                break;
            }
            best = g.shell(p, r).fold(best, closer);
            if best <= g.bound(r) {
                break;
            }
        }
    }
    best
}

/// Share of the triangles, shortest longest edge first, in the small grid
/// of [`sample_distances`].
const SMALL_SHARE: Real = 0.99;

/// Triangles binned by the cell of their centroid in a grid of cell
/// `cell`, at least the longest edge of each: a triangle's points lie
/// within two thirds of its longest edge (at most `cell`) of its
/// centroid, which bounds how near a triangle binned far from a point can
/// be ([`Bins::bound`]).
struct Bins {
    cell: Real,
    /// `(cell, triangle)`, sorted.
    binned: Vec<([i64; 3], u32)>,
    /// Each cell's run in `binned`.
    /// (Cells are hashed by [`crate::cell_map::CellHasher`]: a million
    /// samples make tens of millions of lookups.)
    runs: CellMap<(usize, usize)>,
}

impl Bins {
    /// Bins `set` (triangles of `faces`) in a grid of cell `cell_of(set)`.
    fn new(
        vertices: &[Point3],
        faces: &[[u32; 3]],
        set: Vec<u32>,
        cell_of: impl Fn(&[u32]) -> Real,
    ) -> Bins {
        let cell = cell_of(&set);
        // The triangles sorted by the cell of their centroid (a parallel
        // sort of distinct pairs), each cell's run found through a map.
        let mut binned: Vec<([i64; 3], u32)> = set
            .into_par_iter()
            .map(|t| {
                let c = faces[t as usize]
                    .iter()
                    .fold(Vec3::zeros(), |s, &v| s + vertices[v as usize].coords)
                    / 3.0;
                (key(&c, cell), t)
            })
            .collect();
        binned.par_sort_unstable();
        let runs = crate::cell_map::runs(&binned);
        Bins { cell, binned, runs }
    }

    /// The triangles binned in the cells `r` cells (Chebyshev) from
    /// `p`'s: its own cell for `r = 0`.
    fn shell(&self, p: &Point3, r: i64) -> impl Iterator<Item = usize> + '_ {
        let k = key(&p.coords, self.cell);
        let side = -r..=r;
        side.clone()
            .flat_map(move |z| side.clone().map(move |y| (y, z)))
            .flat_map(move |(y, z)| (-r..=r).map(move |x| [x, y, z]))
            .filter(move |d| d.iter().any(|c| c.abs() == r))
            .flat_map(move |d| {
                let at = [0, 1, 2].map(|j| k[j].saturating_add(d[j]));
                self.runs
                    .get(&at)
                    .map_or(&[][..], |&(a, b)| &self.binned[a..b])
            })
            .map(|&(_, t)| t as usize)
    }

    /// A lower bound on the distance from a point to any triangle binned
    /// outside the shells `0..=r` about its cell: their centroids lie at
    /// least `r` cells away, their points within two thirds of a cell of
    /// the centroid.
    fn bound(&self, r: i64) -> Real {
        (r as Real - 2.0 / 3.0) * self.cell
    }
}

/// The cell of `p` in a grid of cell `cell`.
fn key(p: &Vec3, cell: Real) -> [i64; 3] {
    [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64)
}

/// Distance from `p` to the triangle `abc` (closest point by region,
/// Ericson, Real-Time Collision Detection §5.1.5).
pub fn point_triangle_distance(p: &Point3, a: &Point3, b: &Point3, c: &Point3) -> Real {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm();
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).norm();
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).norm();
    }
    let denom = va + vb + vc;
    if denom == 0.0 || denom.is_nan() {
        // Degenerate triangle: the nearest of its edges' end points.
        return ap.norm().min(bp.norm()).min(cp.norm());
    }
    let v = vb / denom;
    let w = vc / denom;
    (p - (a + ab * v + ac * w)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertices no face uses are dropped and the faces renumbered: the
    /// same triangles, in the same order, on the same points.
    #[test]
    fn unused_vertices_are_dropped() {
        let p = |x: Real| Point3::new(x, x * x, 0.0);
        let mut mesh = SurfaceMesh {
            vertices: (0..6).map(|k| p(k as Real)).collect(),
            normals: vec![Vec3::z(); 6],
            faces: vec![[1, 3, 4], [3, 5, 4]],
            euler_characteristic: 1,
            boundary_loops: 1,
            rms_distance: 0.0,
            max_distance: 0.0,
        };
        let before: Vec<[Point3; 3]> = mesh
            .faces
            .iter()
            .map(|f| f.map(|v| mesh.vertices[v as usize]))
            .collect();
        assert_eq!(mesh.drop_unused_vertices(), 2);
        assert_eq!(mesh.vertices.len(), 4);
        assert_eq!(mesh.normals.len(), 4);
        assert_eq!(mesh.faces, vec![[0, 1, 2], [1, 3, 2]]);
        let after: Vec<[Point3; 3]> = mesh
            .faces
            .iter()
            .map(|f| f.map(|v| mesh.vertices[v as usize]))
            .collect();
        assert_eq!(before, after);
        assert_eq!(mesh.drop_unused_vertices(), 0);
    }

    /// A wobbly strip of 798 triangles with three long tilted fans across
    /// it, and 3009 samples near and far (some far off the strip, the
    /// fans' corners on them: at distance zero).
    fn strip_with_fans() -> (Vec<Point3>, Vec<[u32; 3]>, Vec<Point3>) {
        let mut vertices = Vec::new();
        let mut faces = Vec::new();
        for i in 0..400u32 {
            let x = i as Real * 0.1;
            let wobble = 0.02 * (x * 3.0).sin();
            vertices.push(Point3::new(x, 0.0, wobble));
            vertices.push(Point3::new(x, 0.1, -wobble));
            if i > 0 {
                let (a, b, c, d) = (2 * i - 2, 2 * i - 1, 2 * i, 2 * i + 1);
                faces.push([a, c, b]);
                faces.push([b, c, d]);
            }
        }
        // Three long fans, tilted, across the strip.
        for (k, x) in [5.0, 17.3, 30.1].into_iter().enumerate() {
            let n = vertices.len() as u32;
            vertices.push(Point3::new(x, -2.0, 0.3 * k as Real));
            vertices.push(Point3::new(x + 4.0, 1.0, 0.5));
            vertices.push(Point3::new(x + 1.0, 3.0, -0.4));
            faces.push([n, n + 1, n + 2]);
        }
        let mut samples: Vec<Point3> = (0..3000)
            .map(|k| {
                let t = k as Real;
                Point3::new(
                    (t * 0.0137) % 41.0 - 0.5,
                    (t * 0.731).sin() * 2.5,
                    (t * 0.377).cos() * [0.001, 0.05, 1.0, 7.0][k % 4],
                )
            })
            .collect();
        samples.extend_from_slice(&vertices[vertices.len() - 9..]);
        (vertices, faces, samples)
    }

    /// After faces went (a fan among them), came (a fan about a new
    /// vertex, a copy of a face), turned (one wound the other way) and
    /// every vertex and face was renumbered, the distances found from the
    /// change are those of a fresh search, bit for bit, where the nearest
    /// triangle went and where a new one came nearer.
    #[test]
    fn distances_after_a_change_are_a_fresh_search() {
        let (vertices, faces, samples) = strip_with_fans();
        let before_d = sample_distances(&samples, &vertices, &faces);
        let mut kept: Vec<[u32; 3]> = faces
            .iter()
            .enumerate()
            .filter(|(t, _)| t % 37 != 5 && *t != faces.len() - 2)
            .map(|(_, f)| *f)
            .collect();
        kept[10] = [kept[10][0], kept[10][2], kept[10][1]];
        kept.push(kept[200]);
        let mut new_vertices = vertices.clone();
        let centre = new_vertices.len() as u32;
        new_vertices.push(Point3::new(12.05, 0.05, 0.4));
        for k in 120..126u32 {
            kept.push([2 * k, 2 * k + 2, centre]);
        }
        // Every vertex and face renumbered.
        let n = new_vertices.len() as u32;
        new_vertices.reverse();
        let after_faces: Vec<[u32; 3]> = kept.iter().rev().map(|f| f.map(|v| n - 1 - v)).collect();
        let (gone, came) = changed_faces((&vertices, &faces), (&new_vertices, &after_faces));
        // 22 strip faces and a fan went, one turned; six came, a copy, the turned one.
        assert_eq!((gone.len(), came.len()), (22 + 1 + 1, 6 + 1 + 1));
        let fresh = sample_distances(&samples, &new_vertices, &after_faces);
        let found = sample_distances_after(
            &samples,
            &before_d,
            (&vertices, &faces),
            (&new_vertices, &after_faces),
        );
        let bits = |d: &[Real]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&found), bits(&fresh));
        let farther = before_d.iter().zip(&fresh).filter(|(b, a)| a > b).count();
        let nearer = before_d.iter().zip(&fresh).filter(|(b, a)| a < b).count();
        assert!(
            farther > 10 && nearer > 10,
            "{farther} farther, {nearer} nearer"
        );
        // Nothing changed: nothing to search.
        let same = changed_faces((&vertices, &faces), (&vertices, &faces));
        assert_eq!(same, (vec![], vec![]));
    }

    /// [`sample_distances`] is the exact nearest distance (every triangle
    /// tried) to the last bit: a strip of small triangles with a few
    /// long fans among them (in the coarse grid), samples on, near and
    /// far from them.
    #[test]
    fn sample_distances_are_the_nearest_of_all_triangles() {
        let (vertices, faces, samples) = strip_with_fans();
        let found = sample_distances(&samples, &vertices, &faces);
        for (p, d) in samples.iter().zip(&found) {
            let exact = faces
                .iter()
                .map(|f| {
                    let v = |k: usize| &vertices[f[k] as usize];
                    point_triangle_distance(p, v(0), v(1), v(2))
                })
                .fold(Real::INFINITY, Real::min);
            assert_eq!(d.to_bits(), exact.to_bits(), "at {p:?}");
        }
        assert!(sample_distances(&samples, &vertices, &[])
            .iter()
            .all(|d| d.is_infinite()));
    }

    #[test]
    fn point_triangle_distance_regions() {
        let (a, b, c) = (
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        );
        let d =
            |x: Real, y: Real, z: Real| point_triangle_distance(&Point3::new(x, y, z), &a, &b, &c);
        assert!((d(0.2, 0.2, 0.5) - 0.5).abs() < 1e-12);
        assert!((d(-1.0, -1.0, 0.0) - 2f64.sqrt()).abs() < 1e-12);
        assert!((d(0.5, -2.0, 0.0) - 2.0).abs() < 1e-12);
        assert!((d(1.0, 1.0, 0.0) - 0.5f64.sqrt()).abs() < 1e-12);
        assert!((d(3.0, 0.0, 4.0) - 20f64.sqrt()).abs() < 1e-12);
    }
}
