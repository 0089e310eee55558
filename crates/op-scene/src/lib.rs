//! (in progress)
pub mod render;
