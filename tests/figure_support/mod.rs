//! Helpers shared by the figure tests (`tests/figures.rs`,
//! `tests/figures_surface.rs`): load, build and run a scene the way `opsim
//! run` does, and the measures the figure checks use.
#![allow(dead_code)]

use std::path::Path;

use oriented_particles::op_dynamics::{Mat3, Point3, Real, Vec3};
use oriented_particles::op_scene::{self, load_scene, BuiltScene, RunOptions, Scene, Summary};

/// Loads `scenes/<name>.ron`.
pub fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.ron"));
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Builds `scene` without running it (points files relative to `scenes/`).
pub fn build(scene: &Scene) -> BuiltScene {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    scene.build(Some(&base), None).expect("builds")
}

/// Builds and runs `scene` through the runner into a fresh directory
/// (`tag` tells runs of the same scene apart); returns the built scene in
/// its final state and the summary.
pub fn run(scene: &Scene, tag: &str) -> (BuiltScene, Summary) {
    let mut built = build(scene);
    let out = std::env::temp_dir().join(format!(
        "opsim-fig-{}-{tag}-{}",
        scene.name,
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&out);
    let opts = RunOptions {
        out_dir: out.clone(),
        frames: None,
        formats: vec![op_scene::export::FrameFormat::Obj],
    };
    let summary = op_scene::run(&mut built, &opts, &mut |_, _| {}).expect("runs");
    assert!(!summary.diverged);
    let _ = std::fs::remove_dir_all(&out);
    (built, summary)
}

/// Current positions of the particles with the given ids (all alive).
pub fn positions(built: &BuiltScene, ids: &[u32]) -> Vec<Point3> {
    let p = built.world.particles();
    ids.iter()
        .map(|&id| p.positions()[p.slot_of(id).expect("alive")])
        .collect()
}

/// Best-fit plane of `points`: unit normal and RMS distance to the plane.
pub fn plane_fit(points: &[Point3]) -> (Vec3, Real) {
    let n = points.len() as Real;
    let c = points.iter().map(|p| p.coords).sum::<Vec3>() / n;
    let cov = points
        .iter()
        .map(|p| (p.coords - c) * (p.coords - c).transpose())
        .fold(Mat3::zeros(), |a, b| a + b);
    let eig = cov.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let normal = eig.eigenvectors.column(k).into_owned();
    let rms = (points
        .iter()
        .map(|p| (p.coords - c).dot(&normal).powi(2))
        .sum::<Real>()
        / n)
        .sqrt();
    (normal, rms)
}

/// Connected components of the graph joining points closer than `radius`
/// (brute force: the figures are small): a component label per point.
pub fn labels(points: &[Point3], radius: Real) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..points.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            if (points[i] - points[j]).norm() < radius {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    (0..points.len()).map(|i| root(&mut parent, i)).collect()
}

/// Sizes, largest first, of the connected components of the graph joining
/// points closer than `radius` ([`labels`]).
pub fn components(points: &[Point3], radius: Real) -> Vec<usize> {
    let mut sizes = vec![0; points.len()];
    for l in labels(points, radius) {
        sizes[l] += 1;
    }
    let mut sizes: Vec<usize> = sizes.into_iter().filter(|&s| s > 0).collect();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

/// The median (upper middle) of `v`.
pub fn median(mut v: Vec<Real>) -> Real {
    v.sort_by(Real::total_cmp);
    v[v.len() / 2]
}

/// Distance from each point to its nearest other point.
pub fn nearest_distances(points: &[Point3]) -> Vec<Real> {
    (0..points.len())
        .map(|i| {
            (0..points.len())
                .filter(|&j| j != i)
                .map(|j| (points[i] - points[j]).norm())
                .fold(Real::INFINITY, Real::min)
        })
        .collect()
}
