//! The README's walk-through runs as written: the first ```` ```sh ```` block after the heading
//! "## A first material", line by line, through `sh -c` in a fresh temporary folder whose `assets`
//! is a link to the repository's, with the directory of the binary under test first on `PATH` (so
//! `brdf-shop` is this build). Every line must exit 0, and every file a line names with `--out` must
//! exist and hold something. The block must be there, and must run `brdf-shop` at least once.
//! Debug builds run the binary with the validation layer, whose errors fail a GPU command.

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

/// Runs `line` with `sh -c` in `dir` with `path` as `PATH`; returns its exit status and output, or
/// fails the test when it runs past [`LINE_LIMIT`] (the child is killed first).
fn run(line: &str, dir: &Path, path: &str) -> (std::process::ExitStatus, String) {
    let log = dir.join(".line-output");
    let file = std::fs::File::create(&log).expect("the output log is created");
    let mut child = Command::new("sh")
        .args(["-c", line])
        .current_dir(dir)
        .env("PATH", path)
        .stdin(Stdio::null())
        .stdout(file.try_clone().expect("the log is cloned"))
        .stderr(file)
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
            panic!("{line:?} ran past {LINE_LIMIT:?}: {}", std::fs::read_to_string(&log).unwrap_or_default());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let output = std::fs::read_to_string(&log).unwrap_or_default();
    let _ = std::fs::remove_file(&log);
    (status, output)
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

    for line in &commands {
        let (status, output) = run(line, dir.path(), &path);
        eprintln!("$ {line}\n{output}");
        assert!(status.success(), "README walk-through: {line:?} exited with {status}:\n{output}");
        assert!(!output.contains("panicked"), "{line:?}: {output}");
        for out in outputs(line) {
            let file = dir.path().join(&out);
            let len = std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0);
            assert!(len > 0, "README walk-through: {line:?} left {out} missing or empty");
        }
    }
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
}
