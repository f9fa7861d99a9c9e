//! Meshes: the built-in `sphere` (fine enough that tessellation is invisible at 1024²) and `torus`
//! (the paper's Figure 2), and mesh files, one loader per format: Wavefront OBJ (`obj.rs`, through
//! `tobj`), glTF 2.0 (`gltf.rs`, `.gltf` and `.glb`) and PLY (`ply.rs`, ASCII and binary). Every file
//! goes through [`Mesh::from_triangles`]: area-weighted normals (outward winding) where the file has
//! none, centred on its bounding-box centre and scaled so its bounding sphere (half the box
//! diagonal) has radius 1, so the default camera frames any of them. Tangents are not stored (and
//! never derived from UVs, which are not read): the shading frame comes from the interpolated normal
//! by the rule of docs/model.md, Frames and conventions.

mod closure;
mod gltf;
mod obj;
mod ply;

use std::path::Path;

use glam::{DVec3, Vec3};

use crate::error::{Error, Result};

pub use closure::Hidden;

/// The largest mesh file (and glTF buffer file) read, in bytes, checked before it is read: a
/// million-triangle OBJ is about 60 MB, and loading takes roughly ten times the file's size in
/// memory at worst (OBJ text → positions, indices, normals), so 256 MiB keeps a load within a few GB.
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;

/// The most triangles a mesh file may expand to, counted before anything of that size is allocated
/// (in glTF, every reuse of an accessor, mesh or node counts again): 16 × the benchmark's largest
/// mesh (1 M triangles). At the limit the indices alone take 192 MiB, the loaders, the reference
/// renderer's ray-casting structure and the GPU buffers a few times that.
pub const MAX_TRIANGLES: u64 = 1 << 24;

/// The most vertices a mesh file may expand to (counted like [`MAX_TRIANGLES`]): as many as
/// triangles, 24 bytes each (position and normal) and about as much again while loading.
pub const MAX_VERTICES: u64 = 1 << 24;

/// The most primitives a glTF scene may draw, counting a mesh once per node that draws it: a million,
/// far past any real scene, so that a file reusing a mesh of many empty primitives (points, no
/// triangles) cannot make the loader walk them for hours.
pub const MAX_PRIMITIVE_INSTANCES: u64 = 1 << 20;

/// Refuses `vertices` or `triangles` past [`MAX_VERTICES`] / [`MAX_TRIANGLES`], the message naming
/// the limit.
pub(crate) fn check_expansion(vertices: u64, triangles: u64) -> std::result::Result<(), String> {
    if triangles > MAX_TRIANGLES {
        return Err(format!("expands to {triangles} triangles or more, past the limit of {MAX_TRIANGLES}"));
    }
    if vertices > MAX_VERTICES {
        return Err(format!("expands to {vertices} vertices or more, past the limit of {MAX_VERTICES}"));
    }
    Ok(())
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Unit, per vertex.
    pub normals: Vec<Vec3>,
    /// Triangles, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Unit sphere, 128 rings of latitude from pole to pole (Δθ = π/128), each ring of latitude θ cut
    /// into `⌈256 sin θ⌉` equal segments (so no segment is longer than the equator's 2π/256), the
    /// poles single vertices; neighbouring rings joined by the shorter diagonal at each step (41,848
    /// triangles). A flat triangle sags below the sphere by at most `(Δφ² + Δθ²)/8 = 1.5e-4`
    /// (Δ = 2π/256 = π/128), at the equator, which at 1024² with the default camera (radius about
    /// 495 px) is under 0.08 px; the silhouette, along edges, deviates by `Δ²/8`: under 0.04 px.
    /// The same worst sag as the 256 × 128 UV sphere (`Mesh::uv_sphere`, 65,024 triangles), whose
    /// rings near the poles hold 256 segments each, far shorter than the equator's; on llvmpipe a
    /// G-buffer pass costs about a triangle's setup and its pixels' blocks per triangle drawn, so the
    /// fewer triangles rasterise the same pixels faster (docs/renderer.md, Alternatives measured and
    /// rejected).
    pub fn sphere() -> Mesh {
        let (seg, rings) = (256u32, 128u32);
        let mut positions = Vec::new();
        // Each ring's first vertex and segment count (0 at a pole, a single vertex); a ring's last
        // vertex repeats its first (φ = 2π).
        let mut ring = Vec::with_capacity(rings as usize + 1);
        for r in 0..=rings {
            let theta = std::f64::consts::PI * f64::from(r) / f64::from(rings);
            let n = if r == 0 || r == rings { 0 } else { ((f64::from(seg) * theta.sin()).ceil() as u32).clamp(3, seg) };
            ring.push((positions.len() as u32, n));
            for s in 0..=n {
                let phi = 2.0 * std::f64::consts::PI * f64::from(s) / f64::from(n.max(1));
                let p = DVec3::new(theta.sin() * phi.sin(), theta.cos(), theta.sin() * phi.cos());
                positions.push(p.as_vec3());
            }
        }
        let normals = positions.iter().map(|p| p.normalize()).collect();
        let mut indices = Vec::new();
        for pair in ring.windows(2) {
            let ((a, na), (b, nb)) = (pair[0], pair[1]);
            let (mut i, mut j) = (0, 0);
            // Counter-clockwise seen from outside: (upper i, lower j, upper i + 1) and (upper i,
            // lower j, lower j + 1); a pole (no segments) is the apex of the other ring's fan.
            while i < na || j < nb {
                let upper = if na == 0 {
                    false
                } else if nb == 0 || j == nb {
                    true
                } else if i == na {
                    false
                } else {
                    let d = |x: u32, y: u32| (positions[x as usize] - positions[y as usize]).as_dvec3().length();
                    d(a + i + 1, b + j) <= d(a + i, b + j + 1)
                };
                if upper {
                    indices.extend_from_slice(&[a + i, b + j, a + i + 1]);
                    i += 1;
                } else {
                    indices.extend_from_slice(&[a + i, b + j, b + j + 1]);
                    j += 1;
                }
            }
        }
        Mesh { name: "sphere".into(), positions, normals, indices }
    }

    /// A unit UV sphere with `seg` segments around and `rings` from pole to pole (at least 3 and 2):
    /// `2·seg·(rings − 1)` triangles. The benchmark's meshes of 1 k … 1 M triangles.
    pub fn uv_sphere(seg: u32, rings: u32) -> Mesh {
        let (seg, rings) = (seg.max(3), rings.max(2));
        let mut positions = Vec::new();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=seg {
                let phi = 2.0 * std::f32::consts::PI * s as f32 / seg as f32;
                positions.push(Vec3::new(theta.sin() * phi.sin(), theta.cos(), theta.sin() * phi.cos()));
            }
        }
        let normals = positions.iter().map(|p| p.normalize()).collect();
        // Row 0 touches the north pole and row `rings − 1` the south pole with a zero-length edge:
        // the first triangle of each quad in row 0 and the second in the last row are degenerate.
        let tris_per_row = 2 * seg as usize;
        let last = rings as usize - 1;
        let indices = grid_indices(seg, rings, false)
            .chunks_exact(3)
            .enumerate()
            .filter(|(t, _)| {
                let (row, second) = (t / tris_per_row, t % 2 == 1);
                !((row == 0 && !second) || (row == last && second))
            })
            .flat_map(|(_, tri)| tri.iter().copied())
            .collect();
        Mesh { name: format!("sphere-{seg}x{rings}"), positions, normals, indices }
    }

    /// The paper's Figure 2 torus: ring in the `xz` plane (axis `y`), major radius 0.7, minor 0.3.
    pub fn torus() -> Mesh {
        let (major, minor) = (0.7f32, 0.3f32);
        let (seg, rings) = (256u32, 96u32);
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        for r in 0..=rings {
            let v = 2.0 * std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=seg {
                let u = 2.0 * std::f32::consts::PI * s as f32 / seg as f32;
                let centre = Vec3::new(major * u.sin(), 0.0, major * u.cos());
                let out = Vec3::new(v.cos() * u.sin(), v.sin(), v.cos() * u.cos());
                positions.push(centre + minor * out);
                normals.push(out);
            }
        }
        // `v` grows upward on the outer equator where the sphere's `θ` grows downward: the opposite
        // diagonal order keeps the triangles counter-clockwise from outside.
        Mesh { name: "torus".into(), positions, normals, indices: grid_indices(seg, rings, true) }
    }

    /// `sphere`, `torus`, or a mesh file (OBJ, glTF, PLY; see [`Mesh::load`]): what `--mesh` and
    /// the editor's file drop take.
    pub fn resolve(arg: &str) -> Result<Mesh> {
        match arg {
            "sphere" => Ok(Mesh::sphere()),
            "torus" => Ok(Mesh::torus()),
            path => Mesh::load(Path::new(path)),
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// A mesh file, by its extension (any case): `.obj` (Wavefront OBJ), `.gltf` / `.glb` (glTF 2.0)
    /// or `.ply` (ASCII or binary). Every loader ends in [`Mesh::from_triangles`], so every format
    /// is centred, scaled and given normals the same way.
    pub fn load(path: &Path) -> Result<Mesh> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        match ext.as_str() {
            "obj" => Mesh::load_obj(path),
            "gltf" | "glb" => Mesh::load_gltf(path),
            "ply" => Mesh::load_ply(path),
            _ => Err(Error::input(
                path.display().to_string(),
                "not a mesh file this program reads (expected .obj, .gltf, .glb or .ply)",
            )),
        }
    }

    /// Whether `path` names a mesh file [`Mesh::load`] reads (by extension).
    pub fn is_mesh_file(path: &Path) -> bool {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        matches!(ext.as_str(), "obj" | "gltf" | "glb" | "ply")
    }

    /// The end of every loader: refuses (naming `origin`) an empty triangle list, a non-finite
    /// coordinate and a mesh whose vertices are all at one point; centres the mesh on its bounding-box
    /// centre and scales it to bounding radius 1. `normals` (one per vertex, from the file) are used
    /// when every one is finite and non-zero; otherwise the normals are the area-weighted face
    /// normals, after the winding is made outward (a closed mesh whose signed volume is negative is
    /// wound inward and gets flipped). Indices must be in range (the loaders check them, naming the
    /// face).
    pub fn from_triangles(
        origin: &str,
        name: String,
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        mut indices: Vec<u32>,
    ) -> Result<Mesh> {
        if indices.is_empty() || indices.len() % 3 != 0 {
            return Err(Error::input(origin, "no triangles"));
        }
        check_expansion(positions.len() as u64, indices.len() as u64 / 3).map_err(|m| Error::input(origin, m))?;
        if let Some(k) = indices.iter().position(|&i| i as usize >= positions.len()) {
            let what = format!("triangle {} uses vertex {} of {}", k / 3, indices[k], positions.len());
            return Err(Error::input(origin, what));
        }
        if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
            return Err(Error::input(origin, format!("a vertex has a non-finite coordinate: {p}")));
        }
        let (lo, hi) = positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        // In f64: the diagonal of a box near f32::MAX would overflow f32.
        let (lo64, hi64) = (lo.as_dvec3(), hi.as_dvec3());
        let radius = (hi64 - lo64).length() / 2.0;
        if !(radius > 0.0) {
            return Err(Error::input(origin, "degenerate: all vertices are at one point"));
        }
        let centre = (lo64 + hi64) / 2.0;
        let positions: Vec<Vec3> = positions.iter().map(|p| ((p.as_dvec3() - centre) / radius).as_vec3()).collect();
        let usable = normals
            .as_ref()
            .filter(|n| n.len() == positions.len() && n.iter().all(|n| n.is_finite() && n.length() > 1e-12));
        let normals = match usable {
            Some(n) => n.iter().map(|n| n.normalize()).collect(),
            None => {
                if signed_volume(&positions, &indices) < 0.0 {
                    for t in indices.chunks_exact_mut(3) {
                        t.swap(1, 2);
                    }
                }
                area_normals(&positions, &indices)
            }
        };
        Ok(Mesh { name, positions, normals, indices })
    }
}

/// The file name shown as a mesh's name.
fn file_name(path: &Path) -> String {
    path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| path.display().to_string())
}

/// Six times the signed volume enclosed by the triangles (positive when they wind counter-clockwise
/// seen from outside a closed surface).
fn signed_volume(positions: &[Vec3], indices: &[u32]) -> f64 {
    indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize].as_dvec3());
            a.dot(b.cross(c))
        })
        .sum()
}

/// Triangles of a `(seg+1) × (rings+1)` vertex grid, two per quad, row by row; `flip` reverses the
/// winding.
fn grid_indices(seg: u32, rings: u32, flip: bool) -> Vec<u32> {
    let mut idx = Vec::new();
    let w = seg + 1;
    for r in 0..rings {
        for s in 0..seg {
            let (a, b, c, d) = (r * w + s, r * w + s + 1, (r + 1) * w + s, (r + 1) * w + s + 1);
            if flip {
                idx.extend_from_slice(&[a, b, c, b, d, c]);
            } else {
                idx.extend_from_slice(&[a, c, b, b, c, d]);
            }
        }
    }
    idx
}

/// Per-vertex normals as the area-weighted sum of the incident faces' normals; a vertex of only
/// degenerate faces gets `+y`.
fn area_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    // Accumulated in f64 so tiny triangles of fine meshes neither underflow nor lose precision.
    let mut acc = vec![DVec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize].as_dvec3());
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[i as usize] += n;
        }
    }
    acc.into_iter().map(|n| if n.length() > 0.0 && n.is_finite() { n.normalize().as_vec3() } else { Vec3::Y }).collect()
}
