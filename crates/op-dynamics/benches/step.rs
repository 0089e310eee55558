//! One world step at 10k and 100k particles: the full oriented interaction
//! and spacing-only, on a slightly noisy hexagonal sheet (velocity Verlet,
//! cached neighbour lists). At 10k also what the optional mechanisms cost
//! on top of each: explicit bonds (`*_bonded`, breaking on) and heat
//! (`*_heated`: a weakening material at non-uniform temperatures, with
//! conduction and cooling every step). Also prints the bytes per particle
//! of the store.
//!
//! Run: `cargo bench -p op-dynamics --bench step`

use criterion::{BenchmarkId, Criterion, Throughput};
use op_dynamics::bonds::BondParams;
use op_dynamics::interactions::{CohesionParams, Spacing, WeightParams};
use op_dynamics::{
    HeatParams, HeatResponse, Material, ParticleDesc, Particles, Point3, Quat, Real, Vec3, World,
    WorldParams,
};

fn sheet(n: usize) -> Particles {
    let side = (n as Real).sqrt().ceil() as usize;
    let mut p = Particles::new();
    let mut seed = 0x1234_5678_u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as Real / (1u64 << 53) as Real) - 0.5
    };
    for k in 0..n {
        let (i, j) = (k % side, k / side);
        let x = (i as Real + 0.5 * (j % 2) as Real) + 0.05 * rnd();
        let y = j as Real * 0.866 + 0.05 * rnd();
        let mut d = ParticleDesc::at(Point3::new(x, y, 0.05 * rnd()));
        d.orientation = Quat::from_scaled_axis(Vec3::new(0.05 * rnd(), 0.05 * rnd(), 0.0));
        d.temperature = 5.0 + 5.0 * rnd();
        p.push(d).unwrap();
    }
    p
}

/// The variants of a material measured at 10k: bonded (breaking beyond
/// 1.5) and heated (weakening, with the world's conduction and cooling).
fn variants(name: &str, m: Material) -> Vec<(String, Material, WorldParams)> {
    vec![
        (
            format!("{name}_bonded"),
            Material {
                bonds: Some(BondParams {
                    radius: 1.2,
                    break_length: Some(1.5),
                }),
                ..m
            },
            WorldParams::default(),
        ),
        (
            format!("{name}_heated"),
            Material {
                heat: Some(HeatResponse {
                    melting: 10.0,
                    residual: 0.2,
                    cold_drag: 0.0,
                }),
                ..m
            },
            WorldParams {
                heat: Some(HeatParams::default()),
                ..WorldParams::default()
            },
        ),
    ]
}

fn materials() -> [(&'static str, Material); 2] {
    let cohesion = Some(Spacing::Cohesion(CohesionParams::default()));
    [
        (
            "spacing_only",
            Material {
                spacing: cohesion,
                ..Material::empty()
            },
        ),
        (
            "full_oriented",
            Material {
                spacing: cohesion,
                weight: WeightParams {
                    cutoff: 2.0,
                    ..Default::default()
                },
                coplanarity: 1.0,
                conormality: 0.5,
                cocircularity: 0.5,
                form: 1.0,
                ..Material::empty()
            },
        ),
    ]
}

fn bench_step(c: &mut Criterion) {
    eprintln!(
        "particle store: {} bytes per particle",
        Particles::BYTES_PER_PARTICLE
    );
    let mut g = c.benchmark_group("world_step");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(8));
    for n in [10_000usize, 100_000] {
        let mut cases: Vec<(String, Material, WorldParams)> = Vec::new();
        for (name, m) in materials() {
            cases.push((name.to_string(), m, WorldParams::default()));
            if n == 10_000 {
                cases.extend(variants(name, m));
            }
        }
        for (name, m, params) in cases {
            let mut w = World::new(sheet(n), &[m], params).unwrap();
            w.step().unwrap();
            let pairs = w.neighbour_pairs().map_or(0, |l| l.num_pairs());
            eprintln!(
                "{name} n={n}: {pairs} listed pairs ({:.1} per particle)",
                pairs as Real / n as Real
            );
            g.throughput(Throughput::Elements(n as u64));
            g.bench_with_input(BenchmarkId::new(&name, n), &n, |b, _| {
                b.iter(|| w.step().unwrap().dt)
            });
        }
    }
    g.finish();
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench_step(&mut c);
    c.final_summary();
}
