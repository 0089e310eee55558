//! Frame files written on a thread of their own while the next interval
//! runs.
//!
//! Each frame file is written atomically and synced to disk
//! ([`super::write_atomically`]): waiting for the disk took a fifth of a
//! skinned scene's run when the runner wrote its files itself. The
//! [`super::FrameWriter`] now encodes a file's bytes and hands them to a
//! [`FileQueue`], whose thread writes them in the order they came; the
//! queue holds at most `DEPTH` (64) files, so a slow disk slows the run down
//! instead of filling the memory. A file that cannot be written stops the
//! queue: the files before it are complete on disk, none after it is
//! written, and the failure (with its frame) is returned by the next
//! [`FileQueue::push`] or by [`FileQueue::finish`]. Index files (the
//! series files) are written atomically but not synced
//! ([`super::replace_atomically`], [`FileQueue::push_index`]).

use std::io::Write;
use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

use super::{replace_atomically, write_atomically};

/// The most files waiting to be written.
const DEPTH: usize = 64;

/// A file of a frame that could not be written.
#[derive(Debug)]
pub struct WriteFailure {
    /// The frame it belongs to: frames before it are complete on disk.
    pub frame: usize,
    /// The file.
    pub path: PathBuf,
    /// Why.
    pub error: std::io::Error,
}

/// One file to write: its frame, path, bytes (in pieces written one after
/// the other) and whether it is synced to disk.
type Job = (usize, PathBuf, Vec<Vec<u8>>, bool);

/// The first failure of the writing thread, shared with the queue.
type Failed = Arc<Mutex<Option<WriteFailure>>>;

/// Files written in order by a thread of their own (module docs).
#[derive(Debug, Default)]
pub struct FileQueue {
    sender: Option<SyncSender<Job>>,
    thread: Option<JoinHandle<()>>,
    failed: Failed,
}

impl FileQueue {
    /// Queues `bytes` to be written atomically to `path`, a file of frame
    /// `frame`, starting the writing thread on first use.
    ///
    /// # Errors
    ///
    /// An earlier file's failure (nothing more is written after one).
    pub fn push(
        &mut self,
        frame: usize,
        path: PathBuf,
        bytes: Vec<u8>,
    ) -> Result<(), WriteFailure> {
        self.push_pieces(frame, path, vec![bytes])
    }

    /// [`FileQueue::push`] of a file whose bytes are the concatenation of
    /// `pieces` (a format encoded in parallel hands its pieces over
    /// without joining them into one more buffer of the file's size).
    ///
    /// # Errors
    ///
    /// An earlier file's failure (nothing more is written after one).
    pub fn push_pieces(
        &mut self,
        frame: usize,
        path: PathBuf,
        pieces: Vec<Vec<u8>>,
    ) -> Result<(), WriteFailure> {
        self.send((frame, path, pieces, true))
    }

    /// [`FileQueue::push`] for an index file rewritten after every frame
    /// (a series file): written atomically after the files queued before
    /// it, not synced ([`super::replace_atomically`]).
    ///
    /// # Errors
    ///
    /// An earlier file's failure (nothing more is written after one).
    pub fn push_index(
        &mut self,
        frame: usize,
        path: PathBuf,
        bytes: Vec<u8>,
    ) -> Result<(), WriteFailure> {
        self.send((frame, path, vec![bytes], false))
    }

    /// Queues `job`, starting the writing thread on first use.
    fn send(&mut self, job: Job) -> Result<(), WriteFailure> {
        self.check()?;
        let sender = match &self.sender {
            Some(s) => s,
            None => self.start()?,
        };
        if let Err(lost) = sender.send(job) {
            // The thread ended: it records why before it does.
            self.check()?;
            let (frame, path, _, _) = lost.0;
            return Err(WriteFailure {
                frame,
                path,
                error: std::io::Error::other("the frame writing thread ended"),
            });
        }
        Ok(())
    }

    /// Waits until every queued file is written and stops the thread.
    ///
    /// # Errors
    ///
    /// The first file that could not be written.
    pub fn finish(&mut self) -> Result<(), WriteFailure> {
        self.sender = None;
        if let Some(thread) = self.thread.take() {
            if thread.join().is_err() {
                let mut failed = self.failed.lock().unwrap_or_else(PoisonError::into_inner);
                failed.get_or_insert(WriteFailure {
                    frame: 0,
                    path: PathBuf::new(),
                    error: std::io::Error::other("the frame writing thread panicked"),
                });
            }
        }
        self.check()
    }

    /// The failure recorded by the thread, if any (it stays recorded).
    fn check(&self) -> Result<(), WriteFailure> {
        let failed = self.failed.lock().unwrap_or_else(PoisonError::into_inner);
        match &*failed {
            None => Ok(()),
            Some(f) => Err(WriteFailure {
                frame: f.frame,
                path: f.path.clone(),
                error: std::io::Error::new(f.error.kind(), f.error.to_string()),
            }),
        }
    }

    /// Starts the writing thread.
    fn start(&mut self) -> Result<&SyncSender<Job>, WriteFailure> {
        let (sender, receiver) = sync_channel::<Job>(DEPTH);
        let failed = Arc::clone(&self.failed);
        let thread = std::thread::Builder::new()
            .name("opsim-frames".into())
            .spawn(move || write_all(&receiver, &failed))
            .map_err(|error| WriteFailure {
                frame: 0,
                path: PathBuf::new(),
                error,
            })?;
        self.thread = Some(thread);
        Ok(self.sender.insert(sender))
    }
}

impl Drop for FileQueue {
    /// Writes what is queued before the queue goes (a run that stops early
    /// keeps the frames it made).
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

/// The writing thread: every job in order until the queue closes or a
/// file fails.
fn write_all(jobs: &Receiver<Job>, failed: &Failed) {
    for (frame, path, pieces, sync) in jobs {
        let write = |w: &mut dyn Write| pieces.iter().try_for_each(|p| w.write_all(p));
        let written = if sync {
            write_atomically(&path, write)
        } else {
            replace_atomically(&path, write)
        };
        if let Err(error) = written {
            let mut slot = failed.lock().unwrap_or_else(PoisonError::into_inner);
            *slot = Some(WriteFailure { frame, path, error });
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Files come out in order and complete (a file in pieces as their
    /// concatenation); a file that cannot be written
    /// stops the queue and names its frame, and the ones before it stay.
    #[test]
    fn writes_in_order_and_stops_at_a_failure() {
        let dir = std::env::temp_dir().join(format!("op-file-queue-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut q = FileQueue::default();
        for k in 0..200 {
            q.push(
                k,
                dir.join(format!("f{k}")),
                format!("frame {k}").into_bytes(),
            )
            .unwrap();
        }
        let pieces = vec![b"in ".to_vec(), Vec::new(), b"pieces".to_vec()];
        q.push_pieces(200, dir.join("pieces"), pieces).unwrap();
        q.finish().unwrap();
        for k in 0..200 {
            let text = std::fs::read_to_string(dir.join(format!("f{k}"))).unwrap();
            assert_eq!(text, format!("frame {k}"));
        }
        let text = std::fs::read_to_string(dir.join("pieces")).unwrap();
        assert_eq!(text, "in pieces", "pieces are written one after the other");
        let mut q = FileQueue::default();
        q.push(0, dir.join("ok"), b"a".to_vec()).unwrap();
        q.push(1, dir.join("missing").join("f"), b"b".to_vec())
            .unwrap();
        let _ = q.push(2, dir.join("after"), b"c".to_vec());
        let failure = q.finish().unwrap_err();
        assert_eq!(failure.frame, 1);
        assert!(failure.path.ends_with("missing/f"), "{:?}", failure.path);
        assert!(dir.join("ok").exists());
        assert!(
            !dir.join("after").exists(),
            "nothing is written after a failure"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
