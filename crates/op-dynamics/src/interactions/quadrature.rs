//! Gauss–Legendre quadrature and cubic Hermite tables (support for the
//! cohesion energy, seed 002 §3, whose force has no closed-form integral).

use crate::math::Real;
use std::sync::OnceLock;

/// Number of Gauss–Legendre points per panel.
pub const GL_POINTS: usize = 16;

struct Rule {
    x: [Real; GL_POINTS],
    w: [Real; GL_POINTS],
}

/// The nodes and weights on [-1, 1], computed once by Newton's iteration on
/// the Legendre polynomial (accurate to round-off).
fn rule() -> &'static Rule {
    static RULE: OnceLock<Rule> = OnceLock::new();
    RULE.get_or_init(|| {
        let n = GL_POINTS;
        let mut x = [0.0; GL_POINTS];
        let mut w = [0.0; GL_POINTS];
        for i in 0..n.div_ceil(2) {
            let mut z = (std::f64::consts::PI * (i as Real + 0.75) / (n as Real + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p1, mut p2) = (1.0, 0.0);
                for j in 0..n {
                    let p3 = p2;
                    p2 = p1;
                    p1 = ((2 * j + 1) as Real * z * p2 - j as Real * p3) / (j + 1) as Real;
                }
                dp = n as Real * (z * p1 - p2) / (z * z - 1.0);
                let z1 = z;
                z = z1 - p1 / dp;
                if (z - z1).abs() <= 1e-16 {
                    break;
                }
            }
            x[i] = -z;
            x[n - 1 - i] = z;
            let wi = 2.0 / ((1.0 - z * z) * dp * dp);
            w[i] = wi;
            w[n - 1 - i] = wi;
        }
        Rule { x, w }
    })
}

/// `∫_a^b f` by one 16-point Gauss–Legendre panel (exact for polynomials of
/// degree 31; for analytic `f` on a panel well away from its singularities
/// the error is at round-off).
#[inline]
pub fn gauss_legendre(a: Real, b: Real, f: impl Fn(Real) -> Real) -> Real {
    let rule = rule();
    let mid = 0.5 * (a + b);
    let half = 0.5 * (b - a);
    let mut sum = 0.0;
    for k in 0..GL_POINTS {
        sum += rule.w[k] * f(mid + half * rule.x[k]);
    }
    sum * half
}

/// A piecewise cubic Hermite interpolant on uniform nodes over `[x0, x1]`,
/// built from values and derivatives at the nodes. Its derivative is the
/// exact derivative of the interpolated value (so a tabulated force is
/// exactly minus the gradient of the tabulated energy).
#[derive(Clone, Debug, PartialEq)]
pub struct HermiteTable {
    x0: Real,
    x1: Real,
    h: Real,
    inv_h: Real,
    /// Per interval, `c0 + c1 τ + c2 τ² + c3 τ³` with `τ ∈ [0, 1]`.
    coeffs: Vec<[Real; 4]>,
}

impl HermiteTable {
    /// Tabulates `f(x) = (value, derivative)` at `nodes >= 2` uniform nodes.
    pub fn new(x0: Real, x1: Real, nodes: usize, f: impl Fn(Real) -> (Real, Real)) -> Self {
        assert!(nodes >= 2 && x1 > x0);
        let h = (x1 - x0) / (nodes - 1) as Real;
        let node = |k: usize| {
            if k == nodes - 1 {
                x1
            } else {
                x0 + h * k as Real
            }
        };
        let mut prev = f(node(0));
        let mut coeffs = Vec::with_capacity(nodes - 1);
        for k in 1..nodes {
            let next = f(node(k));
            let (u0, d0) = (prev.0, prev.1 * h);
            let (u1, d1) = (next.0, next.1 * h);
            coeffs.push([
                u0,
                d0,
                3.0 * (u1 - u0) - 2.0 * d0 - d1,
                2.0 * (u0 - u1) + d0 + d1,
            ]);
            prev = next;
        }
        HermiteTable {
            x0,
            x1,
            h,
            inv_h: 1.0 / h,
            coeffs,
        }
    }

    /// The first node.
    pub fn start(&self) -> Real {
        self.x0
    }

    /// The last node.
    pub fn end(&self) -> Real {
        self.x1
    }

    /// Node spacing.
    pub fn spacing(&self) -> Real {
        self.h
    }

    /// `(value, derivative)` at `x`, clamped into `[x0, x1]`.
    #[inline]
    pub fn eval(&self, x: Real) -> (Real, Real) {
        let s = ((x - self.x0) * self.inv_h).max(0.0);
        let last = self.coeffs.len() - 1;
        let k = (s as usize).min(last);
        let t = (s - k as Real).min(1.0);
        let c = &self.coeffs[k];
        let v = c[0] + t * (c[1] + t * (c[2] + t * c[3]));
        let d = c[1] + t * (2.0 * c[2] + t * 3.0 * c[3]);
        (v, d * self.inv_h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_and_exp_exactly() {
        let rule = rule();
        let wsum: Real = rule.w.iter().sum();
        assert!((wsum - 2.0).abs() < 1e-14);
        let v = gauss_legendre(0.0, 2.0, |x| x.powi(31));
        assert!((v / (2.0_f64.powi(32) / 32.0) - 1.0).abs() < 1e-14);
        let e = gauss_legendre(-1.0, 1.5, Real::exp);
        assert!((e - (1.5_f64.exp() - (-1.0_f64).exp())).abs() < 1e-14);
    }

    #[test]
    fn hermite_reproduces_cubics_and_its_derivative_is_consistent() {
        let f = |x: Real| (x * x * x - 2.0 * x + 1.0, 3.0 * x * x - 2.0);
        let t = HermiteTable::new(-1.0, 2.0, 7, f);
        for k in 0..=100 {
            let x = -1.0 + 3.0 * k as Real / 100.0;
            let (v, d) = t.eval(x);
            assert!((v - f(x).0).abs() < 1e-13, "{x}");
            assert!((d - f(x).1).abs() < 1e-12, "{x}");
        }
    }
}
