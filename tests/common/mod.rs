//! Test data made on the spot, so the suite needs nothing beside the clone: the repository's assets
//! by path, and procedural meshes (subdivided icospheres, radially displaced into a creased blob)
//! written as OBJ into a temporary folder.

// Each test crate uses a different part of this module.
#![allow(dead_code)]

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A file of the repository's `assets/`, wherever the clone is.
pub fn asset(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets").join(rel)
}

/// Triangles over `f32` positions, counter-clockwise seen from outside.
#[derive(Clone, Debug)]
pub struct TriMesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// The unit icosphere: the icosahedron with every triangle split in four `level` times and the new
/// vertices pushed onto the sphere; `20 · 4^level` triangles, `10 · 4^level + 2` vertices.
pub fn icosphere(level: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|v| unit(*v))
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut split = |a: u32, b: u32, p: &mut Vec<[f64; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (x, y) = (p[a as usize], p[b as usize]);
                p.push(unit([x[0] + y[0], x[1] + y[1], x[2] + y[2]]));
                (p.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let (ab, bc, ca) = (split(a, b, &mut p), split(b, c, &mut p), split(c, a, &mut p));
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    TriMesh { positions: p.iter().map(|v| v.map(|x| x as f32)).collect(), triangles: tris }
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / l)
}

/// An icosphere displaced along its radius by `1 + 0.3 sin(3x + 1) sin(2y) sin(4z + 0.5)`: a closed,
/// star-shaped surface (so never self-intersecting) with bumps, hollows and creases — the many-triangle
/// stand-in for a scanned mesh.
pub fn blob(level: u32) -> TriMesh {
    let mut m = icosphere(level);
    for p in &mut m.positions {
        let [x, y, z] = p.map(f64::from);
        let r = 1.0 + 0.3 * (3.0 * x + 1.0).sin() * (2.0 * y).sin() * (4.0 * z + 0.5).sin();
        *p = [x * r, y * r, z * r].map(|v| v as f32);
    }
    m
}

/// Writes `m` as OBJ (positions and faces only) after `p ↦ scale · p + offset`; `inward` reverses
/// every triangle, so the loader's outward rule has to turn it back.
pub fn write_obj(path: &Path, m: &TriMesh, scale: f32, offset: [f32; 3], inward: bool) {
    let mut s = String::from("# procedural test mesh\n");
    for p in &m.positions {
        let q: Vec<f32> = (0..3).map(|k| scale * p[k] + offset[k]).collect();
        let _ = writeln!(s, "v {} {} {}", q[0], q[1], q[2]);
    }
    for [a, b, c] in &m.triangles {
        let (b, c) = if inward { (c, b) } else { (b, c) };
        let _ = writeln!(s, "f {} {} {}", a + 1, b + 1, c + 1);
    }
    std::fs::write(path, s).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
