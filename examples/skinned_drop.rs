//! A skinned ball (seed 002 §6) dropped on a plane, built in Rust: its
//! implicit skin is read back as a triangle mesh at a few times, and the
//! skin, not the particles, rests on the plane.
//!
//! Run it with `cargo run --release --example skinned_drop`.

use oriented_particles::op_modeling::tools::{Role, ToolPath, ToolShape};
use oriented_particles::prelude::*;

fn scene() -> Scene {
    let ground = ToolSpec {
        name: "ground".into(),
        shape: ToolShape::Plane {
            normal: [0.0, 0.0, 1.0],
        },
        path: ToolPath::default(),
        role: Role::Obstacle {
            stiffness: 400.0,
            margin: 0.0,
            damping: 1.0,
            friction: 0.5,
        },
        objects: None,
    };
    Scene::new("skinned_drop")
        .with_world(|w| {
            w.dt = 0.004;
            w.duration = 6.0;
            w.gravity = [0.0, 0.0, -1.0];
            w.linear_damping = 0.2.into();
            w.angular_damping = 0.1;
        })
        // The cohesion force of seed 002 §3 holds the ball together.
        .with_material(
            "ball",
            Material {
                spacing: Some(Spacing::Cohesion(CohesionParams {
                    e: 200.0,
                    r0: 1.0,
                    alpha: 16.0,
                    cutoff: Some(1.5),
                    ..CohesionParams::default()
                })),
                ..Material::empty()
            },
        )
        .with_object(
            ObjectSpec::new(
                "ball",
                "ball",
                Generator::SolidBall {
                    center: [0.0, 0.0, 4.0],
                    radius: 1.5,
                    spacing: 1.0,
                },
            )
            .with_skin(SkinSpec::new(SkinPrimitive::Point, 1.2, 0.25)),
        )
        .with_tool(ground)
}

/// The lowest vertex of the ball's skin at the scene's current time.
fn skin_bottom(built: &BuiltScene) -> Result<f64, Box<dyn std::error::Error>> {
    let skin = &built.skins()[0];
    let mesh = skin.mesh_in(built.skins(), built.skin_tools(), built.world().time())?;
    Ok(mesh
        .positions()
        .iter()
        .map(|p| p.z)
        .fold(f64::MAX, f64::min))
}

/// Drops the ball and returns the skin's lowest point at the end.
fn drop_ball() -> Result<f64, Box<dyn std::error::Error>> {
    let mut built = scene().build(None, None)?;
    for t in [0.0, 2.0, 4.0, 6.0] {
        built.advance_to(t)?;
        let lowest_particle = built
            .world()
            .particles()
            .positions()
            .iter()
            .map(|p| p.z)
            .fold(f64::MAX, f64::min);
        println!(
            "t {t}: lowest particle z {lowest_particle:.3}, lowest skin vertex z {:.3}",
            skin_bottom(&built)?
        );
    }
    skin_bottom(&built)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let bottom = drop_ball()?;
    println!("the skin rests on the plane z = 0 (lowest vertex {bottom:.3})");
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        let bottom = super::drop_ball().unwrap();
        // The skin, not the particles, meets the ground: it rests on it,
        // pressed in by less than a cell.
        assert!(bottom.abs() < 0.3, "skin bottom at z {bottom}");
    }
}
