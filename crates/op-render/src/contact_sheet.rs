//! Contact sheets: frames of a run in a grid, seen from one fixed camera.

use std::path::Path;

use image::RgbImage;

use super::error::RenderError;
use super::run_dir::{frame_sets, read_frame, FrameSet};
use super::{
    auto_camera, check_area, render_with_camera, CameraSpec, ObjData, RenderOptions, Rendering,
};

/// Renders a grid of at most `max_frames` frames chosen evenly (first and last
/// included) from the frames of `dir`: its `*.obj` files (one frame each,
/// sorted by name with numbers in numeric order), else the numbered files of
/// its subfolders or of `dir/frames`'s (one file per object, those with the
/// same number making one frame: the layout `opsim run` writes).
///
/// Each cell is `opts.width x opts.height` and is labelled with the frame's
/// index (the number in its file name, else its rank). The grid has
/// [`sheet_grid`]`(n)` columns and rows for `n` frames. The camera is
/// `opts.camera`, or frames the whole run (the chosen frames and up to 64
/// frames spread over it), so motion shows and stays in the picture.
///
/// # Errors
/// [`RenderError::BadOption`] for `max_frames == 0`, bad options or a sheet larger
/// than [`super::MAX_PIXELS`]; [`RenderError::Io`] if the directory cannot be
/// read; [`RenderError::Empty`] if it holds no OBJ file or the frames have no
/// vertex; [`RenderError::Parse`] for a malformed frame.
pub fn render_contact_sheet(
    dir: &Path,
    opts: &RenderOptions,
    max_frames: usize,
) -> Result<RgbImage, RenderError> {
    contact_sheet(dir, opts, max_frames).map(|r| r.image)
}

/// Frames (at most) whose bounds the automatic camera of a contact sheet
/// frames, spread evenly over the run.
const FRAMED_FRAMES: usize = 64;

/// Columns and rows of the contact sheet of `frames` frames (`ceil(sqrt(n))` columns).
pub fn sheet_grid(frames: usize) -> (usize, usize) {
    if frames == 0 {
        return (0, 0);
    }
    let mut cols = (frames as f64).sqrt().ceil() as usize;
    while cols * cols < frames {
        cols += 1;
    }
    (cols, frames.div_ceil(cols))
}

/// Which frames of a run a picture shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameChoice {
    /// At most this many frames, chosen evenly, first and last included
    /// (`opsim render RUN --frames 9`).
    Spread(usize),
    /// The frames numbered `first`, `first + step`, ... up to `last`
    /// (`--frames A:B:S`; `--frame K` is `K:K:1`).
    Numbers {
        /// First frame number.
        first: u64,
        /// Last frame number (included when on the step).
        last: u64,
        /// Step between frame numbers, >= 1.
        step: u64,
    },
}

impl FrameChoice {
    /// Every frame of the run (`opsim render RUN --out run.gif` without
    /// `--frames`).
    pub const ALL: FrameChoice = FrameChoice::Spread(usize::MAX);

    /// The indices into `files` (frame number or rank, and files) chosen.
    pub(crate) fn indices<T>(&self, files: &[(Option<u64>, T)]) -> Result<Vec<usize>, RenderError> {
        match *self {
            FrameChoice::Spread(0) => {
                Err(RenderError::option("max_frames", "0; allowed: 1 or more"))
            }
            FrameChoice::Spread(m) => Ok(choose(files.len(), m)),
            FrameChoice::Numbers { step: 0, .. } => Err(RenderError::option(
                "frames",
                "a step of 0; allowed: 1 or more",
            )),
            FrameChoice::Numbers { first, last, step } => {
                let number = |k: usize| files[k].0.unwrap_or(k as u64);
                let chosen: Vec<usize> = (0..files.len())
                    .filter(|&k| {
                        let n = number(k);
                        (first..=last).contains(&n) && (n - first) % step == 0
                    })
                    .collect();
                if chosen.is_empty() {
                    let range = match files.len() {
                        0 => "none".to_string(),
                        len => format!("{} to {}", number(0), number(len - 1)),
                    };
                    return Err(RenderError::option(
                        "frames",
                        format!(
                            "{first}:{last}:{step} selects no frame; the run has frames {range}"
                        ),
                    ));
                }
                Ok(chosen)
            }
        }
    }
}

/// [`render_contact_sheet`] with the notes of every frame (each note once).
pub(crate) fn contact_sheet(
    dir: &Path,
    opts: &RenderOptions,
    max_frames: usize,
) -> Result<Rendering, RenderError> {
    render_run_frames(dir, opts, FrameChoice::Spread(max_frames))
}

/// The frames `choice` picks from the run (or frame folder) `dir`, in a
/// grid as [`render_contact_sheet`] draws them (one frame: one labelled
/// picture), seen from `opts.camera` or from the camera that frames the
/// whole run, so that pictures of different frames of a run compare.
///
/// # Errors
/// As [`render_contact_sheet`]; [`RenderError::BadOption`] also for a
/// choice that selects no frame (the message gives the run's frame
/// numbers) or a step of 0.
pub fn render_run_frames(
    dir: &Path,
    opts: &RenderOptions,
    choice: FrameChoice,
) -> Result<Rendering, RenderError> {
    opts.validate()?;
    let files = frame_sets(dir)?;
    let chosen = choice.indices(&files)?;
    let (cols, rows) = sheet_grid(chosen.len());
    let (w, h) = (opts.width as usize, opts.height as usize);
    check_area((cols * w) as u64, (rows * h) as u64)?;
    let (frames, spec) = read_chosen(dir, opts, &files, &chosen)?;

    let mut sheet = RgbImage::from_pixel(
        (cols * w) as u32,
        (rows * h) as u32,
        image::Rgb(opts.background),
    );
    let mut notes: Vec<String> = Vec::new();
    let ink = ink_for(opts.background);
    let scale = (h / 120).clamp(2, 8);
    for (cell, (rank, data)) in frames.iter().enumerate() {
        let r = render_with_camera(data, opts, &spec)?;
        for note in r.notes {
            if !notes.contains(&note) {
                notes.push(note);
            }
        }
        let (x0, y0) = ((cell % cols) * w, (cell / cols) * h);
        for (x, y, px) in r.image.enumerate_pixels() {
            sheet.put_pixel(x0 as u32 + x, y0 as u32 + y, *px);
        }
        let label = frame_label(&files, *rank);
        draw_number(
            &mut sheet,
            label,
            x0 + 2 * scale,
            y0 + 2 * scale,
            scale,
            ink,
        );
    }
    draw_separators(&mut sheet, cols, rows, w, h, ink);
    Ok(Rendering {
        image: sheet,
        notes,
    })
}

/// The frames at `chosen` (indices into `files`, the run `dir`'s frames),
/// read, with the camera that shows them: `opts.camera`, or the camera
/// that frames the whole run (the chosen frames and up to
/// [`FRAMED_FRAMES`] more spread over it), so that pictures of different
/// frames of a run compare.
pub(crate) fn read_chosen(
    dir: &Path,
    opts: &RenderOptions,
    files: &[FrameSet],
    chosen: &[usize],
) -> Result<(Vec<(usize, ObjData)>, CameraSpec), RenderError> {
    let mut frames = Vec::with_capacity(chosen.len());
    for &i in chosen {
        frames.push((i, read_frame(&files[i].1)?));
    }
    let spec = match opts.camera {
        Some(spec) => spec,
        None => {
            if frames.iter().all(|(_, d)| d.vertex_count() == 0) {
                return Err(RenderError::empty(format!(
                    "the frames in {} have no vertices",
                    dir.display()
                )));
            }
            let mut framed = Vec::new();
            for i in choose(files.len(), FRAMED_FRAMES) {
                if !chosen.contains(&i) {
                    framed.push(read_frame(&files[i].1)?);
                }
            }
            auto_camera(frames.iter().map(|(_, d)| d).chain(&framed), opts)
        }
    };
    Ok((frames, spec))
}

/// The label of frame `rank` of `files`: the number in its file names,
/// else its rank.
pub(crate) fn frame_label(files: &[FrameSet], rank: usize) -> u64 {
    files[rank].0.unwrap_or(rank as u64)
}

/// `min(m, n)` indices out of `0..n`, evenly spread, first and last included
/// (just the last when `m == 1`).
fn choose(n: usize, m: usize) -> Vec<usize> {
    if m >= n {
        return (0..n).collect();
    }
    if m == 1 {
        return vec![n - 1];
    }
    (0..m)
        .map(|i| (i * (n - 1) + (m - 1) / 2) / (m - 1))
        .collect()
}

/// Dark ink on a light background, light ink on a dark one.
pub(crate) fn ink_for(bg: [u8; 3]) -> [u8; 3] {
    let luma = 0.299 * f64::from(bg[0]) + 0.587 * f64::from(bg[1]) + 0.114 * f64::from(bg[2]);
    if luma > 128.0 {
        [40, 40, 40]
    } else {
        [225, 225, 225]
    }
}

fn draw_separators(
    sheet: &mut RgbImage,
    cols: usize,
    rows: usize,
    w: usize,
    h: usize,
    ink: [u8; 3],
) {
    let line = image::Rgb(ink.map(|c| ((u16::from(c) + 2 * 160) / 3) as u8));
    for c in 1..cols {
        for y in 0..sheet.height() {
            sheet.put_pixel((c * w) as u32, y, line);
        }
    }
    for r in 1..rows {
        for x in 0..sheet.width() {
            sheet.put_pixel(x, (r * h) as u32, line);
        }
    }
}

/// 5x7 bitmaps of the digits 0-9, one row per byte, bit 4 leftmost.
const DIGITS: [[u8; 7]; 10] = [
    [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
    [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
    [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
    [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
    [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
    [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
    [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
    [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
    [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
    [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
];

/// Draws the decimal `value` with its top-left corner at `(x, y)`, each font
/// pixel `scale x scale`; clipped to the image.
pub(crate) fn draw_number(
    img: &mut RgbImage,
    value: u64,
    x: usize,
    y: usize,
    scale: usize,
    ink: [u8; 3],
) {
    let text = value.to_string();
    for (k, ch) in text.bytes().enumerate() {
        let glyph = &DIGITS[usize::from(ch - b'0')];
        let gx = x + k * 6 * scale;
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..5 {
                if bits & (0x10 >> col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (px, py) = (gx + col * scale + dx, y + row * scale + dy);
                        if px < img.width() as usize && py < img.height() as usize {
                            img.put_pixel(px as u32, py as u32, image::Rgb(ink));
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn grid_shapes() {
        assert_eq!(sheet_grid(0), (0, 0));
        assert_eq!(sheet_grid(1), (1, 1));
        assert_eq!(sheet_grid(2), (2, 1));
        assert_eq!(sheet_grid(5), (3, 2));
        assert_eq!(sheet_grid(9), (3, 3));
        assert_eq!(sheet_grid(10), (4, 3));
    }

    #[test]
    fn frames_chosen_evenly() {
        assert_eq!(choose(5, 10), vec![0, 1, 2, 3, 4]);
        assert_eq!(choose(11, 3), vec![0, 5, 10]);
        assert_eq!(choose(100, 4), vec![0, 33, 66, 99]);
        assert_eq!(choose(7, 1), vec![6]);
        let c = choose(1000, 12);
        assert_eq!(c.len(), 12);
        assert!(c.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn numeric_file_order() {
        use super::super::run_dir::{frame_number, sort_key};
        let mut names: Vec<PathBuf> = ["f10.obj", "f9.obj", "f100.obj", "a.obj"]
            .iter()
            .map(PathBuf::from)
            .collect();
        names.sort_by_cached_key(|p| sort_key(p));
        let sorted: Vec<_> = names.iter().map(|p| p.to_str().unwrap()).collect();
        assert_eq!(sorted, ["a.obj", "f9.obj", "f10.obj", "f100.obj"]);
        assert_eq!(frame_number(Path::new("d/frame_00012.obj")), Some(12));
        assert_eq!(frame_number(Path::new("d/frame.obj")), None);
    }

    #[test]
    fn digits_are_drawn_and_clipped() {
        let mut img = RgbImage::from_pixel(40, 20, image::Rgb([255, 255, 255]));
        draw_number(&mut img, 1234567890, 1, 1, 2, [0, 0, 0]);
        let inked = img.pixels().filter(|p| p.0 == [0, 0, 0]).count();
        assert!(inked > 50, "{inked}");
        // "1": the foot of the 1 (row 6 is 0x0E) is inked, its top-left corner is not.
        assert_eq!(img.get_pixel(1, 1).0, [255, 255, 255]);
        assert_eq!(img.get_pixel(1 + 2 * 2, 1 + 6 * 2).0, [0, 0, 0]);
    }
}
