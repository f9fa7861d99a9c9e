//! Wavefront OBJ through `tobj`.

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
        let origin = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
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
