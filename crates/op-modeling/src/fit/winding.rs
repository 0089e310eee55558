//! Consistent winding of a fit's triangles.
//!
//! The triangulation winds each triangle along the sum of its three
//! particle normals (seed 000 §5). Where the normals of a region point the
//! wrong way (the orientation propagated across a thin feature, Hoppe et
//! al. 1992 §3.3, where the nearest samples of one side include the other
//! side's), its triangles are wound against their neighbours': an edge
//! traversed the same way by both its triangles. The boundary of a hole
//! there cannot be traced, and the hole pass leaves it open (13 such edges
//! and 7 open holes on the 26,002 vertices of a scanned armadillo).
//!
//! [`orient`] walks each connected piece across its edges held by two
//! triangles, breadth first from its first triangle, and turns every
//! triangle to agree with the one it was reached from; a piece whose
//! triangles then mostly face against their corner normals is turned
//! whole. The vertex normals are then turned to agree with their
//! triangles.
//!
//! Where no winding agrees everywhere (a band whose normals turn by 180°
//! on the way round: a Möbius band across the rim of a feature thinner
//! than the spacing), [`cut_crosscaps`] drops the triangles of the edges
//! where the walk meets itself wound against, and the hole pass fills the
//! cut.

use std::collections::VecDeque;

use op_dynamics::{Point3, Vec3};
use rayon::prelude::*;

use super::mesh::SurfaceMesh;
use crate::triangulation::EdgeTable;

/// Whether triangle `f` traverses `a -> b`.
pub(super) fn forward(f: &[u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|k| f[k] == a && f[(k + 1) % 3] == b)
}

/// Winds the triangles of `mesh` consistently (see the module
/// documentation) and turns each vertex normal that points against the
/// (area-weighted) sum of its triangles' normals. `edges` is the
/// [`EdgeTable`] of the mesh's triangles (built from them as they are, or
/// before some were only turned: a turned triangle holds the same edges).
/// Returns the number of triangles turned.
pub(super) fn orient(mesh: &mut SurfaceMesh, edges: &EdgeTable) -> usize {
    let faces = &mut mesh.faces;
    let mut seen = vec![false; faces.len()];
    let mut flipped = vec![false; faces.len()];
    for start in 0..faces.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut piece = vec![start];
        let mut queue = VecDeque::from([start]);
        while let Some(t) = queue.pop_front() {
            let f = faces[t];
            let sides = edges.sides(t);
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                // The side of `t` on {a, b}, whatever turns `t` took.
                let Some(&e) = sides
                    .iter()
                    .find(|&&e| edges.vertices(e) == (a.min(b), a.max(b)))
                else {
                    continue;
                };
                let on = edges.slots(e);
                if on.len() != 2 {
                    continue;
                }
                let (t0, t1) = (on[0] as usize / 3, on[1] as usize / 3);
                let u = if t0 == t { t1 } else { t0 };
                if seen[u] {
                    continue;
                }
                seen[u] = true;
                if forward(&faces[u], a, b) {
                    faces[u].swap(1, 2);
                    flipped[u] = true;
                }
                piece.push(u);
                queue.push_back(u);
            }
        }
        let against = piece
            .iter()
            .filter(|&&t| {
                let f = faces[t];
                let n = f
                    .iter()
                    .fold(Vec3::zeros(), |s, &v| s + mesh.normals[v as usize]);
                face_normal(&mesh.vertices, &f).dot(&n) < 0.0
            })
            .count();
        if 2 * against > piece.len() {
            for &t in &piece {
                faces[t].swap(1, 2);
                flipped[t] = !flipped[t];
            }
        }
    }
    let mut sums = vec![Vec3::zeros(); mesh.vertices.len()];
    for f in faces.iter() {
        let n = face_normal(&mesh.vertices, f);
        for &v in f {
            sums[v as usize] += n;
        }
    }
    mesh.normals
        .par_iter_mut()
        .zip(&sums)
        .with_min_len(4096)
        .for_each(|(n, s)| {
            if n.dot(s) < 0.0 {
                *n = -*n;
            }
        });
    flipped.iter().filter(|&&f| f).count()
}

/// Makes the mesh orientable: while [`orient`] leaves edges whose two
/// triangles traverse them the same way, drops those triangles and winds
/// again. Such an edge closes a band whose normals turned by 180° on the
/// way round (a Möbius band: across the rim of a feature thinner than the
/// spacing, where the normals turn within one triangle); dropping its
/// triangles cuts the band across, and the hole pass fills the cut as
/// a hole of an orientable surface. `edges` is the table of the mesh's
/// triangles when the caller has it. Returns the number of triangles
/// dropped and the table of the triangles left (valid for them: a wound
/// triangle holds the same edges). On the 26,002 vertices of a scanned
/// armadillo: two such bands at the ears (4 triangles), which had left
/// two holes that could not be traced and χ -2.
pub(super) fn cut_crosscaps(
    mesh: &mut SurfaceMesh,
    edges: Option<EdgeTable>,
) -> (usize, EdgeTable) {
    let mut dropped = 0;
    let mut edges = edges.unwrap_or_else(|| EdgeTable::new(&mesh.faces));
    loop {
        orient(mesh, &edges);
        let faces = &mesh.faces;
        let mut bad = vec![false; faces.len()];
        let crossed: Vec<[usize; 2]> = (0..edges.len())
            .into_par_iter()
            .with_min_len(4096)
            .filter_map(|e| {
                let &[s0, s1] = edges.slots(e) else {
                    return None;
                };
                let (a, b) = edges.vertices(e);
                let (t0, t1) = (s0 as usize / 3, s1 as usize / 3);
                (forward(&faces[t0], a, b) == forward(&faces[t1], a, b)).then_some([t0, t1])
            })
            .collect();
        for t in crossed.into_iter().flatten() {
            bad[t] = true;
        }
        let n = bad.iter().filter(|&&b| b).count();
        if n == 0 {
            return (dropped, edges);
        }
        dropped += n;
        let mut k = 0;
        mesh.faces.retain(|_| {
            k += 1;
            !bad[k - 1]
        });
        edges = EdgeTable::new(&mesh.faces);
    }
}

/// `(b - a) × (c - a)` of the triangle `f` (twice its vector area).
fn face_normal(vertices: &[Point3], f: &[u32; 3]) -> Vec3 {
    let p = f.map(|v| vertices[v as usize]);
    (p[1] - p[0]).cross(&(p[2] - p[0]))
}

/// Whether every edge held by two triangles is traversed once each way.
#[cfg(test)]
fn consistent(faces: &[[u32; 3]]) -> bool {
    use std::collections::HashMap;
    let mut half: HashMap<(u32, u32), usize> = HashMap::new();
    for f in faces {
        for k in 0..3 {
            *half.entry((f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    half.values().all(|&c| c == 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron with two triangles wound the wrong way and one
    /// vertex normal flipped: all wound outward afterwards, the normal
    /// turned back.
    #[test]
    fn flipped_triangles_and_normals_are_turned() {
        let vertices = vec![
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(-1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, -1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(0.0, 0.0, -1.0),
        ];
        let outward = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        let mut faces = outward.to_vec();
        faces[1].swap(1, 2);
        faces[6].swap(1, 2);
        let mut normals: Vec<Vec3> = vertices.iter().map(|p| p.coords).collect();
        normals[4] = -normals[4];
        let mut mesh = SurfaceMesh {
            vertices,
            normals,
            faces,
            euler_characteristic: 0,
            boundary_loops: 0,
            rms_distance: 0.0,
            max_distance: 0.0,
        };
        assert!(!consistent(&mesh.faces));
        let edges = EdgeTable::new(&mesh.faces);
        orient(&mut mesh, &edges);
        assert!(consistent(&mesh.faces));
        for f in &mesh.faces {
            let c = f
                .iter()
                .fold(Vec3::zeros(), |s, &v| s + mesh.vertices[v as usize].coords);
            assert!(face_normal(&mesh.vertices, f).dot(&c) > 0.0, "{f:?}");
        }
        assert_eq!(mesh.normals[4], Vec3::z());
    }
}
