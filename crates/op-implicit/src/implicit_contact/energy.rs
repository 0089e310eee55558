//! The contact energy of two skins and its gradient: the reactions of
//! [`super::ContactPair::reactions`].
//!
//! **Energy.** With the excesses `e_A = f_A - ISO` and `e_B = f_B - ISO`
//! (positive inside),
//!
//! ```text
//! E = k ∫ max(0, min(e_A, e_B)) dV
//! ```
//!
//! over the interpenetration region, `k` the contact stiffness. Its
//! density is the excess Gascuel's deformation removes from each skin
//! (seed 002 §6): where the two skins meet flat, with field slopes `g_A`
//! and `g_B` and a penetration `d`, `E` per unit area is
//! `k g_A g_B d^2 / (2 (g_A + g_B))`, and its derivative in `d` is
//! `k e`, with `e = g_A g_B d / (g_A + g_B)` the common excess on the
//! contact surface `e_A = e_B`: the pressure of Gascuel's contact surface,
//! with the same stiffness. Unlike pressures sampled on that surface and
//! shared among primitives, the reactions below are the gradient of one
//! function of the particles' positions and orientations, so contact does
//! no work around a closed loop and its stiffness is symmetric.
//!
//! **Quadrature.** The interpenetration region of skins pressed together
//! is a thin lens, often thinner than a cell: a sum over the lattice's
//! nodes would miss it. `E` is integrated along the lattice's edges
//! instead: each of the three families of parallel edges covers the
//! volume once (`h^2` per line), and a point of an edge along axis `k`
//! counts with the share `n_k^2` of the contact normal
//! `n = D / |D|`, `D = ∇e_B - ∇e_A` (the shares of the three axes sum to
//! one, so `E` is unchanged): a line crossing the lens counts, one
//! grazing it inside its plane, which would stand for a slab a cell thick,
//! does not. On an edge, the integrand is smooth between the roots of
//! `e_A`, of `e_B` and of `e_A - e_B` (found by Illinois regula falsi, as
//! the contact surface's samples are), and each piece where both are
//! positive is integrated by three-point Gauss-Legendre: a point
//! primitive's field is a polynomial of degree 6 along a line, integrated
//! to about `(piece / R)^6`. Edges are those the band reaches with both
//! excesses positive at an end (a lens that touches no node along an edge
//! is missed, as for the contact surface).
//!
//! **Lattice.** The lattice of cell `h` is anchored at `o`, the mean of
//! the carrying particles' positions over both skins' primitives (each
//! primitive counted once). Moving both skins together moves the lattice
//! with them, so `E_h` does not change: the reactions sum to zero exactly
//! (to round-off). (Rotations turn the skins against the lattice's axes:
//! the torques balance to the quadrature's accuracy.)
//!
//! **Gradient.** The integrand vanishes at the roots of `e_A` and `e_B`
//! and is continuous at those of `e_A - e_B`, so moving the pieces' ends
//! adds nothing: the derivative of an edge's integral is the integral of
//! the derivative, taken at the same Gauss points. A point of weight `W`
//! (times `k`) contributes `W n_k^2 e` with `e = Σ_i f_i(x) - ISO` over
//! the weaker skin's primitives. Moving a particle `p` by `δp` and turning
//! it by `ω` about itself moves its primitives rigidly, changing `f_i(x)`
//! by `-∇f_i · (δp + ω × (x - p))` and `∇f_i(x)` by
//! `ω × ∇f_i - H_i (δp + ω × (x - p))` (`H_i` the Hessian). With
//! `G = W e ∂(n_k^2)/∂D`, a primitive of the weaker skin gets the force
//! `W n_k^2 ∇f_i - H_i G` and the torque `(x - p) × force + ∇f_i × G`; one
//! of the other skin the force `H_i G` and the torque
//! `(x - p) × force - ∇f_i × G`. Moving the lattice by `δo` changes `E_h`
//! by `S · δo`, `S` the sum of those forces over both skins, and `o` moves
//! by `c_p / N` of `δp` (`c_p` of the `N` primitives ride on `p`): each
//! particle also gets `-(c_p / N) S`, the term that makes the forces sum
//! to zero. The kernel's weights (stretch compensation,
//! [`crate::stretch`]) are held fixed over an evaluation. The forces are
//! continuous in the state where the lens does not jump past a node
//! unseen, which velocity Verlet's second order needs.
//!
//! Edges are integrated in parallel and summed in edge order: the same
//! bits at any thread count.

use std::collections::BTreeMap;

use nalgebra::Matrix3;
use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::band;
use crate::contact::{Reaction, Reactions};
use crate::error::PolygonizeError;
use crate::field::{Along, Field, Sums};
use crate::kernel::ISO;
use crate::polygonize::blocks::Grid;

/// The quadrature lattice of cell `h` over the intersection of the two
/// support boxes, anchored at [`anchor`] (module doc); `None` when the
/// boxes do not overlap. Errors: a non-finite box, or more than
/// `max_nodes` nodes along an axis.
pub(super) fn lattice(
    a: &Field,
    b: &Field,
    h: Real,
    max_nodes: usize,
) -> Result<Option<Grid>, PolygonizeError> {
    let Some((lo, hi)) = super::common_box(a, b)? else {
        return Ok(None);
    };
    anchored((lo, hi), &anchor(a, b), h, max_nodes).map(Some)
}

/// The lattice of cell `h` over the box `(lo, hi)` whose nodes lie at
/// `o` plus multiples of `h`. Errors: more than `max_nodes` nodes along an
/// axis, or a non-finite first node.
pub(super) fn anchored(
    (lo, hi): (Point3, Point3),
    o: &Point3,
    h: Real,
    max_nodes: usize,
) -> Result<Grid, PolygonizeError> {
    // Saturating: an astronomical box needs more nodes than any limit,
    // and says so. One more node than the box needs: the lattice's first
    // node may lie up to a cell before the box.
    let needed = (0..3)
        .map(|k| (((hi[k] - lo[k]) / h).ceil() as usize).saturating_add(2))
        .max()
        .unwrap_or(2);
    if needed > max_nodes {
        return Err(PolygonizeError::TooManyNodes {
            needed,
            max: max_nodes,
        });
    }
    let mut start = lo;
    let mut dims = [2; 3];
    for k in 0..3 {
        start[k] = o[k] + h * ((lo[k] - o[k]) / h).floor();
        dims[k] = (((hi[k] - start[k]) / h).ceil() as usize)
            .saturating_add(1)
            .clamp(2, needed);
    }
    if !start.iter().all(|x| x.is_finite()) {
        // Positions near the largest finite number: their mean overflows.
        return Err(PolygonizeError::NonFiniteRegion);
    }
    Ok(Grid { lo: start, h, dims })
}

/// The lattice's anchor: the mean of the carrying particles' positions
/// over both skins' primitives.
fn anchor(a: &Field, b: &Field) -> Point3 {
    let all = a.primitives().iter().chain(b.primitives());
    let n = a.primitives().len() + b.primitives().len();
    let sum: Vec3 = all.map(|p| p.particle_position().coords / n as Real).sum();
    Point3::from(sum)
}

/// Three-point Gauss-Legendre on `[0, 1]`: nodes and weights.
pub(super) const GAUSS: [(Real, Real); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// Width of the bracket the roots are found to, as a fraction of the edge:
/// an error `δ` in a root costs `O(δ^2)` of the integral.
const ROOT_BRACKET: Real = 1e-10;

/// The root of `phi` along an edge (`t` in `[0, 1]`), when its values
/// `f0` and `f1` at the ends differ in sign: the middle of a bracket
/// narrower than [`ROOT_BRACKET`].
pub(super) fn edge_root(phi: &dyn Fn(Real) -> Real, f0: Real, f1: Real) -> Option<Real> {
    ((f0 > 0.0) != (f1 > 0.0)).then(|| {
        let (t0, t1) = super::crossing_to(phi, f0, f1, ROOT_BRACKET);
        0.5 * (t0 + t1)
    })
}

/// Whether a sign has flipped by `u` along an edge: past its `root` (at or
/// before a piece's start `u`).
fn flipped(root: Option<Real>, u: Real) -> bool {
    root.is_some_and(|t| t <= u)
}

/// Per particle: the force and torque summed so far.
type PerParticle = BTreeMap<u32, (Vec3, Vec3)>;

/// One quadrature point's force and torque on the particle of one
/// primitive (module doc, **Gradient**).
type Term = (u32, Vec3, Vec3);

/// One edge's share of the energy and its gradient.
#[derive(Default)]
struct EdgeSum {
    energy: Real,
    peak: Option<(Point3, Real)>,
    a: Vec<Term>,
    b: Vec<Term>,
}

/// The sum over the whole lattice, in edge order.
#[derive(Default)]
pub(super) struct Sweep {
    /// `E_h` (module doc).
    pub energy: Real,
    /// Edges with a positive integral.
    pub edges: usize,
    /// The point of largest common excess `min(e_A, e_B)`, and that excess.
    pub peak: Option<(Point3, Real)>,
    /// Force and torque per particle of A before the lattice term, and of
    /// B (empty unless the gradient was asked for).
    pub a: PerParticle,
    pub b: PerParticle,
}

/// `E_h` over `grid`, with the gradient's point terms when `gradient`
/// (module doc), for stiffness `k`.
pub(super) fn sweep(grid: &Grid, a: &Field, b: &Field, k: Real, gradient: bool) -> Sweep {
    let edges = band::overlap_edges(grid, a, b);
    // Each axis's lines cover the volume once: h^2 per line, h along the
    // edge.
    let scale = k * grid.h.powi(3);
    let sums: Vec<EdgeSum> = edges
        .par_iter()
        .with_min_len(super::min_len(a, b, edges.len()))
        .filter_map(|&(i, axis)| {
            let p0 = band::node(grid, i);
            edge_integral((a, b), &p0, axis, grid.h, scale, gradient)
        })
        .collect();
    let mut out = Sweep::default();
    for s in sums {
        out.energy += s.energy;
        out.edges += 1;
        if let Some((x, e)) = s.peak {
            if out.peak.is_none_or(|(_, best)| e > best) {
                out.peak = Some((x, e));
            }
        }
        for (terms, into) in [(s.a, &mut out.a), (s.b, &mut out.b)] {
            for (id, f, t) in terms {
                let entry = into.entry(id).or_default();
                entry.0 += f;
                entry.1 += t;
            }
        }
    }
    out
}

/// The integral of `scale * max(0, min(e_A, e_B))` along the edge from
/// `p0` along `axis`, of length `h`, with its gradient terms when
/// `gradient` (module doc); `None` when it is zero.
fn edge_integral(
    (a, b): (&Field, &Field),
    p0: &Point3,
    axis: usize,
    h: Real,
    scale: Real,
    gradient: bool,
) -> Option<EdgeSum> {
    let mut dir = Vec3::zeros();
    dir[axis] = h;
    let at = |t: Real| p0 + dir * t;
    // Every point read lies between the edge's ends as `at` places them.
    let (a, b) = (a.along(&at(0.0), &at(1.0)), b.along(&at(0.0), &at(1.0)));
    let (a, b) = (&a, &b);
    let ea = |t: Real| a.value(&at(t)) - ISO;
    let eb = |t: Real| b.value(&at(t)) - ISO;
    let (a0, a1, b0, b1) = (ea(0.0), ea(1.0), eb(0.0), eb(1.0));
    let ta = edge_root(&ea, a0, a1);
    let tb = edge_root(&eb, b0, b1);
    let tc = edge_root(&|t| ea(t) - eb(t), a0 - b0, a1 - b1);
    let mut cuts = vec![0.0, 1.0];
    cuts.extend([ta, tb, tc].into_iter().flatten());
    cuts.sort_by(Real::total_cmp);
    let mut sum = EdgeSum::default();
    let (mut near_w, mut near_o) = (Vec::new(), Vec::new());
    for piece in cuts.windows(2) {
        let (u, v) = (piece[0], piece[1]);
        let inside_a = (a0 > 0.0) != flipped(ta, u);
        let inside_b = (b0 > 0.0) != flipped(tb, u);
        if v <= u || !(inside_a && inside_b) {
            continue;
        }
        let a_weaker = (a0 - b0 <= 0.0) != flipped(tc, u);
        let (weaker, other) = if a_weaker { (a, b) } else { (b, a) };
        for (x, w) in GAUSS {
            let point = at(u + x * (v - u));
            let (f, gw) = near(weaker, &point, gradient, &mut near_w);
            let excess = f - ISO;
            if excess <= 0.0 {
                // Only where a field is not monotone along the edge.
                continue;
            }
            let (_, go) = near(other, &point, gradient, &mut near_o);
            // The axis's share s = n_k^2 of the contact normal n = D / |D|,
            // D = ∇e_other - ∇e_weaker.
            let d = go - gw;
            let d2 = d.norm_squared();
            let (share, dk) = if d2 > 0.0 {
                (d[axis] * d[axis] / d2, d[axis] / d2)
            } else {
                (1.0 / 3.0, 0.0)
            };
            let along = scale * w * (v - u);
            let weight = along * share;
            sum.energy += weight * excess;
            if sum.peak.is_none_or(|(_, best)| excess > best) {
                sum.peak = Some((point, excess));
            }
            if gradient {
                // G = W excess ∂s/∂D, ∂s/∂D = 2 (D_k / |D|^2) (e_k - (D_k / |D|^2) D).
                let mut e_k = Vec3::zeros();
                e_k[axis] = 1.0;
                let big_g = (e_k - d * dk) * (2.0 * dk * along * excess);
                let (into_w, into_o) = if a_weaker {
                    (&mut sum.a, &mut sum.b)
                } else {
                    (&mut sum.b, &mut sum.a)
                };
                for n in &near_w {
                    let force = n.gradient * weight - n.hessian * big_g;
                    let torque = n.lever.cross(&force) + n.gradient.cross(&big_g);
                    into_w.push((n.particle, force, torque));
                }
                for n in &near_o {
                    let force = n.hessian * big_g;
                    let torque = n.lever.cross(&force) - n.gradient.cross(&big_g);
                    into_o.push((n.particle, force, torque));
                }
            }
        }
    }
    (sum.energy > 0.0).then_some(sum)
}

/// A primitive reaching a quadrature point: its particle, the lever from
/// the particle to the point, and its field's gradient and Hessian there.
struct Near {
    particle: u32,
    lever: Vec3,
    gradient: Vec3,
    hessian: Matrix3<Real>,
}

/// The field of `field` at `point` and its gradient; with `hessians`,
/// `out` lists the primitives reaching the point ([`Near`]).
fn near(field: &Along<'_>, point: &Point3, hessians: bool, out: &mut Vec<Near>) -> (Real, Vec3) {
    out.clear();
    if !hessians {
        return field.value_and_gradient(point);
    }
    let (mut f, mut g) = (0.0, Vec3::zeros());
    field.for_each_near(point, |_, prim| {
        let (fi, gi, hi) = prim.field_gradient_hessian(point);
        f += fi;
        g += gi;
        if gi != Vec3::zeros() {
            out.push(Near {
                particle: prim.particle(),
                lever: point - prim.particle_position(),
                gradient: gi,
                hessian: hi,
            });
        }
    });
    (f, g)
}

/// Each skin's reactions from the point terms of `sweep`: every particle of
/// both skins also gets its share `-(c_p / N) S` of the lattice term
/// (module doc).
pub(super) fn reactions(a: &Field, b: &Field, sweep: Sweep) -> (Reactions, Reactions) {
    if sweep.edges == 0 {
        return (Reactions::default(), Reactions::default());
    }
    let total: Vec3 = sweep.a.values().chain(sweep.b.values()).map(|x| x.0).sum();
    let n = a.primitives().len() + b.primitives().len();
    let per_primitive = -total / n as Real;
    (
        side(a, sweep.a, per_primitive, sweep.edges),
        side(b, sweep.b, per_primitive, sweep.edges),
    )
}

/// One skin's reactions: its point terms and `per_primitive` times the
/// number of its primitives riding on each particle, in increasing
/// particle id, from `edges` edges in contact.
fn side(field: &Field, mut terms: PerParticle, per_primitive: Vec3, edges: usize) -> Reactions {
    let mut ids: Vec<u32> = field.primitives().iter().map(|p| p.particle()).collect();
    ids.sort_unstable();
    let mut reactions: Vec<Reaction> = Vec::with_capacity(ids.len());
    for id in ids {
        match reactions.last_mut() {
            Some(last) if last.particle == id => last.force += per_primitive,
            _ => {
                let (force, torque) = terms.remove(&id).unwrap_or_default();
                reactions.push(Reaction {
                    particle: id,
                    force: force + per_primitive,
                    torque,
                });
            }
        }
    }
    let total_force = reactions.iter().map(|r| r.force).sum();
    Reactions::from_parts(reactions, edges, total_force)
}

#[cfg(test)]
mod tests;
