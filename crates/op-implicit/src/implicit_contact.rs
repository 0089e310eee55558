//! Contact between two implicit objects: Gascuel's exact contact surface
//! (Gascuel 1993, "An implicit formulation for precise contact modeling
//! between flexible solids", SIGGRAPH 93; seed 002 §6: "exact
//! contact surfaces are modelled by adding negative terms to the
//! potentials").
//!
//! **Deformation.** Write each field as its excess over the iso value,
//! `e_A = f_A - ISO`, `e_B = f_B - ISO` (positive inside). In the
//! interpenetration region (`e_A > 0` and `e_B > 0`) the deformed fields
//! are `f'_A = f_A - e_B` and `f'_B = f_B - e_A`, so both deformed skins
//! lie on the one surface `e_A = e_B`: no gap, no overlap. (The same
//! subtraction is applied wherever the other excess is positive, which
//! leaves the skins unchanged and keeps the fields continuous; see
//! [`deform`]; the deformed field is continuous, with a crease at
//! `e_B = 0`.) Elsewhere the fields are unchanged, unless the optional [`Bulge`]
//! (default off) is on: outside B (`e_B < 0`), A's field gets `+ g(-e_B)`,
//! a C1 profile of two cubic pieces in the distance to the interpenetration
//! boundary (see [`Bulge`]). [`DeformedField`] is the deformed field of one
//! object, a [`ScalarField`], so [`crate::polygonize_field`] exports the
//! deformed skin.
//!
//! **Reaction.** The reactions on both objects' particles are the
//! gradient of one contact energy, `k ∫ max(0, min(e_A, e_B)) dV` (module
//! `energy`): where the skins meet flat its pressure is Gascuel's, the
//! stiffness `k` times the excess removed on the contact surface
//! `e_A = e_B`. It is integrated along the edges of a lattice of cubic
//! cells anchored at the skins' mean particle position, so the forces sum
//! to zero; each particle's force and torque come from its primitives'
//! field gradients at the quadrature points.
//!
//! **Contact surface.** [`ContactPair::contact_surface`] samples the
//! surface `e_A = e_B > 0` itself, for display and measurement: every
//! edge of a grid of cubic cells along which `e_A - e_B` changes sign is
//! searched to `1e-12` of its length (Illinois regula falsi), and the
//! crossing is a sample when the common excess there is positive. A
//! crossing on an edge along axis `k` stands for the area `h^2 |n_k|`
//! (`h` the cell size, `n = (grad e_B - grad e_A) / |...|` the unit
//! contact normal, out of A into B): summed over the three axes this is,
//! on average, the surface area.
//!
//! Only the blocks of the grid that both objects' primitives reach are
//! sampled (the narrow band, module `band`), in parallel, with ordered
//! sums: the same bits for any thread count. Contact regions thinner
//! than a cell may be missed.

use op_dynamics::external::ExternalAccumulator;
use op_dynamics::{Point3, Real, Vec3, World};
use rayon::prelude::*;

use crate::contact::Reactions;
use crate::error::PolygonizeError;
use crate::field::{Field, ScalarField, ValueGradient};
use crate::kernel::ISO;
use crate::polygonize::blocks::Grid;

mod band;
mod energy;
mod obstacle;

pub use obstacle::ObstacleContact;

/// The optional bulge of Gascuel's propagation region (Gascuel 1993).
///
/// Outside the other object B (`s = -e_B > 0`, the distance to the
/// interpenetration boundary measured in B's field units, i.e. about the
/// distance times `|grad f_B|`), A's deformed field is `f_A + g(s)`:
///
/// ```text
/// g(s) = s - s^3 / (3 s0^2)                       0 <= s <= s0
/// g(s) = (2/3) s0 (1 - 3u^2 + 2u^3),  u = (s-s0)/(w-s0)   s0 <= s <= w
/// g(s) = 0                                         s >= w
/// ```
///
/// with `s0 = peak * w`. `g(0) = 0` and `g'(0) = 1`, matching the slope of
/// `f_A - e_B` inside, so the deformed field is C1 across the
/// interpenetration boundary; `g` peaks at `s0` with height `2 s0 / 3`
/// (C1 join of the two cubics) and ends at `w` with zero value and slope.
/// `g(s) <= s` everywhere, which keeps the bulged skins disjoint. The bulge
/// is applied wherever A's skin comes within `w` of B's, also away from
/// the contact itself; keep `w` small.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bulge {
    /// Width `w` of the propagation region, in field units, in
    /// `(0, ISO]` (so the bulge never creates skin outside A's support).
    pub width: Real,
    /// Position of the bulge's peak as a fraction of the width, in
    /// `(0, 1)`. Default: 0.5.
    pub peak: Real,
}

impl Bulge {
    /// A bulge of width `width` peaking at mid-width.
    pub fn with_width(width: Real) -> Self {
        Bulge { width, peak: 0.5 }
    }

    /// Whether `0 < width <= ISO` and `0 < peak < 1`.
    pub fn is_valid(&self) -> bool {
        self.width > 0.0 && self.width <= ISO && self.peak > 0.0 && self.peak < 1.0
    }

    /// `g(s)` and `g'(s)` (type doc).
    pub fn profile(&self, s: Real) -> (Real, Real) {
        let w = self.width;
        let s0 = self.peak * w;
        if s <= 0.0 || s >= w {
            (0.0, 0.0)
        } else if s <= s0 {
            (s - s * s * s / (3.0 * s0 * s0), 1.0 - s * s / (s0 * s0))
        } else {
            let h = 2.0 / 3.0 * s0;
            let u = (s - s0) / (w - s0);
            (
                h * (1.0 - u * u * (3.0 - 2.0 * u)),
                h * 6.0 * u * (u - 1.0) / (w - s0),
            )
        }
    }
}

/// The deformed field of `own` in contact with `other` (module doc), from
/// both fields' values and gradients at one point.
///
/// `f_own - e_other` wherever `e_other > 0`: in the interpenetration region
/// this is Gascuel's deformation; inside the other object but outside this
/// one it lowers a field already below `ISO`, so the skin is unchanged
/// there, and the deformed field stays continuous (the polygonizer
/// interpolates linearly along cell edges: a jump at this object's
/// original skin inside the other would misplace the vertices there by up
/// to a cell).
pub fn deform(own: ValueGradient, other: ValueGradient, bulge: Option<&Bulge>) -> ValueGradient {
    let (fa, ga) = own;
    let (fb, gb) = other;
    let eb = fb - ISO;
    if eb > 0.0 {
        return (fa - eb, ga - gb);
    }
    match bulge {
        Some(b) if eb < 0.0 => {
            let (g, dg) = b.profile(-eb);
            (fa + g, ga - gb * dg)
        }
        _ => (fa, ga),
    }
}

/// The deformed field of one object of a [`ContactPair`]: a
/// [`ScalarField`] for [`crate::polygonize_field`].
#[derive(Clone, Copy, Debug)]
pub struct DeformedField<'a> {
    own: &'a Field,
    other: &'a Field,
    bulge: Option<Bulge>,
}

impl ScalarField for DeformedField<'_> {
    fn value(&self, p: &Point3) -> Real {
        let own = (self.own.value(p), Vec3::zeros());
        let other = (self.other.value(p), Vec3::zeros());
        deform(own, other, self.bulge.as_ref()).0
    }

    fn value_and_gradient(&self, p: &Point3) -> ValueGradient {
        let own = self.own.value_and_gradient(p);
        deform(own, self.other.value_and_gradient(p), self.bulge.as_ref())
    }

    /// The own field's support box: the deformation only lowers the field,
    /// and a valid bulge adds less than `ISO`.
    fn support_box(&self) -> Option<(Point3, Point3)> {
        self.own.support_box()
    }

    /// The own field without a bulge (the deformation only lowers it); a
    /// bulge raises it.
    fn bounding_field(&self) -> Option<&Field> {
        self.bulge.is_none().then_some(self.own)
    }
}

/// Parameters of [`ContactPair::reactions`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImplicitContactParams {
    /// Pressure per unit removed field excess, >= 0 (force / area / field
    /// unit): the contact stiffness of both objects.
    pub stiffness: Real,
    /// Edge length of the cubic sampling cells, world units, > 0.
    pub cell_size: Real,
    /// Largest number of grid nodes along an axis. Default: 512.
    pub max_nodes_per_axis: usize,
}

impl ImplicitContactParams {
    /// `stiffness` and `cell_size`, the node limit at its default.
    pub fn new(stiffness: Real, cell_size: Real) -> Self {
        ImplicitContactParams {
            stiffness,
            cell_size,
            max_nodes_per_axis: 512,
        }
    }
}

/// One sample of the contact surface `e_A = e_B > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSample {
    /// Position (world).
    pub position: Point3,
    /// Unit contact normal, out of A into B.
    pub normal: Vec3,
    /// The common excess `e_A = e_B` (the removed excess), > 0.
    pub excess: Real,
    /// Surface area the sample stands for.
    pub area: Real,
}

/// The reactions of one pair evaluation: on A, on B, and the contact
/// energy they derive from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PairReactions {
    a: Reactions,
    b: Reactions,
    energy: Real,
    edges_in_contact: usize,
    peak: Option<(Point3, Real)>,
}

impl PairReactions {
    /// Reactions on A's particles.
    pub fn a(&self) -> &Reactions {
        &self.a
    }

    /// Reactions on B's particles.
    pub fn b(&self) -> &Reactions {
        &self.b
    }

    /// The contact energy whose gradient the reactions are
    /// ([`ContactPair::energy`]).
    pub fn energy(&self) -> Real {
        self.energy
    }

    /// Edges of the energy's lattice with a positive integral (module
    /// `energy`).
    pub fn edges_in_contact(&self) -> usize {
        self.edges_in_contact
    }

    /// The quadrature point of largest common excess `min(e_A, e_B)`, and
    /// that excess: the deepest point of the interpenetration found.
    /// `None` without contact.
    pub fn peak(&self) -> Option<(Point3, Real)> {
        self.peak
    }

    /// Adds the reactions on both objects to `world` for its next step
    /// (`World::add_external_force`).
    pub fn apply(&self, world: &mut World) {
        self.a.apply(world);
        self.b.apply(world);
    }

    /// Adds the reactions on both objects to `held` (see
    /// [`Reactions::add_to`]).
    pub fn add_to(&self, held: &mut ExternalAccumulator) {
        self.a.add_to(held);
        self.b.add_to(held);
    }
}

/// Two implicit objects in contact (module doc).
#[derive(Clone, Copy, Debug)]
pub struct ContactPair<'a> {
    a: &'a Field,
    b: &'a Field,
    bulge: Option<Bulge>,
}

impl<'a> ContactPair<'a> {
    /// The pair of objects with fields `a` and `b`, without bulge.
    pub fn new(a: &'a Field, b: &'a Field) -> Self {
        ContactPair { a, b, bulge: None }
    }

    /// The same pair with the propagation-region bulge on (`None` turns it
    /// off). Panics if the bulge is not [`Bulge::is_valid`].
    pub fn with_bulge(mut self, bulge: Option<Bulge>) -> Self {
        assert!(
            bulge.is_none_or(|b| b.is_valid()),
            "invalid bulge {bulge:?}"
        );
        self.bulge = bulge;
        self
    }

    /// A's deformed field.
    pub fn deformed_a(&self) -> DeformedField<'a> {
        DeformedField {
            own: self.a,
            other: self.b,
            bulge: self.bulge,
        }
    }

    /// B's deformed field.
    pub fn deformed_b(&self) -> DeformedField<'a> {
        DeformedField {
            own: self.b,
            other: self.a,
            bulge: self.bulge,
        }
    }

    /// The reactions on both objects: the gradient of the contact energy
    /// (module doc and module `energy`), with `params.stiffness` as `k` and
    /// `params.cell_size` as the lattice's cell. No overlap gives empty
    /// reactions. Errors (the lattice's, as for polygonization): a cell
    /// size that is not finite and > 0, a skin at a non-finite position,
    /// or more than `max_nodes_per_axis` nodes along an axis of the
    /// intersection of the two support boxes.
    pub fn reactions(
        &self,
        params: &ImplicitContactParams,
    ) -> Result<PairReactions, PolygonizeError> {
        let Some(grid) = self.lattice(params)? else {
            return Ok(PairReactions::default());
        };
        let sweep = energy::sweep(&grid, self.a, self.b, params.stiffness, true);
        let (energy, edges_in_contact, peak) = (sweep.energy, sweep.edges, sweep.peak);
        let (a, b) = energy::reactions(self.a, self.b, sweep);
        Ok(PairReactions {
            a,
            b,
            energy,
            edges_in_contact,
            peak,
        })
    }

    /// The contact energy `k ∫ max(0, min(e_A, e_B)) dV` on the lattice of
    /// [`ContactPair::reactions`] (whose reactions are its exact
    /// gradient); 0 without overlap. Errors as for the reactions.
    pub fn energy(&self, params: &ImplicitContactParams) -> Result<Real, PolygonizeError> {
        Ok(match self.lattice(params)? {
            Some(grid) => energy::sweep(&grid, self.a, self.b, params.stiffness, false).energy,
            None => 0.0,
        })
    }

    /// The contact energy's lattice (module `energy`), after checking the
    /// cell size.
    fn lattice(&self, params: &ImplicitContactParams) -> Result<Option<Grid>, PolygonizeError> {
        let h = params.cell_size;
        if !(h.is_finite() && h > 0.0) {
            return Err(PolygonizeError::InvalidCellSize(h));
        }
        energy::lattice(self.a, self.b, h, params.max_nodes_per_axis)
    }

    /// Samples of the contact surface `e_A = e_B > 0` (module doc) on a
    /// grid of cell `cell_size`, in grid edge order; empty without
    /// overlap. Errors as for the reactions.
    pub fn contact_surface(
        &self,
        params: &ImplicitContactParams,
    ) -> Result<Vec<ContactSample>, PolygonizeError> {
        let h = params.cell_size;
        if !(h.is_finite() && h > 0.0) {
            return Err(PolygonizeError::InvalidCellSize(h));
        }
        let Some(grid) = self.sampling_grid(h, params.max_nodes_per_axis)? else {
            return Ok(Vec::new());
        };
        Ok(self.samples(&grid, &band::crossing_edges(&grid, self.a, self.b)))
    }

    /// The sampling grid of cell size `h` over the intersection of the two
    /// support boxes, centred on it; `None` when the boxes do not overlap.
    fn sampling_grid(&self, h: Real, max_nodes: usize) -> Result<Option<Grid>, PolygonizeError> {
        let Some((lo, hi)) = common_box(self.a, self.b)? else {
            return Ok(None);
        };
        // Saturating: a box of astronomical size needs more nodes than any
        // limit, and says so.
        let dims = [0, 1, 2].map(|k| (((hi[k] - lo[k]) / h).ceil() as usize).saturating_add(1));
        let needed = dims.into_iter().max().unwrap_or(1);
        if needed > max_nodes {
            return Err(PolygonizeError::TooManyNodes {
                needed,
                max: max_nodes,
            });
        }
        // The grid centred on the box, so a symmetric contact is sampled
        // symmetrically: a ball hitting a ribbon in the ribbon's plane
        // pushes it in that plane, not out of it by the grid's offset.
        let lo = Point3::from(
            (lo.coords + hi.coords) * 0.5 - Vec3::from(dims.map(|n| 0.5 * (n - 1) as Real * h)),
        );
        Ok(Some(Grid { lo, h, dims }))
    }

    /// The samples on the crossed `edges` of `grid`, in edge order.
    fn samples(&self, grid: &Grid, edges: &[(usize, usize)]) -> Vec<ContactSample> {
        edges
            .par_iter()
            .with_min_len(min_len(self.a, self.b, edges.len()))
            .filter_map(|&(i, k)| {
                let mut dir = Vec3::zeros();
                dir[k] = grid.h;
                self.sample_on_edge(&band::node(grid, i), &dir, k, grid.h)
            })
            .collect()
    }

    /// Finds the crossing of `e_A - e_B` on the edge from `p0` to
    /// `p0 + dir` (axis `k`, length `h`) and returns it when it is in
    /// contact. The root is bracketed and found by regula falsi with the
    /// Illinois modification (Dowell & Jarratt 1971: the value at an end
    /// kept twice in a row is halved, which makes the convergence
    /// superlinear) to a bracket of `1e-12 h`: 8 evaluations on average
    /// and at most 14 on the crossed edges of the tests' contacts, where
    /// bisection to round-off took 50 (test `iterations_of_the_crossing`).
    fn sample_on_edge(&self, p0: &Point3, dir: &Vec3, k: usize, h: Real) -> Option<ContactSample> {
        let phi = |t: Real| {
            let p = p0 + dir * t;
            self.a.value(&p) - self.b.value(&p)
        };
        let (t0, t1) = crossing(phi);
        let position = p0 + dir * (0.5 * (t0 + t1));
        let (fa, ga) = self.a.value_and_gradient(&position);
        let (fb, gb) = self.b.value_and_gradient(&position);
        let excess = 0.5 * (fa + fb) - ISO;
        let normal = (gb - ga).try_normalize(0.0)?;
        (excess > 0.0).then(|| ContactSample {
            position,
            normal,
            excess,
            area: h * h * normal[k].abs(),
        })
    }
}

/// The intersection `(lo, hi)` of the support boxes of `a` and `b`; `None`
/// when they do not overlap. Error: a non-finite box (each box is checked
/// on its own: the component-wise max and min of a pair drop a NaN).
pub(crate) fn common_box(
    a: &Field,
    b: &Field,
) -> Result<Option<(Point3, Point3)>, PolygonizeError> {
    let (Some((lo_a, hi_a)), Some((lo_b, hi_b))) = (a.support_box(), b.support_box()) else {
        return Ok(None);
    };
    if ![lo_a, hi_a, lo_b, hi_b]
        .iter()
        .all(|p| p.iter().all(|x| x.is_finite()))
    {
        return Err(PolygonizeError::NonFiniteRegion);
    }
    let (lo, hi) = (lo_a.sup(&lo_b), hi_a.inf(&hi_b));
    Ok((0..3).all(|k| hi[k] > lo[k]).then_some((lo, hi)))
}

/// Width of the bracket [`crossing`] stops at, as a fraction of the edge.
const BRACKET: Real = 1e-12;

/// The bracket `(t0, t1)` of `[0, 1]` around the sign change of `phi`
/// (`phi(0)` and `phi(1)` of opposite signs; otherwise the bracket is
/// bisected towards the end whose sign differs from `phi(0)`'s, as a
/// plain bisection would): Illinois regula falsi (see
/// [`ContactPair::sample_on_edge`]) until the bracket is narrower than
/// [`BRACKET`], at most 48 evaluations inside it.
fn crossing(phi: impl Fn(Real) -> Real) -> (Real, Real) {
    let (f0, f1) = (phi(0.0), phi(1.0));
    crossing_from(phi, f0, f1)
}

/// [`crossing`] from the end values `f0 = phi(0)` and `f1 = phi(1)`,
/// already known.
fn crossing_from(phi: impl Fn(Real) -> Real, f0: Real, f1: Real) -> (Real, Real) {
    crossing_to(phi, f0, f1, BRACKET)
}

/// The least number of `items` (blocks, edges) a parallel pass over the
/// pair `a`, `b` gives one task: all of them (one task, no other thread
/// woken) when the two skins hold fewer than
/// [`op_dynamics::MIN_PARALLEL_LEN`] primitives together, the codebase's
/// rule for small passes. A small pair's whole evaluation takes tens of
/// microseconds (`ball_vs_spiral`: 2 to 4 blocks and about one crossed
/// edge), less than waking a thread and joining it.
fn min_len(a: &Field, b: &Field, items: usize) -> usize {
    if a.primitives().len() + b.primitives().len() >= op_dynamics::MIN_PARALLEL_LEN {
        1
    } else {
        items.max(1)
    }
}

/// [`crossing_from`] to a bracket narrower than `bracket` instead of
/// [`BRACKET`].
fn crossing_to(phi: impl Fn(Real) -> Real, f0: Real, f1: Real, bracket: Real) -> (Real, Real) {
    let (mut t0, mut t1) = (0.0, 1.0);
    let (mut f0, mut f1) = (f0, f1);
    let positive0 = f0 > 0.0;
    let bracketed = (f1 > 0.0) != positive0;
    // Which end the previous step replaced (0 or 1; 2: none yet).
    let mut replaced = 2;
    for _ in 0..48 {
        if t1 - t0 <= bracket {
            break;
        }
        // The secant point, kept half a bracket width inside the ends: a
        // converged estimate next to one end then lands just past the
        // root and closes the bracket from the other side.
        let inset = 0.5 * bracket;
        let secant = (t0 * f1 - t1 * f0) / (f1 - f0);
        let t = if bracketed && secant.is_finite() {
            secant.clamp(t0 + inset, t1 - inset)
        } else {
            0.5 * (t0 + t1)
        };
        if t <= t0 || t >= t1 {
            break;
        }
        let f = phi(t);
        if f == 0.0 {
            return (t, t);
        }
        if (f > 0.0) == positive0 {
            (t0, f0) = (t, f);
            if replaced == 0 {
                f1 *= 0.5;
            }
            replaced = 0;
        } else {
            (t1, f1) = (t, f);
            if replaced == 1 {
                f0 *= 0.5;
            }
            replaced = 1;
        }
    }
    (t0, t1)
}

#[cfg(test)]
mod tests;
