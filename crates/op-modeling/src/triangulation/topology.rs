//! Topology of a triangulation (seed 000 §5): the pieces of a set of
//! triangles ([`vertex_components`]) and the queries on a
//! [`Triangulation`] its module docs list as helpers: its vertices and
//! edges, Euler characteristic, boundary loops, manifoldness and
//! consistent orientation.

use std::collections::BTreeMap;

use rayon::prelude::*;

use super::{EdgeTable, Triangulation};
use crate::disjoint_sets::DisjointSets;

/// The pieces of a set of triangles (vertex indices): for each vertex
/// index up to the largest used, the smallest vertex of its piece, `None`
/// for an index no triangle uses. Triangles sharing a vertex are one piece
/// (union-find with path halving).
pub fn vertex_components(triangles: &[[u32; 3]]) -> Vec<Option<u32>> {
    let n = triangles
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let mut pieces = DisjointSets::new(n);
    let mut used = vec![false; n];
    for t in triangles {
        used[t[0] as usize] = true;
        for k in 1..3 {
            used[t[k] as usize] = true;
            pieces.union(t[0] as usize, t[k] as usize);
        }
    }
    (0..n)
        .map(|i| used[i].then(|| pieces.root(i) as u32))
        .collect()
}

impl Triangulation {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True when there is no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The distinct vertices (particle ids) used by the triangles, ascending.
    pub fn vertices(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.triangles.iter().flatten().copied().collect();
        v.par_sort_unstable();
        v.dedup();
        v
    }

    /// Each undirected edge `(a, b)`, `a < b`, with the number of triangles
    /// holding it.
    pub fn edges(&self) -> BTreeMap<(u32, u32), usize> {
        let mut e = BTreeMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *e.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        e
    }

    /// Euler characteristic `V - E + F` of the triangles (V counts the
    /// vertices used by some triangle): 2 for a sphere, 0 for a torus, 1
    /// for a disc.
    pub fn euler_characteristic(&self) -> i64 {
        self.euler_characteristic_with(&EdgeTable::new(&self.triangles))
    }

    /// [`Self::euler_characteristic`] with the triangles' [`EdgeTable`].
    pub fn euler_characteristic_with(&self, edges: &EdgeTable) -> i64 {
        self.vertices().len() as i64 - edges.len() as i64 + self.triangles.len() as i64
    }

    /// Number of boundary loops: connected components of the edges held by
    /// exactly one triangle (0 for a closed surface, 1 for a disc).
    pub fn boundary_loops(&self) -> usize {
        Self::boundary_loops_of(&EdgeTable::new(&self.triangles))
    }

    /// [`Self::boundary_loops`] of the triangles whose [`EdgeTable`] is
    /// `edges`.
    pub fn boundary_loops_of(edges: &EdgeTable) -> usize {
        let boundary: Vec<(u32, u32)> = (0..edges.len())
            .filter(|&e| edges.count(e) == 1)
            .map(|e| edges.vertices(e))
            .collect();
        let mut verts: Vec<u32> = boundary.iter().flat_map(|&(a, b)| [a, b]).collect();
        verts.sort_unstable();
        verts.dedup();
        let at = |v: u32| verts.binary_search(&v).unwrap_or(0);
        let mut loops = DisjointSets::new(verts.len());
        let mut components = verts.len();
        for &(a, b) in &boundary {
            if loops.union(at(a), at(b)) {
                components -= 1;
            }
        }
        components
    }

    /// True when the triangles form a 2-manifold (with boundary): every
    /// edge in one or two triangles, and around every vertex the triangles
    /// form a single fan (the link of the vertex is one path or one cycle).
    pub fn is_manifold(&self) -> bool {
        if self.edges().values().any(|&c| c > 2) {
            return false;
        }
        // Link of each vertex: the edges opposite to it.
        let mut links: BTreeMap<u32, Vec<(u32, u32)>> = BTreeMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                links
                    .entry(t[k])
                    .or_default()
                    .push((t[(k + 1) % 3], t[(k + 2) % 3]));
            }
        }
        links.values().all(|link| is_single_fan(link))
    }

    /// True when every edge held by two triangles is traversed in opposite
    /// directions by them (a consistent orientation).
    pub fn is_consistently_oriented(&self) -> bool {
        let mut directed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        directed.values().all(|&c| c == 1)
    }
}

/// True when the link edges form one connected path or cycle.
fn is_single_fan(link: &[(u32, u32)]) -> bool {
    let mut degree: BTreeMap<u32, usize> = BTreeMap::new();
    for &(a, b) in link {
        *degree.entry(a).or_insert(0) += 1;
        *degree.entry(b).or_insert(0) += 1;
    }
    if degree.values().any(|&d| d > 2) {
        return false;
    }
    // Connected: walk from the first vertex over the link edges.
    let mut seen = vec![link[0].0];
    let mut frontier = vec![link[0].0];
    while let Some(v) = frontier.pop() {
        for &(a, b) in link {
            for (x, y) in [(a, b), (b, a)] {
                if x == v && !seen.contains(&y) {
                    seen.push(y);
                    frontier.push(y);
                }
            }
        }
    }
    seen.len() == degree.len()
}
