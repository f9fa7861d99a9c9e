//! The README's walk-through runs as written: the first ```` ```sh ```` block after the heading
//! "## A first material", line by line, through `sh -c` in a fresh temporary folder whose `assets`
//! is a link to the repository's, with the directory of the binary under test first on `PATH` (so
//! `brdf-shop` is this build). Every line must exit 0, and every file a line names with `--out` must
//! exist and hold something; images must decode (PNG, EXR) at the line's `--size`. What the README
//! says a command prints must be printed ([`check_promises`]). The block must be there, and must run
//! `brdf-shop` at least once. Debug builds run the binary with the validation layer, whose errors
//! fail a GPU command.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const HEADING: &str = "## A first material";

/// The longest one line may take: the walk-through's slowest line is a 256² render on lavapipe in a
/// debug build, which takes seconds; a line past this is taken as hung and fails the test.
const LINE_LIMIT: Duration = Duration::from_secs(300);

/// The shell lines of the walk-through in `readme`: the first block opened with ```` ```sh ```` after
/// the line [`HEADING`], without blank lines and `#` comments, lines ending in `\` joined to the
/// next. An error names what is missing.
fn walkthrough(readme: &str) -> Result<Vec<String>, String> {
    let mut lines = readme.lines();
    lines.by_ref().find(|l| l.trim_end() == HEADING).ok_or_else(|| format!("no heading {HEADING:?}"))?;
    lines.by_ref().find(|l| l.trim() == "```sh").ok_or_else(|| format!("no ```sh block after {HEADING:?}"))?;
    let mut commands = Vec::new();
    let mut pending = String::new();
    let mut closed = false;
    for line in lines {
        if line.trim_start().starts_with("```") {
            closed = true;
            break;
        }
        let line = line.trim();
        if pending.is_empty() && (line.is_empty() || line.starts_with('#')) {
            continue;
        }
        match line.strip_suffix('\\') {
            Some(head) => {
                pending.push_str(head);
                pending.push(' ');
            }
            None => {
                pending.push_str(line);
                commands.push(std::mem::take(&mut pending));
            }
        }
    }
    if !closed {
        return Err(format!("the ```sh block after {HEADING:?} is not closed"));
    }
    if !pending.is_empty() {
        return Err(format!("the block ends in a continued line: {pending:?}"));
    }
    if !commands.iter().any(|c| c.split_whitespace().next() == Some("brdf-shop")) {
        return Err(format!("the block after {HEADING:?} runs no `brdf-shop` line: {commands:?}"));
    }
    Ok(commands)
}

/// The files `line` names with `--out FILE` or `--out=FILE` (quotes and a trailing `;` dropped).
fn outputs(line: &str) -> Vec<String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let name = |f: &str| f.trim_end_matches(';').trim_matches(|c| c == '"' || c == '\'').to_owned();
    let mut out = Vec::new();
    for (i, w) in words.iter().enumerate() {
        if *w == "--out" {
            out.extend(words.get(i + 1).map(|f| name(f)));
        } else if let Some(f) = w.strip_prefix("--out=") {
            out.push(name(f));
        }
    }
    out
}

/// The `WxH` a line asks for with `--size WxH`, if it does.
fn size(line: &str) -> Option<(u32, u32)> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "--size")?;
    let (w, h) = words.get(at + 1)?.split_once('x')?;
    Some((w.parse().ok()?, h.parse().ok()?))
}

/// Width and height of the image at `file` (`.png` through `image`, `.exr` through `exr`), decoded
/// whole: a file that does not decode fails the test. EXR pixels must be finite (the renderers write
/// radiance beyond `f32` as ±`f32::MAX`) with alpha 0 or 1 (docs/model.md: coverage of the pixel
/// centre). `None` for other files.
fn decoded_size(file: &Path) -> Option<(u32, u32)> {
    let name = file.display();
    match file.extension()?.to_str()? {
        "png" => {
            let img = image::open(file).unwrap_or_else(|e| panic!("{name} does not decode as PNG: {e}"));
            Some((img.width(), img.height()))
        }
        "exr" => {
            use exr::prelude::*;
            let img = read_first_rgba_layer_from_file(
                file,
                |res, _| (res.width(), res.height(), Vec::with_capacity(res.width() * res.height())),
                |px: &mut (usize, usize, Vec<[f32; 4]>), _, (r, g, b, a): (f32, f32, f32, f32)| px.2.push([r, g, b, a]),
            )
            .unwrap_or_else(|e| panic!("{name} does not decode as EXR: {e}"));
            let (w, h, pixels) = img.layer_data.channel_data.pixels;
            assert_eq!(pixels.len(), w * h, "{name}: {} pixels for {w}x{h}", pixels.len());
            assert!(pixels.iter().flatten().all(|v| v.is_finite()), "{name}: a non-finite value");
            assert!(pixels.iter().all(|p| p[3] == 0.0 || p[3] == 1.0), "{name}: alpha other than 0 or 1");
            Some((w as u32, h as u32))
        }
        _ => None,
    }
}

/// What the README's walk-through says each command prints, on the stream the program prints it to
/// (status lines on stderr, reports on stdout):
/// - `paint` prints `wrote FILE (N lobes)` (stderr), `N` the lobes of the material it wrote, at
///   least one;
/// - `check` prints the line `verdict: physically correct` and, the painted material preserving
///   energy, a `white furnace, lobe k` line per lobe and the material's, each from at least 0.98
///   (stdout);
/// - `render` prints the GPU time it took (stderr, `rendered WxH on … ms of GPU time …`) and, for
///   the mesh view, which lights the `key` estimator split off the map (`key estimator: …`);
///   `render --plan` without `--out` prints the frame's plan (stdout, from `plan of the mesh view: `,
///   the G-buffer's pass first, then what is left out);
/// - `reference` prints its size and sample count (stderr, `reference WxH at N spp …`).
fn check_promises(line: &str, dir: &Path, stdout: &str, stderr: &str) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let out = outputs(line).into_iter().next();
    let dims = size(line).map(|(w, h)| format!("{w}x{h}"));
    let has = |text: &str, prefix: &str, parts: &[&str]| {
        text.lines().any(|l| l.starts_with(prefix) && parts.iter().all(|p| l.contains(p)))
    };
    match words.get(1).copied() {
        Some("paint") => {
            let out = out.expect("paint names --out");
            let m = brdf_shop::brdf::Material::load(&dir.join(&out))
                .unwrap_or_else(|e| panic!("{line:?}: {out} does not load: {e}"));
            assert!(!m.lobes.is_empty(), "{line:?}: the painted material has no lobes");
            let want = format!("wrote {out} ({} lobes)", m.lobes.len());
            assert!(stderr.lines().any(|l| l == want), "{line:?}: no line {want:?} on stderr:\n{stderr}");
        }
        Some("check") => {
            let want = "verdict: physically correct";
            assert!(stdout.lines().any(|l| l == want), "{line:?}: no line {want:?} on stdout:\n{stdout}");
            let furnace: Vec<&str> = stdout.lines().filter(|l| l.starts_with("white furnace, ")).collect();
            assert!(furnace.len() >= 2, "{line:?}: no white-furnace lines on stdout:\n{stdout}");
            for l in furnace {
                let from: f64 =
                    l.split("): ").nth(1).and_then(|r| r.split(' ').next()).and_then(|v| v.parse().ok()).unwrap_or(0.0);
                assert!(from >= 0.98, "{line:?}: {l}");
            }
        }
        Some("render") if words.contains(&"--plan") && out.is_none() => {
            assert!(stdout.starts_with("plan of the mesh view: "), "{line:?}: no plan on stdout:\n{stdout}");
            assert!(has(stdout, "  1. gbuffer", &[]) && has(stdout, "left out:", &[]), "{line:?}:\n{stdout}");
        }
        Some("render") => {
            let dims = dims.expect("the README's render lines give --size");
            assert!(
                has(stderr, &format!("rendered {dims} on "), &["ms of GPU time"]),
                "{line:?}: no GPU time on stderr:\n{stderr}"
            );
            let canvas = words.windows(2).any(|w| w == ["--view", "canvas"]);
            if !canvas {
                assert!(has(stderr, "key estimator: ", &[]), "{line:?}: no key lights on stderr:\n{stderr}");
            }
        }
        Some("reference") => {
            let dims = dims.expect("the README's reference lines give --size");
            assert!(has(stderr, &format!("reference {dims} at "), &[" spp "]), "{line:?}: stderr:\n{stderr}");
        }
        _ => {}
    }
}

/// Runs `line` with `sh -c` in `dir` with `path` as `PATH`; returns its exit status, stdout and
/// stderr, or fails the test when it runs past [`LINE_LIMIT`] (the child is killed first).
fn run(line: &str, dir: &Path, path: &str) -> (std::process::ExitStatus, String, String) {
    let log = dir.join(".line-output");
    let err_log = dir.join(".line-errors");
    let file = std::fs::File::create(&log).expect("the output log is created");
    let err_file = std::fs::File::create(&err_log).expect("the error log is created");
    let mut child = Command::new("sh")
        .args(["-c", line])
        .current_dir(dir)
        .env("PATH", path)
        .stdin(Stdio::null())
        .stdout(file)
        .stderr(err_file)
        .spawn()
        .expect("sh starts");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("the child is waited on") {
            break status;
        }
        if start.elapsed() > LINE_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            let err = std::fs::read_to_string(&err_log).unwrap_or_default();
            panic!("{line:?} ran past {LINE_LIMIT:?}: {}{err}", std::fs::read_to_string(&log).unwrap_or_default());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let stdout = std::fs::read_to_string(&log).unwrap_or_default();
    let stderr = std::fs::read_to_string(&err_log).unwrap_or_default();
    let _ = std::fs::remove_file(&log);
    let _ = std::fs::remove_file(&err_log);
    (status, stdout, stderr)
}

#[test]
fn the_readme_walkthrough_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md is read");
    let commands = walkthrough(&readme).unwrap_or_else(|e| panic!("README.md: {e}"));

    let dir = tempfile::TempDir::new().expect("a temporary folder");
    std::os::unix::fs::symlink(root.join("assets"), dir.path().join("assets")).expect("assets is linked");
    let bin: PathBuf = Path::new(env!("CARGO_BIN_EXE_brdf-shop")).parent().expect("the binary's folder").into();
    let path = std::env::join_paths(
        std::iter::once(bin).chain(std::env::var_os("PATH").iter().flat_map(std::env::split_paths)),
    )
    .expect("PATH is joined");
    let path = path.to_str().expect("PATH is UTF-8").to_owned();

    let mut images = 0;
    for line in &commands {
        let (status, stdout, stderr) = run(line, dir.path(), &path);
        eprintln!("$ {line}\n{stdout}{stderr}");
        assert!(status.success(), "README walk-through: {line:?} exited with {status}:\n{stdout}{stderr}");
        assert!(!stdout.contains("panicked") && !stderr.contains("panicked"), "{line:?}: {stdout}{stderr}");
        for out in outputs(line) {
            let file = dir.path().join(&out);
            let len = std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0);
            assert!(len > 0, "README walk-through: {line:?} left {out} missing or empty");
            if let Some(got) = decoded_size(&file) {
                let want = size(line).unwrap_or_else(|| panic!("{line:?} writes the image {out} without --size"));
                assert_eq!(got, want, "README walk-through: {line:?} wrote {out} at {got:?}, not --size {want:?}");
                images += 1;
            }
        }
        check_promises(line, dir.path(), &stdout, &stderr);
    }
    // The walk-through's two renders and its reference image were decoded.
    assert!(images >= 3, "only {images} images in the walk-through");
}

/// The parser fails where the walk-through is missing, so a README without it fails the test above
/// instead of running nothing.
#[test]
fn the_walkthrough_parser_refuses_what_is_not_a_walkthrough() {
    let block = "brdf-shop paint --strokes assets/default.strokes.json --out first.brdf.json";
    let ok = format!("# x\n\n{HEADING}\n\ntext\n\n```sh\n# paint\n{block}\n\nbrdf-shop check \\\n  --material first.brdf.json\n```\n");
    assert_eq!(
        walkthrough(&ok).unwrap(),
        vec![block.to_owned(), "brdf-shop check  --material first.brdf.json".to_owned()]
    );
    assert!(walkthrough(&format!("## Another heading\n\n```sh\n{block}\n```\n")).unwrap_err().contains("no heading"));
    assert!(walkthrough(&format!("{HEADING}\n\n```\n{block}\n```\n")).unwrap_err().contains("no ```sh block"));
    assert!(walkthrough(&format!("{HEADING}\n\n```sh\n{block}\n")).unwrap_err().contains("not closed"));
    assert!(walkthrough(&format!("{HEADING}\n\n```sh\nls\necho hi\n```\n")).unwrap_err().contains("no `brdf-shop`"));
    assert_eq!(outputs(block), vec!["first.brdf.json"]);
    assert_eq!(outputs("brdf-shop render --out=a.png --size 8x8"), vec!["a.png"]);
    assert_eq!(outputs("brdf-shop paint --out b.json; ls"), vec!["b.json"]);
    assert!(outputs("brdf-shop check --material m.json").is_empty());
    assert_eq!(size("brdf-shop render --size 256x128 --out a.png"), Some((256, 128)));
    assert_eq!(size("brdf-shop render --out a.png"), None);
}
