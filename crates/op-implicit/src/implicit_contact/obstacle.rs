//! The contact energy of a skin pressed into a rigid obstacle and its
//! gradient: [`super::ObstacleContact`] (seed 002 §6, Gascuel 1993 with
//! only the deformable skin compressed).
//!
//! **Energy.** With the skin's excess `e = f - ISO` (positive inside) and
//! `C` the obstacle's interior,
//!
//! ```text
//! E = k ∫_C max(0, e) dV,
//! ```
//!
//! the limit of the two skins' energy `k ∫ max(0, min(e_A, e_B)) dV`
//! (module `energy`) when the other object's excess grows without bound
//! inside it: a rigid object is not compressed. Where the skin meets a
//! flat face at depth `d`, with field slope `g` there, `E` per unit area
//! is `k g d^2 / 2`: the pressure `k g d`, Gascuel's pressure `k e` with
//! the whole excess removed from the skin.
//!
//! **Quadrature.** As for two skins, `E` is integrated along the edges of
//! a lattice of cell `h` (each of the three families of parallel edges
//! covers the volume once, `h^2` per line), a point of an edge along axis
//! `k` counted with the share `n_k^2` of the obstacle's outward normal `n`
//! there (the shares sum to one): the lines crossing a thin lens count,
//! those grazing it do not. An edge is cut at the obstacle's surface (a
//! ray cast, or the root of its signed distance), then the part inside at
//! the root of `e` (Illinois regula falsi, searched there only: an edge
//! whose skin ends outside the obstacle costs no search), and the piece
//! inside the obstacle where `e > 0` is integrated by three-point
//! Gauss-Legendre. The lattice is anchored at the world's origin (an
//! obstacle takes no reaction, so nothing needs to balance). Edges are
//! those with `e > 0` at an end and an end inside the obstacle: a lens
//! that reaches no node along an edge is missed.
//!
//! **Gradient.** The integrand vanishes at the root of `e`, and the
//! obstacle's surface does not move with the particles, so moving the
//! pieces' ends adds nothing: the derivative of an edge's integral is the
//! integral of the derivative, at the same Gauss points. The share `n_k^2`
//! depends on the obstacle only. Moving a particle `p` by `δp` and turning
//! it by `ω` about itself moves its primitives rigidly and changes their
//! fields by `-∇f_i · (δp + ω × (x - p))`, so a point of weight `W`
//! (times `k`, the share included) gives primitive `i` the force
//! `W ∇f_i(x)` and the torque `(x - p) × W ∇f_i(x)`. The kernel's weights
//! (stretch compensation, [`crate::stretch`]) are held fixed over an
//! evaluation. The forces are continuous in the state where the lens does
//! not jump past a node unseen, which velocity Verlet's second order
//! needs.
//!
//! **Band.** Only the lattice's blocks whose bounding sphere may reach
//! inside the obstacle are sampled, and of those only the ones the skin's
//! bound reaches ([`box_bounds`]); the obstacle's signed distance is
//! computed only at nodes next to one where `e > 0`. Edges are integrated
//! in parallel and summed in edge order: the same bits at any thread
//! count.

use std::collections::BTreeMap;

use op_dynamics::{Point3, Real, Vec3};
use op_modeling::tools::signed_distance;
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::Ray;
use parry3d_f64::shape::Shape;
use rayon::prelude::*;

use super::band;
use super::energy::{anchored, edge_root, GAUSS};
use super::ImplicitContactParams;
use crate::contact::{Reaction, Reactions};
use crate::error::PolygonizeError;
use crate::field::{Field, Sums};
use crate::kernel::ISO;
use crate::polygonize::blocks::{box_bounds, margin, splat_block, Block, BlockLists, Grid};

/// A skin pressed into a rigid obstacle (module doc): its reactions are
/// the gradient of the contact energy [`ObstacleContact::energy`].
#[derive(Clone, Copy)]
pub struct ObstacleContact<'a> {
    field: &'a Field,
    obstacle: Obstacle<'a>,
}

impl<'a> ObstacleContact<'a> {
    /// The skin of `field` against the obstacle `shape` at `pose`.
    pub fn new(field: &'a Field, shape: &'a dyn Shape, pose: &'a Pose) -> Self {
        ObstacleContact {
            field,
            obstacle: Obstacle::new(shape, pose),
        }
    }

    /// Every particle's force and torque (about itself): minus the
    /// derivatives of [`ObstacleContact::energy`] in its position and in a
    /// rotation about itself, in increasing particle id. Their
    /// `max_depth` is the deepest quadrature point inside the obstacle
    /// where the skin's field is above the iso value, and their samples
    /// the edges with a positive integral. Errors: an invalid cell size, a
    /// non-finite box, or too many lattice nodes along an axis.
    pub fn reactions(&self, params: &ImplicitContactParams) -> Result<Reactions, PolygonizeError> {
        let Some(grid) = self.lattice(params)? else {
            return Ok(Reactions::default());
        };
        let sweep = sweep(&grid, self.field, &self.obstacle, params.stiffness, true);
        Ok(reactions(sweep))
    }

    /// The contact energy `E_h` (module doc) with stiffness
    /// `params.stiffness` on the lattice of cell `params.cell_size`.
    pub fn energy(&self, params: &ImplicitContactParams) -> Result<Real, PolygonizeError> {
        Ok(match self.lattice(params)? {
            Some(grid) => sweep(&grid, self.field, &self.obstacle, params.stiffness, false).energy,
            None => 0.0,
        })
    }

    fn lattice(&self, params: &ImplicitContactParams) -> Result<Option<Grid>, PolygonizeError> {
        let h = params.cell_size;
        if !(h.is_finite() && h > 0.0) {
            return Err(PolygonizeError::InvalidCellSize(h));
        }
        lattice(self.field, &self.obstacle, h, params.max_nodes_per_axis)
    }
}

/// A rigid obstacle: a parry shape at a pose, with its bounding box.
#[derive(Clone, Copy)]
struct Obstacle<'a> {
    shape: &'a dyn Shape,
    pose: &'a Pose,
    /// The shape's bounding box at the pose (infinite for a half-space).
    aabb: (Point3, Point3),
}

impl<'a> Obstacle<'a> {
    /// `shape` at `pose`, its bounding box computed once.
    fn new(shape: &'a dyn Shape, pose: &'a Pose) -> Self {
        Obstacle {
            shape,
            pose,
            aabb: crate::contact::shape_box(shape, pose),
        }
    }

    /// The signed distance at `x` (negative inside) and the outward
    /// normal there; on the surface itself, where parry gives no normal,
    /// 0 and none.
    fn signed(&self, x: &Point3) -> (Real, Option<Vec3>) {
        match signed_distance(self.shape, self.pose, &x.coords) {
            Some((s, n)) => (s, Some(n)),
            None => (0.0, None),
        }
    }

    /// Whether `x` lies strictly inside (signed distance below 0; a point
    /// on the surface is not): a containment test first, cheaper than the
    /// signed distance, which is computed only for the points it keeps.
    fn contains(&self, x: &Point3) -> bool {
        self.shape
            .contains_point(self.pose, Vector::new(x.x, x.y, x.z))
            && self.signed(x).0 < 0.0
    }

    /// Whether the ball of centre `c` and radius `r` may reach inside (a
    /// signed distance moves by at most the distance moved). A ball
    /// farther from the bounding box than `r` by a millionth of `1 + r`
    /// along an axis is farther from the shape too, beyond the signed
    /// distance's test and its round-off: it is answered without the
    /// distance (a skin much larger than its obstacle, as a draped cloth
    /// of 100k particles, has most of its primitives there).
    fn may_reach_inside(&self, c: &Point3, r: Real) -> bool {
        let pad = r + 1e-6 * (1.0 + r);
        let (lo, hi) = &self.aabb;
        if (0..3).any(|k| c[k] + pad < lo[k] || c[k] - pad > hi[k]) {
            return false;
        }
        self.signed(c).0 <= r + 1e-9 * (1.0 + r)
    }

    /// Where the segment from `a` (inside) to `b` (outside) leaves the
    /// obstacle, as a fraction of the way (a ray cast; `None` if it finds
    /// no exit, at round-off from the surface).
    fn exit(&self, a: &Point3, b: &Point3) -> Option<Real> {
        let ray = Ray::new(Vector::new(a.x, a.y, a.z), {
            let d = b - a;
            Vector::new(d.x, d.y, d.z)
        });
        self.shape
            .cast_ray(self.pose, &ray, 1.0, false)
            .filter(|t| (0.0..=1.0).contains(t))
    }

    /// The obstacle's bounding box.
    fn bounding_box(&self) -> (Point3, Point3) {
        self.aabb
    }
}

/// The lattice of cell `h` (nodes at multiples of `h`, [`anchored`] at the
/// origin) over the intersection of the skin's support box and the
/// obstacle's bounding box; `None` when they do not overlap. Errors: a
/// non-finite skin box (the obstacle's may be infinite: a half-space), or
/// more than `max_nodes` nodes along an axis.
fn lattice(
    field: &Field,
    obstacle: &Obstacle<'_>,
    h: Real,
    max_nodes: usize,
) -> Result<Option<Grid>, PolygonizeError> {
    let Some((flo, fhi)) = field.support_box() else {
        return Ok(None);
    };
    if ![flo, fhi].iter().all(|p| p.iter().all(|x| x.is_finite())) {
        return Err(PolygonizeError::NonFiniteRegion);
    }
    // A half-space's box is infinite: the skin's bounds it.
    let (tlo, thi) = obstacle.bounding_box();
    let (lo, hi) = (flo.sup(&tlo), fhi.inf(&thi));
    if ![lo, hi].iter().all(|p| p.iter().all(|x| x.is_finite())) {
        return Err(PolygonizeError::NonFiniteRegion);
    }
    if (0..3).any(|k| lo[k] >= hi[k]) {
        return Ok(None);
    }
    anchored((lo, hi), &Point3::origin(), h, max_nodes).map(Some)
}

/// A lattice edge along which the skin can be inside the obstacle, with
/// what sampling its block found at its two ends.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// Its first node (linear index in the lattice).
    node: usize,
    /// The axis it runs along to its second node.
    axis: usize,
    /// Whether its ends, the first node then the second, lie inside the
    /// obstacle.
    ends: [bool; 2],
}

/// The edges of block `b` of `grid` along which the skin can be inside
/// the obstacle: `e > 0` at an end and an end inside (module doc,
/// **Band**), in increasing node and axis, less those it shares with a
/// later block (an edge on a face two blocks share belongs to the block
/// whose first node is its first node: [`owns`]). `lists` are the
/// primitives that may reach inside, per block.
fn owned_edges(
    grid: &Grid,
    field: &Field,
    obstacle: &Obstacle<'_>,
    lists: &BlockLists,
    b: usize,
    arch: pulp::Arch,
) -> Vec<Edge> {
    let block = grid.block(b);
    let list = lists.of(b);
    let (lo, hi) = block.bounds(grid);
    let centre = lo + (hi - lo) * 0.5;
    if list.is_empty() || !obstacle.may_reach_inside(&centre, 0.5 * (hi - lo).norm()) {
        return Vec::new();
    }
    let (_, upper) = box_bounds(field, (&lo, &hi), list);
    if upper + margin(upper) < ISO {
        return Vec::new();
    }
    let (values, _) = splat_block(field, grid, &block, list, arch);
    if values.iter().all(|&v| v <= ISO) {
        return Vec::new();
    }
    // The obstacle as a second "field" whose excess is minus the signed
    // distance, computed where an edge has e > 0 at an end.
    let inside = insides(grid, &block, &values, obstacle);
    let nodes = block.nodes();
    let strides = [1, nodes[0], nodes[0] * nodes[1]];
    // Both ends of an edge the test keeps were tested for containment
    // (`insides`: each has e > 0 or a neighbour with).
    let end = |l: usize| inside[l] > ISO;
    band::block_edges(grid, &values, &inside, &block, band::overlapped)
        .into_iter()
        .filter_map(|(node, axis)| {
            let at = band::coords(grid, node);
            let here = [0, 1, 2].map(|k| at[k] - block.start[k]);
            owns(grid, &block, here).then(|| {
                let l: usize = (0..3).map(|k| here[k] * strides[k]).sum();
                Edge {
                    node,
                    axis,
                    ends: [end(l), end(l + strides[axis])],
                }
            })
        })
        .collect()
}

/// Whether `block` owns the edges from its node `here` (block
/// coordinates): those on its faces with a later block belong to that
/// block, which finds them too, with the same flags. A block whose
/// neighbour across such a face is passed over finds none there: its
/// nodes on the face are outside the obstacle or have `e <= 0` (the
/// neighbour's tests), and a node's value and containment do not depend
/// on its block (each block's list holds every primitive reaching its
/// face nodes).
fn owns(grid: &Grid, block: &Block, here: [usize; 3]) -> bool {
    (0..3).all(|k| here[k] < block.cells[k] || block.start[k] + here[k] + 1 == grid.dims[k])
}

/// Per node of `block` (values `values`, x fastest), the obstacle as a
/// second field for the edges' test, which reads only its side of the iso
/// value: above it (`ISO + 1`) at every node inside the obstacle with
/// `e > 0` there or at a neighbour along an axis, below it (0) elsewhere.
fn insides(grid: &Grid, block: &Block, values: &[Real], obstacle: &Obstacle<'_>) -> Vec<Real> {
    let nodes = block.nodes();
    let strides = [1, nodes[0], nodes[0] * nodes[1]];
    let mut out = vec![0.0; values.len()];
    for z in 0..nodes[2] {
        for y in 0..nodes[1] {
            for x in 0..nodes[0] {
                let here = [x, y, z];
                let i = x + strides[1] * y + strides[2] * z;
                let positive = |j: usize| values[j] > ISO;
                let needed = positive(i)
                    || (0..3).any(|k| {
                        (here[k] > 0 && positive(i - strides[k]))
                            || (here[k] + 1 < nodes[k] && positive(i + strides[k]))
                    });
                if needed {
                    let [a, b, c] = [0, 1, 2].map(|k| block.start[k] + here[k]);
                    if obstacle.contains(&grid.node(a, b, c)) {
                        out[i] = ISO + 1.0;
                    }
                }
            }
        }
    }
    out
}

/// The least number of edges a parallel task integrates: each costs about
/// twenty field values (a root search and three Gauss points).
const EDGES_PER_TASK: usize = 16;

/// One quadrature point's force and torque on the particle of one
/// primitive (module doc, **Gradient**).
type Term = (u32, Vec3, Vec3);

/// One edge's share of the energy, its deepest point inside the obstacle
/// with `e > 0`, and its gradient's terms.
#[derive(Default)]
struct EdgeSum {
    energy: Real,
    depth: Real,
    terms: Vec<Term>,
}

/// The sum over the lattice, in edge order.
#[derive(Default)]
struct Sweep {
    /// `E_h` (module doc).
    energy: Real,
    /// Edges with a positive integral.
    edges: usize,
    /// The deepest quadrature point inside the obstacle with `e > 0`.
    depth: Real,
    /// Force and torque per particle (empty unless the gradient was
    /// asked for).
    per_particle: BTreeMap<u32, (Vec3, Vec3)>,
}

/// `E_h` over `grid` for stiffness `k`, with the gradient's terms when
/// `gradient` (module doc). Each block finds its edges and integrates
/// them in one task, its edges themselves split among the threads (a
/// small skin reaches a handful of blocks); the sums are then added in
/// edge order, so the bits do not depend on the thread count.
fn sweep(grid: &Grid, field: &Field, obstacle: &Obstacle<'_>, k: Real, gradient: bool) -> Sweep {
    let lists = BlockLists::filtered(field, grid, |c, r| obstacle.may_reach_inside(c, r + grid.h));
    let n_blocks: usize = grid.blocks().iter().product();
    let arch = pulp::Arch::new();
    let scale = k * grid.h.powi(3);
    // A block each task, even for a small skin: a block that passes the
    // tests of `owned_edges` is splatted, tens of microseconds of work,
    // more than waking a thread costs (sheet_on_sphere's 100-particle
    // skin: contact 1.44 s at 1 thread, 1.06-1.23 s at 2, 1.53-1.58 s at
    // 2 with one task for a skin under MIN_PARALLEL_LEN primitives).
    let mut sums: Vec<((usize, usize), EdgeSum)> = (0..n_blocks)
        .into_par_iter()
        .flat_map_iter(|b| {
            owned_edges(grid, field, obstacle, &lists, b, arch)
                .par_iter()
                .with_min_len(EDGES_PER_TASK)
                .filter_map(|edge| {
                    edge_integral(field, obstacle, grid, edge, scale, gradient)
                        .map(|sum| ((edge.node, edge.axis), sum))
                })
                .collect::<Vec<_>>()
        })
        .collect();
    sums.sort_unstable_by_key(|(key, _)| *key);
    let mut out = Sweep::default();
    for (_, s) in sums {
        out.energy += s.energy;
        out.edges += 1;
        out.depth = out.depth.max(s.depth);
        for (id, f, t) in s.terms {
            let entry = out.per_particle.entry(id).or_default();
            entry.0 += f;
            entry.1 += t;
        }
    }
    out
}

/// The integral of `scale * max(0, e)` inside the obstacle along `edge`
/// of `grid`, with its gradient terms when `gradient` (module doc);
/// `None` when it is zero.
fn edge_integral(
    field: &Field,
    obstacle: &Obstacle<'_>,
    grid: &Grid,
    edge: &Edge,
    scale: Real,
    gradient: bool,
) -> Option<EdgeSum> {
    let axis = edge.axis;
    // The edge's two nodes, as the lattice places them.
    let first = band::coords(grid, edge.node);
    let mut second = first;
    second[axis] += 1;
    let ends = [first, second].map(|[x, y, z]| grid.node(x, y, z));
    let p0 = ends[0];
    let mut dir = Vec3::zeros();
    dir[axis] = grid.h;
    let at = |t: Real| p0 + dir * t;
    // Every point read lies between the edge's ends as `at` places them.
    let field = field.along(&at(0.0), &at(1.0));
    let e = |t: Real| field.value(&at(t)) - ISO;
    // Whether end `k` (at `t = k`) is inside: where it is its node
    // (always, on a lattice whose nodes' coordinates are exact, as for
    // cells of a power of two), as the edges' pass found it. (Not the
    // field: the splat's sum may differ from `Field::value` in the last
    // bits.)
    let contains = |k: usize| {
        let p = at(k as Real);
        if p == ends[k] {
            debug_assert_eq!(edge.ends[k], obstacle.contains(&p));
            edge.ends[k]
        } else {
            obstacle.contains(&p)
        }
    };
    // The part of the edge inside the obstacle, `[lo, hi]`: where the
    // surface crosses it, a ray cast from the inner end, or, failing that,
    // the root of the signed distance.
    let inside = |t: Real| -obstacle.signed(&at(t)).0;
    let root = || edge_root(&inside, inside(0.0), inside(1.0));
    let (lo, hi) = match (contains(0), contains(1)) {
        (true, true) => (0.0, 1.0),
        (false, false) => return None,
        (true, false) => (0.0, obstacle.exit(&at(0.0), &at(1.0)).or_else(root)?),
        (false, true) => {
            let cast = obstacle.exit(&at(1.0), &at(0.0)).map(|t| 1.0 - t);
            (cast.or_else(root)?, 1.0)
        }
    };
    // The skin's part of it, `[u, v]`: cut at the skin's root, if its
    // excess changes sign there (the skin is monotone along an edge).
    let (e_lo, e_hi) = (e(lo), e(hi));
    let (u, v) = match (e_lo > 0.0, e_hi > 0.0) {
        (true, true) => (lo, hi),
        (false, false) => return None,
        (positive_lo, _) => {
            let along = |x: Real| e(lo + x * (hi - lo));
            let root = lo + (hi - lo) * edge_root(&along, e_lo, e_hi)?;
            if positive_lo {
                (lo, root)
            } else {
                (root, hi)
            }
        }
    };
    if v <= u {
        return None;
    }
    let mut sum = EdgeSum::default();
    for (x, w) in GAUSS {
        let point = at(u + x * (v - u));
        let (s, normal) = obstacle.signed(&point);
        // The axis's share n_k^2 of the obstacle's normal.
        let share = normal.map_or(1.0 / 3.0, |n| n[axis] * n[axis]);
        let weight = scale * w * (v - u) * share;
        let start = sum.terms.len();
        let mut f = 0.0;
        field.for_each_near(&point, |_, prim| {
            let (fi, gi) = prim.field_and_gradient(&point);
            f += fi;
            if gradient && gi != Vec3::zeros() {
                let force = gi * weight;
                let lever = point - prim.particle_position();
                sum.terms
                    .push((prim.particle(), force, lever.cross(&force)));
            }
        });
        let excess = f - ISO;
        if excess <= 0.0 {
            // Only where the field is not monotone along the edge.
            sum.terms.truncate(start);
            continue;
        }
        sum.energy += weight * excess;
        sum.depth = sum.depth.max(-s);
    }
    (sum.energy > 0.0).then_some(sum)
}

/// The reactions of `sweep`, in increasing particle id.
fn reactions(sweep: Sweep) -> Reactions {
    let reactions: Vec<Reaction> = sweep
        .per_particle
        .into_iter()
        .map(|(particle, (force, torque))| Reaction {
            particle,
            force,
            torque,
        })
        .collect();
    let total_force = reactions.iter().map(|r| r.force).sum();
    Reactions::from_parts(reactions, sweep.edges, total_force).with_max_depth(sweep.depth)
}

#[cfg(test)]
mod tests;
