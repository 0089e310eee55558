//! A small, forgiving-but-strict Wavefront OBJ reader.
//!
//! Reads what our frames and common tools write: `o`/`g` names, `v x y z`, `vn`,
//! `vt` (counted, otherwise ignored), `f` with `v`, `v/vt`, `v//vn` and `v/vt/vn`
//! references (polygons fan-triangulated, negative indices relative to the end),
//! `l` polylines and `p` points. Other statements (`s`, `usemtl`, `mtllib`, ...)
//! are ignored. A malformed line gives [`RenderError::Parse`] naming the file,
//! the line and what is wrong (a long offending token is cut to 80 characters,
//! ending with `...`); nothing panics. Only regular files (symlinks followed) of
//! at most [`MAX_OBJ_FILE_BYTES`] are read; a leading UTF-8 byte-order mark is
//! skipped.
//!
//! Vertex normals: a vertex takes the normal that an element references with it
//! (`f 1//4 ...`, the first such reference wins). A vertex that no element gives
//! a normal takes the object's `vn` of the same rank when the object declares as
//! many `vn` as `v` lines: this is how particles (vertices with no faces) carry
//! their orientation in our frames.

use std::collections::HashMap;
use std::path::Path;

use super::error::RenderError;
use op_scene::input::{excerpt, read_regular_file, InputFileError};

/// Largest OBJ file read (1 GiB); a larger one, or one that is not a
/// regular file, is a [`RenderError::Input`] naming it.
pub const MAX_OBJ_FILE_BYTES: u64 = 1 << 30;

/// One object (`o` or `g` block) of an OBJ file, with indices local to it.
///
/// Invariant: `normals().len() == vertices().len()` and every index of
/// `triangles()`, `lines()` and `points()` is below `vertices().len()`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjObject {
    name: String,
    vertices: Vec<[f64; 3]>,
    normals: Vec<Option<[f64; 3]>>,
    triangles: Vec<[usize; 3]>,
    lines: Vec<[usize; 2]>,
    points: Vec<usize>,
}

impl ObjObject {
    /// An empty object called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        ObjObject {
            name: name.into(),
            ..ObjObject::default()
        }
    }

    /// The object's name (empty when the file named none).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }

    /// Unit normal of each vertex, `None` where the file gave none.
    pub fn normals(&self) -> &[Option<[f64; 3]>] {
        &self.normals
    }

    /// Triangles (faces fan-triangulated), as vertex indices.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Line segments (`l` polylines split into segments), as vertex indices.
    pub fn lines(&self) -> &[[usize; 2]] {
        &self.lines
    }

    /// Point elements (`p`), as vertex indices.
    pub fn points(&self) -> &[usize] {
        &self.points
    }

    /// Whether the object has triangles.
    pub fn has_faces(&self) -> bool {
        !self.triangles.is_empty()
    }

    /// Appends a vertex and returns its index. The normal is normalized; a zero
    /// or non-finite normal is stored as `None`.
    ///
    /// # Errors
    /// [`RenderError::InvalidData`] if the position is not finite.
    pub fn push_vertex(
        &mut self,
        position: [f64; 3],
        normal: Option<[f64; 3]>,
    ) -> Result<usize, RenderError> {
        if !position.iter().all(|c| c.is_finite()) {
            return Err(self.invalid(format!("non-finite vertex position {position:?}")));
        }
        self.vertices.push(position);
        self.normals.push(normal.and_then(unit));
        Ok(self.vertices.len() - 1)
    }

    /// Appends a triangle of existing vertices.
    ///
    /// # Errors
    /// [`RenderError::InvalidData`] if an index is not below the vertex count.
    pub fn push_triangle(&mut self, triangle: [usize; 3]) -> Result<(), RenderError> {
        self.check(&triangle)?;
        self.triangles.push(triangle);
        Ok(())
    }

    /// Appends a line segment between existing vertices.
    ///
    /// # Errors
    /// [`RenderError::InvalidData`] if an index is not below the vertex count.
    pub fn push_line(&mut self, line: [usize; 2]) -> Result<(), RenderError> {
        self.check(&line)?;
        self.lines.push(line);
        Ok(())
    }

    /// Appends a point element on an existing vertex.
    ///
    /// # Errors
    /// [`RenderError::InvalidData`] if the index is not below the vertex count.
    pub fn push_point(&mut self, vertex: usize) -> Result<(), RenderError> {
        self.check(&[vertex])?;
        self.points.push(vertex);
        Ok(())
    }

    fn check(&self, indices: &[usize]) -> Result<(), RenderError> {
        match indices.iter().find(|&&i| i >= self.vertices.len()) {
            Some(i) => Err(self.invalid(format!(
                "vertex index {i} out of range ({} vertices, indices start at 0)",
                self.vertices.len()
            ))),
            None => Ok(()),
        }
    }

    fn invalid(&self, message: String) -> RenderError {
        RenderError::InvalidData {
            object: self.name.clone(),
            message,
        }
    }
}

/// The contents of one OBJ file: its objects in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjData {
    objects: Vec<ObjObject>,
}

impl ObjData {
    /// Data made of `objects`.
    pub fn from_objects(objects: Vec<ObjObject>) -> Self {
        ObjData { objects }
    }

    /// The objects, in file order.
    pub fn objects(&self) -> &[ObjObject] {
        &self.objects
    }

    /// Appends an object.
    pub fn push_object(&mut self, object: ObjObject) {
        self.objects.push(object);
    }

    /// Total number of vertices over all objects.
    pub fn vertex_count(&self) -> usize {
        self.objects.iter().map(|o| o.vertices.len()).sum()
    }

    /// Total number of triangles over all objects.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.triangles.len()).sum()
    }

    /// Axis-aligned bounds `(min, max)` of all vertices, `None` when there are none.
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let mut it = self.objects.iter().flat_map(|o| o.vertices.iter());
        let first = *it.next()?;
        Some(it.fold((first, first), |(mut lo, mut hi), v| {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
            (lo, hi)
        }))
    }

    /// Reads and parses the OBJ file at `path`.
    ///
    /// # Errors
    /// [`RenderError::Io`] if the file cannot be read, [`RenderError::Input`] if
    /// it is not a regular file (after following symlinks) or is larger than
    /// [`MAX_OBJ_FILE_BYTES`], [`RenderError::Parse`] for a malformed line.
    pub fn read(path: &Path) -> Result<Self, RenderError> {
        let bytes = read_regular_file(path, MAX_OBJ_FILE_BYTES).map_err(|e| match e {
            InputFileError::Io(source) => RenderError::io(path, source),
            e => RenderError::Input {
                path: path.to_path_buf(),
                message: e.message(MAX_OBJ_FILE_BYTES),
            },
        })?;
        Self::parse(
            &String::from_utf8_lossy(&bytes),
            &path.display().to_string(),
        )
    }

    /// Parses OBJ text; `source` names it in error messages (usually the file path).
    ///
    /// # Errors
    /// [`RenderError::Parse`] naming the line and what is wrong.
    pub fn parse(text: &str, source: &str) -> Result<Self, RenderError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut parser = Parser {
            source,
            line: 0,
            positions: Vec::new(),
            normals: Vec::new(),
            tex_count: 0,
            objects: Vec::new(),
        };
        let mut pending = String::new();
        let mut start_line = 0;
        for (i, raw) in text.lines().enumerate() {
            let content = raw.split('#').next().unwrap_or("");
            if pending.is_empty() {
                start_line = i + 1;
            }
            if let Some(stripped) = content.trim_end().strip_suffix('\\') {
                pending.push_str(stripped);
                pending.push(' ');
                continue;
            }
            pending.push_str(content);
            parser.line = start_line;
            parser.statement(&pending)?;
            pending.clear();
        }
        if !pending.is_empty() {
            parser.line = start_line;
            parser.statement(&pending)?;
        }
        Ok(parser.finish())
    }
}

/// Normalizes `n`, `None` if it is zero or not finite.
fn unit(n: [f64; 3]) -> Option<[f64; 3]> {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    (len.is_finite() && len > 1e-300).then(|| [n[0] / len, n[1] / len, n[2] / len])
}

/// A reference from an element: global vertex index and optional global normal index.
type Ref = (usize, Option<usize>);

/// An object while its file is being read; indices are global (0-based).
#[derive(Default)]
struct Pending {
    name: String,
    declared: Vec<usize>,
    declared_normals: Vec<usize>,
    triangles: Vec<[Ref; 3]>,
    lines: Vec<[Ref; 2]>,
    points: Vec<Ref>,
}

impl Pending {
    fn has_elements(&self) -> bool {
        !(self.triangles.is_empty() && self.lines.is_empty() && self.points.is_empty())
    }
}

struct Parser<'a> {
    source: &'a str,
    line: usize,
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    tex_count: usize,
    objects: Vec<Pending>,
}

impl Parser<'_> {
    fn error(&self, message: impl Into<String>) -> RenderError {
        RenderError::Parse {
            file: self.source.to_string(),
            line: self.line,
            message: message.into(),
        }
    }

    fn current(&mut self) -> &mut Pending {
        if self.objects.is_empty() {
            self.objects.push(Pending::default());
        }
        let last = self.objects.len() - 1;
        &mut self.objects[last]
    }

    fn statement(&mut self, text: &str) -> Result<(), RenderError> {
        let mut tokens = text.split_whitespace();
        let Some(keyword) = tokens.next() else {
            return Ok(());
        };
        let args: Vec<&str> = tokens.collect();
        match keyword {
            "v" => {
                let p = self.numbers(keyword, &args)?;
                let id = self.positions.len();
                self.positions.push(p);
                self.current().declared.push(id);
            }
            "vn" => {
                let n = self.numbers(keyword, &args)?;
                let id = self.normals.len();
                self.normals.push(n);
                self.current().declared_normals.push(id);
            }
            "vt" => self.tex_count += 1,
            "o" | "g" => self.start_object(keyword, args.join(" ")),
            "f" => {
                if args.len() < 3 {
                    return Err(self.error(format!(
                        "a face needs at least 3 vertices, found {}",
                        args.len()
                    )));
                }
                let refs = self.refs(&args)?;
                let tris: Vec<[Ref; 3]> = (1..refs.len() - 1)
                    .map(|k| [refs[0], refs[k], refs[k + 1]])
                    .collect();
                self.current().triangles.extend(tris);
            }
            "l" => {
                if args.len() < 2 {
                    return Err(self.error(format!(
                        "a line needs at least 2 vertices, found {}",
                        args.len()
                    )));
                }
                let refs = self.refs(&args)?;
                let segs: Vec<[Ref; 2]> = refs.windows(2).map(|w| [w[0], w[1]]).collect();
                self.current().lines.extend(segs);
            }
            "p" => {
                if args.is_empty() {
                    return Err(self.error("a point element needs at least 1 vertex"));
                }
                let refs = self.refs(&args)?;
                self.current().points.extend(refs);
            }
            _ => {}
        }
        Ok(())
    }

    fn start_object(&mut self, keyword: &str, name: String) {
        let reuse = match self.objects.last_mut() {
            // `g` inside an `o` block that has no elements yet names a material
            // group of the same object: keep one object.
            Some(cur) if keyword == "g" && !cur.has_elements() => {
                if cur.name.is_empty() {
                    cur.name = name.clone();
                }
                true
            }
            Some(cur) if cur.declared.is_empty() && !cur.has_elements() => {
                cur.name = name.clone();
                true
            }
            _ => false,
        };
        if !reuse {
            self.objects.push(Pending {
                name,
                ..Pending::default()
            });
        }
    }

    /// Three finite numbers (extra ones, like `w` or vertex colours, are ignored).
    fn numbers(&self, keyword: &str, args: &[&str]) -> Result<[f64; 3], RenderError> {
        if args.len() < 3 {
            return Err(self.error(format!("'{keyword}' needs 3 numbers, found {}", args.len())));
        }
        let mut out = [0.0; 3];
        for (k, token) in args.iter().enumerate() {
            let x: f64 = token.parse().map_err(|_| {
                self.error(format!("'{keyword}': '{}' is not a number", excerpt(token)))
            })?;
            if !x.is_finite() {
                return Err(self.error(format!("'{keyword}': '{}' is not finite", excerpt(token))));
            }
            if k < 3 {
                out[k] = x;
            }
        }
        Ok(out)
    }

    fn refs(&self, args: &[&str]) -> Result<Vec<Ref>, RenderError> {
        args.iter().map(|token| self.reference(token)).collect()
    }

    /// One `v`, `v/vt`, `v//vn` or `v/vt/vn` reference.
    fn reference(&self, token: &str) -> Result<Ref, RenderError> {
        let parts: Vec<&str> = token.split('/').collect();
        if parts.len() > 3 {
            return Err(self.error(format!("bad vertex reference '{}'", excerpt(token))));
        }
        let v = self.index(parts[0], self.positions.len(), "vertex", token)?;
        if let Some(t) = parts.get(1).filter(|t| !t.is_empty()) {
            self.index(t, self.tex_count, "texture", token)?;
        }
        let n = match parts.get(2).filter(|t| !t.is_empty()) {
            Some(t) => Some(self.index(t, self.normals.len(), "normal", token)?),
            None => None,
        };
        Ok((v, n))
    }

    /// Resolves a 1-based or negative OBJ index against `count` items defined so far.
    fn index(
        &self,
        text: &str,
        count: usize,
        what: &str,
        token: &str,
    ) -> Result<usize, RenderError> {
        let k: i64 = text.parse().map_err(|_| {
            self.error(format!(
                "bad {what} index '{}' in '{}'",
                excerpt(text),
                excerpt(token)
            ))
        })?;
        let resolved = if k > 0 {
            usize::try_from(k - 1).ok().filter(|&i| i < count)
        } else if k < 0 {
            usize::try_from(k.unsigned_abs())
                .ok()
                .and_then(|back| count.checked_sub(back))
        } else {
            return Err(self.error(format!(
                "{what} index 0 in '{}' (OBJ indices start at 1)",
                excerpt(token)
            )));
        };
        resolved.ok_or_else(|| {
            self.error(format!(
                "{what} index {k} in '{}' out of range ({count} defined so far)",
                excerpt(token)
            ))
        })
    }

    fn finish(self) -> ObjData {
        let mut objects = Vec::new();
        for p in &self.objects {
            if p.declared.is_empty() && !p.has_elements() {
                continue;
            }
            objects.push(self.build(p));
        }
        ObjData { objects }
    }

    fn build(&self, p: &Pending) -> ObjObject {
        let mut local: HashMap<usize, usize> = HashMap::new();
        let mut obj = ObjObject::new(p.name.clone());
        for &g in &p.declared {
            local.insert(g, obj.vertices.len());
            obj.vertices.push(self.positions[g]);
            obj.normals.push(None);
        }
        let mut map = |obj: &mut ObjObject, (g, n): Ref| -> usize {
            let i = *local.entry(g).or_insert_with(|| {
                obj.vertices.push(self.positions[g]);
                obj.normals.push(None);
                obj.vertices.len() - 1
            });
            if obj.normals[i].is_none() {
                obj.normals[i] = n.and_then(|n| unit(self.normals[n]));
            }
            i
        };
        for t in &p.triangles {
            let tri = [
                map(&mut obj, t[0]),
                map(&mut obj, t[1]),
                map(&mut obj, t[2]),
            ];
            obj.triangles.push(tri);
        }
        for l in &p.lines {
            let seg = [map(&mut obj, l[0]), map(&mut obj, l[1])];
            obj.lines.push(seg);
        }
        for &r in &p.points {
            let i = map(&mut obj, r);
            obj.points.push(i);
        }
        if p.declared_normals.len() == p.declared.len() {
            for (i, &n) in p.declared_normals.iter().enumerate() {
                if obj.normals[i].is_none() {
                    obj.normals[i] = unit(self.normals[n]);
                }
            }
        }
        obj
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL_FORMS: &str = "\
# comment line
mtllib scene.mtl
o particles
v 0 0 0
v 1 0 0
v 0 1 0
vn 0 0 1
vn 0 0 2   # not unit: normalized
vn 0 0 0
o mesh
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vn 0 1 0
s off
f 4//1 5//1 6//1
f 4/1/1 6/1/1 7/1/1
f -4 -3 -2 -1
l 4 5 6
p 7
";

    #[test]
    fn parses_all_forms() {
        let d = ObjData::parse(ALL_FORMS, "all.obj").unwrap();
        assert_eq!(d.objects().len(), 2);
        let p = &d.objects()[0];
        assert_eq!(p.name(), "particles");
        assert_eq!(p.vertices().len(), 3);
        assert!(!p.has_faces());
        // Paired by rank: no element references these normals.
        assert_eq!(p.normals()[1], Some([0.0, 0.0, 1.0]));
        assert_eq!(p.normals()[2], None, "zero normal becomes None");
        let m = &d.objects()[1];
        assert_eq!(m.name(), "mesh");
        assert_eq!(m.vertices().len(), 4);
        // 1 + 1 + quad fan-triangulated into 2.
        assert_eq!(m.triangles().len(), 4);
        assert_eq!(m.triangles()[0], [0, 1, 2]);
        assert_eq!(m.triangles()[2], [0, 1, 2], "negative indices");
        assert_eq!(m.triangles()[3], [0, 2, 3]);
        assert_eq!(m.lines(), &[[0, 1], [1, 2]]);
        assert_eq!(m.points(), &[3]);
        assert_eq!(m.normals()[0], Some([0.0, 0.0, 1.0]));
        assert_eq!(m.normals()[3], Some([0.0, 0.0, 1.0]));
        assert_eq!(d.vertex_count(), 7);
        assert_eq!(d.triangle_count(), 4);
        let (lo, hi) = d.bounds().unwrap();
        assert_eq!((lo, hi), ([0.0; 3], [1.0; 3]));
    }

    #[test]
    fn faces_may_use_vertices_of_earlier_objects() {
        let d = ObjData::parse("v 0 0 0\nv 1 0 0\nv 0 1 0\no tri\nf 1 2 3\n", "x").unwrap();
        assert_eq!(d.objects().len(), 2);
        assert_eq!(d.objects()[1].vertices().len(), 3);
        assert_eq!(d.objects()[1].triangles(), &[[0, 1, 2]]);
    }

    #[test]
    fn group_inside_object_keeps_one_object() {
        let text = "o cube\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng cube_mat\nf 1 2 3\n";
        let d = ObjData::parse(text, "x").unwrap();
        assert_eq!(d.objects().len(), 1);
        assert_eq!(d.objects()[0].name(), "cube");
    }

    #[test]
    fn line_continuation() {
        let d = ObjData::parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3\n", "x").unwrap();
        assert_eq!(d.objects()[0].triangles().len(), 1);
    }

    fn parse_error(text: &str) -> (usize, String) {
        match ObjData::parse(text, "bad.obj") {
            Err(RenderError::Parse {
                file,
                line,
                message,
            }) => {
                assert_eq!(file, "bad.obj");
                (line, message)
            }
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn bad_lines_name_the_line() {
        let (line, msg) = parse_error("v 0 0 0\nv 1 zero 0\n");
        assert_eq!(line, 2);
        assert!(msg.contains("'zero' is not a number"), "{msg}");
        let (line, msg) = parse_error("o a\n\nv 0 0\n");
        assert_eq!(line, 3);
        assert!(msg.contains("needs 3 numbers"), "{msg}");
        let (line, msg) = parse_error("v 0 0 0\nv 1 0 0\nf 1 2\n");
        assert_eq!(line, 3);
        assert!(msg.contains("at least 3"), "{msg}");
        let (_, msg) = parse_error("v nan 0 0\n");
        assert!(msg.contains("not finite"), "{msg}");
        let (_, msg) = parse_error("v 0 0 0\np 1/x\n");
        assert!(msg.contains("bad texture index"), "{msg}");
        let (_, msg) = parse_error("v 0 0 0\np 1/2/3/4\n");
        assert!(msg.contains("bad vertex reference"), "{msg}");
    }

    #[test]
    fn out_of_range_indices() {
        let (line, msg) = parse_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
        assert_eq!(line, 4);
        assert!(msg.contains("vertex index 4"), "{msg}");
        assert!(msg.contains("(3 defined so far)"), "{msg}");
        let (_, msg) = parse_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n");
        assert!(msg.contains("index -4"), "{msg}");
        let (_, msg) = parse_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
        assert!(msg.contains("start at 1"), "{msg}");
        let (_, msg) = parse_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2 3\n");
        assert!(msg.contains("normal index 1"), "{msg}");
        let (_, msg) = parse_error("v 0 0 0\np 99999999999999999999999\n");
        assert!(msg.contains("bad vertex index"), "{msg}");
    }

    #[test]
    fn builder_checks_indices() {
        let mut o = ObjObject::new("b");
        o.push_vertex([0.0; 3], Some([0.0, 2.0, 0.0])).unwrap();
        assert_eq!(o.normals()[0], Some([0.0, 1.0, 0.0]));
        assert!(o.push_triangle([0, 0, 1]).is_err());
        assert!(o.push_line([0, 3]).is_err());
        assert!(o.push_point(0).is_ok());
        assert!(o.push_vertex([f64::NAN, 0.0, 0.0], None).is_err());
    }

    /// A long bad token is quoted cut to 80 characters (it was echoed
    /// whole), with the line number.
    #[test]
    fn long_bad_tokens_are_elided() {
        let long = "9".repeat(50_000) + "x";
        for text in [
            format!("v 0 0 0\nv 1 {long} 0\n"),
            format!("v 0 0 0\nf 1 1 {long}\n"),
            format!("v 0 0 0\np 1/{long}/2/3\n"),
        ] {
            let (line, msg) = parse_error(&text);
            assert_eq!(line, 2);
            assert!(msg.contains("...") && msg.len() < 250, "{msg}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let d = ObjData::parse("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "x").unwrap();
        assert_eq!(d.triangle_count(), 1);
    }

    /// A symlink to /dev/zero was read until memory ran out; it is refused
    /// before it is opened, naming the file.
    #[cfg(unix)]
    #[test]
    fn only_regular_files_are_read() {
        let dir = std::env::temp_dir().join(format!("op-render-obj-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let zero = dir.join("zero.obj");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let e = ObjData::read(&zero).unwrap_err();
        assert!(matches!(e, RenderError::Input { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(
            msg.contains("zero.obj") && msg.contains("not a regular file"),
            "{msg}"
        );
        let e = ObjData::read(&dir).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
