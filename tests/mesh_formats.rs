//! Mesh files besides OBJ: PLY (ASCII, binary little and big endian) and glTF 2.0 (`.gltf` with a
//! base64 data URI or an external buffer, `.glb`). One procedural mesh (a subdivided icosphere,
//! `tests/common`) is written in every format into a temporary folder; each load must give the same
//! triangles, positions and normals as the OBJ of the same data, within stated tolerances. Then the
//! refusals (each names the file and says what is wrong) and two renders through the binary.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use brdf_shop::scene::Mesh;
use brdf_shop::Error;
use common::TriMesh;
use glam::{DMat3, DMat4, DQuat, DVec3, Vec3};
use serde_json::{json, Value};

/// Positions of two loads of the same data agree to this (both are normalised to radius 1 in `f64`
/// from `f32` inputs that differ by at most an `f32` rounding of the transform: a few ulp of 1).
const POS_TOL: f32 = 1e-5;
/// Unit normals agree to this (the inverse transpose in `f64` here and in the loader, each rounded
/// to `f32` once before normalisation).
const NORMAL_TOL: f32 = 1e-5;

/// Triangle `k`'s corners `(position, normal)` sorted by position, so that meshes whose loaders
/// number vertices differently (tobj renumbers them) or start a triangle at another corner compare.
fn corners(m: &Mesh) -> Vec<[(Vec3, Vec3); 3]> {
    m.indices
        .chunks_exact(3)
        .map(|t| {
            let mut c = [t[0], t[1], t[2]].map(|i| (m.positions[i as usize], m.normals[i as usize]));
            c.sort_by(|a, b| a.0.to_array().partial_cmp(&b.0.to_array()).unwrap());
            c
        })
        .collect()
}

/// Every triangle is wound counter-clockwise seen from the side its vertex normals point to.
fn assert_outward(m: &Mesh) {
    for (k, t) in m.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
        let n: Vec3 = t.iter().map(|&i| m.normals[i as usize]).sum();
        assert!((b - a).cross(c - a).dot(n) > 0.0, "{}: triangle {k} winds against its normals", m.name);
    }
}

fn assert_same(what: &str, got: &Mesh, want: &Mesh) {
    assert_eq!(got.triangle_count(), want.triangle_count(), "{what}: triangle count");
    let (g, w) = (corners(got), corners(want));
    let (mut dp, mut dn) = (0.0f32, 0.0f32);
    for (k, (a, b)) in g.iter().zip(&w).enumerate() {
        for c in 0..3 {
            dp = dp.max((a[c].0 - b[c].0).abs().max_element());
            dn = dn.max((a[c].1 - b[c].1).abs().max_element());
            assert!(dp < POS_TOL, "{what}: triangle {k} corner {c}: position {} vs {}", a[c].0, b[c].0);
            assert!(dn < NORMAL_TOL, "{what}: triangle {k} corner {c}: normal {} vs {}", a[c].1, b[c].1);
        }
    }
    assert_outward(got);
    eprintln!("{what}: {} triangles, worst position {dp:.1e}, worst normal {dn:.1e}", got.triangle_count());
}

// --- writers ---

fn obj(path: &Path, positions: &[[f32; 3]], normals: Option<&[[f32; 3]]>, tris: &[[u32; 3]]) {
    let mut s = String::new();
    for p in positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for n in normals.unwrap_or(&[]) {
        let _ = writeln!(s, "vn {} {} {}", n[0], n[1], n[2]);
    }
    for t in tris {
        let [a, b, c] = t.map(|i| i + 1);
        match normals {
            Some(_) => writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}"),
            None => writeln!(s, "f {a} {b} {c}"),
        }
        .unwrap();
    }
    std::fs::write(path, s).unwrap();
}

/// ASCII PLY with a colour property and an extra element to read past.
fn ply_ascii(path: &Path, m: &TriMesh, normals: Option<&[[f32; 3]]>) {
    let mut s = format!("ply\nformat ascii 1.0\ncomment test\nelement vertex {}\n", m.positions.len());
    s += "property float x\nproperty float y\nproperty float z\n";
    if normals.is_some() {
        s += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    s += &format!("property uchar red\nelement face {}\nproperty list uchar int vertex_indices\n", m.triangles.len());
    s += "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    for (k, p) in m.positions.iter().enumerate() {
        let _ = write!(s, "{} {} {}", p[0], p[1], p[2]);
        if let Some(n) = normals {
            let _ = write!(s, " {} {} {}", n[k][0], n[k][1], n[k][2]);
        }
        s += " 200\n";
    }
    for t in &m.triangles {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s += "0 1\n";
    std::fs::write(path, s).unwrap();
}

/// Binary PLY: little endian with `float` coordinates and a `uint` index list, or big endian with
/// `double` coordinates and `int` indices; a trailing `uchar` after the list in both.
fn ply_binary(path: &Path, m: &TriMesh, big: bool) -> Vec<u8> {
    let (fmt, coord, idx) = if big { ("big", "double", "int") } else { ("little", "float", "uint") };
    let mut b = format!(
        "ply\nformat binary_{fmt}_endian 1.0\nelement vertex {}\nproperty {coord} x\nproperty {coord} y\n\
         property {coord} z\nelement face {}\nproperty list uchar {idx} vertex_index\nproperty uchar flags\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )
    .into_bytes();
    let put = |b: &mut Vec<u8>, le: &[u8]| {
        let mut v = le.to_vec();
        if big {
            v.reverse();
        }
        b.extend_from_slice(&v);
    };
    for p in &m.positions {
        for x in p {
            if big {
                put(&mut b, &(*x as f64).to_le_bytes());
            } else {
                put(&mut b, &x.to_le_bytes());
            }
        }
    }
    for t in &m.triangles {
        b.push(3);
        for i in t {
            put(&mut b, &i.to_le_bytes());
        }
        b.push(7);
    }
    std::fs::write(path, &b).unwrap();
    b
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            s.push(if k <= c.len() { A[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' });
        }
    }
    s
}

#[derive(Clone, Copy, Debug)]
enum Indices {
    None,
    U8,
    U16,
    U32,
}

/// A glTF document over one binary buffer: positions, optional normals, optional indices of the
/// given type; one mesh under `nodes` (node 0 the root). Returns the JSON (buffer 0 without a uri)
/// and the buffer.
fn gltf_doc(m: &TriMesh, normals: Option<&[[f32; 3]]>, idx: Indices, nodes: Value) -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    let f32s = |bin: &mut Vec<u8>, v: &[[f32; 3]]| v.iter().flatten().for_each(|x| bin.extend(x.to_le_bytes()));
    f32s(&mut bin, &m.positions);
    let n = m.positions.len();
    let lo = (0..3).map(|k| m.positions.iter().map(|p| p[k]).fold(f32::MAX, f32::min)).collect::<Vec<_>>();
    let hi = (0..3).map(|k| m.positions.iter().map(|p| p[k]).fold(f32::MIN, f32::max)).collect::<Vec<_>>();
    let mut views = vec![json!({"buffer": 0, "byteOffset": 0, "byteLength": 12 * n})];
    let mut accessors =
        vec![json!({"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi})];
    let mut attributes = json!({"POSITION": 0});
    if let Some(ns) = normals {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": 12 * n}));
        f32s(&mut bin, ns);
        accessors.push(json!({"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"}));
        attributes["NORMAL"] = json!(1);
    }
    let mut primitive = json!({"attributes": attributes, "mode": 4});
    let flat: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    let (ctype, size) = match idx {
        Indices::None => (0, 0),
        Indices::U8 => (5121, 1),
        Indices::U16 => (5123, 2),
        Indices::U32 => (5125, 4),
    };
    if size > 0 {
        let start = bin.len();
        for i in &flat {
            bin.extend_from_slice(&i.to_le_bytes()[..size]);
        }
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": bin.len() - start}));
        accessors.push(
            json!({"bufferView": views.len() - 1, "componentType": ctype, "count": flat.len(), "type": "SCALAR"}),
        );
        primitive["indices"] = json!(accessors.len() - 1);
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": [{"primitives": [primitive]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    (doc, bin)
}

fn write_gltf(path: &Path, mut doc: Value, bin: &[u8]) {
    doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64(bin)));
    std::fs::write(path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
}

fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(doc).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut b = Vec::new();
    b.extend_from_slice(b"glTF");
    b.extend_from_slice(&2u32.to_le_bytes());
    b.extend_from_slice(&(total as u32).to_le_bytes());
    b.extend_from_slice(&(j.len() as u32).to_le_bytes());
    b.extend_from_slice(b"JSON");
    b.extend_from_slice(&j);
    b.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    b.extend_from_slice(b"BIN\0");
    b.extend_from_slice(bin);
    b
}

/// The node tree of the tests: a root with translation and rotation, its child with a non-uniform
/// scale (mirrored in x when `mirror`) holding mesh 0; returns the tree and the child's world matrix.
fn nodes(mirror: bool) -> (Value, DMat4) {
    let (t, q) = (DVec3::new(1.0, -2.0, 0.5), DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7));
    let s = DVec3::new(if mirror { -2.0 } else { 2.0 }, 0.5, 1.5);
    let q32 = q.as_quat();
    let tree = json!([
        {"children": [1], "translation": [t.x, t.y, t.z], "rotation": [q32.x, q32.y, q32.z, q32.w]},
        {"mesh": 0, "scale": [s.x, s.y, s.z]},
    ]);
    let world = DMat4::from_rotation_translation(q32.as_dquat(), t) * DMat4::from_scale(s);
    (tree, world)
}

/// `m` under `world`, and its unit-sphere normals under the inverse transpose, as `f32`.
fn transformed(m: &TriMesh, world: DMat4) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let nm = DMat3::from_mat4(world).inverse().transpose();
    let p = m.positions.iter().map(|p| world.transform_point3(Vec3::from(*p).as_dvec3()).as_vec3().to_array());
    let n = m.positions.iter().map(|p| (nm * Vec3::from(*p).as_dvec3()).normalize().as_vec3().to_array());
    (p.collect(), n.collect())
}

fn load(path: &Path) -> Mesh {
    Mesh::resolve(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn ply_files_load_like_the_obj() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let m = common::icosphere(2);
    // The unit sphere's normals are its positions.
    let normals = m.positions.clone();
    obj(&d("ico.obj"), &m.positions, None, &m.triangles);
    obj(&d("ico-n.obj"), &m.positions, Some(&normals), &m.triangles);
    let (plain, with_normals) = (load(&d("ico.obj")), load(&d("ico-n.obj")));
    ply_ascii(&d("ascii.ply"), &m, None);
    ply_ascii(&d("ascii-n.PLY"), &m, Some(&normals));
    ply_binary(&d("le.ply"), &m, false);
    ply_binary(&d("be.ply"), &m, true);
    assert_same("ascii.ply", &load(&d("ascii.ply")), &plain);
    assert_same("ascii-n.PLY", &load(&d("ascii-n.PLY")), &with_normals);
    assert_same("le.ply", &load(&d("le.ply")), &plain);
    assert_same("be.ply", &load(&d("be.ply")), &plain);
    // Quads with integer coordinates, off centre, wound inward: fan-triangulated like tobj does,
    // turned outward, centred and scaled.
    let v = "0 0 0\n4 0 0\n4 4 0\n0 4 0\n0 0 4\n4 0 4\n4 4 4\n0 4 4\n";
    let quads = ["0 1 2 3", "4 7 6 5", "0 4 5 1", "1 5 6 2", "2 6 7 3", "3 7 4 0"];
    let mut ply = String::from("ply\nformat ascii 1.0\nelement vertex 8\nproperty short x\nproperty short y\n");
    ply += "property short z\nelement face 6\nproperty list uchar ushort vertex_indices\nend_header\n";
    ply += v;
    let mut objs: String = v.lines().map(|l| format!("v {l}\n")).collect();
    for q in quads {
        ply += &format!("4 {q}\n");
        objs += &format!(
            "f {}\n",
            q.split(' ').map(|i| (i.parse::<u32>().unwrap() + 1).to_string()).collect::<Vec<_>>().join(" ")
        );
    }
    std::fs::write(d("cube.ply"), ply).unwrap();
    std::fs::write(d("cube.obj"), objs).unwrap();
    let cube = load(&d("cube.ply"));
    assert_eq!(cube.triangle_count(), 12);
    assert_same("cube.ply", &cube, &load(&d("cube.obj")));
    assert!(cube.positions.iter().all(|p| (p.abs() - Vec3::splat(1.0 / 3f32.sqrt())).abs().max_element() < 1e-6));
}

/// The glTF node tree's world transform (translation, rotation, non-uniform scale, with and without
/// a mirror) is applied to positions, and its inverse transpose to the file's normals; indices of
/// every type and none give the same triangles. The OBJ references hold the same positions
/// transformed here (unshared per triangle for the non-indexed files, as they are in those).
#[test]
fn gltf_files_apply_their_node_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let m = common::icosphere(2);
    assert!(m.positions.len() <= 256, "u8 indices need at most 256 vertices");
    let unshared = TriMesh {
        positions: m.triangles.iter().flatten().map(|&i| m.positions[i as usize]).collect(),
        triangles: (0..m.triangles.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
    };
    for mirror in [false, true] {
        let (tree, world) = nodes(mirror);
        let tag = if mirror { "mirrored" } else { "plain" };
        for idx in [Indices::None, Indices::U8, Indices::U16, Indices::U32] {
            let mesh = if matches!(idx, Indices::None) { &unshared } else { &m };
            let (p, n) = transformed(mesh, world);
            let name = format!("{tag}-{idx:?}");
            obj(&d(&format!("{name}.obj")), &p, None, &mesh.triangles);
            obj(&d(&format!("{name}-n.obj")), &p, Some(&n), &mesh.triangles);
            for normals in [false, true] {
                let file_normals = normals.then_some(&mesh.positions[..]);
                let (doc, bin) = gltf_doc(mesh, file_normals, idx, tree.clone());
                let want = load(&d(&format!("{name}{}.obj", if normals { "-n" } else { "" })));
                let name = format!("{name}-{}", if normals { "n" } else { "computed" });
                let gltf = d(&format!("{name}.gltf"));
                write_gltf(&gltf, doc.clone(), &bin);
                assert_same(&format!("{name}.gltf"), &load(&gltf), &want);
                let path = d(&format!("{name}.glb"));
                std::fs::write(&path, glb(&doc, &bin)).unwrap();
                assert_same(&format!("{name}.glb"), &load(&path), &want);
            }
        }
    }
    // An external buffer beside the file, its URI percent-encoded.
    let (tree, _) = nodes(false);
    let (mut doc, bin) = gltf_doc(&m, None, Indices::U16, tree);
    doc["buffers"][0]["uri"] = json!("mesh%20data.bin");
    std::fs::write(d("mesh data.bin"), &bin).unwrap();
    std::fs::write(d("external.gltf"), doc.to_string()).unwrap();
    assert_same("external.gltf", &load(&d("external.gltf")), &load(&d("plain-U16.obj")));
}

/// Broken files of both formats: one error each, naming the file and what is wrong.
#[test]
fn bad_mesh_files_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let m = common::icosphere(1);
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    let face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let verts = "0 0 0\n1 0 0\n0 1 0\n";
    let le = ply_binary(&d("whole.ply"), &m, false);
    let huge = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n\
                property float z\nend_header\n\0\0\0\0";
    let ply_cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("not.ply", b"hello\n".to_vec(), "not a PLY file"),
        ("no_end.ply", head.as_bytes().to_vec(), "end_header"),
        (
            "type.ply",
            format!("{}property float128 w\n{face}{verts}3 0 1 2\n", head).into_bytes(),
            "unknown property type",
        ),
        ("format.ply", b"ply\nformat binary_middle_endian 1.0\nend_header\n".to_vec(), "unknown format"),
        ("huge.ply", huge.as_bytes().to_vec(), "4000000000"),
        (
            "count.ply",
            format!("{}{face}{verts}3 0 1 2\n", head.replace("vertex 3", "vertex 10")).into_bytes(),
            "can hold",
        ),
        ("truncated.ply", le[..le.len() - 50].to_vec(), "truncated"),
        ("range.ply", format!("{head}{face}{verts}3 0 1 7\n").into_bytes(), "uses vertex 7 of 3"),
        ("nan.ply", format!("{head}{face}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n").into_bytes(), "non-finite"),
        ("token.ply", format!("{head}{face}0 0 0\n1 zebra 0\n0 1 0\n3 0 1 2\n").into_bytes(), "not a number"),
        (
            "xyz.ply",
            format!("{}{face}{verts}3 0 1 2\n", head.replace("property float z", "property float w")).into_bytes(),
            "x, y and z",
        ),
        ("no_faces.ply", format!("{head}end_header\n{verts}").into_bytes(), "no triangles"),
        ("lines.ply", format!("{head}{face}{verts}2 0 1\n").into_bytes(), "no triangles"),
        (
            "list.ply",
            format!("{head}element face 1\nproperty list float int vertex_indices\nend_header\n{verts}3 0 1 2\n")
                .into_bytes(),
            "integer type",
        ),
    ];
    let (tree, _) = nodes(false);
    let (doc, bin) = gltf_doc(&m, None, Indices::U16, tree);
    let with_uri = |mut doc: Value| {
        doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64(&bin)));
        doc
    };
    let good = with_uri(doc.clone());
    let edit = |f: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        f(&mut v);
        v.to_string().into_bytes()
    };
    let whole = glb(&doc, &bin);
    let mut nan_bin = bin.clone();
    nan_bin[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut nan_doc = doc.clone();
    nan_doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64(&nan_bin)));
    let nv = m.positions.len();
    let mut range_bin = bin.clone();
    let istart = good["bufferViews"][1]["byteOffset"].as_u64().unwrap() as usize;
    range_bin[istart..istart + 2].copy_from_slice(&(nv as u16 + 5).to_le_bytes());
    let mut range_doc = doc.clone();
    range_doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64(&range_bin)));
    let range_msg = format!("index {} of a primitive with {nv} vertices", nv + 5);
    let gltf_cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("garbage.gltf", b"{ not json".to_vec(), "not a readable glTF"),
        ("truncated.glb", whole[..whole.len() / 2].to_vec(), "not a readable glTF"),
        ("missing.gltf", edit(&|v| v["buffers"][0]["uri"] = json!("missing.bin")), "missing.bin"),
        ("short.gltf", edit(&|v| v["buffers"][0]["byteLength"] = json!(100_000)), "100000 declared"),
        ("past.gltf", edit(&|v| v["accessors"][0]["count"] = json!(1000)), "run past"),
        ("huge.gltf", edit(&|v| v["accessors"][0]["count"] = json!(4_000_000_000u64)), "past the limit"),
        ("view.gltf", edit(&|v| v["bufferViews"][0]["byteLength"] = json!(1_000_000)), "reaches past"),
        ("nan.gltf", nan_doc.to_string().into_bytes(), "non-finite"),
        ("range.gltf", range_doc.to_string().into_bytes(), &range_msg),
        ("points.gltf", edit(&|v| v["meshes"][0]["primitives"][0]["mode"] = json!(0)), "points or lines"),
        (
            "no_scene.gltf",
            edit(&|v| {
                v.as_object_mut().unwrap().remove("scenes");
                v.as_object_mut().unwrap().remove("scene");
            }),
            "no scene",
        ),
        ("cycle.gltf", edit(&|v| v["nodes"][1]["children"] = json!([0])), "not a tree"),
        (
            "sparse.gltf",
            edit(&|v| {
                v["accessors"][0]["sparse"] = json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}})
            }),
            "sparse",
        ),
        ("type.gltf", edit(&|v| v["accessors"][0]["componentType"] = json!(5123)), "POSITION"),
    ];
    for (name, bytes, why) in ply_cases.iter().chain(&gltf_cases) {
        let path = d(name);
        std::fs::write(&path, bytes).unwrap();
        let e = Mesh::resolve(path.to_str().unwrap()).map(|m| m.triangle_count()).unwrap_err();
        let msg = e.to_string();
        eprintln!("{msg}");
        assert!(matches!(e, Error::Input { .. }), "{name}: {e:?}");
        assert!(msg.contains(name), "{name}: message does not name the file: {msg}");
        assert!(msg.contains(why), "{name}: message does not say {why:?}: {msg}");
        assert!(!msg.contains('\n'), "{name}: more than one line: {msg}");
    }
    let e = Mesh::resolve(d("mesh.stl").to_str().unwrap()).unwrap_err();
    assert!(e.to_string().contains("mesh.stl") && e.to_string().contains(".ply"), "{e}");
    let e = Mesh::resolve(d("absent.glb").to_str().unwrap()).unwrap_err();
    assert!(matches!(e, Error::Io { .. }) && e.to_string().contains("absent.glb"), "{e:?}");
}

// --- through the binary ---

fn render(mesh: &Path, out: &Path) -> (i32, String) {
    let env = common::asset("hdri/city.exr");
    let o = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(["render", "--mesh", mesh.to_str().unwrap(), "--env", env.to_str().unwrap()])
        .args(["--size", "32x32", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Pixels with alpha (coverage) above one half.
fn coverage(path: &Path) -> usize {
    common::read_exr(path).pixels.iter().filter(|p| p[3] > 0.5).count()
}

/// A `.ply` and a `.glb` render through the real binary and cover what the OBJ of the same mesh
/// covers (the icosphere, radius 1/√3 once its bounding box has half-diagonal 1: 240 of 1024
/// pixels at the default camera, measured; the formats give the same triangles, so the counts agree
/// to a pixel of rounding); a broken file is refused in one line with nothing written.
#[test]
fn ply_and_glb_render_through_the_binary() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let m = common::icosphere(3);
    obj(&d("ico.obj"), &m.positions, None, &m.triangles);
    ply_binary(&d("ico.ply"), &m, false);
    let (doc, bin) = gltf_doc(&m, Some(&m.positions), Indices::U32, json!([{"mesh": 0}]));
    std::fs::write(d("ico.glb"), glb(&doc, &bin)).unwrap();
    let mut counts = Vec::new();
    for f in ["ico.obj", "ico.ply", "ico.glb"] {
        let out: PathBuf = d(&format!("{f}.exr"));
        let (code, stderr) = render(&d(f), &out);
        assert_eq!(code, 0, "{f}: {stderr}");
        counts.push(coverage(&out));
    }
    eprintln!("covered pixels obj/ply/glb: {counts:?}");
    assert!(counts[0] > 150, "{counts:?}");
    assert!(counts.iter().all(|c| c.abs_diff(counts[0]) <= 1), "{counts:?}");
    std::fs::write(d("bad.ply"), "ply\nformat ascii 1.0\nelement vertex 1000\nproperty float x\nend_header\n").unwrap();
    let out = d("bad.exr");
    let (code, stderr) = render(&d("bad.ply"), &out);
    assert_eq!(code, 1, "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("bad.ply") && !stderr.contains("panicked"), "{stderr}");
    assert!(!out.exists());
}
