//! Pair interactions of oriented particles: energies, and the forces and
//! torques derived from them (docs/model.md §3; seed 000 §3 and App. B, seed 002
//! §3-5).
//!
//! # Entry points
//!
//! - [`Material`] (serde, validated) → [`Material::prepare`] →
//!   [`PreparedMaterial`]: tables built, enabled terms fixed, the neighbour
//!   radius it needs ([`PreparedMaterial::cutoff`]).
//! - [`evaluate_pair`]: energy, forces and torques of one unordered pair,
//!   both directions `E_ij` and `E_ji` evaluated in one visit, for a
//!   [`Coupling`] (complete, oriented or not, or repulsion only).
//! - [`evaluate_spacing`]: the spacing-only fast path.
//!
//! ```
//! use op_dynamics::interactions::{evaluate_pair, Coupling, Material, ParticleView};
//! use op_dynamics::math::{Point3, Vec3};
//!
//! // Cohesion spacing plus co-planarity and shape memory (seed 002 §5).
//! let material = Material { coplanarity: 1.0, form: 2.0, ..Material::default() };
//! let m = material.prepare().expect("valid material");
//! assert_eq!(m.enabled_terms(), ["cohesion", "coplanarity", "form", "repulsion"]);
//! let view = |x: f64| ParticleView {
//!     position: Point3::new(x, 0.0, 0.0),
//!     normal: Vec3::z(),
//!     tangent: Vec3::x(),
//!     kappa: 0.0,
//!     material: &m,
//! };
//! let res = evaluate_pair(&view(0.0), &view(1.2), Coupling::Complete { oriented: true });
//! assert!(res.force_j.x < 0.0); // beyond r0 = 1: attraction
//! assert_eq!(res.force_i, -res.force_j);
//! ```
//!
//! # Terms, one file each
//!
//! | file | energy (before weighting) | seed |
//! |---|---|---|
//! | [`lennard_jones`] | `ε/(n-m) [m (r0/r)ⁿ - n (r0/r)ᵐ]` | 000 eq. 5 |
//! | [`cohesion`] | `∫_r^{r_c} E (r0-s)³/s e^{-α(r0-s)²} ds` (exact or tabulated) | 002 §3 |
//! | [`repulsion`] | `ε exp((σ - r)/λ)` | 002 §5 |
//! | [`coplanarity`] | `(n_i·r)²` (normalized `/|r|²`) | 000 eq. 6 |
//! | [`conormality`] | `|n_i - n_j|²` | 000 eq. 7 |
//! | [`cocircularity`] | `((n_i+n_j)·r)²` (normalized `/|r|²`) | 000 eq. 8 |
//! | [`form`] | `|r + (n_i-n_j)/κ_i|²` (normalized `|κ_i r + n_i - n_j|²`) | 002 §4 |
//! | [`spin`] | `x² z` or `x² z²` (normalized `/|r|³`, `/|r|⁴`), torque about `n_i` only | 000 eq. 14-15 |
//!
//! Orientation terms are weighted by `ψ` ([`weight`], seed 000 eq. 10) and
//! every term is tapered to zero at its cut-off ([`cutoff`]), so energy and
//! force are continuous when a pair leaves the neighbour radius. The
//! normalized co-planarity, co-circularity and spin terms, which depend on
//! the direction of `r` only, also fade to zero below a coincidence radius
//! (a quarter of the spacing's rest distance, see [`material`]), so they
//! stay continuous and bounded when particles overlap.
//!
//! Forces and torques are never typed in from the papers' tables (which
//! contain typos): each term returns its gradients with respect to `r`,
//! `n_i` and `n_j`, and [`pair`] turns them into forces and torques by the
//! rules documented there. Tests compare every term against central finite
//! differences of the pair energy and check momentum conservation.

pub mod cocircularity;
pub mod cohesion;
pub mod conormality;
pub mod coplanarity;
pub mod cutoff;
pub mod form;
pub mod lennard_jones;
pub mod material;
pub mod pair;
pub mod quadrature;
pub mod repulsion;
pub mod spacing;
pub mod spin;
pub mod weight;

#[cfg(test)]
pub(crate) mod test_support;

pub use cohesion::{Cohesion, CohesionMode, CohesionParams};
pub use cutoff::Taper;
pub use lennard_jones::{LennardJones, LennardJonesParams};
pub use material::{Material, PreparedMaterial};
pub use pair::{
    evaluate_pair, evaluate_pair_weakened, evaluate_spacing, evaluate_spacing_sq,
    evaluate_spacing_weakened, Coupling, OrientationGrad, PairGeometry, PairResult, ParticleView,
    TermGrad,
};
pub use repulsion::{Repulsion, RepulsionParams};
pub use spacing::{Spacing, SpacingKernel};
pub use spin::SpinKind;
pub use weight::{Weight, WeightParams, WeightShape};
