//! The uniform spacing pass (`uniform_spacing` worlds of the parent
//! module: one material, every pair complete): one loop per spacing
//! potential, monomorphized, and for 12-6 Lennard-Jones the pairs in SIMD
//! lanes ([`crate::lanes`]), whose sums are bit for bit the scalar loop's.

use super::{accumulate, BlockScratch, PairSource, Scalar, SpacingPair, Sums};
use crate::interactions::{LennardJones, PreparedMaterial, SpacingKernel};
use crate::lanes::{self, RowLanes};
use crate::math::{Point3, Real, Vec3};
use crate::neighbours::NeighbourList;

/// The uniform 12-6 spacing pass in SIMD lanes ([`crate::lanes`]).
struct LjLanes<'a> {
    arch: pulp::Arch,
    lj: &'a LennardJones,
    cutoff2: Real,
    p: &'a [Point3],
}

impl PairSource for LjLanes<'_> {
    type Out = SpacingPair;
    type Row = RowLanes;
    const DENSE: bool = true;
    #[inline(always)]
    fn prepare(&self, i: usize, row: &[u32], scratch: &mut RowLanes) {
        lanes::lj_12_6_row(self.arch, self.lj, self.cutoff2, self.p, i, row, scratch);
    }
    #[inline(always)]
    fn pair_or_zero(&self, _: usize, _: usize, k: usize, scratch: &RowLanes) -> SpacingPair {
        let (force_j, energy) = scratch.get_or_zero(k);
        SpacingPair { force_j, energy }
    }
    #[inline(always)]
    fn pair_kept(&self, _: usize, _: usize, k: usize, scratch: &RowLanes) -> (SpacingPair, bool) {
        let (force_j, energy) = scratch.get_or_zero(k);
        (
            SpacingPair { force_j, energy },
            scratch.kept(k, self.cutoff2),
        )
    }
    #[inline(always)]
    fn pair(&self, _: usize, _: usize, k: usize, scratch: &RowLanes) -> Option<SpacingPair> {
        scratch
            .get(k, self.cutoff2)
            .map(|(force_j, energy)| SpacingPair { force_j, energy })
    }
    #[inline(always)]
    fn in_block<const TORQUES: bool>(
        &self,
        _: usize,
        row: &[u32],
        b0: usize,
        scratch: &RowLanes,
        local_f: &mut [Vec3],
        _: &mut [Vec3],
    ) -> (Vec3, Vec3, Real) {
        let (fo, eo) = scratch.add_in_block(row, b0, local_f);
        (fo, Vec3::zeros(), eo)
    }
}

/// One pair of the scalar loops: the potential `eval(d², 1/d²)` gives
/// `(U, U'(r)/r)`; coincident (d² = 0), NaN and beyond-cut-off pairs
/// contribute nothing.
#[inline(always)]
fn pair(
    eval: impl Fn(Real, Real) -> (Real, Real),
    cutoff2: Real,
    p: &[Point3],
    i: usize,
    j: usize,
) -> Option<SpacingPair> {
    let r = p[j] - p[i];
    let d2 = r.norm_squared();
    if d2 > cutoff2 || d2.is_nan() || d2 <= 0.0 {
        return None;
    }
    let (energy, g) = eval(d2, 1.0 / d2);
    Some(SpacingPair {
        force_j: r * (-g),
        energy,
    })
}

/// The uniform spacing kernel for one material: the pass monomorphized per
/// spacing potential. `lanes`: 12-6 Lennard-Jones runs in SIMD lanes (the
/// scalar loop otherwise, kept for the test that the two agree).
pub(super) fn uniform_spacing_pass(
    m: &PreparedMaterial,
    cutoff2: Real,
    p: &[Point3],
    list: &NeighbourList,
    blocks: &mut Vec<BlockScratch>,
    out: Sums<'_>,
    lanes: bool,
) {
    match m.spacing() {
        Some(SpacingKernel::LennardJones(l)) if l.is_12_6() && lanes => {
            let src = LjLanes {
                arch: pulp::Arch::new(),
                lj: l,
                cutoff2,
                p,
            };
            accumulate::<false, _>(list, blocks, src, out);
        }
        Some(SpacingKernel::LennardJones(l)) if l.is_12_6() => {
            let f = |i, j| pair(|d2, inv| l.eval_sq_12_6(d2, inv), cutoff2, p, i, j);
            accumulate::<false, _>(list, blocks, Scalar(f), out);
        }
        Some(SpacingKernel::LennardJones(l)) => {
            let f = |i, j| pair(|d2, inv| l.eval_sq(d2, inv), cutoff2, p, i, j);
            accumulate::<false, _>(list, blocks, Scalar(f), out);
        }
        Some(SpacingKernel::Cohesion(c)) => {
            let eval = |d2: Real, inv: Real| {
                let r = d2.sqrt();
                let (u, du) = c.eval(r);
                (u, du * (r * inv))
            };
            let f = |i, j| pair(eval, cutoff2, p, i, j);
            accumulate::<false, _>(list, blocks, Scalar(f), out);
        }
        None => {
            let f = |i, j| pair(|_, _| (0.0, 0.0), cutoff2, p, i, j);
            accumulate::<false, _>(list, blocks, Scalar(f), out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::pass_bits::{jittered_block, lj_12_6_material, pass_bits};
    use crate::interactions::test_support::Rng;
    use crate::neighbours::NeighbourBackend;

    /// The dispatched SIMD pass and the scalar loop give the same bits:
    /// forces and energies of a jittered 5,000-particle block (three
    /// accumulation blocks, so in-block and spilled pairs), taper and
    /// skin pairs included, at one and two threads.
    #[test]
    fn lanes_pass_equals_the_scalar_pass_bit_for_bit() {
        let m = lj_12_6_material();
        let p = jittered_block(17, &mut Rng::new(0x2545_f491));
        let cutoff = m.cutoff();
        let mut list = NeighbourList::new(NeighbourBackend::CellList, cutoff, 0.3);
        list.update(&p);
        let run = |lanes: bool, threads: usize| {
            pass_bits(p.len(), threads, |blocks, out| {
                uniform_spacing_pass(&m, cutoff * cutoff, &p, &list, blocks, out, lanes)
            })
        };
        let scalar = run(false, 1);
        assert!(scalar.iter().any(|&b| b != 0));
        assert_eq!(scalar, run(true, 1), "lanes vs scalar, 1 thread");
        assert_eq!(scalar, run(true, 2), "lanes vs scalar, 2 threads");
    }
}
