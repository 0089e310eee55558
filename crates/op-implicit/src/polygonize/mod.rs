//! Polygonization of a field's iso-surface: narrow-band marching cubes
//! over blocks, in parallel (seed 002 §6: "the object surface is
//! an isosurface of the sum of all emitted potentials").
//!
//! Stages: (1) the region is the union of the primitives' support boxes
//! ([`ScalarField::support_box`]), padded by one cell so the surface is
//! closed, on a grid of cubic cells of the requested size in world units,
//! cut into blocks of 16 x 8 x 8 cells; (2) `blocks`: for a [`Field`], only the
//! blocks its primitives' supports reach and whose field bounds straddle
//! the iso value are sampled, by splatting the primitives onto their
//! nodes (the narrow band); any other [`ScalarField`] is sampled at every
//! node; (3) marching cubes (`tables`, Lorensen & Cline 1987) runs per
//! block, in parallel, each block's crossing points keyed by their global
//! grid edge; (4) blocks are merged in order, points on edges shared by
//! blocks welded by that key, so the mesh is the one a single pass over
//! the whole grid gives, closed and the same for any number of threads;
//! (5) vertex normals are the normalized analytic gradient,
//! `-grad f / |grad f|` (outward).

pub(crate) mod blocks;
pub mod smoothing;
mod tables;

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

use crate::contact::ClippedField;
use crate::error::PolygonizeError;
use crate::field::{Field, ScalarField};
use crate::kernel::ISO;
use blocks::{BlockLists, Grid, Sampled};
use parry3d_f64::math::Pose;
use parry3d_f64::shape::Shape;

/// Parameters of [`polygonize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolygonizeParams {
    /// Edge length of the cubic sampling cells, in world units, > 0. The
    /// vertex error falls as its square (measured in the tests).
    pub cell_size: Real,
    /// Largest number of grid nodes allowed along the region's longest
    /// axis. Default: [`MAX_NODES_PER_AXIS`].
    pub max_nodes_per_axis: usize,
    /// The iso value: the surface is `{p : field(p) = iso}`, the inside
    /// `field > iso`; finite and > 0. Default: [`ISO`] (an isolated point
    /// primitive's skin at half its support radius).
    pub iso: Real,
}

/// The default [`PolygonizeParams::max_nodes_per_axis`]: a skinned cloth
/// of 316 x 316 particles at a cell of 0.25 needs about 1,280. A skin's narrow
/// band costs as its area in cells (the blocks its primitives reach), but
/// a [`ScalarField`] without a bounding field is sampled at every node of
/// the region, as its volume.
pub const MAX_NODES_PER_AXIS: usize = 2048;

impl PolygonizeParams {
    /// Cells of `cell_size` world units, other fields at their defaults.
    pub fn with_cell_size(cell_size: Real) -> Self {
        PolygonizeParams {
            cell_size,
            max_nodes_per_axis: MAX_NODES_PER_AXIS,
            iso: ISO,
        }
    }
}

/// Whether triangles (vertex indices) form a closed, edge-manifold,
/// consistently oriented surface: every directed edge occurs exactly once
/// and its reverse exactly once, and no triangle repeats a vertex. Any
/// mesh's check, also one this crate did not make ([`Mesh`] uses it).
pub fn is_closed_oriented_manifold(triangles: &[[u32; 3]]) -> bool {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return false;
        }
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    directed
        .iter()
        .all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
}

/// A triangle mesh: vertex positions and unit normals (same length), and
/// counter-clockwise triangles seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    positions: Vec<Point3>,
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Vertex positions (world).
    pub fn positions(&self) -> &[Point3] {
        &self.positions
    }

    /// Unit outward vertex normals, one per position.
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The positions, normals and triangles, moved out (no copy).
    pub fn into_parts(self) -> (Vec<Point3>, Vec<Vec3>, Vec<[u32; 3]>) {
        (self.positions, self.normals, self.triangles)
    }

    /// Whether the mesh is empty (no triangles).
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The enclosed volume, signed: positive for a closed mesh whose
    /// triangles face outward.
    pub fn signed_volume(&self) -> Real {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize].coords);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum()
    }

    /// Whether the mesh is closed, manifold along edges and consistently
    /// oriented: every directed edge occurs exactly once and its reverse
    /// exactly once (so every edge bounds exactly two triangles, which
    /// traverse it in opposite directions), and no triangle repeats a
    /// vertex.
    pub fn is_closed_oriented_manifold(&self) -> bool {
        is_closed_oriented_manifold(&self.triangles)
    }
}

/// What a polygonization sampled, for measuring the narrow band.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PolygonizeStats {
    /// Nodes of the whole padded grid.
    pub grid_nodes: usize,
    /// Blocks of the grid.
    pub blocks: usize,
    /// Blocks sampled (the rest cannot hold a crossing).
    pub sampled_blocks: usize,
    /// Nodes of the sampled blocks (nodes on block faces count once per
    /// block).
    pub sampled_nodes: usize,
    /// Primitive (or, without a band, whole-field) evaluations.
    pub field_evaluations: usize,
}

/// Polygonizes the iso-surface `field = params.iso` (the skin) at the
/// resolution of `params` (module doc for the stages), sampling only the
/// narrow band of blocks the primitives' supports reach. An empty field
/// gives an empty mesh.
pub fn polygonize(field: &Field, params: &PolygonizeParams) -> Result<Mesh, PolygonizeError> {
    polygonize_with_stats(field, params).map(|(mesh, _)| mesh)
}

/// As [`polygonize`], with what was sampled.
pub fn polygonize_with_stats(
    field: &Field,
    params: &PolygonizeParams,
) -> Result<(Mesh, PolygonizeStats), PolygonizeError> {
    let Some(grid) = grid(field, params, None)? else {
        return Ok(Default::default());
    };
    let lists = BlockLists::new(field, &grid);
    let iso = params.iso;
    let arch = pulp::Arch::new();
    Ok(extract(field, &grid, iso, |b| {
        blocks::sample_band(field, &grid, &lists, b, iso, arch)
    }))
}

/// As [`polygonize`], for any [`ScalarField`]: for instance the deformed
/// skin of an object in contact, [`crate::DeformedField`]. Its nodes are
/// sampled one by one ([`ScalarField::value`]) in the blocks where its
/// [`ScalarField::bounding_field`] can reach the iso value, every block
/// of the region when it has none.
pub fn polygonize_field<F: ScalarField + ?Sized>(
    field: &F,
    params: &PolygonizeParams,
) -> Result<Mesh, PolygonizeError> {
    polygonize_region(field, params, None)
}

/// As [`polygonize_field`], over the part of the skin's region inside the
/// box `clip = (lo, hi)` only (the whole region when `None`). The mesh is
/// open where the box cuts the skin; its vertices sample the skin there
/// (contact sampling near a collider). A box that misses the skin gives an
/// empty mesh.
pub fn polygonize_region<F: ScalarField + ?Sized>(
    field: &F,
    params: &PolygonizeParams,
    clip: Option<(Point3, Point3)>,
) -> Result<Mesh, PolygonizeError> {
    let Some(grid) = grid(field, params, clip)? else {
        return Ok(Mesh::default());
    };
    let iso = params.iso;
    let (mesh, _) = match field.bounding_field() {
        // Only the band of the bounding field's primitives can cross.
        Some(bound) => {
            let lists = BlockLists::new(bound, &grid);
            extract(field, &grid, iso, |b| {
                if blocks::below_everywhere(bound, &grid, &grid.block(b), lists.of(b), iso) {
                    Sampled::Skipped
                } else {
                    blocks::sample_dense(field, &grid, b)
                }
            })
        }
        None => extract(field, &grid, iso, |b| blocks::sample_dense(field, &grid, b)),
    };
    Ok(mesh)
}

/// The skin of `own` deformed by contact with `other` (Gascuel's
/// deformation without bulge, [`crate::ContactPair::deformed_a`]), as
/// [`polygonize_field`] of that deformed field gives it but with the nodes
/// sampled by splatting: both skins' primitives are splatted onto the
/// blocks where `own` can reach the iso value, and `other`'s excess over
/// the iso value, where positive, is taken off `own`'s field there
/// (blocks where `other` is below the iso value everywhere are left as
/// they are). The normals are the deformed field's gradients. Measured on
/// two skinned solid balls of 10,185 particles each in contact
/// (`reports/scenes.md`, 3 frames, 1 thread): export took 11.7 s with
/// every node evaluated one by one, 1.6 s with this.
pub fn polygonize_deformed(
    own: &Field,
    other: &Field,
    params: &PolygonizeParams,
) -> Result<Mesh, PolygonizeError> {
    let deformed = crate::ContactPair::new(own, other).deformed_a();
    splatted_mesh(
        &deformed,
        (own, Some(other)),
        None::<&ClippedField<Field>>,
        params,
    )
}

/// The skin of `own`, deformed by contact with `other` when given (as
/// [`polygonize_deformed`]), clipped by rigid `colliders` (shape, pose)
/// with slope `slope` ([`ClippedField`]): as [`polygonize_field`] of the
/// clipped field gives it, but with the nodes splatted. The clip is
/// evaluated at the nodes of the blocks where it can bite: where its
/// lower bound over the block (the signed distance moves by at most the
/// distance moved) is below the largest node value. Measured on a
/// skinned cloth of 120 x 120 particles dropped on a ball (the scene
/// report's cloth, 3 frames, 1 thread): export took 4.57 s with every node
/// evaluated one by one, 2.50 s with this, the same bytes.
pub fn polygonize_clipped(
    own: &Field,
    other: Option<&Field>,
    colliders: Vec<(&dyn Shape, Pose)>,
    slope: Real,
    params: &PolygonizeParams,
) -> Result<Mesh, PolygonizeError> {
    match other {
        Some(other) => {
            let deformed = crate::ContactPair::new(own, other).deformed_a();
            let clipped = ClippedField::new(&deformed, colliders, slope);
            splatted_mesh(&clipped, (own, Some(other)), Some(&clipped), params)
        }
        None => {
            let clipped = ClippedField::new(own, colliders, slope);
            splatted_mesh(&clipped, (own, None), Some(&clipped), params)
        }
    }
}

/// The mesh of `field`, whose node values are `own`'s splatted, less
/// `other`'s excess over the iso value where positive (Gascuel's
/// deformation without bulge, `crate::implicit_contact::deform`), then
/// lowered to `clip`'s value where it is lower: blocks where `own` is
/// below the iso value everywhere are skipped (deforming and clipping only
/// lower the field), and `other` is splatted only where it can exceed the
/// iso value.
fn splatted_mesh<F: ScalarField + ?Sized, C: ScalarField + ?Sized>(
    field: &F,
    (own, other): (&Field, Option<&Field>),
    clip: Option<&ClippedField<'_, C>>,
    params: &PolygonizeParams,
) -> Result<Mesh, PolygonizeError> {
    let Some(grid) = grid(field, params, None)? else {
        return Ok(Mesh::default());
    };
    let lists = BlockLists::new(own, &grid);
    let others = other.map(|o| (o, BlockLists::new(o, &grid)));
    let iso = params.iso;
    let arch = pulp::Arch::new();
    let (mesh, _) = extract(field, &grid, iso, |b| {
        let Some((mut values, mut evaluations)) =
            blocks::sample_unless_below(own, &grid, &lists, b, iso, arch)
        else {
            return Sampled::Skipped;
        };
        if let Some((other, others)) = &others {
            if let Some((fb, n)) = blocks::sample_unless_below(other, &grid, others, b, ISO, arch) {
                evaluations += n;
                for (fa, fb) in values.iter_mut().zip(fb) {
                    // crate::implicit_contact::deform's value, without bulge.
                    let eb = fb - ISO;
                    if eb > 0.0 {
                        *fa -= eb;
                    }
                }
            }
        }
        if let Some(clip) = clip {
            clip_block(clip, &grid, b, &mut values);
        }
        Sampled::Values(values, evaluations)
    });
    Ok(mesh)
}

/// Lowers the node values `values` of block `b` to `clip`'s value where
/// it is lower, evaluating the clip only when its lower bound over the
/// block's bounding sphere is below the largest value.
fn clip_block<C: ScalarField + ?Sized>(
    clip: &ClippedField<'_, C>,
    grid: &Grid,
    b: usize,
    values: &mut [Real],
) {
    let block = grid.block(b);
    let (lo, hi) = block.bounds(grid);
    let top = values.iter().copied().fold(Real::NEG_INFINITY, Real::max);
    let centre = lo + (hi - lo) * 0.5;
    if clip.clip_lower_bound(&centre, 0.5 * (hi - lo).norm()) >= top {
        return;
    }
    let [nx, ny, _] = block.nodes();
    let [a, bb, c] = block.start;
    for (n, v) in values.iter_mut().enumerate() {
        let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
        if let Some(cv) = clip.clip_value_below(&grid.node(a + i, bb + j, c + k), *v) {
            *v = v.min(cv);
        }
    }
}

/// The padded node grid over the field's support box (clipped), or `None`
/// when there is nothing to polygonize.
fn grid<F: ScalarField + ?Sized>(
    field: &F,
    params: &PolygonizeParams,
    clip: Option<(Point3, Point3)>,
) -> Result<Option<Grid>, PolygonizeError> {
    let h = params.cell_size;
    if !(h.is_finite() && h > 0.0) {
        return Err(PolygonizeError::InvalidCellSize(h));
    }
    if !(params.iso.is_finite() && params.iso > 0.0) {
        return Err(PolygonizeError::InvalidIso(params.iso));
    }
    let Some((mut lo, mut hi)) = field.support_box() else {
        return Ok(None);
    };
    if !(lo.iter().chain(hi.iter()).all(|x| x.is_finite())) {
        return Err(PolygonizeError::NonFiniteRegion);
    }
    if let Some((clo, chi)) = clip {
        lo = lo.sup(&clo);
        hi = hi.inf(&chi);
        if (0..3).any(|k| lo[k].partial_cmp(&hi[k]) != Some(std::cmp::Ordering::Less)) {
            return Ok(None);
        }
    }
    let lo = lo - Vec3::repeat(h);
    let dims = [0, 1, 2].map(|k| {
        (((hi[k] + h - lo[k]) / h).ceil() as usize)
            .saturating_add(1)
            .max(2)
    });
    let n = dims.into_iter().max().unwrap_or(2);
    if n > params.max_nodes_per_axis {
        return Err(PolygonizeError::TooManyNodes {
            needed: n,
            max: params.max_nodes_per_axis,
        });
    }
    Ok(Some(Grid { lo, h, dims }))
}

/// One block's piece of the mesh: crossing points keyed by global edge
/// (`shared`: the edge may be another block's too) and triangles over
/// them.
#[derive(Default)]
struct Piece {
    keys: Vec<(u64, bool)>,
    positions: Vec<Point3>,
    triangles: Vec<[u32; 3]>,
}

/// Samples and marches every block in parallel, merges the pieces in block
/// order (stages 2-5 of the module doc).
fn extract<F: ScalarField + ?Sized>(
    field: &F,
    grid: &Grid,
    iso: Real,
    sample: impl Fn(usize) -> Sampled + Sync,
) -> (Mesh, PolygonizeStats) {
    let (positions, triangles, stats) = vertices(grid, iso, sample);
    let mut normals: Vec<Vec3> = positions
        .par_iter()
        .map(|p| {
            let (_, g) = field.value_and_gradient(p);
            -g.try_normalize(0.0).unwrap_or_else(Vec3::zeros)
        })
        .collect();
    if normals.contains(&Vec3::zeros()) {
        normals_where_flat(field, grid.h, &positions, &triangles, &mut normals);
    }
    let mesh = Mesh {
        positions,
        normals,
        triangles,
    };
    (mesh, stats)
}

/// Samples and marches every block in parallel and merges the pieces in
/// block order (stages 2-4 of the module doc): the welded vertices and the
/// triangles over them.
fn vertices(
    grid: &Grid,
    iso: Real,
    sample: impl Fn(usize) -> Sampled + Sync,
) -> (Vec<Point3>, Vec<[u32; 3]>, PolygonizeStats) {
    let n_blocks: usize = grid.blocks().iter().product();
    let pieces: Vec<(Piece, usize, usize)> = (0..n_blocks)
        .into_par_iter()
        .map(|b| match sample(b) {
            Sampled::Skipped => (Piece::default(), 0, 0),
            Sampled::Values(values, evaluations) => {
                let n = values.len();
                (march(grid, b, &values, iso), n, evaluations)
            }
        })
        .collect();
    let mut stats = PolygonizeStats {
        grid_nodes: grid.dims.iter().product(),
        blocks: n_blocks,
        ..Default::default()
    };
    for (_, nodes, evaluations) in &pieces {
        stats.sampled_blocks += usize::from(*nodes > 0);
        stats.sampled_nodes += nodes;
        stats.field_evaluations += evaluations;
    }
    let pieces: Vec<Piece> = pieces.into_iter().map(|(piece, _, _)| piece).collect();
    let (positions, triangles) = weld(&pieces);
    (positions, triangles, stats)
}

/// Merges the pieces in block order (stage 4 of the module doc): each
/// crossing point on a shared edge is the first piece's to hold that
/// edge, and the others' triangles use it; every other point is its
/// piece's own. The vertices are numbered in piece order, each piece's in
/// its order, skipping those welded to an earlier piece's: the numbering a
/// serial pass with a map from edge to vertex gives, found in parallel
/// (the shared points sorted by edge, then piece, the first of each edge
/// its owner), so the same at any thread count. Serial, the map took 4%
/// of a skinned cloth's export at 2 threads.
fn weld(pieces: &[Piece]) -> (Vec<Point3>, Vec<[u32; 3]>) {
    // Where each piece's points start in the concatenation of all points.
    let mut start = Vec::with_capacity(pieces.len() + 1);
    start.push(0usize);
    for piece in pieces {
        start.push(start[start.len() - 1] + piece.positions.len());
    }
    let total = start[pieces.len()];
    // The shared points as (edge, point), in piece order within an edge.
    let mut shared: Vec<(u64, u32)> = pieces
        .par_iter()
        .enumerate()
        .flat_map_iter(|(p, piece)| {
            let at = start[p];
            piece
                .keys
                .iter()
                .enumerate()
                .filter(|(_, (_, shared))| *shared)
                .map(move |(k, &(key, _))| (key, (at + k) as u32))
        })
        .collect();
    shared.par_sort_unstable();
    // Each point's owner: itself, or the first point of its edge.
    let mut owner: Vec<u32> = (0..total as u32).into_par_iter().collect();
    let mut first = 0;
    for k in 1..=shared.len() {
        if k == shared.len() || shared[k].0 != shared[first].0 {
            for &(_, q) in &shared[first + 1..k] {
                owner[q as usize] = shared[first].1;
            }
            first = k;
        }
    }
    // Vertex numbers: each owned point's rank among the owned points, in
    // order; every point takes its owner's.
    let owned = |q: usize| owner[q] as usize == q;
    let owned_per_piece: Vec<usize> = (0..pieces.len())
        .into_par_iter()
        .map(|p| (start[p]..start[p + 1]).filter(|&q| owned(q)).count())
        .collect();
    let mut base = Vec::with_capacity(pieces.len());
    let mut next = 0usize;
    for n in &owned_per_piece {
        base.push(next as u32);
        next += n;
    }
    // The outputs are filled in place, each piece its own slice of them
    // (a collect of a flattened iterator gathers per-task vectors and
    // appends them on one thread, touching the memory twice): zeroed
    // vectors of plain numbers come from the allocator zeroed, their pages
    // touched by the parallel fill.
    let sizes: Vec<usize> = pieces.iter().map(|p| p.positions.len()).collect();
    let mut rank = vec![0u32; total];
    pieces_of(&mut rank, &sizes)
        .into_par_iter()
        .enumerate()
        .for_each(|(p, out)| {
            let mut n = base[p];
            for (slot, q) in out.iter_mut().zip(start[p]..) {
                *slot = n;
                n += u32::from(owned(q));
            }
        });
    let numbers: Vec<u32> = (0..total)
        .into_par_iter()
        .with_min_len(4096)
        .map(|q| rank[owner[q] as usize])
        .collect();
    // Each owned point as its piece (high half) and index in the piece
    // (low half), in vertex order; the positions collected from them.
    let mut sources = vec![0u64; next];
    pieces_of(&mut sources, &owned_per_piece)
        .into_par_iter()
        .enumerate()
        .for_each(|(p, out)| {
            let at = start[p];
            let kept = (0..sizes[p]).filter(|&k| owned(at + k));
            for (slot, k) in out.iter_mut().zip(kept) {
                *slot = ((p as u64) << 32) | k as u64;
            }
        });
    let positions: Vec<Point3> = sources
        .par_iter()
        .with_min_len(4096)
        .map(|&s| pieces[(s >> 32) as usize].positions[(s & 0xffff_ffff) as usize])
        .collect();
    let counts: Vec<usize> = pieces.iter().map(|p| p.triangles.len()).collect();
    let mut triangles = vec![[0u32; 3]; counts.iter().sum()];
    pieces_of(&mut triangles, &counts)
        .into_par_iter()
        .enumerate()
        .for_each(|(p, out)| {
            let local = &numbers[start[p]..start[p + 1]];
            for (slot, t) in out.iter_mut().zip(&pieces[p].triangles) {
                *slot = t.map(|i| local[i as usize]);
            }
        });
    (positions, triangles)
}

/// `all` cut into consecutive slices of `counts[p]` elements, one per
/// piece `p` (the counts sum to its length).
fn pieces_of<'a, T>(mut all: &'a mut [T], counts: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(counts.len());
    for &n in counts {
        let (head, tail) = std::mem::take(&mut all).split_at_mut(n);
        out.push(head);
        all = tail;
    }
    out
}

/// Where the gradient vanishes (a clipped field exactly on a collider's
/// surface, where its normal is undefined), the gradient is taken a
/// millionth of a cell outside, along the adjacent triangles' summed
/// normal; failing that, that summed normal is used.
fn normals_where_flat<F: ScalarField + ?Sized>(
    field: &F,
    h: Real,
    positions: &[Point3],
    triangles: &[[u32; 3]],
    normals: &mut [Vec3],
) {
    let flat: Vec<bool> = normals.iter().map(|n| *n == Vec3::zeros()).collect();
    let mut sums = vec![Vec3::zeros(); positions.len()];
    for t in triangles {
        if t.iter().any(|&i| flat[i as usize]) {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let n = (b - a).cross(&(c - a));
            for &i in t {
                sums[i as usize] += n;
            }
        }
    }
    for (i, n) in normals.iter_mut().enumerate() {
        if flat[i] {
            let out = sums[i].try_normalize(0.0).unwrap_or_else(Vec3::zeros);
            let (_, g) = field.value_and_gradient(&(positions[i] + out * (1e-6 * h)));
            *n = (-g).try_normalize(0.0).unwrap_or(out);
        }
    }
}

/// Marching cubes over block `b` with node values `values` (x fastest).
fn march(grid: &Grid, b: usize, values: &[Real], iso: Real) -> Piece {
    let block = grid.block(b);
    let [nx, ny, _] = block.nodes();
    let [cx, cy, cz] = block.cells;
    let cases = tables::cases();
    let mut piece = Piece::default();
    // Local vertex of each (node, axis) edge, or u32::MAX.
    let mut slot = vec![u32::MAX; block.node_count() * 3];
    let at = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let [gx, gy, _] = grid.dims;
    for k in 0..cz {
        for j in 0..cy {
            for i in 0..cx {
                let mut case = 0usize;
                for c in 0..8u8 {
                    let [a, bb, cc] = tables::corner_offset(c);
                    if values[at(i + a, j + bb, k + cc)] > iso {
                        case |= 1 << c;
                    }
                }
                let tris = &cases[case];
                if tris.is_empty() {
                    continue;
                }
                for t in tris {
                    let tri = t.map(|e| {
                        let (c, axis) = tables::EDGES[e as usize];
                        let [a, bb, cc] = tables::corner_offset(c);
                        let node = [i + a, j + bb, k + cc];
                        let s = at(node[0], node[1], node[2]) * 3 + axis as usize;
                        if slot[s] == u32::MAX {
                            slot[s] = piece.positions.len() as u32;
                            let mut other = node;
                            other[axis as usize] += 1;
                            let v0 = values[at(node[0], node[1], node[2])];
                            let v1 = values[at(other[0], other[1], other[2])];
                            let g = [0, 1, 2].map(|d| block.start[d] + node[d]);
                            let p0 = grid.node(g[0], g[1], g[2]);
                            let mut p = p0;
                            p[axis as usize] += (iso - v0) / (v1 - v0) * grid.h;
                            let key = (((g[2] * gy + g[1]) * gx + g[0]) * 3 + axis as usize) as u64;
                            // Shared with another block unless all four
                            // cells around the edge are in this one.
                            let shared = (0..3)
                                .filter(|&d| d != axis as usize)
                                .any(|d| node[d] == 0 || node[d] >= block.cells[d]);
                            piece.keys.push((key, shared));
                            piece.positions.push(p);
                        }
                        slot[s]
                    });
                    piece.triangles.push(tri);
                }
            }
        }
    }
    piece
}

#[cfg(test)]
mod tests;
