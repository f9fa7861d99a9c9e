//! PLY (Stanford polygon file), ASCII and binary (little and big endian), read by hand: the header's
//! elements and properties, then the `vertex` element's `x y z` (any scalar type) and optional
//! `nx ny nz`, and the `face` element's `vertex_indices` (or `vertex_index`) list, polygons
//! fan-triangulated. Other elements and properties (a second `vertex` or `face` element among them)
//! are read past. Every count the header declares is checked against the bytes that follow it before
//! anything is allocated, and the vertices and triangles against `MAX_VERTICES` / `MAX_TRIANGLES`.

use std::path::Path;

use glam::Vec3;

use super::{file_name, Mesh};
use crate::error::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
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

    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The range of an integer type.
    fn int_range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            _ => (0, u32::MAX.into()),
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    /// Count type, item type.
    List(Scalar, Scalar),
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary { big_endian: bool },
}

/// The header: format, elements, and where the data starts.
fn parse_header(bytes: &[u8]) -> std::result::Result<(Format, Vec<Element>, usize), String> {
    let mut pos = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut line_no = 0;
    loop {
        line_no += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err("no end_header line (not a PLY file, or the header is cut off)".into());
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let line = std::str::from_utf8(raw).map_err(|_| format!("header line {line_no} is not text"))?;
        let words: Vec<&str> = line.split_whitespace().collect();
        if line_no == 1 {
            if line.trim_end() != "ply" {
                return Err("not a PLY file (the first line is not \"ply\")".into());
            }
            continue;
        }
        let bad = |what: &str| format!("header line {line_no}: {what}: \"{}\"", line.trim_end());
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, v] => {
                if !v.starts_with('1') {
                    return Err(bad("unsupported PLY version"));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Binary { big_endian: false },
                    "binary_big_endian" => Format::Binary { big_endian: true },
                    _ => return Err(bad("unknown format")),
                });
            }
            ["element", name, count] => {
                let count = count.parse::<u64>().map_err(|_| bad("the element count is not a count"))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            ["property", "list", count, item, name] => {
                let (Some(c), Some(i)) = (Scalar::parse(count), Scalar::parse(item)) else {
                    return Err(bad("unknown property type"));
                };
                if !c.is_int() {
                    return Err(bad("a list count must have an integer type"));
                }
                let e = elements.last_mut().ok_or_else(|| bad("a property before any element"))?;
                e.props.push(Property { name: name.to_string(), kind: Kind::List(c, i) });
            }
            ["property", ty, name] => {
                let t = Scalar::parse(ty).ok_or_else(|| bad("unknown property type"))?;
                let e = elements.last_mut().ok_or_else(|| bad("a property before any element"))?;
                e.props.push(Property { name: name.to_string(), kind: Kind::Scalar(t) });
            }
            ["end_header"] => {
                let format = format.ok_or("no format line in the header")?;
                return Ok((format, elements, pos));
            }
            _ => return Err(bad("not a PLY header line")),
        }
    }
}

/// Reads values from the data after the header.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    format: Format,
    /// The current line (ASCII).
    line: usize,
}

impl Body<'_> {
    /// One value of type `t`, as `f64` (exact for every PLY type but `double`, which it is).
    fn read(&mut self, t: Scalar) -> std::result::Result<f64, String> {
        match self.format {
            Format::Ascii => {
                while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
                    if self.data[self.pos] == b'\n' {
                        self.line += 1;
                    }
                    self.pos += 1;
                }
                let start = self.pos;
                while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
                    self.pos += 1;
                }
                if start == self.pos {
                    return Err("the file ends early (truncated)".into());
                }
                let tok = std::str::from_utf8(&self.data[start..self.pos]).unwrap_or("?");
                let what = |kind: &str| format!("data line {}: \"{tok}\" is not {kind}", self.line);
                if t.is_int() {
                    let v: i64 = tok.parse().map_err(|_| what("an integer"))?;
                    let (lo, hi) = t.int_range();
                    if v < lo || v > hi {
                        return Err(what("in the range of its type"));
                    }
                    Ok(v as f64)
                } else {
                    tok.parse::<f64>().map_err(|_| what("a number"))
                }
            }
            Format::Binary { big_endian } => {
                let n = t.size();
                let Some(b) = self.data.get(self.pos..self.pos + n) else {
                    return Err("the file ends early (truncated)".into());
                };
                self.pos += n;
                let mut a = [0u8; 8];
                a[..n].copy_from_slice(b);
                if big_endian {
                    a[..n].reverse();
                }
                Ok(match t {
                    Scalar::I8 => a[0] as i8 as f64,
                    Scalar::U8 => a[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(a),
                })
            }
        }
    }

    /// Bytes left after the read position.
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
}

/// The fewest bytes one instance of `e` can take: binary, every scalar and every list's count;
/// ASCII, every property one character and one separator.
fn min_instance_bytes(e: &Element, format: Format) -> u64 {
    e.props
        .iter()
        .map(|p| match (format, p.kind) {
            (Format::Ascii, _) => 2,
            (_, Kind::Scalar(t) | Kind::List(t, _)) => t.size() as u64,
        })
        .sum()
}

impl Mesh {
    /// A PLY file (ASCII, binary little or big endian). Refuses (naming the file and what is wrong)
    /// a bad header, an unknown property type, a vertex element without `x y z`, counts the data
    /// cannot hold, a truncated file, a non-finite coordinate, a face using a vertex the file does
    /// not have, and a file without triangles. Normals come from `nx ny nz` when present, else as
    /// for every format ([`Mesh::from_triangles`]).
    pub fn load_ply(path: &Path) -> Result<Mesh> {
        let origin = crate::fsio::show(path);
        let bytes = crate::fsio::read_limited(path, super::MAX_MESH_FILE_BYTES, "a mesh file")?;
        let (positions, normals, indices) = read_ply(&bytes).map_err(|m| Error::input(&origin, m))?;
        Mesh::from_triangles(&origin, file_name(path), positions, normals, indices)
    }
}

type Parts = (Vec<Vec3>, Option<Vec<Vec3>>, Vec<u32>);

fn read_ply(bytes: &[u8]) -> std::result::Result<Parts, String> {
    let (format, elements, start) = parse_header(bytes)?;
    let body_len = (bytes.len() - start) as u64;
    // Every declared count against the data, before anything is allocated.
    let mut need: u64 = 0;
    for e in &elements {
        let each = min_instance_bytes(e, format);
        need = e.count.checked_mul(each).and_then(|n| need.checked_add(n)).unwrap_or(u64::MAX);
        let slack = u64::from(format == Format::Ascii);
        if need > body_len + slack {
            return Err(format!(
                "the header declares {} \"{}\" elements, more than the {body_len} bytes after the header can hold",
                e.count, e.name
            ));
        }
    }
    // The first `vertex` and the first `face` element are the mesh; any later element of either
    // name is read past like any other element.
    let vertex_at = elements.iter().position(|e| e.name == "vertex").ok_or("no vertex element")?;
    let face_at = elements.iter().position(|e| e.name == "face");
    let vertex = &elements[vertex_at];
    let scalar = |name: &str| vertex.props.iter().position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)));
    let (Some(x), Some(y), Some(z)) = (scalar("x"), scalar("y"), scalar("z")) else {
        return Err("the vertex element has no scalar x, y and z properties".into());
    };
    let normal_props = match (scalar("nx"), scalar("ny"), scalar("nz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    super::check_expansion(vertex.count, 0)?;
    let vertex_count = vertex.count as usize;
    let mut body = Body { data: &bytes[start..], pos: 0, format, line: 1 };
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let mut saw_faces = false;
    let mut values = Vec::new();
    for (ei, e) in elements.iter().enumerate() {
        let is_vertex = ei == vertex_at;
        let is_face_element = Some(ei) == face_at;
        let face_list = is_face_element
            .then(|| {
                e.props.iter().position(|p| {
                    (p.name == "vertex_indices" || p.name == "vertex_index") && matches!(p.kind, Kind::List(..))
                })
            })
            .flatten();
        if is_face_element {
            let Some(k) = face_list else {
                return Err("the face element has no vertex_indices (or vertex_index) list".into());
            };
            if let Kind::List(_, item) = e.props[k].kind {
                if !item.is_int() {
                    return Err("the face element's vertex indices are not integers".into());
                }
            }
            saw_faces = true;
        }
        if is_vertex {
            // Bounded by the data (checked above).
            positions.reserve(e.count as usize);
        }
        let mut polygon: Vec<u32> = Vec::new();
        for k in 0..if e.props.is_empty() { 0 } else { e.count } {
            let at = |m: String| format!("{} {k}: {m}", e.name);
            values.clear();
            for (pi, p) in e.props.iter().enumerate() {
                match p.kind {
                    Kind::Scalar(t) => values.push(body.read(t).map_err(at)?),
                    Kind::List(ct, it) => {
                        let n = body.read(ct).map_err(at)?;
                        if n < 0.0 {
                            return Err(at(format!("list {} has a negative length {n}", p.name)));
                        }
                        let is_face = Some(pi) == face_list;
                        // At least a byte per item in ASCII, its size in binary.
                        let item_min = if format == Format::Ascii { 1 } else { it.size() as u64 };
                        if (n as u64).saturating_mul(item_min) > body.remaining() as u64 {
                            return Err(at(format!(
                                "list {} of {n} items runs past the end of the file (truncated)",
                                p.name
                            )));
                        }
                        polygon.clear();
                        for _ in 0..n as u64 {
                            let v = body.read(it).map_err(at)?;
                            if is_face {
                                if !(v >= 0.0 && (v as usize) < vertex_count) {
                                    return Err(at(format!("uses vertex {v} of {vertex_count}")));
                                }
                                polygon.push(v as u32);
                            }
                        }
                        if is_face {
                            // Fan triangulation; a face of fewer than three vertices has no area.
                            let adds = polygon.len().saturating_sub(2) as u64;
                            super::check_expansion(0, (indices.len() / 3) as u64 + adds).map_err(at)?;
                            for w in 1..polygon.len().saturating_sub(1) {
                                indices.extend_from_slice(&[polygon[0], polygon[w], polygon[w + 1]]);
                            }
                        }
                        values.push(0.0);
                    }
                }
            }
            if is_vertex {
                let p = Vec3::new(values[x] as f32, values[y] as f32, values[z] as f32);
                if !p.is_finite() {
                    let (a, b, c) = (values[x], values[y], values[z]);
                    return Err(at(format!("a non-finite coordinate: {a} {b} {c}")));
                }
                positions.push(p);
                if let Some([a, b, c]) = normal_props {
                    normals.push(Vec3::new(values[a] as f32, values[b] as f32, values[c] as f32));
                }
            }
        }
    }
    if !saw_faces || indices.is_empty() {
        return Err("no triangles (no face with three or more vertices)".into());
    }
    Ok((positions, normal_props.map(|_| normals), indices))
}
