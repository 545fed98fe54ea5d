//! Every command README.md shows runs, and exits 0; what the README says those commands print
//! or write is what they print and write today.
//!
//! The commands are the lines of the README's fenced `sh`, `bash` and `shell` blocks and the
//! `$ ` lines of its `console` blocks. `cargo run --release --` (with or without `--locked`)
//! and a leading `csm-lab` become the binary cargo built for this test. They run in README
//! order through `sh` in a fresh directory holding a copy of `configs/`, so every file they
//! write lands under that directory's `out/` and `ci/` (the README's own paths), never in the
//! repository. `cargo test --release` is the suite this test belongs to and is the one line not
//! run (`NOT_RUN`); any other `cargo` line fails the test rather than being skipped.
//!
//! Exit codes: every command must exit 0. The README shows no `check` that demonstrates a
//! failing gate (exit 1), so no command is allowed a non-zero exit; `EXPECTED_EXIT` is where
//! such a command would be listed, with its code, if one is ever shown.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Lines shown in the README's command blocks that this test does not run, and why.
const NOT_RUN: &[(&str, &str)] = &[("cargo test --release", "the test suite this test is part of")];

/// Commands the README shows on purpose with a non-zero exit code (a failing gate). None today.
const EXPECTED_EXIT: &[(&str, i32)] = &[];

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn readme() -> String {
    std::fs::read_to_string(repo("README.md")).unwrap()
}

/// A fenced block of the README: its info string, its first line's number (1-based) and its
/// lines, without the indent of its fence (a block inside a list item is indented).
struct Block {
    lang: String,
    line: usize,
    indent: usize,
    lines: Vec<String>,
}

fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim_start();
        if let Some(info) = line.strip_prefix("```") {
            match open.take() {
                Some(b) => out.push(b),
                None => {
                    open = Some(Block {
                        lang: info.trim().to_string(),
                        line: i + 2,
                        indent: raw.len() - line.len(),
                        lines: Vec::new(),
                    })
                }
            }
            continue;
        }
        if let Some(b) = open.as_mut() {
            let indent = raw.len() - raw.trim_start_matches(' ').len();
            b.lines.push(raw[indent.min(b.indent)..].to_string());
        }
    }
    assert!(open.is_none(), "README.md: a code fence is not closed");
    out
}

/// The commands the README shows, in order, with the README line each comes from.
fn commands(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for b in blocks(text) {
        for (k, line) in b.lines.iter().enumerate() {
            let cmd = match b.lang.as_str() {
                "sh" | "bash" | "shell" => Some(line.as_str()),
                "console" => line.strip_prefix("$ "),
                _ => None,
            };
            if let Some(cmd) = cmd.map(str::trim).filter(|c| !c.is_empty() && !c.starts_with('#')) {
                out.push((b.line + k, cmd.to_string()));
            }
        }
    }
    out
}

/// The command line with the tool's invocation replaced by the built binary.
fn with_binary(cmd: &str) -> Option<String> {
    let bin = env!("CARGO_BIN_EXE_csm-lab");
    for prefix in ["cargo run --release --locked --", "cargo run --release --"] {
        if let Some(rest) = cmd.strip_prefix(prefix) {
            return Some(format!("{bin}{rest}"));
        }
    }
    cmd.strip_prefix("csm-lab ").map(|rest| format!("{bin} {rest}"))
}

fn copy_configs(to: &Path) {
    std::fs::create_dir(to.join("configs")).unwrap();
    for e in std::fs::read_dir(repo("configs")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join("configs").join(e.file_name())).unwrap();
    }
}

/// Whitespace runs folded to one space (the README wraps long printed lines).
fn folded(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The fenced block right after the HTML comment that starts with `marker`.
fn block_after<'a>(blocks: &'a [Block], text: &str, marker: &str) -> &'a Block {
    let at = text
        .find(marker)
        .unwrap_or_else(|| panic!("README.md: no {marker:?} marker"));
    let marker_line = text[..at].lines().count() + 1;
    blocks
        .iter()
        .find(|b| b.line > marker_line)
        .unwrap_or_else(|| panic!("README.md: no block after {marker:?}"))
}

#[test]
fn every_command_the_readme_shows_runs_and_exits_0() {
    let text = readme();
    let cmds = commands(&text);
    let dir = tempfile::tempdir().unwrap();
    copy_configs(dir.path());
    let mut ran = Vec::new();
    let mut stdout_of_default_sweep = None;
    for (line, cmd) in &cmds {
        let bare = cmd.split(" #").next().unwrap().trim();
        if NOT_RUN.iter().any(|(c, _)| bare == *c) {
            continue;
        }
        let shell = match with_binary(cmd) {
            Some(s) => s,
            None => {
                assert!(
                    !cmd.starts_with("cargo "),
                    "README.md:{line}: `{cmd}` is a cargo command this test neither runs nor \
                     lists in NOT_RUN"
                );
                cmd.clone()
            }
        };
        let out = Command::new("sh")
            .arg("-c")
            .arg(&shell)
            .current_dir(dir.path())
            .output()
            .unwrap();
        let expected = EXPECTED_EXIT
            .iter()
            .find(|(c, _)| bare == *c)
            .map_or(0, |(_, code)| *code);
        assert_eq!(
            out.status.code(),
            Some(expected),
            "README.md:{line}: `{cmd}`\nstdout:\n{}\nstderr:\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        if bare == "cargo run --release -- sweep configs/default.toml" {
            stdout_of_default_sweep = Some(String::from_utf8_lossy(&out.stdout).into_owned());
        }
        ran.push(cmd.clone());
    }
    // The extraction found the quick start and the "Your own scene" path, not nothing.
    let shown = |sub: &str| ran.iter().any(|c| c.contains(sub));
    for sub in [
        "-- sweep configs/default.toml",
        "cp configs/default.toml configs/my_scene.toml",
        "-- sweep configs/my_scene.toml",
        "--preset bevy",
        "--engine-settings out/my_scene/sweep-bevy/recommendation.bevy.txt",
        "check configs/my_scene.toml --init",
        "check configs/my_scene.toml --thresholds",
    ] {
        assert!(shown(sub), "no README command contains {sub:?}: ran {ran:?}");
    }
    // The commands wrote where the README says they do.
    let d = dir.path();
    for f in [
        "out/default/sweep/report.html",
        "out/my_scene/sweep/report.html",
        "out/my_scene/sweep-bevy/recommendation.bevy.txt",
        "out/my_scene/analyze-bevy-settings/summary.json",
        "ci/my-scene-gate.toml",
        "ci/my-scene-gate.baseline.json",
    ] {
        assert!(d.join(f).is_file(), "{f} was not written");
    }

    // The printed verdict the README shows is what the sweep prints, piece by piece ("..."
    // marks what the README leaves out).
    let all = blocks(&text);
    let verdict = block_after(
        &all,
        &text,
        "<!-- printed by: cargo run --release -- sweep configs/default.toml",
    );
    let printed = folded(&stdout_of_default_sweep.expect("the default sweep ran"));
    let shown = verdict.lines.join("\n");
    let pieces: Vec<&str> = shown.split("...\n").collect();
    assert!(pieces.len() >= 3, "{shown}");
    for piece in pieces {
        let piece = folded(piece);
        assert!(
            printed.contains(&piece),
            "README.md:{}: not printed by the sweep:\n{piece}\nprinted:\n{printed}",
            verdict.line
        );
    }

    // The engine settings file the README shows is the one the command writes.
    let settings = block_after(&all, &text, "<!-- written by the command above");
    assert_eq!(settings.lang, "rust");
    let written = std::fs::read_to_string(d.join("out/my_scene/sweep-bevy/recommendation.bevy.txt")).unwrap();
    assert_eq!(
        settings.lines.join("\n"),
        written.trim_end(),
        "README.md:{}: the Bevy settings differ from what `sweep --preset bevy` writes",
        settings.line
    );
}

/// GitHub's anchor of a heading: lower case, spaces to hyphens, other punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c.to_ascii_lowercase()),
            _ => None,
        })
        .collect()
}

#[test]
fn the_readme_has_the_shape_of_issue_19_and_its_links_resolve() {
    let text = readme();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len() <= 200, "README.md has {} lines", lines.len());
    // It opens with the two commands, verbatim (CI runs them).
    let first = &blocks(&text)[0];
    assert_eq!(first.lang, "sh");
    assert!(first.lines[0].starts_with("cargo run --release -- sweep configs/default.toml "));
    assert!(first.lines[1].starts_with("cargo test --release "));
    let own = lines
        .iter()
        .position(|l| *l == "## Your own scene")
        .expect("a \"Your own scene\" heading");
    assert!(own < 100, "\"Your own scene\" at line {}", own + 1);
    let arch = text.find("docs/architecture.md").unwrap();
    assert!(text[..arch].lines().count() < 30, "docs/architecture.md linked late");

    assert!(links_resolve(&repo("README.md")) > 20);
}

/// Checks that every relative link of a Markdown file names a file that exists and, with a
/// `#fragment`, a heading of that file; returns how many links it checked.
fn links_resolve(file: &Path) -> usize {
    let text = std::fs::read_to_string(file).unwrap();
    let dir = file.parent().unwrap();
    let mut rest = text.as_str();
    let mut checked = 0;
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        let Some(end) = rest.find(')') else { break };
        let target = &rest[..end];
        if target.starts_with("http") || target.contains(' ') {
            continue;
        }
        let (name, frag) = target.split_once('#').unwrap_or((target, ""));
        let path = if name.is_empty() {
            file.to_path_buf()
        } else {
            dir.join(name)
        };
        assert!(path.exists(), "{}: links {target}: no such file", file.display());
        if !frag.is_empty() {
            let doc = std::fs::read_to_string(&path).unwrap();
            let anchors: Vec<String> = doc
                .lines()
                .filter(|l| l.starts_with('#'))
                .map(|l| anchor(l.trim_start_matches('#').trim()))
                .collect();
            assert!(
                anchors.iter().any(|a| a == frag),
                "{}: links {target}: no such heading",
                file.display()
            );
        }
        checked += 1;
    }
    checked
}

#[test]
fn the_links_of_contributing_and_docs_resolve() {
    let mut checked = links_resolve(&repo("CONTRIBUTING.md"));
    for e in std::fs::read_dir(repo("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            checked += links_resolve(&p);
        }
    }
    assert!(checked > 50, "{checked} links");
}
