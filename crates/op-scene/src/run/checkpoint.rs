//! Checkpoints of a run, and resuming from one (`opsim run --resume`;
//! docs/checkpoints.md).
//!
//! A run writes `checkpoint.bin` into its output directory after a frame
//! ([`CheckpointEvery`]: every so many frames, or once the wall time since
//! the last one passed a bound; and after the last frame). It holds
//! everything the run needs to go on from that frame: the world's state
//! ([`op_dynamics::checkpoint`]: particles, integrator, neighbour list,
//! bonds and their memories, heat, plastic curvatures, tools, time and
//! steps), the driver's stages' states, the scene's parts that change
//! (objects with their created particles and settled rest shapes, skins'
//! attachments, creation schedule, fit release, contact figures), and the
//! runner's own (the health and energy watches, the per-object figures,
//! `metrics.csv` so far, the frame writer's series and warnings, the
//! warnings, the wall time and stage timings so far). The frames up to it
//! are on disk before it is written, and it is written atomically: a run
//! killed at any moment leaves the previous checkpoint or the new one,
//! whole.
//!
//! A resumed run rebuilds the scene from its file, checks that it is the
//! scene the checkpoint was taken of (a hash of the scene's settings, the
//! particles it builds, the frame count and formats), puts the state back
//! and goes on from the next frame. Every step then takes the same
//! floating-point operations in the same order as in the run that was
//! interrupted, so the frames, the metrics rows and the summary are the
//! same bytes as an uninterrupted run's, at any thread count; only the
//! wall-clock figures differ, as they do between any two runs.
//!
//! The file: the magic line `opsim checkpoint\n`, the format version (u32
//! little-endian, [`FORMAT`]), the program's version (u32 length, then
//! UTF-8), the payload's length (u64) and its [`checksum`] (u64), then the
//! payload (postcard, [`op_dynamics::checkpoint::encode`]). A file of
//! another format or program version, truncated, or with any bit changed
//! is refused with a message saying which.
//!
//! A large world's checkpoint is hundreds of megabytes (289,210 particles
//! of two skinned balls: 369 MB, 276 MB of it the world's state), so it is
//! encoded in parts side by side and checksummed in chunks side by side:
//! the same bytes and checksum at any thread count.

use std::collections::BTreeMap;
use std::path::Path;

use op_dynamics::checkpoint::{decode, encode, WorldState};
use op_dynamics::Real;
use op_implicit::SkinState;
use serde::{Deserialize, Serialize};

use super::energy_watch::EnergyWatch;
use super::{Run, Tally};
use crate::built_scene::{BuiltObject, BuiltScene};
use crate::export::{FrameFormat, WriterState};
use crate::health::Health;
use crate::skins::ContactStats;

/// The checkpoint's file name in the output directory.
pub const FILE: &str = "checkpoint.bin";

/// Version of the checkpoint's layout (this module's, in the thousands,
/// and op-dynamics' [`op_dynamics::checkpoint::STATE_VERSION`]): a file of
/// another version is refused. This module's layout 3: the payload's
/// checksum is [`checksum`] (layout 2 hashed it with [`fnv1a`], a byte at
/// a time: 0.58 s of the 369 MB above, on one core).
pub const FORMAT: u32 = 3000 + op_dynamics::checkpoint::STATE_VERSION;

const MAGIC: &[u8] = b"opsim checkpoint\n";

/// The program's version a checkpoint records: a checkpoint is resumed
/// only by the version that wrote it (another may step differently).
const PROGRAM: &str = env!("CARGO_PKG_VERSION");

/// When a run writes checkpoints (always after its last frame too).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CheckpointEvery {
    /// After every `n`-th frame (`n >= 1`).
    Frames(usize),
    /// After the first frame that ends at least this many wall seconds
    /// after the last checkpoint (or the start of the run).
    Seconds(f64),
}

impl Default for CheckpointEvery {
    /// About every minute of wall time: what `opsim run` does.
    fn default() -> Self {
        CheckpointEvery::Seconds(60.0)
    }
}

impl CheckpointEvery {
    /// What the setting accepts, for messages.
    pub const EXPECTED: &'static str =
        "expected a number of frames (`10`), of wall seconds (`60s`) or `off`";

    /// Reads a setting as `opsim run --checkpoint-every` takes it: `N`
    /// frames (`N >= 1`), `Ss` wall seconds (`60s`, finite, `>= 0`), or
    /// `off` (no checkpoints: `None`). The error is the text quoted with
    /// [`CheckpointEvery::EXPECTED`].
    pub fn parse_setting(text: &str) -> Result<Option<CheckpointEvery>, String> {
        let bad = || format!("{text:?}: {}", Self::EXPECTED);
        if text == "off" {
            return Ok(None);
        }
        if let Some(seconds) = text.strip_suffix('s') {
            return match seconds.parse::<f64>() {
                Ok(s) if s.is_finite() && s >= 0.0 => Ok(Some(CheckpointEvery::Seconds(s))),
                _ => Err(bad()),
            };
        }
        match text.parse::<usize>() {
            Ok(n) if n >= 1 => Ok(Some(CheckpointEvery::Frames(n))),
            _ => Err(bad()),
        }
    }
}

/// The 64-bit FNV-1a hash of `bytes` (the checkpoint's integrity check
/// and its scene hash: not a cryptographic one).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Bytes per chunk of [`checksum`].
const CHUNK: usize = 1 << 20;

/// The checkpoint's integrity check (not a cryptographic hash): the
/// payload cut into chunks of 1 MiB, each hashed by a four-lane
/// multiply-xor over its 64-bit words (in parallel), then [`fnv1a`] of the
/// length and the chunks' hashes. A changed byte always changes its
/// lane's value (every round is a bijection of the lane for a fixed word,
/// and of the word for a fixed lane), and so the checksum but for a
/// 64-bit collision. The same value at any thread count.
pub fn checksum(bytes: &[u8]) -> u64 {
    checksum_parts(&[bytes])
}

/// [`checksum`] of the payload `parts` one after another, without joining
/// them (a chunk across parts is copied).
fn checksum_parts(parts: &[&[u8]]) -> u64 {
    use rayon::prelude::*;
    let total: usize = parts.iter().map(|p| p.len()).sum();
    let starts: Vec<usize> = parts
        .iter()
        .scan(0, |at, p| {
            let start = *at;
            *at += p.len();
            Some(start)
        })
        .collect();
    let hashes: Vec<u64> = (0..total.div_ceil(CHUNK))
        .into_par_iter()
        .with_min_len(4)
        .map(|c| {
            let (from, to) = (c * CHUNK, ((c + 1) * CHUNK).min(total));
            // The part holding the chunk's first byte: whole in it, or
            // gathered across the parts it spans.
            let k = starts.partition_point(|&s| s <= from) - 1;
            let local = from - starts[k];
            if starts[k] + parts[k].len() >= to {
                chunk_hash(&parts[k][local..local + (to - from)])
            } else {
                let mut chunk = Vec::with_capacity(to - from);
                let mut at = from;
                for (p, &s) in parts.iter().zip(&starts).skip(k) {
                    if at >= to {
                        break;
                    }
                    let end = (s + p.len()).min(to);
                    chunk.extend_from_slice(&p[at - s..end - s]);
                    at = end;
                }
                chunk_hash(&chunk)
            }
        })
        .collect();
    let mut summary = Vec::with_capacity(8 * (hashes.len() + 1));
    summary.extend_from_slice(&(total as u64).to_le_bytes());
    for h in hashes {
        summary.extend_from_slice(&h.to_le_bytes());
    }
    fnv1a(&summary)
}

/// A multiply-xor hash of `chunk`'s 64-bit words in four lanes (four
/// independent multiply chains, 32 bytes per round, where FNV-1a takes one
/// multiply per byte), the bytes past the last whole round folded in by
/// FNV-1a, the lanes combined by FNV-1a.
fn chunk_hash(chunk: &[u8]) -> u64 {
    // Odd, so that multiplying by it is a bijection of the lane.
    const PRIME: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut lanes: [u64; 4] = [1, 2, 3, 4].map(|k| 0xcbf2_9ce4_8422_2325_u64.wrapping_mul(k));
    let mut rounds = chunk.chunks_exact(32);
    for round in &mut rounds {
        for (k, lane) in lanes.iter_mut().enumerate() {
            let mut word = [0u8; 8];
            word.copy_from_slice(&round[8 * k..8 * k + 8]);
            *lane = (*lane ^ u64::from_le_bytes(word)).wrapping_mul(PRIME);
        }
    }
    let mut tail = Vec::with_capacity(64);
    for lane in lanes {
        tail.extend_from_slice(&lane.to_le_bytes());
    }
    tail.extend_from_slice(rounds.remainder());
    fnv1a(&tail)
}

/// What identifies the run a checkpoint belongs to: the scene as built
/// ([`BuiltScene::inputs`]), the particles it built (data files read by
/// the scene), the frame count and the formats. Taken before the first
/// step.
pub(super) fn run_inputs(scene: &BuiltScene, total: usize, formats: &[FrameFormat]) -> u64 {
    let mut bytes = encode(scene.world.particles());
    bytes.extend_from_slice(&scene.inputs.to_le_bytes());
    bytes.extend_from_slice(&(total as u64).to_le_bytes());
    for f in formats {
        bytes.extend_from_slice(f.extension().as_bytes());
        bytes.push(b',');
    }
    checksum(&bytes)
}

/// Everything a run needs to go on after frame [`Checkpoint::frame`]
/// (module docs). `W` is the world's state: a [`WorldState`] once read;
/// nothing (`()`) when taken to be written, the world encoding its state
/// straight from itself ([`op_dynamics::World::encode_state`]), without a
/// copy of it (0.4 s of the 276 MB above).
#[derive(Serialize, Deserialize)]
pub(super) struct Checkpoint<W = WorldState> {
    /// [`run_inputs`] of the run.
    pub inputs: u64,
    /// The scene's name (for messages).
    pub scene: String,
    /// The last frame written.
    pub frame: usize,
    /// World time of frame 0.
    pub t0: Real,
    pub world: W,
    pub driver: Vec<(String, Vec<u8>)>,
    pub objects: Vec<BuiltObject>,
    pub skins: Vec<Vec<SkinState>>,
    pub contact: ContactStats,
    /// The creation rules' next step and, with a fit, whether its samples
    /// were released.
    pub creation: Option<(u64, Option<bool>)>,
    pub settled: bool,
    pub tally: Tally,
    pub health: Health,
    pub watch: EnergyWatch,
    /// `metrics.csv` so far, when the run writes it.
    pub metrics: Option<String>,
    pub writer: WriterState,
    pub warnings: Vec<String>,
    /// What a resumed run counts on from ([`Carried`]).
    pub wall_seconds: f64,
    pub setup_seconds: f64,
    pub stages: BTreeMap<String, f64>,
}

impl<W> Checkpoint<W> {
    /// [`encode`] of the checkpoint in parts, encoded side by side, the
    /// world's state in the parts `world` makes: the parts one after
    /// another are its encoding (postcard writes a struct as its fields one
    /// after another). Joining them would copy hundreds of megabytes into
    /// fresh pages (0.43 s of the 369 MB above).
    fn encode_parts(&self, world: impl Fn() -> Vec<Vec<u8>> + Sync) -> Vec<Vec<u8>>
    where
        W: Sync,
    {
        use rayon::prelude::*;
        let parts: Vec<Vec<Vec<u8>>> = (0..5)
            .into_par_iter()
            .map(|k| match k {
                0 => vec![encode(&(self.inputs, &self.scene, self.frame, self.t0))],
                1 => world(),
                2 => vec![encode(&(&self.driver, &self.objects))],
                3 => vec![encode(&self.skins)],
                _ => vec![encode(&(
                    &self.contact,
                    &self.creation,
                    self.settled,
                    &self.tally,
                    &self.health,
                    &self.watch,
                    &self.metrics,
                    &self.writer,
                    &self.warnings,
                    self.wall_seconds,
                    self.setup_seconds,
                    &self.stages,
                ))],
            })
            .collect();
        parts.into_iter().flatten().collect()
    }
}

impl Checkpoint<()> {
    /// The checkpoint of `scene` and the runner after frame `frame`, whose
    /// files are all on disk; the world's state is left to
    /// [`Checkpoint::write`], which encodes it from the world.
    pub fn take(
        scene: &BuiltScene,
        run: &Run,
        at: (usize, Real),
        inputs: u64,
        carried: Carried,
    ) -> Self {
        Checkpoint {
            inputs,
            scene: scene.name.clone(),
            frame: at.0,
            t0: at.1,
            world: (),
            driver: scene.driver.states(),
            objects: scene.objects.clone(),
            skins: scene.skins.iter().map(|s| s.state()).collect(),
            contact: scene.contact,
            creation: scene
                .creation
                .as_ref()
                .map(|c| (c.next_step, c.fit.as_ref().map(|f| f.released))),
            settled: scene.settled,
            tally: run.tally.snapshot(),
            health: run.health.clone(),
            watch: run.watch.clone(),
            metrics: run.metrics.as_ref().map(|m| m.text.clone()),
            writer: run.writer.state(),
            warnings: run.warnings.clone(),
            wall_seconds: carried.wall_seconds,
            setup_seconds: carried.setup_seconds,
            stages: carried.stages,
        }
    }

    /// Writes the checkpoint, with the state of `world`, to `path`
    /// atomically.
    pub fn write(&self, world: &op_dynamics::World, path: &Path) -> std::io::Result<()> {
        let parts = self.encode_parts(|| world.encode_state());
        let parts: Vec<&[u8]> = parts.iter().map(Vec::as_slice).collect();
        let length: usize = parts.iter().map(|p| p.len()).sum();
        let hash = checksum_parts(&parts);
        crate::export::write_atomically(path, |w| {
            w.write_all(MAGIC)?;
            w.write_all(&FORMAT.to_le_bytes())?;
            w.write_all(&(PROGRAM.len() as u32).to_le_bytes())?;
            w.write_all(PROGRAM.as_bytes())?;
            w.write_all(&(length as u64).to_le_bytes())?;
            w.write_all(&hash.to_le_bytes())?;
            parts.iter().try_for_each(|p| w.write_all(p))
        })
    }
}

impl Checkpoint {
    /// Reads a checkpoint written by [`Checkpoint::write`]; the error says
    /// what is wrong with the file.
    pub fn read(path: &Path) -> Result<Checkpoint, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("cannot read it: {e}"))?;
        let mut rest = bytes
            .strip_prefix(MAGIC)
            .ok_or("it is not an opsim checkpoint (its first line is not `opsim checkpoint`)")?;
        let mut take = |n: usize| -> Result<&[u8], String> {
            if rest.len() < n {
                return Err("it is truncated (it ends inside its header)".into());
            }
            let (head, tail) = rest.split_at(n);
            rest = tail;
            Ok(head)
        };
        let u32_at = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        let u64_at = |b: &[u8]| {
            let mut a = [0u8; 8];
            a.copy_from_slice(b);
            u64::from_le_bytes(a)
        };
        let format = u32_at(take(4)?);
        let program_len = u32_at(take(4)?) as usize;
        let program = String::from_utf8_lossy(take(program_len.min(256))?).into_owned();
        if format != FORMAT || program != PROGRAM {
            return Err(format!(
                "it was written by opsim {program} (checkpoint format {format}); this opsim \
                 {PROGRAM} resumes only its own (format {FORMAT}): run the scene again \
                 without --resume, or resume with the opsim that wrote it"
            ));
        }
        let length = u64_at(take(8)?);
        let hash = u64_at(take(8)?);
        if rest.len() as u64 != length {
            return Err(format!(
                "it is truncated or damaged: its payload has {} bytes, its header says {length}",
                rest.len()
            ));
        }
        if checksum(rest) != hash {
            return Err("it is damaged: its payload does not match its checksum".into());
        }
        decode(rest).map_err(|e| format!("it is damaged: {e}"))
    }
}

/// What a resumed run carries over from the run it continues: the wall
/// seconds and stage timings up to the checkpoint.
#[derive(Clone, Debug, Default)]
pub(super) struct Carried {
    /// Seconds of the runs' clocks (the `wall_seconds` of `metrics.csv`).
    pub wall_seconds: f64,
    /// Seconds spent making the scene in each of them.
    pub setup_seconds: f64,
    pub stages: BTreeMap<String, f64>,
}

impl Checkpoint {
    /// Puts the checkpoint back into `scene` (built from the same scene
    /// file as the run it was taken of) and the runner; returns the frame
    /// to go on from, the world time of frame 0 and what the resumed run
    /// carries over. When it fails, `scene` may be left half restored:
    /// it is not to be run.
    pub fn restore(
        self,
        scene: &mut BuiltScene,
        run: &mut Run,
        inputs: u64,
    ) -> Result<(usize, Real, Carried), String> {
        if self.inputs != inputs {
            return Err(format!(
                "it was taken of another run: scene {:?} with other settings, particles, \
                 frame count or formats (resume with the same scene file and the same \
                 --frames and --format, or run without --resume to start over)",
                self.scene
            ));
        }
        let names = |o: &[BuiltObject]| o.iter().map(|o| o.name.clone()).collect::<Vec<_>>();
        if names(&self.objects) != names(&scene.objects)
            || self.skins.len() != scene.skins.len()
            || self.creation.is_some() != scene.creation.is_some()
        {
            return Err("its objects, skins or creation rules are not the scene's".into());
        }
        let damaged = |e: &dyn std::fmt::Display| format!("it does not fit the scene: {e}");
        scene.world.restore(self.world).map_err(|e| damaged(&e))?;
        scene
            .driver
            .restore(&self.driver)
            .map_err(|e| damaged(&e))?;
        for (skin, state) in scene.skins.iter_mut().zip(self.skins) {
            skin.restore(state, scene.world.particles())
                .map_err(|e| damaged(&e))?;
        }
        run.writer
            .restore(self.writer, self.frame)
            .map_err(|e| damaged(&e))?;
        scene.objects = self.objects;
        scene.contact = self.contact;
        if let (Some(c), Some((next, released))) = (scene.creation.as_mut(), self.creation) {
            c.next_step = next;
            if let (Some(f), Some(r)) = (c.fit.as_mut(), released) {
                f.released = r;
            }
        }
        scene.settled = self.settled;
        run.tally = self.tally;
        run.health = self.health;
        run.watch = self.watch;
        if let (Some(m), Some(text)) = (run.metrics.as_mut(), self.metrics) {
            m.text = text;
        }
        run.warnings = self.warnings;
        Ok((
            self.frame + 1,
            self.t0,
            Carried {
                wall_seconds: self.wall_seconds,
                setup_seconds: self.setup_seconds,
                stages: self.stages,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use op_dynamics::checkpoint::encode_state;

    use super::*;
    use crate::run::{run, RunOptions};

    /// Bytes that are not all alike: a 64-bit LCG's top bytes.
    fn bytes(n: usize) -> Vec<u8> {
        let mut x = 0x2545_f491_4f6c_dd1d_u64;
        (0..n)
            .map(|_| {
                x = x
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (x >> 56) as u8
            })
            .collect()
    }

    /// Any one changed byte (in a whole round, the tail of a chunk, at a
    /// chunk's edge, in the last short chunk), a truncation or an appended
    /// zero changes the checksum; it is the same at 1 and 2 threads.
    #[test]
    fn the_checksum_changes_with_any_byte_and_not_with_threads() {
        let data = bytes(2 * CHUNK + 1000 + 7);
        let base = checksum(&data);
        for at in [
            0,
            31,
            32,
            CHUNK - 1,
            CHUNK,
            CHUNK + 17,
            2 * CHUNK + 999,
            2 * CHUNK + 1006,
        ] {
            for flip in [1u8, 0x80] {
                let mut d = data.clone();
                d[at] ^= flip;
                assert_ne!(checksum(&d), base, "byte {at} ^ {flip:#x}");
            }
        }
        assert_ne!(checksum(&data[..data.len() - 1]), base, "truncated");
        let mut longer = data.clone();
        longer.push(0);
        assert_ne!(checksum(&longer), base, "a zero appended");
        assert_ne!(checksum(&[]), checksum(&[0]));
        // In parts, cut anywhere (inside a chunk, at its edge, empty parts).
        for cuts in [
            vec![0, 10, CHUNK + 5, data.len()],
            vec![0, CHUNK, CHUNK, 2 * CHUNK - 1, data.len()],
            vec![0, 0, 1, 2, 3, data.len() - 1, data.len()],
        ] {
            let parts: Vec<&[u8]> = cuts.windows(2).map(|w| &data[w[0]..w[1]]).collect();
            assert_eq!(checksum_parts(&parts), base, "cut at {cuts:?}");
        }
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            assert_eq!(pool.install(|| checksum(&data)), base, "{threads} threads");
        }
    }

    /// A skinned scene's checkpoint encoded in parts side by side is its
    /// postcard encoding, byte for byte, and reads back.
    #[test]
    fn a_checkpoint_encoded_in_parts_is_its_encoding() {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/ball_vs_spiral.ron");
        let dir = std::env::temp_dir().join(format!("op-scene-parts-{}", std::process::id()));
        let opts = RunOptions {
            out_dir: dir.clone(),
            frames: Some(2),
            formats: vec![crate::export::FrameFormat::PLY],
            checkpoints: Some(CheckpointEvery::Frames(1)),
            resume: false,
        };
        let mut built = crate::load_scene(&scene)
            .expect("the scene loads")
            .build(None, None)
            .expect("the scene builds");
        run(&mut built, &opts, &mut |_, _| {}).expect("the scene runs");
        let c = Checkpoint::read(&dir.join(FILE)).expect("the checkpoint reads back");
        assert!(!c.skins.is_empty(), "the scene has skins");
        let parts = c.encode_parts(|| encode_state(&c.world));
        assert!(parts.len() > 5, "the world's state in parts");
        assert!(
            parts.concat() == encode(&c),
            "parts in the encoding's order"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
