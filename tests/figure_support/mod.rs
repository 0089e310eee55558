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
        formats: vec![op_scene::export::FrameFormat::OBJ],
        ..Default::default()
    };
    let summary = op_scene::run(&mut built, &opts, &mut |_, _| {}).expect("runs");
    assert!(!summary.diverged);
    let _ = std::fs::remove_dir_all(&out);
    (built, summary)
}

/// Current positions of the particles with the given ids (all alive).
pub fn positions(built: &BuiltScene, ids: &[u32]) -> Vec<Point3> {
    let p = built.world().particles();
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
    let mut sets = op_modeling::disjoint_sets::DisjointSets::new(points.len());
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            if (points[i] - points[j]).norm() < radius {
                sets.union(i, j);
            }
        }
    }
    (0..points.len()).map(|i| sets.root(i)).collect()
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

/// Topology of an object's exported surface (`<object>_surface`, the mesh
/// `opsim run` writes, [`op_scene::export::geometry::surface_geometry`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SurfaceTopology {
    /// Euler characteristic `V - E + F` (a disc 1, a sphere 2, two discs 2).
    pub chi: i64,
    /// Connected components of the triangles (edge-connected).
    pub components: usize,
    /// Boundary loops (components of the edges in one triangle).
    pub loops: usize,
    /// Edges held by exactly one triangle.
    pub boundary_edges: usize,
    /// Every edge in at most two triangles, every vertex a single fan.
    pub manifold: bool,
    /// Number of triangles.
    pub triangles: usize,
}

impl SurfaceTopology {
    /// A topological disc: one component, one boundary loop, chi 1.
    pub fn is_disc(&self) -> bool {
        self.manifold && self.components == 1 && self.loops == 1 && self.chi == 1
    }

    /// `n` topological discs.
    pub fn is_discs(&self, n: usize) -> bool {
        self.manifold && self.components == n && self.loops == n && self.chi == n as i64
    }

    /// A closed surface of genus 0 (a sphere): one component, no boundary.
    pub fn is_sphere(&self) -> bool {
        self.manifold && self.components == 1 && self.loops == 0 && self.chi == 2
    }
}

/// The exported surface of `built`'s object `name` in its current state,
/// and its triangles as indices into the mesh vertices.
pub fn surface_mesh(built: &BuiltScene, name: &str) -> op_scene::export::FrameMesh {
    let object = built
        .objects()
        .iter()
        .find(|o| o.name == name)
        .unwrap_or_else(|| panic!("no object {name}"));
    op_scene::export::geometry::surface_geometry(
        built.world(),
        object,
        built.outputs(),
        built.sheet_gap(),
    )
}

/// The topology of `built`'s object `name`'s exported surface now.
pub fn surface_topology(built: &BuiltScene, name: &str) -> SurfaceTopology {
    use oriented_particles::op_modeling::triangulation::Triangulation;
    let mesh = surface_mesh(built, name);
    let t = Triangulation {
        triangles: mesh.triangles.clone(),
    };
    let labels = triangle_components(&mesh.triangles);
    SurfaceTopology {
        chi: t.euler_characteristic(),
        components: labels,
        loops: t.boundary_loops(),
        boundary_edges: t.edges().values().filter(|&&c| c == 1).count(),
        manifold: t.is_manifold(),
        triangles: t.len(),
    }
}

/// Number of pieces of `triangles` (triangles sharing a vertex are one).
fn triangle_components(triangles: &[[u32; 3]]) -> usize {
    let piece = oriented_particles::op_modeling::triangulation::vertex_components(triangles);
    piece
        .iter()
        .enumerate()
        .filter(|(i, p)| **p == Some(*i as u32))
        .count()
}

/// Builds `scene` and advances it frame by frame as `opsim run` does (the
/// settle phase, then frame `k` at `k / frame_rate` after it, to the
/// scene's duration, measuring each frame), calling `f(frame, &built)` at every frame, frame 0
/// included; returns the final state.
pub fn each_frame(scene: &Scene, mut f: impl FnMut(usize, &BuiltScene)) -> BuiltScene {
    let mut built = build(scene);
    built.settle().expect("settles");
    let t0 = built.world().time();
    let frames = (built.duration() * built.frame_rate()).round() as usize;
    for k in 0..=frames {
        let t = if k == 0 {
            t0
        } else {
            t0 + k as Real / built.frame_rate()
        };
        built.advance_to(t).unwrap_or_else(|e| panic!("{e}"));
        // The runner measures every frame: a force evaluation, which may
        // refresh the neighbour list and so the bits of what follows.
        let _ = built.world_mut().diagnostics();
        f(k, &built);
    }
    built
}

/// The `// claim: ` line of `scenes/<name>.ron`.
pub fn claim(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.ron"));
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .find_map(|l| l.strip_prefix("// claim: ").map(str::to_string))
        .unwrap_or_else(|| panic!("{name} states no claim"))
}
