//! Binary PLY frame files (ply-rs-bw): one mesh per file, little endian,
//! in scene coordinates (z-up, as Blender's PLY importer takes them).
//!
//! Elements: `vertex` (`x y z nx ny nz`, float), `face` (`vertex_indices`,
//! a list of `uchar` count and `int` indices, three per triangle) and
//! `edge` (`vertex1 vertex2`, int) for line segments. `face` is declared
//! even with no entry (count 0: a point cloud); `edge` only when the mesh
//! has line segments, because readers that do not know it (meshio,
//! trimesh without scipy) refuse a file that declares it.

use std::io::Write;

use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Ply, Property, PropertyAccess, PropertyDef, PropertyType,
    ScalarType,
};

use super::geometry::FrameMesh;

/// One PLY element of any of the three kinds (ply-rs-bw wants one type).
#[derive(Clone, Debug, Default)]
struct Element {
    floats: [f32; 6],
    ints: [i32; 3],
}

const FLOATS: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];

impl PropertyAccess for Element {
    fn new() -> Self {
        Element::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        match (name, property) {
            ("vertex1", Property::Int(v)) => self.ints[0] = v,
            ("vertex2", Property::Int(v)) => self.ints[1] = v,
            ("vertex_indices", Property::ListInt(v)) => {
                for (slot, i) in self.ints.iter_mut().zip(v) {
                    *slot = i;
                }
            }
            (name, Property::Float(v)) => {
                if let Some(k) = FLOATS.iter().position(|&n| n == name) {
                    self.floats[k] = v;
                }
            }
            _ => {}
        }
    }
    fn get_float(&self, name: &str) -> Option<f32> {
        FLOATS
            .iter()
            .position(|&n| n == name)
            .map(|k| self.floats[k])
    }
    fn get_int(&self, name: &str) -> Option<i32> {
        match name {
            "vertex1" => Some(self.ints[0]),
            "vertex2" => Some(self.ints[1]),
            _ => None,
        }
    }
    fn get_list_int(&self, name: &str) -> Option<&[i32]> {
        (name == "vertex_indices").then_some(&self.ints[..])
    }
}

fn index(v: u32) -> i32 {
    // Frame meshes are far below 2^31 vertices (the work limits bound them).
    i32::try_from(v).unwrap_or(i32::MAX)
}

/// The PLY model of `mesh`.
fn model(mesh: &FrameMesh) -> Ply<Element> {
    let mut ply = Ply::<Element>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.push(format!(
        "opsim frame: {} (scene coordinates, z up)",
        mesh.name
    ));
    let float = PropertyType::Scalar(ScalarType::Float);
    let mut vertex = ElementDef::new("vertex".to_string());
    for name in FLOATS {
        vertex
            .properties
            .add(PropertyDef::new(name.to_string(), float.clone()));
    }
    let mut face = ElementDef::new("face".to_string());
    face.properties.add(PropertyDef::new(
        "vertex_indices".to_string(),
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    ));
    let mut edge = ElementDef::new("edge".to_string());
    for name in ["vertex1", "vertex2"] {
        edge.properties.add(PropertyDef::new(
            name.to_string(),
            PropertyType::Scalar(ScalarType::Int),
        ));
    }
    ply.header.elements.add(vertex);
    ply.header.elements.add(face);
    if !mesh.lines.is_empty() {
        ply.header.elements.add(edge);
    }
    let vertices = mesh
        .vertices
        .iter()
        .zip(&mesh.normals)
        .map(|(x, n)| Element {
            floats: [x.x, x.y, x.z, n.x, n.y, n.z].map(|c| c as f32),
            ints: [0; 3],
        })
        .collect();
    let faces = mesh
        .triangles
        .iter()
        .map(|t| Element {
            floats: [0.0; 6],
            ints: t.map(index),
        })
        .collect();
    let edges = mesh
        .lines
        .iter()
        .map(|l| Element {
            floats: [0.0; 6],
            ints: [index(l[0]), index(l[1]), 0],
        })
        .collect();
    ply.payload.insert("vertex".to_string(), vertices);
    ply.payload.insert("face".to_string(), faces);
    if !mesh.lines.is_empty() {
        ply.payload.insert("edge".to_string(), edges);
    }
    ply
}

/// Writes `mesh` as a binary little-endian PLY file.
pub fn write(mesh: &FrameMesh, w: &mut dyn Write) -> std::io::Result<()> {
    let mut ply = model(mesh);
    ply_rs_bw::writer::Writer::new()
        .write_ply(&mut super::SizedWriter(w), &mut ply)
        .map(|_| ())
}

/// Binary little-endian PLY, one file per sequence and frame, in scene
/// coordinates (z-up, as Blender's PLY importer takes them): vertices with
/// normals (`x y z nx ny nz`, float), `face` (`vertex_indices`) and, for
/// line segments, `edge` (`vertex1 vertex2`) elements.
#[derive(Debug)]
pub struct PlyFormat;

impl super::format::FileFormat for PlyFormat {
    fn name(&self) -> &'static str {
        "ply"
    }

    fn axes(&self) -> &'static str {
        "z_up"
    }

    fn files(&self) -> super::format::Files {
        super::format::Files::PerSequence
    }

    fn encode_mesh(&self, mesh: &FrameMesh, out: &mut dyn Write) -> std::io::Result<()> {
        write(mesh, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_dynamics::Vec3;
    use ply_rs_bw::ply::DefaultElement;

    #[test]
    fn parses_back_with_counts_and_values() {
        let mesh = FrameMesh {
            name: "m".into(),
            vertices: vec![Vec3::zeros(), Vec3::x(), Vec3::new(0.0, 2.0, 3.0)],
            normals: vec![Vec3::z(); 3],
            triangles: vec![[0, 1, 2]],
            lines: vec![[0, 2]],
        };
        let mut bytes = Vec::new();
        write(&mesh, &mut bytes).unwrap();
        assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
        let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
            .read_ply(&mut bytes.as_slice())
            .unwrap();
        let v = &ply.payload["vertex"];
        assert_eq!(v.len(), 3);
        assert_eq!(v[2]["z"], Property::Float(3.0));
        assert_eq!(v[2]["nz"], Property::Float(1.0));
        assert_eq!(
            ply.payload["face"][0]["vertex_indices"],
            Property::ListInt(vec![0, 1, 2])
        );
        assert_eq!(ply.payload["edge"][0]["vertex2"], Property::Int(2));
    }

    /// A mesh without line segments declares no `edge` element (trimesh
    /// without scipy refuses `element edge 0`); a point cloud still
    /// declares `face` with count 0.
    #[test]
    fn declares_edges_only_when_there_are_some() {
        let header = |mesh: &FrameMesh| {
            let mut bytes = Vec::new();
            write(mesh, &mut bytes).unwrap();
            let end = bytes
                .windows(11)
                .position(|w| w == b"end_header\n")
                .unwrap();
            String::from_utf8(bytes[..end].to_vec()).unwrap()
        };
        let mut mesh = FrameMesh {
            name: "m".into(),
            vertices: vec![Vec3::zeros(), Vec3::x(), Vec3::y()],
            normals: vec![Vec3::z(); 3],
            triangles: vec![[0, 1, 2]],
            lines: vec![],
        };
        let h = header(&mesh);
        assert!(h.contains("element face 1\n"), "{h}");
        assert!(!h.contains("element edge"), "{h}");
        mesh.triangles.clear();
        let h = header(&mesh);
        assert!(
            h.contains("element vertex 3\n") && h.contains("element face 0\n"),
            "{h}"
        );
        assert!(!h.contains("element edge"), "{h}");
        mesh.lines.push([0, 1]);
        assert!(header(&mesh).contains("element edge 1\n"));
    }
}
