//! One tile of the cluster kernel: a cluster of [`CLUSTER`] particles
//! against another, `CLUSTER x CLUSTER` pairs of the tapered 12-6
//! Lennard-Jones potential (seed 002 §3, [`LennardJones`]) computed
//! branch-free in lanes of `f64` or `f32`.

use std::ops::{Add, Div, Mul, Sub};

use crate::interactions::LennardJones;
use crate::math::{Real, Vec3};
use crate::neighbours::CLUSTER;

/// Pairs in a tile.
pub(super) const TILE: usize = CLUSTER * CLUSTER;

/// A lane type of the tile: `f64` or `f32`.
pub(crate) trait Lane:
    'static
    + Copy
    + Send
    + Sync
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
{
    const NAN: Self;
    /// `x` rounded to the lane type.
    fn of(x: Real) -> Self;
    /// The lane value as a `Real` (exact).
    fn real(self) -> Real;
    #[cfg(test)]
    fn sqrt(self) -> Self;
    /// The tile kernel of this lane type: [`tile_f32`] for `f32`, the
    /// plain `tile` for `f64` (tests only).
    fn tile<'j, S: pulp::Simd, const SELF: bool>(
        simd: S,
        c: &Constants<Self>,
        xi: &[[Self; TILE]; 3],
        xj: [&[Self; TILE]; 3],
        s: &mut Sums16<Self>,
        partner: impl FnOnce() -> &'j mut Lanes3<Self>,
    ) -> bool;
}

/// `f64` lanes: the tests' exact check of the cluster machinery against
/// the row kernel (the world runs the row kernel in double precision).
#[cfg(test)]
impl Lane for f64 {
    const NAN: Self = f64::NAN;
    #[inline(always)]
    fn of(x: Real) -> Self {
        x
    }
    #[inline(always)]
    fn real(self) -> Real {
        self
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn tile<'j, S: pulp::Simd, const SELF: bool>(
        _: S,
        c: &Constants<Self>,
        xi: &[[Self; TILE]; 3],
        xj: [&[Self; TILE]; 3],
        s: &mut Sums16<Self>,
        partner: impl FnOnce() -> &'j mut Lanes3<Self>,
    ) -> bool {
        tile::<f64, SELF>(c, xi, xj, s, partner)
    }
}

impl Lane for f32 {
    const NAN: Self = f32::NAN;
    #[inline(always)]
    fn of(x: Real) -> Self {
        x as f32
    }
    #[inline(always)]
    fn real(self) -> Real {
        Real::from(self)
    }
    #[cfg(test)]
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn tile<'j, S: pulp::Simd, const SELF: bool>(
        simd: S,
        c: &Constants<Self>,
        xi: &[[Self; TILE]; 3],
        xj: [&[Self; TILE]; 3],
        s: &mut Sums16<Self>,
        partner: impl FnOnce() -> &'j mut Lanes3<Self>,
    ) -> bool {
        tile_f32::<S, SELF>(simd, c, xi, xj, s, partner)
    }
}

/// The constants of [`LennardJones::eval_sq_12_6_select`] in lanes of `F`,
/// and the squared cut-off.
#[derive(Clone, Copy)]
pub(crate) struct Constants<F> {
    r0_sq: F,
    c_n: F,
    c_m: F,
    c_g: F,
    r_on_sq: F,
    rc_sq: F,
    r_on: F,
    inv_width: F,
    cutoff2: F,
}

impl<F: Lane> Constants<F> {
    pub(super) fn of(lj: &LennardJones, cutoff2: Real) -> Self {
        let c = lj.lane_constants();
        Constants {
            r0_sq: F::of(c.r0_sq),
            c_n: F::of(c.c_n),
            c_m: F::of(c.c_m),
            c_g: F::of(c.c_g),
            r_on_sq: F::of(c.r_on_sq),
            rc_sq: F::of(c.rc_sq),
            r_on: F::of(c.r_on),
            inv_width: F::of(c.inv_width),
            cutoff2: F::of(cutoff2),
        }
    }
}

#[cfg(test)]
#[inline(always)]
fn pick<F: Copy>(m: bool, a: F, b: F) -> F {
    if m {
        a
    } else {
        b
    }
}

/// One pair of a tile: `(U, U'(r)/r)` of the tapered 12-6 potential at
/// squared distance `d2`, and whether the pair contributes (not beyond
/// the cut-off, coincident or NaN; zeros where it does not). The operations of
/// [`LennardJones::eval_sq_12_6_select`] and the taper's select form, in
/// order, every case computed. The plain tile's pair (tests only).
#[cfg(test)]
#[inline(always)]
fn lj_pair<F: Lane>(c: &Constants<F>, d2: F) -> (F, F, bool) {
    let zero = F::of(0.0);
    let one = F::of(1.0);
    let valid = (d2 <= c.cutoff2) & (d2 > zero);
    let d2 = pick(valid, d2, one);
    let inv = one / d2;
    let x2 = c.r0_sq * inv;
    let x6 = x2 * x2 * x2;
    let (xn, xm) = (x6 * x6, x6);
    let u = c.c_n * xn - c.c_m * xm;
    let g = c.c_g * (xm - xn) * x2;
    let r = d2.sqrt();
    // The taper s(x), x = (r - r_on) / width (`cutoff::Taper`).
    let x = (r - c.r_on) * c.inv_width;
    let y = one - x;
    let y2 = y * y;
    let s = y2 * y * (F::of(10.0) - F::of(15.0) * y + F::of(6.0) * y2);
    let ds = F::of(-30.0) * x * x * y2;
    let (low, high) = (x <= zero, x >= one);
    let s = pick(low, one, pick(high, zero, s));
    let ds = pick(low, zero, pick(high, zero, ds));
    let before = r <= c.r_on;
    let s = pick(before, one, s);
    let ds = pick(before, zero, ds * c.inv_width);
    let (ut, gt) = (u * s, g * s + u * ds * (r * inv));
    let (outside, inner) = (d2 >= c.rc_sq, d2 <= c.r_on_sq);
    let u = pick(inner, u, ut);
    let g = pick(inner, g, gt);
    let keep = valid & !outside;
    (pick(keep, u, zero), pick(keep, g, zero), keep)
}

/// Per-lane sums of one cluster's row: force components and energy of
/// each of its `CLUSTER` particles against each lane of the partner.
pub(crate) struct Sums16<F> {
    fx: [F; TILE],
    fy: [F; TILE],
    fz: [F; TILE],
    e: [F; TILE],
}

impl<F: Lane> Sums16<F> {
    pub(super) fn zero() -> Self {
        let z = [F::of(0.0); TILE];
        Sums16 {
            fx: z,
            fy: z,
            fz: z,
            e: z,
        }
    }

    /// The sums of particle `a` of the cluster: its lanes, in `Real`,
    /// added pairwise.
    #[inline(always)]
    pub(super) fn particle(&self, a: usize) -> (Vec3, Real) {
        let lanes = |v: &[F; TILE]| {
            let l = &v[CLUSTER * a..CLUSTER * (a + 1)];
            (l[0].real() + l[1].real()) + (l[2].real() + l[3].real())
        };
        (
            Vec3::new(lanes(&self.fx), lanes(&self.fy), lanes(&self.fz)),
            lanes(&self.e),
        )
    }
}

/// The force on each particle of a partner cluster from one tile,
/// `[x; CLUSTER], [y; CLUSTER], [z; CLUSTER]`.
pub(crate) type PartnerForces = [Real; 3 * CLUSTER];

/// Adds the tile of cluster `i` (its own side `xi`,
/// [`super::coords::ClusterCoords::own`]) against the partner side `xj`:
/// lane `CLUSTER * a + b` is the pair (particle `a` of `i`, particle `b`
/// of `j`), the force on `a` being `(x_b - x_a) U'/r`. Adds each lane's
/// force and energy to `s` and, for a tile of two clusters (`SELF`
/// false), subtracts each lane's force from the partner's lanes
/// (`partner`); for the cluster against itself (`SELF`, every pair in two
/// lanes) half of each energy and nothing for the partner. Returns false,
/// having added nothing, when no lane is within the cut-off. Plain Rust
/// in any lane type: the oracle of [`tile_f32`] and the `f64` lanes of
/// the tests.
#[cfg(test)]
#[inline(always)]
fn tile<'j, F: Lane, const SELF: bool>(
    c: &Constants<F>,
    xi: &[[F; TILE]; 3],
    xj: [&[F; TILE]; 3],
    s: &mut Sums16<F>,
    partner: impl FnOnce() -> &'j mut Lanes3<F>,
) -> bool {
    let zero = F::of(0.0);
    let mut dx = [zero; TILE];
    let mut dy = [zero; TILE];
    let mut dz = [zero; TILE];
    let mut d2 = [zero; TILE];
    let mut near = false;
    for k in 0..TILE {
        dx[k] = xj[0][k] - xi[0][k];
        dy[k] = xj[1][k] - xi[1][k];
        dz[k] = xj[2][k] - xi[2][k];
        // `r.norm_squared()` as nalgebra sums it: (x² + y²) + z².
        d2[k] = dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k];
        near |= d2[k] <= c.cutoff2;
    }
    // The list holds pairs within cut-off + skin: a tile without a pair
    // within the cut-off at this step would add only zeros.
    if !near {
        return false;
    }
    // The pairs in the lane type, then each lane's force and energy
    // converted to `Real` and added (separate loops, each of which the
    // compiler vectorizes cleanly).
    let mut px = [zero; TILE];
    let mut py = [zero; TILE];
    let mut pz = [zero; TILE];
    let mut pu = [zero; TILE];
    for k in 0..TILE {
        // A NaN coordinate (a padding slot) times a zero g is NaN: the
        // force is selected, not only g.
        let (u, g, keep) = lj_pair(c, d2[k]);
        px[k] = pick(keep, dx[k] * g, zero);
        py[k] = pick(keep, dy[k] * g, zero);
        pz[k] = pick(keep, dz[k] * g, zero);
        pu[k] = u;
    }
    accumulate::<F, SELF>(s, &px, &py, &pz, &pu, partner);
    true
}

/// Adds a tile's lanes (forces `p*` on the own particles, energies `pu`)
/// to the row sums `s`, and for a tile of two clusters their negatives to
/// the partner's lanes (`partner`, summed over the block's tiles and
/// reduced once, [`Lanes3::reduce`]).
#[inline(always)]
fn accumulate<'j, F: Lane, const SELF: bool>(
    s: &mut Sums16<F>,
    px: &[F; TILE],
    py: &[F; TILE],
    pz: &[F; TILE],
    pu: &[F; TILE],
    partner: impl FnOnce() -> &'j mut Lanes3<F>,
) {
    let half = F::of(0.5);
    for k in 0..TILE {
        s.fx[k] = s.fx[k] + px[k];
        s.fy[k] = s.fy[k] + py[k];
        s.fz[k] = s.fz[k] + pz[k];
        s.e[k] = s.e[k] + if SELF { half * pu[k] } else { pu[k] };
    }
    if !SELF {
        let j = partner();
        for k in 0..TILE {
            j.x[k] = j.x[k] - px[k];
            j.y[k] = j.y[k] - py[k];
            j.z[k] = j.z[k] - pz[k];
        }
    }
}

/// The partner-side sums of one cluster over a block's tiles, unreduced:
/// lane `CLUSTER * a + b` holds the forces on its particle `b` from the
/// particles `a` of the visiting clusters.
#[derive(Clone, Copy)]
pub(crate) struct Lanes3<F> {
    x: [F; TILE],
    y: [F; TILE],
    z: [F; TILE],
}

impl<F: Lane> Lanes3<F> {
    pub(super) fn zero() -> Self {
        let z = [F::of(0.0); TILE];
        Lanes3 { x: z, y: z, z }
    }

    /// The force on each particle `b`: its four lanes added pairwise
    /// (`a` = 0 + 2, 1 + 3, then the two), widened to `Real`.
    pub(super) fn reduce(&self) -> PartnerForces {
        let mut out = [0.0; 3 * CLUSTER];
        for (d, p) in [&self.x, &self.y, &self.z].into_iter().enumerate() {
            for b in 0..CLUSTER {
                let lo = p[b] + p[2 * CLUSTER + b];
                let hi = p[CLUSTER + b] + p[3 * CLUSTER + b];
                out[CLUSTER * d + b] = (lo + hi).real();
            }
        }
        out
    }
}

/// The tile for `f32` lanes in explicit SIMD of the instruction set `S`:
/// the plain `tile` (tests) in the same operations and order, so the same
/// bits; the compiler's own vectorization of that plain code kept `f32`
/// at 256 bits on AVX-512.
#[inline(always)]
fn tile_f32<'j, S: pulp::Simd, const SELF: bool>(
    simd: S,
    c: &Constants<f32>,
    xi: &[[f32; TILE]; 3],
    xj: [&[f32; TILE]; 3],
    s: &mut Sums16<f32>,
    partner: impl FnOnce() -> &'j mut Lanes3<f32>,
) -> bool {
    let mut dx = [0.0f32; TILE];
    let mut dy = [0.0f32; TILE];
    let mut dz = [0.0f32; TILE];
    let mut d2 = [0.0f32; TILE];
    let cut = simd.splat_f32s(c.cutoff2);
    let mut near = simd.less_than_f32s(cut, cut);
    {
        let (ix, _) = S::as_simd_f32s(&xi[0]);
        let (iy, _) = S::as_simd_f32s(&xi[1]);
        let (iz, _) = S::as_simd_f32s(&xi[2]);
        let (jx, _) = S::as_simd_f32s(xj[0]);
        let (jy, _) = S::as_simd_f32s(xj[1]);
        let (jz, _) = S::as_simd_f32s(xj[2]);
        let (vx, _) = S::as_mut_simd_f32s(&mut dx);
        let (vy, _) = S::as_mut_simd_f32s(&mut dy);
        let (vz, _) = S::as_mut_simd_f32s(&mut dz);
        let (v2, _) = S::as_mut_simd_f32s(&mut d2);
        for v in 0..vx.len() {
            let x = simd.sub_f32s(jx[v], ix[v]);
            let y = simd.sub_f32s(jy[v], iy[v]);
            let z = simd.sub_f32s(jz[v], iz[v]);
            let r2 = simd.add_f32s(
                simd.add_f32s(simd.mul_f32s(x, x), simd.mul_f32s(y, y)),
                simd.mul_f32s(z, z),
            );
            near = simd.or_m32s(near, simd.less_than_or_equal_f32s(r2, cut));
            (vx[v], vy[v], vz[v], v2[v]) = (x, y, z, r2);
        }
    }
    if simd.first_true_m32s(near) >= S::F32_LANES {
        return false;
    }
    let mut px = [0.0f32; TILE];
    let mut py = [0.0f32; TILE];
    let mut pz = [0.0f32; TILE];
    let mut pu = [0.0f32; TILE];
    {
        let k = |x: f32| simd.splat_f32s(x);
        let (zero, one) = (k(0.0), k(1.0));
        let (vx, _) = S::as_simd_f32s(&dx);
        let (vy, _) = S::as_simd_f32s(&dy);
        let (vz, _) = S::as_simd_f32s(&dz);
        let (v2, _) = S::as_simd_f32s(&d2);
        let (ox, _) = S::as_mut_simd_f32s(&mut px);
        let (oy, _) = S::as_mut_simd_f32s(&mut py);
        let (oz, _) = S::as_mut_simd_f32s(&mut pz);
        let (ou, _) = S::as_mut_simd_f32s(&mut pu);
        for v in 0..vx.len() {
            let (add, sub, mul) = (
                |a, b| simd.add_f32s(a, b),
                |a, b| simd.sub_f32s(a, b),
                |a, b| simd.mul_f32s(a, b),
            );
            let sel = |m, a, b| simd.select_f32s(m, a, b);
            let d2 = v2[v];
            let valid = simd.and_m32s(
                simd.less_than_or_equal_f32s(d2, cut),
                simd.greater_than_f32s(d2, zero),
            );
            let d2 = sel(valid, d2, one);
            let inv = simd.div_f32s(one, d2);
            let x2 = mul(k(c.r0_sq), inv);
            let x6 = mul(mul(x2, x2), x2);
            let (xn, xm) = (mul(x6, x6), x6);
            let u = sub(mul(k(c.c_n), xn), mul(k(c.c_m), xm));
            let g = mul(mul(k(c.c_g), sub(xm, xn)), x2);
            let r = simd.sqrt_f32s(d2);
            let x = mul(sub(r, k(c.r_on)), k(c.inv_width));
            let y = sub(one, x);
            let y2 = mul(y, y);
            let sm = mul(
                mul(y2, y),
                add(sub(k(10.0), mul(k(15.0), y)), mul(k(6.0), y2)),
            );
            let ds = mul(mul(mul(k(-30.0), x), x), y2);
            let (low, high) = (
                simd.less_than_or_equal_f32s(x, zero),
                simd.greater_than_or_equal_f32s(x, one),
            );
            let sm = sel(low, one, sel(high, zero, sm));
            let ds = sel(low, zero, sel(high, zero, ds));
            let before = simd.less_than_or_equal_f32s(r, k(c.r_on));
            let sm = sel(before, one, sm);
            let ds = sel(before, zero, mul(ds, k(c.inv_width)));
            let (ut, gt) = (mul(u, sm), add(mul(g, sm), mul(mul(u, ds), mul(r, inv))));
            let inner = simd.less_than_or_equal_f32s(d2, k(c.r_on_sq));
            let u = sel(inner, u, ut);
            let g = sel(inner, g, gt);
            // `valid & !(d2 >= rc²)` of `lj_pair`, without a mask negation
            // (a valid `d2` is not NaN).
            let keep = simd.and_m32s(valid, simd.less_than_f32s(d2, k(c.rc_sq)));
            ox[v] = sel(keep, mul(vx[v], g), zero);
            oy[v] = sel(keep, mul(vy[v], g), zero);
            oz[v] = sel(keep, mul(vz[v], g), zero);
            ou[v] = sel(keep, u, zero);
        }
    }
    accumulate::<f32, SELF>(s, &px, &py, &pz, &pu, partner);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::pass_bits::lj_12_6_material;
    use crate::interactions::test_support::Rng;

    /// Both tiles of one pair of clusters, at the best instruction set:
    /// the explicit `f32` SIMD one and the plain one in `f32` lanes.
    struct Both<'a> {
        c: &'a Constants<f32>,
        xi: &'a [[f32; TILE]; 3],
        xj: [&'a [f32; TILE]; 3],
    }

    type Out = (bool, Vec<u32>);

    impl pulp::WithSimd for Both<'_> {
        type Output = [Out; 2];
        fn with_simd<S: pulp::Simd>(self, simd: S) -> [Out; 2] {
            let run = |explicit: bool| {
                let (mut s, mut j) = (Sums16::zero(), Lanes3::zero());
                let near = if explicit {
                    tile_f32::<S, false>(simd, self.c, self.xi, self.xj, &mut s, || &mut j)
                } else {
                    tile::<f32, false>(self.c, self.xi, self.xj, &mut s, || &mut j)
                };
                let bits = [s.fx, s.fy, s.fz, s.e, j.x, j.y, j.z]
                    .iter()
                    .flatten()
                    .map(|v| v.to_bits())
                    .collect();
                (near, bits)
            };
            [run(true), run(false)]
        }
    }

    /// The explicit `f32` SIMD tile gives the plain tile's bits: random
    /// clusters across the taper and beyond the cut-off, with a padding
    /// (NaN) slot and a coincident pair; far tiles add nothing in both.
    #[test]
    fn explicit_simd_tile_equals_the_plain_tile_bit_for_bit() {
        let lj = lj_12_6_material();
        let cutoff = lj.cutoff();
        let c = Constants::<f32>::of(lj.lennard_jones_12_6().unwrap(), cutoff * cutoff);
        let mut rng = Rng::new(0x5eed);
        let (mut near, mut far) = (0, 0);
        for case in 0..400 {
            // Every fourth partner sits 2 to 8 away: some tiles far.
            let (spread, shift) = if case % 4 == 0 {
                (2.5, 2.0 + 6.0 * rng.uniform())
            } else {
                (2.5, 0.0)
            };
            let mut own = [[0.0f32; CLUSTER]; 3];
            let mut xj = [[0.0f32; TILE]; 3];
            for d in 0..3 {
                for o in own[d].iter_mut() {
                    *o = (spread * rng.uniform()) as f32;
                }
                for k in 0..TILE {
                    xj[d][k] = xj[d][k % CLUSTER];
                    if k < CLUSTER {
                        let x = spread * rng.uniform() + if d == 0 { shift } else { 0.0 };
                        xj[d][k] = x as f32;
                    }
                }
            }
            if case % 5 == 1 {
                // A padding slot of the partner, and a coincident pair.
                for k in (3..TILE).step_by(CLUSTER) {
                    xj[0][k] = f32::NAN;
                }
                for d in 0..3 {
                    for k in (0..TILE).step_by(CLUSTER) {
                        xj[d][k] = own[d][1];
                    }
                }
            }
            let xi: [[f32; TILE]; 3] =
                std::array::from_fn(|d| std::array::from_fn(|k| own[d][k / CLUSTER]));
            let [a, b] = pulp::Arch::new().dispatch(Both {
                c: &c,
                xi: &xi,
                xj: [&xj[0], &xj[1], &xj[2]],
            });
            assert_eq!(a, b, "case {case}");
            if a.0 {
                near += 1;
            } else {
                far += 1;
                assert!(a.1.iter().all(|&v| v == 0), "a far tile added something");
            }
        }
        assert!(near > 200 && far > 20, "{near} near, {far} far tiles");
    }
}
