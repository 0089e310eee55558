//! `metrics.csv`: one row of energies and speeds per frame.

use std::path::PathBuf;
use std::time::Instant;

use crate::export::write_atomically;

use super::{io, RunError};

/// `metrics.csv`, kept in memory and written atomically (like the frames)
/// at most every few seconds of wall time and at the end, so the file on
/// disk is always whole.
pub(super) struct Metrics {
    path: PathBuf,
    pub(super) text: String,
    saved: Instant,
}

impl Metrics {
    const HEADER: &'static str =
        "frame,time,kinetic,potential,total,oscillation,max_speed,wall_seconds\n";
    /// Seconds between two saves during a run.
    const SAVE_INTERVAL: f64 = 5.0;

    pub(super) fn new(path: PathBuf) -> Self {
        Metrics {
            path,
            text: Self::HEADER.to_string(),
            saved: Instant::now(),
        }
    }

    pub(super) fn push(&mut self, row: std::fmt::Arguments) -> Result<(), RunError> {
        use std::fmt::Write as _;
        let _ = writeln!(self.text, "{row}");
        if self.saved.elapsed().as_secs_f64() > Self::SAVE_INTERVAL {
            self.save()?;
        }
        Ok(())
    }

    pub(super) fn save(&mut self) -> Result<(), RunError> {
        self.saved = Instant::now();
        write_atomically(&self.path, |w| w.write_all(self.text.as_bytes())).map_err(io(&self.path))
    }
}
