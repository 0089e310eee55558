//! The per-pair kernels of the force evaluation (docs/model.md §2, seed 000
//! eq. 11): a pair's geometry and both directions of its energy, its heat
//! weakening and its friction, inlined into the block loops of
//! [`super`].

use rayon::prelude::*;

use super::{coupling, BondLookup, OrientedPair, SpacingPair};
use crate::heat::pair_strength;
use crate::integrators::StateRef;
use crate::interactions::{
    evaluate_pair, evaluate_pair_weakened, evaluate_spacing_sq, evaluate_spacing_weakened,
    Coupling, ParticleView, PreparedMaterial,
};
use crate::math::{Real, Vec3};
use crate::particles::Attributes;

/// World normals and tangents of every particle at state `s`.
pub(super) fn frames(
    normals: &mut Vec<Vec3>,
    tangents: &mut Vec<Vec3>,
    a: &Attributes<'_>,
    s: StateRef<'_>,
) {
    let n = s.positions.len();
    normals.resize(n, Vec3::zeros());
    tangents.resize(n, Vec3::zeros());
    normals
        .par_iter_mut()
        .zip(tangents.par_iter_mut())
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, (nv, tv))| {
            let q = &s.orientations[i];
            *nv = q * a.normal_axes[i];
            *tv = q * a.tangent_axes[i];
        });
}

/// The heat strength of the pair `(i, j)` when the world is `heated`
/// ([`crate::heat::pair_strength`]), else 1.
#[inline]
fn strength(
    a: &Attributes<'_>,
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    heated: bool,
    i: usize,
    j: usize,
) -> Real {
    if heated {
        pair_strength(
            mi.heat_response(),
            mj.heat_response(),
            a.temperatures[i],
            a.temperatures[j],
        )
    } else {
        1.0
    }
}

/// [`strength`] of a pair of two particles of material `m`: its one
/// strength at the pair's mean temperature, with the same bits
/// ([`crate::heat::pair_strength`] averages two equal strengths, `0.5 (s +
/// s) = s` exactly), one division instead of two.
#[inline]
fn uniform_strength(a: &Attributes<'_>, m: &PreparedMaterial, i: usize, j: usize) -> Real {
    match m.heat_response() {
        Some(r) => r.strength(0.5 * (a.temperatures[i] + a.temperatures[j])),
        None => 1.0,
    }
}

/// The spacing kernel's pair: spacing potential for complete pairs
/// (weakened by heat when `heated`), the typing repulsion otherwise; zero
/// beyond the cut-off.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(super) fn spacing_pair(
    a: &Attributes<'_>,
    materials: &[PreparedMaterial],
    bonds: &impl BondLookup,
    heated: bool,
    cutoff2: Real,
    s: StateRef<'_>,
    i: usize,
    j: usize,
) -> Option<SpacingPair> {
    let p = s.positions;
    let r = p[j] - p[i];
    let d2 = r.norm_squared();
    if d2 > cutoff2 {
        return None;
    }
    let (mi, mj) = (
        &materials[a.materials[i] as usize],
        &materials[a.materials[j] as usize],
    );
    let (energy, force_j) = match coupling(a, bonds, i, j) {
        Coupling::Complete { .. } => {
            let st = strength(a, mi, mj, heated, i, j);
            if st < 1.0 {
                evaluate_spacing_weakened(mi, mj, &r, d2.sqrt(), st)
            } else {
                evaluate_spacing_sq(mi, mj, &r, d2)
            }
        }
        Coupling::RepulsionOnly => {
            let res = evaluate_pair(
                &view(p[i], Vec3::zeros(), Vec3::zeros(), 0.0, mi),
                &view(p[j], Vec3::zeros(), Vec3::zeros(), 0.0, mj),
                Coupling::RepulsionOnly,
            );
            (res.energy, res.force_j)
        }
    };
    Some(SpacingPair { force_j, energy })
}

#[inline]
fn view(
    position: crate::math::Point3,
    normal: Vec3,
    tangent: Vec3,
    kappa: Real,
    material: &PreparedMaterial,
) -> ParticleView<'_> {
    ParticleView {
        position,
        normal,
        tangent,
        kappa,
        material,
    }
}

/// The oriented kernel's pair: the full interaction of the pair's coupling
/// (weakened by heat when `heated`) plus inter-particle friction; zero
/// beyond the cut-off.
///
/// `UNIFORM`: every particle has material 0, one object, one type and is
/// oriented ([`uniform_oriented`]): every pair is complete and oriented,
/// without per-pair lookups, and its heat strength is its one material's
/// at the pair's mean temperature ([`uniform_strength`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn oriented_pair<const UNIFORM: bool>(
    a: &Attributes<'_>,
    materials: &[PreparedMaterial],
    bonds: &impl BondLookup,
    friction: bool,
    heated: bool,
    cutoff2: Real,
    normals: &[Vec3],
    tangents: &[Vec3],
    s: StateRef<'_>,
    i: usize,
    j: usize,
) -> Option<OrientedPair> {
    let p = s.positions;
    let r = p[j] - p[i];
    let d2 = r.norm_squared();
    if d2 > cutoff2 {
        return None;
    }
    let (mi, mj, c) = if UNIFORM {
        let m = &materials[0];
        (m, m, Coupling::Complete { oriented: true })
    } else {
        (
            &materials[a.materials[i] as usize],
            &materials[a.materials[j] as usize],
            coupling(a, bonds, i, j),
        )
    };
    let (vi, vj) = (
        view(p[i], normals[i], tangents[i], a.curvatures[i], mi),
        view(p[j], normals[j], tangents[j], a.curvatures[j], mj),
    );
    let res = if UNIFORM && heated {
        evaluate_pair_weakened(&vi, &vj, c, uniform_strength(a, mi, i, j))
    } else if !UNIFORM && heated && matches!(c, Coupling::Complete { .. }) {
        evaluate_pair_weakened(&vi, &vj, c, strength(a, mi, mj, heated, i, j))
    } else {
        evaluate_pair(&vi, &vj, c)
    };
    let mut force_j = res.force_j;
    if friction && matches!(c, Coupling::Complete { .. }) {
        let v_rel = s.velocities[j] - s.velocities[i];
        force_j += friction_force(mi, mj, &r, d2.sqrt(), &v_rel);
    }
    Some(OrientedPair {
        force_j,
        torque_i: res.torque_i,
        torque_j: res.torque_j,
        energy: res.energy,
    })
}

/// Inter-particle friction (seed 002 §3, §5): damping of the relative
/// velocity of two particles. Applied along the line of centres (the
/// dissipative force of DPD), so it conserves linear *and* angular momentum;
/// weight `1 - r/r_c` over the spacing cut-off, coefficient the mean of the
/// two materials'. Returns the force on j (the force on i is its negative).
#[inline]
pub fn friction_force(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    r: &Vec3,
    dist: Real,
    v_rel: &Vec3,
) -> Vec3 {
    let gamma = 0.5 * (mi.friction() + mj.friction());
    let rc = mi.spacing_cutoff().max(mj.spacing_cutoff());
    if gamma == 0.0 || dist >= rc || dist == 0.0 {
        return Vec3::zeros();
    }
    let e = r / dist;
    -gamma * (1.0 - dist / rc) * v_rel.dot(&e) * e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flags::Flags;
    use crate::forces::Unbonded;
    use crate::heat::HeatResponse;
    use crate::interactions::test_support::Rng;
    use crate::interactions::{CohesionParams, Material, Spacing};
    use crate::math::{Point3, Quat};
    use crate::particles::ParticleType;

    /// A heated world of one material runs the lookup-free pair
    /// (`UNIFORM`): every pair of a clay block at temperatures below, across
    /// and above the melting point gives the general pair's bits.
    #[test]
    fn the_uniform_heated_pair_is_the_general_one_bit_for_bit() {
        let clay = Material {
            spacing: Some(Spacing::Cohesion(CohesionParams::default())),
            cocircularity: 10.0,
            coplanarity: 3.0,
            heat: Some(HeatResponse {
                melting: 5.0,
                residual: 0.1,
                cold_drag: 100.0,
            }),
            ..Material::empty()
        }
        .prepare()
        .unwrap();
        let materials = [clay];
        let mut rng = Rng::new(13);
        let side = 4;
        let positions: Vec<Point3> = (0..side * side * side)
            .map(|k| {
                let c = [k % side, (k / side) % side, k / (side * side)];
                Point3::from(c.map(|x| x as Real + 0.3 * (rng.uniform() - 0.5)))
            })
            .collect();
        let n = positions.len();
        let orientations: Vec<Quat> = (0..n).map(|_| rng.rotation()).collect();
        let velocities: Vec<Vec3> = (0..n).map(|_| rng.unit_vector()).collect();
        let temperatures: Vec<Real> = (0..n).map(|_| rng.range(-1.0, 7.0)).collect();
        let ids: Vec<u32> = (0..n as u32).collect();
        let (axes_n, axes_t) = (vec![Vec3::z(); n], vec![Vec3::x(); n]);
        let a = Attributes {
            ids: &ids,
            slot_of: &ids,
            normal_axes: &axes_n,
            tangent_axes: &axes_t,
            flags: &vec![Flags::empty(); n],
            objects: &vec![0; n],
            kinds: &vec![ParticleType::Standard(0); n],
            materials: &vec![0; n],
            curvatures: &(0..n).map(|_| rng.range(-0.2, 0.2)).collect::<Vec<_>>(),
            temperatures: &temperatures,
            masses: &vec![1.0; n],
        };
        let s = StateRef {
            positions: &positions,
            velocities: &velocities,
            orientations: &orientations,
            angular_velocities: &vec![Vec3::zeros(); n],
        };
        let (mut normals, mut tangents) = (Vec::new(), Vec::new());
        frames(&mut normals, &mut tangents, &a, s);
        let bits = |o: Option<OrientedPair>| {
            o.map(|o| {
                [o.force_j, o.torque_i, o.torque_j]
                    .iter()
                    .flat_map(|v| [v.x, v.y, v.z])
                    .chain([o.energy])
                    .map(Real::to_bits)
                    .collect::<Vec<u64>>()
            })
        };
        let (nv, tv, cutoff2) = (&normals[..], &tangents[..], 2.25);
        let mut weakened = 0;
        for i in 0..n {
            for j in i + 1..n {
                for friction in [false, true] {
                    let uniform = oriented_pair::<true>(
                        &a, &materials, &Unbonded, friction, true, cutoff2, nv, tv, s, i, j,
                    );
                    let general = oriented_pair::<false>(
                        &a, &materials, &Unbonded, friction, true, cutoff2, nv, tv, s, i, j,
                    );
                    assert_eq!(bits(uniform), bits(general), "pair ({i}, {j})");
                }
                let st = strength(&a, &materials[0], &materials[0], true, i, j);
                weakened += usize::from(st < 1.0 && (positions[j] - positions[i]).norm() < 1.5);
            }
        }
        // The check covers weakened pairs, not only cold ones.
        assert!(weakened > 50, "{weakened} weakened pairs");
    }
}
