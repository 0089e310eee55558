//! Named materials for the common cases, usable from a scene by name: an
//! object whose `material` is not a key of the scene's `materials` but is
//! the name of a preset gets the preset (a scene's own material of the same
//! name wins).
//!
//! Each preset is the material of a shipped, tested scene, written in the
//! scene format, with the damping it was tested with and a step `dt` chosen
//! from the stability law (`dt √λ < 2` for velocity Verlet,
//! [`crate::stability`]): the largest 1-2-5 step below a fifth of the
//! largest stable step of a representative object of particle mass 1 (a
//! 20 x 20 sheet, a sphere of radius 4, a 10-particle spiral). The
//! Hessian at rest underestimates the stiffness of a strongly deformed
//! object, hence the factor 5. A rate process needs its rate resolved too:
//! `plastic_clay`'s flow (rate 50) is integrated exactly over each step
//! with the current offsets held, and its dented shell of
//! `scenes/fig_12_plastic.ron` ends within 0.001 of the same side at `dt`
//! 1e-3, 2e-3, 5e-3 and 1e-2. A test keeps every step between 1/50 and 1/2 of
//! the stability bound. For a particle mass `m`, the stable step scales as
//! `√m`.
//!
//! ```
//! let scene = op_scene::parse_scene(
//!     r#"(name: "flag", world: (dt: 0.005, gravity: (0, 0, -0.2), linear_damping: 0.1),
//!        objects: [(name: "flag", material: "cloth",
//!                   generator: HexSheet(nx: 10, ny: 10, spacing: 1))])"#,
//!     op_scene::Format::Ron,
//!     "<doc>",
//! )?;
//! assert!(scene.materials["cloth"].bonds.is_some());
//! # Ok::<(), op_scene::SceneError>(())
//! ```

use op_dynamics::{Material, Real};
use ron::extensions::Extensions;

use crate::schema::Scene;

/// A named material with the world settings it was tested with.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// The name a scene uses as an object's `material`.
    pub name: &'static str,
    /// What it is for, in one sentence.
    pub summary: &'static str,
    /// The material, in the scene format.
    pub material_ron: &'static str,
    /// The shipped scene it comes from.
    pub scene: &'static str,
    /// Time step for particles of mass 1 under velocity Verlet (see the
    /// module docs for how it is chosen).
    pub dt: Real,
    /// Linear damping `β0` it was tested with.
    pub linear_damping: Real,
    /// Angular damping `β1` it was tested with.
    pub angular_damping: Real,
}

impl Preset {
    /// The material.
    pub fn material(&self) -> Material {
        ron::Options::default()
            .with_default_extension(Extensions::IMPLICIT_SOME)
            .from_str(self.material_ron)
            .unwrap_or_else(|e| panic!("preset {:?} does not parse: {e}", self.name))
    }
}

/// The presets.
pub const PRESETS: &[Preset] = &[
    Preset {
        name: "cloth",
        summary:
            "a sheet that bends freely, keeps its area and drapes: Lennard-Jones spacing, weak \
                  co-planarity, explicit bonds so folded layers slide over each other",
        material_ron: "(spacing: LennardJones((epsilon: 10, r0: 1, cutoff: 1.5)), \
                       coplanarity: 0.5, bonds: (radius: 1.2))",
        scene: "scenes/fig_12_drape.ron",
        dt: 0.005,
        linear_damping: 0.1,
        angular_damping: 0.05,
    },
    Preset {
        name: "elastic_shell",
        summary: "a closed surface that springs back to round: cohesion, the form interaction \
                  with the generator's curvature, friction and bonds to the nearest neighbours \
                  (Lombardo & Puech §3-5); co-circularity alone keeps a squeezed shell flat",
        material_ron: "(spacing: Cohesion((e: 200, r0: 1, alpha: 16, cutoff: 1.5)), \
                       weight: (k: 1, a: 1, cutoff: 1.5), form: 2, coplanarity: 0.2, \
                       friction: 1, bonds: (radius: 1.2))",
        scene: "scenes/sphere_shell.ron",
        dt: 0.01,
        linear_damping: 0.5,
        angular_damping: 0.05,
    },
    Preset {
        name: "shape_memory_wire",
        summary: "a curve that remembers its per-particle curvature and returns to it when \
                  released: cohesion, form interaction, friction (Lombardo & Puech §4-5, fig. 5)",
        material_ron: "(spacing: Cohesion((e: 200, r0: 1, alpha: 16, cutoff: 1.5)), \
                       weight: (k: 1, a: 1, cutoff: 1.5), form: 2, coplanarity: 0.2, \
                       friction: 1, repulsion: (strength: 1, sigma: 1, lambda: 0.1, cutoff: 1.5))",
        scene: "scenes/spiral.ron",
        dt: 0.02,
        linear_damping: 0.3,
        angular_damping: 0.05,
    },
    Preset {
        name: "plastic_clay",
        summary: "a curve or surface that keeps the shape it is pushed into beyond a yield: \
                  a bonded lattice whose bonds remember their offsets in the particles' \
                  frames and flow (Szeliski & Tonnesen fig. 12b, after Terzopoulos & \
                  Fleischer)",
        material_ron: "(spacing: None, bonds: (radius: 1.5), \
                       bond_memory: (stiffness: 100, flow: (yield_offset: 0.01, rate: 50)))",
        scene: "scenes/fig_12_plastic.ron",
        dt: 0.002,
        linear_damping: 1.0,
        angular_damping: 0.1,
    },
];

/// The preset of that name.
pub fn preset(name: &str) -> Option<&'static Preset> {
    PRESETS.iter().find(|p| p.name == name)
}

/// Adds to `scene.materials` the presets its objects name and it does not
/// define.
pub fn resolve(scene: &mut Scene) {
    for o in &scene.objects {
        if !scene.materials.contains_key(&o.material) {
            if let Some(p) = preset(&o.material) {
                scene.materials.insert(o.material.clone(), p.material());
            }
        }
    }
}

/// The preset names, quoted, for messages.
pub fn names() -> String {
    PRESETS
        .iter()
        .map(|p| format!("{:?}", p.name))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_parses_and_validates() {
        for p in PRESETS {
            p.material()
                .validate()
                .unwrap_or_else(|e| panic!("{}: {e}", p.name));
        }
    }

    #[test]
    fn every_preset_is_the_material_of_its_scene() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        for p in PRESETS {
            let scene = crate::load_scene(&root.join(p.scene)).unwrap();
            assert!(
                scene.materials.values().any(|m| *m == p.material()),
                "{}: no material of {} is the preset",
                p.name,
                p.scene
            );
            assert_eq!(
                scene.world.linear_damping,
                p.linear_damping.into(),
                "{}",
                p.name
            );
            assert_eq!(scene.world.angular_damping, p.angular_damping, "{}", p.name);
        }
    }

    /// A representative object of each preset, in the scene format.
    fn representative(name: &str) -> &'static str {
        match name {
            "cloth" => "HexSheet(nx: 20, ny: 20, spacing: 1)",
            "elastic_shell" | "plastic_clay" => "SphereShell(radius: 4, spacing: 1)",
            _ => "Spiral(count: 10, spacing: 1, curvature_start: 0.1, curvature_end: 0.9)",
        }
    }

    #[test]
    fn every_preset_step_is_chosen_from_the_stability_law() {
        for p in PRESETS {
            let text = format!(
                "(name: \"t\", world: (dt: {}, linear_damping: {}, angular_damping: {}), \
                 objects: [(name: \"o\", material: {:?}, generator: {})])",
                p.dt,
                p.linear_damping,
                p.angular_damping,
                p.name,
                representative(p.name)
            );
            let scene = crate::parse_scene(&text, crate::Format::Ron, "<test>").unwrap();
            let bound = crate::stability::estimate(&scene, None)
                .unwrap()
                .dt_max
                .unwrap();
            let ratio = p.dt / bound;
            assert!(
                (0.02..=0.5).contains(&ratio),
                "{}: dt {} is {ratio:.3} of the stable bound {bound:.4}",
                p.name,
                p.dt
            );
        }
    }

    #[test]
    fn a_scene_material_of_the_same_name_wins() {
        let scene = crate::parse_scene(
            r#"(name: "s", materials: {"cloth": (coplanarity: 3)},
                objects: [(name: "a", material: "cloth", generator: Chain(count: 3, spacing: 1))])"#,
            crate::Format::Ron,
            "<test>",
        )
        .unwrap();
        assert_eq!(scene.materials["cloth"].coplanarity, 3.0);
        assert!(scene.materials["cloth"].bonds.is_none());
    }

    #[test]
    fn an_unknown_material_names_the_presets() {
        let err = crate::parse_scene(
            r#"(name: "s", objects: [(name: "a", material: "clothh",
                generator: Chain(count: 3, spacing: 1))])"#,
            crate::Format::Ron,
            "<test>",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("clothh") && err.contains("\"cloth\""), "{err}");
    }
}
