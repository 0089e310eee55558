//! The experiments and report generators of oriented-particles
//! (unpublished): cohesion against Lennard-Jones and the spiral that
//! uncoils and recovers (seed 002 §3 and §5, docs/model.md §6), accuracy
//! against converged references, stability maps, the membership and
//! scaling experiments, and the plots of the reports. Shared by the
//! workspace's integration tests (`tests/shape_memory.rs`,
//! `tests/cohesion_vs_lj.rs`, ...) and the report generators in this
//! crate's `examples/` (`cargo run --profile ci -p op-experiments --example
//! NAME`: `accuracy_report`, `stability_report`, `shape_memory_report`,
//! `performance_report`, `fitting_report`, and `gallery`, which renders
//! `docs/gallery/`). The generators read and write paths under
//! [`workspace_root`].

pub mod accuracy;
pub mod machine;
pub mod matching;
pub mod membership;
pub mod oscillation;
pub mod plot;
pub mod plot_loglog;
pub mod scaling;
pub mod spiral;
pub mod spiral_damping;
pub mod stability;
pub mod triangle;

/// The workspace's root directory (where `scenes/`, `reports/` and `docs/`
/// are), from this crate's manifest directory.
pub fn workspace_root() -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // The plain path when it cannot be resolved: it names the same place.
    std::fs::canonicalize(&root).unwrap_or(root)
}

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
