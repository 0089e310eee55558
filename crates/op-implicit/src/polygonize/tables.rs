//! Marching-cubes case tables (Lorensen & Cline 1987), generated at first
//! use rather than typed in: for each of the 256 inside/outside patterns
//! of a cell's corners, the triangles, as triples of cell edges.
//!
//! Corners are numbered by their offset bits, `c = x + 2 y + 4 z`; edge
//! `e` joins corner [`EDGES`]`[e].0` to the corner one step along axis
//! [`EDGES`]`[e].1`. On each face the crossing points are joined so that
//! the inside corners are separated (a run of consecutive inside corners
//! around the face is cut off by one segment): the choice depends only on
//! the face's four corners, so the two cells sharing a face cut it the
//! same way and the mesh is closed. Segments are directed with the inside
//! on a fixed side seen from outside the cell, so they chain into closed
//! oriented loops around the cell; each loop is triangulated as a fan.

use std::sync::OnceLock;

/// The 12 cell edges as (lower corner, axis): the four x edges, then y,
/// then z.
pub(super) const EDGES: [(u8, u8); 12] = [
    (0, 0),
    (2, 0),
    (4, 0),
    (6, 0),
    (0, 1),
    (1, 1),
    (4, 1),
    (5, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (3, 2),
];

/// Offset of corner `c` in cells along each axis.
#[inline]
pub(super) fn corner_offset(c: u8) -> [usize; 3] {
    [
        (c & 1) as usize,
        ((c >> 1) & 1) as usize,
        ((c >> 2) & 1) as usize,
    ]
}

/// Triangles (edge triples, counter-clockwise seen from outside the
/// surface) of every case, indexed by the inside-corner bit mask.
pub(super) fn cases() -> &'static [Vec<[u8; 3]>] {
    static CASES: OnceLock<Vec<Vec<[u8; 3]>>> = OnceLock::new();
    CASES.get_or_init(|| (0..256).map(|m| triangulate(m as u8)).collect())
}

/// The edge joining corners `a` and `b` (adjacent).
fn edge_between(a: u8, b: u8) -> u8 {
    let (lo, diff) = (a.min(b), a ^ b);
    let axis = diff.trailing_zeros() as u8;
    EDGES
        .iter()
        .position(|&e| e == (lo, axis))
        .expect("adjacent corners") as u8
}

/// The four corners of each face in cyclic order, counter-clockwise seen
/// from outside the cell.
fn faces() -> [[u8; 4]; 6] {
    let mut out = [[0; 4]; 6];
    for axis in 0..3u8 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in 0..2u8 {
            // (0,0) -> (1,0) -> (1,1) -> (0,1) turns about +axis (e_u x e_v = e_axis).
            let mut cyc = [(0, 0), (1, 0), (1, 1), (0, 1)]
                .map(|(cu, cv): (u8, u8)| (side << axis) | (cu << u) | (cv << v));
            if side == 0 {
                cyc.reverse();
            }
            out[(2 * axis + side) as usize] = cyc;
        }
    }
    out
}

/// The triangles of case `mask` (bit `c` set: corner `c` inside).
fn triangulate(mask: u8) -> Vec<[u8; 3]> {
    let inside = |c: u8| mask >> c & 1 == 1;
    // next[e]: the crossing point that follows edge e's along its loop.
    let mut next = [u8::MAX; 12];
    for cyc in faces() {
        for i in 0..4 {
            let prev = cyc[(i + 3) % 4];
            if !inside(cyc[i]) || inside(prev) {
                continue;
            }
            // A run of inside corners starts at i: find where it ends.
            let mut j = i;
            while inside(cyc[(j + 1) % 4]) {
                j = (j + 1) % 4;
            }
            let enter = edge_between(prev, cyc[i]);
            let leave = edge_between(cyc[j], cyc[(j + 1) % 4]);
            next[enter as usize] = leave;
        }
    }
    let mut triangles = Vec::new();
    let mut seen = [false; 12];
    for start in 0..12 {
        if next[start] == u8::MAX || seen[start] {
            continue;
        }
        let mut lp = Vec::new();
        let mut e = start;
        while !seen[e] {
            seen[e] = true;
            lp.push(e as u8);
            e = next[e] as usize;
        }
        for k in 1..lp.len() - 1 {
            triangles.push([lp[0], lp[k], lp[k + 1]]);
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_crossing_edge_is_used_and_complements_mirror() {
        let cases = cases();
        assert!(cases[0].is_empty() && cases[255].is_empty());
        for (m, case) in cases.iter().enumerate() {
            let mut used = [false; 12];
            for t in case {
                for &e in t {
                    used[e as usize] = true;
                }
            }
            for (e, &(c, axis)) in EDGES.iter().enumerate() {
                let other = c | (1 << axis);
                let crossing = (m >> c & 1) != (m >> other & 1);
                assert_eq!(used[e], crossing, "case {m} edge {e}");
            }
            // One triangle per crossing point beyond two, per loop: at most 4 loops.
            assert!(case.len() <= 12);
        }
        // Single inside corner: one triangle.
        assert_eq!(cases[1].len(), 1);
        // Half the cube inside: a quad.
        assert_eq!(cases[0b0101_0101].len(), 2);
    }
}
