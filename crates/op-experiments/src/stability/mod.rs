//! Stability (docs/model.md §6): for stiffness x time step x integrator,
//! whether a small system released near rest converged, kept oscillating
//! or diverged; the largest stable step of each integrator against the
//! stiffness; and the extreme cases (compressions, coincident particles,
//! mass ratios, impossible curvature, huge forces, a thousand particles on
//! one point). Shared by `tests/extreme_cases.rs` and
//! `examples/stability_report.rs`.
//!
//! - [`probe`]: the probe systems (a spacing pair, a form pair), their
//!   effective stiffness from the energy (largest eigenvalue of the
//!   mass-weighted Hessian) and the classification of one run.
//! - [`sweep`]: the outcome table and the largest-stable-step search with
//!   its log-log fit.
//! - [`extreme`]: the extreme scenes of `scenes/extreme/` run through the
//!   op-scene runner, and the coincident pair built in code.

pub mod extreme;
pub mod probe;
pub mod sweep;
