//! Exponential repulsion between particles that do not interact completely
//! (seed 002 §5: different standard types, or different objects).
//!
//! `U(r) = ε exp((σ - r)/λ) s(r)`: `ε` is the energy at the contact distance
//! `σ` (when the taper starts beyond `σ`), `λ` the decay length, `s` the
//! taper of [`super::cutoff`]. The force on `j` is `-U'(r) r/|r|`, always
//! pushing the particles apart (plus the small taper correction near the
//! cut-off). Seed 002 names only "an exponential function of the distance";
//! this parameterisation is ours.

use super::cutoff::{validate_fraction, Taper};
use crate::error::{non_negative, positive, ParamError};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Parameters of the exponential repulsion.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RepulsionParams {
    /// Energy `ε` at the contact distance (>= 0; 0 disables the
    /// repulsion). Default: 1.
    pub strength: Real,
    /// Contact distance `σ` (> 0). Default: 1 (the default rest distance).
    pub sigma: Real,
    /// Decay length `λ` (> 0). Default: 0.1.
    pub lambda: Real,
    /// Cut-off radius (> sigma). Default: 2 (`σ + 10 λ`).
    pub cutoff: Real,
    /// Fraction of the cut-off over which `U` is tapered to 0
    /// (`0 < taper <= 1`). Default: 0.2.
    pub taper: Real,
}

impl Default for RepulsionParams {
    fn default() -> Self {
        RepulsionParams {
            strength: 1.0,
            sigma: 1.0,
            lambda: 0.1,
            cutoff: 2.0,
            taper: 0.2,
        }
    }
}

impl RepulsionParams {
    /// Rejects NaN, infinite and out-of-range values.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("strength", self.strength)?;
        positive("sigma", self.sigma)?;
        positive("lambda", self.lambda)?;
        positive("cutoff", self.cutoff)?;
        if self.cutoff <= self.sigma {
            return Err(ParamError::OutOfRange {
                field: "cutoff".into(),
                value: self.cutoff,
                allowed: format!("must be > sigma = {}", self.sigma),
            });
        }
        validate_fraction("taper", self.taper)
    }

    /// Validates and builds the evaluator.
    pub fn prepare(&self) -> Result<Repulsion, ParamError> {
        self.validate()?;
        Ok(Repulsion {
            strength: self.strength,
            sigma: self.sigma,
            inv_lambda: 1.0 / self.lambda,
            taper: Taper::new(self.cutoff, self.taper),
        })
    }
}

/// The prepared exponential repulsion.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Repulsion {
    strength: Real,
    sigma: Real,
    inv_lambda: Real,
    taper: Taper,
}

impl Repulsion {
    /// The cut-off radius.
    #[inline]
    pub fn cutoff(&self) -> Real {
        self.taper.cutoff()
    }

    /// True when `strength > 0`.
    #[inline]
    pub fn is_enabled(&self) -> bool {
        self.strength > 0.0
    }

    /// `(U(r), dU/dr)`, tapered; zero beyond the cut-off.
    #[inline]
    pub fn eval(&self, r: Real) -> (Real, Real) {
        if r >= self.taper.cutoff() || self.strength == 0.0 {
            return (0.0, 0.0);
        }
        let u = self.strength * ((self.sigma - r) * self.inv_lambda).exp();
        self.taper.apply(r, u, -u * self.inv_lambda)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_at_contact_and_derivative() {
        let rep = RepulsionParams::default().prepare().unwrap();
        let (u, du) = rep.eval(1.0);
        assert!((u - 1.0).abs() < 1e-15 && (du + 10.0).abs() < 1e-13);
        for k in 0..200 {
            let r = 0.2 + 1.79 * k as Real / 199.0;
            let h = 1e-6;
            let fd = (rep.eval(r + h).0 - rep.eval(r - h).0) / (2.0 * h);
            let du = rep.eval(r).1;
            assert!(
                (fd - du).abs() < 1e-6 * (1.0 + du.abs()),
                "r={r}: {fd} vs {du}"
            );
        }
    }

    #[test]
    fn continuous_at_the_cutoff_and_disabled_at_zero_strength() {
        let rep = RepulsionParams::default().prepare().unwrap();
        let (u, du) = rep.eval(2.0 * (1.0 - 1e-7));
        assert!(u.abs() < 1e-18 && du.abs() < 1e-12);
        assert_eq!(rep.eval(2.0), (0.0, 0.0));
        let off = RepulsionParams {
            strength: 0.0,
            ..Default::default()
        }
        .prepare()
        .unwrap();
        assert!(!off.is_enabled());
        assert_eq!(off.eval(0.5), (0.0, 0.0));
    }

    /// Serde without a format crate: missing fields take their defaults,
    /// misspelt ones are rejected by name.
    #[test]
    fn deserializes_with_defaults_and_rejects_unknown_fields() {
        use serde::de::value::{Error, MapDeserializer};
        let de = |pairs: Vec<(&'static str, Real)>| {
            RepulsionParams::deserialize(MapDeserializer::<_, Error>::new(pairs.into_iter()))
        };
        let ok = de(vec![("lambda", 0.3)]).unwrap();
        assert_eq!(
            ok,
            RepulsionParams {
                lambda: 0.3,
                ..Default::default()
            }
        );
        let bad = de(vec![("lamda", 0.3)]).unwrap_err().to_string();
        assert!(bad.contains("unknown field `lamda`"), "{bad}");
    }

    #[test]
    fn validation_rejects_bad_values() {
        let d = RepulsionParams::default();
        let cases = [
            (
                RepulsionParams {
                    strength: -1.0,
                    ..d
                },
                "repulsion.strength",
            ),
            (
                RepulsionParams {
                    sigma: Real::NAN,
                    ..d
                },
                "repulsion.sigma",
            ),
            (RepulsionParams { lambda: 0.0, ..d }, "repulsion.lambda"),
            (RepulsionParams { cutoff: 0.5, ..d }, "> sigma"),
            (RepulsionParams { taper: -0.5, ..d }, "repulsion.taper"),
        ];
        for (p, needle) in cases {
            let e = p.validate().unwrap_err().within("repulsion").to_string();
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }
}
