//! Which faces of a mesh the rasteriser may skip. A surface that is closed and consistently oriented
//! (after welding vertices within [`WELD`] of each other: UV seams and split normals leave
//! duplicates, computed along different paths) hides
//! every face turned away from an eye outside it behind one turned towards it, so skipping those
//! faces leaves the image unchanged. Anything else — an open surface (a hole shows its inside), an
//! edge shared by more than two faces, faces wound against their neighbours — keeps every face.
//! Faces of zero area after welding are left out of the check.

use std::collections::HashMap;

use super::Mesh;

/// The faces that cannot be seen from outside the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hidden {
    /// None can be skipped.
    None,
    /// Faces wound clockwise seen from the eye (the mesh is wound counter-clockwise from outside).
    Clockwise,
    /// Faces wound counter-clockwise seen from the eye (the mesh is wound inward).
    CounterClockwise,
}

impl Mesh {
    /// See the module: which faces a camera outside the mesh's bounding sphere never sees.
    pub fn hidden_faces(&self) -> Hidden {
        let id = weld(&self.positions);
        let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.indices.len());
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| id[i as usize]);
            if a == b || b == c || a == c {
                // Zero area (a UV sphere's pole row): nothing to see, nothing to close.
                continue;
            }
            for e in [(a, b), (b, c), (c, a)] {
                *edges.entry(e).or_insert(0) += 1;
            }
        }
        let closed = edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1));
        if !closed {
            return Hidden::None;
        }
        let volume: f64 = self
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize].as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        if volume > 0.0 {
            Hidden::Clockwise
        } else if volume < 0.0 {
            Hidden::CounterClockwise
        } else {
            Hidden::None
        }
    }
}

/// Vertices closer than this (the meshes are scaled to bounding radius 1) are one vertex for the
/// check: 1e-5 is far above the f32 rounding of a seam computed two ways (~1e-7) and far below any
/// edge of a mesh worth rendering.
pub const WELD: f32 = 1e-5;

/// For each vertex, the index of the first vertex within [`WELD`] of it (a grid of cells of that
/// size; the 27 cells around a vertex hold every vertex that close).
fn weld(positions: &[glam::Vec3]) -> Vec<u32> {
    let cell = |p: glam::Vec3| (p / WELD).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::with_capacity(positions.len());
    let mut id = Vec::with_capacity(positions.len());
    for (i, &p) in positions.iter().enumerate() {
        let c = cell(p);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    for &j in grid.get(&(c + glam::IVec3::new(dx, dy, dz))).map_or(&[][..], |v| v.as_slice()) {
                        if positions[j as usize].distance(p) <= WELD {
                            found = Some(j);
                            break 'search;
                        }
                    }
                }
            }
        }
        let j = found.unwrap_or(i as u32);
        if found.is_none() {
            grid.entry(c).or_default().push(j);
        }
        id.push(j);
    }
    id
}
