//! Backend agreement, transpose, thread-count determinism and skin tests.

use super::*;
use crate::interactions::test_support::Rng;
use crate::math::Vec3;

/// A random vector uniform in the ball of radius `r` (rejection sampling).
fn vec_in_ball(rng: &mut Rng, r: Real) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if v.norm_squared() < 1.0 {
            return v * r;
        }
    }
}

fn random_volume(n: usize, side: Real, seed: u64) -> Vec<Point3> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            Point3::new(
                rng.range(0.0, side),
                rng.range(0.0, side),
                rng.range(0.0, side),
            )
        })
        .collect()
}

/// A hexagonal sheet in the z = 0 plane, spacing 1, with jitter in the plane.
fn hex_sheet(rows: usize, cols: usize, jitter: Real, seed: u64) -> Vec<Point3> {
    let mut rng = Rng::new(seed);
    let mut pts = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        for c in 0..cols {
            let x = c as Real + 0.5 * (r % 2) as Real + rng.range(-jitter, jitter);
            let y = r as Real * (0.75 as Real).sqrt() + rng.range(-jitter, jitter);
            pts.push(Point3::new(x, y, 0.0));
        }
    }
    pts
}

fn rotated(pts: &[Point3]) -> Vec<Point3> {
    let rot = crate::math::Quat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8));
    pts.iter().map(|p| rot * p).collect()
}

fn clustered(n: usize, seed: u64) -> Vec<Point3> {
    let mut rng = Rng::new(seed);
    let centres: Vec<Point3> = (0..5)
        .map(|_| Point3::from(vec_in_ball(&mut rng, 20.0)))
        .collect();
    (0..n)
        .map(|i| {
            let c = centres[i % centres.len()];
            // Some tight clumps, some exact duplicates.
            match i % 7 {
                0 => c,
                1 => c + vec_in_ball(&mut rng, 1e-9),
                _ => c + vec_in_ball(&mut rng, 2.0),
            }
        })
        .collect()
}

fn oracle(positions: &[Point3], radius: Real) -> PairList {
    let mut l = PairList::new();
    all_pairs(positions, radius, &mut l);
    l
}

/// The incoming index computed the naive way from the rows.
fn naive_incoming(l: &PairList) -> Vec<Vec<u32>> {
    let mut inc = vec![Vec::new(); l.len()];
    for (k, &j) in l.neighbours().iter().enumerate() {
        inc[j as usize].push(k as u32);
    }
    inc
}

/// Checks the structural invariants of a list against the positions.
fn check_invariants(l: &PairList, positions: &[Point3], radius: Real) {
    assert_eq!(l.len(), positions.len());
    let r2 = radius * radius;
    for i in 0..l.len() {
        let row = l.row(i);
        assert!(row.windows(2).all(|w| w[0] < w[1]), "row {i} not sorted");
        assert!(
            row.iter().all(|&j| j as usize > i),
            "row {i} not a half row"
        );
        for (k, &j) in l.row_range(i).zip(row) {
            assert_eq!(l.pair_source(k), i);
            assert_eq!(l.pair_target(k), j as usize);
            assert!(csr::dist2(&csr::arr(&positions[i]), &csr::arr(&positions[j as usize])) <= r2);
        }
    }
    let inc = naive_incoming(l);
    for (j, expect) in inc.iter().enumerate() {
        assert_eq!(l.incoming(j), expect.as_slice(), "incoming({j})");
    }
}

const FAST: [NeighbourBackend; 2] = [NeighbourBackend::CellList, NeighbourBackend::KdTree];

/// Every fast backend equals the oracle, and the oracle is well formed.
fn assert_backends_agree(positions: &[Point3], radius: Real, what: &str) {
    let expect = oracle(positions, radius);
    check_invariants(&expect, positions, radius);
    for backend in FAST {
        let mut got = PairList::new();
        search(backend, positions, radius, &mut got);
        assert!(got == expect, "{what}: {backend:?} differs from all-pairs (radius {radius})\n got {} pairs, expected {}", got.num_pairs(), expect.num_pairs());
        // Reuse of buffers: a second search into the same list.
        search(backend, positions, radius, &mut got);
        assert!(got == expect, "{what}: {backend:?} second build differs");
    }
}

#[test]
fn backends_equal_oracle_on_random_volume() {
    let pts = random_volume(2000, 12.0, 1);
    for radius in [0.5, 1.0, 1.7, 3.0] {
        assert_backends_agree(&pts, radius, "random volume");
    }
    let l = oracle(&pts, 1.7);
    assert!(l.num_pairs() > 2000, "test should have many pairs");
}

#[test]
fn backends_equal_oracle_on_flat_sheet() {
    let pts = hex_sheet(40, 50, 0.05, 2);
    for radius in [1.0, 1.05, 2.5] {
        assert_backends_agree(&pts, radius, "flat sheet");
    }
    // A perfect lattice: many pairs exactly at the spacing.
    let pts = hex_sheet(30, 30, 0.0, 3);
    assert_backends_agree(&pts, 1.0, "perfect sheet");
}

#[test]
fn backends_equal_oracle_on_rotated_sheet() {
    let pts = rotated(&hex_sheet(40, 50, 0.05, 4));
    for radius in [1.0, 2.5] {
        assert_backends_agree(&pts, radius, "rotated sheet");
    }
}

#[test]
fn backends_equal_oracle_on_clustered_points() {
    let pts = clustered(3000, 5);
    for radius in [0.0, 1e-9, 0.3, 1.5] {
        assert_backends_agree(&pts, radius, "clustered");
    }
}

#[test]
fn pairs_at_exactly_the_radius_are_included() {
    // Integer lattice, spacing 1: neighbours at exactly 1, sqrt 2, sqrt 3.
    let mut pts = Vec::new();
    for z in 0..6 {
        for y in 0..7 {
            for x in 0..8 {
                pts.push(Point3::new(x as Real, y as Real, z as Real));
            }
        }
    }
    assert_backends_agree(&pts, 1.0, "lattice at radius 1");
    let l = oracle(&pts, 1.0);
    // Every lattice edge is a pair: 3 * 8*7*6 - (7*6 + 8*6 + 8*7) edges.
    assert_eq!(l.num_pairs(), 3 * 8 * 7 * 6 - (7 * 6 + 8 * 6 + 8 * 7));
    // A 3-4-5 triangle: squared distance exactly 25.
    let tri = [
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(3.0, 4.0, 0.0),
        Point3::new(3.0, 0.0, 0.0),
    ];
    assert_backends_agree(&tri, 5.0, "3-4-5 at radius 5");
    assert_eq!(oracle(&tri, 5.0).num_pairs(), 3);
    assert_eq!(oracle(&tri, 5.0 - 1e-12).num_pairs(), 2);
    // Binary fractions: spacing 0.25, radius 0.5.
    let line: Vec<Point3> = (0..100)
        .map(|i| Point3::new(0.25 * i as Real, 0.0, 0.0))
        .collect();
    assert_backends_agree(&line, 0.5, "line at radius 0.5");
    assert_eq!(oracle(&line, 0.5).num_pairs(), 99 + 98);
}

#[test]
fn tiny_systems() {
    for radius in [0.0, 1.0, 10.0] {
        assert_backends_agree(&[], radius, "0 particles");
        assert_backends_agree(&[Point3::new(1.0, 2.0, 3.0)], radius, "1 particle");
        assert_backends_agree(
            &[Point3::origin(), Point3::new(0.5, 0.0, 0.0)],
            radius,
            "2 particles",
        );
    }
    assert_eq!(
        oracle(&[Point3::origin(), Point3::new(0.5, 0.0, 0.0)], 1.0).num_pairs(),
        1
    );
    assert_eq!(
        oracle(&[Point3::origin(), Point3::new(0.5, 0.0, 0.0)], 0.4).num_pairs(),
        0
    );
}

#[test]
fn degenerate_input_does_not_panic() {
    // All particles at one point: every pair, at radius 0 too.
    let same = vec![Point3::new(1.5, -2.0, 3.0); 300];
    for radius in [0.0, 1.0] {
        assert_backends_agree(&same, radius, "all at one point");
        assert_eq!(oracle(&same, radius).num_pairs(), 300 * 299 / 2);
    }
    // Huge coordinate ranges: a tight cluster plus far outliers.
    let mut pts = random_volume(500, 3.0, 6);
    pts.extend([
        Point3::new(1e300, 0.0, 0.0),
        Point3::new(1e300, 0.5, 0.0),
        Point3::new(-1e300, -1e300, 1e300),
        Point3::new(Real::MAX, Real::MAX, -Real::MAX),
        Point3::new(Real::MAX, Real::MAX, -Real::MAX),
        Point3::new(1e-300, 0.0, 0.0),
    ]);
    for radius in [0.0, 0.7, 1e10] {
        assert_backends_agree(&pts, radius, "huge range");
    }
    assert!(oracle(&pts, 0.7).row(500).contains(&501));
    // Non-finite positions: no neighbours, others unaffected.
    let mut pts = random_volume(500, 3.0, 7);
    pts[10] = Point3::new(Real::NAN, 0.0, 0.0);
    pts[20] = Point3::new(Real::INFINITY, 1.0, 1.0);
    pts[21] = Point3::new(Real::INFINITY, 1.0, 1.0);
    pts[30] = Point3::new(Real::NAN, Real::NAN, Real::NAN);
    assert_backends_agree(&pts, 0.7, "non-finite");
    let l = oracle(&pts, 0.7);
    for i in [10, 20, 21, 30] {
        assert!(l.row(i).is_empty() && l.incoming(i).is_empty());
    }
    // All non-finite.
    assert_backends_agree(&[Point3::new(Real::NAN, 0.0, 0.0); 4], 1.0, "all NaN");
    // Radius: NaN and negative find nothing; infinite finds every finite pair.
    let pts = random_volume(100, 3.0, 8);
    for radius in [Real::NAN, -1.0, Real::NEG_INFINITY] {
        assert_backends_agree(&pts, radius, "bad radius");
        assert_eq!(oracle(&pts, radius).num_pairs(), 0);
    }
    assert_backends_agree(&pts, Real::INFINITY, "infinite radius");
    assert_eq!(oracle(&pts, Real::INFINITY).num_pairs(), 100 * 99 / 2);
}

#[test]
fn incoming_is_the_exact_transpose() {
    let pts = random_volume(3000, 14.0, 9);
    for backend in [
        NeighbourBackend::CellList,
        NeighbourBackend::KdTree,
        NeighbourBackend::AllPairs,
    ] {
        let mut l = PairList::new();
        search(backend, &pts, 1.5, &mut l);
        assert!(l.num_pairs() > 0);
        check_invariants(&l, &pts, 1.5);
        // Every pair is listed once as incoming of its second particle.
        let total: usize = (0..l.len()).map(|j| l.incoming(j).len()).sum();
        assert_eq!(total, l.num_pairs());
    }
}

#[test]
fn same_lists_at_one_and_two_threads() -> Result<(), rayon::ThreadPoolBuildError> {
    let cases = [
        (random_volume(5000, 16.0, 10), 1.3),
        (hex_sheet(60, 80, 0.05, 11), 2.5),
        (rotated(&hex_sheet(60, 80, 0.05, 12)), 2.5),
    ];
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let two = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    for (pts, radius) in &cases {
        for backend in FAST {
            let mut a = PairList::new();
            let mut b = PairList::new();
            one.install(|| search(backend, pts, *radius, &mut a));
            two.install(|| search(backend, pts, *radius, &mut b));
            assert!(a == b, "{backend:?}: 1 vs 2 threads differ");
            assert_eq!(a, oracle(pts, *radius));
        }
        let order_one = one.install(|| spatial_order(pts, *radius));
        let order_two = two.install(|| spatial_order(pts, *radius));
        assert_eq!(order_one, order_two);
    }
    Ok(())
}

#[test]
fn backends_agree_after_spatial_sort() {
    let pts = random_volume(3000, 14.0, 13);
    let order = spatial_order(&pts, 1.5);
    let sorted: Vec<Point3> = order.iter().map(|&i| pts[i as usize]).collect();
    assert_backends_agree(&sorted, 1.5, "spatially sorted volume");
    // Same pairs as before the sort, up to the relabelling.
    let before = oracle(&pts, 1.5);
    let after = oracle(&sorted, 1.5);
    assert_eq!(before.num_pairs(), after.num_pairs());
    let mut mapped: Vec<(u32, u32)> = after
        .iter_pairs()
        .map(|(a, b)| {
            let (i, j) = (order[a], order[b]);
            (i.min(j), i.max(j))
        })
        .collect();
    mapped.sort_unstable();
    let original: Vec<(u32, u32)> = before
        .iter_pairs()
        .map(|(i, j)| (i as u32, j as u32))
        .collect();
    assert_eq!(mapped, original);
}

#[test]
fn update_rebuilds_only_when_the_two_largest_moves_exceed_the_skin() {
    let pts = hex_sheet(10, 10, 0.0, 14);
    let mut list = NeighbourList::new(NeighbourBackend::CellList, 1.2, 0.4);
    assert_eq!(list.radius(), 1.2 + 0.4);
    assert!(list.pairs().is_empty());
    assert!(list.update(&pts), "first update builds");
    assert_eq!(list.rebuilds(), 1);
    assert!(!list.update(&pts), "no motion, no rebuild");
    let mut moved = pts.clone();
    moved[42].x += 0.39;
    assert!(
        !list.update(&moved),
        "one particle moving 0.39 < skin while the others rest keeps the list"
    );
    moved[7].y -= 0.005;
    assert!(!list.update(&moved), "0.39 + 0.005 < skin keeps the list");
    moved[7].y -= 0.01; // now 0.39 + 0.015 > 0.4
    assert!(list.needs_rebuild(&moved));
    assert!(
        list.update(&moved),
        "two moves adding up above the skin rebuild"
    );
    assert!(!list.needs_rebuild(&moved));
    assert_eq!(list.rebuilds(), 2);
    assert_eq!(list.reference_positions(), moved.as_slice());
    assert!(!list.update(&moved));
    moved.push(Point3::new(100.0, 0.0, 0.0));
    assert!(list.update(&moved), "particle count changed");
    moved[0] = Point3::new(Real::NAN, 0.0, 0.0);
    assert!(list.update(&moved), "a particle turning NaN rebuilds");
    assert!(!list.update(&moved), "a particle staying NaN does not");
    moved[0] = Point3::new(0.0, 0.0, 0.0);
    assert!(list.update(&moved), "back to finite rebuilds");
    assert_eq!(list.rebuilds(), 5);
    list.rebuild(&moved);
    assert_eq!(list.rebuilds(), 6);
    assert_eq!(list.pairs(), &oracle(&moved, list.radius()));
}

#[test]
fn skin_keeps_every_pair_within_cutoff() {
    let (cutoff, skin) = (1.5, 0.5);
    for backend in FAST {
        let mut rng = Rng::new(15);
        let mut pts = random_volume(1500, 10.0, 16);
        let mut list = NeighbourList::new(backend, cutoff, skin);
        let mut rebuilt = 0;
        for step in 0..60 {
            // Random moves of up to 0.45 skin/2 per step: several steps
            // accumulate past the bound and force rebuilds.
            for p in pts.iter_mut() {
                *p += vec_in_ball(&mut rng, 0.45 * 0.5 * skin);
            }
            if list.update(&pts) {
                rebuilt += 1;
            }
            let need = oracle(&pts, cutoff);
            let have = list.pairs();
            for (i, j) in need.iter_pairs() {
                assert!(
                    have.row(i).binary_search(&(j as u32)).is_ok(),
                    "{backend:?} step {step}: pair ({i}, {j}) within cutoff missing"
                );
            }
        }
        assert!(
            rebuilt > 5 && rebuilt < 60,
            "{backend:?}: {rebuilt} rebuilds"
        );
    }
}

#[test]
fn skin_guarantee_holds_at_the_boundary() {
    // A pair exactly at cutoff + skin at the build, each particle moving
    // exactly skin/2 toward the other: at the cutoff, and in the list.
    let (cutoff, skin) = (1.0, 0.5);
    let mut list = NeighbourList::new(NeighbourBackend::KdTree, cutoff, skin);
    let pts = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.5, 0.0, 0.0)];
    list.update(&pts);
    assert_eq!(list.pairs().num_pairs(), 1);
    let moved = [Point3::new(0.25, 0.0, 0.0), Point3::new(1.25, 0.0, 0.0)];
    list.update(&moved);
    assert_eq!(list.pairs().num_pairs(), 1);
    // One particle moving the whole skin, the other resting: also at the
    // cut-off, also in the list.
    let mut list = NeighbourList::new(NeighbourBackend::CellList, cutoff, skin);
    list.update(&pts);
    let moved = [Point3::new(0.5, 0.0, 0.0), Point3::new(1.5, 0.0, 0.0)];
    list.update(&moved);
    assert_eq!(list.pairs().num_pairs(), 1);
}

#[test]
fn bad_parameters_are_rejected() {
    assert!(NeighbourList::try_new(NeighbourBackend::CellList, -1.0, 0.1).is_err());
    assert!(NeighbourList::try_new(NeighbourBackend::CellList, 1.0, Real::NAN).is_err());
    assert!(NeighbourList::try_new(NeighbourBackend::CellList, Real::INFINITY, 0.0).is_err());
    let e = NeighbourList::try_new(NeighbourBackend::KdTree, 1.0, -0.5).unwrap_err();
    assert!(e.to_string().contains("skin"), "{e}");
    // Zero cutoff and skin are allowed: coincident particles only.
    let mut l = NeighbourList::new(NeighbourBackend::CellList, 0.0, 0.0);
    assert!(l.update(&[
        Point3::origin(),
        Point3::origin(),
        Point3::new(1.0, 0.0, 0.0)
    ]));
    assert_eq!(l.pairs().num_pairs(), 1);
    assert!(!l.update(&[
        Point3::origin(),
        Point3::origin(),
        Point3::new(1.0, 0.0, 0.0)
    ]));
    assert!(l.update(&[
        Point3::origin(),
        Point3::origin(),
        Point3::new(1.0, 1e-12, 0.0)
    ]));
}

#[test]
fn backend_default_and_accessors() {
    assert_eq!(NeighbourBackend::default(), NeighbourBackend::CellList);
    let l = NeighbourList::new(NeighbourBackend::default(), 1.0, 0.1);
    assert_eq!((l.cutoff(), l.skin(), l.rebuilds()), (1.0, 0.1, 0));
    assert_eq!(l.backend(), NeighbourBackend::CellList);
}

#[test]
fn cell_list_rebuild_reuses_its_buffers() {
    let pts = random_volume(3000, 14.0, 17);
    let mut l = PairList::new();
    search(NeighbourBackend::CellList, &pts, 1.5, &mut l);
    let ptrs = |l: &PairList| {
        (
            l.neighbours().as_ptr() as usize,
            l.offsets().as_ptr() as usize,
            l.scratch.grid.buffer_ptrs(),
        )
    };
    let before = ptrs(&l);
    search(NeighbourBackend::CellList, &pts, 1.5, &mut l);
    assert_eq!(ptrs(&l), before);
}
