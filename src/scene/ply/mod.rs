//! PLY meshes (ASCII, binary little- and big-endian): vertex positions, optional vertex
//! normals and texture coordinates (`u, v`, `s, t`, `texture_u, texture_v` or
//! `texture_s, texture_t`), and faces of three or four corners (quads split in two). Owns the file format and
//! its errors; the caller places the mesh in the world. A count in the header is checked
//! against the bytes (or lines) the file really has before anything is allocated for it, so a
//! header that claims 10¹² vertices is refused, not obeyed. Binary bodies of fixed-size
//! records (the common case) are read in parallel ([`fast`]), the rest record by record
//! ([`body`]). Must not know scenes or Embree.

mod body;
mod fast;

use super::files::SceneFiles;
use body::{AsciiBody, Body, element_error};
use glam::{Vec2, Vec3};
use std::path::Path;

/// A mesh as the file gives it, in the file's own coordinates.
#[derive(Debug, Default, PartialEq)]
pub struct PlyMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
}

/// What went wrong, and where: a header line, or an element of the body.
#[derive(Debug, PartialEq)]
pub struct PlyError {
    /// 1-based line (header lines, and body lines of an ASCII file).
    pub line: Option<usize>,
    /// The header line or element named, e.g. `element vertex` or `face[12]`.
    pub field: String,
    pub message: String,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy, Debug, PartialEq)]
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

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value in `raw` (exactly [`Scalar::size`] bytes) of either byte order.
    #[inline]
    fn decode(self, raw: &[u8], big: bool) -> f64 {
        let mut b = [0u8; 8];
        b[..raw.len()].copy_from_slice(raw);
        if big {
            b[..raw.len()].reverse();
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }

    /// The fewest bytes one value of this property takes in a binary file.
    fn min_size(&self) -> usize {
        match self {
            Property::Scalar { ty, .. } => ty.size(),
            Property::List { count, .. } => count.size(),
        }
    }
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
    line: usize,
}

/// Vertex indices above this do not fit the u32 triangles (and no real file has them).
const MAX_VERTICES: usize = u32::MAX as usize;

pub fn read(path: &Path, files: &dyn SceneFiles) -> Result<PlyMesh, PlyError> {
    let bytes = files.read(path).map_err(|err| PlyError {
        line: None,
        field: "file".into(),
        message: format!("cannot read: {err}"),
    })?;
    parse(&bytes)
}

pub fn parse(bytes: &[u8]) -> Result<PlyMesh, PlyError> {
    let (encoding, elements, body_start, header_lines) = header(bytes)?;
    let body = &bytes[body_start..];
    let mut reader = match encoding {
        Encoding::Ascii => Body::Ascii(AsciiBody::new(body, header_lines)?),
        Encoding::Little | Encoding::Big => Body::Binary {
            bytes: body,
            at: 0,
            big: encoding == Encoding::Big,
        },
    };
    reader.check_counts(&elements)?;

    let mut mesh = PlyMesh::default();
    let mut vertex_count = None;
    for element in &elements {
        match element.name.as_str() {
            "vertex" => {
                vertex_count = Some(element.count);
                let fast = (reader.binary_rest())
                    .and_then(|(rest, big)| fast::vertices(rest, element, big, &mut mesh));
                let ascii = fast.is_none()
                    && (reader.ascii_lines(element.count))
                        .and_then(|lines| fast::ascii_vertices(lines, element, &mut mesh))
                        .is_some();
                match fast {
                    Some(used) => reader.advance(used),
                    None if ascii => reader.skip_lines(element.count),
                    None => read_vertices(&mut reader, element, &mut mesh)?,
                }
            }
            "face" => {
                let Some(vertices) = vertex_count else {
                    return Err(PlyError {
                        line: Some(element.line),
                        field: "element face".into(),
                        message: "faces come before any vertices".into(),
                    });
                };
                let fast = (reader.binary_rest()).and_then(|(rest, big)| {
                    fast::triangles(rest, element, vertices, big, &mut mesh)
                });
                let ascii = fast.is_none()
                    && (reader.ascii_lines(element.count))
                        .and_then(|lines| {
                            fast::ascii_triangles(lines, element, vertices, &mut mesh)
                        })
                        .is_some();
                match fast {
                    Some(used) => reader.advance(used),
                    None if ascii => reader.skip_lines(element.count),
                    None => read_faces(&mut reader, element, vertices, &mut mesh)?,
                }
            }
            _ => {
                for i in 0..element.count {
                    reader.begin(&element.name, i)?;
                    for p in &element.properties {
                        reader.skip(p, &element.name, i)?;
                    }
                    reader.end(&element.name, i)?;
                }
            }
        }
    }
    if vertex_count.is_none() {
        return Err(PlyError {
            line: None,
            field: "header".into(),
            message: "has no `element vertex`".into(),
        });
    }
    Ok(mesh)
}

fn header_error(line: usize, field: &str, message: impl Into<String>) -> PlyError {
    PlyError {
        line: Some(line),
        field: field.into(),
        message: message.into(),
    }
}

/// Reads the header; returns the encoding, the elements, where the body starts and how many
/// lines the header has.
fn header(bytes: &[u8]) -> Result<(Encoding, Vec<Element>, usize, usize), PlyError> {
    let mut at = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[at..].iter().position(|&b| b == b'\n') else {
            return Err(header_error(
                line_no + 1,
                "header",
                "ends before `end_header`",
            ));
        };
        line_no += 1;
        let raw = &bytes[at..at + len];
        at += len + 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(header_error(line_no, "header", "is not ASCII text"));
        };
        let text = text.trim_end_matches('\r');
        let words: Vec<&str> = text.split_whitespace().collect();
        if line_no == 1 {
            if text.trim() != "ply" {
                return Err(header_error(
                    1,
                    "magic",
                    "the file does not start with `ply`",
                ));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", kind, version] => {
                if *version != "1.0" {
                    return Err(header_error(
                        line_no,
                        "format",
                        format!("version {version} is not 1.0"),
                    ));
                }
                encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    other => {
                        return Err(header_error(
                            line_no,
                            "format",
                            format!(
                                "`{other}` is not ascii, binary_little_endian or binary_big_endian"
                            ),
                        ));
                    }
                });
            }
            ["element", name, count] => {
                let field = format!("element {name}");
                let count: usize = count.parse().map_err(|_| {
                    header_error(
                        line_no,
                        &field,
                        format!("count `{count}` is not a whole number"),
                    )
                })?;
                if elements.iter().any(|e| e.name == *name) {
                    return Err(header_error(line_no, &field, "is declared twice"));
                }
                elements.push(Element {
                    name: (*name).into(),
                    count,
                    properties: Vec::new(),
                    line: line_no,
                });
            }
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return Err(header_error(
                        line_no,
                        "property",
                        "comes before any element",
                    ));
                };
                let field = format!("element {} property", element.name);
                let scalar = |name: &str| {
                    Scalar::parse(name).ok_or_else(|| {
                        header_error(line_no, &field, format!("`{name}` is not a PLY type"))
                    })
                };
                let property = match rest {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if !count.is_integer() {
                            return Err(header_error(
                                line_no,
                                &field,
                                "a list's count type must be an integer type",
                            ));
                        }
                        Property::List {
                            name: (*name).into(),
                            count,
                            item: scalar(item)?,
                        }
                    }
                    [ty, name] => Property::Scalar {
                        name: (*name).into(),
                        ty: scalar(ty)?,
                    },
                    _ => return Err(header_error(line_no, &field, "is malformed")),
                };
                if element
                    .properties
                    .iter()
                    .any(|p| p.name() == property.name())
                {
                    return Err(header_error(line_no, &field, "is declared twice"));
                }
                element.properties.push(property);
            }
            ["end_header"] => break,
            [word, ..] => {
                return Err(header_error(
                    line_no,
                    "header",
                    format!("`{word}` is not a PLY header keyword"),
                ));
            }
        }
    }
    let encoding = encoding.ok_or_else(|| header_error(line_no, "format", "is missing"))?;
    Ok((encoding, elements, at, line_no))
}

/// Where `vertex` keeps a position (x, y, z), a normal (nx, ny, nz) and texture coordinates,
/// by property index.
struct VertexLayout {
    position: [usize; 3],
    normal: Option<[usize; 3]>,
    uv: Option<[usize; 2]>,
}

/// The names texture coordinates go by in PLY files, in the order they are looked for.
const UV_NAMES: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];

fn vertex_layout(element: &Element) -> Result<VertexLayout, PlyError> {
    let index = |name: &str| {
        element
            .properties
            .iter()
            .position(|p| p.name() == name && matches!(p, Property::Scalar { .. }))
    };
    let position = ["x", "y", "z"].map(index);
    let [Some(x), Some(y), Some(z)] = position else {
        return Err(header_error(
            element.line,
            "element vertex",
            "needs scalar properties x, y and z",
        ));
    };
    let normal = match ["nx", "ny", "nz"].map(index) {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        [None, None, None] => None,
        _ => {
            return Err(header_error(
                element.line,
                "element vertex",
                "has some of nx, ny, nz but not all three",
            ));
        }
    };
    let uv = UV_NAMES.iter().find_map(|names| match names.map(index) {
        [Some(a), Some(b)] => Some([a, b]),
        _ => None,
    });
    Ok(VertexLayout {
        position: [x, y, z],
        normal,
        uv,
    })
}

fn read_vertices(reader: &mut Body, element: &Element, mesh: &mut PlyMesh) -> Result<(), PlyError> {
    if element.count > MAX_VERTICES {
        return Err(header_error(
            element.line,
            "element vertex",
            "has more vertices than u32 indices can name",
        ));
    }
    let VertexLayout {
        position,
        normal,
        uv,
    } = vertex_layout(element)?;
    mesh.positions.reserve(element.count);
    let mut normals = normal.map(|_| Vec::with_capacity(element.count));
    let mut uvs = uv.map(|_| Vec::with_capacity(element.count));
    let mut values = vec![0.0f64; element.properties.len()];
    for i in 0..element.count {
        reader.begin("vertex", i)?;
        for (slot, p) in element.properties.iter().enumerate() {
            match p {
                Property::Scalar { ty, .. } => values[slot] = reader.scalar(*ty, "vertex", i)?,
                list => reader.skip(list, "vertex", i)?,
            }
        }
        reader.end("vertex", i)?;
        let v =
            |[a, b, c]: [usize; 3]| Vec3::new(values[a] as f32, values[b] as f32, values[c] as f32);
        let p = v(position);
        if !p.is_finite() {
            return Err(element_error(reader, "vertex", i, "position is not finite"));
        }
        mesh.positions.push(p);
        if let (Some(normals), Some(layout)) = (normals.as_mut(), normal) {
            let n = v(layout);
            if !n.is_finite() {
                return Err(element_error(reader, "vertex", i, "normal is not finite"));
            }
            normals.push(n);
        }
        if let (Some(uvs), Some([a, b])) = (uvs.as_mut(), uv) {
            let t = Vec2::new(values[a] as f32, values[b] as f32);
            if !t.is_finite() {
                return Err(element_error(
                    reader,
                    "vertex",
                    i,
                    "texture coordinate is not finite",
                ));
            }
            uvs.push(t);
        }
    }
    mesh.normals = normals;
    mesh.uvs = uvs;
    Ok(())
}

fn read_faces(
    reader: &mut Body,
    element: &Element,
    vertex_count: usize,
    mesh: &mut PlyMesh,
) -> Result<(), PlyError> {
    let corners_at = element
        .properties
        .iter()
        .position(|p| {
            matches!(p, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index")
        })
        .ok_or_else(|| {
            header_error(
                element.line,
                "element face",
                "needs a list property vertex_indices (or vertex_index)",
            )
        })?;
    mesh.triangles.reserve(element.count);
    for i in 0..element.count {
        reader.begin("face", i)?;
        let mut corners = [0u32; 4];
        let mut n = 0;
        for (slot, p) in element.properties.iter().enumerate() {
            match p {
                Property::List { count, item, .. } if slot == corners_at => {
                    let k = reader.scalar(*count, "face", i)?;
                    if k != 3.0 && k != 4.0 {
                        return Err(element_error(
                            reader,
                            "face",
                            i,
                            format!("has {k} corners; only triangles and quads are read"),
                        ));
                    }
                    n = k as usize;
                    for corner in corners.iter_mut().take(n) {
                        let v = reader.scalar(*item, "face", i)?;
                        if !(v >= 0.0 && v.fract() == 0.0 && (v as usize) < vertex_count) {
                            return Err(element_error(
                                reader,
                                "face",
                                i,
                                format!(
                                    "vertex index {v} is not one of the {vertex_count} vertices"
                                ),
                            ));
                        }
                        *corner = v as u32;
                    }
                }
                other => reader.skip(other, "face", i)?,
            }
        }
        reader.end("face", i)?;
        let [a, b, c, d] = corners;
        mesh.triangles.push([a, b, c]);
        if n == 4 {
            mesh.triangles.push([a, c, d]);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
