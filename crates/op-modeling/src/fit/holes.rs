//! The final pass of a fit: the holes (boundary loops) left after the
//! relaxation and the triangulation (seed 000 §5) that are narrower than
//! a threshold are closed with triangles, keeping every edge in at most
//! two triangles.
//!
//! First the triangles on edges held by more than two triangles are
//! dropped (the hole they leave is filled like any other). A hole is
//! traced along the boundary edges against the faces' winding; its
//! *width* is `4 A / P` (the diameter of a disc, the side of a square:
//! `A` the norm of its vector area, `P` its perimeter). A hole narrower
//! than the threshold is closed by ears (smallest angle first, in the
//! plane normal to its vertices' mean normal) when it has at most 6
//! corners, otherwise by a fan from a new vertex at its centroid moved
//! onto the tangent plane of the nearest sample. An ear whose new edge
//! already exists is skipped (it would make an edge in three triangles).
//! Pinched vertices are split before and after (`pinches.rs`), pieces
//! touching only at one joined across its wedge first, and specks
//! dropped ([`drop_specks`]).

use std::collections::{BTreeMap, HashMap};

use op_dynamics::{Point3, Real, Vec3};

use super::mesh::SurfaceMesh;
use super::pinches::{join_at_pinches, split_pinched_vertices};
use super::spacing::Nearest;
use crate::triangulation::{vertex_components, EdgeTable};

/// Closes the holes of `mesh` narrower than `max_width` (unit spacing),
/// after joining the pieces that touch at a pinched vertex across a
/// wedge at most `join_radius` wide ([`join_at_pinches`]);
/// `samples` with unit `normals` place the centre vertices of large
/// holes. For `open` data the longest loop of each piece is its rim, not
/// a hole, and is never closed (however narrow a sheet it bounds). The triangles are first wound consistently
/// ([`super::winding::orient`]); pinched vertices are split before and
/// after, and pieces of
/// fewer than `min_vertices` vertices dropped after. Returns the number
/// of holes closed. The figures of `mesh` are
/// not updated (see [`SurfaceMesh::measure`]).
pub(super) fn fill_holes(
    mesh: &mut SurfaceMesh,
    max_width: Real,
    join_radius: Real,
    open: bool,
    samples: &[Point3],
    normals: &[Vec3],
    min_vertices: usize,
) -> usize {
    let table = drop_overfull_edges(&mut mesh.faces);
    let (_, table) = super::winding::cut_crosscaps(mesh, table);
    // Splitting renumbers corners: the table holds while nothing split.
    let copies = split_pinched_vertices(mesh);
    let table = if copies.is_empty() {
        table
    } else {
        join_at_pinches(mesh, &copies, join_radius);
        EdgeTable::new(&mesh.faces)
    };
    let loops = boundary_loops_of(&mesh.faces, &table);
    let mut edges = EdgeCounts {
        table,
        added: HashMap::new(),
    };
    let mut closed = 0;
    // The samples' tree, built for the first fan (a scan of every sample
    // per fan made closing holes quadratic: 1,000,000 random samples of
    // the torus spent about 4 s of their holes' 14 s there).
    let tree = std::cell::OnceCell::new();
    let nearest = |c: &Point3| {
        tree.get_or_init(|| Nearest::new(samples))
            .as_ref()
            .and_then(|t| t.nearest_to(c))
            .map(|s| (samples[s], normals[s]))
    };
    let rims = if open {
        rims(&mesh.vertices, &mesh.faces, &loops)
    } else {
        vec![false; loops.len()]
    };
    for (hole, rim) in loops.into_iter().zip(rims) {
        if rim || hole.len() < 3 || width(&mesh.vertices, &hole) >= max_width {
            continue;
        }
        let before = mesh.faces.len();
        if hole.len() <= 6 {
            close_by_ears(mesh, &mut edges, hole, &nearest);
        } else {
            close_by_fan(mesh, &mut edges, &hole, &nearest);
        }
        if mesh.faces.len() > before {
            closed += 1;
        }
    }
    split_pinched_vertices(mesh);
    drop_specks(&mut mesh.faces, min_vertices);
    mesh.drop_unused_vertices();
    closed
}

/// Drops the connected pieces of the mesh with fewer than `min_vertices`
/// vertices while a larger piece remains: fewer vertices than the samples
/// a normal is estimated from are below what the data resolve (the
/// splitting of a pinched vertex can leave such a piece: two or three
/// triangles closed on themselves, measured on 20,000 random samples of
/// the saddle). Returns the number of triangles dropped.
fn drop_specks(faces: &mut Vec<[u32; 3]>, min_vertices: usize) -> usize {
    let piece = vertex_components(faces);
    let mut size: HashMap<u32, usize> = HashMap::new();
    for p in piece.iter().flatten() {
        *size.entry(*p).or_insert(0) += 1;
    }
    let largest = size.values().copied().max().unwrap_or(0);
    if largest < min_vertices {
        return 0;
    }
    let before = faces.len();
    faces.retain(|f| piece[f[0] as usize].is_some_and(|p| size[&p] >= min_vertices));
    before - faces.len()
}

/// Median of the Gamma(6, 1) distribution: for samples spread uniformly at
/// random (a Poisson process of `ρ` per area), `π ρ r₆²` of the distance
/// `r₆` to the 6th nearest sample follows it.
const GAMMA6_MEDIAN: Real = 5.670_186_1;

/// The width of the widest gap that uniformly random sampling leaves by
/// chance among `samples` samples whose distance to their 6th nearest
/// sample has the median `r6`, exceeded with probability at most 1%.
///
/// The density is `ρ = 5.67 / (π r6²)` (the median of Gamma(6, 1), see
/// [`GAMMA6_MEDIAN`]). The empty circles of a planar Poisson process are
/// the circumcircles of its Delaunay triangles, about `2 n` of them, and
/// `x = π ρ R²` of their radius `R` is Gamma(3, 1) distributed (Miles
/// 1970, "On the homogeneous planar Poisson point process", Math. Biosci.
/// 6, §8): `P(x > t) = e^{-t} (1 + t + t²/2)`. The returned width is the
/// diameter `2 R` at which `2 n P(x > t)` is 0.01. A hole in the data no
/// wider than that cannot be told from a sampling gap: about 4.7 spacings
/// on 5,000 samples at the default spacing, 5.1 on 50,000.
pub(super) fn sampling_gap_width(samples: usize, r6: Real) -> Real {
    let expected = |t: Real| 2.0 * samples as Real * (-t).exp() * (1.0 + t + 0.5 * t * t);
    // Decreasing in t >= 0: bisection between 0 and a t where it is tiny.
    let (mut lo, mut hi) = (0.0, 1.0);
    while expected(hi) > 0.01 && hi < 1e3 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if expected(mid) > 0.01 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let density = GAMMA6_MEDIAN / (std::f64::consts::PI * r6 * r6);
    2.0 * (hi / (std::f64::consts::PI * density)).sqrt()
}

/// Undirected edge key.
fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Number of triangles on each edge while holes are closed: the counts of
/// the mesh's [`EdgeTable`] plus those of the triangles added since.
struct EdgeCounts {
    table: EdgeTable,
    added: HashMap<(u32, u32), usize>,
}

impl EdgeCounts {
    /// Number of triangles on the edge `{a, b}`.
    fn count(&self, a: u32, b: u32) -> usize {
        self.table.count_of(a, b) + self.added.get(&key(a, b)).copied().unwrap_or(0)
    }
}

/// Drops the triangles on edges held by more than two. Returns the
/// [`EdgeTable`] of `faces` when none was dropped (it still holds).
fn drop_overfull_edges(faces: &mut Vec<[u32; 3]>) -> Option<EdgeTable> {
    let e = EdgeTable::new(faces);
    if (0..e.len()).all(|k| e.count(k) <= 2) {
        return Some(e);
    }
    let mut t = 0;
    faces.retain(|_| {
        t += 1;
        e.sides(t - 1).iter().all(|&k| e.count(k) <= 2)
    });
    None
}

/// The holes: loops of boundary half-edges, each reversed from its face's
/// winding (so a triangle `[prev, cur, next]` on a hole is wound like the
/// mesh). Deterministic (started from the smallest unused half-edge).
#[cfg(test)]
fn boundary_loops(faces: &[[u32; 3]]) -> Vec<Vec<u32>> {
    boundary_loops_of(faces, &EdgeTable::new(faces))
}

/// [`boundary_loops`] of `faces`, whose [`EdgeTable`] is `table` (built
/// from them, or before some were only turned).
fn boundary_loops_of(faces: &[[u32; 3]], table: &EdgeTable) -> Vec<Vec<u32>> {
    let mut next: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for e in (0..table.len()).filter(|&e| table.count(e) == 1) {
        let f = faces[table.slots(e)[0] as usize / 3];
        let (a, b) = table.vertices(e);
        // The direction the triangle traverses its boundary edge now.
        let (a, b) = if super::winding::forward(&f, a, b) {
            (a, b)
        } else {
            (b, a)
        };
        next.entry(b).or_default().push(a);
    }
    next.values_mut().for_each(|v| v.sort_unstable());
    // Lists only shrink: the first one left with a half-edge is never
    // before the last one found.
    let starts: Vec<u32> = next.keys().copied().collect();
    let mut first = 0;
    let mut loops = Vec::new();
    loop {
        while first < starts.len() && next[&starts[first]].is_empty() {
            first += 1;
        }
        let Some(&start) = starts.get(first) else {
            break;
        };
        let mut hole = vec![start];
        let mut at = start;
        while let Some(to) = next.get_mut(&at).and_then(Vec::pop) {
            if to == start {
                break;
            }
            hole.push(to);
            at = to;
            if hole.len() > faces.len() * 3 {
                break;
            }
        }
        loops.extend(split_at_pinches(hole));
    }
    loops
}

/// Which of `loops` is the rim of its piece of `faces`: the longest of
/// the piece's loops (the first of equal ones).
fn rims(vertices: &[Point3], faces: &[[u32; 3]], loops: &[Vec<u32>]) -> Vec<bool> {
    let piece = vertex_components(faces);
    let mut longest: HashMap<u32, (Real, usize)> = HashMap::new();
    for (k, hole) in loops.iter().enumerate() {
        let Some(p) = hole.first().and_then(|&v| piece[v as usize]) else {
            continue;
        };
        let length: Real = (0..hole.len())
            .map(|i| {
                let (a, b) = (hole[i], hole[(i + 1) % hole.len()]);
                (vertices[b as usize] - vertices[a as usize]).norm()
            })
            .sum();
        let best = longest.entry(p).or_insert((length, k));
        if length > best.0 {
            *best = (length, k);
        }
    }
    let mut rim = vec![false; loops.len()];
    for (_, k) in longest.values() {
        rim[*k] = true;
    }
    rim
}

/// A traced loop split into simple loops where it visits a vertex twice
/// (two holes touching at a vertex).
fn split_at_pinches(hole: Vec<u32>) -> Vec<Vec<u32>> {
    let mut out = Vec::new();
    let mut path: Vec<u32> = Vec::new();
    for v in hole {
        if let Some(k) = path.iter().position(|&u| u == v) {
            out.push(path.split_off(k));
        }
        path.push(v);
    }
    out.push(path);
    out
}

/// `4 A / P` of the polygon `hole`.
fn width(vertices: &[Point3], hole: &[u32]) -> Real {
    let p = |k: usize| vertices[hole[k % hole.len()] as usize];
    let c = centroid(vertices, hole);
    let mut area = Vec3::zeros();
    let mut perimeter = 0.0;
    for k in 0..hole.len() {
        area += (p(k) - c).cross(&(p(k + 1) - c)) * 0.5;
        perimeter += (p(k + 1) - p(k)).norm();
    }
    4.0 * area.norm() / perimeter.max(1e-300)
}

fn centroid(vertices: &[Point3], hole: &[u32]) -> Point3 {
    Point3::from(
        hole.iter()
            .fold(Vec3::zeros(), |s, &v| s + vertices[v as usize].coords)
            / hole.len() as Real,
    )
}

/// The sample nearest to a point (the first by index among equally near)
/// and its unit normal; `None` when there is none.
type NearestSample<'a> = dyn Fn(&Point3) -> Option<(Point3, Vec3)> + 'a;

/// Closes `hole` by clipping its sharpest ear first.
fn close_by_ears(
    mesh: &mut SurfaceMesh,
    edges: &mut EdgeCounts,
    hole: Vec<u32>,
    nearest: &NearestSample,
) {
    let n = hole
        .iter()
        .fold(Vec3::zeros(), |s, &v| s + mesh.normals[v as usize]);
    let mut hole = hole;
    while hole.len() >= 3 {
        let m = hole.len();
        let angle = |k: usize| {
            let (a, b, c) = (
                mesh.vertices[hole[(k + m - 1) % m] as usize],
                mesh.vertices[hole[k] as usize],
                mesh.vertices[hole[(k + 1) % m] as usize],
            );
            let (e1, e2) = (c - b, a - b);
            let s = n.dot(&e1.cross(&e2));
            let a = s.atan2(e1.dot(&e2));
            if a < 0.0 {
                a + std::f64::consts::TAU
            } else {
                a
            }
        };
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)).then(a.cmp(&b)));
        let ear = order.into_iter().find(|&k| {
            let (a, b, c) = (hole[(k + m - 1) % m], hole[k], hole[(k + 1) % m]);
            let diagonal = edges.count(a, c);
            a != b
                && b != c
                && a != c
                && edges.count(a, b) <= 1
                && edges.count(b, c) <= 1
                && (diagonal == 0 || (m == 3 && diagonal <= 1))
        });
        let Some(k) = ear else {
            // No ear can be clipped without an edge in three triangles:
            // a fan from a new centre vertex (its edges are new).
            close_by_fan(mesh, edges, &hole, nearest);
            return;
        };
        let f = [hole[(k + m - 1) % m], hole[k], hole[(k + 1) % m]];
        add_face(mesh, edges, f);
        hole.remove(k);
        if m == 3 {
            return;
        }
    }
}

/// Closes `hole` by a fan from a new vertex at its centroid, moved onto
/// the tangent plane of the nearest sample.
fn close_by_fan(
    mesh: &mut SurfaceMesh,
    edges: &mut EdgeCounts,
    hole: &[u32],
    nearest: &NearestSample,
) {
    let mut sorted = hole.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() < hole.len()
        || (0..hole.len()).any(|k| edges.count(hole[k], hole[(k + 1) % hole.len()]) > 1)
    {
        // A pinched loop (a vertex twice): left open.
        return;
    }
    let mut c = centroid(&mesh.vertices, hole);
    if let Some((sample, normal)) = nearest(&c) {
        c -= normal * normal.dot(&(c - sample));
    }
    let n = hole
        .iter()
        .fold(Vec3::zeros(), |s, &v| s + mesh.normals[v as usize]);
    let v = mesh.vertices.len() as u32;
    mesh.vertices.push(c);
    mesh.normals
        .push(n.try_normalize(1e-12).unwrap_or(Vec3::z()));
    for k in 0..hole.len() {
        add_face(mesh, edges, [hole[k], hole[(k + 1) % hole.len()], v]);
    }
}

fn add_face(mesh: &mut SurfaceMesh, edges: &mut EdgeCounts, f: [u32; 3]) {
    for k in 0..3 {
        *edges.added.entry(key(f[k], f[(k + 1) % 3])).or_insert(0) += 1;
    }
    mesh.faces.push(f);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of 4 triangles around a centre with one removed: the
    /// hole is found and closed.
    #[test]
    fn a_missing_triangle_is_filled() {
        let vertices = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.5, 0.5, 0.0),
        ];
        // Closed octahedron-like fan: a pyramid, both sides.
        let mut faces = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        faces.extend([[0, 2, 1], [0, 3, 2]]);
        faces.remove(1);
        let mut mesh = SurfaceMesh {
            normals: vec![Vec3::z(); 5],
            vertices,
            faces,
            euler_characteristic: 0,
            boundary_loops: 0,
            rms_distance: 0.0,
            max_distance: 0.0,
        };
        assert_eq!(boundary_loops(&mesh.faces).len(), 1);
        // Open data: the only loop is the piece's rim, kept.
        let mut open = mesh.clone();
        assert_eq!(fill_holes(&mut open, 10.0, 2.0, true, &[], &[], 3), 0);
        assert_eq!(boundary_loops(&open.faces).len(), 1);
        assert_eq!(fill_holes(&mut mesh, 10.0, 2.0, false, &[], &[], 3), 1);
        assert!(boundary_loops(&mesh.faces).is_empty());
        let table = EdgeTable::new(&mesh.faces);
        assert!((0..table.len()).all(|e| table.count(e) == 2));
    }

    /// The chance gap width grows with the number of samples and scales
    /// with their spacing: 4.6-4.7 spacings on 5,000 samples at the
    /// default spacing (`r6 = 1.25 h`).
    #[test]
    fn sampling_gap_width_follows_the_poisson_delaunay_law() {
        let w = sampling_gap_width(5000, 1.25);
        assert!((4.5..4.8).contains(&w), "{w}");
        assert!(sampling_gap_width(50_000, 1.25) > w);
        assert!(sampling_gap_width(500, 1.25) < w);
        assert!((sampling_gap_width(5000, 2.5) - 2.0 * w).abs() < 1e-9 * w);
    }
}
