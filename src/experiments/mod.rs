//! The experiments of seed 002 §3 and §5 (docs/model.md §6): cohesion against
//! Lennard-Jones, and the spiral that uncoils and recovers. Shared by the
//! integration tests (`tests/shape_memory.rs`, `tests/cohesion_vs_lj.rs`)
//! and the report generator (`examples/shape_memory_report.rs`).

pub mod accuracy;
pub mod machine;
pub mod matching;
pub mod membership;
pub mod oscillation;
pub mod plot;
pub mod plot_loglog;
pub mod scaling;
pub mod spiral;
pub mod stability;
pub mod triangle;

/// Runs `f` on a local pool of one worker thread. The experiments step
/// tiny worlds (3 to a few dozen particles), where a parallel pass costs
/// more in scheduling than it saves; results are the same at any thread
/// count. Does not touch the global pool.
///
/// # Panics
///
/// If the pool cannot be started.
pub fn single_threaded<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool")
        .install(f)
}
