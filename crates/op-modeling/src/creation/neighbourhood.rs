//! The neighbours the creation rules look at, searched once per
//! application and shared by stretching and growing.
//!
//! Each rule reads the particles within its own radius of a particle
//! (stretching: `max(d_max, reach + d_max / 2)`, which holds every
//! particle near a pair's midpoint; growing: `max(radius, r0 +
//! clearance)`, which holds every particle near a candidate). One search
//! at the larger radius serves both: a rule narrows a particle's
//! neighbours to its radius with the search's own test (`|p_k - p_i|^2 <=
//! radius^2`, the same arithmetic), so each rule sees exactly the
//! particles a search at its radius would have given, in the same order.

use op_dynamics::math::{Point3, Real};
use op_dynamics::neighbours::{search, NeighbourBackend, PairList};

/// Every particle's neighbours within one radius: a half list and, for
/// each pair, its first particle (so a particle's neighbours below it are
/// read from the incoming index without a full list per particle).
pub(crate) struct Neighbourhood<'a> {
    positions: &'a [Point3],
    radius: Real,
    half: PairList,
    sources: Vec<u32>,
}

impl<'a> Neighbourhood<'a> {
    /// The pairs of `positions` within `radius` (non-finite positions have
    /// none).
    pub(crate) fn new(positions: &'a [Point3], radius: Real) -> Self {
        let mut half = PairList::new();
        search(NeighbourBackend::CellList, positions, radius, &mut half);
        let mut sources = Vec::new();
        half.sources_into(&mut sources);
        Neighbourhood {
            positions,
            radius,
            half,
            sources,
        }
    }

    /// The neighbours `j > i` of `i` within `radius` (at most the search
    /// radius), ascending.
    pub(crate) fn above(&self, i: usize, radius: Real) -> impl Iterator<Item = usize> + '_ {
        let keep = self.within(i, radius);
        self.half
            .row(i)
            .iter()
            .map(|&j| j as usize)
            .filter(move |&j| keep(j))
    }

    /// Every neighbour of `i` within `radius` (at most the search radius),
    /// ascending: those below `i`, then those above.
    pub(crate) fn around(&self, i: usize, radius: Real) -> impl Iterator<Item = usize> + '_ {
        let keep = self.within(i, radius);
        self.half
            .incoming(i)
            .iter()
            .map(|&k| self.sources[k as usize])
            .chain(self.half.row(i).iter().copied())
            .map(|k| k as usize)
            .filter(move |&k| keep(k))
    }

    /// [`Neighbourhood::around`] into `out` (cleared first).
    pub(crate) fn around_into(&self, i: usize, radius: Real, out: &mut Vec<u32>) {
        out.clear();
        out.extend(self.around(i, radius).map(|k| k as u32));
    }

    /// Whether a neighbour `k` of `i` is within `radius` of it, by the
    /// search's own test; every neighbour is when `radius` is the search's.
    fn within(&self, i: usize, radius: Real) -> impl Fn(usize) -> bool + '_ {
        debug_assert!(radius <= self.radius, "a rule reads beyond the search");
        let (all, r2, p) = (radius >= self.radius, radius * radius, self.positions[i]);
        move |k| {
            let q = self.positions[k];
            let (dx, dy, dz) = (q.x - p.x, q.y - p.y, q.z - p.z);
            all || dx * dx + dy * dy + dz * dz <= r2
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Narrowed to a smaller radius, the neighbours are those of a search
    /// at that radius, in the same order (pairs exactly at both radii
    /// included).
    #[test]
    fn a_narrowed_neighbourhood_is_a_search_at_the_smaller_radius() {
        let mut positions: Vec<Point3> = (0..400)
            .map(|n| {
                let h = |s: u64| ((n as u64 + 1) * s % 1009) as Real / 1009.0 * 6.0;
                Point3::new(h(389), h(521), h(757))
            })
            .collect();
        positions.extend([
            Point3::new(20.0, 0.0, 0.0),
            Point3::new(21.5, 0.0, 0.0),
            Point3::new(24.25, 0.0, 0.0),
            Point3::new(Real::NAN, 0.0, 0.0),
        ]);
        let wide = Neighbourhood::new(&positions, 2.75);
        for radius in [1.5, 1.7, 2.75] {
            let narrow = Neighbourhood::new(&positions, radius);
            for i in 0..positions.len() {
                let (a, b): (Vec<usize>, Vec<usize>) = (
                    wide.around(i, radius).collect(),
                    narrow.around(i, radius).collect(),
                );
                assert_eq!(a, b, "particle {i}, radius {radius}");
                let above: Vec<usize> = wide.above(i, radius).collect();
                let expected: Vec<usize> = narrow.half.row(i).iter().map(|&j| j as usize).collect();
                assert_eq!(above, expected, "particle {i}, radius {radius}");
            }
        }
        assert_eq!(wide.around(401, 1.5).collect::<Vec<_>>(), vec![400]);
        assert_eq!(wide.around(402, 1.5).count(), 0);
        assert_eq!(wide.around(402, 2.75).collect::<Vec<_>>(), vec![401]);
        assert_eq!(wide.around(403, 2.75).count(), 0);
    }
}
