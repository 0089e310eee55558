//! `opsim run --format obj,ply,vtu,usd`: binary PLY frame sequences
//! and VTU particle state parse back with the crates that wrote them, with
//! the counts of the OBJ frames and every per-particle attribute; every
//! sequence, in every format, has a series file listing exactly its frame
//! files with their times (ParaView time series of everything);
//! the USD cache reads back with openusd, with the counts of the PLY frames.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use op_test_support::{fresh_path, temp_dir};
use ply_rs_bw::ply::{DefaultElement, Property};
use vtkio::model::{Attribute, DataSet, IOBuffer, Piece};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn opsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_opsim"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("run opsim")
}

/// `(vertices, faces, lines)` of an OBJ frame file.
fn obj_counts(path: &Path) -> (usize, usize, usize) {
    let text = std::fs::read_to_string(path).unwrap();
    let count = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
    (count("v "), count("f "), count("l "))
}

fn ply(path: &Path) -> ply_rs_bw::ply::Ply<DefaultElement> {
    let mut f = std::fs::File::open(path).unwrap();
    ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut f)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn float(e: &DefaultElement, key: &str) -> f64 {
    match e[key] {
        Property::Float(v) => f64::from(v),
        ref p => panic!("{key}: {p:?}"),
    }
}

/// The f64 values of a VTU point array, and its component count.
fn array<'a>(attrs: &'a [Attribute], name: &str) -> (&'a IOBuffer, u32) {
    for a in attrs {
        if let Attribute::DataArray(d) = a {
            if d.name == name {
                return (&d.data, d.elem.num_comp());
            }
        }
    }
    panic!("no point array {name}");
}

fn floats(b: &IOBuffer) -> Vec<f64> {
    match b {
        IOBuffer::F64(v) => v.clone(),
        other => panic!("expected Float64, got {other:?}"),
    }
}

fn ints(b: &IOBuffer) -> Vec<i32> {
    match b {
        IOBuffer::I32(v) => v.clone(),
        other => panic!("expected Int32, got {other:?}"),
    }
}

#[test]
fn ply_and_vtu_frames_parse_back_with_counts_and_attributes() {
    let out = fresh_path("all");
    let o = opsim(&[
        "run",
        "scenes/hinge_spiral.ron",
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "3",
        "--format",
        "obj,ply,vtu",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["files"]["formats"],
        serde_json::json!(["obj", "ply", "vtu"])
    );
    assert_eq!(summary["files"]["axes"]["obj"], "y_up");
    assert_eq!(summary["files"]["axes"]["ply"], "z_up");
    let particles = summary["objects"][0]["particles"].as_u64().unwrap() as usize;
    for k in 0..3 {
        check_ply_frame(&out, k, particles);
        check_vtu_frame(&out, k, particles);
    }
    check_vtu_series(&out, &summary);
    let _ = std::fs::remove_dir_all(&out);
}

/// Frame `k` of the spiral as binary PLY: the OBJ frame's counts, in scene
/// coordinates (OBJ is y-up), unit normals, triangles.
fn check_ply_frame(out: &Path, k: usize, particles: usize) {
    let obj = out.join(format!("frames/spiral/spiral_{k:05}.obj"));
    let (v, f, l) = obj_counts(&obj);
    let path = out.join(format!("frames/spiral/spiral_{k:05}.ply"));
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    let p = ply(&path);
    assert_eq!(p.payload["vertex"].len(), v, "{}", path.display());
    assert_eq!(p.payload["face"].len(), f);
    // No segments (discs): no `edge` element.
    assert_eq!(p.payload.get("edge").map_or(0, Vec::len), l);
    assert_eq!(v, 7 * particles, "discs: 7 vertices per particle");
    let first_obj: Vec<f64> = std::fs::read_to_string(&obj)
        .unwrap()
        .lines()
        .find_map(|l| l.strip_prefix("v "))
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let e = &p.payload["vertex"][0];
    let scene = [float(e, "x"), float(e, "y"), float(e, "z")];
    let expected = [first_obj[0], -first_obj[2], first_obj[1]];
    for c in 0..3 {
        assert!(
            (scene[c] - expected[c]).abs() < 2e-6,
            "{scene:?} {expected:?}"
        );
    }
    let n = [float(e, "nx"), float(e, "ny"), float(e, "nz")];
    assert!(((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-5);
    match &p.payload["face"][0]["vertex_indices"] {
        Property::ListInt(t) => assert_eq!(t.len(), 3),
        other => panic!("{other:?}"),
    }
}

/// Frame `k` as VTU: every particle with its attributes.
fn check_vtu_frame(out: &Path, k: usize, particles: usize) {
    let path = out.join(format!("vtu/state_{k:05}.vtu"));
    let vtk = vtkio::Vtk::import(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid");
    };
    let Piece::Inline(piece) = &pieces[0] else {
        panic!("not inline");
    };
    assert_eq!(piece.num_points(), particles);
    assert_eq!(piece.cells.types.len(), particles);
    let attrs = &piece.data.point;
    for (name, comps) in [
        ("orientation", 4),
        ("normal", 3),
        ("velocity", 3),
        ("rest_curvature", 1),
        ("temperature", 1),
    ] {
        let (b, c) = array(attrs, name);
        assert_eq!(c, comps, "{name}");
        let v = floats(b);
        assert_eq!(v.len(), comps as usize * particles, "{name}");
        assert!(v.iter().all(|x| x.is_finite()), "{name}");
    }
    let q = floats(array(attrs, "orientation").0);
    for c in q.chunks(4) {
        let norm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-9, "{c:?}");
    }
    // The spiral's rest curvature runs from 0.25 to 0.7.
    let kappa = floats(array(attrs, "rest_curvature").0);
    assert!(
        kappa.iter().all(|&x| (0.2..=0.75).contains(&x)),
        "{kappa:?}"
    );
    // Standard(1) x6, the hinge (-1), Standard(2) x6 (seed 002 §5).
    let kinds = ints(array(attrs, "type").0);
    assert_eq!(kinds.iter().filter(|&&t| t == -1).count(), 1, "{kinds:?}");
    assert_eq!(kinds.iter().filter(|&&t| t == 1).count(), 6, "{kinds:?}");
    assert_eq!(kinds.iter().filter(|&&t| t == 2).count(), 6, "{kinds:?}");
    assert!(ints(array(attrs, "object").0).iter().all(|&o| o == 0));
    assert_eq!(ints(array(attrs, "id").0).len(), particles);
}

/// The VTU series file: the three frames with their times at the run's
/// frame rate.
fn check_vtu_series(out: &Path, summary: &serde_json::Value) {
    let series: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("vtu/state.vtu.series")).unwrap())
            .unwrap();
    let files = series["files"].as_array().unwrap();
    assert_eq!(files.len(), 3);
    let rate = summary["frame_rate"].as_f64().unwrap();
    for (k, f) in files.iter().enumerate() {
        assert_eq!(f["name"], format!("state_{k:05}.vtu"));
        assert!((f["time"].as_f64().unwrap() - k as f64 / rate).abs() < 1e-9);
    }
}

#[test]
fn vtu_alone_writes_no_mesh_frames_and_an_unknown_format_is_refused() {
    let out = fresh_path("vtu");
    let o = opsim(&[
        "run",
        "scenes/two_sheets.ron",
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "2",
        "--format",
        "vtu",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!out.join("frames").exists());
    let vtk = vtkio::Vtk::import(out.join("vtu/state_00001.vtu")).unwrap();
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid");
    };
    let Piece::Inline(piece) = &pieces[0] else {
        panic!("not inline");
    };
    assert_eq!(piece.num_points(), 288);
    let objects = ints(array(&piece.data.point, "object").0);
    assert_eq!(objects.iter().filter(|&&o| o == 1).count(), 144);
    let o = opsim(&[
        "run",
        "scenes/two_sheets.ron",
        "--out",
        out.to_str().unwrap(),
        "--format",
        "obj,stl",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("stl") && err.contains("the formats are obj, ply, vtu"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// The frame files of `stem` in `folder`: `<stem>_<digits>.<ext>`, sorted.
fn frame_files_of(folder: &Path, stem: &str, ext: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| {
            n.strip_prefix(stem)
                .and_then(|r| r.strip_prefix('_'))
                .and_then(|r| r.strip_suffix(ext))
                .and_then(|r| r.strip_suffix('.'))
                .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        })
        .collect();
    names.sort();
    names
}

/// The files a series file lists, with their times, checked to increase.
fn series_listing(path: &Path) -> Vec<(String, f64)> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let series: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(series["file-series-version"], "1.0");
    let files: Vec<(String, f64)> = series["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["name"].as_str().unwrap().to_string(),
                f["time"].as_f64().unwrap(),
            )
        })
        .collect();
    assert!(
        files.windows(2).all(|w| w[0].1 < w[1].1),
        "{}: times increase: {files:?}",
        path.display()
    );
    files
}

/// A skinned scene with tools, its triangulation written too, run with
/// `--format vtu,ply`: every sequence has a series file per format that
/// writes it (`frames/<stem>/<stem>.ply.series`; `vtu/<stem>.vtu.series`
/// for the skin, surface and tools, whose VTU files hold triangles and
/// normals) listing exactly the frame files on disk at increasing times,
/// and `summary.json` lists the series files. A rerun with another format
/// replaces them.
#[test]
fn every_sequence_has_a_series_file_listing_its_frame_files() {
    let dir = temp_dir("series");
    let scene = dir.join("skinned_cut_surface.ron");
    let text = std::fs::read_to_string(repo().join("tests/data/skinned_cut.ron")).unwrap();
    let text = text.replace(
        "outputs: (particles: Discs)",
        "outputs: (particles: Discs, triangulation: true)",
    );
    assert!(text.contains("triangulation: true"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("run");
    let run = |formats: &str, frames: &str| {
        let o = opsim(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--frames",
            frames,
            "--format",
            formats,
            "--allow-breakup",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_str::<serde_json::Value>(
            &std::fs::read_to_string(out.join("summary.json")).unwrap(),
        )
        .unwrap()
    };
    let summary = run("vtu,ply", "3");
    let rate = summary["frame_rate"].as_f64().unwrap();
    let sequences = summary["files"]["sequences"].as_array().unwrap();
    let kinds: Vec<&str> = sequences
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    for kind in ["particles", "skin", "surface", "tool"] {
        assert!(kinds.contains(&kind), "a {kind} sequence: {kinds:?}");
    }
    let mut expected = Vec::new();
    for s in sequences {
        let stem = s["stem"].as_str().unwrap();
        expected.push(format!("frames/{stem}/{stem}.ply.series"));
        if s["kind"] != "particles" {
            expected.push(format!("vtu/{stem}.vtu.series"));
        }
    }
    expected.push("vtu/state.vtu.series".into());
    let listed: Vec<String> = summary["files"]["series"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect();
    assert_eq!(listed, expected);

    for rel in &listed {
        let path = out.join(rel);
        let folder = path.parent().unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let (stem, ext) = name
            .strip_suffix(".series")
            .and_then(|n| n.rsplit_once('.'))
            .unwrap();
        let files = series_listing(&path);
        let names: Vec<String> = files.iter().map(|f| f.0.clone()).collect();
        assert_eq!(names, frame_files_of(folder, stem, ext), "{rel}");
        assert_eq!(files.len(), 3, "{rel}");
        for (k, (_, t)) in files.iter().enumerate() {
            assert!((t - k as f64 / rate).abs() < 1e-9, "{rel}: {t}");
        }
        if ext == "vtu" && stem != "state" {
            for f in &names {
                check_vtu_mesh(&folder.join(f));
            }
        }
    }

    // A rerun with PLY alone replaces every file of the first run.
    let summary = run("ply", "2");
    let vtu_left: Vec<_> = std::fs::read_dir(out.join("vtu"))
        .map(|d| d.map(|e| e.unwrap().file_name()).collect())
        .unwrap_or_default();
    assert!(vtu_left.is_empty(), "{vtu_left:?}");
    for rel in summary["files"]["series"].as_array().unwrap() {
        let path = out.join(rel.as_str().unwrap());
        assert_eq!(series_listing(&path).len(), 2, "{}", path.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A skin, surface or tool frame in VTU: triangles over its points, a unit
/// normal per point.
fn check_vtu_mesh(path: &Path) {
    let vtk = vtkio::Vtk::import(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid");
    };
    let Piece::Inline(piece) = &pieces[0] else {
        panic!("not inline");
    };
    let n = piece.num_points();
    assert!(n > 0, "{}: no points", path.display());
    assert!(
        piece
            .cells
            .types
            .iter()
            .all(|t| *t == vtkio::model::CellType::Triangle),
        "{}",
        path.display()
    );
    assert!(!piece.cells.types.is_empty(), "{}", path.display());
    let (normals, comps) = array(&piece.data.point, "normal");
    assert_eq!(comps, 3);
    let normals = floats(normals);
    assert_eq!(normals.len(), 3 * n);
    for c in normals.chunks(3) {
        let norm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-6, "{}: {c:?}", path.display());
    }
}

/// The time samples of a USD attribute: time code and value.
fn samples(
    layer: &dyn openusd::sdf::AbstractData,
    attribute: &str,
) -> Vec<(f64, openusd::sdf::Value)> {
    let path = openusd::sdf::path(attribute).unwrap();
    match layer.get_field(&path, "timeSamples") {
        Ok(v) => match v.into_owned() {
            openusd::sdf::Value::TimeSamples(s) => s,
            other => panic!("{attribute}: {other:?}"),
        },
        Err(e) => panic!("{attribute}: {e}"),
    }
}

/// The length of an array value.
fn array_len(v: &openusd::sdf::Value) -> usize {
    use openusd::sdf::Value;
    match v {
        Value::Vec3fVec(a) => a.len(),
        Value::IntVec(a) => a.len(),
        Value::FloatVec(a) => a.len(),
        Value::QuatfVec(a) => a.len(),
        other => panic!("not an array: {other:?}"),
    }
}

/// `--format ply,usd` on the skinned spiral hit by a ball: one USD file
/// whose prims (one per sequence, under the default prim `/Run`) hold one
/// time sample per frame, with the vertex and face counts of the PLY frames
/// of the same run and one point per particle; the stage says z-up, one
/// metre per unit and the frame rate; `summary.json` names the file and
/// its prims.
#[test]
fn usd_cache_holds_every_sequence_with_the_counts_of_the_ply_frames() {
    use openusd::sdf::{path, AbstractData as _, Value};
    let out = fresh_path("usd");
    let frames = 4;
    let o = opsim(&[
        "run",
        "scenes/ball_vs_spiral.ron",
        "--out",
        out.to_str().unwrap(),
        "--frames",
        &frames.to_string(),
        "--format",
        "ply,usd",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["files"]["formats"],
        serde_json::json!(["ply", "usd"])
    );
    assert_eq!(summary["files"]["axes"]["usda"], "z_up");
    let usd = &summary["files"]["usd"];
    assert_eq!(usd["file"], "usd/run.usda");
    assert_eq!(usd["default_prim"], "/Run");
    let sequences = summary["files"]["sequences"].as_array().unwrap();
    let prims = usd["prims"].as_array().unwrap();
    assert_eq!(prims.len(), sequences.len());
    let kinds: Vec<&str> = prims.iter().map(|p| p["kind"].as_str().unwrap()).collect();
    assert!(
        kinds.contains(&"particles") && kinds.contains(&"skin"),
        "{kinds:?}"
    );
    let bytes = std::fs::read(out.join("usd/run.usda")).unwrap();
    assert!(bytes.starts_with(b"#usda 1.0"), "a USD text layer");
    let layer = openusd::usda::read_file(out.join("usd/run.usda")).unwrap();
    let root = path("/").unwrap();
    let field = |p: &openusd::sdf::Path, f: &str| layer.get_field(p, f).unwrap().into_owned();
    assert_eq!(field(&root, "upAxis"), Value::Token("Z".into()));
    assert_eq!(field(&root, "metersPerUnit"), Value::Double(1.0));
    let rate = summary["frame_rate"].as_f64().unwrap();
    assert_eq!(field(&root, "timeCodesPerSecond"), Value::Double(rate));
    assert_eq!(field(&root, "framesPerSecond"), Value::Double(rate));
    assert_eq!(field(&root, "startTimeCode"), Value::Double(0.0));
    assert_eq!(
        field(&root, "endTimeCode"),
        Value::Double((frames - 1) as f64)
    );
    assert_eq!(field(&root, "defaultPrim"), Value::Token("Run".into()));
    let Value::TokenVec(children) = field(&path("/Run").unwrap(), "primChildren") else {
        panic!("/Run has children");
    };
    assert_eq!(children.len(), sequences.len());
    for (seq, prim) in sequences.iter().zip(prims) {
        let (stem, kind) = (seq["stem"].as_str().unwrap(), seq["kind"].as_str().unwrap());
        let at = prim["path"].as_str().unwrap();
        assert_eq!(prim["name"], seq["name"]);
        let ty = field(&path(at).unwrap(), "typeName");
        let points = samples(&layer, &format!("{at}.points"));
        assert_eq!(points.len(), frames, "{at}: one sample per frame");
        for (k, (t, v)) in points.iter().enumerate() {
            assert_eq!(*t, k as f64);
            let n = array_len(v);
            let normals = &samples(&layer, &format!("{at}.normals"))[k].1;
            assert_eq!(array_len(normals), n, "{at} frame {k}");
            if kind == "particles" {
                assert_eq!(ty, Value::Token("Points".into()));
                let object = summary["objects"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .find(|o| o["name"] == seq["name"])
                    .unwrap();
                assert_eq!(n as u64, object["particles"].as_u64().unwrap(), "{at}");
                for attr in ["widths", "primvars:orientations"] {
                    let s = &samples(&layer, &format!("{at}.{attr}"))[k].1;
                    assert_eq!(array_len(s), n, "{at}.{attr} frame {k}");
                }
            } else {
                assert_eq!(ty, Value::Token("Mesh".into()));
                let p = ply(&out.join(format!("frames/{stem}/{stem}_{k:05}.ply")));
                assert_eq!(n, p.payload["vertex"].len(), "{at} frame {k}");
                let counts = &samples(&layer, &format!("{at}.faceVertexCounts"))[k].1;
                let indices = &samples(&layer, &format!("{at}.faceVertexIndices"))[k].1;
                assert_eq!(array_len(counts), p.payload["face"].len(), "{at} frame {k}");
                assert_eq!(array_len(indices), 3 * array_len(counts));
                if kind == "skin" {
                    assert!(array_len(counts) > 0, "{at} frame {k}: a skin has faces");
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}
