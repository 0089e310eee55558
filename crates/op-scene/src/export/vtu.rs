//! VTU particle state (vtkio): every particle of the scene as one vertex
//! cell of a VTK XML unstructured grid, in scene coordinates (z-up), with
//! per-particle point data for ParaView:
//!
//! | array | components | meaning |
//! |---|---|---|
//! | `id` | 1 (Int32) | particle id |
//! | `object` | 1 (Int32) | index of its object in the scene's `objects` |
//! | `type` | 1 (Int32) | part number `k` of `Standard(k)`, `-1` for a hinge |
//! | `orientation` | 4 (Float64) | unit quaternion `(w, x, y, z)` of its frame |
//! | `normal` | 3 (Float64) | normal `R(q) a` |
//! | `velocity` | 3 (Float64) | velocity |
//! | `rest_curvature` | 1 (Float64) | rest curvature `kappa` |
//! | `temperature` | 1 (Float64) | temperature |
//!
//! Objects are written in scene order, each with its original then its
//! created particles. `vtu/state.vtu.series` lists the files with their
//! scene times (ParaView's file-series format, [`super::series`]).
//!
//! Beside them, every skin, surface and tool of the frames (the meshes of
//! [`super::FrameMesh`], also in scene coordinates) is a sequence of its
//! own, `vtu/<stem>_00000.vtu` listed in `vtu/<stem>.vtu.series`: an
//! unstructured grid of its triangles (and line segments, if any) with the
//! point data `normal` (3, Float64: the skin's field gradient, the
//! particle normals of a surface, the face normal of a tool), which
//! ParaView uses to shade it smoothly.

use std::io::Write;

use op_dynamics::{ParticleType, World};
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

use super::geometry::FrameMesh;
use crate::built_scene::BuiltObject;

/// The VTK model of the particle state of `objects` in `world`.
fn model(world: &World, objects: &[BuiltObject], title: &str) -> Vtk {
    let p = world.particles();
    let mut slots = Vec::new();
    let mut object = Vec::new();
    for (k, o) in objects.iter().enumerate() {
        for s in o.all_ids().filter_map(|id| p.slot_of(id)) {
            slots.push(s);
            object.push(i32::try_from(k).unwrap_or(i32::MAX));
        }
    }
    let n = slots.len();
    let flat3 =
        |f: &dyn Fn(usize) -> [f64; 3]| -> Vec<f64> { slots.iter().flat_map(|&s| f(s)).collect() };
    let points = flat3(&|s| p.positions()[s].coords.into());
    let orientation: Vec<f64> = slots
        .iter()
        .flat_map(|&s| {
            let q = p.orientations()[s].into_inner();
            [q.w, q.i, q.j, q.k]
        })
        .collect();
    let normal = flat3(&|s| p.normal(s).into());
    let velocity = flat3(&|s| p.velocities()[s].into());
    let ids: Vec<i32> = slots
        .iter()
        .map(|&s| i32::try_from(p.ids()[s]).unwrap_or(i32::MAX))
        .collect();
    let kinds: Vec<i32> = slots
        .iter()
        .map(|&s| match p.kinds()[s] {
            ParticleType::Standard(k) => i32::from(k),
            ParticleType::Hinge => -1,
        })
        .collect();
    let scalar = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { slots.iter().map(|&s| f(s)).collect() };
    let point = vec![
        Attribute::scalars("id", 1).with_data(ids),
        Attribute::scalars("object", 1).with_data(object),
        Attribute::scalars("type", 1).with_data(kinds),
        Attribute::generic("orientation", 4).with_data(orientation),
        Attribute::normals("normal").with_data(normal),
        Attribute::vectors("velocity").with_data(velocity),
        Attribute::scalars("rest_curvature", 1).with_data(scalar(&|s| p.curvatures()[s])),
        Attribute::scalars("temperature", 1).with_data(scalar(&|s| p.temperatures()[s])),
    ];
    Vtk {
        version: Version::new_xml(1, 0),
        title: title.to_string(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: points.into(),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity: (0..n as u64).collect(),
                    offsets: (1..=n as u64).collect(),
                },
                types: vec![CellType::Vertex; n],
            },
            data: Attributes {
                point,
                cell: Vec::new(),
            },
        }),
    }
}

/// Writes the particle state of `objects` in `world` as a VTU file.
pub fn write(
    world: &World,
    objects: &[BuiltObject],
    title: &str,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    model(world, objects, title)
        .write_xml(w)
        .map_err(|e| std::io::Error::other(e.to_string()))
}

/// Writes the `.series` JSON of `files` (name relative to the series file,
/// scene time): [`super::series::write`].
pub fn write_series(files: &[(String, f64)], w: &mut dyn Write) -> std::io::Result<()> {
    super::series::write(files, w)
}

/// The VTK model of one frame mesh: its vertices, one triangle cell per
/// triangle and one line cell per segment, and the point data `normal`.
fn mesh_model(mesh: &FrameMesh) -> Vtk {
    let points: Vec<f64> = mesh.vertices.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    let normals: Vec<f64> = mesh.normals.iter().flat_map(|n| [n.x, n.y, n.z]).collect();
    let mut connectivity = Vec::with_capacity(3 * mesh.triangles.len() + 2 * mesh.lines.len());
    let mut offsets = Vec::with_capacity(mesh.triangles.len() + mesh.lines.len());
    let mut types = Vec::with_capacity(offsets.capacity());
    for t in &mesh.triangles {
        connectivity.extend(t.map(u64::from));
        offsets.push(connectivity.len() as u64);
        types.push(CellType::Triangle);
    }
    for l in &mesh.lines {
        connectivity.extend(l.map(u64::from));
        offsets.push(connectivity.len() as u64);
        types.push(CellType::Line);
    }
    Vtk {
        version: Version::new_xml(1, 0),
        title: mesh.name.clone(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: points.into(),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity,
                    offsets,
                },
                types,
            },
            data: Attributes {
                point: vec![Attribute::normals("normal").with_data(normals)],
                cell: Vec::new(),
            },
        }),
    }
}

/// Writes one frame mesh (a skin, surface or tool) as a VTU file.
pub fn write_mesh(mesh: &FrameMesh, w: &mut dyn Write) -> std::io::Result<()> {
    mesh_model(mesh)
        .write_xml(w)
        .map_err(|e| std::io::Error::other(e.to_string()))
}

/// VTK XML unstructured grid of every particle (one vertex cell each) with
/// per-particle attributes, one file per frame, in scene coordinates,
/// listed with their times in `vtu/state.vtu.series` (ParaView opens the
/// series as a time series); and every skin, surface and tool mesh as a
/// sequence `vtu/<stem>_<k:05>.vtu` of its own, listed in
/// `vtu/<stem>.vtu.series`.
#[derive(Debug)]
pub struct VtuFormat;

impl super::format::FileFormat for VtuFormat {
    fn name(&self) -> &'static str {
        "vtu"
    }

    fn axes(&self) -> &'static str {
        "z_up"
    }

    fn files(&self) -> super::format::Files {
        super::format::Files::State
    }

    fn encode_state(
        &self,
        world: &World,
        objects: &[BuiltObject],
        title: &str,
        out: &mut dyn Write,
    ) -> std::io::Result<()> {
        write(world, objects, title, out)
    }

    fn writes_meshes_with_state(&self) -> bool {
        true
    }

    fn encode_mesh(&self, mesh: &FrameMesh, out: &mut dyn Write) -> std::io::Result<()> {
        write_mesh(mesh, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_dynamics::Vec3;

    /// A mesh reads back with its triangles, segments and normals.
    #[test]
    fn meshes_parse_back_with_cells_and_normals() {
        let mesh = FrameMesh {
            name: "m".into(),
            vertices: vec![Vec3::zeros(), Vec3::x(), Vec3::new(0.0, 2.0, 3.0)],
            normals: vec![Vec3::z(); 3],
            triangles: vec![[0, 1, 2]],
            lines: vec![[0, 2]],
        };
        let mut bytes = Vec::new();
        write_mesh(&mesh, &mut bytes).unwrap();
        let vtk = Vtk::parse_xml(bytes.as_slice()).unwrap();
        let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
            panic!("not an unstructured grid");
        };
        let vtkio::model::Piece::Inline(piece) = &pieces[0] else {
            panic!("not inline");
        };
        assert_eq!(piece.num_points(), 3);
        assert_eq!(piece.cells.types, [CellType::Triangle, CellType::Line]);
        let Attribute::DataArray(normal) = &piece.data.point[0] else {
            panic!("no normals");
        };
        assert_eq!(normal.name, "normal");
        assert_eq!(normal.data.len(), 9);
    }
}
