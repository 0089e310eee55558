//! The full oriented pair in SIMD lanes: both directions of a
//! pair of one material from one shared geometry (seed 000 eq. 11, App. B;
//! seed 002 §4-5), `LANES` pairs of a neighbour row at a time.
//!
//! Per pair it performs, in the same order and without fused
//! multiply-adds, the operations of the scalar kernel for a complete,
//! oriented pair of one material (`interactions::pair`'s
//! `evaluate_pair` with [`crate::interactions::PreparedMaterial`]'s
//! `direction` on both sides): the 12-6 Lennard-Jones spacing and its taper
//! ([`super::lj_12_6`]), the orientation weight `ψ` (seed 000 eq. 10) with
//! its taper, the co-planarity, co-normality, co-circularity and form
//! terms (seed 000 eq. 4-7; docs/model.md §3 for the normalized forms),
//! their fade near coincidence, and the torques of both directions. Every
//! case is computed and the result selected, so the lanes give the scalar
//! kernel's bits on any instruction set. The exponential of `ψ` is the
//! one operation not in the lanes: it is taken per pair with the scalar
//! `exp`, so it has exactly the scalar kernel's value.

use super::{lj_12_6, taper, LjLaneConstants, L, LANES, V3};
use crate::math::{Point3, Real, Vec3};

/// The constants of a prepared orientation weight the lanes read
/// ([`crate::interactions::Weight::eval_scalar`]).
#[derive(Copy, Clone, Debug)]
pub(crate) struct WeightLaneConstants {
    pub k: Real,
    pub inv_a2: Real,
    /// `1/2b² - 1/2a²` (0 for the isotropic shape).
    pub c: Real,
    pub anisotropic: bool,
    pub r_on: Real,
    pub inv_width: Real,
    pub cutoff: Real,
}

/// The constants of a material the oriented lanes evaluate: 12-6
/// Lennard-Jones spacing, the weight, the term weights, the coincidence
/// radius; no spin.
#[derive(Copy, Clone, Debug)]
pub(crate) struct OrientedLaneConstants {
    pub lj: LjLaneConstants,
    pub weight: WeightLaneConstants,
    pub normalized: bool,
    pub w_p: Real,
    pub w_n: Real,
    pub w_c: Real,
    pub w_f: Real,
    /// The coincidence radius `r_near` of the fade.
    pub near: Real,
}

/// One row's per-pair results from the oriented lanes: force on `j`,
/// torques on `i` and `j`, energy, and the squared distance. Indexed like
/// the row; sized to a whole number of lane batches.
#[derive(Default)]
pub(crate) struct OrientedRow {
    f: [Vec<Real>; 3],
    ti: [Vec<Real>; 3],
    tj: [Vec<Real>; 3],
    energy: Vec<Real>,
    d2: Vec<Real>,
}

/// One pair's result: force on `j`, torque on `i`, torque on `j`, energy.
pub(crate) type OrientedResult = (Vec3, Vec3, Vec3, Real);

impl OrientedRow {
    /// The result of the `k`-th pair of the row, `None` when the pair
    /// contributes nothing (beyond `cutoff2`; coincident and NaN pairs give
    /// zeros, as the scalar pair does).
    #[inline(always)]
    pub fn get(&self, k: usize, cutoff2: Real) -> Option<OrientedResult> {
        self.kept(k, cutoff2).then(|| self.get_or_zero(k))
    }

    /// Whether the `k`-th pair contributes (the test of [`Self::get`]),
    /// without a branch.
    #[inline(always)]
    pub fn kept(&self, k: usize, cutoff2: Real) -> bool {
        let d2 = self.d2[k];
        (d2 <= cutoff2) | d2.is_nan()
    }

    /// The result of the `k`-th pair, zeros when it contributes nothing.
    #[inline(always)]
    pub fn get_or_zero(&self, k: usize) -> OrientedResult {
        let v = |a: &[Vec<Real>; 3]| Vec3::new(a[0][k], a[1][k], a[2][k]);
        (v(&self.f), v(&self.ti), v(&self.tj), self.energy[k])
    }

    /// The accumulation's in-block pairs of the row (its first
    /// `row.len()` pairs, every second particle in the block starting at
    /// `b0`), as [`super::RowLanes::add_in_block`] with the torques: in
    /// row order, subtracts each pair's force from the row's running sum,
    /// adds its energy and its torque on `i`, and adds its force and its
    /// torque on `j` to `j`'s slots of `local_f` and `local_t`; returns the
    /// sums `(force, torque, energy)`. Not inlined, so that the sums stay
    /// in registers (see there).
    #[inline(never)]
    pub fn add_in_block(
        &self,
        row: &[u32],
        b0: usize,
        local_f: &mut [Vec3],
        local_t: &mut [Vec3],
    ) -> (Vec3, Vec3, Real) {
        let m = row.len();
        fn s(a: &[Vec<Real>; 3], m: usize) -> [&[Real]; 3] {
            [&a[0][..m], &a[1][..m], &a[2][..m]]
        }
        let (f, ti, tj) = (s(&self.f, m), s(&self.ti, m), s(&self.tj, m));
        let en = &self.energy[..m];
        let (mut fo, mut to, mut eo) = (Vec3::zeros(), Vec3::zeros(), 0.0);
        for (k, (&j, &e)) in row.iter().zip(en).enumerate() {
            let j = j as usize - b0;
            let fj = Vec3::new(f[0][k], f[1][k], f[2][k]);
            fo -= fj;
            eo += e;
            local_f[j] += fj;
            to += Vec3::new(ti[0][k], ti[1][k], ti[2][k]);
            local_t[j] += Vec3::new(tj[0][k], tj[1][k], tj[2][k]);
        }
        (fo, to, eo)
    }

    fn resize(&mut self, n: usize) {
        let n = n.div_ceil(LANES) * LANES;
        if self.energy.len() < n {
            for v in self.f.iter_mut().chain(&mut self.ti).chain(&mut self.tj) {
                v.resize(n, 0.0);
            }
            self.energy.resize(n, 0.0);
            self.d2.resize(n, 0.0);
        }
    }
}

/// What one row of the oriented lanes reads.
pub(crate) struct OrientedInput<'a> {
    pub c: &'a OrientedLaneConstants,
    pub cutoff2: Real,
    pub p: &'a [Point3],
    pub normals: &'a [Vec3],
    pub curvatures: &'a [Real],
}

/// The full oriented pair of one material on one row, dispatched to the
/// best instruction set ([`super`]): fills `out` for the pairs
/// `(i, row[k])`, with the scalar kernel's bits.
pub(crate) fn oriented_row(
    arch: pulp::Arch,
    input: &OrientedInput<'_>,
    i: usize,
    row: &[u32],
    out: &mut OrientedRow,
) {
    out.resize(row.len());
    arch.dispatch(Row { input, i, row, out });
}

struct Row<'a, 'b> {
    input: &'a OrientedInput<'b>,
    i: usize,
    row: &'a [u32],
    out: &'a mut OrientedRow,
}

impl pulp::WithSimd for Row<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        let n = self.row.len();
        let mut k0 = 0;
        while k0 < n {
            batch(simd, self.input, self.i, self.row, k0, self.out);
            k0 += LANES;
        }
    }
}

/// The per-lane inputs of one batch, gathered from the row.
struct Gathered {
    r: [[Real; LANES]; 3],
    n: [[Real; LANES]; 3],
    kappa: [Real; LANES],
}

/// Pairs `k0 .. k0 + LANES` of the row: gather, the weight's exponent in
/// the lanes, `exp` per pair, then the rest in the lanes.
#[inline(always)]
fn batch<S: pulp::Simd>(
    simd: S,
    input: &OrientedInput<'_>,
    i: usize,
    row: &[u32],
    k0: usize,
    out: &mut OrientedRow,
) {
    let l = L(simd);
    let c = input.c;
    let w = &c.weight;
    let (pi, ni) = (input.p[i], input.normals[i]);
    let n = row.len();
    let mut g = Gathered {
        r: [[0.0; LANES]; 3],
        n: [[0.0; LANES]; 3],
        kappa: [0.0; LANES],
    };
    // Lanes past the row's end repeat its last pair and are never read.
    for q in 0..LANES {
        let j = row[(k0 + q).min(n - 1)] as usize;
        let (pj, nj) = (input.p[j], input.normals[j]);
        g.r[0][q] = pj.x - pi.x;
        g.r[1][q] = pj.y - pi.y;
        g.r[2][q] = pj.z - pi.z;
        g.n[0][q] = nj.x;
        g.n[1][q] = nj.y;
        g.n[2][q] = nj.z;
        g.kappa[q] = input.curvatures[j];
    }
    // Stage 1: |r|², the stand-in for pairs that contribute nothing, and
    // the exponent of ψ on each side.
    let mut d2s = [0.0; LANES];
    let mut expo = [[0.0; LANES]; 2];
    let mut near_any = false;
    {
        let (rx, _) = S::as_simd_f64s(&g.r[0]);
        let (ry, _) = S::as_simd_f64s(&g.r[1]);
        let (rz, _) = S::as_simd_f64s(&g.r[2]);
        let (nx, _) = S::as_simd_f64s(&g.n[0]);
        let (ny, _) = S::as_simd_f64s(&g.n[1]);
        let (nz, _) = S::as_simd_f64s(&g.n[2]);
        let (d2o, _) = S::as_mut_simd_f64s(&mut d2s);
        let [e0, e1] = &mut expo;
        let (ei, _) = S::as_mut_simd_f64s(e0);
        let (ej, _) = S::as_mut_simd_f64s(e1);
        let niv = V3 {
            x: l.k(ni.x),
            y: l.k(ni.y),
            z: l.k(ni.z),
        };
        for v in 0..rx.len() {
            let r = V3 {
                x: rx[v],
                y: ry[v],
                z: rz[v],
            };
            let d2 = l.dot(r, r);
            d2o[v] = d2;
            let valid = l.in_range(d2, input.cutoff2);
            let d2 = l.sel(valid, d2, l.k(1.0));
            // `Weight::eval_scalar`: -d²/2a², minus c z² when anisotropic.
            let e = l.mul(l.mul(l.k(-0.5), d2), l.k(w.inv_a2));
            if w.anisotropic {
                let nj = V3 {
                    x: nx[v],
                    y: ny[v],
                    z: nz[v],
                };
                let zi = l.dot(niv, r);
                let zj = l.neg(l.dot(nj, r));
                ei[v] = l.sub(e, l.mul(l.mul(l.k(w.c), zi), zi));
                ej[v] = l.sub(e, l.mul(l.mul(l.k(w.c), zj), zj));
            } else {
                ei[v] = e;
            }
        }
    }
    // The fade near coincidence needs a division: only batches with a
    // pair that may be that close compute it (`|r|² < (1.01 r_near)²`
    // is a superset of `|r| < r_near`; the lanes then test `|r|` exactly).
    if c.normalized {
        let near2 = (1.01 * c.near) * (1.01 * c.near);
        near_any = d2s.iter().any(|&d2| d2 < near2);
    }
    // `ψ₀ = K exp(...)`, the scalar `exp` per pair.
    let sides = if w.anisotropic { 2 } else { 1 };
    let mut psi0 = [[0.0; LANES]; 2];
    for s in 0..sides {
        for q in 0..LANES {
            psi0[s][q] = w.k * expo[s][q].exp();
        }
    }
    stage_2(l, input, i, k0, &g, &psi0, near_any, out);
}

/// Stage 2 of [`batch`]: everything after `exp`, in the lanes.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn stage_2<S: pulp::Simd>(
    l: L<S>,
    input: &OrientedInput<'_>,
    i: usize,
    k0: usize,
    g: &Gathered,
    psi0: &[[Real; LANES]; 2],
    near_any: bool,
    out: &mut OrientedRow,
) {
    let simd = l.0;
    let c = input.c;
    let w = &c.weight;
    let (ni, kappa_i) = (input.normals[i], input.curvatures[i]);
    let niv = V3 {
        x: l.k(ni.x),
        y: l.k(ni.y),
        z: l.k(ni.z),
    };
    let (rx, _) = S::as_simd_f64s(&g.r[0]);
    let (ry, _) = S::as_simd_f64s(&g.r[1]);
    let (rz, _) = S::as_simd_f64s(&g.r[2]);
    let (nx, _) = S::as_simd_f64s(&g.n[0]);
    let (ny, _) = S::as_simd_f64s(&g.n[1]);
    let (nz, _) = S::as_simd_f64s(&g.n[2]);
    let (kj, _) = S::as_simd_f64s(&g.kappa);
    let (p0, _) = S::as_simd_f64s(&psi0[0]);
    let (p1, _) = S::as_simd_f64s(&psi0[1]);
    let mut o = OutLanes::<S>::new(out, k0);
    let one = l.k(1.0);
    for v in 0..rx.len() {
        let r = V3 {
            x: rx[v],
            y: ry[v],
            z: rz[v],
        };
        let nj = V3 {
            x: nx[v],
            y: ny[v],
            z: nz[v],
        };
        let d2 = l.dot(r, r);
        o.sq[v] = d2;
        let valid = l.in_range(d2, input.cutoff2);
        let d2 = l.sel(valid, d2, one);
        let inv_d2 = l.div(one, d2);
        // Spacing (`evaluate_spacing_sq`): U and the force on j, -g r.
        let (u, gs) = lj_12_6(simd, &c.lj, d2, inv_d2);
        let f_sp = l.scale(r, l.neg(gs));
        // The shared geometry (`oriented_terms`).
        let dist = simd.sqrt_f64s(d2);
        let on = simd.less_than_f64s(dist, l.k(w.cutoff));
        let inv_dist = l.mul(dist, inv_d2);
        let zi = l.dot(niv, r);
        let zj = l.dot(nj, r);
        let d = l.sub3(niv, nj);
        let dd = l.dot(d, d);
        // ψ and its gradient scalars on both sides (`Weight::eval_scalar`).
        let (ts, tds) = taper(simd, dist, w.r_on, w.inv_width);
        let wl = WeightLanes {
            ts,
            tds,
            inv_dist,
            on,
        };
        let wi = weight(l, w, &wl, p0[v], zi);
        let wj = if w.anisotropic {
            weight(l, w, &wl, p1[v], l.neg(zj))
        } else {
            wi
        };
        let (fs, fds) = fade(l, c, dist, near_any);
        let geo = Geometry {
            dist,
            inv_d2,
            dd,
            fs,
            fds,
        };
        let di = direction(l, c, &geo, zi, zj, r, d, l.k(kappa_i), wi);
        let dj = direction(l, c, &geo, l.neg(zj), l.neg(zi), r, d, kj[v], wj);
        let p = combine(l, r, niv, nj, u, f_sp, &di, &dj);
        o.store(l, v, valid, &p);
    }
}

/// The fade `(S, S')` of the normalized direction terms near coincidence:
/// computed only when some pair of the batch may be that close
/// (`near_any`), `(1, 0)` at and beyond `r_near`.
#[inline(always)]
fn fade<S: pulp::Simd>(
    l: L<S>,
    c: &OrientedLaneConstants,
    dist: S::f64s,
    near_any: bool,
) -> (S::f64s, S::f64s) {
    let simd = l.0;
    let zero = l.k(0.0);
    let one = l.k(1.0);
    if near_any {
        let close = simd.less_than_f64s(dist, l.k(c.near));
        let x = l.div(dist, l.k(c.near));
        let y = l.sub(one, x);
        let s = l.mul(
            l.mul(l.mul(x, x), x),
            l.add(
                l.sub(l.k(10.0), l.mul(l.k(15.0), x)),
                l.mul(l.mul(l.k(6.0), x), x),
            ),
        );
        let ds = l.mul(l.mul(l.mul(l.mul(l.k(30.0), x), x), y), y);
        let ds = l.div(ds, l.k(c.near));
        (l.sel(close, s, one), l.sel(close, ds, zero))
    } else {
        (one, zero)
    }
}

/// One pair's results in the lanes, before the cut-off selection.
struct PairLanes<T> {
    f: V3<T>,
    ti: V3<T>,
    tj: V3<T>,
    energy: T,
}

/// The pair's force on `j`, torques on `i` and `j` and energy from the
/// spacing and both directions' gradient scalars.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn combine<S: pulp::Simd>(
    l: L<S>,
    r: V3<S::f64s>,
    niv: V3<S::f64s>,
    nj: V3<S::f64s>,
    u: S::f64s,
    f_sp: V3<S::f64s>,
    di: &Dir<S::f64s>,
    dj: &Dir<S::f64s>,
) -> PairLanes<S::f64s> {
    let rxi = l.cross(r, niv);
    let rxj = l.cross(r, nj);
    let nxn = l.cross(niv, nj);
    let bt = l.add(di.b, dj.b);
    let energy = l.add(u, l.add(di.energy, dj.energy));
    let f_or = l.add3(
        l.add3(
            l.scale(r, l.sub(l.neg(di.g_r), dj.g_r)),
            l.scale(niv, l.sub(dj.g_n, di.g_e)),
        ),
        l.scale(nj, l.sub(dj.g_e, di.g_n)),
    );
    let f = l.add3(f_sp, f_or);
    let ti = l.add3(l.scale(rxi, l.sub(di.g_e, dj.g_n)), l.scale(nxn, bt));
    let tj = l.sub3(l.scale(rxj, l.sub(di.g_n, dj.g_e)), l.scale(nxn, bt));
    PairLanes { f, ti, tj, energy }
}

/// The row's result slices of one batch, `k0 .. k0 + LANES`, as lanes.
struct OutLanes<'o, S: pulp::Simd> {
    f: [&'o mut [S::f64s]; 3],
    ti: [&'o mut [S::f64s]; 3],
    tj: [&'o mut [S::f64s]; 3],
    en: &'o mut [S::f64s],
    sq: &'o mut [S::f64s],
}

impl<'o, S: pulp::Simd> OutLanes<'o, S> {
    /// The batch's slices of `out`.
    #[inline(always)]
    fn new(out: &'o mut OrientedRow, k0: usize) -> Self {
        let range = k0..k0 + LANES;
        let lanes = |a: &'o mut [Vec<Real>; 3]| {
            let [x, y, z] = a;
            let (x, _) = S::as_mut_simd_f64s(&mut x[range.clone()]);
            let (y, _) = S::as_mut_simd_f64s(&mut y[range.clone()]);
            let (z, _) = S::as_mut_simd_f64s(&mut z[range.clone()]);
            [x, y, z]
        };
        let f = lanes(&mut out.f);
        let ti = lanes(&mut out.ti);
        let tj = lanes(&mut out.tj);
        let (en, _) = S::as_mut_simd_f64s(&mut out.energy[range.clone()]);
        let (sq, _) = S::as_mut_simd_f64s(&mut out.d2[range]);
        OutLanes { f, ti, tj, en, sq }
    }

    /// Stores lane `v` of the pair's results, zeros where it is not
    /// `valid` (the squared distance is stored before, as read).
    #[inline(always)]
    fn store(&mut self, l: L<S>, v: usize, valid: S::m64s, p: &PairLanes<S::f64s>) {
        let zero = l.k(0.0);
        self.f[0][v] = l.sel(valid, p.f.x, zero);
        self.f[1][v] = l.sel(valid, p.f.y, zero);
        self.f[2][v] = l.sel(valid, p.f.z, zero);
        self.ti[0][v] = l.sel(valid, p.ti.x, zero);
        self.ti[1][v] = l.sel(valid, p.ti.y, zero);
        self.ti[2][v] = l.sel(valid, p.ti.z, zero);
        self.tj[0][v] = l.sel(valid, p.tj.x, zero);
        self.tj[1][v] = l.sel(valid, p.tj.y, zero);
        self.tj[2][v] = l.sel(valid, p.tj.z, zero);
        self.en[v] = l.sel(valid, p.energy, zero);
    }
}

/// The taper of `ψ` at `|r|`, `1/|r|` and whether `|r|` is inside the
/// weight's cut-off: what both sides' weights share.
struct WeightLanes<T, M> {
    ts: T,
    tds: T,
    inv_dist: T,
    on: M,
}

/// `Weight::eval_scalar` from `ψ₀ = K exp(...)`: `(ψ, w_r, w_n)`, zero at
/// and beyond the cut-off.
#[inline(always)]
fn weight<S: pulp::Simd>(
    l: L<S>,
    w: &WeightLaneConstants,
    wl: &WeightLanes<S::f64s, S::m64s>,
    psi0: S::f64s,
    z: S::f64s,
) -> (S::f64s, S::f64s, S::f64s) {
    let zero = l.k(0.0);
    let psi = l.mul(psi0, wl.ts);
    let wr = l.sub(
        l.mul(psi0, l.mul(wl.tds, wl.inv_dist)),
        l.mul(psi, l.k(w.inv_a2)),
    );
    let wn = if w.anisotropic {
        l.mul(l.mul(l.k(-2.0 * w.c), z), psi)
    } else {
        zero
    };
    (
        l.sel(wl.on, psi, zero),
        l.sel(wl.on, wr, zero),
        l.sel(wl.on, wn, zero),
    )
}

/// The scalars both directions share.
struct Geometry<T> {
    dist: T,
    inv_d2: T,
    dd: T,
    /// The fade `(S, S')` (`(1, 0)` at and beyond `r_near`).
    fs: T,
    fds: T,
}

/// One direction's gradient scalars (`material::Direction`).
struct Dir<T> {
    energy: T,
    g_r: T,
    g_e: T,
    g_n: T,
    b: T,
}

/// `PreparedMaterial::direction` in the lanes, operation for operation.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn direction<S: pulp::Simd>(
    l: L<S>,
    c: &OrientedLaneConstants,
    geo: &Geometry<S::f64s>,
    z_e: S::f64s,
    z_r: S::f64s,
    r: V3<S::f64s>,
    d: V3<S::f64s>,
    kappa: S::f64s,
    (psi, wr, wn): (S::f64s, S::f64s, S::f64s),
) -> Dir<S::f64s> {
    let zero = l.k(0.0);
    let pn = if c.normalized { geo.inv_d2 } else { l.k(1.0) };
    let cc = l.add(z_e, z_r);
    let phi_p = l.mul(l.mul(z_e, z_e), pn);
    let phi_c = l.mul(l.mul(cc, cc), pn);
    let (a_f, v2) = if c.w_f > 0.0 {
        let a_f = if c.normalized {
            l.k(c.w_f)
        } else {
            let flat = l.0.equal_f64s(kappa, zero);
            l.sel(flat, zero, l.div(l.k(c.w_f), l.mul(kappa, kappa)))
        };
        let e = l.add3(l.scale(r, kappa), d);
        (a_f, l.dot(e, e))
    } else {
        (zero, zero)
    };
    let (fs, fds) = (geo.fs, geo.fds);
    let (w_p, w_n, w_c) = (l.k(c.w_p), l.k(c.w_n), l.k(c.w_c));
    let pc = l.add(l.mul(w_p, phi_p), l.mul(w_c, phi_c));
    let phi = l.add(
        l.add(
            l.add(l.mul(fs, l.mul(w_p, phi_p)), l.mul(w_n, geo.dd)),
            l.mul(fs, l.mul(w_c, phi_c)),
        ),
        l.mul(a_f, v2),
    );
    let nr = if c.normalized { geo.inv_d2 } else { zero };
    let two = l.k(2.0);
    let rr = l.add(
        l.mul(
            two,
            l.sub(l.mul(l.mul(a_f, kappa), kappa), l.mul(nr, l.mul(fs, pc))),
        ),
        l.mul(l.mul(fds, pc), l.mul(geo.dist, geo.inv_d2)),
    );
    let rc = l.mul(l.mul(l.mul(l.mul(two, pn), l.k(c.w_c)), cc), fs);
    let rf = l.mul(l.mul(two, a_f), kappa);
    let rne = l.add(
        l.add(l.mul(l.mul(l.mul(l.mul(two, pn), l.k(c.w_p)), z_e), fs), rc),
        rf,
    );
    let rnr = l.sub(rc, rf);
    Dir {
        energy: l.mul(psi, phi),
        g_r: l.add(l.mul(psi, rr), l.mul(phi, wr)),
        g_e: l.add(l.mul(psi, rne), l.mul(phi, wn)),
        g_n: l.mul(psi, rnr),
        b: l.mul(psi, l.mul(two, l.add(w_n, a_f))),
    }
}

#[cfg(test)]
mod tests;
