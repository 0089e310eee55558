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
//! scene times (ParaView's file-series format).

use std::io::Write;

use op_dynamics::{ParticleType, World};
use serde::Serialize;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

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

/// ParaView's `.series` file: the frame files and their times.
#[derive(Serialize)]
struct Series<'a> {
    #[serde(rename = "file-series-version")]
    version: &'static str,
    files: Vec<SeriesFile<'a>>,
}

#[derive(Serialize)]
struct SeriesFile<'a> {
    name: &'a str,
    time: f64,
}

/// Writes the `.series` JSON of `files` (name relative to the series file,
/// scene time).
pub fn write_series(files: &[(String, f64)], w: &mut dyn Write) -> std::io::Result<()> {
    let series = Series {
        version: "1.0",
        files: files
            .iter()
            .map(|(name, time)| SeriesFile { name, time: *time })
            .collect(),
    };
    serde_json::to_writer_pretty(&mut *w, &series).map_err(std::io::Error::other)?;
    writeln!(w)
}

/// VTK XML unstructured grid of every particle (one vertex cell each) with
/// per-particle attributes, one file per frame, in scene coordinates,
/// listed with their times in `vtu/state.vtu.series` (ParaView opens the
/// series as a time series).
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

    fn encode_series(&self, files: &[(String, f64)], out: &mut dyn Write) -> std::io::Result<()> {
        write_series(files, out)
    }
}
