//! A scene written in Rust, not in a scene file: a flag held by a pole in
//! the wind (the cookbook's `flag_in_wind`), built with the typed scene
//! constructors, stepped, read, and written as OBJ frames.
//!
//! Run it with `cargo run --release --example flag_from_code [OUT_DIR]`.

use std::path::PathBuf;

use oriented_particles::op_modeling::tools::{Keyframe, Role, ToolPath, ToolShape};
use oriented_particles::op_scene::features::wind::Gust;
use oriented_particles::prelude::*;

fn flag() -> Scene {
    let pole = ToolSpec {
        name: "pole".into(),
        shape: ToolShape::Cuboid {
            half_extents: [0.6, 6.0, 1.0],
        },
        path: ToolPath {
            keyframes: vec![Keyframe {
                time: 0.0,
                position: [-7.5, 0.0, 0.0],
                rotation: [0.0; 3],
            }],
        },
        role: Role::Mover {
            stiffness: 200.0,
            damping: 5.0,
            release: f64::INFINITY,
        },
        objects: None,
    };
    let gust = |time, up| Gust {
        time,
        velocity: [0.0, 0.0, up],
    };
    Scene::new("flag_from_code")
        .with_world(|w| {
            w.dt = 0.005;
            w.duration = 12.0;
            w.frame_rate = 2.0;
            w.gravity = [0.0, 0.0, -0.2];
            w.linear_damping = 0.1.into();
            w.angular_damping = 0.05;
        })
        // `cloth` is a preset material: no materials section needed.
        .with_object(ObjectSpec::new(
            "flag",
            "cloth",
            Generator::HexSheet {
                nx: 16,
                ny: 10,
                spacing: 1.0,
                center: [0.0; 3],
                normal: [0.0, 0.0, 1.0],
                noise: 0.0,
                seed: 0,
            },
        ))
        .with_tool(pole)
        .with_feature(Wind {
            velocity: [3.0, 0.0, 0.0],
            drag: 0.3,
            gusts: vec![gust(6.0, 0.0), gust(8.0, 4.0), gust(10.0, 0.0)],
            objects: None,
        })
        .with_outputs(Outputs {
            particles: ParticleOutput::Discs,
            ..Outputs::default()
        })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("opsim-flag_from_code"));
    flag_to(out)
}

/// Builds and steps the flag, then writes its frames under `out`.
fn flag_to(out: PathBuf) -> Result<(), Box<dyn std::error::Error>> {
    let scene = flag();

    // Step it by hand and read the particles: the free edge drifts downwind.
    let mut built = scene.build(None, None)?;
    let ids = built.objects()[0].ids.clone();
    // The free edge: the particles farthest from the pole.
    let far = {
        let p = built.world().particles();
        let x = |id: &u32| p.slot_of(*id).map_or(f64::MIN, |s| p.positions()[s].x);
        let end = ids.iter().map(x).fold(f64::MIN, f64::max);
        ids.iter()
            .copied()
            .filter(|id| x(id) > end - 0.5)
            .collect::<Vec<u32>>()
    };
    let edge = |b: &BuiltScene| {
        let p = b.world().particles();
        let slots: Vec<usize> = far.iter().filter_map(|&id| p.slot_of(id)).collect();
        let mean = |f: &dyn Fn(usize) -> f64| {
            slots.iter().map(|&s| f(s)).sum::<f64>() / slots.len() as f64
        };
        (mean(&|s| p.positions()[s].x), mean(&|s| p.positions()[s].z))
    };
    built.advance_to(5.0)?;
    let (x, z) = edge(&built);
    println!(
        "free edge at t 5: x {x:.2}, z {z:.2} (the pole is at x -7.5, z 0; the flag is 15 long)"
    );
    // Without the wind it would hang about 15 below the pole.
    assert!(z > -5.0 && x > 5.0, "the flag streams downwind");

    // Or let the runner write the frames, metrics and summary.
    let mut built = scene.build(None, None)?;
    let opts = RunOptions {
        out_dir: out.clone(),
        frames: None,
        formats: vec![FrameFormat::OBJ],
        ..Default::default()
    };
    let summary = run(&mut built, &opts, &mut |_, _| {})?;
    println!(
        "{} frames in {:.2} s -> {}",
        summary.frames,
        summary.wall_seconds,
        out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        let out = std::env::temp_dir().join(format!("opsim-example-flag-{}", std::process::id()));
        super::flag_to(out.clone()).unwrap();
        assert!(out.join("summary.json").is_file());
        assert!(out.join("frames/flag/flag_00024.obj").is_file());
        let _ = std::fs::remove_dir_all(out);
    }
}
