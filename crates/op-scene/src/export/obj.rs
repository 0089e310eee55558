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
//!
//! The file is obj-exporter's text byte for byte: its object line is
//! obj-exporter's, and the vertex, normal and element lines are encoded
//! by op-scene's `export::obj_text` as obj-exporter formats them, without
//! `core::fmt` (the tests compare the two).

use std::io::Write;

#[cfg(test)]
use obj_exporter::{Geometry, Primitive, Shape, Vertex};
use obj_exporter::{ObjSet, Object};
use op_dynamics::Vec3;
use rayon::prelude::*;

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

#[cfg(test)]
fn vertex(v: &Vec3) -> Vertex {
    let [x, y, z] = scene_to_obj([v.x, v.y, v.z]);
    Vertex { x, y, z }
}

#[cfg(test)]
fn shape(primitive: Primitive) -> Shape {
    Shape {
        primitive,
        groups: Vec::new(),
        smoothing_groups: Vec::new(),
    }
}

/// Vertices, normals or elements per piece of a file that
/// [`write`] encodes on its own.
const PIECE: usize = 1 << 14;

/// One piece of a mesh's file: a run of its vertices, normals, triangles
/// or segments.
#[derive(Clone, Copy)]
enum Piece {
    Vertices(usize, usize),
    Normals(usize, usize),
    Triangles(usize, usize),
    Lines(usize, usize),
}

/// The pieces of `mesh`'s file in file order: vertices, normals,
/// triangles, then segments, each cut into runs of [`PIECE`].
fn pieces(mesh: &FrameMesh) -> Vec<Piece> {
    let runs = |n: usize, make: fn(usize, usize) -> Piece| {
        (0..n.div_ceil(PIECE)).map(move |k| make(k * PIECE, ((k + 1) * PIECE).min(n)))
    };
    runs(mesh.vertices.len(), Piece::Vertices)
        .chain(runs(mesh.normals.len(), Piece::Normals))
        .chain(runs(mesh.triangles.len(), Piece::Triangles))
        .chain(runs(mesh.lines.len(), Piece::Lines))
        .collect()
}

/// The obj-exporter object of a piece of `mesh`, named `name`: a
/// piece's indices are the mesh's, and an object holding no vertex before
/// them numbers them as the whole file does. The tests' reference for
/// [`encode`].
#[cfg(test)]
fn object(mesh: &FrameMesh, piece: Piece, name: &str) -> Object {
    let with_normal = |v: u32| (v as usize, None, Some(v as usize));
    let plain = |v: u32| (v as usize, None, None);
    let mut object = Object {
        name: name.to_string(),
        vertices: Vec::new(),
        tex_vertices: Vec::new(),
        normals: Vec::new(),
        geometry: Vec::new(),
    };
    let shapes: Vec<Shape> = match piece {
        Piece::Vertices(a, b) => {
            object.vertices = mesh.vertices[a..b].iter().map(vertex).collect();
            Vec::new()
        }
        Piece::Normals(a, b) => {
            object.normals = mesh.normals[a..b].iter().map(vertex).collect();
            Vec::new()
        }
        Piece::Triangles(a, b) => mesh.triangles[a..b]
            .iter()
            .map(|t| {
                shape(Primitive::Triangle(
                    with_normal(t[0]),
                    with_normal(t[1]),
                    with_normal(t[2]),
                ))
            })
            .collect(),
        Piece::Lines(a, b) => mesh.lines[a..b]
            .iter()
            .map(|l| shape(Primitive::Line(plain(l[0]), plain(l[1]))))
            .collect(),
    };
    object.geometry.push(Geometry {
        material_name: None,
        shapes,
    });
    object
}

/// An upper bound of the bytes of `piece`'s lines in `mesh`'s file, for
/// coordinates below 1e9 in size: a `v` or `vn` line holds three numbers
/// of at most 17 characters (sign, 9 digits, point, 6 decimals), an `f`
/// line three `a//a` of the vertex count's digits, an `l` line two.
fn piece_bytes(mesh: &FrameMesh, piece: Piece) -> usize {
    let digits = mesh.vertices.len().max(1).ilog10() as usize + 1;
    let (lines, per_line) = match piece {
        Piece::Vertices(a, b) | Piece::Normals(a, b) => (b - a, 3 + 3 * 18),
        Piece::Triangles(a, b) => (b - a, 2 + 3 * (2 * digits + 3)),
        Piece::Lines(a, b) => (b - a, 2 + 2 * (digits + 1)),
    };
    lines * per_line
}

/// About how many bytes [`write`] writes for `mesh`.
pub(crate) fn size_hint(mesh: &FrameMesh) -> usize {
    let header = mesh.name.len() + 3;
    header
        + pieces(mesh)
            .into_iter()
            .map(|p| piece_bytes(mesh, p))
            .sum::<usize>()
}

/// The lines of `piece` of `mesh`'s file, as obj-exporter writes them
/// ([`super::obj_text`]): a piece's indices are the mesh's, numbered as the
/// whole file numbers them.
fn encode(mesh: &FrameMesh, piece: Piece) -> Vec<u8> {
    use super::obj_text::{point_lines, segment_lines, triangle_lines};
    let to_file = |v: &Vec3| scene_to_obj([v.x, v.y, v.z]);
    let mut out = Vec::with_capacity(piece_bytes(mesh, piece));
    match piece {
        Piece::Vertices(a, b) => point_lines(&mut out, b"v", &mesh.vertices[a..b], to_file),
        Piece::Normals(a, b) => point_lines(&mut out, b"vn", &mesh.normals[a..b], to_file),
        Piece::Triangles(a, b) => triangle_lines(&mut out, &mesh.triangles[a..b]),
        Piece::Lines(a, b) => segment_lines(&mut out, &mesh.lines[a..b]),
    }
    out
}

/// obj-exporter's text of `objects`, into a buffer of `capacity` bytes.
fn export(objects: Vec<Object>, capacity: usize) -> std::io::Result<Vec<u8>> {
    let set = ObjSet {
        material_library: None,
        objects,
    };
    let mut out = Vec::with_capacity(capacity);
    obj_exporter::export(&set, &mut out)?;
    Ok(out)
}

/// `mesh`'s one-object OBJ file in pieces: obj-exporter's object line,
/// then its lines encoded in pieces of 16,384 lines in parallel
/// ([`encode`]), in file order, so their concatenation is the same at
/// any thread count and what one obj-exporter call would write. Measured
/// on the scene report's skinned cloth at 120 x 120 particles (skins of
/// 403,822 vertices, 3 frames): the export stage took 2.12 s at 2 threads
/// with one call per file, 1.32 s with pieces (2.50 and 2.26 s at 1
/// thread).
fn file_pieces(mesh: &FrameMesh) -> std::io::Result<Vec<Vec<u8>>> {
    let header = Object {
        name: mesh.name.clone(),
        vertices: Vec::new(),
        tex_vertices: Vec::new(),
        normals: Vec::new(),
        geometry: Vec::new(),
    };
    let mut out = vec![export(vec![header], 0)?];
    let pieces = pieces(mesh);
    // A small mesh (fewer lines than one piece holds) on one task: its
    // few pieces cost less than waking a thread.
    let lines = mesh.vertices.len() + mesh.normals.len() + mesh.triangles.len() + mesh.lines.len();
    let min_len = if lines < PIECE {
        pieces.len().max(1)
    } else {
        1
    };
    out.par_extend(
        pieces
            .into_par_iter()
            .with_min_len(min_len)
            .map(|piece| encode(mesh, piece)),
    );
    Ok(out)
}

/// Writes `mesh` as a one-object OBJ file: its pieces (`file_pieces`)
/// one after the other.
pub fn write(mesh: &FrameMesh, w: &mut dyn Write) -> std::io::Result<()> {
    for piece in file_pieces(mesh)? {
        w.write_all(&piece)?;
    }
    Ok(())
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

    fn mesh_size_hint(&self, mesh: &FrameMesh) -> usize {
        size_hint(mesh)
    }

    fn encode_mesh(&self, mesh: &FrameMesh, out: &mut dyn Write) -> std::io::Result<()> {
        write(mesh, out)
    }

    fn encode_mesh_pieces(&self, mesh: &FrameMesh) -> std::io::Result<Vec<Vec<u8>>> {
        file_pieces(mesh)
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

    /// A mesh of `n` vertices on a helix, a triangle per three
    /// consecutive vertices and a segment per two.
    fn helix(n: usize) -> FrameMesh {
        let at = |k: usize| {
            let t = k as f64 * 0.01;
            Vec3::new(t.cos(), t.sin(), 0.001 * k as f64 - 7.5)
        };
        FrameMesh {
            name: "helix".into(),
            vertices: (0..n).map(at).collect(),
            normals: (0..n).map(|k| at(k).normalize()).collect(),
            triangles: (0..n as u32 - 2).map(|k| [k, k + 1, k + 2]).collect(),
            lines: (0..n as u32 - 1).map(|k| [k, k + 1]).collect(),
        }
    }

    #[test]
    fn pieces_write_the_bytes_of_one_object() {
        let mesh = helix(2 * PIECE + 17);
        let whole = Object {
            name: mesh.name.clone(),
            vertices: mesh.vertices.iter().map(vertex).collect(),
            tex_vertices: Vec::new(),
            normals: mesh.normals.iter().map(vertex).collect(),
            geometry: vec![Geometry {
                material_name: None,
                shapes: ["triangles", "lines"]
                    .iter()
                    .flat_map(|kind| {
                        let piece = match *kind {
                            "triangles" => Piece::Triangles(0, mesh.triangles.len()),
                            _ => Piece::Lines(0, mesh.lines.len()),
                        };
                        object(&mesh, piece, "").geometry.remove(0).shapes
                    })
                    .collect(),
            }],
        };
        let expected = export(vec![whole], 0).unwrap();
        assert!(
            expected.len() <= size_hint(&mesh),
            "the size hint bounds the file"
        );
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut out = Vec::new();
            pool.install(|| write(&mesh, &mut out)).unwrap();
            assert!(
                out == expected,
                "{threads} threads: the pieces differ from one object"
            );
        }
        let text = String::from_utf8(expected).unwrap();
        let last = mesh.vertices.len();
        assert!(
            text.contains(&format!("\nf {0}//{0} ", last - 2)),
            "the last triangle"
        );
        assert!(
            text.contains(&format!("\nl {} {last}\n", last - 1)),
            "the last segment"
        );
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
