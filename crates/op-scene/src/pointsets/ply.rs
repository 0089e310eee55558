//! PLY point sets (`ascii 1.0`, `binary_little_endian 1.0`): the header,
//! the rows of the `vertex` element, its positions and normals.

use op_dynamics::{Point3, Real, Vec3};

use super::{format_err, number, unit, PointSet, PointSetError};
use crate::input::{excerpt, strip_bom};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The little-endian value at the start of `b` (`b.len() >= size`).
    fn read_le(self, b: &[u8]) -> Real {
        match self {
            Scalar::I8 => b[0] as i8 as Real,
            Scalar::U8 => b[0] as Real,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as Real,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as Real,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as Real,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as Real,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as Real,
            Scalar::F64 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

/// A PLY property: a scalar, or a list (count type, item type).
#[derive(Clone, Debug)]
struct Property {
    name: String,
    scalar: Scalar,
    list: Option<Scalar>,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Parses a `.ply` file, `ascii 1.0` or `binary_little_endian 1.0`: the
/// `vertex` element's `x y z` (any numeric type) are the points, `nx ny nz`
/// their normals when all three are present. Other elements (faces, ...)
/// are skipped.
pub fn parse_ply(bytes: &[u8], file: &str) -> Result<PointSet, PointSetError> {
    parse_ply_at_most(bytes, file, usize::MAX)
}

/// [`parse_ply`], refusing from the header a file of more than
/// `max_points` vertices, before any of its data is read.
pub fn parse_ply_at_most(
    bytes: &[u8],
    file: &str,
    max_points: usize,
) -> Result<PointSet, PointSetError> {
    let bytes = strip_bom(bytes);
    let header = PlyHeader::parse(bytes, file)?;
    let Some(vertex_index) = header.elements.iter().position(|e| e.name == "vertex") else {
        return Err(format_err(file, None, "no `vertex` element"));
    };
    let vertex = &header.elements[vertex_index];
    if vertex.count > max_points {
        return Err(format_err(
            file,
            None,
            format!(
                "its header declares {} points, more than the {max_points} allowed",
                vertex.count
            ),
        ));
    }
    let find = |n: &str| {
        vertex
            .properties
            .iter()
            .position(|p| p.name == n && p.list.is_none())
    };
    let (Some(ix), Some(iy), Some(iz)) = (find("x"), find("y"), find("z")) else {
        return Err(format_err(
            file,
            None,
            "the `vertex` element needs scalar properties x, y and z",
        ));
    };
    let normal_ix = match (find("nx"), find("ny"), find("nz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let data = &bytes[header.data_start..];
    let rows = if header.binary {
        binary_rows(data, &header.elements, vertex_index, file)?
    } else {
        ascii_rows(data, &header, vertex_index, file)?
    };
    // Map property positions to row positions (lists are not in rows).
    let scalar_pos = |i: usize| {
        vertex.properties[..i]
            .iter()
            .filter(|p| p.list.is_none())
            .count()
    };
    let columns = VertexColumns {
        position: [scalar_pos(ix), scalar_pos(iy), scalar_pos(iz)],
        normal: normal_ix.map(|n| n.map(scalar_pos)),
    };
    columns.points(&rows, file)
}

/// A PLY header: the data format, the elements and where the data start.
struct PlyHeader {
    binary: bool,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// Lines read (the header's), for the line numbers of ascii data.
    lines: usize,
}

impl PlyHeader {
    /// Reads the header: text lines up to `end_header`.
    fn parse(bytes: &[u8], file: &str) -> Result<PlyHeader, PointSetError> {
        let mut pos = 0;
        let mut line_no = 0;
        let mut format = None;
        let mut elements: Vec<Element> = Vec::new();
        loop {
            let Some(end) = bytes[pos..].iter().position(|&b| b == b'\n') else {
                return Err(format_err(
                    file,
                    None,
                    "the header has no `end_header` line",
                ));
            };
            line_no += 1;
            let raw = String::from_utf8_lossy(&bytes[pos..pos + end]);
            pos += end + 1;
            let fields: Vec<&str> = raw.split_whitespace().collect();
            let err = |m: String| format_err(file, Some(line_no), m);
            if line_no == 1 {
                if fields != ["ply"] {
                    return Err(err("the first line must be `ply`".into()));
                }
                continue;
            }
            match fields.first().copied() {
                None | Some("comment") | Some("obj_info") => {}
                Some("format") => {
                    format = match fields.get(1).copied() {
                        Some("ascii") => Some(false),
                        Some("binary_little_endian") => Some(true),
                        other => {
                            return Err(err(format!(
                                "format {} is not supported: use ascii or binary_little_endian",
                                excerpt(other.unwrap_or("(missing)"))
                            )))
                        }
                    }
                }
                Some("element") => {
                    let (Some(name), Some(count)) = (fields.get(1), fields.get(2)) else {
                        return Err(err("`element` needs a name and a count".into()));
                    };
                    let count = count.parse().map_err(|_| {
                        err(format!("element count `{}` is not a count", excerpt(count)))
                    })?;
                    elements.push(Element {
                        name: name.to_string(),
                        count,
                        properties: Vec::new(),
                    });
                }
                Some("property") => {
                    let Some(element) = elements.last_mut() else {
                        return Err(err("`property` before any `element`".into()));
                    };
                    element.properties.push(property(&fields, &raw, err)?);
                }
                Some("end_header") => break,
                Some(other) => {
                    return Err(err(format!("unknown header keyword `{}`", excerpt(other))))
                }
            }
        }
        let Some(binary) = format else {
            return Err(format_err(file, None, "the header has no `format` line"));
        };
        Ok(PlyHeader {
            binary,
            elements,
            data_start: pos,
            lines: line_no,
        })
    }
}

/// The property of a `property` header line (`fields`, the line `raw`).
fn property(
    fields: &[&str],
    raw: &str,
    err: impl Fn(String) -> PointSetError,
) -> Result<Property, PointSetError> {
    let ty = |k: usize| {
        fields.get(k).and_then(|t| Scalar::parse(t)).ok_or_else(|| {
            err(format!(
                "unknown property type in `{}`",
                excerpt(raw.trim())
            ))
        })
    };
    Ok(if fields.get(1) == Some(&"list") {
        Property {
            list: Some(ty(2)?),
            scalar: ty(3)?,
            name: fields.get(4).unwrap_or(&"").to_string(),
        }
    } else {
        Property {
            scalar: ty(1)?,
            list: None,
            name: fields.get(2).unwrap_or(&"").to_string(),
        }
    })
}

/// The scalar values of every row of element `vertex_index` in binary
/// little-endian `data` (the elements before it skipped; lists skipped).
fn binary_rows(
    mut data: &[u8],
    elements: &[Element],
    vertex_index: usize,
    file: &str,
) -> Result<Vec<Vec<Real>>, PointSetError> {
    let mut rows = Vec::with_capacity(elements[vertex_index].count.min(1 << 24));
    let truncated = || format_err(file, None, "binary data ends early");
    for (k, element) in elements.iter().enumerate() {
        if element.properties.is_empty() {
            // Rows of no bytes (the vertex element has x, y and z):
            // nothing to skip, however large the count.
            continue;
        }
        for _ in 0..element.count {
            let mut row = Vec::with_capacity(element.properties.len());
            for p in &element.properties {
                let items = match p.list {
                    Some(count_type) => {
                        if data.len() < count_type.size() {
                            return Err(truncated());
                        }
                        let n = count_type.read_le(data);
                        data = &data[count_type.size()..];
                        if n < 0.0 {
                            return Err(format_err(file, None, "negative list length"));
                        }
                        n as usize
                    }
                    None => 1,
                };
                let need = items.checked_mul(p.scalar.size()).ok_or_else(truncated)?;
                if data.len() < need {
                    return Err(truncated());
                }
                if p.list.is_none() {
                    row.push(p.scalar.read_le(data));
                }
                data = &data[need..];
            }
            if k == vertex_index {
                rows.push(row);
            }
        }
    }
    if !data.is_empty() {
        return Err(beyond_header(file, data.len(), "bytes"));
    }
    Ok(rows)
}

/// The error of data beyond the rows the header declares: a header count
/// smaller than the data would silently drop points.
fn beyond_header(file: &str, extra: usize, unit: &str) -> PointSetError {
    format_err(
        file,
        None,
        format!(
            "{extra} {unit} of data after the rows its header declares: an `element` count \
             is smaller than the data (fix the counts)"
        ),
    )
}

/// The values of every row of element `vertex_index` in ascii `data` (the
/// rows of the elements before it skipped).
fn ascii_rows(
    data: &[u8],
    header: &PlyHeader,
    vertex_index: usize,
    file: &str,
) -> Result<Vec<Vec<Real>>, PointSetError> {
    let vertex = &header.elements[vertex_index];
    let mut rows = Vec::with_capacity(vertex.count.min(1 << 24));
    let text = String::from_utf8_lossy(data);
    let mut line_no = header.lines;
    let mut lines = text.lines().map(|l| {
        line_no += 1;
        (line_no, l)
    });
    for (k, element) in header.elements.iter().enumerate() {
        for _ in 0..element.count {
            let Some((line, l)) = lines.next() else {
                return Err(format_err(
                    file,
                    None,
                    format!(
                        "the file ends before its {} `{}` rows",
                        element.count, element.name
                    ),
                ));
            };
            if k != vertex_index {
                continue;
            }
            let fields: Vec<&str> = l.split_whitespace().collect();
            if vertex.properties.iter().any(|p| p.list.is_some()) {
                return Err(format_err(
                    file,
                    Some(line),
                    "list properties in `vertex` are not supported in ascii PLY",
                ));
            }
            if fields.len() != vertex.properties.len() {
                return Err(format_err(
                    file,
                    Some(line),
                    format!(
                        "expected {} values, found {}",
                        vertex.properties.len(),
                        fields.len()
                    ),
                ));
            }
            rows.push(
                fields
                    .iter()
                    .map(|f| number(f, file, line))
                    .collect::<Result<Vec<_>, _>>()?,
            );
        }
    }
    let extra = lines.filter(|(_, l)| !l.trim().is_empty()).count();
    if extra > 0 {
        return Err(beyond_header(file, extra, "lines"));
    }
    Ok(rows)
}

/// Where the position and normal coordinates are in a vertex row.
struct VertexColumns {
    position: [usize; 3],
    normal: Option<[usize; 3]>,
}

impl VertexColumns {
    /// The points (and normals) of `rows`.
    fn points(&self, rows: &[Vec<Real>], file: &str) -> Result<PointSet, PointSetError> {
        let [ix, iy, iz] = self.position;
        let mut positions = Vec::with_capacity(rows.len());
        let mut normals = Vec::new();
        for (k, row) in rows.iter().enumerate() {
            let p = Point3::new(row[ix], row[iy], row[iz]);
            if !p.iter().all(|c| c.is_finite()) {
                return Err(format_err(
                    file,
                    None,
                    format!("vertex {k} has a non-finite coordinate"),
                ));
            }
            positions.push(p);
            if let Some(n) = self.normal {
                let v = Vec3::new(row[n[0]], row[n[1]], row[n[2]]);
                normals.push(unit(v, file, None).map_err(|_| {
                    format_err(file, None, format!("vertex {k} has a non-finite normal"))
                })?);
            }
        }
        Ok(PointSet {
            positions,
            normals: self.normal.and_then(|_| super::given_normals(normals)),
        })
    }
}
