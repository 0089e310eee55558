//! Facade.
pub use op_dynamics;
