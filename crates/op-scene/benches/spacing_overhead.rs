//! Pay for what you use (issue: scene/CLI): a spacing-only scene built
//! through op-scene and stepped by the generic `World` against the same
//! particles stepped by a hand-written spacing-only loop (velocity Verlet,
//! serial scatter over the same half neighbour list, the same potential).
//! Both run on one thread so the comparison measures the framework's
//! overhead, not parallel speed-up.
//!
//! Run: `cargo bench -p op-scene --bench spacing_overhead`

use criterion::{BenchmarkId, Criterion};
use op_dynamics::interactions::SpacingKernel;
use op_dynamics::neighbours::{NeighbourBackend, NeighbourList};
use op_dynamics::{Point3, Real, Vec3};

const SCENE: &str = r#"(
    name: "spacing_only",
    world: (integrator: VelocityVerlet, dt: 2e-3, duration: 1),
    materials: { "lj": (spacing: LennardJones((cutoff: 2.0))) },
    objects: [(name: "sheet", material: "lj", generator: HexSheet(nx: NX, ny: NY, spacing: 1, noise: 0.05, seed: 3))],
)"#;

/// The dedicated kernel: positions, velocities, forces and a half list.
struct HandWritten {
    p: Vec<Point3>,
    v: Vec<Vec3>,
    f: Vec<Vec3>,
    inv_m: Real,
    dt: Real,
    list: NeighbourList,
    potential: SpacingKernel,
}

impl HandWritten {
    fn forces(&mut self) {
        self.list.update(&self.p);
        let rc2 = self.list.cutoff() * self.list.cutoff();
        self.f.iter_mut().for_each(|f| *f = Vec3::zeros());
        let pairs = self.list.pairs();
        for i in 0..self.p.len() {
            let pi = self.p[i];
            let mut fi = Vec3::zeros();
            for &j in pairs.row(i) {
                let j = j as usize;
                let r = self.p[j] - pi;
                let d2 = r.norm_squared();
                if d2 < rc2 {
                    let d = d2.sqrt();
                    let (_, du) = self.potential.eval(d);
                    let fj = -(du / d) * r;
                    fi -= fj;
                    self.f[j] += fj;
                }
            }
            self.f[i] += fi;
        }
    }

    fn step(&mut self) {
        let h = 0.5 * self.dt * self.inv_m;
        for i in 0..self.p.len() {
            self.v[i] += h * self.f[i];
            self.p[i] += self.dt * self.v[i];
        }
        self.forces();
        for i in 0..self.p.len() {
            self.v[i] += h * self.f[i];
        }
    }
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("spacing_only_step");
    g.sample_size(20);
    g.measurement_time(std::time::Duration::from_secs(6));
    for (nx, ny) in [(100usize, 100usize), (320, 320)] {
        let n = nx * ny;
        let text = SCENE
            .replace("NX", &nx.to_string())
            .replace("NY", &ny.to_string());
        let scene = op_scene::parse_scene(&text, op_scene::Format::Ron, "<bench>").unwrap();
        let mut built = scene.build(None, None).unwrap();
        let world = built.world_mut();
        eprintln!("n = {n}: enabled {:?}", world.enabled());
        pool.install(|| world.step().map(|_| ()).unwrap());
        let list = world.neighbours().unwrap();
        let p = world.particles();
        let mut hand = HandWritten {
            p: p.positions().to_vec(),
            v: p.velocities().to_vec(),
            f: vec![Vec3::zeros(); n],
            inv_m: 1.0 / p.masses()[0],
            dt: world.params().dt,
            list: NeighbourList::new(NeighbourBackend::CellList, list.cutoff(), list.skin()),
            potential: world.materials()[0].spacing().unwrap().clone(),
        };
        hand.forces();
        g.bench_with_input(BenchmarkId::new("scene_world", n), &n, |b, _| {
            b.iter(|| pool.install(|| world.step().map(|r| r.dt).unwrap()))
        });
        g.bench_with_input(BenchmarkId::new("hand_written", n), &n, |b, _| {
            b.iter(|| pool.install(|| hand.step()))
        });
    }
    g.finish();
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c);
    c.final_summary();
}
