//! `tools/check-self-contained` on small trees made here: a clean tree passes, and each kind of
//! work-history marker fails it with the file and line. The markers are spelled in pieces
//! (`concat!`) so that this file does not carry them itself.

use std::path::Path;
use std::process::Command;

/// A tree with the script at `tools/check-self-contained` and the files the check reads, each
/// clean; `extra` is written over it (path, text).
fn tree(extra: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::TempDir::new().expect("a temporary folder");
    let root = dir.path();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/check-self-contained");
    let files: &[(&str, &str)] = &[
        ("README.md", "# x\n\nSince x > 0 the sum is positive; the spec of the format is in docs/formats.md.\n"),
        ("CHANGELOG.md", "# Changelog\n\n## 0.2.0\n\n- The renderer is used to draw the canvas.\n"),
        ("docs/model.md", "# Model\n\nThe frame is right-handed. See README, Commands.\n"),
        ("docs/perf/lavapipe/bench.txt", "goal: 40 ms\n"),
        ("build.rs", "fn main() {}\n"),
        ("src/lib.rs", "//! The model (docs/model.md, The paper model): `f` per unit albedo.\npub fn f() {}\n"),
        ("glsl/a.comp", "// The lobe pass; measured on 2-core lavapipe, 512²: 9.2 → 6.5 ms.\n"),
        ("tests/a.rs", "// The editor restores the last session's material.\n"),
        ("tools/run", "#!/bin/sh\necho run\n"),
        (".ci/run", "#!/bin/sh\ntools/check-self-contained\n"),
    ];
    for (path, text) in files.iter().chain(extra) {
        let p = root.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
    }
    std::fs::create_dir_all(root.join("tools")).unwrap();
    std::fs::copy(&script, root.join("tools/check-self-contained")).expect("the script is copied");
    dir
}

/// Runs the script in `dir`: exit status and stderr.
fn check(dir: &tempfile::TempDir) -> (i32, String) {
    let out =
        Command::new("bash").arg(dir.path().join("tools/check-self-contained")).output().expect("bash runs the script");
    (out.status.code().expect("an exit status"), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn a_clean_tree_passes() {
    let (code, stderr) = check(&tree(&[]));
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn each_history_marker_fails_with_file_and_line() {
    let cases: &[(&str, String, &str)] = &[
        ("src/a.rs", format!("// ok\n// {} 24: faster\n", concat!("Sess", "ion")), "src/a.rs:2:"),
        ("glsl/b.comp", format!("// {} 10's goal\n", concat!("iss", "ue")), "glsl/b.comp:1:"),
        ("tests/c.rs", format!("// {}: see the frame\n", concat!("iss", "ue #3")), "tests/c.rs:1:"),
        ("src/d.rs", format!("/// The frame ({} §1).\n", concat!("SP", "EC")), "src/d.rs:1:"),
        ("src/e.rs", format!("/// 75° ({} before).\n", 65), "src/e.rs:1:"),
        ("docs/renderer.md", format!("The pass {} runs twice.\n", concat!("no ", "longer")), "docs/renderer.md:1:"),
        (
            "docs/perf/stability.md",
            format!("It {} took 9 ms.\n", concat!("previ", "ously")),
            "docs/perf/stability.md:1:",
        ),
        ("tools/run", format!("#!/bin/sh\n# The tool {} copy it.\n", concat!("used", " to")), "tools/run:2:"),
        ("glsl/f.comp", format!("// The cost ({}).\n", concat!("see ", "README")), "glsl/f.comp:1:"),
        ("README.md", format!("Fast {} the review.\n", concat!("since ", "session")), "README.md:1:"),
        (
            concat!("docs/perf/bench-", "session", "13.txt"),
            "x\n".to_owned(),
            concat!("docs/perf/bench-", "session", "13.txt"),
        ),
    ];
    for (path, text, want) in cases {
        let (code, stderr) = check(&tree(&[(path, text)]));
        assert_eq!(code, 1, "{path}: {text:?} passed: {stderr}");
        assert!(stderr.contains(want), "{path}: {text:?}: stderr does not name {want:?}: {stderr}");
    }
}
