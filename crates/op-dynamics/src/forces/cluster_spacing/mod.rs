//! The uniform 12-6 Lennard-Jones spacing pass on cluster pairs
//! ([`crate::neighbours::ClusterPairs`]): the kernel of mixed precision
//! ([`Precision::Mixed`]).
//!
//! A cluster of [`CLUSTER`] particles is evaluated against each cluster of
//! its (half) row as one `CLUSTER x CLUSTER` tile ([`tile`]): the partner's
//! coordinates are contiguous (structure of arrays by cluster, no gather),
//! every lane of the tile computes its pair branch-free (the cut-off,
//! coincident slots and padding masked, as in [`crate::lanes`]), the
//! forces on the cluster's own particles are summed per lane over its
//! row, and their negatives per lane into the partner's sums.
//!
//! **Determinism: fixed blocks, ordered merge** (as the row kernel,
//! [`crate::forces`]). Clusters are cut into blocks of `BLOCK` (a
//! function of the cluster count only). Each block, in parallel, visits
//! its rows and keeps the partner sums of every cluster it touches; at
//! its end it adds those of its own clusters to their particles and
//! hands the others (clusters of later blocks) to a second parallel pass,
//! where every block adds what the earlier blocks aimed at it, sources
//! ascending. Every particle's force is thus added in one fixed order at
//! any thread count.
//!
//! **Precision.** The lanes are `f32` (sixteen per AVX-512 register, as
//! GROMACS' mixed precision): coordinates relative to an origin near the
//! particles (the lowest corner at the last list build), the pair, and
//! each lane's sum over one row (own side) or one block (partner side);
//! the per-particle sums and everything after them (integration) are
//! `f64`. A pair force carries a relative error of a few `f32` roundings
//! and the coordinates' quantization (about `1e-6` of the spacing). The
//! same code in `f64` lanes checks the cluster machinery in the tests
//! against the row kernel; in double precision the world runs the row
//! kernel, which is faster there: the tiles compute four to five times the
//! pairs within the cut-off (a tile is kept when any of its sixteen pairs
//! is in reach), which `f64` lanes do not pay back. No fused multiply-add
//! is formed, so the bits are the same on every instruction set.
//!
//! The pair is [`LennardJones::eval_sq_12_6_select`] (seed 002 §3, the
//! tapered 12-6 potential): the same operations in the same order, in the
//! lane type.

mod coords;
#[cfg(test)]
mod tests;
mod tile;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::Sums;
use crate::interactions::LennardJones;
use crate::math::{Point3, Real, Vec3};
use crate::neighbours::{ClusterPairs, NeighbourList, CLUSTER};
use coords::ClusterCoords;
use tile::{Constants, Lane, Lanes3, PartnerForces, Sums16};

/// Arithmetic of the pair kernels (world setting `precision`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// Every operation in `f64` (the default).
    #[default]
    Double,
    /// Pair arithmetic in `f32` lanes, per-particle sums and integration
    /// in `f64` (GROMACS' mixed precision), where a kernel has it: the
    /// cluster kernel of one 12-6 Lennard-Jones spacing material (worlds
    /// without orientation terms, heat or bonds). Pair forces carry a relative error of about
    /// `1e-6`; other worlds run in double precision.
    Mixed,
}

/// The cluster kernel's scratch in lanes of `F`, owned by the force
/// scratch: the cluster pairs, the coordinates, the merge's buffers.
#[derive(Default)]
pub(crate) struct ClusterScratch<F> {
    pairs: ClusterPairs,
    /// Origin of the coordinates: the lowest corner of the finite
    /// positions at the last list build.
    origin: Point3,
    coords: ClusterCoords<F>,
    /// Per block, what it adds to later blocks.
    halos: Vec<Halo>,
    /// Per block, the halo entries it receives.
    incoming: Vec<Vec<(u32, u32, u32)>>,
}

/// Clusters per block of the ordered merge (256 particles): a function of
/// the cluster count only, never of the thread count.
const BLOCK: usize = 64;

/// What a block adds to the particles of later blocks: per target
/// cluster (ascending after the block's pass), the sum of its tiles'
/// partner forces, added in the block's visiting order.
#[derive(Default)]
pub(crate) struct Halo {
    entries: Vec<(u32, PartnerForces)>,
    /// The entries by target block: `(block, first entry, end)`, blocks
    /// ascending, found by the block's own task while its entries are in
    /// its cache (the merge's serial step then only reads these: a binary
    /// search of the entries there, through memory the other threads had
    /// written, took 5% of a mixed-precision step at 2 threads).
    spans: Vec<(u32, u32, u32)>,
    /// Scratch where the targets span many clusters ([`HALO_SCAN`]): the
    /// entries in the block's visiting order, and their `(target,
    /// position)` keys (sorting the small keys, then gathering the
    /// entries, moves each entry once).
    visited: Vec<(u32, PartnerForces)>,
    keys: Vec<(u32, u32)>,
}

/// Per-thread scratch of [`block_rows`]: a map from cluster to its
/// partner sums (all `u32::MAX` between blocks), and the sums, in the
/// order the block first touched their clusters.
struct Touched<F> {
    slot: Vec<u32>,
    sums: Vec<(u32, Lanes3<F>)>,
}

/// Pass 1 of block `b` (see the module docs): every row of its clusters.
/// `forces` and `energies` are the block's particles; on return each holds
/// its in-block sum (its own row, then what the block's other rows add to
/// it); `halo` the forces on later blocks' particles.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn block_rows<F: Lane, S: pulp::Simd>(
    simd: S,
    c: &Constants<F>,
    pairs: &ClusterPairs,
    xs: &ClusterCoords<F>,
    b: usize,
    forces: &mut [Vec3],
    energies: &mut [Real],
    halo: &mut Halo,
    touched: &mut Touched<F>,
) {
    let c0 = b * BLOCK;
    let c1 = c0 + forces.len().div_ceil(CLUSTER);
    let Touched { slot, sums } = touched;
    sums.clear();
    for ci in c0..c1 {
        let xi = xs.own(ci);
        let mut s = Sums16::zero();
        let row = pairs.row(ci);
        F::tile::<S, true>(simd, c, &xi, xs.partner(ci), &mut s, || unreachable!());
        for &cj in &row[1..] {
            F::tile::<S, false>(simd, c, &xi, xs.partner(cj as usize), &mut s, || {
                let k = &mut slot[cj as usize];
                if *k == u32::MAX {
                    *k = sums.len() as u32;
                    sums.push((cj, Lanes3::zero()));
                }
                &mut sums[*k as usize].1
            });
        }
        let at = CLUSTER * (ci - c0);
        let end = forces.len().min(at + CLUSTER);
        for (a, (f, e)) in forces[at..end]
            .iter_mut()
            .zip(&mut energies[at..end])
            .enumerate()
        {
            (*f, *e) = s.particle(a);
        }
    }
    // The block's own clusters first (each adds to its own particles: any
    // order), then the halo in ascending target.
    let (mut halo_len, mut last) = (0, c1);
    for (t, lanes) in sums.iter() {
        let t = *t as usize;
        if t < c1 {
            slot[t] = u32::MAX;
            add_partner(forces, CLUSTER * (t - c0), &lanes.reduce());
        } else {
            halo_len += 1;
            last = last.max(t);
        }
    }
    let Halo {
        entries,
        spans,
        visited,
        keys,
    } = halo;
    entries.clear();
    spans.clear();
    if halo_len == 0 {
        return;
    }
    if last - c1 < HALO_SCAN * halo_len {
        // Targets within a short span: read them off the slot map in
        // ascending order (each appears once), no sort.
        for (t, k) in slot[c1..=last].iter_mut().enumerate() {
            if *k != u32::MAX {
                entries.push(((c1 + t) as u32, sums[*k as usize].1.reduce()));
                *k = u32::MAX;
            }
        }
    } else {
        // Ascending targets (each appears once: the order is unique).
        visited.clear();
        for (t, lanes) in sums.iter().filter(|(t, _)| *t as usize >= c1) {
            slot[*t as usize] = u32::MAX;
            visited.push((*t, lanes.reduce()));
        }
        keys.clear();
        keys.extend(visited.iter().enumerate().map(|(k, h)| (h.0, k as u32)));
        keys.sort_unstable();
        entries.extend(keys.iter().map(|&(_, k)| visited[k as usize]));
    }
    target_spans(entries, spans);
}

/// Sets `spans` to the runs of `entries` (ascending target cluster) that
/// aim at one block: `(block, first entry, end)`, blocks ascending.
fn target_spans(entries: &[(u32, PartnerForces)], spans: &mut Vec<(u32, u32, u32)>) {
    spans.clear();
    for (k, (target, _)) in entries.iter().enumerate() {
        let (t, k) = ((*target as usize / BLOCK) as u32, k as u32);
        match spans.last_mut() {
            Some(last) if last.0 == t => last.2 = k + 1,
            _ => spans.push((t, k, k + 1)),
        }
    }
}

/// A block's halo targets are read off its slot map in ascending order
/// when they span fewer than this many clusters per target (a scan of a
/// few `u32` per target, instead of sorting them; in the 32k LJ block the
/// sort took 3% of a mixed-precision step).
const HALO_SCAN: usize = 16;

/// Adds the partner forces `fj` to the particles from slot `at` of
/// `forces` (those that exist: the last cluster is padded).
#[inline(always)]
fn add_partner(forces: &mut [Vec3], at: usize, fj: &PartnerForces) {
    let end = forces.len().min(at + CLUSTER);
    for (q, f) in forces[at..end].iter_mut().enumerate() {
        *f += Vec3::new(fj[q], fj[CLUSTER + q], fj[2 * CLUSTER + q]);
    }
}

/// [`block_rows`] as the operation pulp dispatches (see the module docs).
struct BlockRows<'a, F> {
    c: &'a Constants<F>,
    pairs: &'a ClusterPairs,
    xs: &'a ClusterCoords<F>,
    b: usize,
    forces: &'a mut [Vec3],
    energies: &'a mut [Real],
    halo: &'a mut Halo,
    touched: &'a mut Touched<F>,
}

impl<F: Lane> pulp::WithSimd for BlockRows<'_, F> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        block_rows(
            simd,
            self.c,
            self.pairs,
            self.xs,
            self.b,
            self.forces,
            self.energies,
            self.halo,
            self.touched,
        );
    }
}

/// Sets `out` to the uniform 12-6 spacing of every listed pair (forces,
/// zero torques, per-particle energies: each pair's energy on the first
/// particle of its tile, half of it on each particle of a cluster's own
/// tile), computed on the cluster pairs of `list` in lanes of `F`.
pub(super) fn cluster_spacing_pass<F: Lane>(
    lj: &LennardJones,
    cutoff2: Real,
    p: &[Point3],
    list: &NeighbourList,
    scratch: &mut ClusterScratch<F>,
    out: Sums<'_>,
) {
    let n = p.len();
    if scratch.pairs.update(list, n) {
        scratch.origin = lowest_corner(list.reference_positions());
    }
    out.torques
        .par_iter_mut()
        .with_min_len(crate::MIN_PARALLEL_LEN)
        .for_each(|t| *t = Vec3::zeros());
    let ClusterScratch {
        pairs,
        origin,
        coords,
        halos,
        incoming,
    } = scratch;
    coords.fill(p, *origin);
    let merge = Merge { halos, incoming };
    pass(&Constants::<F>::of(lj, cutoff2), pairs, coords, merge, out);
}

/// The ordered merge's buffers ([`ClusterScratch`]).
struct Merge<'a> {
    halos: &'a mut Vec<Halo>,
    /// Per target block: `(source block, entry range)` of the halo entries
    /// aimed at it, sources ascending.
    incoming: &'a mut Vec<Vec<(u32, u32, u32)>>,
}

/// The two passes of the ordered merge: every block's rows, then every
/// block adds the halo entries of the earlier blocks aimed at it, sources
/// ascending. Each particle's force is thus added in one fixed order (in
/// block, own row, earlier blocks) at any thread count.
fn pass<F: Lane>(
    c: &Constants<F>,
    pairs: &ClusterPairs,
    xs: &ClusterCoords<F>,
    merge: Merge<'_>,
    out: Sums<'_>,
) {
    let arch = pulp::Arch::new();
    let nc = pairs.clusters();
    let size = BLOCK * CLUSTER;
    let nb = out.forces.len().div_ceil(size);
    let Merge { halos, incoming } = merge;
    halos.resize_with(nb.max(halos.len()), Halo::default);
    out.forces
        .par_chunks_mut(size)
        .zip(out.energies.par_chunks_mut(size))
        .zip(halos[..nb].par_iter_mut())
        .enumerate()
        .for_each_init(
            || Touched {
                slot: vec![u32::MAX; nc],
                sums: Vec::new(),
            },
            |touched, (b, ((forces, energies), halo))| {
                arch.dispatch(BlockRows {
                    c,
                    pairs,
                    xs,
                    b,
                    forces,
                    energies,
                    halo,
                    touched,
                })
            },
        );
    // Which entries of which earlier blocks each block receives.
    incoming.resize_with(nb.max(incoming.len()), Vec::new);
    incoming.iter_mut().for_each(Vec::clear);
    for (s, halo) in halos[..nb].iter().enumerate() {
        for &(t, lo, hi) in &halo.spans {
            incoming[t as usize].push((s as u32, lo, hi));
        }
    }
    let halos = &halos[..nb];
    out.forces
        .par_chunks_mut(size)
        .zip(incoming[..nb].par_iter())
        .enumerate()
        .for_each(|(t, (forces, from))| {
            for &(s, lo, hi) in from {
                for (cj, fj) in &halos[s as usize].entries[lo as usize..hi as usize] {
                    add_partner(forces, CLUSTER * (*cj as usize - t * BLOCK), fj);
                }
            }
        });
}

/// The componentwise minimum of the finite positions (the origin when
/// there are none).
fn lowest_corner(p: &[Point3]) -> Point3 {
    p.par_iter()
        .filter(|q| q.iter().all(|v| v.is_finite()))
        .copied()
        .reduce_with(|a, b| a.inf(&b))
        .unwrap_or_else(Point3::origin)
}
