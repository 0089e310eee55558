//! Pinched vertices: two fans of triangles meeting at one vertex (two
//! sheets, or two corners of holes, touching at a point), where the mesh
//! is no surface. They are split ([`split_pinched_vertices`]), and two
//! pieces that touch only there are joined by one triangle across the
//! wedge between their fans ([`join_at_pinches`]).
//!
//! The join is for scans: at a crease sharper than 90° the two sheets'
//! normals are more than 90° apart, and the triangulation's side test
//! (seed 000 §5, [`crate::triangulation::TriangulationParams::separate_sides`])
//! joins no particle of one sheet to one of the other; only the sample on
//! the crease, in both sheets' triangles, holds them together. On CGAL's
//! scanned hippo (`hippo1`), the head hung on the body by such a vertex
//! and counted as a piece of its own.

use std::collections::{BTreeMap, HashMap, HashSet};

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
/// the copy merged back into `v`: one vertex again, with one fan, and the
/// wedge's first triangle. Fans of one piece stay apart (a triangle
/// between them would make a handle or a pinched tube). Returns the
/// number of joins.
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
    // Directed edges of the triangles, and the triangles at each vertex
    // of a pinch (the only ones rewritten).
    let mut directed: HashSet<(u32, u32)> = HashSet::new();
    let mut at: HashMap<u32, Vec<usize>> = copies
        .iter()
        .flat_map(|&(v, w)| [(v, Vec::new()), (w, Vec::new())])
        .collect();
    for (t, f) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            directed.insert((f[k], f[(k + 1) % 3]));
            if let Some(list) = at.get_mut(&f[k]) {
                list.push(t);
            }
        }
    }
    let mut joined = 0;
    for &(v, w) in copies {
        let (Some(pv), Some(pw)) = (piece[v as usize], piece[w as usize]) else {
            continue;
        };
        if pieces.root(pv as usize) == pieces.root(pw as usize) {
            continue;
        }
        // Boundary edges at x: `into` (y -> x, no x -> y), `out_of`.
        let ends = |x: u32, into: bool| -> Vec<u32> {
            let mut out: Vec<u32> = at[&x]
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
                    directed.contains(&e) && !directed.contains(&back)
                })
                .collect();
            out.sort_unstable();
            out.dedup();
            out
        };
        let p = |x: u32| mesh.vertices[x as usize];
        let n = |x: u32| mesh.normals[x as usize];
        let mut best: Option<(Real, u32, u32)> = None;
        for (from, to) in [(v, w), (w, v)] {
            for a in ends(from, true) {
                for b in ends(to, false) {
                    // Each edge of (v, a, b) once in its direction, at
                    // v and at the copy merged into it.
                    let taken = [(a, b), (v, a), (w, a), (b, v), (b, w)];
                    if a == b || taken.iter().any(|e| directed.contains(e)) {
                        continue;
                    }
                    let d = (p(b) - p(a)).norm();
                    let facing = (p(a) - p(v))
                        .cross(&(p(b) - p(v)))
                        .dot(&(n(v) + n(a) + n(b)));
                    if d <= radius && facing > 0.0 && best.is_none_or(|(bd, ..)| d < bd) {
                        best = Some((d, a, b));
                    }
                }
            }
        }
        let Some((_, a, b)) = best else {
            continue;
        };
        for &t in &at[&w] {
            let f = mesh.faces[t];
            for k in 0..3 {
                directed.remove(&(f[k], f[(k + 1) % 3]));
            }
            let f = f.map(|c| if c == w { v } else { c });
            for k in 0..3 {
                directed.insert((f[k], f[(k + 1) % 3]));
            }
            mesh.faces[t] = f;
        }
        let moved = at.remove(&w).unwrap_or_default();
        let list = at.entry(v).or_default();
        list.extend(moved);
        list.push(mesh.faces.len());
        let f = [v, a, b];
        for k in 0..3 {
            directed.insert((f[k], f[(k + 1) % 3]));
        }
        mesh.faces.push(f);
        pieces.union(pv as usize, pw as usize);
        joined += 1;
    }
    joined
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
}
