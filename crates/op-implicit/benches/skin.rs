//! Field evaluation and polygonization of skins of 1k and 10k particles:
//! a hexagonal sheet of oriented particles, each carrying a
//! square skeleton in the sheet plane (the ribbon/slab skin of seed 002
//! fig. 6), kernel radius 0.8 r0, polygonized at 0.25 r0.
//!
//! ```text
//! cargo bench -p op-implicit --bench skin
//! ```
//!
//! Measured per sheet size: `repose` (pose every primitive from the
//! particle frames and rebuild the pruning grid), `field` (value and
//! gradient at 10k points spread over the skin's box, pruned),
//! `polygonize` (sample the region at 0.25 r0 and run marching cubes).

use criterion::{BenchmarkId, Criterion};
use op_dynamics::{Material, ParticleDesc, Particles, Point3, Real, Vec3, World, WorldParams};
use op_implicit::{polygonize, PolygonizeParams, Primitive, Skin};

/// A flat hexagonal sheet of about `n` particles one unit apart, with a
/// little out-of-plane waviness so the skin is not trivially flat.
fn sheet(n: usize) -> World {
    let side = (n as Real).sqrt().round() as usize;
    let mut p = Particles::new();
    for j in 0..side {
        for i in 0..side {
            let x = i as Real + 0.5 * (j % 2) as Real;
            let y = j as Real * 0.75_f64.sqrt();
            let z = 0.2 * (0.3 * x).sin() * (0.2 * y).cos();
            p.push(ParticleDesc::at(Point3::new(x, y, z))).unwrap();
        }
    }
    World::new(p, &[Material::empty()], WorldParams::default()).unwrap()
}

fn skin_of(world: &World) -> Skin {
    let prim = Primitive::square(Vec3::z(), 0.5, 0.8);
    let ids = 0..world.particles().len() as u32;
    Skin::new(world, ids.map(|id| (id, prim)).collect()).unwrap()
}

/// 10k points on a regular lattice over the skin's support box.
fn probes(skin: &Skin) -> Vec<Point3> {
    let (lo, hi) = skin.field().support_box().unwrap();
    let k = 22; // 22^3 ≈ 10k
    let mut out = Vec::with_capacity(k * k * k);
    for a in 0..k {
        for b in 0..k {
            for c in 0..k {
                let t = Vec3::new(a as Real, b as Real, c as Real) / (k - 1) as Real;
                out.push(lo + (hi - lo).component_mul(&t));
            }
        }
    }
    out
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("skin");
    group.sample_size(10);
    for n in [1_000usize, 10_000] {
        let world = sheet(n);
        let mut skin = skin_of(&world);
        let points = probes(&skin);
        let count = world.particles().len();
        group.bench_with_input(BenchmarkId::new("repose", count), &world, |b, w| {
            b.iter(|| skin.repose(w).unwrap())
        });
        group.bench_with_input(
            BenchmarkId::new("field_10k_points", count),
            &points,
            |b, p| b.iter(|| skin.field().values_and_gradients(p)),
        );
        let params = PolygonizeParams::with_cell_size(0.25);
        let mesh = polygonize(skin.field(), &params).unwrap();
        println!(
            "skin of {count} particles: {} vertices, {} triangles at cell 0.25",
            mesh.positions().len(),
            mesh.triangles().len()
        );
        group.bench_with_input(BenchmarkId::new("polygonize", count), &params, |b, p| {
            b.iter(|| polygonize(skin.field(), p).unwrap())
        });
    }
    group.finish();
}

// A plain `main` instead of `criterion_group!`/`criterion_main!`, whose
// generated public function would trip `missing_docs`.
fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c);
    c.final_summary();
}
