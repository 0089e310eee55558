//! OBJ frames (DESIGN §6): one named OBJ object per scene object, particle
//! geometry as asked by [`Outputs`], vertex normals from the particle
//! frames, skins as triangle meshes with vertex normals, the particle
//! triangulations (seed 000 §5) as `<object>_surface` meshes when
//! [`Outputs::triangulation`] is set, each file written atomically (temp
//! file + rename) so a frame on disk is always complete.
//!
//! obj-exporter prints fixed 6 decimals: coordinates below 1e-6 scene units
//! are lost, so keep scenes in sensible units (r0 ~ 1).

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use obj_exporter::{Geometry, ObjSet, Object, Primitive, Shape, Vertex};
use op_dynamics::triangulation::{triangulate_points, TriangulationParams};
use op_dynamics::{Real, Tool, Vec3, World};
use op_implicit::Mesh;

use crate::built::BuiltObject;
use crate::outputs::{Outputs, ParticleOutput};
use crate::skins::{BuiltSkin, SkinTool};

/// Writes `bytes_fn`'s output to `path` atomically: a temporary file in the
/// same directory, flushed and synced, then renamed over `path`. The
/// temporary file is created exclusively (`create_new`: it fails rather than
/// follow a symbolic link or reuse a file someone else made) under a name
/// no other process can predict (process id, a counter and the clock's
/// nanoseconds), and removed when anything fails.
pub fn write_atomically(
    path: &Path,
    bytes_fn: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let (tmp, file) = create_temporary(dir, &name)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        bytes_fn(&mut w)?;
        w.flush()?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Whether `file_name` is one of [`write_atomically`]'s temporary files.
pub fn is_temporary(file_name: &str) -> bool {
    file_name.starts_with('.') && file_name.ends_with(".opsim-tmp")
}

/// A new temporary file `.{name}.{pid}-{counter}-{nanos}.opsim-tmp` in `dir`,
/// created exclusively; retried under a new name if one exists.
fn create_temporary(dir: &Path, name: &str) -> std::io::Result<(PathBuf, fs::File)> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut last = None;
    for _ in 0..16 {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let k = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(
            ".{name}.{}-{k}-{nanos}.opsim-tmp",
            std::process::id()
        ));
        match fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("cannot create a temporary file")))
}

fn vertex(v: Vec3) -> Vertex {
    Vertex {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn shape(primitive: Primitive) -> Shape {
    Shape {
        primitive,
        groups: Vec::new(),
        smoothing_groups: Vec::new(),
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

/// The OBJ object of one scene object at the world's current state.
pub fn object_geometry(world: &World, object: &BuiltObject, outputs: &Outputs) -> Object {
    let p = world.particles();
    let size = outputs.glyph_size * object.rest_spacing;
    let mut vertices = Vec::new();
    let mut normals = Vec::new();
    let mut shapes = Vec::new();
    for id in object.all_ids() {
        let Some(s) = p.slot_of(id) else { continue };
        let x = p.positions()[s].coords;
        let q = p.orientations()[s];
        let n = q * p.normal_axes()[s];
        match outputs.particles {
            ParticleOutput::None => {}
            ParticleOutput::Points => {
                // Plain `v` / `vn` pairs of the same rank and no element:
                // every OBJ reader keeps loose vertices, while `p` elements
                // are read by few (the wavefront_obj parser runs out of
                // memory on them).
                vertices.push(vertex(x));
                normals.push(vertex(n));
            }
            ParticleOutput::Discs => {
                let (t, b) = tangent_pair(&n);
                let (c, nk) = (vertices.len(), normals.len());
                vertices.push(vertex(x));
                normals.push(vertex(n));
                for k in 0..6 {
                    let a = k as Real * std::f64::consts::PI / 3.0;
                    vertices.push(vertex(x + size * (a.cos() * t + a.sin() * b)));
                }
                for k in 0..6 {
                    let (v1, v2) = (c + 1 + k, c + 1 + (k + 1) % 6);
                    shapes.push(shape(Primitive::Triangle(
                        (c, None, Some(nk)),
                        (v1, None, Some(nk)),
                        (v2, None, Some(nk)),
                    )));
                }
            }
            ParticleOutput::Axes => {
                let tx = q * p.tangent_axes()[s];
                let ty = n.cross(&tx);
                let c = vertices.len();
                let nk = normals.len();
                vertices.push(vertex(x));
                normals.push(vertex(n));
                for axis in [tx, ty, n] {
                    let k = vertices.len();
                    vertices.push(vertex(x + size * axis));
                    shapes.push(shape(Primitive::Line(
                        (c, None, Some(nk)),
                        (k, None, Some(nk)),
                    )));
                }
            }
        }
    }
    Object {
        name: object.name.clone(),
        vertices,
        tex_vertices: Vec::new(),
        normals,
        geometry: vec![Geometry {
            material_name: None,
            shapes,
        }],
    }
}

/// The OBJ object `name` of a polygonized skin: its triangles with
/// per-vertex normals (analytic field gradient).
pub fn mesh_geometry(name: &str, mesh: &Mesh) -> Object {
    let tri = |t: &[u32; 3]| {
        let c = |k: usize| (t[k] as usize, None, Some(t[k] as usize));
        shape(Primitive::Triangle(c(0), c(1), c(2)))
    };
    Object {
        name: name.to_string(),
        vertices: mesh.positions().iter().map(|p| vertex(p.coords)).collect(),
        tex_vertices: Vec::new(),
        normals: mesh.normals().iter().map(|&n| vertex(n)).collect(),
        geometry: vec![Geometry {
            material_name: None,
            shapes: mesh.triangles().iter().map(tri).collect(),
        }],
    }
}

/// The OBJ object `tool_<name>` (`tool_<k>` when unnamed) of tool `k` at
/// world time `t`: flat-shaded triangles (three vertices and the face
/// normal each). Planes are drawn as a square of half side 10.
pub fn tool_geometry(k: usize, tool: &Tool, t: Real) -> Object {
    let (v, tris) = tool.surface_mesh(t, 10.0);
    let name = match tool.params().name.as_str() {
        "" => format!("tool_{k}"),
        n => format!("tool_{n}"),
    };
    let mut vertices = Vec::with_capacity(3 * tris.len());
    let mut normals = Vec::with_capacity(tris.len());
    let mut shapes = Vec::with_capacity(tris.len());
    for (f, tri) in tris.iter().enumerate() {
        let [a, b, c] = tri.map(|i| v[i as usize].coords);
        normals.push(vertex(
            (b - a)
                .cross(&(c - a))
                .try_normalize(0.0)
                .unwrap_or_default(),
        ));
        vertices.extend([a, b, c].map(vertex));
        let corner = |j: usize| (3 * f + j, None, Some(f));
        shapes.push(shape(Primitive::Triangle(corner(0), corner(1), corner(2))));
    }
    Object {
        name,
        vertices,
        tex_vertices: Vec::new(),
        normals,
        geometry: vec![Geometry {
            material_name: None,
            shapes,
        }],
    }
}

/// The OBJ object `<object>_surface`: the object's live particles (original
/// then created) as vertices with their normals as `vn` of the same rank,
/// and the triangles of [`op_dynamics::triangulation`] over them (mutual
/// neighbours within `triangulation_radius` rest spacings, wound along the
/// particle normals).
pub fn surface_geometry(world: &World, object: &BuiltObject, outputs: &Outputs) -> Object {
    let p = world.particles();
    let slots: Vec<usize> = object.all_ids().filter_map(|id| p.slot_of(id)).collect();
    let positions: Vec<_> = slots.iter().map(|&s| p.positions()[s]).collect();
    let normals: Vec<Vec3> = slots.iter().map(|&s| p.normal(s)).collect();
    let params =
        TriangulationParams::with_radius(outputs.triangulation_radius * object.rest_spacing);
    // The radius is validated with the scene; a non-finite spacing leaves
    // the surface without triangles rather than failing the frame.
    let triangles = triangulate_points(&positions, &normals, &params).unwrap_or_default();
    let c = |k: u32| (k as usize, None, Some(k as usize));
    Object {
        name: format!("{}_surface", object.name),
        vertices: positions.iter().map(|q| vertex(q.coords)).collect(),
        tex_vertices: Vec::new(),
        normals: normals.iter().map(|&n| vertex(n)).collect(),
        geometry: vec![Geometry {
            material_name: None,
            shapes: triangles
                .iter()
                .map(|t| shape(Primitive::Triangle(c(t[0]), c(t[1]), c(t[2]))))
                .collect(),
        }],
    }
}

/// Writes one OBJ frame holding every object of the scene, then every
/// skin (polygonized at its current pose, deformed where it touches another
/// skin and clipped where it presses on an obstacle tool) as an object `<object>_skin`, then, when asked, every object's
/// triangulation as `<object>_surface`, then every tool at its current
/// pose as `tool_<name>`.
pub fn write_frame(
    path: &Path,
    world: &World,
    objects: &[BuiltObject],
    skins: &[BuiltSkin],
    skin_tools: &[SkinTool],
    tools: &[Tool],
    outputs: &Outputs,
) -> std::io::Result<()> {
    let scene_objects = objects;
    let mut objects: Vec<Object> = objects
        .iter()
        .map(|o| object_geometry(world, o, outputs))
        .collect();
    for s in skins {
        let mesh = s
            .mesh_in(skins, skin_tools, world.time())
            .map_err(std::io::Error::other)?;
        objects.push(mesh_geometry(&s.name, &mesh));
    }
    if outputs.triangulation {
        objects.extend(
            scene_objects
                .iter()
                .map(|o| surface_geometry(world, o, outputs)),
        );
    }
    for (k, tool) in tools.iter().enumerate() {
        objects.push(tool_geometry(k, tool, world.time()));
    }
    let set = ObjSet {
        material_library: None,
        objects,
    };
    write_atomically(path, |w| {
        let mut adapter = WriteAdapter(w);
        obj_exporter::export(&set, &mut adapter)
    })
}

/// `obj_exporter::export` wants a sized writer.
struct WriteAdapter<'a>(&'a mut dyn Write);

impl Write for WriteAdapter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// The file name of frame `k`: `frame_00000.obj`.
pub fn frame_name(k: usize) -> String {
    format!("frame_{k:05}.obj")
}
