//! Held cells of a triangulation (see "Held cells" in the module docs of
//! [`crate::triangulation`]): holes of three or four edges whose sides all
//! hold together are closed.

use std::collections::BTreeMap;

use op_dynamics::math::Point3;
use rayon::prelude::*;

use super::{canonical, Linked};

/// Closes the holes of three or four edges whose sides are all linked
/// (see "Held cells" in the module docs): the missing triangle, or two
/// triangles on the cell's shorter diagonal, wound against the triangles
/// that hold the sides. A loop that is the rim of a lone triangle, or
/// whose diagonals are already edges (a patch of two triangles), is not a
/// hole and stays open.
pub(super) fn close_held_cells(
    tris: &mut Vec<[u32; 3]>,
    positions: &[Point3],
    linked: &Linked<'_>,
) {
    // Every directed edge `a -> b` of the kept triangles as `a << 32 | b`,
    // ascending (a parallel sort: the same at any thread count).
    let key = |a: u32, b: u32| (u64::from(a) << 32) | u64::from(b);
    let mut directed: Vec<u64> = tris
        .par_iter()
        .flat_map_iter(|&t| (0..3).map(move |k| key(t[k], t[(k + 1) % 3])))
        .collect();
    directed.par_sort_unstable();
    let runs = |a: u32, b: u32| directed.binary_search(&key(a, b)).is_ok();
    let has = |a: u32, b: u32| runs(a, b) || runs(b, a);
    // Boundary edges, as the direction their one triangle runs them: run
    // once, never run back; ascending.
    let boundary: Vec<(u32, u32)> = (0..directed.len())
        .into_par_iter()
        .with_min_len(4096)
        .filter(|&i| {
            let d = directed[i];
            let (a, b) = ((d >> 32) as u32, d as u32);
            (i == 0 || directed[i - 1] != d) && directed.get(i + 1) != Some(&d) && !runs(b, a)
        })
        .map(|i| ((directed[i] >> 32) as u32, directed[i] as u32))
        .collect();
    let mut next: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for &(a, b) in &boundary {
        next.entry(a).or_default().push(b);
    }
    let mut added = Vec::new();
    for &(a, b) in &boundary {
        // Follow the loop a -> b -> c -> d -> a when every vertex on it
        // leaves by one boundary edge; start at its smallest vertex only.
        let step = |v: u32| match next.get(&v).map(Vec::as_slice) {
            Some([w]) => Some(*w),
            _ => None,
        };
        let (Some(c), true) = (step(b), step(a) == Some(b)) else {
            continue;
        };
        if step(c) == Some(a) {
            // A missing triangle: three held sides, no triangle on them.
            let held = linked(a.min(b), a.max(b))
                && linked(b.min(c), b.max(c))
                && linked(a.min(c), a.max(c));
            // The rim of a lone triangle runs the way that triangle does.
            let present = tris.binary_search(&canonical([a, b, c])).is_ok();
            if a < b.min(c) && held && !present {
                added.push(canonical([a, c, b]));
            }
            continue;
        }
        let Some(d) = step(c) else {
            continue;
        };
        if step(d) != Some(a) || a > b.min(c).min(d) {
            continue;
        }
        let ring = [a, b, c, d];
        let sides_hold = (0..4).all(|k| {
            let (p, q) = (ring[k], ring[(k + 1) % 4]);
            linked(p.min(q), p.max(q))
        });
        if !sides_hold || has(a, c) || has(b, d) {
            continue;
        }
        let len = |p: u32, q: u32| (positions[p as usize] - positions[q as usize]).norm();
        // The triangles run the ring backwards, against the ones around it.
        let (first, second) = if len(a, c) <= len(b, d) {
            ([a, d, c], [a, c, b])
        } else {
            ([b, a, d], [b, d, c])
        };
        added.push(canonical(first));
        added.push(canonical(second));
    }
    if !added.is_empty() {
        tris.extend(added);
        // Equal triangles are the same bits: the parallel sort gives the
        // serial one's list.
        tris.par_sort_unstable();
    }
}
