//! Property-based fuzzing of every parser that reads user input: the material and
//! strokes files, the EXR and HDR loaders, the OBJ, PLY and glTF loaders, and `eval`'s line reader.
//! Nightly `cargo fuzz` is not part of the toolchain here, so `proptest` drives them: each target
//! starts from a valid input made on the spot and applies 1–16 random mutations (byte flips,
//! insertions of interesting bytes and numbers, deletions, truncations, duplicated slices), plus
//! purely random bytes. The property: the parser returns, never panics, and a refusal is a user
//! error (exit status 1 in the binary) with a one-line message.
//!
//! Case counts are bounded so the whole file runs in well under a minute in the test profile
//! (`CASES` per target); the seed is fixed (13) so CI is reproducible, and `PROPTEST_RNG_SEED=N`
//! with `BRDF_SHOP_FUZZ_CASES=N` explores other and more inputs. Inputs that ever crashed a parser are kept in
//! `tests/corpus/` and replayed by [`corpus_regressions`].

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use brdf_shop::brdf::Material;
use brdf_shop::brush::strokes::Strokes;
use brdf_shop::fsio::shortest;
use brdf_shop::scene::{Environment, Mesh};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// Cases per in-process target: 1500 × 8 targets take about 10 s on the 2-core machine (test
/// profile). `BRDF_SHOP_FUZZ_CASES=N` runs N per target instead (longer fuzzing sessions).
const CASES: u32 = 1500;
/// Cases for `eval` through the binary (a process each, about 5 ms).
const EVAL_CASES: u32 = 256;

fn config(cases: u32) -> Config {
    let seed = std::env::var("PROPTEST_RNG_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(13);
    let cases = std::env::var("BRDF_SHOP_FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(cases);
    Config { cases, failure_persistence: None, rng_seed: RngSeed::Fixed(seed), ..Config::default() }
}

/// One mutation of a byte string.
#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: usize, bit: u8 },
    Set { at: usize, byte: u8 },
    Insert { at: usize, bytes: Vec<u8> },
    Delete { at: usize, len: usize },
    Truncate { at: usize },
    Duplicate { at: usize, len: usize },
}

/// Bytes and numbers that make parsers take rare paths.
fn interesting() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        Just(b"-1".to_vec()),
        Just(b"1e309".to_vec()),
        Just(b"NaN".to_vec()),
        Just(b"4294967296".to_vec()),
        Just(b"18446744073709551616".to_vec()),
        Just(b"-2147483648".to_vec()),
        Just(vec![0xff, 0xff, 0xff, 0x7f]),
        Just(vec![0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]),
        Just(vec![0, 0, 0, 0]),
        Just(vec![0x80, 0, 0, 0]),
        Just(b"\n".to_vec()),
        Just(b"\"".to_vec()),
        Just(b"[[[[[[[[".to_vec()),
        Just(b"{".to_vec()),
        Just("\u{1b}\u{0}é".as_bytes().to_vec()),
        prop::collection::vec(any::<u8>(), 1..16),
    ]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Set { at, byte }),
        (any::<usize>(), interesting()).prop_map(|(at, bytes)| Mutation::Insert { at, bytes }),
        (any::<usize>(), 1usize..64).prop_map(|(at, len)| Mutation::Delete { at, len }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        (any::<usize>(), 1usize..64).prop_map(|(at, len)| Mutation::Duplicate { at, len }),
    ]
}

fn apply(mut b: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        let n = b.len().max(1);
        match m {
            Mutation::Flip { at, bit } => {
                if !b.is_empty() {
                    b[at % n] ^= 1 << bit;
                }
            }
            Mutation::Set { at, byte } => {
                if !b.is_empty() {
                    b[at % n] = *byte;
                }
            }
            Mutation::Insert { at, bytes } => {
                let at = at % (b.len() + 1);
                b.splice(at..at, bytes.iter().copied());
            }
            Mutation::Delete { at, len } => {
                let at = at % n;
                let end = (at + len).min(b.len());
                if at < end {
                    b.drain(at..end);
                }
            }
            Mutation::Truncate { at } => b.truncate(at % n),
            Mutation::Duplicate { at, len } => {
                let at = at % n;
                let end = (at + len).min(b.len());
                if at < end {
                    let slice = b[at..end].to_vec();
                    b.splice(end..end, slice);
                }
            }
        }
    }
    b
}

/// A valid input mutated 1–16 times, or (one case in eight) random bytes.
fn mutated(seed: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        7 => prop::collection::vec(mutation(), 1..16).prop_map(move |m| apply(seed.clone(), &m)),
        1 => prop::collection::vec(any::<u8>(), 0..512),
    ]
}

/// The property every parser must keep: no panic (the call returns), and a refusal is a user error
/// whose message is exactly one line: something besides white space, and no line break (`\n`, or a
/// `\r` that a terminal shows as one) anywhere in it, a trailing one included.
fn refused_cleanly<T>(r: brdf_shop::Result<T>) -> Result<(), TestCaseError> {
    if let Err(e) = r {
        prop_assert!(e.is_user_error(), "not a user error: {e}");
        let msg = e.to_string();
        prop_assert!(!msg.trim().is_empty(), "an empty message: {:?}", msg);
        prop_assert!(!msg.contains(['\n', '\r']), "not one line: {:?}", msg);
    }
    Ok(())
}

fn material_seed() -> Vec<u8> {
    let m = serde_json::json!({
        "format": "brdf-shop/material", "version": 2, "diffuse": [0.1, 0.2, 0.3],
        "lobes": [
            { "albedo": [0.3, 0.2, 0.1], "alpha_x": 0.1, "alpha_y": 0.3, "tangent_angle": 0.5,
              "rotation": [0.9, 0.1, 0.2, 0.0], "split": true },
            { "albedo": [0.1, 0.1, 0.1], "alpha_x": 0.01, "alpha_y": 0.01 }
        ]
    });
    serde_json::to_vec_pretty(&m).unwrap()
}

fn strokes_seed() -> Vec<u8> {
    include_bytes!("../assets/default.strokes.json").to_vec()
}

/// An 8×4 EXR (through the `exr` crate) with varied texels.
fn exr_seed() -> Vec<u8> {
    use exr::prelude::*;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| (p.x() as f32, p.y() as f32 * 0.5, 1.0f32));
    let layer = Layer::new((8, 4), LayerAttributes::named("t"), Encoding::UNCOMPRESSED, channels);
    let mut c = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut c).unwrap();
    c.into_inner()
}

/// An 8×4 Radiance HDR (flat RGBE scanlines).
fn hdr_seed() -> Vec<u8> {
    let mut b = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n".to_vec();
    for k in 0..32u8 {
        b.extend_from_slice(&[k.wrapping_mul(7), 64, 200, 129]);
    }
    b
}

fn obj_seed() -> Vec<u8> {
    b"# cube\nv -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
vn 0 0 1\nvt 0 0\nf 1 2 3 4\nf 5/1/1 6/1/1 7/1/1 8/1/1\nf 1 5 8\nf -1 -2 -3\ng side\nf 2 6 7 3\n"
        .to_vec()
}

fn ply_seed() -> Vec<u8> {
    b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 1\n3 0 1 2\n4 0 1 2 3\n"
        .to_vec()
}

fn ply_binary_seed() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
        .to_vec();
    for v in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b.push(3);
    for i in 0u32..3 {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

fn gltf_seed() -> Vec<u8> {
    // One triangle, positions and indices in a base64 `data:` buffer.
    let mut buf = Vec::new();
    for v in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            buf.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        buf.extend_from_slice(&i.to_le_bytes());
    }
    let b64 = base64(&buf);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        buf.len()
    )
    .into_bytes()
}

fn base64(b: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in b.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Writes `bytes` to a fresh file named `name` in a temporary folder and loads it with `load`.
fn via_file<T>(name: &str, bytes: &[u8], load: impl Fn(&Path) -> brdf_shop::Result<T>) -> brdf_shop::Result<T> {
    let dir = tempfile::TempDir::new().expect("temporary folder");
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).expect("write");
    load(&p)
}

#[test]
fn seeds_are_valid() {
    // The mutations start from inputs that load: otherwise the fuzzing would test only refusals.
    Material::from_json(std::str::from_utf8(&material_seed()).unwrap(), "seed").expect("material seed");
    Strokes::from_json(std::str::from_utf8(&strokes_seed()).unwrap(), "seed").expect("strokes seed");
    Environment::from_exr_bytes(&exr_seed(), "seed").expect("EXR seed");
    via_file("s.hdr", &hdr_seed(), Environment::load).expect("HDR seed");
    via_file("s.obj", &obj_seed(), Mesh::load).expect("OBJ seed");
    via_file("s.ply", &ply_seed(), Mesh::load).expect("PLY seed");
    via_file("b.ply", &ply_binary_seed(), Mesh::load).expect("binary PLY seed");
    via_file("s.gltf", &gltf_seed(), Mesh::load).expect("glTF seed");
}

proptest! {
    #![proptest_config(config(CASES))]

    #[test]
    fn fuzz_material(bytes in mutated(material_seed())) {
        refused_cleanly(Material::from_json(&String::from_utf8_lossy(&bytes), "fuzz"))?;
    }

    #[test]
    fn fuzz_strokes(bytes in mutated(strokes_seed())) {
        let parsed = Strokes::from_json(&String::from_utf8_lossy(&bytes), "fuzz");
        if let Ok(s) = &parsed {
            // Replaying what parsed must not panic either (strokes are cheap: the file is small).
            refused_cleanly(s.replay(&Material::scratch(), "fuzz"))?;
        }
        refused_cleanly(parsed)?;
    }

    #[test]
    fn fuzz_exr(bytes in mutated(exr_seed())) {
        refused_cleanly(Environment::from_exr_bytes(&bytes, "fuzz"))?;
    }

    #[test]
    fn fuzz_hdr(bytes in mutated(hdr_seed())) {
        refused_cleanly(via_file("f.hdr", &bytes, Environment::load))?;
    }

    #[test]
    fn fuzz_obj(bytes in mutated(obj_seed())) {
        refused_cleanly(via_file("f.obj", &bytes, Mesh::load))?;
    }

    #[test]
    fn fuzz_ply(bytes in mutated(ply_seed())) {
        refused_cleanly(via_file("f.ply", &bytes, Mesh::load))?;
    }

    #[test]
    fn fuzz_ply_binary(bytes in mutated(ply_binary_seed())) {
        refused_cleanly(via_file("f.ply", &bytes, Mesh::load))?;
    }

    #[test]
    fn fuzz_gltf(bytes in mutated(gltf_seed())) {
        refused_cleanly(via_file("f.gltf", &bytes, Mesh::load))?;
    }
}

/// Cases of the structured mesh targets (glTF reuse, PLY element orders): each builds and loads a
/// small file, about as fast as a mutated seed.
const STRUCTURED_CASES: u32 = 500;

/// A glTF scene of reused parts: `nodes` (each its mesh, or none, and children: any node, so
/// cycles and shared children happen), meshes of primitives (mode, POSITION and index accessors
/// shared between them), accessors declaring counts from 0 to 2^32 over one small data buffer.
fn gltf_reuse() -> impl Strategy<Value = Vec<u8>> {
    let accessor =
        (0u32..4, prop_oneof![Just(0u64), Just(3), Just(7), Just(1 << 20), Just(1 << 31), Just(u32::MAX as u64)]);
    let prim = (prop_oneof![Just(0u32), Just(4), Just(5), Just(6)], 0usize..4, prop::option::of(0usize..4));
    let mesh = prop::collection::vec(prim, 0..40);
    let node = (prop::option::of(0usize..3), prop::collection::vec(0usize..60, 0..4));
    (
        prop::collection::vec(accessor, 4),
        prop::collection::vec(mesh, 3),
        prop::collection::vec(node, 1..60),
        prop::collection::vec(0usize..60, 1..8),
    )
        .prop_map(|(accessors, meshes, nodes, roots)| {
            let n = nodes.len();
            // Buffer: 7 vertices, then 7 u16 indices (a data URI).
            let mut buf: Vec<u8> = (0..21).flat_map(|k| ((k % 5) as f32).to_le_bytes()).collect();
            buf.extend((0u16..7).flat_map(|i| i.to_le_bytes()));
            let accessors: Vec<_> = accessors
                .iter()
                .enumerate()
                .map(|(k, &(kind, count))| {
                    if k % 2 == 0 || kind == 0 {
                        serde_json::json!({"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                                           "min": [0, 0, 0], "max": [4, 4, 4]})
                    } else {
                        serde_json::json!({"bufferView": 1, "componentType": 5123, "count": count, "type": "SCALAR"})
                    }
                })
                .collect();
            let meshes: Vec<_> = meshes
                .iter()
                .map(|prims| {
                    let prims: Vec<_> = prims
                        .iter()
                        .map(|&(mode, pos, idx)| {
                            let mut p = serde_json::json!({"attributes": {"POSITION": pos}, "mode": mode});
                            if let Some(i) = idx {
                                p["indices"] = serde_json::json!(i);
                            }
                            p
                        })
                        .collect();
                    serde_json::json!({ "primitives": prims })
                })
                .collect();
            let nodes: Vec<_> = nodes
                .iter()
                .map(|(mesh, children)| {
                    let mut v = serde_json::json!({});
                    if let Some(m) = mesh {
                        v["mesh"] = serde_json::json!(m);
                    }
                    let children: Vec<usize> = children.iter().map(|c| c % n).collect();
                    if !children.is_empty() {
                        v["children"] = serde_json::json!(children);
                    }
                    v
                })
                .collect();
            let roots: Vec<usize> = roots.iter().map(|r| r % n).collect();
            serde_json::json!({
                "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": roots}], "nodes": nodes,
                "meshes": meshes, "accessors": accessors,
                "bufferViews": [{"buffer": 0, "byteLength": 84}, {"buffer": 0, "byteOffset": 84, "byteLength": 14}],
                "buffers": [{"byteLength": buf.len(), "uri": format!("data:application/octet-stream;base64,{}", base64(&buf))}],
            })
            .to_string()
            .into_bytes()
        })
}

/// One PLY element of a random kind: the mesh's `vertex` (x y z), a `vertex` of other properties,
/// a `face` with or without its index list, or an element of another name; with its count.
#[derive(Clone, Copy, Debug)]
enum PlyElement {
    Vertex,
    OtherVertex,
    Face,
    FaceWithoutList,
    Other,
}

/// A PLY file whose elements come in any order and may repeat, ASCII or binary (either byte order),
/// with values of the right shape (face indices 0..6, some past the vertices).
fn ply_orderings() -> impl Strategy<Value = Vec<u8>> {
    let element = (
        prop_oneof![
            Just(PlyElement::Vertex),
            Just(PlyElement::OtherVertex),
            Just(PlyElement::Face),
            Just(PlyElement::FaceWithoutList),
            Just(PlyElement::Other)
        ],
        0u32..5,
    );
    (0u8..3, prop::collection::vec(element, 1..7), prop::collection::vec(0u8..7, 64)).prop_map(
        |(format, elements, values)| {
            let name = ["ascii", "binary_little_endian", "binary_big_endian"][format as usize];
            let mut head = format!("ply\nformat {name} 1.0\n");
            let mut body = Vec::new();
            let mut v = values.iter().cycle();
            let put = |body: &mut Vec<u8>, x: u8, float: bool| match (format, float) {
                (0, _) => body.extend_from_slice(format!("{x} ").as_bytes()),
                (1, true) => body.extend_from_slice(&(x as f32).to_le_bytes()),
                (_, true) => body.extend_from_slice(&(x as f32).to_be_bytes()),
                (1, false) => body.extend_from_slice(&(x as i32).to_le_bytes()),
                (_, false) => body.extend_from_slice(&(x as i32).to_be_bytes()),
            };
            for (kind, count) in elements {
                let (el, props): (&str, &[&str]) = match kind {
                    PlyElement::Vertex => ("vertex", &["float x", "float y", "float z"]),
                    PlyElement::OtherVertex => ("vertex", &["float q"]),
                    PlyElement::Face => ("face", &["list uchar int vertex_indices"]),
                    PlyElement::FaceWithoutList => ("face", &["int k"]),
                    PlyElement::Other => ("edge", &["int a", "int b"]),
                };
                head += &format!("element {el} {count}\n");
                for p in props {
                    head += &format!("property {p}\n");
                }
                for _ in 0..count {
                    for p in props {
                        if p.starts_with("list") {
                            let n = 3 + v.next().unwrap() % 3;
                            match format {
                                0 => body.extend_from_slice(format!("{n} ").as_bytes()),
                                _ => body.push(n),
                            }
                            for _ in 0..n {
                                put(&mut body, *v.next().unwrap(), false);
                            }
                        } else {
                            put(&mut body, *v.next().unwrap(), p.starts_with("float"));
                        }
                    }
                    if format == 0 {
                        body.push(b'\n');
                    }
                }
            }
            head += "end_header\n";
            let mut bytes = head.into_bytes();
            bytes.extend(body);
            bytes
        },
    )
}

/// A structured mesh case: the load returns (no panic), a refusal is a clean user error, and a
/// mesh that loads is within the limits.
fn loads_within_limits(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let r = via_file(name, bytes, Mesh::load);
    if let Ok(m) = &r {
        prop_assert!(m.triangle_count() as u64 <= brdf_shop::scene::mesh::MAX_TRIANGLES);
        prop_assert!(m.positions.len() as u64 <= brdf_shop::scene::mesh::MAX_VERTICES);
    }
    refused_cleanly(r)
}

proptest! {
    #![proptest_config(config(STRUCTURED_CASES))]

    #[test]
    fn fuzz_gltf_node_and_accessor_reuse(bytes in gltf_reuse()) {
        loads_within_limits("r.gltf", &bytes)?;
    }

    #[test]
    fn fuzz_ply_element_orders(bytes in ply_orderings()) {
        loads_within_limits("o.ply", &bytes)?;
    }
}

/// `eval` through the binary: exit 0 with one output line per input line (the library's value of
/// each, [`eval_printed_one_line_per_input_line`]) and nothing on stderr, or exit 1 with one stderr
/// line and nothing on stdout.
fn eval_run(material: &Path, input: &[u8]) -> Result<(), TestCaseError> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(["eval", "--material"])
        .arg(material)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let mut pipe = child.stdin.take().expect("piped");
    let data = input.to_vec();
    let writer = std::thread::spawn(move || {
        let _ = pipe.write_all(&data);
    });
    let out = child.wait_with_output().expect("runs");
    writer.join().expect("writer");
    let stderr = String::from_utf8_lossy(&out.stderr);
    prop_assert!(!stderr.contains("panicked"), "{}", stderr);
    match out.status.code() {
        Some(0) => {
            prop_assert!(stderr.is_empty(), "{}", stderr);
            eval_printed_one_line_per_input_line(material, input, &out.stdout)?;
        }
        Some(1) => {
            prop_assert!(out.stdout.is_empty(), "partial output on a refusal");
            prop_assert_eq!(stderr.lines().count(), 1, "{}", stderr);
            prop_assert!(!stderr.trim_end().chars().any(|c| c.is_control()), "{:?}", stderr);
        }
        other => prop_assert!(false, "exit status {:?}: {}", other, stderr),
    }
    Ok(())
}

/// `eval`'s success: the input's lines (split at `\n`, one trailing `\r` dropped, blank ones
/// skipped, as `eval` reads them) each give exactly one output line, in order, holding
/// `f(ω_i, ω_o)` of that line's six numbers as the library evaluates it
/// (`brdf_shop::fsio::shortest` of each channel), and stdout ends in a line break.
fn eval_printed_one_line_per_input_line(material: &Path, input: &[u8], stdout: &[u8]) -> Result<(), TestCaseError> {
    let m = Material::load(material).expect("the fuzzed material loads");
    let mut want = String::new();
    let mut lines = input.split(|&b| b == b'\n').collect::<Vec<_>>();
    if lines.last().is_some_and(|l| l.is_empty()) {
        lines.pop();
    }
    for line in lines {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let Ok(text) = std::str::from_utf8(line) else {
            return Err(TestCaseError::fail(format!("exit 0 on a line that is not UTF-8: {line:?}")));
        };
        if text.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = text.split_whitespace().filter_map(|t| t.parse().ok()).collect();
        prop_assert_eq!(v.len(), 6, "exit 0 on the line {:?}", text);
        let f = m.eval(glam::DVec3::new(v[0], v[1], v[2]), glam::DVec3::new(v[3], v[4], v[5]));
        want += &format!("{} {} {}\n", shortest(f[0]), shortest(f[1]), shortest(f[2]));
    }
    let got = String::from_utf8_lossy(stdout);
    prop_assert_eq!(got.lines().count(), want.lines().count(), "output lines against input lines: {:?}", got);
    prop_assert_eq!(got, want);
    Ok(())
}

fn material_file() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::TempDir::new().expect("temporary folder");
    let p = dir.path().join("m.brdf.json");
    std::fs::write(&p, material_seed()).expect("write");
    (dir, p)
}

proptest! {
    #![proptest_config(config(EVAL_CASES))]

    #[test]
    fn fuzz_eval_lines(bytes in mutated(b"0 0 1 0 0 1\n0.3 -0.2 0.9 0.1 0.1 1\n\n1e-300 0 1 0 1e300 1\n".to_vec())) {
        let (_dir, m) = material_file();
        eval_run(&m, &bytes)?;
    }
}

/// Every file in `tests/corpus/` (inputs that once crashed or hung a parser, and hand-made hostile
/// ones), loaded by its extension: none may panic, each must load or be refused as a user error.
#[test]
fn corpus_regressions() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("tests/corpus") {
        let p = entry.expect("entry").path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        let r: brdf_shop::Result<()> = if name.ends_with(".brdf.json") {
            Material::load(&p).map(drop)
        } else if name.ends_with(".strokes.json") {
            Strokes::load(&p).and_then(|s| s.replay(&Material::scratch(), "corpus")).map(drop)
        } else if name.ends_with(".exr") || name.ends_with(".hdr") {
            Environment::load(&p).map(drop)
        } else if Mesh::is_mesh_file(&p) {
            Mesh::load(&p).map(drop)
        } else {
            continue;
        };
        if let Err(e) = r {
            assert!(e.is_user_error(), "{name}: {e}");
        }
        seen += 1;
    }
    assert!(seen > 0, "tests/corpus is empty");
}
