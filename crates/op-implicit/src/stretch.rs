//! Displayed skins that keep their thickness as their object stretches.
//!
//! A skin is an iso-surface of the sum of its primitives' potentials
//! (seed 002 §6), so where the particles of a sheet move apart the sum
//! drops: the skin thins, and a thin one opens. A sheet of squares skinned
//! 0.4 thick each side (radius 0.8), draped over a ball and stretched to
//! 1.05-1.3 spacings around the top, opened a hole there although its
//! particles stayed 0.3 above the ball.
//!
//! [`StretchCompensation`] scales each primitive's amplitude by
//! `rho_ref / rho`, where `rho` is the unit-amplitude field of the
//! object's primitives at the primitive's particle (the particle's own
//! primitive and its neighbours', a local density of primitives): the
//! normalization of a sum of kernels by the local density of smoothed
//! particle hydrodynamics (Monaghan 1992, `sum_j (m_j / rho_j) W_ij`), so
//! a stretched region keeps the field, and the skin its thickness, that it
//! had at rest; a compressed region gets factors below 1.
//!
//! The reference `rho_ref` is either
//! - [`StretchCompensation::uniform`]: the median particle's density at
//!   rest, for a sheet, ribbon or shell (square primitives), whose skin
//!   has one thickness everywhere: its rim, cut or torn edges and the
//!   particles created later get the interior's thickness (without it the
//!   rim particles of a thin cloth stood out of its skin), and a particle
//!   left alone keeps a blob of that thickness instead of vanishing; or
//! - [`StretchCompensation::per_particle`]: each particle's own density at
//!   rest, for a clump of points, whose surface particles have fewer
//!   neighbours than its core by nature: at rest every factor is 1 (the
//!   same bits); a particle created later takes its density when it
//!   first appears.

use std::collections::BTreeMap;

use op_dynamics::{Point3, Real};
use rayon::prelude::*;

use crate::field::{box_meets, Field};
use crate::primitives::PosedPrimitive;

/// The reference densities of a skin's primitives (module doc).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum StretchCompensation {
    /// One reference for every primitive: the median density at rest.
    Uniform(Real),
    /// Each particle's own density at rest, by particle id.
    PerParticle(BTreeMap<u32, Real>),
}

impl StretchCompensation {
    /// The median density of `field`'s primitives as every primitive's
    /// reference (a sheet's skin: one thickness everywhere).
    pub fn uniform(field: &Field) -> Self {
        let mut rho = densities(field);
        rho.sort_by(Real::total_cmp);
        StretchCompensation::Uniform(rho.get(rho.len() / 2).copied().unwrap_or(0.0))
    }

    /// Each primitive's density in `field` as its own reference (a clump:
    /// its present shape is the rest shape).
    pub fn per_particle(field: &Field) -> Self {
        let rest = field
            .primitives()
            .iter()
            .zip(densities(field))
            .map(|(p, rho)| (p.particle(), rho))
            .collect();
        StretchCompensation::PerParticle(rest)
    }

    /// Scales the amplitude of every primitive of `field` by `reference /
    /// current` density (module doc). Per particle, one without a
    /// reference (created after the skin was built) takes its current
    /// density: factor 1 now, compensated from then on.
    pub fn apply(&mut self, field: &mut Field) {
        match self {
            StretchCompensation::Uniform(r) => scale_to(field, |_| Some(*r)),
            StretchCompensation::PerParticle(rest) => {
                let now = densities(field);
                for (p, &rho) in field.primitives().iter().zip(&now) {
                    rest.entry(p.particle()).or_insert(rho);
                }
                scale_by(field, &now, |id| rest.get(&id).copied())
            }
        }
    }

    /// [`StretchCompensation::apply`] without recording references: a
    /// particle without one keeps its amplitude (factor 1). The contact
    /// force contributor poses its fields so, at every force evaluation,
    /// from references the skin stages keep (`crate::contact_forces`).
    pub fn apply_held(&self, field: &mut Field) {
        self.apply_held_within(field, None);
    }

    /// [`StretchCompensation::apply_held`] on the primitives whose
    /// bounding sphere's box meets one of the boxes `regions` (all when
    /// `None`): the others keep their amplitude, for a caller that reads
    /// the field only in those boxes (the contact, near a tool or another
    /// skin). Each compensated primitive gets the factor the whole field's
    /// compensation gives it: its density sums every primitive reaching
    /// its particle.
    pub fn apply_held_within(&self, field: &mut Field, regions: Option<&[(Point3, Point3)]>) {
        let within = |p: &PosedPrimitive| {
            regions.is_none_or(|regions| box_meets(regions, p.bounding_sphere(), 0.0))
        };
        let now = densities_within(field, within);
        match self {
            StretchCompensation::Uniform(r) => scale_by(field, &now, |_| Some(*r)),
            StretchCompensation::PerParticle(rest) => {
                scale_by(field, &now, |id| rest.get(&id).copied())
            }
        }
    }

    /// Forgets the particles `keep` rejects (removed from the object).
    pub fn retain(&mut self, mut keep: impl FnMut(u32) -> bool) {
        if let StretchCompensation::PerParticle(rest) = self {
            rest.retain(|id, _| keep(*id));
        }
    }
}

/// Scales the amplitude of every primitive of `field` by `reference /
/// current` density, the reference given per particle id by `reference`
/// (none, or a density that is not positive: factor 1).
fn scale_to(field: &mut Field, reference: impl Fn(u32) -> Option<Real> + Sync) {
    let now = densities(field);
    scale_by(field, &now, reference);
}

/// [`scale_to`] with the current densities `now` (in primitive order).
fn scale_by(field: &mut Field, now: &[Real], reference: impl Fn(u32) -> Option<Real> + Sync) {
    let factors: Vec<Real> = field
        .primitives()
        .par_iter()
        .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
        .zip(now)
        .map(|(p, &rho)| match reference(p.particle()) {
            Some(r) if rho > 0.0 && r > 0.0 => r / rho,
            _ => 1.0,
        })
        .collect();
    field.scale_weights(&factors);
}

/// The unit-amplitude field of `field`'s primitives at each primitive's
/// particle (its own primitive included), in primitive order; summed in
/// increasing primitive index, so the same bits at any thread count.
fn densities(field: &Field) -> Vec<Real> {
    densities_within(field, |_| true)
}

/// [`densities`] of the primitives `within` keeps, 0 for the others (a
/// density of 0 gives the factor 1: the amplitude is kept).
fn densities_within(field: &Field, within: impl Fn(&PosedPrimitive) -> bool + Sync) -> Vec<Real> {
    field
        .primitives()
        .par_iter()
        .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
        .map(|p| {
            if !within(p) {
                return 0.0;
            }
            let x = p.particle_position();
            let mut rho = 0.0;
            field.for_each_near(x, |_, q| rho += q.field(x) / q.weight());
            rho
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::ISO;
    use crate::primitives::Primitive;
    use op_dynamics::{Point3, Quat, Vec3};

    /// A hexagonal sheet of `n x n` ellipsoidal primitives (semi-axes
    /// `reach` in the plane, `b` along z, amplitude `w`) at spacing `s`.
    fn sheet(n: usize, s: Real, reach: Real, b: Real, w: Real) -> Field {
        let prim = Primitive::ellipsoid(
            Vec3::zeros(),
            Quat::identity(),
            Vec3::new(reach / b, reach / b, 1.0),
            b,
        )
        .with_weight(w);
        let mut posed = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let x = s * (i as Real + 0.5 * (j % 2) as Real);
                let y = s * (j as Real) * (3.0 as Real).sqrt() / 2.0;
                let id = (j * n + i) as u32;
                posed.push(prim.posed(id, &Point3::new(x, y, 0.0), &Quat::identity()));
            }
        }
        Field::new(posed)
    }

    /// Where the skin crosses the sheet's normal above the middle particle.
    fn top(field: &Field, at: Point3) -> Real {
        let (mut lo, mut hi) = (0.0, 2.0);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            if field.value(&(at + Vec3::z() * mid)) >= ISO {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// Compensating within a box gives the primitives that meet it the
    /// weights of the whole field's compensation, bit for bit, and leaves
    /// the others as they were.
    #[test]
    fn compensation_within_a_box_is_the_whole_ones_there() {
        let rest = sheet(9, 1.0, 1.7, 1.2, 1.0);
        let comp = StretchCompensation::per_particle(&rest);
        let stretched = sheet(9, 1.3, 1.7, 1.2, 1.0);
        let mut whole = stretched.clone();
        comp.apply_held(&mut whole);
        let region = (Point3::new(-1.0, -1.0, -1.0), Point3::new(2.0, 2.0, 1.0));
        let mut within = stretched.clone();
        comp.apply_held_within(&mut within, Some(&[region]));
        let (mut inside, mut outside) = (0, 0);
        for ((p, w), q) in stretched
            .primitives()
            .iter()
            .zip(within.primitives())
            .zip(whole.primitives())
        {
            let (c, r) = p.bounding_sphere();
            let meets = (0..3).all(|k| c[k] - r <= region.1[k] && region.0[k] <= c[k] + r);
            if meets {
                inside += 1;
                assert_eq!(w.weight(), q.weight());
                assert!((w.weight() - 1.0).abs() > 0.01, "stretched: compensated");
            } else {
                outside += 1;
                assert_eq!(w.weight(), p.weight());
            }
        }
        assert!(
            inside > 5 && outside > 5,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn a_stretched_sheet_keeps_its_thickness() {
        // Amplitude for a skin about 0.4 above the sheet at rest.
        let (reach, b) = (1.7, 1.2);
        let rest = sheet(9, 1.0, reach, b, 1.0);
        let middle = Point3::new(4.0, 4.0 * (3.0 as Real).sqrt() / 2.0, 0.0);
        let w = ISO / rest.value(&(middle + Vec3::z() * 0.4));
        let rest = sheet(9, 1.0, reach, b, w);
        let mut comp = StretchCompensation::per_particle(&rest);
        let t0 = top(&rest, middle);
        assert!((t0 - 0.4).abs() < 1e-9, "{t0}");
        // At rest the factors are 1: the same field, bit for bit.
        let mut same = rest.clone();
        comp.apply(&mut same);
        assert_eq!(
            same.value(&(middle + Vec3::z() * 0.3)),
            rest.value(&(middle + Vec3::z() * 0.3))
        );
        // Stretched by 25% both ways: the plain sum opens (no skin above the
        // middle particle), the compensated one stays near its thickness.
        let stretched = sheet(9, 1.25, reach, b, w);
        let mid2 = middle * 1.25;
        let plain = top(&stretched, mid2);
        let mut kept = stretched.clone();
        comp.apply(&mut kept);
        let thick = top(&kept, mid2);
        // Between particles too.
        let between = mid2 + Vec3::new(0.625, 0.0, 0.0);
        let gap = top(&kept, between);
        println!("stretched 25%: over a particle {plain} -> {thick}, between two {gap}");
        assert!(plain < 0.3, "plain {plain}");
        assert!((thick - 0.4).abs() < 0.04, "compensated {thick}");
        assert!(gap > 0.3, "between particles {gap}");
    }

    #[test]
    fn compression_lowers_and_new_particles_start_at_one() {
        let rest = sheet(5, 1.0, 1.7, 1.2, 0.5);
        let mut comp = StretchCompensation::per_particle(&rest);
        let mut squeezed = sheet(5, 0.8, 1.7, 1.2, 0.5);
        comp.apply(&mut squeezed);
        let middle = 12;
        assert!(squeezed.primitives()[middle].weight() < 0.5);
        // Forgotten particles start again at factor 1.
        comp.retain(|id| id != middle as u32);
        let mut again = sheet(5, 0.8, 1.7, 1.2, 0.5);
        comp.apply(&mut again);
        assert_eq!(again.primitives()[middle].weight(), 0.5);
    }

    /// With one reference, the rim of a sheet at rest gets nearly the
    /// interior's thickness, and the interior keeps its own (factor 1 at
    /// the median). Measured for a skin 0.4 thick: over the middle of the
    /// first row 0.24 -> 0.37, over its corner 0 (no skin) -> 0.34.
    #[test]
    fn a_uniform_reference_thickens_the_rim_to_the_interior() {
        let (reach, b) = (1.7, 1.2);
        let unit = sheet(9, 1.0, reach, b, 1.0);
        let middle = Point3::new(4.0, 4.0 * (3.0 as Real).sqrt() / 2.0, 0.0);
        let w = ISO / unit.value(&(middle + Vec3::z() * 0.4));
        let plain = sheet(9, 1.0, reach, b, w);
        let mut kept = plain.clone();
        StretchCompensation::uniform(&plain).apply(&mut kept);
        // The middle of the first row (4 neighbours) and its corner (2).
        let edge = Point3::new(4.0, 0.0, 0.0);
        let corner = Point3::origin();
        let (edge_plain, edge_kept) = (top(&plain, edge), top(&kept, edge));
        let (corner_plain, corner_kept) = (top(&plain, corner), top(&kept, corner));
        println!("edge {edge_plain} -> {edge_kept}, corner {corner_plain} -> {corner_kept}");
        assert!(edge_plain < 0.35, "plain edge {edge_plain}");
        assert!((edge_kept - 0.4).abs() < 0.03, "kept edge {edge_kept}");
        assert!(corner_kept > corner_plain + 0.05, "corner {corner_kept}");
        assert!((top(&kept, middle) - 0.4).abs() < 0.02);
    }
}
