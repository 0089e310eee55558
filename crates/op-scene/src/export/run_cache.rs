//! Formats of one file per run ([`super::format::Files::Run`], USD): the
//! frames accumulate in a [`RunCache`] in memory and the file is written
//! whole, atomically, whenever the run writes a checkpoint and at its end
//! (also when it diverges or stops early), so the file on disk always
//! holds every frame up to the last checkpoint.
//!
//! A resumed run (`opsim run --resume`, [`crate::run::checkpoint`]) reads
//! the file back ([`RunCache::resume`]) and keeps its frames up to the
//! checkpoint's; those frames come back bit for bit (the cache holds what
//! the file holds), so the resumed run ends with the file an uninterrupted
//! run writes. The file is written before `checkpoint.bin`, so it holds at
//! least the checkpoint's frames.

use std::io::Write;
use std::path::Path;

use op_dynamics::{Real, World};

use super::geometry::FrameMesh;
use crate::built_scene::BuiltObject;

/// One sequence's geometry at a frame, as a [`RunCache`] receives it.
pub enum SequenceFrame<'a> {
    /// An object's particles, as the world holds them (positions,
    /// orientations, normals), drawn `width` across.
    Particles {
        /// The world at the frame.
        world: &'a World,
        /// The object.
        object: &'a BuiltObject,
        /// The width of each particle (absolute length).
        width: Real,
    },
    /// A mesh: a skin, a triangulation or a tool.
    Mesh(FrameMesh),
}

/// The frames of a run in a format of one file per run (module docs).
pub trait RunCache: std::fmt::Debug + Send {
    /// Adds frame `k` (the next frame): the geometry of every sequence, in
    /// the order of the run's sequences.
    ///
    /// # Errors
    ///
    /// A frame out of order or of another number of sequences.
    fn add_frame(&mut self, k: usize, frame: &[SequenceFrame<'_>]) -> std::io::Result<()>;

    /// The frames added so far.
    fn frames(&self) -> usize;

    /// Encodes the file of the frames added so far.
    ///
    /// # Errors
    ///
    /// What the encoder could not encode.
    fn encode(&self, out: &mut dyn Write) -> std::io::Result<()>;

    /// Takes back, from `file` (written by this cache's format for the same
    /// run), the frames `0..=last` (a resumed run's checkpoint's frames)
    /// in place of those added so far.
    ///
    /// # Errors
    ///
    /// A file that is missing, unreadable, of other sequences or with fewer
    /// frames.
    fn resume(&mut self, file: &Path, last: usize) -> Result<(), String>;
}
