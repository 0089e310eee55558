//! Tests of the cluster kernel: against the scalar pass, momentum,
//! thread counts.

use super::*;
use crate::forces::pass_bits::{jittered_block, lj_12_6_material, pass_bits};
use crate::forces::uniform_spacing::uniform_spacing_pass;
use crate::interactions::test_support::Rng;
use crate::neighbours::NeighbourBackend;

/// A jittered block of `side³` particles less the last few (a padded
/// last cluster), with a coincident pair and a NaN particle, its list.
fn block(side: usize) -> (Vec<Point3>, NeighbourList, Real) {
    let mut p = jittered_block(side, &mut Rng::new(0x2545_f491));
    p.truncate(p.len() - 3);
    p[10] = p[11];
    p[20].x = Real::NAN;
    let m = lj_12_6_material();
    let cutoff = m.cutoff();
    let mut list = NeighbourList::new(NeighbourBackend::CellList, cutoff, 0.3);
    list.update(&p);
    (p, list, cutoff)
}

/// The lanes of the tests: `f64` (the cluster machinery, close to the
/// row kernel's sums) and `f32` (mixed precision, the world's).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Lanes {
    F64,
    F32,
}

/// The bits of the cluster pass over `p` in `lanes`, at `threads`.
fn cluster_bits(
    p: &[Point3],
    list: &NeighbourList,
    cutoff: Real,
    lanes: Lanes,
    threads: usize,
) -> Vec<u64> {
    let m = lj_12_6_material();
    let lj = m.lennard_jones_12_6().unwrap();
    pass_bits(p.len(), threads, |_, out| match lanes {
        Lanes::F64 => {
            let mut scratch = ClusterScratch::<f64>::default();
            cluster_spacing_pass(lj, cutoff * cutoff, p, list, &mut scratch, out)
        }
        Lanes::F32 => {
            let mut scratch = ClusterScratch::<f32>::default();
            cluster_spacing_pass(lj, cutoff * cutoff, p, list, &mut scratch, out)
        }
    })
}

fn reals(bits: &[u64]) -> Vec<Real> {
    bits.iter().map(|&b| Real::from_bits(b)).collect()
}

/// The cluster pass in double precision sums the same pairs as the
/// scalar loop, in another order: forces within a few roundings of
/// the largest force, energies (half per particle there, the row's
/// pairs here) equal in total; in mixed precision within `f32`
/// roundings. Any pair missed or counted twice fails by far more.
#[test]
fn cluster_pass_agrees_with_the_scalar_pass() {
    let (p, list, cutoff) = block(13);
    assert_agrees_with_the_scalar_pass(&p, &list, cutoff, 1e-5);
}

/// The same where a block's halo targets lie far apart in index (a slab
/// whose lower half is the first block and whose upper half comes last,
/// an unrelated lump between them): the first block's 32 halo targets
/// span 717 clusters, more than `HALO_SCAN` per target, so it sorts them
/// instead of reading them off its slot map, while the other blocks read
/// theirs.
#[test]
fn cluster_pass_agrees_with_the_scalar_pass_across_far_halos() {
    // 8 x 8 x 8, z slowest: the first 256 particles (one block) are the
    // lower half.
    let slab = jittered_block(8, &mut Rng::new(0x0dd5));
    let lump = jittered_block(14, &mut Rng::new(7));
    let mut p = slab[..256].to_vec();
    p.extend(lump.iter().map(|q| q + Vec3::new(20.0, 0.0, 0.0)));
    p.extend_from_slice(&slab[256..]);
    let m = lj_12_6_material();
    let cutoff = m.cutoff();
    let mut list = NeighbourList::new(NeighbourBackend::CellList, cutoff, 0.3);
    list.update(&p);
    // Coordinates up to 36 (the block's reach 14): a coarser `f32`
    // quantization; the `f64` lanes check the merge to 1e-12.
    assert_agrees_with_the_scalar_pass(&p, &list, cutoff, 1e-4);
}

/// The checks of [`cluster_pass_agrees_with_the_scalar_pass`], mixed
/// precision within `f32_tol` of the largest force, and the same bits at
/// one and two threads.
fn assert_agrees_with_the_scalar_pass(
    p: &[Point3],
    list: &NeighbourList,
    cutoff: Real,
    f32_tol: Real,
) {
    let n = p.len();
    let m = lj_12_6_material();
    let scalar = reals(&pass_bits(n, 1, |blocks, out| {
        uniform_spacing_pass(&m, cutoff * cutoff, p, list, blocks, out, false)
    }));
    let scale = scalar[..3 * n]
        .iter()
        .fold(0.0, |a: Real, &b| a.max(b.abs()));
    assert!(scale > 1.0, "{scale}");
    let energy = |v: &[Real]| v[6 * n..].iter().sum::<Real>();
    for (lanes, tol) in [(Lanes::F64, 1e-12), (Lanes::F32, f32_tol)] {
        let c = reals(&cluster_bits(p, list, cutoff, lanes, 1));
        for k in 0..3 * n {
            assert!(
                (c[k] - scalar[k]).abs() <= tol * scale,
                "{lanes:?} force component {k}: {} vs {}",
                c[k],
                scalar[k]
            );
        }
        assert!(c[3 * n..6 * n].iter().all(|&t| t == 0.0), "no torques");
        let (ec, es) = (energy(&c), energy(&scalar));
        assert!(
            (ec - es).abs() <= tol * es.abs(),
            "{lanes:?} energy {ec} vs {es}"
        );
        assert_eq!(
            cluster_bits(p, list, cutoff, lanes, 1),
            cluster_bits(p, list, cutoff, lanes, 2),
            "{lanes:?}: 1 and 2 threads"
        );
    }
}

/// Internal forces: total force zero to the rounding of the sums
/// (each pair's two sides are exact negatives; they are summed in `f64`
/// in double precision, in `f32` lanes over a block in mixed), and
/// the NaN particle feels nothing.
#[test]
fn cluster_pass_conserves_momentum() {
    let (p, list, cutoff) = block(11);
    let n = p.len();
    for (lanes, eps) in [(Lanes::F64, 1e-12), (Lanes::F32, Real::from(f32::EPSILON))] {
        let c = reals(&cluster_bits(&p, &list, cutoff, lanes, 2));
        let total: Vec<Real> = (0..3).map(|d| (0..n).map(|i| c[3 * i + d]).sum()).collect();
        let scale: Real = c[..3 * n].iter().map(|v| v.abs()).sum();
        assert!(
            total.iter().all(|t| t.abs() <= eps * scale),
            "{lanes:?}: {total:?}"
        );
        assert_eq!(&c[60..63], &[0.0; 3], "NaN particle");
    }
}

/// The same bits at one, two and three threads, in both precisions.
#[test]
fn cluster_pass_is_the_same_at_any_thread_count() {
    let (p, list, cutoff) = block(15);
    for lanes in [Lanes::F64, Lanes::F32] {
        let one = cluster_bits(&p, &list, cutoff, lanes, 1);
        assert_eq!(one, cluster_bits(&p, &list, cutoff, lanes, 2), "{lanes:?}");
        assert_eq!(one, cluster_bits(&p, &list, cutoff, lanes, 3), "{lanes:?}");
    }
}
