//! The object's field: the sum of its primitives' fields (seed 002 §6,
//! "the object surface is an isosurface of the sum of all emitted
//! potentials"), pruned by compact support.
//!
//! A uniform cell grid over the primitives' bounding spheres lists, for any
//! point, the few primitives whose support may contain it; only those are
//! evaluated. Sums run over candidates in increasing primitive index, so a
//! point's value does not depend on the thread that computes it, and the
//! batch evaluators are parallel maps with ordered collects: the same bits
//! for any number of worker threads.

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use crate::grid::CellGrid;
use crate::primitives::PosedPrimitive;

/// A field value and its gradient.
pub type ValueGradient = (Real, Vec3);

/// The most primitives [`Along`] keeps for a box (more: it looks them up
/// per point).
const ALONG_MAX: usize = 64;

/// The field inside a box ([`Field::along`]): when the box lies in one
/// cell of the pruning grid, the cell's primitives whose bounding sphere
/// reaches into it, listed once, so that the many points a root search
/// or a quadrature reads there skip the lookup and the spheres that miss
/// the box; otherwise the lookup of every point. At any point of the box
/// it visits the primitives [`Field::for_each_near`] visits, in the same
/// order: the same values, bit for bit.
pub(crate) struct Along<'a> {
    field: &'a Field,
    /// The box's corners.
    lo: Point3,
    hi: Point3,
    /// The primitives that may reach the box, in increasing index, and
    /// how many there are.
    near: Option<([u32; ALONG_MAX], usize)>,
}

impl Along<'_> {
    /// [`Field::for_each_near`] at `p` (looked up in the grid when `p`
    /// is not in the box: a point rounded just past its end).
    #[inline]
    pub(crate) fn for_each_near(&self, p: &Point3, visit: impl FnMut(usize, &PosedPrimitive)) {
        match &self.near {
            Some((items, len)) if (0..3).all(|k| self.lo[k] <= p[k] && p[k] <= self.hi[k]) => {
                self.field.visit_near(&items[..*len], p, visit)
            }
            _ => self.field.for_each_near(p, visit),
        }
    }
}

impl Sums for Along<'_> {
    fn for_each_near(&self, p: &Point3, visit: impl FnMut(usize, &PosedPrimitive)) {
        Along::for_each_near(self, p, visit)
    }
}

impl Sums for Field {
    fn for_each_near(&self, p: &Point3, visit: impl FnMut(usize, &PosedPrimitive)) {
        Field::for_each_near(self, p, visit)
    }
}

/// The sums of the primitives that a reader of the field visits at a
/// point, in its order: [`Field`]'s, and [`Along`]'s (the same).
pub(crate) trait Sums {
    /// Visits the primitives that may reach `p`, in increasing index.
    fn for_each_near(&self, p: &Point3, visit: impl FnMut(usize, &PosedPrimitive));

    /// The field at `p`.
    #[inline]
    fn value(&self, p: &Point3) -> Real {
        let mut f = 0.0;
        self.for_each_near(p, |_, prim| f += prim.field(p));
        f
    }

    /// The field at `p` and its analytic gradient.
    #[inline]
    fn value_and_gradient(&self, p: &Point3) -> ValueGradient {
        let mut f = 0.0;
        let mut g = Vec3::zeros();
        self.for_each_near(p, |_, prim| {
            let (fi, gi) = prim.field_and_gradient(p);
            f += fi;
            g += gi;
        });
        (f, g)
    }
}

/// The summed field of a set of posed primitives, with a pruning grid.
#[derive(Clone, Debug, Default)]
pub struct Field {
    primitives: Vec<PosedPrimitive>,
    spheres: Vec<(Point3, Real)>,
    grid: CellGrid,
}

impl Field {
    /// Builds the field of `primitives` (and its pruning grid).
    pub fn new(primitives: Vec<PosedPrimitive>) -> Self {
        Self::new_within(primitives, None)
    }

    /// The field of `primitives` read only in the boxes `regions` (all
    /// of space when `None`): [`Field::list_within`] of [`Field::new`].
    pub(crate) fn new_within(
        primitives: Vec<PosedPrimitive>,
        regions: Option<&[(Point3, Point3)]>,
    ) -> Self {
        let mut field = Field {
            spheres: bounding_spheres(&primitives),
            primitives,
            grid: CellGrid::default(),
        };
        field.list_within(regions);
        field
    }

    /// Rebuilds the pruning grid for a field read only in the boxes
    /// `regions` (all of space when `None`): it lists only the primitives
    /// whose bounding sphere's box comes near a region (within twice the
    /// largest distance from a primitive's particle to the far side of its
    /// bounding sphere). Within the regions, and at the particle of any
    /// primitive whose box meets one (where the stretch compensation
    /// reads the density, [`crate::stretch`]), every primitive reaching
    /// the point is listed, in the same order, so values and gradients
    /// there are [`Field::new`]'s, bit for bit; elsewhere the field is too
    /// low. The contact poses every skin at every force evaluation and
    /// reads it near a tool or another skin only: listing a large skin
    /// whole was half of a draped cloth's contact time (100k particles).
    pub(crate) fn list_within(&mut self, regions: Option<&[(Point3, Point3)]>) {
        let spheres = &self.spheres;
        self.grid = match regions {
            None => CellGrid::new(spheres),
            Some([]) => CellGrid::default(),
            Some(regions) => {
                // The particle of a primitive whose box meets a region lies
                // within `reach` of it along each axis, and a primitive
                // reaching that particle has it in its box: its box comes
                // within `reach` of the region. Doubled: headroom for the
                // rounding of the box tests.
                let reach = self
                    .primitives
                    .iter()
                    .zip(spheres)
                    .fold(0.0, |m: Real, (p, (c, r))| {
                        m.max(r + (c - p.particle_position()).norm())
                    });
                CellGrid::new_listing(spheres, |i| box_meets(regions, spheres[i], 2.0 * reach))
            }
        };
    }

    /// Multiplies the amplitude of primitive `i` by `factors[i]` (> 0;
    /// supports, and so the pruning grid, do not depend on amplitudes).
    /// Missing factors leave their primitives as they are.
    pub fn scale_weights(&mut self, factors: &[Real]) {
        for (p, &f) in self.primitives.iter_mut().zip(factors) {
            p.scale_weight(f);
        }
    }

    /// The posed primitives, in the order given to [`Field::new`].
    pub fn primitives(&self) -> &[PosedPrimitive] {
        &self.primitives
    }

    /// The primitives' bounding spheres `(centre, radius)`, in primitive
    /// order: the field is zero outside their union.
    pub(crate) fn spheres(&self) -> &[(Point3, Real)] {
        &self.spheres
    }

    /// Calls `visit(index, primitive)` for every primitive whose bounding
    /// sphere contains `p` (a superset of those with `p` in their support),
    /// in increasing index.
    #[inline]
    pub fn for_each_near(&self, p: &Point3, visit: impl FnMut(usize, &PosedPrimitive)) {
        self.visit_near(self.grid.candidates(p), p, visit);
    }

    /// Calls `visit(index, primitive)` for those of the primitives
    /// `items` (increasing) whose bounding sphere contains `p`, in order:
    /// the test of every lookup ([`Field::for_each_near`], [`Along`]).
    #[inline]
    fn visit_near(&self, items: &[u32], p: &Point3, mut visit: impl FnMut(usize, &PosedPrimitive)) {
        for &i in items {
            let (c, r) = self.spheres[i as usize];
            if (p - c).norm_squared() < r * r {
                visit(i as usize, &self.primitives[i as usize]);
            }
        }
    }

    /// The field read inside the box with opposite corners `a` and `b`
    /// (a lattice edge, where the contact's root searches and quadrature
    /// points lie): [`Along`].
    pub(crate) fn along(&self, a: &Point3, b: &Point3) -> Along<'_> {
        let (lo, hi) = (a.inf(b), a.sup(b));
        let mut near = None;
        if let (Some(cell), Some(other)) = (self.grid.cell_of(&lo), self.grid.cell_of(&hi)) {
            let candidates = self.grid.items_of(cell);
            if cell == other && candidates.len() <= ALONG_MAX {
                let mut items = [0; ALONG_MAX];
                let mut len = 0;
                for &i in candidates {
                    let (c, r) = self.spheres[i as usize];
                    // The box's point nearest the centre: no point of the
                    // box is nearer, in rounded arithmetic too (each
                    // difference, square and sum is monotone), so a sphere
                    // that fails the lookup's test here fails it at every
                    // point of the box.
                    let q = c.sup(&lo).inf(&hi);
                    if (q - c).norm_squared() < r * r {
                        items[len] = i;
                        len += 1;
                    }
                }
                near = Some((items, len));
            }
        }
        Along {
            field: self,
            lo,
            hi,
            near,
        }
    }

    /// The field at `p`.
    pub fn value(&self, p: &Point3) -> Real {
        Sums::value(self, p)
    }

    /// The field at `p` and its analytic gradient.
    pub fn value_and_gradient(&self, p: &Point3) -> ValueGradient {
        Sums::value_and_gradient(self, p)
    }

    /// The unpruned sum over every primitive: the test oracle for the
    /// pruned [`Field::value_and_gradient`].
    pub fn brute_force_value_and_gradient(&self, p: &Point3) -> ValueGradient {
        self.primitives
            .iter()
            .fold((0.0, Vec3::zeros()), |(f, g), prim| {
                let (fi, gi) = prim.field_and_gradient(p);
                (f + fi, g + gi)
            })
    }

    /// The field at many points, in parallel (ordered: `out[i]` is the
    /// value at `points[i]`, bit-identical for any thread count).
    pub fn values(&self, points: &[Point3]) -> Vec<Real> {
        points.par_iter().map(|p| self.value(p)).collect()
    }

    /// Values and gradients at many points, in parallel (ordered).
    pub fn values_and_gradients(&self, points: &[Point3]) -> Vec<ValueGradient> {
        points
            .par_iter()
            .map(|p| self.value_and_gradient(p))
            .collect()
    }

    /// The axis-aligned box `(lo, hi)` holding every primitive's support
    /// (the union of their bounding spheres' boxes), or `None` when there
    /// are no primitives. The skin lies inside it. A primitive at a
    /// non-finite position (a simulation that diverged) makes the whole box
    /// non-finite, which the samplers refuse
    /// ([`crate::PolygonizeError::NonFiniteRegion`]): the component-wise
    /// min and max would keep the finite side and drop it.
    pub fn support_box(&self) -> Option<(Point3, Point3)> {
        let mut it = self.spheres.iter();
        let (c, r) = it.next()?;
        let mut lo = c - Vec3::repeat(*r);
        let mut hi = c + Vec3::repeat(*r);
        let mut finite = true;
        for (c, r) in it {
            let (clo, chi) = (c - Vec3::repeat(*r), c + Vec3::repeat(*r));
            finite &= clo.iter().chain(chi.iter()).all(|x| x.is_finite());
            lo = lo.inf(&clo);
            hi = hi.sup(&chi);
        }
        if !finite {
            let nan = Point3::from(Vec3::repeat(Real::NAN));
            return Some((nan, nan));
        }
        Some((lo, hi))
    }
}

/// Whether the box of the sphere `(c, r)` comes within `margin` of one of
/// the boxes `regions` along every axis (meets it when `margin` is 0).
pub(crate) fn box_meets(
    regions: &[(Point3, Point3)],
    (c, r): (Point3, Real),
    margin: Real,
) -> bool {
    regions
        .iter()
        .any(|(lo, hi)| (0..3).all(|k| c[k] - r <= hi[k] + margin && lo[k] - margin <= c[k] + r))
}

/// The primitives' bounding spheres, in order.
fn bounding_spheres(primitives: &[PosedPrimitive]) -> Vec<(Point3, Real)> {
    primitives
        .par_iter()
        .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
        .map(|p| p.bounding_sphere())
        .collect()
}

/// What [`crate::polygonize_field`] needs of a field: value, analytic
/// gradient and a box holding the skin. Implemented by [`Field`] and by the
/// deformed fields of [`crate::implicit_contact`].
pub trait ScalarField: Sync {
    /// The field at `p`.
    fn value(&self, p: &Point3) -> Real;
    /// The field at `p` and its gradient.
    fn value_and_gradient(&self, p: &Point3) -> ValueGradient;
    /// An axis-aligned box `(lo, hi)` outside which the field is below
    /// [`crate::ISO`], or `None` when the field is empty.
    fn support_box(&self) -> Option<(Point3, Point3)>;
    /// A sum of primitives that is nowhere below this field, if known: the
    /// polygonizer then samples only the blocks where it can reach the
    /// iso value (its narrow band, [`crate::polygonize_region`]). Default:
    /// none (every node of the region is sampled).
    fn bounding_field(&self) -> Option<&Field> {
        None
    }
}

impl ScalarField for Field {
    fn value(&self, p: &Point3) -> Real {
        Field::value(self, p)
    }

    fn value_and_gradient(&self, p: &Point3) -> ValueGradient {
        Field::value_and_gradient(self, p)
    }

    fn support_box(&self) -> Option<(Point3, Point3)> {
        Field::support_box(self)
    }

    fn bounding_field(&self) -> Option<&Field> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::{iso_radius, ISO};
    use crate::primitives::Primitive;
    use op_dynamics::Quat;
    use op_test_support::Rng;

    fn random_field(seed: u64, n: usize) -> Field {
        let mut rng = Rng::new(seed);
        let prims = (0..n)
            .map(|i| {
                let q = Quat::from_scaled_axis(rng.vec3(1.0) * 3.0);
                let x = Point3::from(rng.vec3(1.0) * 3.0);
                let r = 0.4 + 0.3 * rng.uniform(-1.0, 1.0).abs();
                let prim = match i % 4 {
                    0 => Primitive::point(rng.vec3(1.0) * 0.1, r),
                    1 => Primitive::segment(rng.vec3(1.0) * 0.2, rng.vec3(1.0) * 0.2, r),
                    2 => Primitive::square(Vec3::z(), 0.2, r),
                    _ => Primitive::ellipsoid(Vec3::zeros(), q, Vec3::new(1.0, 0.5, 1.5), r),
                };
                prim.posed(i as u32, &x, &q)
            })
            .collect();
        Field::new(prims)
    }

    #[test]
    fn point_primitive_centre_iso_and_support() {
        let r = 0.8;
        let c = Point3::new(0.3, -0.2, 1.0);
        let f = Field::new(vec![Primitive::point(Vec3::zeros(), r).posed(
            0,
            &c,
            &Quat::identity(),
        )]);
        assert_eq!(f.value(&c), 1.0);
        let dir = Vec3::new(1.0, 2.0, -0.5).normalize();
        assert!((f.value(&(c + dir * iso_radius(r))) - ISO).abs() < 1e-14);
        assert_eq!(f.value(&(c + dir * r)), 0.0);
        assert_eq!(f.value(&(c + dir * (r * 1.5))), 0.0);
        assert_eq!(f.value_and_gradient(&(c + dir * 2.0)).1, Vec3::zeros());
    }

    #[test]
    fn pruned_sum_equals_brute_force() {
        let field = random_field(3, 300);
        let mut rng = Rng::new(5);
        let mut nonzero = 0;
        for _ in 0..3000 {
            let p = Point3::from(rng.vec3(1.0) * 3.5);
            let (f, g) = field.value_and_gradient(&p);
            let (fb, gb) = field.brute_force_value_and_gradient(&p);
            assert!((f - fb).abs() < 1e-12, "{f} vs {fb}");
            assert!((g - gb).norm() < 1e-10);
            assert_eq!(f, field.value(&p));
            nonzero += usize::from(f > 0.0);
        }
        assert!(
            nonzero > 1000,
            "test points mostly in the support: {nonzero}"
        );
    }

    /// A field listed within regions has the whole field's bits inside
    /// them and at the particle of every primitive whose box meets one
    /// (where the stretch compensation reads densities), and is too low
    /// somewhere else (it lists fewer primitives).
    #[test]
    fn listed_within_regions_is_the_whole_field_there() {
        let whole = random_field(3, 600);
        let regions = [
            (Point3::new(-1.0, -0.5, -2.0), Point3::new(0.0, 0.5, -1.0)),
            (Point3::new(1.5, 1.5, 1.5), Point3::new(2.0, 2.5, 2.0)),
        ];
        let within = Field::new_within(whole.primitives().to_vec(), Some(&regions));
        let mut rng = Rng::new(11);
        let mut nonzero = 0;
        for (lo, hi) in &regions {
            for _ in 0..2000 {
                let p = Point3::from([0, 1, 2].map(|k| rng.uniform(lo[k], hi[k])));
                assert_eq!(within.value_and_gradient(&p), whole.value_and_gradient(&p));
                assert_eq!(within.value(&p), whole.value(&p));
                nonzero += usize::from(whole.value(&p) > 0.0);
            }
        }
        assert!(
            nonzero > 2000,
            "test points mostly in the support: {nonzero}"
        );
        let mut particles = 0;
        for (p, &sphere) in whole.primitives().iter().zip(whole.spheres()) {
            if box_meets(&regions, sphere, 0.0) {
                let x = p.particle_position();
                assert_eq!(within.value_and_gradient(x), whole.value_and_gradient(x));
                particles += 1;
            }
        }
        assert!(particles > 20, "{particles} primitives meet the regions");
        let outside = (0..3000)
            .map(|_| Point3::from(rng.vec3(1.0) * 3.5))
            .filter(|p| within.value(p) < whole.value(p))
            .count();
        assert!(
            outside > 100,
            "{outside} points where the listed field is lower"
        );
        // No regions: the whole grid; an empty list of regions: no reads.
        let all = Field::new_within(whole.primitives().to_vec(), None);
        let p = Point3::new(0.1, 0.2, 0.3);
        assert_eq!(all.value_and_gradient(&p), whole.value_and_gradient(&p));
        let none = Field::new_within(whole.primitives().to_vec(), Some(&[]));
        assert_eq!(none.value(&p), 0.0);
        assert_eq!(none.support_box(), whole.support_box());
    }

    /// Along a lattice edge, [`Field::along`] visits what the lookup
    /// visits at every point, in the same order (so the same bits), for
    /// a skin of many cells and for one of a single cell, and it drops
    /// most of the cell's candidates; a point past the edge is looked up.
    #[test]
    fn along_an_edge_is_the_field_there() {
        let mut rng = Rng::new(5);
        let (mut listed, mut candidates, mut boxes_in_a_cell) = (0, 0, 0);
        for field in [random_field(3, 600), random_field(6, 12)] {
            for _ in 0..400 {
                let p0 = Point3::from(rng.vec3(1.0) * 3.0);
                let mut dir = Vec3::zeros();
                dir[rng.below(3)] = 0.25;
                let at = |t: Real| p0 + dir * t;
                let along = field.along(&at(0.0), &at(1.0));
                if let Some((_, len)) = along.near {
                    boxes_in_a_cell += 1;
                    listed += len;
                    candidates += field.grid.candidates(&p0).len();
                }
                for t in (0..=20).map(|i| i as Real / 20.0).chain([1.0 + 1e-9]) {
                    let p = at(t);
                    let (mut seen, mut expected) = (Vec::new(), Vec::new());
                    along.for_each_near(&p, |i, _| seen.push(i));
                    field.for_each_near(&p, |i, _| expected.push(i));
                    assert_eq!(seen, expected, "t = {t}");
                    assert_eq!(along.value(&p).to_bits(), field.value(&p).to_bits());
                    assert_eq!(along.value_and_gradient(&p), field.value_and_gradient(&p));
                }
            }
        }
        assert!(
            boxes_in_a_cell > 500,
            "{boxes_in_a_cell} edges within a cell"
        );
        assert!(
            2 * listed < candidates,
            "{listed} of {candidates} candidates kept"
        );
    }

    #[test]
    fn summed_gradient_matches_central_differences() {
        let field = random_field(9, 40);
        let mut rng = Rng::new(1);
        let h = 1e-6;
        for _ in 0..500 {
            let p = Point3::from(rng.vec3(1.0) * 3.0);
            let (_, g) = field.value_and_gradient(&p);
            for k in 0..3 {
                let mut e = Vec3::zeros();
                e[k] = h;
                let fd = (field.value(&(p + e)) - field.value(&(p - e))) / (2.0 * h);
                assert!((fd - g[k]).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn parallel_batch_is_ordered_and_thread_count_independent() {
        let field = random_field(4, 200);
        let mut rng = Rng::new(8);
        let pts: Vec<Point3> = (0..5000)
            .map(|_| Point3::from(rng.vec3(1.0) * 3.0))
            .collect();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| field.values_and_gradients(&pts))
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
        for (p, vg) in pts.iter().zip(&one).step_by(97) {
            assert_eq!(*vg, field.value_and_gradient(p));
        }
        let values = field.values(&pts);
        assert!(values.iter().zip(&one).all(|(v, vg)| *v == vg.0));
    }
}
