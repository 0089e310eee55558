//! Work-precision measurements (docs/model.md §6): each
//! case of [`case::case_table`] is run with every integrator at several
//! steps (and the adaptive scheme at several tolerances), sampled at fixed
//! scene times, and compared with a converged reference run of the same
//! scene (RK4 at a much smaller step, checked against half that step).
//! Errors: RMS position error in units of `r0`, RMS orientation error in
//! radians (angle of `q_ref⁻¹ q`), energy error against the reference and,
//! for conservative cases, the relative energy drift. Used by
//! `examples/accuracy_report.rs` (writes `reports/accuracy.md`) and
//! `tests/accuracy_orders.rs` (measured orders).

pub mod case;
pub mod run;
pub mod sweep;

pub use case::{case_table, Case, CaseEntry, Method, SceneSource};
pub use run::{errors, measure, simulate, Errors, Measurement, Timing, Trajectory};
pub use sweep::{log_slope, pareto, sweep_case, time_to_error, CaseSweep};
