//! `opsim render` (README "Running scenes"): a picture of an OBJ frame, a
//! contact sheet or chosen frames of a run (`.png`), or an animation of a
//! run (`.gif`), chosen by the output's extension; and the demo's pictures.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context};
use op_render::{self as render, FrameChoice, RenderOptions, Style};
use op_scene::export::obj::scene_to_obj;

use super::{is_obj, Failure};

/// `opsim render`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct RenderArgs {
    /// An .obj file, or a run directory (its frames/ are used).
    pub(crate) input: PathBuf,
    /// Output file: `.png` for a picture (a frame, or a contact sheet of
    /// a run), `.gif` for an animation of a run's frames at its frame
    /// rate, looping.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Drawing style: axes, discs, wireframe or shaded (faces; particles
    /// as discs when no object has faces).
    #[arg(long, default_value = "shaded")]
    pub(crate) style: Style,
    /// Picture width in pixels (per frame for a contact sheet).
    #[arg(long, default_value_t = 800)]
    pub(crate) width: u32,
    /// Picture height in pixels (per frame for a contact sheet).
    #[arg(long, default_value_t = 600)]
    pub(crate) height: u32,
    /// Frames of a run directory: `N` (>= 1) frames chosen evenly, or
    /// `A:B:S` the frames numbered A to B every S (`0:40:10`: 0, 10,
    /// 20, 30, 40). Default: 9 for a contact sheet, every frame for a
    /// GIF.
    #[arg(long, value_parser = super::parse_frame_choice)]
    pub(crate) frames: Option<FrameChoice>,
    /// One frame of a run directory, by its number (the picture of
    /// `--frames K:K:1`), seen from the camera that frames the whole run.
    #[arg(long, conflicts_with = "frames")]
    pub(crate) frame: Option<u64>,
    /// Direction the camera looks along, `X,Y,Z` in scene coordinates
    /// (z-up), e.g. `0,0,-1` from above. Default: the run's view (the
    /// scene's `outputs.view`, from summary.json), else from the front
    /// (-y side), 35 degrees to the right and 25 degrees above.
    #[arg(long, value_parser = super::parse_direction, allow_hyphen_values = true)]
    pub(crate) view: Option<[f64; 3]>,
    /// Up direction of the picture, `X,Y,Z` in scene coordinates.
    /// Default: the run's up (the scene's `outputs.up`, else against its
    /// gravity, from summary.json), else +z; +y instead when that is
    /// along the view (looking straight down or up).
    #[arg(long, value_parser = super::parse_direction, allow_hyphen_values = true)]
    pub(crate) up: Option<[f64; 3]>,
}

/// What `opsim render --out` writes, by the file's extension.
#[derive(Clone, Copy, PartialEq)]
enum RenderOutput {
    /// `.png`: a picture.
    Png,
    /// `.gif`: an animation of a run.
    Gif,
}

impl RenderOutput {
    fn of(out: &Path) -> Result<RenderOutput, Failure> {
        let ext = out
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(RenderOutput::Png),
            Some("gif") => Ok(RenderOutput::Gif),
            _ => Err(anyhow!(
                "cannot write {}: render writes a .png picture or a .gif animation of a run; \
                 name the output file with one of these extensions",
                out.display()
            )
            .into()),
        }
    }
}

/// `opsim render`.
pub(crate) fn render_command(args: RenderArgs) -> Result<(), Failure> {
    let RenderArgs {
        input,
        out,
        style,
        width,
        height,
        frames,
        frame,
        view,
        up,
    } = args;
    let kind = RenderOutput::of(&out)?;
    // A file is read as OBJ: say so for another kind of frame
    // rather than find no vertices in it.
    if input.is_file() && !is_obj(&input) {
        return Err(anyhow!(
            "cannot render {}: render reads .obj files (a frame written with \
             --format obj, the default) or a run directory",
            input.display()
        )
        .into());
    }
    if input.is_file() && (frame.is_some() || frames.is_some()) {
        return Err(anyhow!(
            "cannot render {}: --frame and --frames choose frames of a run directory, \
             and this is one frame file",
            input.display()
        )
        .into());
    }
    if input.is_file() && kind == RenderOutput::Gif {
        return Err(anyhow!(
            "cannot animate {}: a .gif animates the frames of a run directory, \
             and this is one frame file (write a .png)",
            input.display()
        )
        .into());
    }
    // The frames are y-up OBJ files of a z-up scene: directions
    // given in scene coordinates are converted like the frames.
    let view = view.or_else(|| render::run_view_axis(&input));
    let up = up.or_else(|| default_up(render::run_up_axis(&input), view));
    let opts = RenderOptions {
        width,
        height,
        style,
        view: view.map(scene_to_obj),
        up: up.map(scene_to_obj),
        ..Default::default()
    };
    let choice = match (frame, frames, kind) {
        (Some(k), _, _) => FrameChoice::Numbers {
            first: k,
            last: k,
            step: 1,
        },
        (None, Some(choice), _) => choice,
        (None, None, RenderOutput::Png) => FrameChoice::Spread(9),
        (None, None, RenderOutput::Gif) => FrameChoice::ALL,
    };
    if kind == RenderOutput::Gif {
        let animation = animate(&input, &opts, choice)?;
        for note in &animation.notes {
            eprintln!("opsim: note: {note}");
        }
        render::save_gif(&animation, &out)?;
        outln!("{}", out.display());
        return Ok(());
    }
    let rendering = if input.is_dir() {
        render::render_run_frames(&input, &opts, choice)
    } else {
        render::render_path(&input, &opts, 1)
    }
    .with_context(|| format!("cannot render {}", input.display()))?;
    for note in &rendering.notes {
        eprintln!("opsim: note: {note}");
    }
    render::save_png(&rendering.image, &out)?;
    outln!("{}", out.display());
    Ok(())
}

/// The animation of the run `dir`'s frames `choice` at its frame rate
/// (`summary.json`; a note says when there is none).
fn animate(
    dir: &Path,
    opts: &RenderOptions,
    choice: FrameChoice,
) -> Result<render::Animation, Failure> {
    let rate = render::run_frame_rate(dir);
    let animation = render::render_run_animation(dir, opts, choice, rate)
        .with_context(|| format!("cannot animate {}", dir.display()))?;
    if rate.is_none() {
        eprintln!(
            "opsim: note: no summary.json with a frame rate found for {}: {} frames a second",
            dir.display(),
            render::DEFAULT_FRAME_RATE
        );
    }
    Ok(animation)
}

/// The up direction of a picture when none is given: the run's `up`
/// (else +z), or +y (+z if the run's up is +y) when that is along the view
/// direction `view`, so that `--view 0,0,-1` alone looks straight down
/// with +y up.
fn default_up(run_up: Option<[f64; 3]>, view: Option<[f64; 3]>) -> Option<[f64; 3]> {
    let along = |a: [f64; 3], b: [f64; 3]| {
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let n = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        n(c) <= 1e-6 * n(a) * n(b)
    };
    match (run_up, view) {
        (up, Some(v)) if along(up.unwrap_or([0.0, 0.0, 1.0]), v) => {
            [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
                .into_iter()
                .find(|&u| !along(u, v))
        }
        (up, _) => up,
    }
}

/// The demo's pictures, seen from above (the demo spiral lies in the
/// plane z = 0): a contact sheet of its run, `contact_sheet.png` in the
/// run folder, and an animation of every frame at the scene's frame rate,
/// `preview.gif` (`opsim render RUN --out run.gif`); prints their paths.
pub(crate) fn demo_contact_sheet(out: &Path) -> Result<(), Failure> {
    let opts = RenderOptions {
        width: 360,
        height: 300,
        style: render::Style::Discs,
        view: Some(scene_to_obj([0.0, 0.0, -1.0])),
        up: Some(scene_to_obj([0.0, 1.0, 0.0])),
        ..Default::default()
    };
    let rendering = render::render_path(out, &opts, 9)
        .with_context(|| format!("cannot render {}", out.display()))?;
    let png = out.join("contact_sheet.png");
    render::save_png(&rendering.image, &png)?;
    outln!("contact sheet: {}", png.display());
    let animation = animate(out, &opts, FrameChoice::ALL)?;
    let gif = out.join("preview.gif");
    render::save_gif(&animation, &gif)?;
    outln!(
        "preview: {} ({} frames; open it in a browser)",
        gif.display(),
        animation.frames.len()
    );
    Ok(())
}
