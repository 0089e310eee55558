//! Neighbour lists: radius queries with a skin (seed 000 §4.2, docs/model.md §5).
//!
//! - [`PairList`]: the flat (CSR) **half** list every consumer reads: row
//!   `i` holds the neighbours `j > i` (ascending), plus, on request, the
//!   transposed incoming index for deterministic per-particle gathers.
//! - [`search`]: one radius search with a chosen [`NeighbourBackend`]
//!   (sorted cell list, kiddo k-d tree, or the all-pairs oracle). All
//!   backends give identical lists.
//! - [`NeighbourList`]: the cached list of a simulation, rebuilt only when
//!   the two largest displacements add up to more than the skin.
//! - [`ClusterPairs`]: the same list over clusters of [`CLUSTER`]
//!   consecutive particles, half rows, for tile kernels.
//! - [`spatial_order`]: a Morton permutation that puts particles in spatial
//!   memory order (the world re-sorts at rebuilds); [`cluster_order`]:
//!   columns sorted along z, for compact clusters (worlds on the cluster
//!   kernel).
//!
//! **Pair test**, shared bit for bit by every backend: `(i, j)` is a pair
//! when `dx*dx + dy*dy + dz*dz <= radius^2` with `d = p_j - p_i` (inclusive;
//! no fused multiply-add). **Degenerate input**: a NaN or negative radius
//! finds no pairs; radius 0 finds coincident particles; particles with a
//! NaN or infinite coordinate have no neighbours (they are "infinitely far
//! away"); huge coordinate ranges and all particles at one point are
//! handled (the cell list caps its number of cells). Nothing here panics on
//! such input; the only panics are capacity limits (`u32` particle and pair
//! indices).

mod all_pairs;
mod cell_list;
mod clusters;
mod csr;
mod kd_tree;
mod morton;

#[cfg(test)]
mod tests;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use all_pairs::all_pairs;
pub use clusters::{ClusterPairs, CLUSTER};
pub use csr::PairList;
pub use morton::{cluster_order, spatial_order};

use crate::error::{self, ParamError};
use crate::math::{Point3, Real};

/// The algorithm that builds a [`PairList`]. Every backend gives the same
/// lists (same pair test, rows sorted); only the cost differs.
///
/// Time to build the half list (with the incoming index), radius 2.5 x
/// spacing (`benches/neighbours.rs`; sheet: hexagonal, flat in z = 0;
/// rotated: the same sheet tilted about a generic axis; volume: jittered
/// cubic lattice; order: Morton-sorted or shuffled). Criterion medians in
/// ms, 2 threads, on a 2-core machine shared with other builds (load 6-7,
/// so wall times are inflated and +-50% between runs):
///
/// | n | shape | order | cell list | kd-tree | kd / cell |
/// |---|---|---|---|---|---|
/// | 10k | sheet | morton | 1.84 | 13.71 | 7.5x |
/// | 10k | sheet | random | 11.73 | 17.31 | 1.5x |
/// | 10k | rotated | morton | 4.41 | 15.25 | 3.5x |
/// | 10k | rotated | random | 10.49 | 17.57 | 1.7x |
/// | 10k | volume | morton | 9.85 | 36.65 | 3.7x |
/// | 10k | volume | random | 23.67 | 42.29 | 1.8x |
/// | 100k | sheet | morton | 21.59 | 176.42 | 8.2x |
/// | 100k | sheet | random | 69.85 | 292.87 | 4.2x |
/// | 100k | rotated | morton | 54.99 | 333.16 | 6.1x |
/// | 100k | rotated | random | 121.60 | 224.53 | 1.8x |
/// | 100k | volume | morton | 133.05 | 407.37 | 3.1x |
/// | 100k | volume | random | 269.51 | 519.12 | 1.9x |
///
/// CPU time per build at one thread (`perf stat` task-clock, hence
/// insensitive to the load), 100k particles, ms:
///
/// | shape | order | cell list | kd-tree |
/// |---|---|---|---|
/// | sheet | morton | 13.7 | 124 |
/// | sheet | random | 46.5 | 149 |
/// | rotated | morton | 34.3 | 93 |
/// | rotated | random | 63.5 | 130 |
/// | volume | morton | 86.6 | 249 |
/// | volume | random | 164 | 317 |
///
/// The cell list wins everywhere (2-9x), most on sheets and in spatial
/// order, so it is the default. Both are 2-3x faster in Morton order than
/// in random order: keep particles spatially sorted
/// ([`spatial_order`]).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum NeighbourBackend {
    /// Sorted uniform cell list (cells >= radius, 27-cell stencil), parallel
    /// over particles. The default: fastest in the benchmark above.
    #[default]
    CellList,
    /// kiddo's `ImmutableKdTree` with unsorted radius queries, parallel over
    /// particles. Slow on sheets lying in an axis plane.
    KdTree,
    /// The serial `O(n^2)` oracle ([`all_pairs`]); tests and tiny systems only.
    AllPairs,
}

/// Fills `out` with the half list of every pair within `radius` (inclusive)
/// of `positions`, using `backend`, with its incoming index. `out`'s
/// buffers are reused.
///
/// A NaN or negative radius gives a list without pairs; particles with a
/// non-finite coordinate have no neighbours.
///
/// # Panics
/// If there are `u32::MAX` particles or more, or more than `u32::MAX` pairs
/// (a radius far too large for the system).
pub fn search(backend: NeighbourBackend, positions: &[Point3], radius: Real, out: &mut PairList) {
    search_rows(backend, positions, radius, out);
    out.build_incoming();
}

/// [`search`] without the incoming index (built on request,
/// [`PairList::build_incoming`]).
fn search_rows(backend: NeighbourBackend, positions: &[Point3], radius: Real, out: &mut PairList) {
    match backend {
        NeighbourBackend::CellList => cell_list::cell_list(positions, radius, out),
        NeighbourBackend::KdTree => kd_tree::kd_tree(positions, radius, out),
        NeighbourBackend::AllPairs => all_pairs(positions, radius, out),
    }
}

/// A cached half neighbour list with a skin (Verlet list).
///
/// The list holds every pair within `cutoff + skin` of the positions at the
/// last build (the reference positions). [`update`](Self::update) rebuilds
/// it when the two largest displacements from the reference positions add
/// up to more than the skin. **Guarantee**: after `update(positions)`, every
/// pair within `cutoff` at `positions` is in [`pairs`](Self::pairs) (its two
/// particles moved at most `skin` together, so the pair was within
/// `cutoff + skin` at the build).
/// The list may also hold pairs farther than `cutoff`: consumers test the
/// distance themselves.
///
/// A particle whose position turns non-finite (or finite again) triggers a
/// rebuild; one that stays non-finite does not, and has no neighbours.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct NeighbourList {
    backend: NeighbourBackend,
    cutoff: Real,
    skin: Real,
    /// Positions at the last build.
    reference: Vec<Point3>,
    pairs: PairList,
    /// Whether `pairs` holds the rows of the current build (false after
    /// [`NeighbourList::rebuild_reference`], until
    /// [`NeighbourList::ensure_rows`]).
    rows: bool,
    built: bool,
    rebuilds: u64,
    /// The bound `d1 + d2` (the two largest displacements from the
    /// reference positions) at the last [`NeighbourList::rebuild_due`]
    /// call.
    last_shift: Real,
}

/// Relative slack on the `d1 + d2 <= skin` rebuild threshold: rebuilding slightly
/// early absorbs the round-off of the displacement and pair tests, so the
/// guarantee holds at the boundary too.
const THRESHOLD_SLACK: Real = 1e-9;

impl NeighbourList {
    /// A list of all pairs within `cutoff + skin`, not built yet.
    ///
    /// # Panics
    /// If `cutoff` or `skin` is negative, NaN or infinite (use
    /// [`try_new`](Self::try_new) to get an error instead).
    pub fn new(backend: NeighbourBackend, cutoff: Real, skin: Real) -> Self {
        Self::try_new(backend, cutoff, skin).unwrap_or_else(|e| panic!("NeighbourList::new: {e}"))
    }

    /// Like [`new`](Self::new), but returns an error naming the bad
    /// parameter (`cutoff` or `skin`) instead of panicking: both must be
    /// finite and `>= 0`. `cutoff = 0` is allowed (only coincident
    /// particles pair up); `skin = 0` rebuilds whenever anything moves.
    pub fn try_new(
        backend: NeighbourBackend,
        cutoff: Real,
        skin: Real,
    ) -> Result<Self, ParamError> {
        error::non_negative("cutoff", cutoff)?;
        error::non_negative("skin", skin)?;
        error::finite("cutoff + skin", cutoff + skin)?;
        Ok(Self {
            backend,
            cutoff,
            skin,
            reference: Vec::new(),
            pairs: PairList::new(),
            rows: true,
            built: false,
            rebuilds: 0,
            last_shift: 0.0,
        })
    }

    /// Rebuilds the list when it has never been built, the particle count
    /// changed, or the two largest displacements since the last build add
    /// up to more than the skin (see [`NeighbourList::needs_rebuild`]).
    /// Returns true when it rebuilt.
    pub fn update(&mut self, positions: &[Point3]) -> bool {
        if !self.needs_rebuild(positions) {
            self.ensure_rows();
            return false;
        }
        self.rebuild(positions);
        true
    }

    /// [`update`](Self::update) for consumers that read only the reference
    /// positions (the cluster kernel builds its own rows from them,
    /// [`ClusterPairs`]): a rebuild takes the new reference positions
    /// without searching the particle rows ([`rebuild_reference`](Self::rebuild_reference)).
    /// The rebuild decision, and so the trajectory, is that of `update`.
    pub fn update_reference(&mut self, positions: &[Point3]) -> bool {
        if !self.needs_rebuild(positions) {
            return false;
        }
        self.rebuild_reference(positions);
        true
    }

    /// True when [`NeighbourList::update`] would rebuild (the world uses it
    /// to re-sort particles in spatial order just before a rebuild).
    ///
    /// The criterion is the pair bound of the Verlet list: a pair's
    /// distance changes by at most the sum of its two particles'
    /// displacements, so while the two largest displacements `d1 >= d2`
    /// satisfy `d1 + d2 <= skin`, no pair that was beyond `cutoff + skin`
    /// at the build can be within `cutoff`. (The per-particle rule
    /// `2 d1 <= skin` is the special case `d2 = d1`; with the pair bound a
    /// few fast particles among slow ones no longer force a rebuild.) A
    /// particle that turned non-finite, or finite again, also rebuilds.
    pub fn needs_rebuild(&self, positions: &[Point3]) -> bool {
        !self.built
            || positions.len() != self.reference.len()
            || self.moved_too_far(self.displacements(positions))
    }

    /// True when [`NeighbourList::needs_rebuild`] is, or when the measured
    /// motion predicts that it will be at the next call: the bound
    /// `d1 + d2` ([`NeighbourList::needs_rebuild`]) grown by its growth
    /// since the previous call (one more step at the same speed) exceeds
    /// the skin. The world calls it once per step, before integrating, so
    /// that rebuilds happen there, where particles can be re-sorted in
    /// spatial order, rather than inside a force evaluation (which still
    /// rebuilds, exactly when needed, if the prediction was short). Only
    /// positions enter: the decision is the same on any machine and at
    /// any thread count.
    pub fn rebuild_due(&mut self, positions: &[Point3]) -> bool {
        if !self.built || positions.len() != self.reference.len() {
            return true;
        }
        let moved = self.displacements(positions);
        if self.moved_too_far(moved) {
            return true;
        }
        let bound = moved.0 + moved.1;
        let growth = (bound - self.last_shift).max(0.0);
        self.last_shift = bound;
        bound + growth > self.skin * (1.0 - THRESHOLD_SLACK)
    }

    /// The two largest distances `(d1, d2)`, `d1 >= d2`, of finite
    /// positions from their references, and whether some particle changed
    /// between finite and non-finite.
    fn displacements(&self, positions: &[Point3]) -> (Real, Real, bool) {
        let (a, b, flipped) = positions
            .par_iter()
            .zip(self.reference.par_iter())
            .with_min_len(4096)
            .fold(
                || (0.0, 0.0, false),
                |(a, b, f): (Real, Real, bool), (p, q)| {
                    let d2 = (p - q).norm_squared();
                    if d2.is_nan() {
                        // Fine only if both are non-finite (no neighbours
                        // either way).
                        return (a, b, f || csr::is_finite(p) || csr::is_finite(q));
                    }
                    let (a, b) = top_two(a, b, d2);
                    (a, b, f || d2.is_infinite())
                },
            )
            .reduce(
                || (0.0, 0.0, false),
                |(a, b, f), (c, d, g)| {
                    let (a, b) = top_two(a, b, c);
                    let (a, b) = top_two(a, b, d);
                    (a, b, f || g)
                },
            );
        (a.sqrt(), b.sqrt(), flipped)
    }

    /// Whether the displacements `(d1, d2, flipped)` call for a rebuild:
    /// `d1 + d2` above the skin (less a round-off slack), or a particle
    /// flipped between finite and non-finite.
    fn moved_too_far(&self, (d1, d2, flipped): (Real, Real, bool)) -> bool {
        flipped || d1 + d2 > self.skin * (1.0 - THRESHOLD_SLACK)
    }

    /// Marks the list stale: the next [`update`](Self::update) rebuilds it
    /// (the world calls this when particles are inserted or removed, since
    /// slots then no longer match the reference positions).
    pub fn invalidate(&mut self) {
        self.built = false;
    }

    /// Rebuilds the list unconditionally, taking `positions` as the new
    /// reference positions. The incoming index is not built
    /// ([`NeighbourList::build_incoming`]).
    pub fn rebuild(&mut self, positions: &[Point3]) {
        self.rebuild_reference(positions);
        self.ensure_rows();
    }

    /// Takes `positions` as the new reference positions, like
    /// [`rebuild`](Self::rebuild), but leaves the particle rows empty
    /// until [`ensure_rows`](Self::ensure_rows) (or
    /// [`update`](Self::update)) searches them: a rebuild for consumers of
    /// the reference positions only.
    pub fn rebuild_reference(&mut self, positions: &[Point3]) {
        copy_positions(&mut self.reference, positions);
        self.pairs.set_empty(positions.len());
        self.rows = false;
        self.built = true;
        self.rebuilds += 1;
        self.last_shift = 0.0;
    }

    /// Searches the particle rows of the current build if
    /// [`rebuild_reference`](Self::rebuild_reference) left them empty:
    /// every pair within `cutoff + skin` of the reference positions, the
    /// same list a [`rebuild`](Self::rebuild) would have made then. Does not
    /// count as a rebuild.
    pub fn ensure_rows(&mut self) {
        if self.rows {
            return;
        }
        let radius = self.radius();
        search_rows(self.backend, &self.reference, radius, &mut self.pairs);
        self.rows = true;
    }

    /// Whether [`pairs`](Self::pairs) holds the rows of the current build
    /// (see [`ensure_rows`](Self::ensure_rows)).
    pub fn has_rows(&self) -> bool {
        self.rows
    }

    /// Builds the incoming index of the current list if it is not built
    /// ([`PairList::build_incoming`]): the stages that gather per particle
    /// call it after [`NeighbourList::update`].
    pub fn build_incoming(&mut self) {
        self.pairs.build_incoming();
    }

    /// The half list of the last build (empty before the first, and after
    /// a [`rebuild_reference`](Self::rebuild_reference) until
    /// [`ensure_rows`](Self::ensure_rows)).
    pub fn pairs(&self) -> &PairList {
        &self.pairs
    }

    /// Whether the list is well formed for `n` particles (a list read back
    /// from a checkpoint is checked before use): unbuilt, or built over `n`
    /// reference positions with a consistent pair list.
    pub(crate) fn is_consistent(&self, n: usize) -> bool {
        !self.built || (self.reference.len() == n && self.pairs.is_consistent(n))
    }

    /// The interaction cut-off radius.
    pub fn cutoff(&self) -> Real {
        self.cutoff
    }

    /// The skin: the list radius is `cutoff + skin`.
    pub fn skin(&self) -> Real {
        self.skin
    }

    /// The radius of the list searches: `cutoff + skin`.
    pub fn radius(&self) -> Real {
        self.cutoff + self.skin
    }

    /// How many times the list was built.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// The search backend.
    pub fn backend(&self) -> NeighbourBackend {
        self.backend
    }

    /// The positions at the last build (empty before the first).
    pub fn reference_positions(&self) -> &[Point3] {
        &self.reference
    }
}

/// The two largest of `a >= b` and `x`, in order.
#[inline(always)]
fn top_two(a: Real, b: Real, x: Real) -> (Real, Real) {
    if x > a {
        (x, a)
    } else if x > b {
        (a, x)
    } else {
        (a, b)
    }
}

/// `dst = positions`, in parallel over fixed chunks: the world keeps the
/// positions before each step (the oscillation measure) and the list its
/// reference positions at each build, a copy of every position that ran
/// on one thread while the others waited.
pub(crate) fn copy_positions(dst: &mut Vec<Point3>, positions: &[Point3]) {
    const CHUNK: usize = 4096;
    dst.resize(positions.len(), Point3::origin());
    dst.par_chunks_mut(CHUNK)
        .zip(positions.par_chunks(CHUNK))
        .for_each(|(a, b)| a.copy_from_slice(b));
}
