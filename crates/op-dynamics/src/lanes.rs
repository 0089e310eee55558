//! Pairs in SIMD lanes with runtime CPU-feature dispatch.
//!
//! A neighbour row `i: j0 j1 ...` is evaluated `LANES` pairs at a time:
//! the positions of the `j` are gathered into lane arrays, the potential is
//! evaluated branch-free in every lane (each case computed, the result
//! selected), and the per-pair results are written to a row buffer that
//! the accumulation ([`crate::forces`]) then adds in the row's order,
//! exactly as it adds the scalar kernel's results.
//!
//! **Dispatch.** The lane loop is compiled once per instruction set that
//! [`pulp::Arch`] knows (x86-64: AVX-512 "v4", AVX2 + FMA "v3", and the
//! baseline) and the best one the CPU has is chosen at run time
//! ([`isa`] names it). The lane code is plain Rust inlined into pulp's
//! `#[target_feature]` instances, so the compiler vectorizes it with the
//! wide registers; no `unsafe` in this crate.
//!
//! **Bits.** The lane code performs the scalar kernel's operations in the
//! same order and never fuses a multiply-add (Rust does not contract
//! floating-point expressions), so every instruction set gives the same
//! bits as the scalar kernel: results are identical across thread counts
//! *and* across machines. The cost of that choice is the FMA instructions
//! left unused (a multiply and an add instead of one instruction); the
//! division and the square root per pair, which FMA does not remove,
//! dominate the lane's latency.

use crate::interactions::LennardJones;
use crate::math::{Point3, Real, Vec3};

mod oriented;
pub(crate) use oriented::{
    oriented_row, OrientedInput, OrientedLaneConstants, OrientedRow, WeightLaneConstants,
};

/// Pairs per lane batch: one AVX-512 register of `f64`, two AVX2 ones.
pub(crate) const LANES: usize = 8;

/// The instruction-set level the dispatched lane kernels run with on this
/// CPU: `"x86-64-v4 (AVX-512)"`, `"x86-64-v3 (AVX2, FMA)"` or
/// `"scalar"` (baseline, or a non-x86 target).
pub fn isa() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        match pulp::Arch::new() {
            pulp::Arch::V4(_) => "x86-64-v4 (AVX-512)",
            pulp::Arch::V3(_) => "x86-64-v3 (AVX2, FMA)",
            _ => "scalar",
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        "scalar"
    }
}

/// One row's per-pair results from the lanes: the force on `j`, the pair
/// energy and the squared distance. Indexed like the row; sized to a whole
/// number of lane batches.
#[derive(Default)]
pub(crate) struct RowLanes {
    fx: Vec<Real>,
    fy: Vec<Real>,
    fz: Vec<Real>,
    energy: Vec<Real>,
    d2: Vec<Real>,
}

impl RowLanes {
    /// The result of the `k`-th pair of the row: `(force on j, energy)`,
    /// `None` when the pair contributes nothing (beyond `cutoff2`,
    /// coincident, or NaN: the scalar pair's test).
    #[inline(always)]
    pub fn get(&self, k: usize, cutoff2: Real) -> Option<(Vec3, Real)> {
        self.kept(k, cutoff2).then(|| self.get_or_zero(k))
    }

    /// Whether the `k`-th pair contributes (the test of [`Self::get`]),
    /// without a branch.
    #[inline(always)]
    pub fn kept(&self, k: usize, cutoff2: Real) -> bool {
        let d2 = self.d2[k];
        (d2 <= cutoff2) & (d2 > 0.0)
    }

    /// The result of the `k`-th pair, `(+0, +0)` when it contributes
    /// nothing (the lanes store zeros there).
    #[inline(always)]
    pub fn get_or_zero(&self, k: usize) -> (Vec3, Real) {
        (
            Vec3::new(self.fx[k], self.fy[k], self.fz[k]),
            self.energy[k],
        )
    }

    /// The accumulation's in-block pairs of the row (its first
    /// `row.len()` pairs, every second particle in the block starting at
    /// `b0`): in row order, subtracts each pair's force from the row's
    /// running sum and adds its energy (both starting from zero), and adds
    /// the force to the second particle's slot of `local`; returns the
    /// sums. The additions of the pair-by-pair loop of
    /// `forces::accumulate`, in its order, over slices (no bounds check
    /// per pair). Not inlined: inlined into the block loop, whose spill
    /// pushes may call the allocator, the running sums were kept in stack
    /// slots, a store-to-load chain per pair.
    #[inline(never)]
    pub fn add_in_block(&self, row: &[u32], b0: usize, local: &mut [Vec3]) -> (Vec3, Real) {
        let m = row.len();
        let (fx, fy, fz, en) = (
            &self.fx[..m],
            &self.fy[..m],
            &self.fz[..m],
            &self.energy[..m],
        );
        let (mut fo, mut eo) = (Vec3::zeros(), 0.0);
        for ((((&j, &x), &y), &z), &e) in row.iter().zip(fx).zip(fy).zip(fz).zip(en) {
            let fj = Vec3::new(x, y, z);
            fo -= fj;
            eo += e;
            local[j as usize - b0] += fj;
        }
        (fo, eo)
    }

    fn resize(&mut self, n: usize) {
        let n = n.div_ceil(LANES) * LANES;
        if self.fx.len() < n {
            self.fx.resize(n, 0.0);
            self.fy.resize(n, 0.0);
            self.fz.resize(n, 0.0);
            self.energy.resize(n, 0.0);
            self.d2.resize(n, 0.0);
        }
    }
}

/// The 12-6 Lennard-Jones spacing of the uniform spacing kernel on one
/// row, dispatched to the best instruction set (see the module docs):
/// fills `out` for the pairs `(i, row[k])`. Per pair the same bits as the
/// scalar `forces::uniform_spacing_pass` pair with
/// [`LennardJones::eval_sq_12_6`].
pub(crate) fn lj_12_6_row(
    arch: pulp::Arch,
    lj: &LennardJones,
    cutoff2: Real,
    p: &[Point3],
    i: usize,
    row: &[u32],
    out: &mut RowLanes,
) {
    out.resize(row.len());
    arch.dispatch(LjRow {
        lj,
        cutoff2,
        p,
        i,
        row,
        out,
    });
}

/// The arguments of [`lj_12_6_lanes`], as the operation pulp dispatches.
struct LjRow<'a> {
    lj: &'a LennardJones,
    cutoff2: Real,
    p: &'a [Point3],
    i: usize,
    row: &'a [u32],
    out: &'a mut RowLanes,
}

impl pulp::WithSimd for LjRow<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        lj_12_6_lanes(
            simd,
            self.lj,
            self.cutoff2,
            self.p,
            self.i,
            self.row,
            self.out,
        );
    }
}

/// The lane loop of [`lj_12_6_row`] for one instruction set `S` (inlined
/// into its `#[target_feature]` instance): gathers `LANES` neighbours, then
/// evaluates them `S::F64_LANES` at a time.
#[inline(always)]
fn lj_12_6_lanes<S: pulp::Simd>(
    simd: S,
    lj: &LennardJones,
    cutoff2: Real,
    p: &[Point3],
    i: usize,
    row: &[u32],
    out: &mut RowLanes,
) {
    let c = lj.lane_constants();
    let pi = p[i];
    let n = row.len();
    let mut k0 = 0;
    while k0 < n {
        let mut dx = [0.0; LANES];
        let mut dy = [0.0; LANES];
        let mut dz = [0.0; LANES];
        // Gather; lanes past the row's end repeat its last pair and are
        // never read.
        for l in 0..LANES {
            let j = row[(k0 + l).min(n - 1)] as usize;
            let q = p[j];
            dx[l] = q.x - pi.x;
            dy[l] = q.y - pi.y;
            dz[l] = q.z - pi.z;
        }
        let (dx, _) = S::as_simd_f64s(&dx);
        let (dy, _) = S::as_simd_f64s(&dy);
        let (dz, _) = S::as_simd_f64s(&dz);
        let (fx, _) = S::as_mut_simd_f64s(&mut out.fx[k0..k0 + LANES]);
        let (fy, _) = S::as_mut_simd_f64s(&mut out.fy[k0..k0 + LANES]);
        let (fz, _) = S::as_mut_simd_f64s(&mut out.fz[k0..k0 + LANES]);
        let (en, _) = S::as_mut_simd_f64s(&mut out.energy[k0..k0 + LANES]);
        let (sq, _) = S::as_mut_simd_f64s(&mut out.d2[k0..k0 + LANES]);
        for v in 0..dx.len() {
            let (x, y, z) = (dx[v], dy[v], dz[v]);
            // The scalar pair's `r.norm_squared()`: (x² + y²) + z².
            let d2 = simd.add_f64s(
                simd.add_f64s(simd.mul_f64s(x, x), simd.mul_f64s(y, y)),
                simd.mul_f64s(z, z),
            );
            // Coincident (d2 = 0), NaN and beyond-cut-off pairs contribute
            // nothing (`RowLanes::get`); their lanes compute on a stand-in.
            let valid = L(simd).in_range(d2, cutoff2);
            let one = simd.splat_f64s(1.0);
            let d2s = simd.select_f64s(valid, d2, one);
            let (u, g) = lj_12_6(simd, &c, d2s, simd.div_f64s(one, d2s));
            let ng = simd.neg_f64s(g);
            let zero = simd.splat_f64s(0.0);
            fx[v] = simd.select_f64s(valid, simd.mul_f64s(x, ng), zero);
            fy[v] = simd.select_f64s(valid, simd.mul_f64s(y, ng), zero);
            fz[v] = simd.select_f64s(valid, simd.mul_f64s(z, ng), zero);
            en[v] = simd.select_f64s(valid, u, zero);
            sq[v] = d2;
        }
        k0 += LANES;
    }
}

/// [`LennardJones::eval_sq_12_6`] on `S::F64_LANES` pairs: the operations
/// of [`LennardJones::eval_sq_12_6_select`] in the same order, cases
/// selected.
#[inline(always)]
fn lj_12_6<S: pulp::Simd>(
    simd: S,
    c: &LjLaneConstants,
    d2: S::f64s,
    inv_d2: S::f64s,
) -> (S::f64s, S::f64s) {
    let l = L(simd);
    let zero = l.k(0.0);
    let x2 = l.mul(l.k(c.r0_sq), inv_d2);
    let x6 = l.mul(l.mul(x2, x2), x2);
    let (xn, xm) = (l.mul(x6, x6), x6);
    let u = l.sub(l.mul(l.k(c.c_n), xn), l.mul(l.k(c.c_m), xm));
    let g = l.mul(l.mul(l.k(c.c_g), l.sub(xm, xn)), x2);
    let r = simd.sqrt_f64s(d2);
    let (s, ds) = taper(simd, r, c.r_on, c.inv_width);
    let ut = l.mul(u, s);
    let gt = l.add(l.mul(g, s), l.mul(l.mul(u, ds), l.mul(r, inv_d2)));
    let inner = simd.less_than_or_equal_f64s(d2, l.k(c.r_on_sq));
    let outside = simd.greater_than_or_equal_f64s(d2, l.k(c.rc_sq));
    let u = simd.select_f64s(inner, u, ut);
    let g = simd.select_f64s(inner, g, gt);
    (
        simd.select_f64s(outside, zero, u),
        simd.select_f64s(outside, zero, g),
    )
}

/// The taper `(s(r), ds/dr)` of [`crate::interactions::cutoff::Taper`]
/// starting at `r_on`, `1/(r_c - r_on) = inv_width`, on `S::F64_LANES`
/// distances: the operations of `Taper::eval_select` and
/// `smooth_fall_select` in the same order, cases selected.
#[inline(always)]
fn taper<S: pulp::Simd>(simd: S, r: S::f64s, r_on: Real, inv_width: Real) -> (S::f64s, S::f64s) {
    let l = L(simd);
    let zero = l.k(0.0);
    let x = l.mul(l.sub(r, l.k(r_on)), l.k(inv_width));
    let y = l.sub(l.k(1.0), x);
    let y2 = l.mul(y, y);
    let s = l.mul(
        l.mul(y2, y),
        l.add(l.sub(l.k(10.0), l.mul(l.k(15.0), y)), l.mul(l.k(6.0), y2)),
    );
    let ds = l.mul(l.mul(l.mul(l.k(-30.0), x), x), y2);
    let (low, high) = (
        simd.less_than_or_equal_f64s(x, zero),
        simd.greater_than_or_equal_f64s(x, l.k(1.0)),
    );
    let s = simd.select_f64s(high, zero, s);
    let s = simd.select_f64s(low, l.k(1.0), s);
    let ds = simd.select_f64s(high, zero, ds);
    let ds = simd.select_f64s(low, zero, ds);
    let before = simd.less_than_or_equal_f64s(r, l.k(r_on));
    let s = simd.select_f64s(before, l.k(1.0), s);
    let ds = simd.select_f64s(before, zero, l.mul(ds, l.k(inv_width)));
    (s, ds)
}

/// A vector of three lane vectors.
#[derive(Copy, Clone)]
struct V3<T> {
    x: T,
    y: T,
    z: T,
}

/// Lane arithmetic for one instruction set: the scalar kernel's
/// operations, one per method.
#[derive(Copy, Clone)]
struct L<S: pulp::Simd>(S);

impl<S: pulp::Simd> L<S> {
    #[inline(always)]
    fn k(self, x: Real) -> S::f64s {
        self.0.splat_f64s(x)
    }
    #[inline(always)]
    fn add(self, a: S::f64s, b: S::f64s) -> S::f64s {
        self.0.add_f64s(a, b)
    }
    #[inline(always)]
    fn sub(self, a: S::f64s, b: S::f64s) -> S::f64s {
        self.0.sub_f64s(a, b)
    }
    #[inline(always)]
    fn mul(self, a: S::f64s, b: S::f64s) -> S::f64s {
        self.0.mul_f64s(a, b)
    }
    #[inline(always)]
    fn div(self, a: S::f64s, b: S::f64s) -> S::f64s {
        self.0.div_f64s(a, b)
    }
    #[inline(always)]
    fn neg(self, a: S::f64s) -> S::f64s {
        self.0.neg_f64s(a)
    }
    #[inline(always)]
    fn sel(self, m: S::m64s, a: S::f64s, b: S::f64s) -> S::f64s {
        self.0.select_f64s(m, a, b)
    }
    /// The lanes whose pair contributes: `0 < d2 <= cutoff2` (coincident,
    /// NaN and beyond-cut-off pairs compute on a stand-in and add nothing).
    #[inline(always)]
    fn in_range(self, d2: S::f64s, cutoff2: Real) -> S::m64s {
        self.0.and_m64s(
            self.0.less_than_or_equal_f64s(d2, self.k(cutoff2)),
            self.0.greater_than_f64s(d2, self.k(0.0)),
        )
    }
    /// `a · b` as nalgebra sums it: `(a.x b.x + a.y b.y) + a.z b.z`.
    #[inline(always)]
    fn dot(self, a: V3<S::f64s>, b: V3<S::f64s>) -> S::f64s {
        self.add(
            self.add(self.mul(a.x, b.x), self.mul(a.y, b.y)),
            self.mul(a.z, b.z),
        )
    }
    #[inline(always)]
    fn cross(self, a: V3<S::f64s>, b: V3<S::f64s>) -> V3<S::f64s> {
        V3 {
            x: self.sub(self.mul(a.y, b.z), self.mul(a.z, b.y)),
            y: self.sub(self.mul(a.z, b.x), self.mul(a.x, b.z)),
            z: self.sub(self.mul(a.x, b.y), self.mul(a.y, b.x)),
        }
    }
    #[inline(always)]
    fn scale(self, a: V3<S::f64s>, s: S::f64s) -> V3<S::f64s> {
        V3 {
            x: self.mul(a.x, s),
            y: self.mul(a.y, s),
            z: self.mul(a.z, s),
        }
    }
    #[inline(always)]
    fn add3(self, a: V3<S::f64s>, b: V3<S::f64s>) -> V3<S::f64s> {
        V3 {
            x: self.add(a.x, b.x),
            y: self.add(a.y, b.y),
            z: self.add(a.z, b.z),
        }
    }
    #[inline(always)]
    fn sub3(self, a: V3<S::f64s>, b: V3<S::f64s>) -> V3<S::f64s> {
        V3 {
            x: self.sub(a.x, b.x),
            y: self.sub(a.y, b.y),
            z: self.sub(a.z, b.z),
        }
    }
}

/// The folded constants of a 12-6 [`LennardJones`] the lanes read.
#[derive(Copy, Clone, Debug)]
pub(crate) struct LjLaneConstants {
    pub r0_sq: Real,
    pub c_n: Real,
    pub c_m: Real,
    pub c_g: Real,
    pub r_on_sq: Real,
    pub rc_sq: Real,
    pub r_on: Real,
    pub inv_width: Real,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::LennardJonesParams;

    /// The dispatched lanes give the scalar pair's bits: every pair of a
    /// jittered block, across the taper and beyond the cut-off, with a
    /// coincident and a NaN neighbour, rows of every length mod `LANES`.
    #[test]
    fn dispatched_lanes_equal_the_scalar_pair_bit_for_bit() {
        let lj = LennardJonesParams {
            r0: (2.0 as Real).powf(1.0 / 6.0),
            taper: 0.1,
            ..Default::default()
        }
        .prepare()
        .unwrap();
        let cutoff2: Real = 2.5 * 2.5;
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as Real / (1u64 << 53) as Real
        };
        let mut p: Vec<Point3> = (0..200)
            .map(|_| Point3::new(4.0 * rnd(), 4.0 * rnd(), 4.0 * rnd()))
            .collect();
        p.push(p[0]);
        p.push(Point3::new(Real::NAN, 0.0, 0.0));
        let n = p.len();
        let mut out = RowLanes::default();
        let mut checked = 0;
        for i in [0, 1, 7, 50, 199] {
            for len in [1, 7, 8, 9, 17, n - i - 1] {
                let row: Vec<u32> = ((i + 1)..n).map(|j| j as u32).take(len).collect();
                let mut row = row;
                row.push((n - 2) as u32);
                row.push((n - 1) as u32);
                lj_12_6_row(pulp::Arch::new(), &lj, cutoff2, &p, i, &row, &mut out);
                for (k, &j) in row.iter().enumerate() {
                    let r = p[j as usize] - p[i];
                    let d2 = r.norm_squared();
                    let scalar = (d2 <= cutoff2 && d2 > 0.0).then(|| {
                        let (u, g) = lj.eval_sq_12_6(d2, 1.0 / d2);
                        (r * (-g), u)
                    });
                    let lanes = out.get(k, cutoff2);
                    let bits = |o: Option<(Vec3, Real)>| {
                        o.map(|(f, e)| [f.x, f.y, f.z, e].map(Real::to_bits))
                    };
                    assert_eq!(bits(scalar), bits(lanes), "pair ({i}, {j})");
                    checked += usize::from(scalar.is_some());
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn isa_names_a_level() {
        assert!(["x86-64-v4 (AVX-512)", "x86-64-v3 (AVX2, FMA)", "scalar"].contains(&isa()));
    }
}
