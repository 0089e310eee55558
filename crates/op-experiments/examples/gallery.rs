//! Regenerates the gallery, `docs/gallery/NAME.png` (the pictures of the
//! README): each scene of [`GALLERY`] is run as `opsim run` runs it (OBJ
//! frames into `target/gallery/NAME`) and its contact sheet is rendered as
//! `opsim render` renders a run: the camera is the scene's own
//! (`outputs.view` and `outputs.up`, chosen so the picture shows the
//! scene's claim), else the renderer's default view with the run's up.
//!
//! ```text
//! cargo run --release -p op-experiments --example gallery              # every picture
//! cargo run --release -p op-experiments --example gallery -- fig_07_knife fig_12_drape
//! ```

use std::path::{Path, PathBuf};

use op_render::{self as render, RenderOptions, Style};
use op_scene::export::obj::scene_to_obj;
use op_scene::export::FrameFormat;
use op_scene::{self, build_scene_file, RunOptions};

/// A picture of the gallery: the scene (`scenes/NAME.ron`), the frames of
/// its contact sheet and the drawing style.
struct Picture {
    name: &'static str,
    frames: usize,
    style: Style,
}

const fn shaded(name: &'static str) -> Picture {
    shaded_frames(name, 4)
}

/// A shaded picture of `frames` frames (a claim that happens between the
/// quarters of the run: the squeeze of `sphere_shell` is deepest at frame
/// 30 of 240).
const fn shaded_frames(name: &'static str, frames: usize) -> Picture {
    Picture {
        name,
        frames,
        style: Style::Shaded,
    }
}

const fn wireframe(name: &'static str) -> Picture {
    Picture {
        name,
        frames: 4,
        style: Style::Wireframe,
    }
}

/// The gallery, in the README's order.
const GALLERY: &[Picture] = &[
    shaded("fig_05_chain_linking"),
    shaded("fig_07_cut"),
    shaded("fig_08_crease"),
    shaded("fig_09_stretching"),
    shaded("fig_15_spin_cylinder"),
    shaded("sphere_surface"),
    shaded("sheet_on_box"),
    shaded("fig_12_drape"),
    shaded("ball_vs_spiral"),
    shaded("fig_07_knife"),
    shaded("fig_13_stem"),
    wireframe("fig_10_interpolation"),
    wireframe("fig_11_open_interpolation"),
    shaded("fig_14_sphere_to_torus"),
    shaded("fig_13_handle"),
    shaded("fig_12_tearing"),
    shaded("sheet_on_sphere"),
    shaded("cookbook/skinned_hit"),
    shaded_frames("sphere_shell", 9),
    shaded_frames("fig_12_plastic_memory", 9),
    shaded_frames("fig_12_plastic", 9),
];

/// Width and height of one frame of a contact sheet, pixels.
const FRAME_SIZE: (u32, u32) = (400, 300);

fn main() -> anyhow::Result<()> {
    let root = op_experiments::workspace_root();
    let root = root.as_path();
    let only: Vec<String> = std::env::args().skip(1).collect();
    if let Some(unknown) = only
        .iter()
        .find(|n| GALLERY.iter().all(|p| p.name != n.as_str()))
    {
        anyhow::bail!("{unknown} is not in the gallery");
    }
    for picture in GALLERY
        .iter()
        .filter(|p| only.is_empty() || only.iter().any(|n| n == p.name))
    {
        let png = draw(root, picture)?;
        println!("{}", png.display());
    }
    Ok(())
}

/// Runs and renders one picture; returns the PNG's path.
fn draw(root: &Path, picture: &Picture) -> anyhow::Result<PathBuf> {
    let scene = root.join("scenes").join(format!("{}.ron", picture.name));
    let mut built = build_scene_file(&scene)?;
    let out = root.join("target/gallery").join(picture.name);
    let opts = RunOptions {
        out_dir: out.clone(),
        frames: None,
        formats: vec![FrameFormat::OBJ],
        ..Default::default()
    };
    let summary = op_scene::run(&mut built, &opts, &mut |_, _| {})?;
    anyhow::ensure!(!summary.diverged, "{} diverged", picture.name);
    // The run's camera, as `opsim render` reads it from summary.json.
    let view = render::run_view_axis(&out);
    let up = render::run_up_axis(&out);
    let opts = RenderOptions {
        width: FRAME_SIZE.0,
        height: FRAME_SIZE.1,
        style: picture.style,
        view: view.map(scene_to_obj),
        up: up.map(scene_to_obj),
        ..Default::default()
    };
    let rendering = render::render_path(&out, &opts, picture.frames)?;
    let png = root
        .join("docs/gallery")
        .join(format!("{}.png", picture.name.replace('/', "_")));
    render::save_png(&rendering.image, &png)?;
    Ok(png)
}
