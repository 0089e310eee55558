//! USD cache of a run (openusd): one USD text layer `usd/run.usda`
//! holding every sequence of the run ([`super::Sequence`]) as a prim
//! under the default prim `/Run` (an `Xform`), time-sampled at the frame
//! rate: frame `k` is time code `k`, at scene time `k / frame_rate`.
//!
//! | sequence | prim | attributes, sampled at every frame |
//! |---|---|---|
//! | an object's particles | `Points` | `points`, `normals` (the particle normals), `widths`, `primvars:orientations` (`quatf[]`, vertex interpolation: each particle's frame), `extent` |
//! | a skin, a triangulation, a tool | `Mesh` | `points`, `normals` (vertex interpolation), `faceVertexCounts`, `faceVertexIndices` (the topology changes from frame to frame), `extent`; `subdivisionScheme = "none"` |
//!
//! Particles have no radius in the model: their `widths` are the diameter
//! of the discs the other formats draw (`2 outputs.glyph_size` times the
//! object's rest spacing). Values are single precision, in scene
//! coordinates. A prim is named after its sequence's stem with every
//! character USD does not allow in a name (anything but ASCII letters,
//! digits and `_`) replaced by `_`, `_` put before a leading digit, and
//! `_2`, `_3`, ... appended to a name already taken ([`prim_names`];
//! `summary.json` `files.usd` lists them).
//!
//! Stage metadata: `upAxis = "Z"` (scenes are z-up), `metersPerUnit = 1`
//! (scenes declare no length unit, docs/units.md: their unit is written as
//! one metre; scale the stage to show it at another size),
//! `timeCodesPerSecond` and `framesPerSecond` the scene's frame rate (one
//! time code per frame, so a second of scene time plays in a second),
//! `startTimeCode = 0` and `endTimeCode` the last frame written.
//!
//! The frames accumulate in memory and the file is written whole,
//! atomically, at each checkpoint and at the end of the run; a resumed
//! run reads it back ([`super::run_cache`]).
//!
//! Text, not the binary crate format: the crate writer of openusd 0.6
//! (the last release that builds with rustc 1.95) stores a prim's list of
//! children as a `token[]` array where USD expects a token vector, and
//! Pixar's usd-core (26.11) refuses to open the file ("Invalid children
//! found in primChildren field"). openusd 0.8 fixes it; with it, this
//! format can write `.usdc` by changing its encoder and extension. The
//! text writer prints each single-precision value as the shortest decimal
//! of its double, so the values read back are those written.

use std::io::Write;
use std::path::Path;

use openusd::gf;
use openusd::sdf::{self, AbstractData, ChildrenKey, FieldKey, SpecType, Specifier, Value};
use openusd::usda::TextWriter;

use super::format::{FileFormat, Files};
use super::geometry::FrameMesh;
use super::layout::{Sequence, SequenceKind};
use super::run_cache::{RunCache, SequenceFrame};
use op_dynamics::Real;

/// The default prim holding every sequence.
pub const ROOT: &str = "Run";

/// The attributes of a particles prim (`Points`), sampled at every frame:
/// name and USD type.
const POINTS_ATTRIBUTES: [(&str, &str); 5] = [
    ("points", "point3f[]"),
    ("normals", "normal3f[]"),
    ("widths", "float[]"),
    ("primvars:orientations", "quatf[]"),
    ("extent", "float3[]"),
];

/// The attributes of a mesh prim (`Mesh`), sampled at every frame.
const MESH_ATTRIBUTES: [(&str, &str); 5] = [
    ("points", "point3f[]"),
    ("normals", "normal3f[]"),
    ("faceVertexCounts", "int[]"),
    ("faceVertexIndices", "int[]"),
    ("extent", "float3[]"),
];

/// The USD prim name of each sequence, in order (module docs).
pub fn prim_names(sequences: &[Sequence]) -> Vec<String> {
    let mut taken = std::collections::HashSet::new();
    sequences
        .iter()
        .map(|s| {
            let mut base: String = s
                .stem
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            if base.is_empty() || base.starts_with(|c: char| c.is_ascii_digit()) {
                base.insert(0, '_');
            }
            let mut name = base.clone();
            let mut k = 1;
            while !taken.insert(name.clone()) {
                k += 1;
                name = format!("{base}_{k}");
            }
            name
        })
        .collect()
}

/// One sequence's prim: its path and whether it is a particles prim.
#[derive(Debug)]
struct Prim {
    path: sdf::Path,
    points: bool,
}

impl Prim {
    fn attributes(&self) -> &'static [(&'static str, &'static str)] {
        if self.points {
            &POINTS_ATTRIBUTES
        } else {
            &MESH_ATTRIBUTES
        }
    }

    fn attribute(&self, name: &str) -> sdf::Path {
        self.path
            .append_property(name)
            .expect("attribute names are valid")
    }
}

/// The frames of a run as a USD layer (module docs).
#[derive(Debug)]
pub struct UsdCache {
    data: sdf::Data,
    prims: Vec<Prim>,
    frames: usize,
}

fn token(s: &str) -> Value {
    Value::Token(s.into())
}

impl UsdCache {
    /// The layer of a run of `sequences` at `frame_rate` frames per unit of
    /// scene time, without frames yet.
    pub fn new(sequences: &[Sequence], frame_rate: Real) -> Self {
        let names = prim_names(sequences);
        let mut data = sdf::Data::new();
        let root = data.create_spec(sdf::Path::abs_root(), SpecType::PseudoRoot);
        root.add(
            ChildrenKey::PrimChildren,
            Value::TokenVec(vec![ROOT.into()]),
        );
        root.add(FieldKey::DefaultPrim, token(ROOT));
        root.add(
            FieldKey::Documentation,
            Value::String("opsim run: every sequence of the run, one time code per frame".into()),
        );
        root.add("upAxis", token("Z"));
        root.add("metersPerUnit", Value::Double(1.0));
        root.add(FieldKey::TimeCodesPerSecond, Value::Double(frame_rate));
        root.add(FieldKey::FramesPerSecond, Value::Double(frame_rate));
        root.add(FieldKey::StartTimeCode, Value::Double(0.0));
        root.add(FieldKey::EndTimeCode, Value::Double(0.0));
        let run = sdf::Path::new(&format!("/{ROOT}")).expect("a valid path");
        let spec = data.create_spec(run.clone(), SpecType::Prim);
        spec.add(FieldKey::Specifier, Value::Specifier(Specifier::Def));
        spec.add(FieldKey::TypeName, token("Xform"));
        spec.add(
            ChildrenKey::PrimChildren,
            Value::TokenVec(names.iter().map(|n| n.as_str().into()).collect()),
        );
        let mut prims = Vec::new();
        for (seq, name) in sequences.iter().zip(&names) {
            let prim = Prim {
                path: sdf::Path::new(&format!("/{ROOT}/{name}")).expect("names are valid"),
                points: seq.kind == SequenceKind::Particles,
            };
            let spec = data.create_spec(prim.path.clone(), SpecType::Prim);
            spec.add(FieldKey::Specifier, Value::Specifier(Specifier::Def));
            spec.add(
                FieldKey::TypeName,
                token(if prim.points { "Points" } else { "Mesh" }),
            );
            let mut properties: Vec<_> = prim.attributes().iter().map(|a| a.0.into()).collect();
            if !prim.points {
                properties.push("subdivisionScheme".into());
            }
            spec.add(ChildrenKey::PropertyChildren, Value::TokenVec(properties));
            for (attr, ty) in prim.attributes() {
                let spec = data.create_spec(prim.attribute(attr), SpecType::Attribute);
                spec.add(FieldKey::TypeName, token(ty));
                if matches!(*attr, "normals" | "primvars:orientations" | "widths") {
                    spec.add("interpolation", token("vertex"));
                }
            }
            if !prim.points {
                let spec =
                    data.create_spec(prim.attribute("subdivisionScheme"), SpecType::Attribute);
                spec.add(FieldKey::TypeName, token("token"));
                spec.add(
                    FieldKey::Variability,
                    Value::Variability(sdf::Variability::Uniform),
                );
                spec.add(FieldKey::Default, token("none"));
            }
            prims.push(prim);
        }
        UsdCache {
            data,
            prims,
            frames: 0,
        }
    }

    /// Appends the sample of `attr` of `prim` at time code `k`.
    fn sample(&mut self, prim: usize, attr: &str, k: usize, value: Value) {
        let path = self.prims[prim].attribute(attr);
        let spec = self
            .data
            .spec_mut(&path)
            .expect("every attribute has a spec");
        match spec.get_mut(FieldKey::TimeSamples.as_str()) {
            Some(Value::TimeSamples(samples)) => samples.push((k as f64, value)),
            _ => spec.add(
                FieldKey::TimeSamples,
                Value::TimeSamples(vec![(k as f64, value)]),
            ),
        }
    }

    /// The samples of prim `n` at frame `k`.
    fn add_sequence(&mut self, n: usize, k: usize, frame: &SequenceFrame<'_>) {
        let f3 = |v: &op_dynamics::Vec3| gf::Vec3f::from([v.x as f32, v.y as f32, v.z as f32]);
        let (points, normals): (Vec<gf::Vec3f>, Vec<gf::Vec3f>) = match frame {
            SequenceFrame::Particles {
                world,
                object,
                width,
            } => {
                let p = world.particles();
                let slots: Vec<usize> = object.all_ids().filter_map(|id| p.slot_of(id)).collect();
                let orientations = slots
                    .iter()
                    .map(|&s| {
                        let q = p.orientations()[s].into_inner();
                        gf::Quatf::from([q.w as f32, q.i as f32, q.j as f32, q.k as f32])
                    })
                    .collect();
                self.sample(
                    n,
                    "widths",
                    k,
                    Value::FloatVec(vec![*width as f32; slots.len()]),
                );
                self.sample(n, "primvars:orientations", k, Value::QuatfVec(orientations));
                slots
                    .iter()
                    .map(|&s| (f3(&p.positions()[s].coords), f3(&p.normal(s))))
                    .unzip()
            }
            SequenceFrame::Mesh(mesh) => {
                let FrameMesh {
                    vertices,
                    normals,
                    triangles,
                    ..
                } = mesh;
                let indices = triangles
                    .iter()
                    .flatten()
                    .map(|&v| i32::try_from(v).unwrap_or(i32::MAX))
                    .collect();
                self.sample(
                    n,
                    "faceVertexCounts",
                    k,
                    Value::IntVec(vec![3; triangles.len()]),
                );
                self.sample(n, "faceVertexIndices", k, Value::IntVec(indices));
                (
                    vertices.iter().map(f3).collect(),
                    normals.iter().map(f3).collect(),
                )
            }
        };
        self.sample(n, "extent", k, Value::Vec3fVec(extent(&points)));
        self.sample(n, "points", k, Value::Vec3fVec(points));
        self.sample(n, "normals", k, Value::Vec3fVec(normals));
    }
}

/// The bounds `[min, max]` of `points` (zero for none).
fn extent(points: &[gf::Vec3f]) -> Vec<gf::Vec3f> {
    if points.is_empty() {
        return vec![gf::Vec3f::default(); 2];
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    vec![lo.into(), hi.into()]
}

impl RunCache for UsdCache {
    fn add_frame(&mut self, k: usize, frame: &[SequenceFrame<'_>]) -> std::io::Result<()> {
        if k != self.frames || frame.len() != self.prims.len() {
            return Err(std::io::Error::other(format!(
                "USD cache: frame {k} of {} sequences, expected frame {} of {}",
                frame.len(),
                self.frames,
                self.prims.len()
            )));
        }
        for (n, f) in frame.iter().enumerate() {
            self.add_sequence(n, k, f);
        }
        self.frames += 1;
        if let Some(root) = self.data.spec_mut(&sdf::Path::abs_root()) {
            root.add(FieldKey::EndTimeCode, Value::Double(k as f64));
        }
        Ok(())
    }

    fn frames(&self) -> usize {
        self.frames
    }

    fn encode(&self, out: &mut dyn Write) -> std::io::Result<()> {
        let text = TextWriter::write_to_string(&self.data)
            .map_err(|e| std::io::Error::other(format!("{e:#}")))?;
        out.write_all(text.as_bytes())
    }

    fn resume(&mut self, file: &Path, last: usize) -> Result<(), String> {
        let what = file.display();
        let read = openusd::usda::read_file(file)
            .map_err(|e| format!("cannot read the USD cache {what}: {e:#}"))?;
        let end = match read.try_field(&sdf::Path::abs_root(), FieldKey::EndTimeCode.as_str()) {
            Ok(Some(v)) => match v.as_ref() {
                Value::Double(t) => *t,
                _ => -1.0,
            },
            _ => -1.0,
        };
        if end < last as f64 {
            return Err(format!(
                "the USD cache {what} ends at frame {end}, before the checkpoint's frame {last}"
            ));
        }
        for n in 0..self.prims.len() {
            for (attr, _) in self.prims[n].attributes() {
                let path = self.prims[n].attribute(attr);
                let samples = match read.try_field(&path, FieldKey::TimeSamples.as_str()) {
                    Ok(Some(v)) => match v.into_owned() {
                        Value::TimeSamples(s) => s,
                        _ => Vec::new(),
                    },
                    _ => Vec::new(),
                };
                let kept: Vec<(f64, Value)> = samples
                    .into_iter()
                    .filter(|(t, _)| *t <= last as f64)
                    .collect();
                if kept.len() != last + 1 {
                    return Err(format!(
                        "the USD cache {what} holds {} samples of {path} up to frame {last}, \
                         expected {}",
                        kept.len(),
                        last + 1
                    ));
                }
                let spec = self
                    .data
                    .spec_mut(&path)
                    .expect("every attribute has a spec");
                spec.add(FieldKey::TimeSamples, Value::TimeSamples(kept));
            }
        }
        self.frames = last + 1;
        if let Some(root) = self.data.spec_mut(&sdf::Path::abs_root()) {
            root.add(FieldKey::EndTimeCode, Value::Double(last as f64));
        }
        Ok(())
    }
}

/// One USD text layer (`.usda`) of the whole run: every sequence
/// as a time-sampled prim (module docs), in scene coordinates (z-up, and
/// the stage says so).
#[derive(Debug)]
pub struct UsdFormat;

impl FileFormat for UsdFormat {
    fn name(&self) -> &'static str {
        "usd"
    }

    fn extension(&self) -> &'static str {
        "usda"
    }

    fn axes(&self) -> &'static str {
        "z_up"
    }

    fn files(&self) -> Files {
        Files::Run
    }

    fn run_cache(&self, sequences: &[Sequence], frame_rate: Real) -> Option<Box<dyn RunCache>> {
        Some(Box::new(UsdCache::new(sequences, frame_rate)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::layout::sequences;

    #[test]
    fn prim_names_are_valid_and_unique() {
        let s = sequences([
            ("a-b".to_string(), SequenceKind::Particles),
            ("a_b".to_string(), SequenceKind::Skin),
            ("3d.x".to_string(), SequenceKind::Tool),
        ]);
        assert_eq!(prim_names(&s), ["a_b", "a_b_2", "_3d_x"]);
    }

    /// Meshes written, read back with openusd's reader, cut at a frame and
    /// continued give the same bytes as the uninterrupted file.
    #[test]
    fn a_cache_read_back_and_continued_is_the_same_file() {
        let s = sequences([("m".to_string(), SequenceKind::Skin)]);
        let mesh = |k: usize| {
            let mut m = FrameMesh::default();
            for v in 0..3 + k {
                m.vertices
                    .push(op_dynamics::Vec3::new(v as Real, k as Real / 3.0, 0.1));
                m.normals.push(op_dynamics::Vec3::z());
            }
            m.triangles = (0..1 + k as u32).map(|t| [0, 1 + t, 2 + t]).collect();
            SequenceFrame::Mesh(m)
        };
        let encode = |c: &UsdCache| {
            let mut b = Vec::new();
            c.encode(&mut b).unwrap();
            b
        };
        let mut whole = UsdCache::new(&s, 24.0);
        for k in 0..4 {
            whole.add_frame(k, &[mesh(k)]).unwrap();
        }
        let dir = std::env::temp_dir().join(format!("op-usd-cache-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("run.usda");
        std::fs::write(&file, encode(&whole)).unwrap();
        let mut resumed = UsdCache::new(&s, 24.0);
        resumed.resume(&file, 1).unwrap();
        assert_eq!(resumed.frames(), 2);
        for k in 2..4 {
            resumed.add_frame(k, &[mesh(k)]).unwrap();
        }
        assert!(encode(&resumed) == encode(&whole), "the same bytes");
        assert!(resumed.add_frame(7, &[mesh(7)]).is_err(), "out of order");
        let e = UsdCache::new(&s, 24.0).resume(&file, 9).unwrap_err();
        assert!(e.contains("before the checkpoint's frame 9"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
