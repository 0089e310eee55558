//! Test support: a seeded RNG, random pair configurations and the
//! finite-difference and momentum checks shared by the term tests.
//!
//! op-dynamics' own unit tests cannot use the workspace's op-test-support
//! (it depends on op-dynamics: its types would be another copy's), so the
//! generator here is the same SplitMix64, giving the same sequences.

use super::material::{Material, PreparedMaterial};
use super::pair::{evaluate_pair, Coupling, PairGeometry, ParticleView, TermGrad};
use super::weight::{WeightParams, WeightShape};
use crate::math::{rotate_by, tangent_axis, Point3, Quat, Real, Vec3};

/// SplitMix64: small, fast, deterministic.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> Real {
        (self.next_u64() >> 11) as Real * (1.0 / (1u64 << 53) as Real)
    }

    pub fn range(&mut self, lo: Real, hi: Real) -> Real {
        lo + (hi - lo) * self.uniform()
    }

    pub fn sign(&mut self) -> Real {
        if self.next_u64() & 1 == 0 {
            1.0
        } else {
            -1.0
        }
    }

    pub fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let n = v.norm();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }

    /// A uniformly random rotation.
    pub fn rotation(&mut self) -> Quat {
        loop {
            let q = nalgebra::Quaternion::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let n = q.norm();
            if n > 0.1 && n <= 1.0 {
                return Quat::from_quaternion(q);
            }
        }
    }
}

/// One particle's state as the world holds it.
#[derive(Copy, Clone, Debug)]
pub struct Body {
    pub p: Point3,
    pub q: Quat,
    /// Body-frame normal axis.
    pub a: Vec3,
    pub kappa: Real,
}

impl Body {
    pub fn normal(&self) -> Vec3 {
        self.q * self.a
    }

    pub fn tangent(&self) -> Vec3 {
        self.q * tangent_axis(&self.a)
    }

    pub fn view<'m>(&self, m: &'m PreparedMaterial) -> ParticleView<'m> {
        ParticleView {
            position: self.p,
            normal: self.normal(),
            tangent: self.tangent(),
            kappa: self.kappa,
            material: m,
        }
    }

    fn moved(&self, dp: Vec3, dtheta: Vec3) -> Body {
        Body {
            p: self.p + dp,
            q: rotate_by(&self.q, &dtheta),
            ..*self
        }
    }
}

/// A random pair at distance `dist`: random positions, orientations, body
/// normal axes and curvatures `±[0.2, 1.5]`.
pub fn random_pair(rng: &mut Rng, dist: Real) -> (Body, Body) {
    fn body(rng: &mut Rng, p: Point3) -> Body {
        Body {
            p,
            q: rng.rotation(),
            a: rng.unit_vector(),
            kappa: rng.sign() * rng.range(0.2, 1.5),
        }
    }
    let shift = Vec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    );
    let bi = body(rng, Point3::new(0.3, -0.7, 0.5) + shift);
    let dir = rng.unit_vector();
    let bj = body(rng, bi.p + dir * dist);
    (bi, bj)
}

pub fn geometry(r: Vec3, n_i: Vec3, n_j: Vec3, t_i: Vec3, kappa_i: Real) -> PairGeometry {
    PairGeometry {
        r,
        dist: r.norm(),
        n_i,
        n_j,
        t_i,
        kappa_i,
    }
}

/// Checks a term's gradients against central differences of its energy,
/// treating `r`, `n_i`, `n_j` as free vectors.
pub fn check_term_gradients(f: impl Fn(&PairGeometry) -> TermGrad, seed: u64) {
    let mut rng = Rng::new(seed);
    for _ in 0..200 {
        let r = rng.unit_vector() * rng.range(0.3, 2.5);
        let g = geometry(
            r,
            rng.unit_vector(),
            rng.unit_vector(),
            rng.unit_vector(),
            rng.sign() * rng.range(0.3, 1.5),
        );
        let t = f(&g);
        let h = 1e-6;
        for k in 0..3 {
            let mut e = Vec3::zeros();
            e[k] = h;
            let fd = |plus: PairGeometry, minus: PairGeometry| {
                (f(&plus).energy - f(&minus).energy) / (2.0 * h)
            };
            let fd_r = fd(
                geometry(r + e, g.n_i, g.n_j, g.t_i, g.kappa_i),
                geometry(r - e, g.n_i, g.n_j, g.t_i, g.kappa_i),
            );
            let fd_ni = fd(
                PairGeometry {
                    n_i: g.n_i + e,
                    ..g
                },
                PairGeometry {
                    n_i: g.n_i - e,
                    ..g
                },
            );
            let fd_nj = fd(
                PairGeometry {
                    n_j: g.n_j + e,
                    ..g
                },
                PairGeometry {
                    n_j: g.n_j - e,
                    ..g
                },
            );
            for (a, b, what) in [
                (fd_r, t.d_r[k], "r"),
                (fd_ni, t.d_ni[k], "n_i"),
                (fd_nj, t.d_nj[k], "n_j"),
            ] {
                assert!(
                    (a - b).abs() <= 1e-7 * (1.0 + a.abs() + t.energy.abs()),
                    "d/d{what}[{k}]: fd {a} vs analytic {b} at {g:?}"
                );
            }
        }
    }
}

/// Total spin energy of the pair (both sides), which `evaluate_pair` turns
/// into torques about the normals but leaves out of the pair energy.
pub fn spin_energy(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    bi: &Body,
    bj: &Body,
    c: Coupling,
) -> Real {
    if c != (Coupling::Complete { oriented: true }) {
        return 0.0;
    }
    let r = bj.p - bi.p;
    let gi = geometry(r, bi.normal(), bj.normal(), bi.tangent(), bi.kappa);
    let gj = geometry(-r, bj.normal(), bi.normal(), bj.tangent(), bj.kappa);
    mi.spin_energy(&gi) + mj.spin_energy(&gj)
}

/// Forces and torques of `evaluate_pair` on both particles against central
/// differences of the pair energy w.r.t. positions and world rotations
/// (`q' = rotate_by(q, h e_k)`). Spin: the torque must be the projection on
/// the normal of the rotational derivative of the spin energy, with no
/// force. Tolerance per vector: `1e-6 |fd| + 1e-8 max|vector| + 1e-9 |E|`.
pub fn check_fd(mi: &PreparedMaterial, mj: &PreparedMaterial, bi: &Body, bj: &Body, c: Coupling) {
    let res = evaluate_pair(&bi.view(mi), &bj.view(mj), c);
    let energy = |a: &Body, b: &Body| evaluate_pair(&a.view(mi), &b.view(mj), c).energy;
    let spin = |a: &Body, b: &Body| spin_energy(mi, mj, a, b, c);
    let z = Vec3::zeros();
    // Central differences with steps h and h/2, Richardson-extrapolated
    // (error O(h⁴)): the tapers make the energy a steep polynomial near
    // the cut-off, where plain O(h²) differences are not accurate enough.
    let h = 1e-4;
    let richardson = |f: &dyn Fn(&Body, &Body) -> Real, which: usize, k: usize| {
        let cd = |step: Real| {
            let mut e = Vec3::zeros();
            e[k] = step;
            let (p, m) = match which {
                0 => ((bi.moved(e, z), *bj), (bi.moved(-e, z), *bj)),
                1 => ((*bi, bj.moved(e, z)), (*bi, bj.moved(-e, z))),
                2 => ((bi.moved(z, e), *bj), (bi.moved(z, -e), *bj)),
                _ => ((*bi, bj.moved(z, e)), (*bi, bj.moved(z, -e))),
            };
            (f(&p.0, &p.1) - f(&m.0, &m.1)) / (2.0 * step)
        };
        (4.0 * cd(0.5 * h) - cd(h)) / 3.0
    };
    let grad = |f: &dyn Fn(&Body, &Body) -> Real, which: usize| {
        Vec3::from_fn(|k, _| richardson(f, which, k))
    };
    // [dE/dp_i, dE/dp_j, dE/dθ_i, dE/dθ_j, dEs/dθ_i, dEs/dθ_j]
    let d = [
        grad(&energy, 0),
        grad(&energy, 1),
        grad(&energy, 2),
        grad(&energy, 3),
        grad(&spin, 2),
        grad(&spin, 3),
    ];
    let (ni, nj) = (bi.normal(), bj.normal());
    let expected = [
        ("force_i", res.force_i, -d[0]),
        ("force_j", res.force_j, -d[1]),
        ("torque_i", res.torque_i, -d[2] - ni * ni.dot(&d[4])),
        ("torque_j", res.torque_j, -d[3] - nj * nj.dot(&d[5])),
    ];
    let big = expected.iter().map(|e| e.1.norm()).fold(0.0, Real::max);
    for (name, got, want) in expected {
        let tol = 1e-6 * want.norm() + 1e-8 * big + 1e-9 * res.energy.abs() + 1e-13;
        assert!(
            (got - want).norm() <= tol,
            "{name}: analytic {got:?} vs finite differences {want:?} (err {:e}, tol {tol:e}); \
             E = {}, dist = {}, bodies {bi:?} {bj:?}, materials {:?} / {:?}",
            (got - want).norm(),
            res.energy,
            (bj.p - bi.p).norm(),
            mi.enabled_terms(),
            mj.enabled_terms()
        );
    }
}

/// Internal forces conserve linear and angular momentum (not with spin).
pub fn check_momentum(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    bi: &Body,
    bj: &Body,
    c: Coupling,
) {
    let res = evaluate_pair(&bi.view(mi), &bj.view(mj), c);
    let big = [res.force_i, res.torque_i, res.torque_j]
        .iter()
        .map(|v| v.norm())
        .fold(1e-300, Real::max);
    let lever = bi.p.coords.norm().max(bj.p.coords.norm()).max(1.0);
    assert!((res.force_i + res.force_j).norm() <= 1e-14 * big);
    let l = bi.p.coords.cross(&res.force_i)
        + bj.p.coords.cross(&res.force_j)
        + res.torque_i
        + res.torque_j;
    assert!(
        l.norm() <= 1e-12 * big * lever,
        "angular momentum {l:?} (scale {big})"
    );
}

/// FD (and, without spin, momentum) checks of a material's orientation
/// terms for isotropic and anisotropic weights, raw and normalized, same
/// and different materials on both sides, distances inside, in the
/// taper region and within the coincidence radius. Spin materials also check: no force, torques along the
/// normals.
pub fn term_suite(base: Material, seed: u64) {
    let mut rng = Rng::new(seed);
    let c = Coupling::Complete { oriented: true };
    for shape in [WeightShape::Isotropic, WeightShape::Anisotropic { b: 0.5 }] {
        for normalized in [false, true] {
            let m = Material {
                weight: WeightParams {
                    shape,
                    ..Default::default()
                },
                normalized,
                ..base
            };
            let scaled = |w: Real| w * 1.7;
            let other = Material {
                weight: WeightParams {
                    a: 0.8,
                    k: 1.3,
                    cutoff: 2.3,
                    taper: 0.4,
                    shape: WeightShape::Anisotropic { b: 0.35 },
                },
                coplanarity: scaled(m.coplanarity),
                conormality: scaled(m.conormality),
                cocircularity: scaled(m.cocircularity),
                form: scaled(m.form),
                spin: scaled(m.spin),
                ..m
            };
            let (pm, po) = (m.prepare().unwrap(), other.prepare().unwrap());
            let rc = pm.cutoff();
            for case in 0..48 {
                // Every fourth configuration lies in the taper region, and
                // every sixth within the coincidence radius, where the
                // normalized direction terms fade out (`material` docs).
                let dist = if case % 4 == 0 {
                    rng.range(0.8 * rc, rc)
                } else if case % 6 == 1 {
                    rng.range(0.01, 1.0) * pm.near_radius()
                } else {
                    rng.range(0.4, rc)
                };
                let (bi, bj) = random_pair(&mut rng, dist);
                let mj = if case % 3 == 0 { &po } else { &pm };
                check_fd(&pm, mj, &bi, &bj, c);
                let res = evaluate_pair(&bi.view(&pm), &bj.view(mj), c);
                if base.spin > 0.0 {
                    assert_eq!(res.force_i, Vec3::zeros());
                    assert!(res.torque_i.cross(&bi.normal()).norm() <= 1e-12 * res.torque_i.norm());
                    assert!(res.torque_j.cross(&bj.normal()).norm() <= 1e-12 * res.torque_j.norm());
                } else {
                    check_momentum(&pm, mj, &bi, &bj, c);
                }
            }
        }
    }
}
