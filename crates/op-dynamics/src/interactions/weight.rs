//! The orientation weight `ψ` (seed 000 eq. 10).
//!
//! Every orientation term is multiplied by `ψ`, a Gaussian in the position of
//! the feeling particle `j` seen from the emitter `i`:
//!
//! - isotropic: `ψ = K exp(-|r|²/2a²)`;
//! - anisotropic, in i's frame: `ψ = K exp(-(x²+y²)/2a² - z²/2b²)` with
//!   `b <= a`, which weights neighbours near i's tangent plane more. With
//!   `z = n_i·r` and `x²+y² = |r|² - z²` it depends on i's frame only through
//!   its normal `n_i` (so a rotation about `n_i` leaves it unchanged).
//!
//! Both are multiplied by the taper of [`super::cutoff`], so `ψ` and its
//! gradient vanish continuously at the cut-off. [`Weight::eval`] returns `ψ`,
//! `∂ψ/∂r` and `∂ψ/∂n_i`.

use super::cutoff::{validate_fraction, Taper};
use crate::error::{positive, ParamError};
use crate::math::{Real, Vec3};
use serde::{Deserialize, Serialize};

/// Shape of the orientation weight.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub enum WeightShape {
    /// `K exp(-|r|²/2a²)`.
    Isotropic,
    /// `K exp(-(x²+y²)/2a² - z²/2b²)` in the emitter's frame; requires
    /// `0 < b <= a`.
    Anisotropic {
        /// Width across the tangent plane (along the emitter's normal).
        b: Real,
    },
}

/// Parameters of the orientation weight `ψ` (seed 000 eq. 10).
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct WeightParams {
    /// Amplitude `K` (> 0). Default: 1.
    pub k: Real,
    /// Width `a` in the tangent plane (> 0). Default: 1 (the default rest
    /// distance).
    pub a: Real,
    /// Isotropic or anisotropic. Default: `Isotropic`.
    pub shape: WeightShape,
    /// Cut-off radius `r_c` (> 0): `ψ = 0` from here on. Default: 2.5.
    pub cutoff: Real,
    /// Fraction of the cut-off over which `ψ` is tapered to 0
    /// (`0 < taper <= 1`; the taper starts at `cutoff (1 - taper)`).
    /// Default: 0.2.
    pub taper: Real,
}

impl Default for WeightParams {
    fn default() -> Self {
        WeightParams {
            k: 1.0,
            a: 1.0,
            shape: WeightShape::Isotropic,
            cutoff: 2.5,
            taper: 0.2,
        }
    }
}

impl WeightParams {
    /// Rejects NaN, infinite and out-of-range values.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("k", self.k)?;
        positive("a", self.a)?;
        if let WeightShape::Anisotropic { b } = self.shape {
            positive("shape.b", b)?;
            if b > self.a {
                return Err(ParamError::OutOfRange {
                    field: "shape.b".into(),
                    value: b,
                    allowed: format!("must be <= a = {} (seed 000 eq. 10)", self.a),
                });
            }
        }
        positive("cutoff", self.cutoff)?;
        validate_fraction("taper", self.taper)
    }

    /// Validates and builds the evaluator.
    pub fn prepare(&self) -> Result<Weight, ParamError> {
        self.validate()?;
        let inv_a2 = 1.0 / (self.a * self.a);
        let (anisotropic, c) = match self.shape {
            WeightShape::Isotropic => (false, 0.0),
            WeightShape::Anisotropic { b } => (true, 0.5 / (b * b) - 0.5 * inv_a2),
        };
        Ok(Weight {
            k: self.k,
            inv_a2,
            c,
            anisotropic,
            taper: Taper::new(self.cutoff, self.taper),
        })
    }
}

/// `ψ` with its gradients.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct WeightEval {
    /// `ψ`.
    pub psi: Real,
    /// `∂ψ/∂r`.
    pub d_r: Vec3,
    /// `∂ψ/∂n_i` (zero for the isotropic weight).
    pub d_n: Vec3,
}

/// The prepared orientation weight (see the module docs).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Weight {
    k: Real,
    inv_a2: Real,
    /// `1/2b² - 1/2a²` (>= 0), the extra decay along the normal.
    c: Real,
    anisotropic: bool,
    taper: Taper,
}

impl Weight {
    /// The cut-off radius.
    #[inline]
    pub fn cutoff(&self) -> Real {
        self.taper.cutoff()
    }

    /// True for the anisotropic shape.
    pub fn is_anisotropic(&self) -> bool {
        self.anisotropic
    }

    /// True when `ψ` depends on the distance only (the same for both
    /// directions of a pair of one material).
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        !self.anisotropic
    }

    /// The constants the oriented SIMD lanes (`lanes.rs`) evaluate
    /// [`Self::eval_scalar`] with.
    pub(crate) fn lane_constants(&self) -> crate::lanes::WeightLaneConstants {
        crate::lanes::WeightLaneConstants {
            k: self.k,
            inv_a2: self.inv_a2,
            c: self.c,
            anisotropic: self.anisotropic,
            r_on: self.taper.r_on(),
            inv_width: self.taper.inv_width(),
            cutoff: self.taper.cutoff(),
        }
    }

    /// [`Self::eval`] as scalars, for the fused pair kernel: `(ψ, w_r, w_n)`
    /// with `∂ψ/∂r = w_r r + w_n n_i` and `∂ψ/∂n_i = w_n r`, from
    /// `d2 = |r|²`, `dist = |r|`, `inv_dist = 1/|r|` and `z = n_i·r`
    /// (`w_n = 0` for the isotropic shape). Zero at and beyond the cut-off.
    #[inline(always)]
    pub fn eval_scalar(&self, d2: Real, dist: Real, inv_dist: Real, z: Real) -> (Real, Real, Real) {
        if dist >= self.taper.cutoff() {
            return (0.0, 0.0, 0.0);
        }
        let (s, ds) = self.taper.eval(dist);
        let mut expo = -0.5 * d2 * self.inv_a2;
        if self.anisotropic {
            expo -= self.c * z * z;
        }
        let psi0 = self.k * expo.exp();
        let psi = psi0 * s;
        let wr = psi0 * (ds * inv_dist) - psi * self.inv_a2;
        let wn = if self.anisotropic {
            -2.0 * self.c * z * psi
        } else {
            0.0
        };
        (psi, wr, wn)
    }

    /// `ψ(r)` and its gradients for `r = p_j - p_i` (`dist = |r| > 0`) and
    /// the emitter's normal `n_i`. Zero at and beyond the cut-off.
    #[inline]
    pub fn eval(&self, r: &Vec3, dist: Real, n_i: &Vec3) -> WeightEval {
        if dist >= self.taper.cutoff() {
            return WeightEval::default();
        }
        let (s, ds) = self.taper.eval(dist);
        let mut expo = -0.5 * dist * dist * self.inv_a2;
        let (psi0, d_r0, d_n0) = if self.anisotropic {
            let z = n_i.dot(r);
            expo -= self.c * z * z;
            let psi0 = self.k * expo.exp();
            let g = -2.0 * self.c * z * psi0;
            (psi0, r * (-psi0 * self.inv_a2) + n_i * g, r * g)
        } else {
            let psi0 = self.k * expo.exp();
            (psi0, r * (-psi0 * self.inv_a2), Vec3::zeros())
        };
        WeightEval {
            psi: psi0 * s,
            d_r: d_r0 * s + r * (psi0 * ds / dist),
            d_n: d_n0 * s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::test_support::Rng;

    fn weights() -> Vec<Weight> {
        let iso = WeightParams::default();
        let aniso = WeightParams {
            shape: WeightShape::Anisotropic { b: 0.4 },
            a: 0.9,
            k: 2.0,
            ..iso
        };
        vec![iso.prepare().unwrap(), aniso.prepare().unwrap()]
    }

    #[test]
    fn gradients_match_finite_differences() {
        let mut rng = Rng::new(11);
        for w in weights() {
            for _ in 0..200 {
                let n = rng.unit_vector();
                let r = rng.unit_vector() * rng.range(0.3, 2.49);
                let e = w.eval(&r, r.norm(), &n);
                let h = 1e-6;
                for k in 0..3 {
                    let mut dv = Vec3::zeros();
                    dv[k] = h;
                    let (rp, rm) = (r + dv, r - dv);
                    let fd_r = (w.eval(&rp, rp.norm(), &n).psi - w.eval(&rm, rm.norm(), &n).psi)
                        / (2.0 * h);
                    let fd_n = (w.eval(&r, r.norm(), &(n + dv)).psi
                        - w.eval(&r, r.norm(), &(n - dv)).psi)
                        / (2.0 * h);
                    assert!((fd_r - e.d_r[k]).abs() < 1e-8, "{fd_r} vs {}", e.d_r[k]);
                    assert!((fd_n - e.d_n[k]).abs() < 1e-8, "{fd_n} vs {}", e.d_n[k]);
                }
            }
        }
    }

    #[test]
    fn anisotropic_weight_favours_the_tangent_plane_and_ignores_spin() {
        let w = &weights()[1];
        let n = Vec3::z();
        let in_plane = Vec3::new(1.0, 0.0, 0.0);
        let along_n = Vec3::new(0.0, 0.0, 1.0);
        assert!(w.eval(&in_plane, 1.0, &n).psi > 10.0 * w.eval(&along_n, 1.0, &n).psi);
        let iso = WeightParams::default().prepare().unwrap();
        let e = iso.eval(&in_plane, 1.0, &n);
        assert!((e.psi - (-0.5 as Real).exp()).abs() < 1e-15);
        assert_eq!(e.d_n, Vec3::zeros());
    }

    #[test]
    fn vanishes_continuously_at_the_cutoff() {
        for w in weights() {
            let rc = w.cutoff();
            let r = Vec3::new(0.3, -0.2, 1.0).normalize() * (rc * (1.0 - 1e-7));
            let e = w.eval(&r, r.norm(), &Vec3::z());
            assert!(e.psi.abs() < 1e-18 && e.d_r.norm() < 1e-11, "{e:?}");
            let at = Vec3::x() * rc;
            assert_eq!(w.eval(&at, rc, &Vec3::z()), WeightEval::default());
        }
    }

    #[test]
    fn validation_names_the_field() {
        let bad_b = WeightParams {
            shape: WeightShape::Anisotropic { b: 2.0 },
            ..Default::default()
        };
        let e = bad_b.validate().unwrap_err().to_string();
        assert!(e.contains("shape.b") && e.contains("<= a"), "{e}");
        let nan_a = WeightParams {
            a: Real::NAN,
            ..Default::default()
        };
        let e = nan_a.validate().unwrap_err().within("weight").to_string();
        assert!(e.contains("weight.a") && e.contains("NaN"), "{e}");
        let neg = WeightParams {
            cutoff: -1.0,
            ..Default::default()
        };
        assert!(neg.validate().unwrap_err().to_string().contains("cutoff"));
        let taper = WeightParams {
            taper: 0.0,
            ..Default::default()
        };
        assert!(taper.validate().unwrap_err().to_string().contains("taper"));
    }
}
