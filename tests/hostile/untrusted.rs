//! Untrusted files and shared folders: mesh files that expand past the limits, glTF buffers that
//! are FIFOs or lead out of the glTF file's folder, PLY files with repeated elements, outputs whose
//! temporary names are planted with symlinks and FIFOs, outputs that are devices or FIFOs, two
//! outputs naming one file, output names of 250 bytes, and success lines with control characters.
//! Each case runs through the binary under the suite's memory and time limits (`support`).
//!
//! "No file opened outside the named ones" is made testable by the folder layout: the mesh lives in
//! `mesh/`, a secret file beside that folder holds a valid triangle of exactly the bytes a buffer
//! declares, so a loader that opens it renders it (exit 0) instead of refusing; the refusal must not
//! name the secret's resolved path or its size.

use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{json, Value};

use crate::support::*;

/// The bytes of three `f32` vertices: one triangle.
fn triangle_bytes() -> Vec<u8> {
    [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|c| c.to_le_bytes()).collect()
}

/// A glTF document: `nodes` nodes each drawing mesh 0, whose `prims` primitives all use accessor 0
/// (`count` vertices, non-indexed triangles) in buffer 0 at `uri` of `byte_length` bytes.
fn gltf_doc(uri: &str, byte_length: u64, count: u64, prims: usize, nodes: usize, mode: u32) -> Value {
    let prim = json!({ "attributes": { "POSITION": 0 }, "mode": mode });
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes).collect::<Vec<_>>() }],
        "nodes": vec![json!({ "mesh": 0 }); nodes],
        "meshes": [{ "primitives": vec![prim; prims] }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0] }],
        "bufferViews": [{ "buffer": 0, "byteLength": 12 * count.max(1) }],
        "buffers": [{ "uri": uri, "byteLength": byte_length }],
    })
}

fn write_json(dir: &Path, name: &str, v: &Value) -> PathBuf {
    write(dir, name, serde_json::to_vec(v).expect("json"))
}

/// `reference` of `mesh` (CPU, 8×8, 1 sample) into `out`.
fn reference(env: &Path, mesh: &Path, out: &Path) -> Run {
    cpu(&["reference", "--env", s(env), "--mesh", s(mesh), "--size", "8x8", "--spp", "1", "--out", s(out)])
}

// ---------------------------------------------------------------------------------------------------
// Mesh files: repeated PLY elements, expansion past the limits.

/// The pixels of a linear RGBA EXR that `reference` wrote, row by row.
fn exr_pixels(path: &Path) -> Vec<[f32; 4]> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
        |px: &mut (usize, Vec<[f32; 4]>), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px.1[pos.y() * px.0 + pos.x()] = [r, g, b, a]
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.layer_data.channel_data.pixels.1
}

/// Each case's mesh is the control's (the first `vertex` element's three vertices and the first
/// `face` element's triangle, nothing of the later elements): the same vertices and triangle through
/// the library's loader, and through the binary the same image as the control's, pixel for pixel
/// (`reference` is deterministic: the same mesh, camera and samples give the same bits), with the
/// triangle covering part of it.
#[test]
fn ply_second_vertex_and_face_elements_are_read_past() {
    let dir = tmp();
    let d = dir.path();
    let env = exr_file(d, "env.exr", 1.0);
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    let face = "element face 1\nproperty list uchar int vertex_indices\n";
    let head_2 = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    let control = write(d, "control.ply", format!("{head}{face}end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    let want = brdf_shop::scene::Mesh::load(&control).expect("the control PLY loads");
    assert_eq!((want.positions.len(), want.indices.len()), (3, 3), "the control is one triangle");
    let control_out = d.join("control.exr");
    let r = reference(&env, &control, &control_out);
    assert_eq!(r.code, 0, "control: {}", r.stderr);
    let want_pixels = exr_pixels(&control_out);
    let covered = want_pixels.iter().filter(|p| p[3] > 0.5).count();
    assert!(covered > 0 && covered < want_pixels.len(), "the control covers {covered} of 64 pixels");
    let cases = [
        // A second `vertex` element with one property, after the faces and between them.
        format!("{head}{face}element vertex 2\nproperty float q\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n5\n6\n"),
        format!("{head}element vertex 1\nproperty uchar q\n{face}end_header\n0 0 0\n1 0 0\n0 1 0\n7\n3 0 1 2\n"),
        // A second `face` element without a vertex list, and one with indices past the vertices.
        format!("{head}{face}element face 1\nproperty int k\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9\n"),
        format!("{head}{face}{face}end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 7 8 9\n"),
        // A second, complete mesh (another triangle's `x y z` and a valid face): a loader that took
        // it would load without complaint, and only the vertices and the image tell.
        format!("{head}{face}{head_2}{face}end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n5 5 5\n7 5 5\n5 9 5\n3 2 1 0\n"),
    ];
    for (k, text) in cases.iter().enumerate() {
        let ply = write(d, &format!("m{k}.ply"), text);
        let out = d.join(format!("o{k}.exr"));
        let mesh = brdf_shop::scene::Mesh::load(&ply).unwrap_or_else(|e| panic!("case {k}: {e}"));
        assert_eq!(mesh.positions, want.positions, "case {k}: the vertices are not the first vertex element's");
        assert_eq!(mesh.indices, want.indices, "case {k}: the triangles are not the first face element's");
        let r = reference(&env, &ply, &out);
        assert_eq!(r.code, 0, "case {k}: only the first vertex and face elements are the mesh: {}", r.stderr);
        assert!(exr_pixels(&out) == want_pixels, "case {k}: the image differs from the control's");
    }
}

#[test]
fn gltf_reused_accessors_meshes_and_nodes_count_against_the_limit() {
    let dir = tmp();
    let d = dir.path();
    let env = exr_file(d, "env.exr", 1.0);
    let out = d.join("o.exr");
    // 300 000 vertices (a sparse 3.6 MB buffer) used by 100 primitives of one mesh drawn by 10 nodes:
    // 3·10⁸ vertices, 10⁸ triangles from a small file.
    let count = 300_000u64;
    sparse(d, "b.bin", 12 * count);
    let bomb = write_json(d, "bomb.gltf", &gltf_doc("b.bin", 12 * count, count, 100, 10, 4));
    refused(&reference(&env, &bomb, &out), 1, &[s(&bomb), "expands to", "limit"]);
    // 10⁵ nodes drawing a mesh of 10⁵ point primitives: 10¹⁰ primitives to walk, none with a surface.
    let points = write_json(d, "points.gltf", &gltf_doc("b.bin", 12 * count, 3, 100_000, 100_000, 0));
    refused(&reference(&env, &points, &out), 1, &[s(&points), "primitives", "limit"]);
    assert_eq!(listing(d), ["b.bin", "bomb.gltf", "env.exr", "points.gltf"]);
}

#[test]
fn ply_and_obj_faces_expanding_past_the_limit() {
    let dir = tmp();
    let d = dir.path();
    let env = exr_file(d, "env.exr", 1.0);
    let out = d.join("o.exr");
    // One polygon of 2^24 + 3 corners (fan-triangulated: 2^24 + 1 triangles): a binary PLY whose
    // list items (vertex 0, one byte each) are the zeros of a sparse tail.
    let n: u32 = (1 << 24) + 3;
    let mut head = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uint uchar vertex_indices\nend_header\n"
        .to_vec();
    head.extend(triangle_bytes());
    head.extend(n.to_le_bytes());
    let ply = write(d, "fan.ply", &head);
    std::fs::OpenOptions::new().write(true).open(&ply).unwrap().set_len(head.len() as u64 + n as u64).unwrap();
    refused(&reference(&env, &ply, &out), 1, &[s(&ply), "expands to", "limit"]);
    // The same polygon as an OBJ face line.
    let mut obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf".to_vec();
    obj.extend(b" 1".repeat(n as usize));
    obj.push(b'\n');
    let obj = write(d, "fan.obj", obj);
    refused(&reference(&env, &obj, &out), 1, &[s(&obj), "line 4", "limit"]);
    assert_eq!(listing(d), ["env.exr", "fan.obj", "fan.ply"]);
}

// ---------------------------------------------------------------------------------------------------
// glTF buffers: FIFOs, zero lengths, URIs leading out of the folder, long URIs.

#[test]
fn gltf_buffer_fifo_or_zero_length_is_refused_without_blocking() {
    let dir = tmp();
    let d = dir.path();
    let env = exr_file(d, "env.exr", 1.0);
    let out = d.join("o.exr");
    mkfifo(&d.join("pipe.bin"));
    // A FIFO declared empty (byteLength 0: the read would wait for a writer forever) and declared
    // 36 bytes long; then an empty regular file declared empty.
    for (k, (uri, len, want)) in
        [("pipe.bin", 0, "byteLength"), ("pipe.bin", 36, "regular file"), ("empty.bin", 0, "byteLength")]
            .into_iter()
            .enumerate()
    {
        write(d, "empty.bin", b"");
        let g = write_json(d, &format!("m{k}.gltf"), &gltf_doc(uri, len, 3, 1, 1, 4));
        refused(&reference(&env, &g, &out), 1, &[s(&g), want]);
    }
    assert!(is_fifo(&d.join("pipe.bin")) && !out.exists());
    assert_eq!(listing(d), ["empty.bin", "env.exr", "m0.gltf", "m1.gltf", "m2.gltf", "pipe.bin"]);
}

#[test]
fn gltf_buffer_uris_stay_in_the_gltf_folder() {
    let dir = tmp();
    let d = dir.path();
    let env = exr_file(d, "env.exr", 1.0);
    let out = d.join("o.exr");
    // The sandbox: mesh/ holds the glTF files; the secret beside it is a valid 36-byte triangle.
    let secret = write(d, "secret.bin", triangle_bytes());
    let mesh = d.join("mesh");
    std::fs::create_dir_all(mesh.join("sub")).unwrap();
    std::os::unix::fs::symlink("../secret.bin", mesh.join("link.bin")).unwrap();
    std::os::unix::fs::symlink("..", mesh.join("up")).unwrap();
    std::os::unix::fs::symlink(&secret, mesh.join("abs-link.bin")).unwrap();
    let uris = [
        "../secret.bin".to_string(),
        s(&secret).to_string(),
        "%2e%2e/secret.bin".into(),
        "%2E%2E%2Fsecret.bin".into(),
        format!("%2F{}", s(&secret).trim_start_matches('/').replace('/', "%2F")),
        "sub/../../secret.bin".into(),
        "./sub/%2e./%2e%2e/secret.bin".into(),
        "link.bin".into(),
        "abs-link.bin".into(),
        "up/secret.bin".into(),
        "file:///etc/passwd".into(),
    ];
    for (k, uri) in uris.iter().enumerate() {
        let g = write_json(&mesh, &format!("m{k}.gltf"), &gltf_doc(uri, 36, 3, 1, 1, 4));
        let r = reference(&env, &g, &out);
        refused(&r, 1, &[s(&g), "buffer 0"]);
        let named = !uri.contains(s(&secret)) && r.stderr.contains(s(&secret));
        assert!(!named, "{uri}: the message names the resolved path: {}", r.stderr);
        assert!(!r.stderr.contains("36 bytes"), "{uri}: the message gives the secret's size: {}", r.stderr);
    }
    // Nothing written by the refusals: no image, no temporary file, the planted links in place.
    assert_eq!(listing(d), ["env.exr", "mesh", "secret.bin"]);
    let mut want: Vec<String> = (0..uris.len()).map(|k| format!("m{k}.gltf")).collect();
    want.extend(["abs-link.bin", "link.bin", "sub", "up"].map(String::from));
    want.sort();
    assert_eq!(listing(&mesh), want);
    assert!(listing(&mesh.join("sub")).is_empty());
    assert_eq!(std::fs::read(&secret).unwrap(), triangle_bytes());
    // The positive control: the same triangle beside the glTF file, named plainly, percent-encoded,
    // and in a subfolder.
    write(&mesh, "b.bin", triangle_bytes());
    write(&mesh.join("sub"), "c d.bin", triangle_bytes());
    for (k, uri) in ["b.bin", "%62.bin", "./b.bin", "sub/c%20d.bin"].iter().enumerate() {
        let g = write_json(&mesh, &format!("ok{k}.gltf"), &gltf_doc(uri, 36, 3, 1, 1, 4));
        let r = reference(&env, &g, &out);
        assert_eq!(r.code, 0, "{uri}: {}", r.stderr);
    }
}

#[test]
fn gltf_long_uri_is_quoted_short() {
    let dir = tmp();
    let d = dir.path();
    let env = exr_file(d, "env.exr", 1.0);
    let uri = "x".repeat(1 << 20);
    let g = write_json(d, "long.gltf", &gltf_doc(&uri, 36, 3, 1, 1, 4));
    let r = reference(&env, &g, &d.join("o.exr"));
    // The URI quoted to 80 characters and its length.
    refused(&r, 1, &[s(&g), "buffer 0", "1048576 bytes"]);
    let longest = r.stderr.split(|c| c != 'x').map(str::len).max().unwrap_or(0);
    assert!(longest <= 80, "{longest} characters of the URI quoted: {}", r.stderr);
    assert_eq!(listing(d), ["env.exr", "long.gltf"]);
}

// ---------------------------------------------------------------------------------------------------
// Outputs: planted temporary names, permissions, devices and FIFOs, one file named twice, long
// names, success lines.

/// The next process ids the kernel hands out (it counts up from the last one: the id of a child
/// started here), for planting files at the temporary names a writer that names them by its process
/// id would use.
fn next_pids(n: u32) -> std::ops::Range<u32> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .arg("--version")
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("start brdf-shop --version");
    let last = child.id();
    child.wait().expect("brdf-shop --version");
    last + 1..last + 1 + n
}

#[test]
fn output_temporary_names_cannot_be_planted() {
    let dir = tmp();
    let d = dir.path();
    let victim = write(d, "victim.txt", b"do not touch");
    let m = write_material(d, "m.brdf.json", &material_json(1));
    let strokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json");
    let outs = ["x.glsl", "p.brdf.json", "o.exr", "t.json"];
    // At every name `.NAME.PID.tmp` a writer named by process id would pick in the next 2000 process
    // ids (the test's threads and other processes take ids too): a symlink to the victim (even ids)
    // or a FIFO (odd ids; opening one for writing waits for a reader).
    let mut planted = Vec::new();
    for pid in next_pids(2000) {
        for o in outs {
            let name = format!(".{o}.{pid}.tmp");
            if pid % 2 == 0 {
                std::os::unix::fs::symlink(&victim, d.join(&name)).unwrap();
            } else {
                mkfifo(&d.join(&name));
            }
            planted.push(name);
        }
    }
    let r = cpu(&["export", "--material", s(&m), "--format", "glsl", "--out", s(&d.join("x.glsl"))]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let r = cpu(&["paint", "--strokes", s(&strokes), "--out", s(&d.join("p.brdf.json"))]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (o, t) = (d.join("o.exr"), d.join("t.json"));
    let r = cpu(&["reference", "--view", "canvas", "--size", "8x8", "--out", s(&o), "--timings", s(&t)]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(std::fs::read(&victim).unwrap(), b"do not touch", "a planted symlink was followed");
    for o in outs {
        let meta = std::fs::symlink_metadata(d.join(o)).unwrap();
        assert!(meta.file_type().is_file(), "{o} is not a regular file");
    }
    let mut want: Vec<String> = planted;
    want.extend(["m.brdf.json", "victim.txt"].iter().chain(outs.iter()).map(|s| s.to_string()));
    want.sort();
    assert_eq!(listing(d), want, "a temporary file was left behind");
}

#[test]
fn outputs_keep_the_replaced_files_permissions() {
    let dir = tmp();
    let d = dir.path();
    let m = write_material(d, "m.brdf.json", &material_json(1));
    let out = write(d, "x.glsl", b"old");
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
    let r = cpu(&["export", "--material", s(&m), "--format", "glsl", "--out", s(&out)]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(std::fs::metadata(&out).unwrap().permissions().mode() & 0o7777, 0o640);
    // A new output gets what a newly created file gets (0666 less the umask), as the test's own.
    let fresh = d.join("y.glsl");
    let r = cpu(&["export", "--material", s(&m), "--format", "glsl", "--out", s(&fresh)]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o7777;
    let control = write(d, "control", b"");
    assert_eq!(mode(&fresh), mode(&control));
    assert_eq!(listing(d), ["control", "m.brdf.json", "x.glsl", "y.glsl"]);
}

#[test]
fn outputs_that_are_not_regular_files_are_refused() {
    let dir = tmp();
    let d = dir.path();
    let m = write_material(d, "m.brdf.json", &material_json(1));
    let strokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json");
    let fifo = d.join("pipe.out");
    mkfifo(&fifo);
    // A socket through a symlink (as `--out /dev/null` is a device through one): the link and the
    // socket must stay.
    let socket = d.join("sock");
    let _listener = std::os::unix::net::UnixListener::bind(&socket).expect("a socket in the test's folder");
    let linked = d.join("linked.out");
    std::os::unix::fs::symlink(&socket, &linked).unwrap();
    for target in [&fifo, &linked] {
        let t = s(target);
        let r = cpu(&["export", "--material", s(&m), "--format", "glsl", "--out", t]);
        refused(&r, 1, &["--out", "regular file"]);
        refused(&cpu(&["paint", "--strokes", s(&strokes), "--out", t]), 1, &["--out", "regular file"]);
        let png = d.join("o.png");
        let r = cpu(&["reference", "--view", "canvas", "--size", "8x8", "--out", s(&png), "--timings", t]);
        refused(&r, 1, &["--timings", "regular file"]);
        let no_display = [("DISPLAY", ""), ("WAYLAND_DISPLAY", "")];
        let r = run_with(&["edit", "--frame-stats", t, "--quit"], Input::None, CPU_MEM_KIB, CPU_SECS, &no_display);
        refused(&r, 1, &["--frame-stats", "regular file"]);
    }
    assert!(is_fifo(&fifo));
    assert!(std::fs::symlink_metadata(&linked).unwrap().file_type().is_symlink());
    assert!(std::fs::symlink_metadata(&socket).unwrap().file_type().is_socket());
    assert_eq!(listing(d), ["linked.out", "m.brdf.json", "pipe.out", "sock"]);
}

#[test]
fn two_outputs_naming_one_file_are_refused_before_any_work() {
    let dir = tmp();
    let d = dir.path();
    let existing = write(d, "o.exr", b"old image");
    std::fs::create_dir(d.join("sub")).unwrap();
    std::os::unix::fs::symlink("o.exr", d.join("alias.json")).unwrap();
    let o = s(&existing);
    let spellings =
        [format!("{}/./o.exr", s(d)), format!("{}/sub/../o.exr", s(d)), s(&d.join("alias.json")).to_string()];
    for cmd in ["render", "reference"] {
        for t in &spellings {
            let r = cpu(&[cmd, "--view", "canvas", "--size", "8x8", "--out", o, "--timings", t]);
            refused(&r, 1, &["--timings", "--out"]);
        }
    }
    // Relative spellings, from inside the folder (under the suite's memory and time limits): the
    // same one-line refusal naming both flags, the existing file untouched, nothing added.
    let args = ["reference", "--view", "canvas", "--size", "8x8", "--out", "o.exr", "--timings", "./o.exr"];
    let child = Command::new("sh")
        .current_dir(d)
        .arg("-c")
        .arg(format!("ulimit -v {CPU_MEM_KIB} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let r = finish(child, CPU_SECS, "reference with relative --out and --timings");
    refused(&r, 1, &["--timings", "--out"]);
    assert_eq!(std::fs::read(&existing).unwrap(), b"old image");
    assert_eq!(listing(d), ["alias.json", "o.exr", "sub"]);
    // The editor: --screenshot or --frame-stats naming --out's file is refused before a window
    // opens (no display is given: a window would fail with exit status 2).
    let shot = format!("{}/./m.png", s(d));
    let m = d.join("m.png");
    let cases: [(&[&str], &[&str]); 3] = [
        (&["edit", "--out", s(&m), "--screenshot", &shot, "--quit"], &["--screenshot", "--out"]),
        (&["edit", "--out", o, "--frame-stats", &spellings[1], "--quit"], &["--frame-stats", "--out"]),
        (&["edit", "--screenshot", s(&m), "--frame-stats", &shot, "--quit"], &["--frame-stats", "--screenshot"]),
    ];
    for (args, names) in cases {
        let r = run_with(args, Input::None, CPU_MEM_KIB, CPU_SECS, &[("DISPLAY", ""), ("WAYLAND_DISPLAY", "")]);
        refused(&r, 1, names);
    }
    assert_eq!(std::fs::read(&existing).unwrap(), b"old image");
    assert_eq!(listing(d), ["alias.json", "o.exr", "sub"]);
    assert!(listing(&d.join("sub")).is_empty());
}

#[test]
fn output_names_of_255_bytes_are_written() {
    let dir = tmp();
    let d = dir.path();
    let m = write_material(d, "m.brdf.json", &material_json(1));
    for len in [243, 250, 255] {
        let name = format!("{}.glsl", "n".repeat(len - 5));
        let out = d.join(&name);
        let r = cpu(&["export", "--material", s(&m), "--format", "glsl", "--out", s(&out)]);
        assert_eq!(r.code, 0, "{len} bytes: {}", r.stderr);
        assert!(out.exists());
        std::fs::remove_file(&out).unwrap();
    }
    let name = format!("{}.png", "n".repeat(251));
    let r = cpu(&["reference", "--view", "canvas", "--size", "8x8", "--out", s(&d.join(&name))]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(listing(d), ["m.brdf.json".to_string(), name]);
}

#[test]
fn success_lines_escape_output_paths() {
    let dir = tmp();
    let d = dir.path();
    let m = write_material(d, "m.brdf.json", &material_json(1));
    let strokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json");
    let weird = |ext: &str| d.join(format!("a\nb\u{1b}[2Jc.{ext}"));
    let runs = [
        cpu(&["export", "--material", s(&m), "--format", "glsl", "--out", s(&weird("glsl"))]),
        cpu(&["paint", "--strokes", s(&strokes), "--out", s(&weird("brdf.json"))]),
        cpu(&["reference", "--view", "canvas", "--size", "8x8", "--out", s(&weird("png"))]),
    ];
    for r in runs {
        assert_eq!(r.code, 0, "{}", r.stderr);
        one_line(&r.stderr);
        assert!(r.stderr.contains("a\\nb\\u{1b}[2Jc."), "{}", r.stderr);
    }
}
