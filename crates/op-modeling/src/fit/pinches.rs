//! Pinched vertices: two fans of triangles meeting at one vertex (two
//! sheets, or two corners of holes, touching at a point), where the mesh
//! is no surface. They are split ([`split_pinched_vertices`]), and two
//! pieces that touch only there are joined by one triangle across the
//! wedge between their fans ([`join_at_pinches`]); the slit beyond it,
//! where their rims run side by side, is zipped with triangles
//! (zippering, Turk and Levoy 1994) while the rims stay within the
//! triangulation radius of each other.
//!
//! The join is for scans: at a crease sharper than 90° the two sheets'
//! normals are more than 90° apart, and the triangulation's side test
//! (seed 000 §5, [`crate::triangulation::TriangulationParams::separate_sides`])
//! joins no particle of one sheet to one of the other; only the sample on
//! the crease, in both sheets' triangles, holds them together. On CGAL's
//! scanned hippo (`hippo1`), the head hung on the body by such a vertex
//! and counted as a piece of its own. On two sheets meeting at 60°
//! through one crease sample (`tests/fit.rs`), the zip took the rim
//! edges along the crease from 72 to 45: it stops where an ear would
//! face away from its corners' normals.

use std::collections::{BTreeMap, HashSet};

use op_dynamics::Real;
use rayon::prelude::*;

use super::mesh::SurfaceMesh;
use crate::disjoint_sets::DisjointSets;
use crate::triangulation::vertex_components;

/// Gives each fan but the first of a pinched vertex a vertex of its own
/// (same position and normal). A vertex's fan is its triangles joined
/// through the edges at it; on a surface it is one disc (inside) or one
/// half-disc (on a boundary). Two fans meeting at one vertex (two sheets
/// or two corners of holes touching at a point) make the mesh no surface
/// there and add 1 to `V - E + F` per extra fan; apart they are the
/// surface the triangles describe. Fans are ordered by their first
/// triangle: deterministic. Returns the vertices added, each as
/// `(v, copy)`, in the order they were added.
pub(super) fn split_pinched_vertices(mesh: &mut SurfaceMesh) -> Vec<(u32, u32)> {
    // The triangles around each vertex, ascending (CSR).
    let n = mesh.vertices.len();
    let mut starts = vec![0usize; n + 1];
    for f in &mesh.faces {
        for &v in f {
            starts[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        starts[v + 1] += starts[v];
    }
    let mut around = vec![0usize; starts[n]];
    let mut next = starts.clone();
    for (t, f) in mesh.faces.iter().enumerate() {
        for &v in f {
            around[next[v as usize]] = t;
            next[v as usize] += 1;
        }
    }
    let fan_of = |v: usize| &around[starts[v]..starts[v + 1]];
    // Which vertices are pinched in the triangles as they are, in
    // parallel. Splitting a vertex renumbers corners of its triangles only,
    // so a vertex none of whose triangles was rewritten keeps this answer;
    // the others are looked at again in order below.
    let faces = &mesh.faces;
    let pinched: Vec<bool> = (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|v| {
            let fan = fan_of(v);
            fan.len() >= 2 && fans(faces, v, fan).count() > 1
        })
        .collect();
    let mut rewritten = vec![false; mesh.faces.len()];
    let mut copies = Vec::new();
    for (v, &was_pinched) in pinched.iter().enumerate() {
        let fan = fan_of(v);
        if fan.len() < 2 || !(was_pinched || fan.iter().any(|&t| rewritten[t])) {
            continue;
        }
        let mut fans = fans(&mesh.faces, v, fan);
        // Roots are the smallest member of each fan: fan order is
        // first-triangle order (`fan` is sorted).
        let mut new_index: BTreeMap<usize, u32> = BTreeMap::new();
        for (k, &t) in fan.iter().enumerate() {
            let r = fans.root(k);
            if r == 0 {
                continue;
            }
            let w = *new_index.entry(r).or_insert_with(|| {
                mesh.vertices.push(mesh.vertices[v]);
                mesh.normals.push(mesh.normals[v]);
                let w = (mesh.vertices.len() - 1) as u32;
                copies.push((v as u32, w));
                w
            });
            for c in mesh.faces[t].iter_mut() {
                if *c as usize == v {
                    *c = w;
                }
            }
            rewritten[t] = true;
        }
    }
    copies
}

/// The fans of vertex `v` (its triangles `fan`, ascending) as disjoint
/// sets over the positions in `fan`: union-find through the edges at `v`
/// the triangles share.
fn fans(faces: &[[u32; 3]], v: usize, fan: &[usize]) -> DisjointSets {
    let mut fans = DisjointSets::new(fan.len());
    let mut by_other: BTreeMap<u32, usize> = BTreeMap::new();
    for (k, &t) in fan.iter().enumerate() {
        for &u in &faces[t] {
            if u as usize == v {
                continue;
            }
            if let Some(&j) = by_other.get(&u) {
                fans.union(j, k);
            } else {
                by_other.insert(u, k);
            }
        }
    }
    fans
}

/// Joins the pieces that touch only at a split vertex: `copies` are
/// [`split_pinched_vertices`]' `(v, copy)`. Where `v`'s fan and its
/// copy's lie in different pieces (as joined so far), a boundary edge of
/// one fan ends at `a`, one of the other at `b` (each traversed so that
/// the triangle `(v, a, b)` is wound as both fans are), `|a b|` is at
/// most `radius` (the triangulation's) and the triangle faces along its
/// corners' normals, the triangle on the shortest such pair is added and
/// the copy merged back into `v`: one vertex again, with one fan. Fans of
/// one piece stay apart (a triangle between them would make a handle or
/// a pinched tube). The slit left on either side of the join, where the
/// two pieces' rims run side by side along the crease, is then zipped
/// ([`Zipper::zip`]). Returns the number of joins.
pub(super) fn join_at_pinches(
    mesh: &mut SurfaceMesh,
    copies: &[(u32, u32)],
    radius: Real,
) -> usize {
    if copies.is_empty() {
        return 0;
    }
    let piece = vertex_components(&mesh.faces);
    let mut pieces = DisjointSets::new(piece.len());
    let mut zipper = Zipper::new(mesh, radius);
    let mut joined = 0;
    for &(v, w) in copies {
        let (Some(pv), Some(pw)) = (piece[v as usize], piece[w as usize]) else {
            continue;
        };
        if pieces.root(pv as usize) == pieces.root(pw as usize) {
            continue;
        }
        let mut best: Option<(Real, u32, u32)> = None;
        for (from, to) in [(v, w), (w, v)] {
            let into = zipper.ends(mesh, to, false);
            for a in zipper.ends(mesh, from, true) {
                for &b in &into {
                    // The edges (v, a) and (b, v) at the copy merged
                    // into v (`fits` looks at v's own).
                    if [(w, a), (b, w)].iter().any(|e| zipper.directed.contains(e)) {
                        continue;
                    }
                    if let Some(d) = zipper.fits(mesh, [v, a, b], (a, b)) {
                        if best.is_none_or(|(bd, ..)| d < bd) {
                            best = Some((d, a, b));
                        }
                    }
                }
            }
        }
        let Some((_, a, b)) = best else {
            continue;
        };
        zipper.merge(mesh, w, v);
        zipper.add(mesh, [v, a, b]);
        pieces.union(pv as usize, pw as usize);
        joined += 1;
        // The slit beyond (a, b), and the one on the other side of v.
        zipper.zip(mesh, a, b);
        if let ([p], [q]) = (
            &zipper.ends(mesh, v, true)[..],
            &zipper.ends(mesh, v, false)[..],
        ) {
            let (p, q) = (*p, *q);
            if zipper.fits(mesh, [v, p, q], (p, q)).is_some() {
                zipper.add(mesh, [v, p, q]);
                zipper.zip(mesh, p, q);
            }
        }
    }
    joined
}

/// The directed sides of triangle `f`, in its winding.
fn sides(f: [u32; 3]) -> [(u32, u32); 3] {
    [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])]
}

/// The triangles of a mesh being joined and zipped: the directed edges
/// of its triangles and the triangles at each vertex.
struct Zipper {
    directed: HashSet<(u32, u32)>,
    around: Vec<Vec<usize>>,
    radius: Real,
}

impl Zipper {
    fn new(mesh: &SurfaceMesh, radius: Real) -> Self {
        let mut zipper = Zipper {
            directed: HashSet::new(),
            around: vec![Vec::new(); mesh.vertices.len()],
            radius,
        };
        for (t, f) in mesh.faces.iter().enumerate() {
            zipper.index(t, *f);
        }
        zipper
    }

    fn index(&mut self, t: usize, f: [u32; 3]) {
        self.directed.extend(sides(f));
        for c in f {
            self.around[c as usize].push(t);
        }
    }

    /// The other ends of the boundary edges at `x`: those into `x`
    /// (`y -> x` with no `x -> y`) or out of it, ascending.
    fn ends(&self, mesh: &SurfaceMesh, x: u32, into: bool) -> Vec<u32> {
        let mut out: Vec<u32> = self.around[x as usize]
            .iter()
            .flat_map(|&t| {
                let f = mesh.faces[t];
                let k = f.iter().position(|&c| c == x).unwrap_or(0);
                [f[(k + 1) % 3], f[(k + 2) % 3]]
            })
            .filter(|&y| {
                let (e, back) = if into {
                    ((y, x), (x, y))
                } else {
                    ((x, y), (y, x))
                };
                self.directed.contains(&e) && !self.directed.contains(&back)
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The length of `f`'s new edge `new` when `f` may be added: three
    /// corners, no edge of it already in a triangle in its direction,
    /// the new edge at most the radius long, and the triangle facing
    /// along the sum of its corners' normals.
    fn fits(&self, mesh: &SurfaceMesh, f: [u32; 3], new: (u32, u32)) -> Option<Real> {
        if f[0] == f[1] || f[1] == f[2] || f[2] == f[0] {
            return None;
        }
        if sides(f).iter().any(|e| self.directed.contains(e)) {
            return None;
        }
        let p = |x: u32| mesh.vertices[x as usize];
        let n = |x: u32| mesh.normals[x as usize];
        let d = (p(new.1) - p(new.0)).norm();
        let facing = (p(f[1]) - p(f[0]))
            .cross(&(p(f[2]) - p(f[0])))
            .dot(&(n(f[0]) + n(f[1]) + n(f[2])));
        (d <= self.radius && facing > 0.0).then_some(d)
    }

    fn add(&mut self, mesh: &mut SurfaceMesh, f: [u32; 3]) {
        self.index(mesh.faces.len(), f);
        mesh.faces.push(f);
    }

    /// Renames `w` to `v` in `w`'s triangles.
    fn merge(&mut self, mesh: &mut SurfaceMesh, w: u32, v: u32) {
        for t in std::mem::take(&mut self.around[w as usize]) {
            let f = mesh.faces[t];
            for e in sides(f) {
                self.directed.remove(&e);
            }
            let f = f.map(|c| if c == w { v } else { c });
            self.directed.extend(sides(f));
            mesh.faces[t] = f;
            self.around[v as usize].push(t);
        }
    }

    /// Zips the slit beyond the boundary edge `a -> b` that joins two
    /// rims (Turk and Levoy's zippering, 1994): while the rim runs
    /// `x -> a -> b -> y` with one boundary edge at each of `a` and `b`,
    /// the ear at `a` (triangle `(a, x, b)`) or at `b` (`(b, a, y)`) with
    /// the shorter new edge is added when it fits ([`Zipper::fits`]), and
    /// the zip goes on from that edge. It stops where the rims part (no
    /// ear's new edge within the radius) or meet.
    fn zip(&mut self, mesh: &mut SurfaceMesh, mut a: u32, mut b: u32) {
        for _ in 0..mesh.faces.len() {
            let boundary = self.directed.contains(&(a, b)) && !self.directed.contains(&(b, a));
            let (xs, ys) = (self.ends(mesh, a, true), self.ends(mesh, b, false));
            let (&[x], &[y], true) = (&xs[..], &ys[..], boundary) else {
                return;
            };
            let at_b = match (
                self.fits(mesh, [a, x, b], (x, b)),
                self.fits(mesh, [b, a, y], (a, y)),
            ) {
                (Some(da), Some(db)) => db < da,
                (Some(_), None) => false,
                (None, Some(_)) => true,
                (None, None) => return,
            };
            if at_b {
                self.add(mesh, [b, a, y]);
                b = y;
            } else {
                self.add(mesh, [a, x, b]);
                a = x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use op_dynamics::{Point3, Vec3};

    use super::*;

    /// A flat mesh facing +z: `xy` points in the plane z = 0.
    fn flat(xy: &[(Real, Real)], faces: Vec<[u32; 3]>) -> SurfaceMesh {
        SurfaceMesh {
            vertices: xy.iter().map(|&(x, y)| Point3::new(x, y, 0.0)).collect(),
            normals: vec![Vec3::z(); xy.len()],
            faces,
            euler_characteristic: 0,
            boundary_loops: 0,
            rms_distance: 0.0,
            max_distance: 0.0,
        }
    }

    /// Two triangles touching at one corner (a bow tie): the shared
    /// vertex is split, `V - E + F` goes from 1 to 2 (two discs), and the
    /// geometry is unchanged.
    #[test]
    fn a_pinched_vertex_is_split() {
        let square = [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (-1.0, 0.0),
            (-1.0, -1.0),
        ];
        let mut mesh = flat(&square, vec![[0, 1, 2], [0, 3, 4]]);
        assert_eq!(split_pinched_vertices(&mut mesh), vec![(0, 5)]);
        assert_eq!(mesh.faces, vec![[0, 1, 2], [5, 3, 4]]);
        assert_eq!(mesh.vertices[5], mesh.vertices[0]);
        mesh.measure(&[]);
        assert_eq!(mesh.euler_characteristic, 2);
        // A closed fan is one fan: nothing to split.
        let mut fan = flat(&square, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]]);
        assert!(split_pinched_vertices(&mut fan).is_empty());
    }

    /// Two fans of two pieces touching at one vertex, the wedge between
    /// them under the radius: split, then joined by one triangle into one
    /// piece with one boundary loop; with a radius shorter than the
    /// wedge's opening they stay apart, and so do the fans of one piece.
    #[test]
    fn pieces_touching_at_a_vertex_are_joined_across_the_wedge() {
        // Fan A: (0,0,0) with (1,0,0), (1,1,0); fan B: (0,0,0) with
        // (-0.2,1,0), (-1,1,0): the wedge (1,1)-(-0.2,1) is 1.2 wide.
        let xy = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (-0.2, 1.0), (-1.0, 1.0)];
        let mesh = flat(&xy, vec![[0, 1, 2], [0, 3, 4]]);
        let mut joined = mesh.clone();
        let copies = split_pinched_vertices(&mut joined);
        assert_eq!(copies, vec![(0, 5)]);
        assert_eq!(join_at_pinches(&mut joined, &copies, 1.5), 1);
        assert_eq!(joined.faces, vec![[0, 1, 2], [0, 3, 4], [0, 2, 3]]);
        joined.drop_unused_vertices();
        joined.measure(&[]);
        assert_eq!((joined.euler_characteristic, joined.boundary_loops), (1, 1));
        assert!(split_pinched_vertices(&mut joined).is_empty());

        let mut narrow = mesh.clone();
        let copies = split_pinched_vertices(&mut narrow);
        assert_eq!(join_at_pinches(&mut narrow, &copies, 1.1), 0);
        assert_eq!(narrow.faces, vec![[0, 1, 2], [5, 3, 4]]);

        // Two pieces touching at two vertices, 0 and 2: the first join
        // makes them one piece, and the second pinch stays split (a
        // second triangle would make a handle).
        let xy = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.2, 0.3), (-1.0, 1.0)];
        let mut twice = flat(&xy, vec![[0, 1, 2], [0, 3, 4], [4, 3, 2]]);
        let copies = split_pinched_vertices(&mut twice);
        assert_eq!(copies, vec![(0, 5), (2, 6)]);
        assert_eq!(join_at_pinches(&mut twice, &copies, 1.5), 1);
        assert_eq!(
            twice.faces,
            vec![[0, 1, 2], [0, 3, 4], [4, 3, 6], [0, 2, 3]]
        );
    }

    /// Two strips whose rims run side by side 0.6 apart (rows y = 0.3
    /// and y = -0.3, x = 1 to 3) and touch at the vertex (0, 0): the
    /// join at the vertex, then the zip along the slit, make one strip
    /// (a disc: one rim, χ 1, 6 + 6 + 1 + 4 triangles). The zip stops at
    /// the strips' ends, and with a radius under the ears' new edges
    /// (1.17) only the join is made.
    #[test]
    fn the_slit_beside_a_join_is_zipped() {
        let xy = [
            (0.0, 0.0),
            (1.0, 0.3),
            (2.0, 0.3),
            (3.0, 0.3),
            (0.0, 1.0),
            (1.0, 1.0),
            (2.0, 1.0),
            (3.0, 1.0),
            (1.0, -0.3),
            (2.0, -0.3),
            (3.0, -0.3),
            (0.0, -1.0),
            (1.0, -1.0),
            (2.0, -1.0),
            (3.0, -1.0),
        ];
        // Upper strip: rows 1-3 (y 0.3) and 4-7 (y 1); lower strip: rows
        // 8-10 (y -0.3) and 11-14 (y -1); both through vertex 0.
        let faces = vec![
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [0, 11, 12],
            [0, 12, 8],
            [8, 12, 13],
            [8, 13, 9],
            [9, 13, 14],
            [9, 14, 10],
        ];
        let mesh = flat(&xy, faces);
        let mut zipped = mesh.clone();
        let copies = split_pinched_vertices(&mut zipped);
        assert_eq!(copies.len(), 1);
        assert_eq!(join_at_pinches(&mut zipped, &copies, 1.5), 1);
        assert_eq!(zipped.faces.len(), 17);
        zipped.drop_unused_vertices();
        zipped.measure(&[]);
        assert_eq!((zipped.euler_characteristic, zipped.boundary_loops), (1, 1));
        assert!(split_pinched_vertices(&mut zipped).is_empty());

        let mut joined = mesh.clone();
        let copies = split_pinched_vertices(&mut joined);
        assert_eq!(join_at_pinches(&mut joined, &copies, 1.1), 1);
        assert_eq!(joined.faces.len(), 13);
    }
}
