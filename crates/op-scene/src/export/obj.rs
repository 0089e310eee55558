//! OBJ frame files (obj-exporter): one object per file, y-up.
//!
//! Axis convention: scenes are z-up (gravity along `-z`); OBJ files are
//! y-up by convention and Blender's OBJ importer (forward `-Z`, up `Y`, its
//! defaults) turns file `(x, y, z)` into Blender `(x, -z, y)`. The files
//! therefore hold scene `(x, y, z)` as `(x, z, -y)` (positions and
//! normals), and Blender shows scene coordinates exactly: scene `+z` is
//! Blender's `+Z`. [`scene_to_obj`] and [`obj_to_scene`] convert.
//!
//! Vertices carry their normals as `vn` of the same rank; triangles are
//! written `f v//v`, segments `l v v` (a normal index is not valid on a
//! line). A mesh with no element is a point cloud of loose vertices, which
//! importers keep only in a file holding nothing else: hence one file per
//! object. obj-exporter prints fixed 6 decimals: coordinates below 1e-6
//! scene units are lost, so keep scenes in sensible units (r0 ~ 1).

use std::io::Write;

use obj_exporter::{Geometry, ObjSet, Object, Primitive, Shape, Vertex};
use op_dynamics::Vec3;

use super::geometry::FrameMesh;

/// Scene coordinates (z-up) to OBJ file coordinates (y-up): `(x, z, -y)`.
pub fn scene_to_obj(v: [f64; 3]) -> [f64; 3] {
    // `0 - y`, not `-y`: no `-0.000000` for a zero coordinate.
    [v[0], v[2], 0.0 - v[1]]
}

/// OBJ file coordinates (y-up) to scene coordinates (z-up): the inverse
/// of [`scene_to_obj`], `(x, -z, y)`.
pub fn obj_to_scene(v: [f64; 3]) -> [f64; 3] {
    [v[0], 0.0 - v[2], v[1]]
}

fn vertex(v: &Vec3) -> Vertex {
    let [x, y, z] = scene_to_obj([v.x, v.y, v.z]);
    Vertex { x, y, z }
}

fn shape(primitive: Primitive) -> Shape {
    Shape {
        primitive,
        groups: Vec::new(),
        smoothing_groups: Vec::new(),
    }
}

/// The obj-exporter object of `mesh`.
fn object(mesh: &FrameMesh) -> Object {
    let with_normal = |v: u32| (v as usize, None, Some(v as usize));
    let plain = |v: u32| (v as usize, None, None);
    let triangles = mesh.triangles.iter().map(|t| {
        shape(Primitive::Triangle(
            with_normal(t[0]),
            with_normal(t[1]),
            with_normal(t[2]),
        ))
    });
    let lines = mesh
        .lines
        .iter()
        .map(|l| shape(Primitive::Line(plain(l[0]), plain(l[1]))));
    Object {
        name: mesh.name.clone(),
        vertices: mesh.vertices.iter().map(vertex).collect(),
        tex_vertices: Vec::new(),
        normals: mesh.normals.iter().map(vertex).collect(),
        geometry: vec![Geometry {
            material_name: None,
            shapes: triangles.chain(lines).collect(),
        }],
    }
}

/// Writes `mesh` as a one-object OBJ file.
pub fn write(mesh: &FrameMesh, w: &mut dyn Write) -> std::io::Result<()> {
    let set = ObjSet {
        material_library: None,
        objects: vec![object(mesh)],
    };
    obj_exporter::export(&set, &mut super::SizedWriter(w))
}

/// Wavefront OBJ, one file per sequence and frame, y-up (scene `z` written
/// as OBJ `y`, scene `y` as OBJ `-z`): what Blender's OBJ importer
/// (forward `-Z`, up `Y`) and other OBJ readers expect.
#[derive(Debug)]
pub struct ObjFormat;

impl super::format::FileFormat for ObjFormat {
    fn name(&self) -> &'static str {
        "obj"
    }

    fn axes(&self) -> &'static str {
        "y_up"
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

    #[test]
    fn axes_round_trip_and_up_is_obj_y() {
        let v = [1.0, 2.0, 3.0];
        assert_eq!(obj_to_scene(scene_to_obj(v)), v);
        assert_eq!(scene_to_obj([0.0, 0.0, 1.0]), [0.0, 1.0, 0.0]);
    }

    #[test]
    fn lines_have_no_normal_index() {
        let mesh = FrameMesh {
            name: "axes".into(),
            vertices: vec![Vec3::zeros(), Vec3::x(), Vec3::z()],
            normals: vec![Vec3::z(); 3],
            triangles: vec![[0, 1, 2]],
            lines: vec![[0, 1]],
        };
        let mut out = Vec::new();
        write(&mesh, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("\nl 1 2\n"), "{text}");
        assert!(text.contains("\nf 1//1 2//2 3//3\n"), "{text}");
        assert!(text.contains("\nv 0.000000 1.000000 0.000000\n"), "{text}");
    }
}
