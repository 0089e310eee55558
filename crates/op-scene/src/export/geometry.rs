//! What one frame file holds: the geometry of one thing of the scene (an
//! object's particles, a skin, a triangulation, a tool) at the world's
//! current state, in scene coordinates, independent of the file format.

use op_dynamics::{Real, Vec3, World};
use op_implicit::Mesh;
use op_modeling::triangulation::{triangulate_linked, TriangulationParams};
use op_modeling::Tool;

use crate::built_scene::BuiltObject;
use crate::outputs::{Outputs, ParticleOutput};

/// One mesh of a frame, in scene coordinates (z-up): vertices with one
/// normal each, triangles and line segments over them.
///
/// Every vertex is either used by an element or the mesh has no element at
/// all (a point cloud): OBJ importers keep loose vertices only in a file
/// that has nothing else, so a mesh never mixes the two, and the vertex
/// and face counts of a file are those an importer shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameMesh {
    /// Object name (the OBJ `o` name).
    pub name: String,
    /// Vertex positions.
    pub vertices: Vec<Vec3>,
    /// Unit normal of each vertex (same length as `vertices`).
    pub normals: Vec<Vec3>,
    /// Triangles, as vertex indices, wound along the normals.
    pub triangles: Vec<[u32; 3]>,
    /// Line segments, as vertex indices.
    pub lines: Vec<[u32; 2]>,
}

impl FrameMesh {
    fn named(name: String) -> Self {
        FrameMesh {
            name,
            ..FrameMesh::default()
        }
    }

    fn push(&mut self, x: Vec3, n: Vec3) -> u32 {
        self.vertices.push(x);
        self.normals.push(n);
        (self.vertices.len() - 1) as u32
    }

    /// Keeps only the triangles of three distinct vertices and the vertices
    /// they use (renumbered in their order), so that no vertex is loose.
    /// Checked first, in parallel: a polygonized skin has neither kind
    /// (its vertices are made by its triangles, on three distinct edges),
    /// and the copies and serial renumbering took 7% of a skinned
    /// cloth's export at 2 threads.
    fn compact_triangles(&mut self) {
        use rayon::prelude::*;
        use std::sync::atomic::{AtomicBool, Ordering};
        let degenerate = |t: &[u32; 3]| t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
        let min = op_dynamics::MIN_PARALLEL_LEN;
        let used: Vec<AtomicBool> = (0..self.vertices.len())
            .into_par_iter()
            .with_min_len(min)
            .map(|_| AtomicBool::new(false))
            .collect();
        let any_degenerate = self
            .triangles
            .par_iter()
            .with_min_len(min)
            .map(|t| {
                for &v in t {
                    used[v as usize].store(true, Ordering::Relaxed);
                }
                degenerate(t)
            })
            .reduce(|| false, |a, b| a | b);
        let all_used = used
            .par_iter()
            .with_min_len(min)
            .all(|u| u.load(Ordering::Relaxed));
        if all_used && !any_degenerate {
            return;
        }
        self.triangles.retain(|t| !degenerate(t));
        let mut new_index = vec![u32::MAX; self.vertices.len()];
        for t in &self.triangles {
            for &v in t {
                new_index[v as usize] = 0;
            }
        }
        let (mut vertices, mut normals) = (Vec::new(), Vec::new());
        for (k, slot) in new_index.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = vertices.len() as u32;
                vertices.push(self.vertices[k]);
                normals.push(self.normals[k]);
            }
        }
        for t in &mut self.triangles {
            *t = t.map(|v| new_index[v as usize]);
        }
        self.vertices = vertices;
        self.normals = normals;
    }
}

/// Two unit vectors spanning the plane perpendicular to `n`.
fn tangent_pair(n: &Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let t = (a - n * n.dot(&a)).normalize();
    (t, n.cross(&t))
}

/// The particles of one scene object at the world's current state, drawn
/// as [`Outputs::particles`] asks: loose vertices (`Points`), hexagonal
/// discs of 7 vertices and 6 triangles (`Discs`) or the particle frame as
/// 4 vertices and 3 segments (`Axes`); normals are the particle normals.
pub fn object_geometry(world: &World, object: &BuiltObject, outputs: &Outputs) -> FrameMesh {
    let p = world.particles();
    let size = outputs.glyph_size * object.rest_spacing;
    let mut mesh = FrameMesh::named(object.name.clone());
    for id in object.all_ids() {
        let Some(s) = p.slot_of(id) else { continue };
        let x = p.positions()[s].coords;
        let q = p.orientations()[s];
        let n = q * p.normal_axes()[s];
        match outputs.particles {
            ParticleOutput::None => {}
            ParticleOutput::Points => {
                mesh.push(x, n);
            }
            ParticleOutput::Discs => {
                let (t, b) = tangent_pair(&n);
                let c = mesh.push(x, n);
                for k in 0..6 {
                    let a = k as Real * std::f64::consts::PI / 3.0;
                    mesh.push(x + size * (a.cos() * t + a.sin() * b), n);
                }
                for k in 0..6 {
                    mesh.triangles.push([c, c + 1 + k, c + 1 + (k + 1) % 6]);
                }
            }
            ParticleOutput::Axes => {
                let tx = q * p.tangent_axes()[s];
                let ty = n.cross(&tx);
                let c = mesh.push(x, n);
                for axis in [tx, ty, n] {
                    let k = mesh.push(x + size * axis, n);
                    mesh.lines.push([c, k]);
                }
            }
        }
    }
    mesh
}

/// The mesh `name` of a polygonized skin: its triangles with per-vertex
/// normals (analytic field gradient); degenerate triangles and unused
/// vertices left out.
pub fn mesh_geometry(name: &str, mesh: Mesh) -> FrameMesh {
    let (positions, normals, triangles) = mesh.into_parts();
    let mut out = FrameMesh {
        name: name.to_string(),
        vertices: positions.into_iter().map(|p| p.coords).collect(),
        normals,
        triangles,
        lines: Vec::new(),
    };
    out.compact_triangles();
    out
}

/// The name of tool `k` in the frames: `tool_<name>`, `tool_<k>` when
/// unnamed.
pub fn tool_name(k: usize, tool: &Tool) -> String {
    match tool.params().name.as_str() {
        "" => format!("tool_{k}"),
        n => format!("tool_{n}"),
    }
}

/// The mesh [`tool_name`] of tool `k` at world time `t`, shaded smooth
/// where the surface is and sharp at its creases ([`weld_smooth`], crease
/// angle [`TOOL_CREASE_DEGREES`]): a ball or a cylinder's side shares its
/// vertices and shades round, a cuboid's faces and a cylinder's caps keep
/// their edges. Planes are drawn as a square of half side 10.
pub fn tool_geometry(k: usize, tool: &Tool, t: Real) -> FrameMesh {
    let (v, tris) = tool.surface_mesh(t, 10.0);
    let positions: Vec<Vec3> = v.iter().map(|p| p.coords).collect();
    weld_smooth(tool_name(k, tool), &positions, &tris, TOOL_CREASE_DEGREES)
}

/// Faces of a tool meeting at more than this angle meet at a crease
/// (sharp in the pictures); below it they shade as one smooth surface.
/// Between the finest facets of a tool (a ball's 15° bands, a cylinder's
/// 11.25° sides) and the 90° of a cuboid's edges.
pub const TOOL_CREASE_DEGREES: Real = 40.0;

/// A mesh over `positions` and `triangles` whose corners share a vertex
/// where they share a position and shade as one smooth surface: each
/// corner's normal is the area-weighted mean of the face normals at its
/// vertex within `crease_degrees` of its own face's (the "auto smooth" of
/// modelling tools), and the corners of one input vertex with the same
/// normal are one vertex. Degenerate triangles are dropped. Vertices come
/// in the order of their first corner, so the mesh is a function of its
/// input only.
pub fn weld_smooth(
    name: String,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    crease_degrees: Real,
) -> FrameMesh {
    // Each triangle's area-weighted normal (twice its area long).
    let faces: Vec<([u32; 3], Vec3)> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (*t, (b - a).cross(&(c - a)))
        })
        .filter(|(_, n)| n.norm() > 0.0)
        .collect();
    let mut incident = vec![Vec::new(); positions.len()];
    for (f, (t, _)) in faces.iter().enumerate() {
        for &v in t {
            incident[v as usize].push(f);
        }
    }
    let cos_crease = crease_degrees.to_radians().cos();
    let mut mesh = FrameMesh::named(name);
    let mut welded = std::collections::HashMap::new();
    for (t, n) in &faces {
        let own = n.normalize();
        let corner = |v: u32| {
            let smooth: Vec3 = incident[v as usize]
                .iter()
                .map(|&g| faces[g].1)
                .filter(|m| m.normalize().dot(&own) >= cos_crease)
                .sum();
            smooth.try_normalize(0.0).unwrap_or(own)
        };
        let tri = t.map(|v| {
            let normal = corner(v);
            let key = (v, [normal.x, normal.y, normal.z].map(Real::to_bits));
            *welded
                .entry(key)
                .or_insert_with(|| mesh.push(positions[v as usize], normal))
        });
        mesh.triangles.push(tri);
    }
    mesh
}

/// The mesh `<object>_surface`: the triangles of
/// [`op_modeling::triangulation`] over the object's live particles (mutual
/// neighbours within `triangulation_radius` rest spacings, wound along the
/// particle normals), with the particles they use as vertices (original
/// then created, in that order) and their normals. Particles in no
/// triangle are left out (they are in the particles' own mesh).
///
/// The mutual-neighbour radius is at least the spacing cut-off of the
/// object's materials ([`surface_radius`]): every pair that still attracts
/// may be an edge. A cohesion shell (seed 002 §3) settles tighter than its
/// `r0` (fig_12_plastic: mean nearest distance 0.82 r0, so 1.7 rest
/// spacings are 1.40 r0, inside the cut-off 1.5 r0); where a finger
/// stretches it, the diagonals of a cell that still attracts (1.40-1.43
/// r0) were longer than the radius and the surface showed a hole.
///
/// Only what holds together is triangulated ([`interacting`]): an edge
/// joins two particles that still attract, so a cut or a tear opens in the
/// surface (seed 000 §6 fig. 7, §8 fig. 12c). `sheet_gap` is the
/// exception: in a scene that creates particles by stretching, a pair the
/// rule leaves as sheet is an edge even when it no longer attracts
/// ([`SheetGap`]).
pub fn surface_geometry(
    world: &World,
    object: &BuiltObject,
    outputs: &Outputs,
    sheet_gap: SheetGap,
) -> FrameMesh {
    let p = world.particles();
    let slots: Vec<usize> = object.all_ids().filter_map(|id| p.slot_of(id)).collect();
    let positions: Vec<_> = slots.iter().map(|&s| p.positions()[s]).collect();
    let normals: Vec<Vec3> = slots.iter().map(|&s| p.normal(s)).collect();
    let params = TriangulationParams::with_radius(surface_radius(world, &slots, object, outputs));
    let linked = |a: u32, b: u32| {
        let (i, j) = (slots[a as usize], slots[b as usize]);
        interacting(world, i, j) || sheet_gap.holds(&positions, a as usize, b as usize)
    };
    // The radius is validated with the scene; a non-finite spacing leaves
    // the surface without triangles rather than failing the frame.
    let triangles = triangulate_linked(&positions, &normals, &params, &linked).unwrap_or_default();
    let mut mesh = FrameMesh {
        name: surface_name(object),
        vertices: positions.iter().map(|q| q.coords).collect(),
        normals,
        triangles,
        lines: Vec::new(),
    };
    mesh.compact_triangles();
    mesh
}

/// The gaps between particles that no longer attract that the stretching
/// rule of seed 000 §7 (op_dynamics::creation::stretching) leaves as sheet,
/// in absolute lengths; the default (both 0) leaves none.
///
/// The rule inserts a particle at the midpoint of two particles `d` apart
/// with `d_min <= d <= d_max` unless another particle lies within
/// `d_min / 2` of that midpoint. So a pair closer than `d_min` is a gap
/// the rule has not yet had to fill, and a pair up to `d_max` apart with a
/// particle near its midpoint is one it counts as filled: both hold the
/// surface together as far as the rule is concerned (fig_13_handle: the
/// rims that join into the neck leave cells whose diagonals, 1.5-1.6 r0,
/// are beyond the cohesion cut-off 1.5 r0 with a particle near their
/// midpoints, which the exported surface showed as holes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SheetGap {
    /// The rule's smallest pair distance (absolute).
    pub d_min: Real,
    /// The rule's largest pair distance (absolute).
    pub d_max: Real,
}

impl SheetGap {
    /// Whether the pair `(a, b)` of `positions` (the object's particles)
    /// is a gap the rule leaves as sheet.
    pub fn holds(&self, positions: &[op_dynamics::Point3], a: usize, b: usize) -> bool {
        let d = (positions[a] - positions[b]).norm();
        if d < self.d_min {
            return true;
        }
        if d > self.d_max {
            return false;
        }
        let m = op_dynamics::Point3::from((positions[a].coords + positions[b].coords) / 2.0);
        let r2 = 0.25 * self.d_min * self.d_min;
        positions
            .iter()
            .enumerate()
            .any(|(k, x)| k != a && k != b && (x - m).norm_squared() < r2)
    }
}

/// The mutual-neighbour radius of an object's surface (absolute length):
/// `triangulation_radius` rest spacings, or the largest spacing cut-off of
/// the materials of the particles in `slots` when that is longer (a pair
/// within it still attracts, seed 000 eq. 5, seed 002 §3, so it holds the
/// surface together and may be an edge of it).
pub fn surface_radius(
    world: &World,
    slots: &[usize],
    object: &BuiltObject,
    outputs: &Outputs,
) -> Real {
    let p = world.particles();
    let materials = world.materials();
    let mut seen = Vec::new();
    let mut cutoff: Real = 0.0;
    for &s in slots {
        let m = p.materials()[s];
        if !seen.contains(&m) {
            seen.push(m);
            if let Some(material) = materials.get(m as usize) {
                cutoff = cutoff.max(material.spacing_cutoff());
            }
        }
    }
    (outputs.triangulation_radius * object.rest_spacing).max(cutoff)
}

/// Whether the particles in slots `a` and `b` still attract each other:
/// closer than the spacing cut-off of their materials (the larger of the
/// two; a material without a spacing term sets no limit) and, when bonds
/// govern the pair (op_dynamics::bonds), bonded. Pairs that fail either
/// only repel or do not interact at all (seed 002 §5).
pub fn interacting(world: &World, a: usize, b: usize) -> bool {
    let p = world.particles();
    let materials = world.materials();
    let (ma, mb) = (p.materials()[a], p.materials()[b]);
    let cutoff = [ma, mb]
        .iter()
        .filter_map(|&m| materials.get(m as usize))
        .map(|m| m.spacing_cutoff())
        .fold(0.0, Real::max);
    if cutoff > 0.0 && (p.positions()[a] - p.positions()[b]).norm() >= cutoff {
        return false;
    }
    match world.bonds() {
        Some(bonds) if bonds.governs(ma, mb) => bonds.contains(p.ids()[a], p.ids()[b]),
        _ => true,
    }
}

/// The name of an object's triangulation in the frames: `<object>_surface`.
pub fn surface_name(object: &BuiltObject) -> String {
    format!("{}_surface", object.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compaction_drops_loose_vertices_and_degenerate_triangles() {
        let mut m = FrameMesh::named("m".into());
        for k in 0..5 {
            m.push(Vec3::new(k as Real, 0.0, 0.0), Vec3::z());
        }
        m.triangles = vec![[1, 2, 4], [2, 2, 3]];
        m.compact_triangles();
        assert_eq!(m.vertices.len(), 3);
        assert_eq!(m.normals.len(), 3);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.vertices[2].x, 4.0);
    }

    fn tool(shape: op_modeling::ToolShape) -> Tool {
        let mut particles = op_dynamics::Particles::new();
        particles
            .push(op_dynamics::ParticleDesc::at(op_dynamics::Point3::new(
                9.0, 9.0, 9.0,
            )))
            .unwrap();
        let params = op_modeling::ToolParams {
            name: "t".into(),
            shape,
            path: op_modeling::tools::ToolPath::fixed([1.0, 2.0, 3.0]),
            role: op_modeling::Role::Obstacle {
                stiffness: 1.0,
                margin: 0.0,
                damping: 0.0,
                friction: 0.0,
            },
            objects: None,
        };
        Tool::new(&params, &particles).unwrap()
    }

    /// A ball tool shares its vertices (no more than the parry mesh has)
    /// and shades round: every vertex normal is within a few degrees of the
    /// radial direction.
    #[test]
    fn a_ball_tool_is_welded_and_smooth() {
        use op_modeling::ToolShape;
        let t = tool(ToolShape::Ball { radius: 1.0 });
        let (raw, tris) = t.surface_mesh(0.0, 10.0);
        let mesh = tool_geometry(0, &t, 0.0);
        assert_eq!(mesh.triangles.len(), tris.len());
        assert!(
            mesh.vertices.len() <= raw.len(),
            "{} > {}",
            mesh.vertices.len(),
            raw.len()
        );
        assert!(mesh.vertices.len() < 3 * tris.len() / 2);
        let centre = Vec3::new(1.0, 2.0, 3.0);
        for (x, n) in mesh.vertices.iter().zip(&mesh.normals) {
            let radial = (x - centre).normalize();
            assert!(n.dot(&radial) > 0.99, "{n:?} at {x:?}");
        }
    }

    /// A cuboid keeps its edges: four vertices per face, each with the
    /// face's normal.
    #[test]
    fn a_cuboid_tool_keeps_its_creases() {
        use op_modeling::ToolShape;
        let t = tool(ToolShape::Cuboid {
            half_extents: [1.0, 2.0, 0.5],
        });
        let mesh = tool_geometry(0, &t, 0.0);
        assert_eq!(mesh.triangles.len(), 12);
        assert_eq!(mesh.vertices.len(), 24);
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|v| mesh.vertices[v as usize]);
            let face = (b - a).cross(&(c - a)).normalize();
            for v in tri {
                assert!((mesh.normals[*v as usize] - face).norm() < 1e-12);
            }
        }
    }

    /// Two triangles folded at 90° along a shared edge keep separate
    /// vertices there; folded at 10° they share them.
    #[test]
    fn welding_follows_the_crease_angle() {
        let fold = |degrees: Real| {
            let a = degrees.to_radians();
            let positions = vec![
                Vec3::zeros(),
                Vec3::x(),
                Vec3::new(0.5, 1.0, 0.0),
                Vec3::new(0.5, -a.cos(), a.sin()),
            ];
            weld_smooth("f".into(), &positions, &[[0, 1, 2], [1, 0, 3]], 40.0)
        };
        assert_eq!(fold(10.0).vertices.len(), 4);
        assert_eq!(fold(90.0).vertices.len(), 6);
    }
}
