//! Animated previews (`opsim render RUN --out run.gif`): the frames of a
//! run, every one or a [`FrameChoice`], each drawn as
//! [`super::render_run_frames`] draws one frame (the same camera: the
//! scene's view, framing the whole run, and the frame number in the
//! corner), as a GIF that loops forever.
//!
//! Each frame is quantized to its own palette of at most 256 colours: the
//! exact colours when it has no more, else the `gif` crate's NeuQuant
//! quantizer (deterministic: the same pictures give the same bytes). Each
//! frame is shown for the scene time to the next one shown, at the run's
//! frame rate (`summary.json`'s `frame_rate`): frame `n` is at `n / rate`
//! seconds, rounded to the GIF's hundredths of a second without drift.

use std::path::Path;

use rayon::prelude::*;

use super::contact_sheet::{draw_number, frame_label, ink_for, read_chosen};
use super::error::RenderError;
use super::run_dir::frame_sets;
use super::{check_area, render_with_camera, FrameChoice, RenderOptions};

/// NeuQuant's sampling factor, 1 (best) to 30 (fastest); 10 is the
/// quantizer's own recommendation.
const QUANTIZER_SPEED: i32 = 10;

/// Frames drawn at once (in parallel) before they are written: bounds the
/// pictures held in memory (32 frames of 800 x 600 are 46 MB).
const PARALLEL_FRAMES: usize = 32;

/// The frame rate assumed for a folder of frames without a `summary.json`
/// (a frame every tenth of a second).
pub const DEFAULT_FRAME_RATE: f64 = 10.0;

/// The shortest frame delay written, in hundredths of a second: viewers
/// show a GIF frame of 0 or 1 hundredth for a tenth of a second instead.
pub const MIN_DELAY_CS: u16 = 2;

/// An animated preview: the GIF's bytes and what it holds.
#[derive(Clone, Debug)]
pub struct Animation {
    /// The GIF file's bytes.
    pub gif: Vec<u8>,
    /// The frame numbers shown, in order.
    pub frames: Vec<u64>,
    /// Each frame's delay, in hundredths of a second.
    pub delays_cs: Vec<u16>,
    /// Human-readable notes, as [`super::Rendering::notes`] (each once).
    pub notes: Vec<String>,
}

/// Animates the frames `choice` picks from the run (or frame folder)
/// `dir` as a GIF that loops forever: each frame drawn as
/// [`super::render_run_frames`] draws one (the same camera, framing the
/// whole run, and the frame number in the corner), quantized to its own
/// palette of at most 256 colours (exact, else the `gif` crate's
/// deterministic NeuQuant), shown for the scene time to the next frame
/// ([`delays`]). `frame_rate` is the run's frames per unit of scene time,
/// one unit a second (`None`: [`DEFAULT_FRAME_RATE`]);
/// [`super::run_frame_rate`] reads it from the run's `summary.json`.
///
/// # Errors
/// As [`super::render_run_frames`]; [`RenderError::BadOption`] also for a
/// picture wider or taller than a GIF allows (65,535 pixels) or a frame
/// rate that is not finite and positive, [`RenderError::EncodeGif`] if
/// the encoder fails.
pub fn render_run_animation(
    dir: &Path,
    opts: &RenderOptions,
    choice: FrameChoice,
    frame_rate: Option<f64>,
) -> Result<Animation, RenderError> {
    opts.validate()?;
    let rate = frame_rate.unwrap_or(DEFAULT_FRAME_RATE);
    if !(rate.is_finite() && rate > 0.0) {
        return Err(RenderError::option(
            "frame rate",
            format!("{rate}; allowed: a finite number above 0"),
        ));
    }
    let (width, height) = (
        gif_side("width", opts.width)?,
        gif_side("height", opts.height)?,
    );
    check_area(u64::from(opts.width), u64::from(opts.height))?;
    let files = frame_sets(dir)?;
    let chosen = choice.indices(&files)?;
    let (frames, spec) = read_chosen(dir, opts, &files, &chosen)?;
    let numbers: Vec<u64> = chosen.iter().map(|&i| frame_label(&files, i)).collect();
    let delays_cs = delays(&numbers, rate);

    let encode_error = |source| RenderError::EncodeGif {
        path: dir.to_path_buf(),
        source,
    };
    let mut encoder = gif::Encoder::new(Vec::new(), width, height, &[]).map_err(encode_error)?;
    encoder
        .set_repeat(gif::Repeat::Infinite)
        .map_err(encode_error)?;
    let ink = ink_for(opts.background);
    let scale = (opts.height as usize / 120).clamp(2, 8);
    let mut notes: Vec<String> = Vec::new();
    let jobs: Vec<_> = frames.iter().zip(&numbers).zip(&delays_cs).collect();
    // Frames are drawn and quantized in parallel, a batch at a time (a
    // batch's pictures are held until they are written), and written in
    // order: the same bytes at any thread count.
    for batch in jobs.chunks(PARALLEL_FRAMES) {
        let drawn: Vec<Result<_, RenderError>> = batch
            .par_iter()
            .map(|&(((_, data), &number), &delay)| {
                let mut r = render_with_camera(data, opts, &spec)?;
                draw_number(&mut r.image, number, 2 * scale, 2 * scale, scale, ink);
                let rgb = r.image.as_raw();
                let mut frame = exact_palette_frame(width, height, rgb).unwrap_or_else(|| {
                    gif::Frame::from_rgb_speed(width, height, rgb, QUANTIZER_SPEED)
                });
                frame.delay = delay;
                Ok((frame, r.notes))
            })
            .collect();
        for result in drawn {
            let (frame, frame_notes) = result?;
            for note in frame_notes {
                if !notes.contains(&note) {
                    notes.push(note);
                }
            }
            encoder.write_frame(&frame).map_err(encode_error)?;
        }
    }
    let gif = encoder.into_inner().map_err(encode_error)?;
    Ok(Animation {
        gif,
        frames: numbers,
        delays_cs,
        notes,
    })
}

/// The frame of an RGB picture of at most 256 colours, with its exact
/// palette (colours in order of first appearance); `None` for more
/// colours (then NeuQuant quantizes). What the `gif` crate's own exact
/// path gives up to the palette's order, without its ordered map per pixel
/// (a third of the animation's time).
fn exact_palette_frame(width: u16, height: u16, rgb: &[u8]) -> Option<gif::Frame<'static>> {
    let mut index: std::collections::HashMap<[u8; 3], u8> = std::collections::HashMap::new();
    let mut palette = Vec::new();
    let mut pixels = Vec::with_capacity(rgb.len() / 3);
    let mut last: Option<([u8; 3], u8)> = None;
    for p in rgb.chunks_exact(3) {
        let colour = [p[0], p[1], p[2]];
        let k = match last {
            Some((c, k)) if c == colour => k,
            _ => {
                let next = index.len();
                let k = *index.entry(colour).or_insert_with(|| {
                    palette.extend_from_slice(&colour);
                    next.min(255) as u8
                });
                if index.len() > 256 {
                    return None;
                }
                last = Some((colour, k));
                k
            }
        };
        pixels.push(k);
    }
    Some(gif::Frame::from_palette_pixels(
        width, height, pixels, palette, None,
    ))
}

/// A picture side as a GIF takes it (at most 65,535 pixels).
fn gif_side(option: &'static str, side: u32) -> Result<u16, RenderError> {
    u16::try_from(side).map_err(|_| {
        RenderError::option(
            option,
            format!("{side} pixels; a GIF allows at most {}", u16::MAX),
        )
    })
}

/// The delay of each frame numbered `numbers` at `rate` frames a second,
/// in hundredths of a second: the time to the next frame shown (the last
/// frame: the time from the one before it, a tenth of a second when it is
/// alone), from the rounded times of both frames so the delays add up to
/// the scene time shown; at least [`MIN_DELAY_CS`].
pub fn delays(numbers: &[u64], rate: f64) -> Vec<u16> {
    let cs = |n: u64| (n as f64 / rate * 100.0).round();
    let step = |a: u64, b: u64| {
        let d = cs(b) - cs(a);
        // A delay above 655 s is shown for 655 s.
        (d.min(f64::from(u16::MAX)) as u16).max(MIN_DELAY_CS)
    };
    let mut out: Vec<u16> = numbers.windows(2).map(|w| step(w[0], w[1])).collect();
    out.push(out.last().copied().unwrap_or(10));
    out
}

/// Writes an animation's GIF at `path` atomically, as [`super::save_png`]
/// writes a picture.
///
/// # Errors
/// [`RenderError::Io`] if the directory is missing or not writable,
/// [`RenderError::BadOption`] if `path` has no file name.
pub fn save_gif(animation: &Animation, path: &Path) -> Result<(), RenderError> {
    if path.file_name().is_none() {
        return Err(RenderError::option(
            "output path",
            format!("'{}' has no file name", path.display()),
        ));
    }
    op_scene::export::write_atomically(path, |w| w.write_all(&animation.gif))
        .map_err(|e| RenderError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact palette keeps every colour of a picture of at most 256
    /// and gives up beyond.
    #[test]
    fn exact_palettes_hold_every_colour() {
        let rgb: Vec<u8> = (0..16u8).flat_map(|k| [k, 255 - k, 7]).collect();
        let f = exact_palette_frame(4, 4, &rgb).unwrap();
        let palette = f.palette.as_ref().unwrap();
        for (k, p) in rgb.chunks_exact(3).enumerate() {
            let i = usize::from(f.buffer[k]);
            assert_eq!(&palette[3 * i..3 * i + 3], p);
        }
        let many: Vec<u8> = (0..300u32)
            .flat_map(|k| [(k % 256) as u8, (k / 256) as u8, 0])
            .collect();
        assert!(exact_palette_frame(300, 1, &many).is_none());
    }

    #[test]
    fn delays_follow_the_frame_rate_without_drift() {
        // 2 frames a second: half a second each.
        assert_eq!(delays(&[0, 1, 2], 2.0), [50, 50, 50]);
        // 30 a second: 3.33 hundredths, rounded so that they add up.
        let d = delays(&(0..31).collect::<Vec<_>>(), 30.0);
        assert_eq!(d[..30].iter().map(|&x| u32::from(x)).sum::<u32>(), 100);
        assert!(d.iter().all(|&x| x == 3 || x == 4), "{d:?}");
        // Every 20th frame at 60 a second: a third of a second.
        assert_eq!(delays(&[0, 20, 40], 60.0), [33, 34, 34]);
        // Too fast for a GIF: the shortest delay viewers honour.
        assert_eq!(delays(&[0, 1], 1000.0), [MIN_DELAY_CS, MIN_DELAY_CS]);
        assert_eq!(delays(&[7], 2.0), [10]);
    }

    #[test]
    fn a_folder_of_frames_animates_and_decodes() {
        let dir = std::env::temp_dir().join(format!("op-animation-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for k in 0..3 {
            std::fs::write(
                dir.join(format!("frame_{k:05}.obj")),
                format!("o t\nv {k} 0 0\nv {} 0 0\nv {k} 1 0\nf 1 2 3\n", k + 1),
            )
            .unwrap();
        }
        let opts = RenderOptions {
            width: 64,
            height: 48,
            ..Default::default()
        };
        let a = render_run_animation(&dir, &opts, FrameChoice::ALL, Some(4.0)).unwrap();
        assert_eq!(a.frames, [0, 1, 2]);
        assert_eq!(a.delays_cs, [25, 25, 25]);
        let mut options = gif::DecodeOptions::new();
        options.set_color_output(gif::ColorOutput::RGBA);
        let mut decoder = options.read_info(a.gif.as_slice()).unwrap();
        let mut pictures = Vec::new();
        while let Some(frame) = decoder.read_next_frame().unwrap() {
            assert_eq!((frame.width, frame.height, frame.delay), (64, 48, 25));
            pictures.push(frame.buffer.to_vec());
        }
        assert_eq!(pictures.len(), 3);
        assert_ne!(pictures[0], pictures[2], "the triangle moves");
        let again = render_run_animation(&dir, &opts, FrameChoice::ALL, Some(4.0)).unwrap();
        assert_eq!(again.gif, a.gif, "deterministic");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
