//! Wavefront OBJ through `tobj`, after [`surfaces_only`] has taken out what has no surface.

use std::path::Path;

use glam::Vec3;

use super::{file_name, Mesh};
use crate::error::{Error, Result};

impl Mesh {
    /// A Wavefront OBJ file, triangulated, every object in it. Normals the file gives for every
    /// vertex are used; otherwise they are computed ([`Mesh::from_triangles`]). Refuses (naming the
    /// file) a file that is not OBJ, has no triangles, uses a vertex it does not have, has a
    /// non-finite coordinate, or has all its vertices at one point.
    pub fn load_obj(path: &Path) -> Result<Mesh> {
        let origin = crate::fsio::show(path);
        let bytes = crate::fsio::read_limited(path, super::MAX_MESH_FILE_BYTES, "a mesh file")?;
        let bytes = surfaces_only(&bytes).map_err(|m| Error::input(&origin, m))?;
        let options =
            tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
        // Materials are not used: a `mtllib` line neither fails the load nor opens another file.
        let (models, _) =
            tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| Err(tobj::LoadError::OpenFileFailed))
                .map_err(|e| Error::input(&origin, format!("not a readable OBJ file: {e}")))?;
        let mut positions: Vec<Vec3> = Vec::new();
        let mut normals: Vec<Vec3> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut all_have_normals = true;
        for m in &models {
            let mesh = &m.mesh;
            let base = positions.len();
            let n = mesh.positions.len() / 3;
            for c in mesh.positions.chunks_exact(3) {
                let p = Vec3::new(c[0], c[1], c[2]);
                if !p.is_finite() {
                    // tobj renumbers vertices in `single_index` mode: the coordinates identify it.
                    let what = format!("a vertex has a non-finite coordinate: v {} {} {}", c[0], c[1], c[2]);
                    return Err(Error::input(&origin, what));
                }
                positions.push(p);
            }
            if mesh.normals.len() == mesh.positions.len() {
                normals.extend(mesh.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
            } else {
                all_have_normals = false;
            }
            if mesh.indices.len() % 3 != 0 {
                return Err(Error::input(&origin, "faces did not triangulate"));
            }
            for &i in &mesh.indices {
                if i as usize >= n {
                    let what = format!("a face uses vertex {} of {n}", i as u64 + 1);
                    return Err(Error::input(&origin, what));
                }
                let global =
                    u32::try_from(base + i as usize).map_err(|_| Error::input(&origin, "more than 2^32 vertices"))?;
                indices.push(global);
            }
        }
        if indices.is_empty() {
            return Err(Error::input(&origin, "no triangles (no faces with three or more vertices)"));
        }
        let normals = all_have_normals.then_some(normals);
        Mesh::from_triangles(&origin, file_name(path), positions, normals, indices)
    }
}

/// The OBJ text with its line (`l`) and point (`p`) elements blanked (they have no surface; `tobj`
/// would read `l a b c` as a triangle and blow up shorter ones into zero-area triangles), line
/// numbers kept. Refuses, naming the line, a face (`f`) of fewer than three vertices and a face
/// index that is 0 or refers past the vertices (`v`, `vt`, `vn`) of the file — before `tobj`, whose
/// index arithmetic overflows on such indices (found by `tests/fuzz.rs`).
pub(crate) fn surfaces_only(bytes: &[u8]) -> std::result::Result<Vec<u8>, String> {
    // Totals for positive indices (which may refer forward), running counts for negative ones.
    let mut total = [0usize; 3];
    for line in bytes.split(|&b| b == b'\n') {
        if let Some(k) = words(line).first().and_then(|w| kind(w)) {
            total[k] += 1;
        }
    }
    let mut seen = [0usize; 3];
    // The triangles tobj will make of the faces, before it allocates anything: a polygon of n
    // vertices is n − 2 triangles. (Its vertices, at most three per triangle, are bounded with them.)
    let mut triangles = 0u64;
    let mut out = Vec::with_capacity(bytes.len());
    for (no, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let w = words(line);
        match w.first().copied() {
            Some(b"l") | Some(b"p") => {}
            Some(b"f") => {
                let n = w.len() - 1;
                if n < 3 {
                    return Err(format!("line {}: a face needs at least three vertices, got {n}", no + 1));
                }
                triangles += n as u64 - 2;
                if triangles > super::MAX_TRIANGLES {
                    let limit = super::MAX_TRIANGLES;
                    return Err(format!(
                        "line {}: expands to {triangles} triangles, past the limit of {limit}",
                        no + 1
                    ));
                }
                for vertex in &w[1..] {
                    for (k, index) in vertex.split(|&b| b == b'/').enumerate().take(3) {
                        let Some(i) = std::str::from_utf8(index).ok().and_then(|t| t.parse::<i64>().ok()) else {
                            continue; // empty (`v//vn`) or not a number: tobj refuses the latter
                        };
                        let ok = if i > 0 {
                            i as u64 <= total[k] as u64
                        } else {
                            i != 0 && i.unsigned_abs() <= seen[k] as u64
                        };
                        if !ok {
                            let what = ["vertex", "texture coordinate", "normal"][k];
                            return Err(format!(
                                "line {}: face index {i} refers to no {what} (the file has {})",
                                no + 1,
                                total[k]
                            ));
                        }
                    }
                }
                out.extend_from_slice(line);
            }
            first => {
                if let Some(k) = first.and_then(kind) {
                    seen[k] += 1;
                }
                out.extend_from_slice(line)
            }
        }
        out.push(b'\n');
    }
    Ok(out)
}

/// `v`, `vt`, `vn` → 0, 1, 2 (the order of a face vertex's `v/vt/vn`).
fn kind(word: &[u8]) -> Option<usize> {
    match word {
        b"v" => Some(0),
        b"vt" => Some(1),
        b"vn" => Some(2),
        _ => None,
    }
}

/// The words of a line (runs without ASCII white space).
fn words(line: &[u8]) -> Vec<&[u8]> {
    line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty()).collect()
}
