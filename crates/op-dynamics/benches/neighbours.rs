//! Building the half neighbour list: sorted cell list against kiddo's k-d
//! tree, at 10k and 100k particles, radius 2.5 x spacing, on
//!
//! - `sheet`: a hexagonal sheet lying flat in the z = 0 plane (kiddo's
//!   worst case: its splits cycle x, y, z),
//! - `rotated`: the same sheet rotated about a generic axis,
//! - `volume`: a jittered cubic lattice,
//!
//! each in spatial (Morton) order and in random order. Also the cost of the
//! skin check of `NeighbourList::update` when nothing needs rebuilding, and
//! of the cluster rows of the cluster kernel (`ClusterPairs::build`): 32k
//! particles placed uniformly at random at the density of the LJ melt
//! (0.8442), radius 2.8 (cut-off 2.5 plus skin 0.3), in column order
//! (`cluster_order`, as the world keeps them) and in random order.
//!
//! Run: `cargo bench -p op-dynamics --bench neighbours` (about 2 minutes;
//! `-- cluster_rows` for the cluster rows only).
//! Medians: `target/criterion/<group>/<id>/new/estimates.json`.

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, SamplingMode};
use op_dynamics::math::{Point3, Quat, Real, Vec3};
use op_dynamics::neighbours::{
    cluster_order, search, spatial_order, ClusterPairs, NeighbourBackend, NeighbourList, PairList,
    CLUSTER,
};
use op_test_support::Rng;

const RADIUS: Real = 2.5;

/// About `n` particles on a hexagonal sheet in the z = 0 plane, spacing 1.
fn sheet(n: usize, rng: &mut Rng) -> Vec<Point3> {
    let cols = (n as Real).sqrt().ceil() as usize;
    let h = (0.75 as Real).sqrt();
    (0..n)
        .map(|m| {
            let (r, c) = (m / cols, m % cols);
            let x = c as Real + 0.5 * (r % 2) as Real + rng.uniform(-0.05, 0.05);
            let y = r as Real * h + rng.uniform(-0.05, 0.05);
            Point3::new(x, y, 0.0)
        })
        .collect()
}

/// `n` particles on a jittered cubic lattice, spacing 1.
fn volume(n: usize, rng: &mut Rng) -> Vec<Point3> {
    let side = (n as Real).cbrt().ceil() as usize;
    (0..n)
        .map(|m| {
            let (x, y, z) = (m % side, (m / side) % side, m / (side * side));
            Point3::new(
                x as Real + rng.uniform(-0.1, 0.1),
                y as Real + rng.uniform(-0.1, 0.1),
                z as Real + rng.uniform(-0.1, 0.1),
            )
        })
        .collect()
}

fn shuffled(pts: &[Point3], rng: &mut Rng) -> Vec<Point3> {
    let mut v = pts.to_vec();
    for i in (1..v.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
    v
}

/// `pts` in the order `order` (a permutation of their indices).
fn permuted(pts: &[Point3], order: &[u32]) -> Vec<Point3> {
    order.iter().map(|&i| pts[i as usize]).collect()
}

fn morton(pts: &[Point3]) -> Vec<Point3> {
    permuted(pts, &spatial_order(pts, RADIUS))
}

fn build_lists(c: &mut Criterion) {
    let rot = Quat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8));
    for n in [10_000usize, 100_000] {
        let mut rng = Rng::new(n as u64);
        let flat = sheet(n, &mut rng);
        let rotated: Vec<Point3> = flat.iter().map(|p| rot * p).collect();
        let vol = volume(n, &mut rng);
        let mut group = c.benchmark_group(format!("build_{}k", n / 1000));
        group
            .sample_size(10)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_millis(if n > 10_000 { 1500 } else { 600 }));
        for (shape, pts) in [("sheet", &flat), ("rotated", &rotated), ("volume", &vol)] {
            let orders = [("morton", morton(pts)), ("random", shuffled(pts, &mut rng))];
            for (order, pts) in &orders {
                for (name, backend) in [
                    ("cell", NeighbourBackend::CellList),
                    ("kd", NeighbourBackend::KdTree),
                ] {
                    let mut out = PairList::new();
                    let id = BenchmarkId::new(name, format!("{shape}/{order}"));
                    group.bench_with_input(id, pts, |b, pts| {
                        b.iter(|| search(backend, pts, RADIUS, &mut out));
                    });
                }
            }
        }
        group.finish();
    }
}

fn skin_check(c: &mut Criterion) {
    let mut rng = Rng::new(7);
    let pts = morton(&volume(100_000, &mut rng));
    let mut list = NeighbourList::new(NeighbourBackend::CellList, 2.0, 0.5);
    list.update(&pts);
    let mut group = c.benchmark_group("update_no_rebuild");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(500));
    group.bench_function("100k", |b| b.iter(|| assert!(!list.update(&pts))));
    group.finish();
}

fn cluster_rows(c: &mut Criterion) {
    let n = 32_000;
    let side = (n as Real / 0.8442).cbrt();
    let mut rng = Rng::new(11);
    let melt: Vec<Point3> = (0..n)
        .map(|_| {
            Point3::new(
                rng.uniform(0.0, side),
                rng.uniform(0.0, side),
                rng.uniform(0.0, side),
            )
        })
        .collect();
    let columns = permuted(&melt, &cluster_order(&melt, CLUSTER));
    let mut group = c.benchmark_group("cluster_rows");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500));
    for (order, pts) in [("columns", &columns), ("random", &melt)] {
        let mut rows = ClusterPairs::new();
        group.bench_with_input(BenchmarkId::new("32k", order), pts, |b, pts| {
            b.iter(|| rows.build(pts, 2.8));
        });
    }
    group.finish();
}

// A plain `main` instead of `criterion_group!`/`criterion_main!`, whose
// generated public function would trip `missing_docs`.
fn main() {
    let mut c = Criterion::default().configure_from_args();
    build_lists(&mut c);
    skin_check(&mut c);
    cluster_rows(&mut c);
    c.final_summary();
}
