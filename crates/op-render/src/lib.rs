//! op-render: pictures of oriented-particle runs, the drawing half of `opsim render`
//! (README "Running scenes"). It reads what op-scene writes (OBJ frames, `summary.json`).
//!
//! Entry points:
//! - [`render_obj_file`] / [`render_data`]: one frame in one [`Style`] (seed 000
//!   figure 4: axes, discs, wireframe, flat shaded);
//! - [`render_contact_sheet`]: a grid of frames chosen evenly from a run's output
//!   directory, seen from one fixed camera so that motion shows;
//! - [`render_path`]: either of those by what the path is, with the notes about
//!   fallbacks (for the CLI to print);
//! - [`render_run_frames`]: chosen frames of a run ([`FrameChoice`]), seen
//!   from the camera that frames the whole run;
//! - [`render_run_animation`]: an animated GIF of a run's frames, at its
//!   frame rate, looping ([`save_gif`]);
//! - [`save_png`]: atomic PNG writing.
//!
//! Everything is pure Rust and deterministic: the same input and options give
//! the same pixels. Frames are read by the small OBJ reader in [`ObjData`]; the
//! camera frames the data's bounding box automatically unless
//! [`RenderOptions::camera`] gives one. World `+y` is up.

#![warn(missing_docs)]

mod animation;
mod camera;
mod contact_sheet;
mod error;
mod obj;
mod raster;
mod run_dir;
mod styles;

use std::path::Path;

pub use animation::{
    delays, render_run_animation, save_gif, Animation, DEFAULT_FRAME_RATE, MIN_DELAY_CS,
};
pub use camera::{CameraSpec, DEFAULT_AZIMUTH_DEG, DEFAULT_ELEVATION_DEG, DEFAULT_FOV_Y_DEG};
pub use contact_sheet::{render_contact_sheet, render_run_frames, sheet_grid, FrameChoice};
pub use error::RenderError;
pub use image::RgbImage;
pub use obj::{ObjData, ObjObject, MAX_OBJ_FILE_BYTES};
pub use run_dir::{read_run_frame, run_frame_rate, run_up_axis, run_view_axis};
pub use styles::Style;

use camera::Camera;
use raster::Canvas;
use styles::Painter;

/// Largest accepted width or height, pixels.
pub const MAX_SIDE: u32 = 16_384;
/// Largest accepted picture (or contact sheet) area, pixels.
pub const MAX_PIXELS: u64 = 50_000_000;

/// What to draw and how big.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Picture width in pixels (a contact sheet cell's width), `1..=MAX_SIDE`. Default: 800.
    pub width: u32,
    /// Picture height in pixels (a contact sheet cell's height), `1..=MAX_SIDE`. Default: 600.
    pub height: u32,
    /// Drawing style. Default: [`Style::Shaded`].
    pub style: Style,
    /// Background colour. Default: white.
    pub background: [u8; 3],
    /// Camera; `None` frames the data automatically, looking along
    /// [`RenderOptions::view`] with [`RenderOptions::up`] up. Default: `None`.
    pub camera: Option<CameraSpec>,
    /// Direction the automatic camera looks along (from the eye towards
    /// the data), in the data's coordinates; `None`: from azimuth
    /// [`DEFAULT_AZIMUTH_DEG`] and elevation [`DEFAULT_ELEVATION_DEG`]
    /// about `up`, from the `+z` side (the front of a z-up scene written
    /// y-up). Default: `None`.
    pub view: Option<[f64; 3]>,
    /// Up direction of the automatic camera's picture, in the data's
    /// coordinates; `None`: `+y`, the up axis of OBJ files (scene `+z` in
    /// opsim's frames). Default: `None`.
    pub up: Option<[f64; 3]>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 800,
            height: 600,
            style: Style::default(),
            background: [255, 255, 255],
            camera: None,
            view: None,
            up: None,
        }
    }
}

impl RenderOptions {
    /// Checks sizes and the camera.
    ///
    /// # Errors
    /// [`RenderError::BadOption`] naming the option and what is allowed.
    pub fn validate(&self) -> Result<(), RenderError> {
        for (name, v) in [("width", self.width), ("height", self.height)] {
            if v == 0 || v > MAX_SIDE {
                return Err(RenderError::option(
                    name,
                    format!("{v} pixels; allowed: 1 to {MAX_SIDE}"),
                ));
            }
        }
        check_area(u64::from(self.width), u64::from(self.height))?;
        if let Some(cam) = &self.camera {
            cam.validate()?;
        }
        for (name, v) in [("view", self.view), ("up", self.up)] {
            if let Some(v) = v {
                let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if !(norm.is_finite() && norm > 0.0) {
                    return Err(RenderError::option(
                        name,
                        format!("{v:?}; a direction must be finite and non-zero"),
                    ));
                }
            }
        }
        if let (Some(v), Some(u)) = (self.view, self.up) {
            let c = [
                v[1] * u[2] - v[2] * u[1],
                v[2] * u[0] - v[0] * u[2],
                v[0] * u[1] - v[1] * u[0],
            ];
            let (nv, nu) = (norm(v), norm(u));
            if norm(c) <= 1e-6 * nv * nu {
                return Err(RenderError::option(
                    "up",
                    format!("{u:?} is parallel to the view direction {v:?}"),
                ));
            }
        }
        Ok(())
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn check_area(width: u64, height: u64) -> Result<(), RenderError> {
    if width * height > MAX_PIXELS {
        return Err(RenderError::option(
            "width x height",
            format!("{width} x {height} pixels; allowed: at most {MAX_PIXELS} pixels in all"),
        ));
    }
    Ok(())
}

/// A picture and the notes about it (fallbacks taken, objects not drawn).
#[derive(Clone, Debug)]
pub struct Rendering {
    /// The picture.
    pub image: RgbImage,
    /// Human-readable notes, e.g. "shaded: no faces in the data, drawing particles
    /// as discs". Empty when everything was drawn as asked.
    pub notes: Vec<String>,
}

/// Renders `data`, returning the picture and notes.
///
/// # Errors
/// [`RenderError::BadOption`] for bad options, [`RenderError::Empty`] if `data`
/// has no vertex.
pub fn render(data: &ObjData, opts: &RenderOptions) -> Result<Rendering, RenderError> {
    opts.validate()?;
    if data.vertex_count() == 0 {
        return Err(RenderError::empty("the data has no vertices"));
    }
    let spec = match opts.camera {
        Some(spec) => spec,
        None => auto_camera([data], opts),
    };
    render_with_camera(data, opts, &spec)
}

/// The automatic camera fitted to all vertices of `frames`, looking along
/// [`RenderOptions::view`] with [`RenderOptions::up`] up.
pub(crate) fn auto_camera<'a>(
    frames: impl IntoIterator<Item = &'a ObjData>,
    opts: &RenderOptions,
) -> CameraSpec {
    let points: Vec<[f64; 3]> = frames
        .into_iter()
        .flat_map(|d| d.objects())
        .flat_map(|o| o.vertices().iter().copied())
        .collect();
    let up = opts.up.unwrap_or([0.0, 1.0, 0.0]);
    let view = opts.view.unwrap_or_else(|| default_view(up));
    CameraSpec::frame_points_along(
        &points,
        f64::from(opts.width) / f64::from(opts.height),
        view,
        up,
    )
}

/// The default view direction about `up`: from azimuth
/// [`DEFAULT_AZIMUTH_DEG`] and elevation [`DEFAULT_ELEVATION_DEG`], the
/// azimuth measured from the `+z` side (`+x` when `up` is along `z`)
/// towards `up x front`. With `up = +y` it is [`CameraSpec::frame_box`]'s.
pub fn default_view(up: [f64; 3]) -> [f64; 3] {
    use nalgebra::Vector3;
    let u = Vector3::from(up).try_normalize(0.0).unwrap_or(Vector3::y());
    let front = [Vector3::z(), Vector3::x()]
        .into_iter()
        .map(|a| a - u * u.dot(&a))
        .find(|f| f.norm() > 1e-3)
        .map_or(Vector3::z(), |f| f.normalize());
    let side = u.cross(&front);
    let (az, el) = (
        DEFAULT_AZIMUTH_DEG.to_radians(),
        DEFAULT_ELEVATION_DEG.to_radians(),
    );
    let to_eye = el.cos() * (az.sin() * side + az.cos() * front) + el.sin() * u;
    (-to_eye).into()
}

/// Renders `data` into a picture of `opts.width x opts.height`.
///
/// # Errors
/// As [`render`].
pub fn render_data(data: &ObjData, opts: &RenderOptions) -> Result<RgbImage, RenderError> {
    render(data, opts).map(|r| r.image)
}

/// Reads the OBJ file at `path` and renders it.
///
/// # Errors
/// [`RenderError::Io`] / [`RenderError::Parse`] for the file, otherwise as [`render`].
pub fn render_obj_file(path: &Path, opts: &RenderOptions) -> Result<RgbImage, RenderError> {
    render_file(path, opts).map(|r| r.image)
}

fn render_file(path: &Path, opts: &RenderOptions) -> Result<Rendering, RenderError> {
    opts.validate()?;
    let data = ObjData::read(path)?;
    render(&data, opts).map_err(|e| match e {
        RenderError::Empty { what } => RenderError::empty(format!("{}: {what}", path.display())),
        e => e,
    })
}

/// Renders what `path` is: an OBJ file as one picture, a directory as a contact
/// sheet of at most `max_frames` frames (see [`render_contact_sheet`]).
///
/// # Errors
/// As [`render_obj_file`] or [`render_contact_sheet`].
pub fn render_path(
    path: &Path,
    opts: &RenderOptions,
    max_frames: usize,
) -> Result<Rendering, RenderError> {
    if path.is_dir() {
        contact_sheet::contact_sheet(path, opts, max_frames)
    } else {
        render_file(path, opts)
    }
}

/// Supersampling factor: 2x2 for anti-aliasing unless the picture is large.
fn supersample(width: u32, height: u32) -> usize {
    if u64::from(width) * u64::from(height) <= 2_500_000 {
        2
    } else {
        1
    }
}

/// Renders with a given camera; options must be valid.
pub(crate) fn render_with_camera(
    data: &ObjData,
    opts: &RenderOptions,
    spec: &CameraSpec,
) -> Result<Rendering, RenderError> {
    let ss = supersample(opts.width, opts.height);
    let (w, h) = (opts.width as usize * ss, opts.height as usize * ss);
    let cam = Camera::new(spec, w, h)?;
    // One nominal line-width pixel, grown a little on big pictures.
    let size_factor = (f64::from(opts.width.min(opts.height)) / 600.0).clamp(0.75, 4.0);
    let unit = ss as f64 * size_factor;
    let mut painter = Painter::new(
        &cam,
        Canvas::new(w, h, opts.background),
        unit,
        opts.background,
    );
    let notes = styles::draw(data, opts.style, &mut painter);
    let canvas = painter.into_canvas();
    debug_assert_eq!((canvas.width(), canvas.height()), (w, h));
    Ok(Rendering {
        image: canvas.downsample(ss),
        notes,
    })
}

/// Writes `img` as a PNG at `path` atomically, as the runner writes its
/// frames ([`op_scene::export::write_atomically`]): a temporary file in the
/// same directory, created exclusively under a name no other process can
/// predict (so a link planted there is never written through), then a
/// rename, so readers never see a half-written picture.
///
/// # Errors
/// [`RenderError::Io`] if the directory is missing or not writable,
/// [`RenderError::BadOption`] if `path` has no file name,
/// [`RenderError::Encode`] if the encoder fails.
pub fn save_png(img: &RgbImage, path: &Path) -> Result<(), RenderError> {
    use image::ImageEncoder;
    if path.file_name().is_none() {
        return Err(RenderError::option(
            "output path",
            format!("'{}' has no file name", path.display()),
        ));
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| RenderError::Encode {
            path: path.to_path_buf(),
            source: e,
        })?;
    op_scene::export::write_atomically(path, |w| w.write_all(&png))
        .map_err(|e| RenderError::io(path, e))
}
