//! What a run writes (README "Running scenes"): particle geometry in the OBJ frames and
//! the metrics table. The runner writes only what is asked for.

use serde::{Deserialize, Serialize};

/// How particles appear in the OBJ frames (seed 000 fig. 4).
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum ParticleOutput {
    /// Not written (an object's skin, and its surface when
    /// `triangulation` is set, still are).
    None,
    /// One vertex per particle with its normal as the `vn` of the same
    /// rank (no element: loose vertices, a point cloud).
    #[default]
    Points,
    /// A small hexagonal disc per particle, perpendicular to its normal.
    Discs,
    /// The particle's local frame: three line segments per particle.
    Axes,
}

/// The outputs a scene asks for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Outputs {
    /// Particle geometry in each OBJ frame. Default: `Points`.
    pub particles: ParticleOutput,
    /// Size of discs and axes as a fraction of the object's rest spacing,
    /// > 0. Default: 0.4.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub glyph_size: f64,
    /// Write `metrics.csv` (energies, oscillation, max speed per frame).
    /// Default: true.
    pub metrics: bool,
    /// Write each object's triangulation (seed 000 §5,
    /// [`op_modeling::triangulation`]) in the OBJ frames as an extra object
    /// `<object>_surface`: its particles as vertices with their normals,
    /// `f` elements wound along the normals. Default: false.
    pub triangulation: bool,
    /// Mutual-neighbour distance of the triangulation as a fraction of the
    /// object's rest spacing, > 0; the exported surface uses at least the
    /// spacing cut-off of the object's material (a pair that still attracts
    /// may be an edge). Default: 1.7.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub triangulation_radius: f64,
    /// The direction the camera of the scene's pictures looks along, in
    /// scene coordinates (z-up), chosen so the picture shows the scene's
    /// claim: written to `summary.json` (`view`) and the default of `opsim
    /// render` on the run. Default: none (the renderer's own view).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
    pub view: Option<[f64; 3]>,
    /// The up direction of the scene's pictures, in scene coordinates, not
    /// along `view`: written to `summary.json` (`up`) in place of the
    /// direction against gravity. Default: none (against gravity, else +z).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
    pub up: Option<[f64; 3]>,
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs {
            particles: ParticleOutput::Points,
            glyph_size: 0.4,
            metrics: true,
            triangulation: false,
            triangulation_radius: 1.7,
            view: None,
            up: None,
        }
    }
}

impl crate::Scene {
    /// What a run of this scene writes besides `summary.json`, as `opsim
    /// check` prints it after `outputs:`: the particle geometry, the
    /// metrics table, the triangulations (`<object>_surface`) and the
    /// skins, each named only when written (`particles as Points,
    /// metrics.csv, triangulations, skins of "ball"`).
    pub fn outputs_summary(&self) -> String {
        let o = &self.outputs;
        let mut parts = vec![format!("particles as {:?}", o.particles)];
        if o.metrics {
            parts.push("metrics.csv".into());
        }
        if o.triangulation {
            parts.push("triangulations (<object>_surface)".into());
        }
        let mut skinned = self
            .objects
            .iter()
            .filter(|ob| ob.skin.is_some())
            .map(|ob| ob.name.as_str())
            .peekable();
        if skinned.peek().is_some() {
            parts.push(format!("skins of {}", crate::error::quoted_list(skinned)));
        }
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use crate::{parse_scene, Format};

    #[test]
    fn the_summary_names_triangulations_and_skins() {
        let scene = |outputs: &str, skin: &str| {
            let text = format!(
                "(name: \"s\", materials: {{\"m\": ()}}, outputs: ({outputs}), objects: [
                    (name: \"ball\", material: \"m\", generator: SphereShell(radius: 2, spacing: 1){skin}),
                    (name: \"bare\", material: \"m\",
                     generator: Chain(count: 2, spacing: 1, start: (0, 0, 9))),
                ])"
            );
            parse_scene(&text, Format::Ron, "<test>").unwrap()
        };
        assert_eq!(
            scene("", "").outputs_summary(),
            "particles as Points, metrics.csv"
        );
        let skin = ", skin: (primitive: Point, radius: 1.2, cell_size: 0.25)";
        assert_eq!(
            scene("metrics: false, triangulation: true", skin).outputs_summary(),
            "particles as Points, triangulations (<object>_surface), skins of \"ball\""
        );
    }
}
