//! glTF 2.0 (`.gltf` with embedded or external buffers, `.glb`) through the `gltf` crate's document
//! model (JSON, validation, GLB container). Buffers and accessors are read here, each range checked
//! against the data before it is read: the crate's own readers assume well-formed files.
//!
//! Every mesh primitive of the default scene (else the first scene) is loaded with its node's world
//! transform; normals go through the inverse transpose, and a mirroring transform (negative
//! determinant) has its triangles' winding reversed so they stay counter-clockwise from outside.
//! `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` are read; points and lines have no surface and are
//! left out. Texture coordinates and tangents are not read (tangents follow the rule of docs/model.md,
//! Frames and conventions).
//!
//! Untrusted files: the triangles, vertices and primitives the scene expands to (every reuse of an
//! accessor, mesh or node counted) are checked against the limits before any buffer is read, and an
//! external buffer must be a regular file inside the glTF file's own folder (docs/formats.md,
//! Limits and untrusted input).

use std::path::{Component, Path};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::buffer::Source;
use ::gltf::mesh::{Mode, Semantic};
use ::gltf::{Accessor, Document, Primitive};
use glam::{DMat3, DMat4, DVec3, Vec3};

use super::{file_name, Mesh};
use crate::error::{Error, Result};

type Res<T> = std::result::Result<T, String>;

impl Mesh {
    /// A glTF 2.0 file (`.gltf` or `.glb`). Refuses (naming the file and what is wrong) a file that
    /// is not glTF, a missing or short buffer, an accessor reaching past its data or of the wrong
    /// type, a sparse accessor, an index out of range, a non-finite coordinate, a node hierarchy that
    /// is not a tree, and a scene without triangles.
    pub fn load_gltf(path: &Path) -> Result<Mesh> {
        let origin = crate::fsio::show(path);
        let bytes = crate::fsio::read_limited(path, super::MAX_MESH_FILE_BYTES, "a mesh file")?;
        let g = parse(&bytes).map_err(|e| Error::input(&origin, format!("not a readable glTF 2.0 file: {e}")))?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut loader = Loader {
            doc: &g.document,
            blob: g.blob.as_deref(),
            dir,
            buffers: vec![None; g.document.buffers().count()],
            positions: Vec::new(),
            normals: Vec::new(),
            all_normals: true,
            indices: Vec::new(),
            skipped: 0,
        };
        loader.load().map_err(|m| Error::input(&origin, m))?;
        let Loader { positions, normals, all_normals, indices, skipped, .. } = loader;
        if indices.is_empty() {
            let why = if skipped > 0 {
                format!("no triangles ({skipped} primitive(s) of points or lines, which have no surface)")
            } else {
                "no triangles in the scene".to_string()
            };
            return Err(Error::input(&origin, why));
        }
        Mesh::from_triangles(&origin, file_name(path), positions, all_normals.then_some(normals), indices)
    }
}

/// `Gltf::from_slice` with the accessor indices of every primitive range-checked before the
/// document is validated: gltf-json 1.4's validation indexes the POSITION accessor unchecked and
/// panics on an index past the accessors (found by `tests/fuzz.rs`; `tests/corpus/` keeps it).
fn parse(bytes: &[u8]) -> std::result::Result<::gltf::Gltf, String> {
    let ::gltf::Gltf { document, blob } =
        ::gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let root = document.into_json();
    let n = root.accessors.len();
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let used = p.attributes.values().chain(p.indices.iter()).chain(
                p.targets
                    .iter()
                    .flatten()
                    .flat_map(|t| t.positions.iter().chain(t.normals.iter()).chain(t.tangents.iter())),
            );
            for a in used {
                if a.value() >= n {
                    return Err(format!("meshes[{mi}].primitives[{pi}]: accessor {} of {n}", a.value()));
                }
            }
        }
    }
    let document = ::gltf::Document::from_json(root).map_err(|e| e.to_string())?;
    Ok(::gltf::Gltf { document, blob })
}

struct Loader<'a> {
    doc: &'a Document,
    blob: Option<&'a [u8]>,
    dir: &'a Path,
    /// Buffers, read when an accessor first needs them.
    buffers: Vec<Option<Vec<u8>>>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    all_normals: bool,
    indices: Vec<u32>,
    skipped: usize,
}

impl Loader<'_> {
    /// Walks the scene's node trees depth first, in file order, after [`Loader::check_expansion`].
    fn load(&mut self) -> Res<()> {
        let scene = self.doc.default_scene().or_else(|| self.doc.scenes().next()).ok_or("no scene")?;
        self.check_expansion(&scene)?;
        let node_count = self.doc.nodes().count();
        let mut stack: Vec<(::gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
        stack.reverse();
        let mut visits = 0;
        while let Some((node, parent)) = stack.pop() {
            visits += 1;
            if visits > node_count {
                return Err("the node hierarchy is not a tree (a node is reached twice)".into());
            }
            let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
            let world = parent * local;
            if !world.is_finite() {
                return Err(format!("node {}: its world transform is not finite", node.index()));
            }
            if let Some(mesh) = node.mesh() {
                for (k, prim) in mesh.primitives().enumerate() {
                    let at = |m: String| format!("node {} mesh {} primitive {k}: {m}", node.index(), mesh.index());
                    self.primitive(&prim, world).map_err(at)?;
                }
            }
            let children: Vec<_> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|c| (c, world)));
        }
        Ok(())
    }

    /// Refuses, before any buffer is read, a scene that expands to more than
    /// [`super::MAX_TRIANGLES`] triangles, [`super::MAX_VERTICES`] vertices or
    /// [`super::MAX_PRIMITIVE_INSTANCES`] primitives: each node's mesh counts once per node that uses it,
    /// and each primitive's accessors once per primitive that uses them, from the counts the
    /// document declares (the data is range checked when read). Costs one pass over the nodes and
    /// one over the meshes, however often they are reused.
    fn check_expansion(&self, scene: &::gltf::Scene) -> Res<()> {
        // Per mesh: (primitives, vertices, triangles) of one instance.
        let mut per_mesh: Vec<Option<(u64, u64, u64)>> = vec![None; self.doc.meshes().count()];
        let node_count = self.doc.nodes().count();
        let mut stack: Vec<::gltf::Node> = scene.nodes().collect();
        let (mut visits, mut prims, mut verts, mut tris) = (0usize, 0u64, 0u64, 0u64);
        while let Some(node) = stack.pop() {
            visits += 1;
            if visits > node_count {
                return Err("the node hierarchy is not a tree (a node is reached twice)".into());
            }
            if let Some(mesh) = node.mesh() {
                let (p, v, t) = *per_mesh[mesh.index()].get_or_insert_with(|| mesh_expansion(&mesh));
                prims = prims.saturating_add(p);
                verts = verts.saturating_add(v);
                tris = tris.saturating_add(t);
                if prims > super::MAX_PRIMITIVE_INSTANCES {
                    let limit = super::MAX_PRIMITIVE_INSTANCES;
                    return Err(format!(
                        "the scene draws {prims} primitives or more (meshes reused by nodes), past the limit of {limit}"
                    ));
                }
                super::check_expansion(verts, tris).map_err(|m| format!("the scene {m}"))?;
            }
            stack.extend(node.children());
        }
        Ok(())
    }

    fn primitive(&mut self, prim: &Primitive, world: DMat4) -> Res<()> {
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.skipped += 1;
            return Ok(());
        }
        let pos = prim.get(&Semantic::Positions).ok_or("no POSITION attribute")?;
        let local = self.vec3s(&pos, "POSITION")?;
        let n = local.len();
        let base = self.positions.len();
        if base + n > u32::MAX as usize {
            return Err("more than 2^32 vertices".into());
        }
        for p in &local {
            let q = world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)).as_vec3();
            if !q.is_finite() {
                return Err(format!("a non-finite coordinate: {} {} {}", p[0], p[1], p[2]));
            }
            self.positions.push(q);
        }
        let linear = DMat3::from_mat4(world);
        let det = linear.determinant();
        if !(det.abs() > 0.0) {
            return Err("its node's transform is singular".into());
        }
        match prim.get(&Semantic::Normals) {
            Some(acc) => {
                let ns = self.vec3s(&acc, "NORMAL")?;
                if ns.len() != n {
                    return Err(format!("{} normals for {n} positions", ns.len()));
                }
                let m = linear.inverse().transpose();
                self.normals
                    .extend(ns.iter().map(|v| (m * DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)).as_vec3()));
            }
            None => self.all_normals = false,
        }
        let order: Vec<u32> = match prim.indices() {
            Some(acc) => self.indices_of(&acc)?,
            None => (0..n as u32).collect(),
        };
        if let Some(i) = order.iter().find(|&&i| i as usize >= n) {
            return Err(format!("index {i} of a primitive with {n} vertices"));
        }
        let tris: Vec<[u32; 3]> = match mode {
            Mode::TriangleStrip => (2..order.len())
                .map(|i| {
                    let (a, b, c) = (order[i - 2], order[i - 1], order[i]);
                    if i % 2 == 0 {
                        [a, b, c]
                    } else {
                        [b, a, c]
                    }
                })
                .collect(),
            Mode::TriangleFan => (2..order.len()).map(|i| [order[0], order[i - 1], order[i]]).collect(),
            _ => order.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        };
        for [a, b, c] in tris {
            // A mirroring transform turns counter-clockwise triangles clockwise.
            let [a, b, c] = if det < 0.0 { [a, c, b] } else { [a, b, c] };
            self.indices.extend([a, b, c].map(|i| base as u32 + i));
        }
        Ok(())
    }

    fn vec3s(&mut self, acc: &Accessor, what: &str) -> Res<Vec<[f32; 3]>> {
        if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
            let (t, d) = (acc.data_type(), acc.dimensions());
            return Err(format!("{what} accessor {} is {t:?} {d:?}, not FLOAT VEC3", acc.index()));
        }
        let (data, stride, count) = self.elements(acc, 12)?;
        Ok((0..count)
            .map(|i| {
                let e = &data[i * stride..i * stride + 12];
                let f = |k: usize| f32::from_le_bytes([e[k], e[k + 1], e[k + 2], e[k + 3]]);
                [f(0), f(4), f(8)]
            })
            .collect())
    }

    fn indices_of(&mut self, acc: &Accessor) -> Res<Vec<u32>> {
        let size = match (acc.data_type(), acc.dimensions()) {
            (DataType::U8, Dimensions::Scalar) => 1,
            (DataType::U16, Dimensions::Scalar) => 2,
            (DataType::U32, Dimensions::Scalar) => 4,
            (t, d) => return Err(format!("index accessor {} is {t:?} {d:?}, not an unsigned SCALAR", acc.index())),
        };
        let (data, stride, count) = self.elements(acc, size)?;
        Ok((0..count)
            .map(|i| {
                let e = &data[i * stride..];
                match size {
                    1 => e[0] as u32,
                    2 => u16::from_le_bytes([e[0], e[1]]) as u32,
                    _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                }
            })
            .collect())
    }

    /// The bytes of `acc` (from its first element to the end of its last), its stride and count,
    /// after checking that `count` elements of `size` bytes fit in its buffer view and the view in
    /// its buffer.
    fn elements(&mut self, acc: &Accessor, size: usize) -> Res<(&[u8], usize, usize)> {
        let id = acc.index();
        if acc.sparse().is_some() {
            return Err(format!("accessor {id} is sparse, which this loader does not read"));
        }
        let view = acc.view().ok_or_else(|| format!("accessor {id} has no bufferView"))?;
        let count = acc.count();
        if count == 0 {
            return Ok((&[], size, 0));
        }
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(format!("buffer view {}: stride {stride} is shorter than an element ({size})", view.index()));
        }
        let end =
            (count - 1).checked_mul(stride).and_then(|n| n.checked_add(size)).and_then(|n| n.checked_add(acc.offset()));
        if end.is_none_or(|e| e > view.length()) {
            return Err(format!(
                "accessor {id}: {count} elements from byte {} run past its buffer view's {} bytes",
                acc.offset(),
                view.length()
            ));
        }
        let b = view.buffer().index();
        let data = self.buffer(b)?;
        let vend = view.offset().checked_add(view.length());
        let Some(bytes) = vend.and_then(|e| data.get(view.offset()..e)) else {
            let len = data.len();
            return Err(format!("buffer view {} reaches past the {len} bytes of buffer {b}", view.index()));
        };
        Ok((&bytes[acc.offset()..], stride, count))
    }

    /// Buffer `i`: the GLB's binary chunk, a base64 `data:` URI, or a file beside the glTF file;
    /// refused when shorter than its declared `byteLength`.
    fn buffer(&mut self, i: usize) -> Res<&[u8]> {
        if self.buffers[i].is_none() {
            let buf = self.doc.buffers().nth(i).ok_or_else(|| format!("no buffer {i}"))?;
            if buf.length() == 0 {
                return Err(format!("buffer {i}: byteLength 0 (glTF requires at least 1)"));
            }
            let data: Vec<u8> = match buf.source() {
                Source::Bin => {
                    self.blob.ok_or_else(|| format!("buffer {i} has no uri and there is no GLB binary chunk"))?.to_vec()
                }
                Source::Uri(uri) if uri.starts_with("data:") => {
                    let (_, b64) = uri
                        .split_once(";base64,")
                        .ok_or_else(|| format!("buffer {i}: a data URI that is not base64"))?;
                    base64(b64).ok_or_else(|| format!("buffer {i}: its data URI is not valid base64"))?
                }
                Source::Uri(uri) => self.external(i, uri, buf.length())?,
            };
            if data.len() < buf.length() {
                return Err(format!("buffer {i} has {} bytes, {} declared", data.len(), buf.length()));
            }
            self.buffers[i] = Some(data);
        }
        Ok(self.buffers[i].as_deref().unwrap_or(&[]))
    }
}

/// One instance of `mesh`: its primitives, and the vertices and triangles of those with triangles,
/// as their accessors declare them (saturating: the limits refuse the sum).
fn mesh_expansion(mesh: &::gltf::Mesh) -> (u64, u64, u64) {
    let (mut prims, mut verts, mut tris) = (0u64, 0u64, 0u64);
    for prim in mesh.primitives() {
        prims += 1;
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            continue;
        }
        let n = prim.get(&Semantic::Positions).map_or(0, |a| a.count() as u64);
        let order = prim.indices().map_or(n, |a| a.count() as u64);
        verts = verts.saturating_add(n);
        tris = tris.saturating_add(match mode {
            Mode::Triangles => order / 3,
            _ => order.saturating_sub(2),
        });
    }
    (prims, verts, tris)
}

impl Loader<'_> {
    /// An external buffer file: `uri` (percent-decoded) must name a regular file inside the glTF
    /// file's folder. Refused without touching the file system: a URI with a scheme, an absolute
    /// path, a `..` component. Refused with one message that says nothing of what is there: a path
    /// that does not resolve (after symlinks) to a file inside the folder. A FIFO, device or socket
    /// is refused before it is opened ([`crate::fsio::read_regular_limited`]).
    fn external(&self, i: usize, uri: &str, declared: usize) -> Res<Vec<u8>> {
        let shown = crate::fsio::quote(uri);
        if uri.split('/').next().is_some_and(|s| s.contains(':')) {
            return Err(format!("buffer {i}: URI \"{shown}\" is not a relative file path"));
        }
        let decoded = percent_decode(uri);
        let rel = Path::new(&decoded);
        let escapes = decoded.contains('\0')
            || decoded.contains('\\')
            || rel.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir));
        let outside =
            || format!("buffer {i}: URI \"{shown}\" leads out of the glTF file's folder (buffers are files beside it)");
        if escapes {
            return Err(outside());
        }
        let unreadable = || format!("buffer {i}: URI \"{shown}\" is not a readable file in the glTF file's folder");
        let dir = if self.dir.as_os_str().is_empty() { Path::new(".") } else { self.dir };
        let folder = std::fs::canonicalize(dir).map_err(|_| unreadable())?;
        let file = std::fs::canonicalize(folder.join(rel)).map_err(|_| unreadable())?;
        if !file.starts_with(&folder) || file == folder {
            return Err(unreadable());
        }
        let data = crate::fsio::read_regular_limited(&file, super::MAX_MESH_FILE_BYTES)
            .map_err(|e| format!("buffer {i}: URI \"{shown}\": {e}"))?;
        if data.len() < declared {
            return Err(format!("buffer {i}: URI \"{shown}\" has {} bytes, {declared} declared", data.len()));
        }
        Ok(data)
    }
}

/// Standard (and URL-safe) base64, padding optional; `None` on any other character.
fn base64(s: &str) -> Option<Vec<u8>> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// `%XX` escapes of a relative URI decoded (others kept as they are).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |k: usize| b.get(k).and_then(|c| (*c as char).to_digit(16));
        match (b[i], hex(i + 1), hex(i + 2)) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}
