//! The uniform oriented pass (`uniform_oriented` worlds of the parent
//! module: one material, every pair complete and oriented, no heat, no
//! bonds): with 12-6 Lennard-Jones spacing and no spin or friction, the
//! full oriented pair in SIMD lanes ([`crate::lanes`]), whose sums are bit
//! for bit the scalar kernel's.

use super::{accumulate, BlockScratch, OrientedPair, PairSource, Sums};
use crate::lanes::{self, OrientedInput, OrientedRow};
use crate::math::{Real, Vec3};
use crate::neighbours::NeighbourList;

/// The full oriented pair of one material in SIMD lanes.
struct OrientedLanes<'a> {
    arch: pulp::Arch,
    input: OrientedInput<'a>,
}

impl PairSource for OrientedLanes<'_> {
    type Out = OrientedPair;
    type Row = OrientedRow;
    const DENSE: bool = true;
    #[inline(always)]
    fn prepare(&self, i: usize, row: &[u32], scratch: &mut OrientedRow) {
        lanes::oriented_row(self.arch, &self.input, i, row, scratch);
    }
    #[inline(always)]
    fn pair_or_zero(&self, _: usize, _: usize, k: usize, scratch: &OrientedRow) -> OrientedPair {
        let (force_j, torque_i, torque_j, energy) = scratch.get_or_zero(k);
        OrientedPair {
            force_j,
            torque_i,
            torque_j,
            energy,
        }
    }
    #[inline(always)]
    fn in_block<const TORQUES: bool>(
        &self,
        _: usize,
        row: &[u32],
        b0: usize,
        scratch: &OrientedRow,
        local_f: &mut [Vec3],
        local_t: &mut [Vec3],
    ) -> (Vec3, Vec3, Real) {
        scratch.add_in_block(row, b0, local_f, local_t)
    }
    #[inline(always)]
    fn pair_kept(
        &self,
        i: usize,
        j: usize,
        k: usize,
        scratch: &OrientedRow,
    ) -> (OrientedPair, bool) {
        let o = self.pair_or_zero(i, j, k, scratch);
        (o, scratch.kept(k, self.input.cutoff2))
    }
    #[inline(always)]
    fn pair(&self, _: usize, _: usize, k: usize, scratch: &OrientedRow) -> Option<OrientedPair> {
        scratch
            .get(k, self.input.cutoff2)
            .map(|(force_j, torque_i, torque_j, energy)| OrientedPair {
                force_j,
                torque_i,
                torque_j,
                energy,
            })
    }
}

/// The uniform oriented pass in SIMD lanes over `list`, for the material
/// of `input.c` (see [`crate::interactions::PreparedMaterial`]'s
/// `oriented_lane_constants`).
pub(super) fn uniform_oriented_pass(
    input: OrientedInput<'_>,
    list: &NeighbourList,
    blocks: &mut Vec<BlockScratch>,
    out: Sums<'_>,
) {
    let src = OrientedLanes {
        arch: pulp::Arch::new(),
        input,
    };
    accumulate::<true, _>(list, blocks, src, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::pass_bits::{jittered_block, pass_bits};
    use crate::forces::Scalar;
    use crate::interactions::test_support::Rng;
    use crate::interactions::{
        evaluate_pair, Coupling, LennardJonesParams, Material, ParticleView, Spacing, WeightParams,
    };
    use crate::math::{Real, Vec3};
    use crate::neighbours::NeighbourBackend;

    /// The dispatched oriented lanes pass and the scalar pass (the
    /// uniform oriented kernel's `evaluate_pair` per pair) give the same
    /// bits: forces, torques and energies of a jittered, randomly oriented
    /// 5,000-particle block (three accumulation blocks, so in-block and
    /// spilled pairs), taper and skin pairs included, at one and two
    /// threads.
    #[test]
    fn lanes_pass_equals_the_scalar_pass_bit_for_bit() {
        let m = Material {
            spacing: Some(Spacing::LennardJones(LennardJonesParams {
                r0: (2.0 as Real).powf(1.0 / 6.0),
                taper: 0.1,
                ..Default::default()
            })),
            weight: WeightParams {
                cutoff: 2.5,
                ..Default::default()
            },
            coplanarity: 0.1,
            conormality: 0.05,
            cocircularity: 0.05,
            form: 0.1,
            ..Material::empty()
        }
        .prepare()
        .unwrap();
        let c = m.oriented_lane_constants().unwrap();
        let mut rng = Rng::new(183);
        let p = jittered_block(17, &mut rng);
        let normals: Vec<Vec3> = p.iter().map(|_| rng.unit_vector()).collect();
        let kappa: Vec<Real> = p.iter().map(|_| rng.range(-0.5, 0.5)).collect();
        let cutoff = m.cutoff();
        let cutoff2 = cutoff * cutoff;
        let mut list = NeighbourList::new(NeighbourBackend::CellList, cutoff, 0.3);
        list.update(&p);
        let run = |lanes: bool, threads: usize| {
            pass_bits(p.len(), threads, |blocks, out| {
                if lanes {
                    let input = OrientedInput {
                        c: &c,
                        cutoff2,
                        p: &p,
                        normals: &normals,
                        curvatures: &kappa,
                    };
                    uniform_oriented_pass(input, &list, blocks, out);
                } else {
                    let view = |q: usize| ParticleView {
                        position: p[q],
                        normal: normals[q],
                        tangent: Vec3::zeros(),
                        kappa: kappa[q],
                        material: &m,
                    };
                    let pair = |i: usize, j: usize| {
                        ((p[j] - p[i]).norm_squared() <= cutoff2).then(|| {
                            let r = evaluate_pair(
                                &view(i),
                                &view(j),
                                Coupling::Complete { oriented: true },
                            );
                            OrientedPair {
                                force_j: r.force_j,
                                torque_i: r.torque_i,
                                torque_j: r.torque_j,
                                energy: r.energy,
                            }
                        })
                    };
                    accumulate::<true, _>(&list, blocks, Scalar(pair), out);
                }
            })
        };
        let scalar = run(false, 1);
        assert!(scalar.iter().any(|&b| b != 0));
        assert_eq!(scalar, run(false, 2), "scalar, 1 vs 2 threads");
        assert_eq!(scalar, run(true, 1), "lanes vs scalar, 1 thread");
        assert_eq!(scalar, run(true, 2), "lanes vs scalar, 2 threads");
    }
}
