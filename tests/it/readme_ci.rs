//! The CI snippet of `docs/check.md` ("Setting a gate up", moved there from the README), run
//! verbatim in a fresh directory holding the bundled configs:
//! `--init` and the commit, then the workflow's `run:` step exits 0; after a change that makes
//! aliasing 10 % worse (shadow.resolution 2048 -> 1861: aliasing is proportional to the texel size) the
//! same step exits 1. Also the gate's guarantees from issue 14: `snap = false` against a
//! snapped baseline fails on `shimmer`; `check --sweep` stays short; a failed run replaces the
//! JUnit file.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_csm-lab"))
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// The lines of the `docs/check.md` block after the `ci-init` marker (fenced with ```), and the
/// `run: >` command of the workflow.
fn snippets() -> (Vec<String>, String) {
    let doc = std::fs::read_to_string(repo("docs/check.md")).unwrap();
    let at = doc.find("<!-- ci-init").expect("the ci-init marker");
    let block = &doc[at..];
    let body = &block[block.find("```sh\n").unwrap() + 6..];
    let body = &body[..body.find("```").unwrap()];
    let init: Vec<String> = body.lines().map(str::to_string).collect();
    let yaml = &block[block.find("```yaml\n").unwrap()..];
    let run_at = yaml.find("run: >\n").unwrap() + 7;
    let mut run = Vec::new();
    for line in yaml[run_at..].lines() {
        if !line.starts_with("          ") {
            break;
        }
        run.push(line.trim());
    }
    (init, run.join(" "))
}

/// Runs a documented command line with `cargo run ... --` replaced by the built binary.
fn sh(dir: &Path, line: &str) -> i32 {
    let line = line
        .replace("cargo run --release --locked --", &bin().display().to_string())
        .replace("cargo run --release --", &bin().display().to_string());
    let out = Command::new("sh")
        .arg("-c")
        .arg(&line)
        .current_dir(dir)
        .env("GIT_AUTHOR_NAME", "t")
        .env("GIT_AUTHOR_EMAIL", "t@example.com")
        .env("GIT_COMMITTER_NAME", "t")
        .env("GIT_COMMITTER_EMAIL", "t@example.com")
        .output()
        .unwrap();
    eprintln!(
        "$ {line}\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out.status.code().unwrap()
}

fn fresh_clone() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("configs")).unwrap();
    for e in std::fs::read_dir(repo("configs")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), dir.path().join("configs").join(e.file_name())).unwrap();
    }
    for cmd in ["git init -q", "git add configs", "git commit -q -m init"] {
        assert_eq!(sh(dir.path(), cmd), 0, "{cmd}");
    }
    dir
}

#[test]
fn the_ci_snippet_passes_on_a_fresh_clone_and_fails_after_a_10_percent_aliasing_regression() {
    let (init, run) = snippets();
    assert!(init.iter().any(|l| l.contains("--init")), "{init:?}");
    assert!(run.contains("--thresholds ci/shadow-gate.toml"), "{run}");
    let dir = fresh_clone();
    for line in &init {
        assert_eq!(sh(dir.path(), line), 0, "{line}");
    }
    assert_eq!(sh(dir.path(), &run), 0, "{run}");
    let xml = std::fs::read_to_string(dir.path().join("target/ci-report/check.xml")).unwrap();
    assert!(roxmltree::Document::parse(&xml).is_ok());
    assert!(xml.contains("failures=\"0\""));

    let cfg = dir.path().join("configs/default.toml");
    let text = std::fs::read_to_string(&cfg).unwrap();
    // The scene (camera, screen, light, bounds, motion) stays the baseline's; the setting worsens.
    assert!(text.contains("resolution = 2048"));
    std::fs::write(&cfg, text.replace("resolution = 2048", "resolution = 1861")).unwrap();
    assert_eq!(sh(dir.path(), &run), 1, "{run}");
    let xml = std::fs::read_to_string(dir.path().join("target/ci-report/check.xml")).unwrap();
    assert!(xml.contains("mean_aliasing"), "{xml}");
    assert!(!xml.contains("failures=\"0\" errors=\"0\" skipped=\"0\" time=\"0\">\n  <testsuite"));
}

#[test]
fn snap_false_against_a_snapped_gate_exits_1_naming_the_shimmer_rule() {
    let dir = fresh_clone();
    assert_eq!(
        sh(
            dir.path(),
            "csm-lab-bin check configs/default.toml --init ci/gate.toml"
                .replace("csm-lab-bin", &bin().display().to_string())
                .as_str()
        ),
        0
    );
    let cfg = dir.path().join("configs/default.toml");
    let text = std::fs::read_to_string(&cfg).unwrap();
    std::fs::write(&cfg, text.replace("snap = true", "snap = false")).unwrap();
    for format in ["table", "json"] {
        let out = Command::new(bin())
            .current_dir(dir.path())
            .args([
                "check",
                "configs/default.toml",
                "--thresholds",
                "ci/gate.toml",
                "--format",
                format,
            ])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{format}");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let failing: Vec<&str> = stdout
            .lines()
            .filter(|l| l.contains("FAIL") && l.contains(" shimmer "))
            .collect();
        if format == "table" {
            assert_eq!(failing.len(), 1, "{stdout}");
        } else {
            let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
            let rules = v["rules"].as_array().unwrap();
            assert!(
                rules.iter().any(|r| r["metric"] == "shimmer" && r["status"] == "fail"),
                "{v}"
            );
        }
    }
}

#[test]
fn check_sweep_prints_a_short_summary_unless_verbose() {
    let dir = fresh_clone();
    let run = |extra: &[&str]| {
        let out = Command::new(bin())
            .current_dir(dir.path())
            .args([
                "check",
                "configs/default.toml",
                "--thresholds",
                "configs/thresholds.toml",
                "--sweep",
            ])
            .args(extra)
            .output()
            .unwrap();
        (
            out.status.code().unwrap(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    let (code, text) = run(&[]);
    assert!(code == 0 || code == 1, "{text}");
    assert!(text.lines().count() <= 40, "{} lines:\n{text}", text.lines().count());
    assert!(text.contains("worst offenders"), "{text}");
    let (code_v, verbose) = run(&["--verbose"]);
    assert_eq!(code, code_v);
    assert!(verbose.lines().count() > 1000);
}

#[test]
fn a_check_that_cannot_run_replaces_an_earlier_passing_junit_file() {
    let dir = fresh_clone();
    let junit = dir.path().join("check.xml");
    let run = |config: &str| {
        Command::new(bin())
            .current_dir(dir.path())
            .args(["check", config, "--thresholds", "configs/thresholds.toml", "--junit"])
            .arg(&junit)
            .output()
            .unwrap()
            .status
            .code()
    };
    assert_eq!(run("configs/default.toml"), Some(0));
    assert!(std::fs::read_to_string(&junit).unwrap().contains("errors=\"0\""));
    assert_eq!(run("configs/missing.toml"), Some(2));
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let root = doc.root_element();
    assert_eq!(root.attribute("errors"), Some("1"));
    assert!(doc.descendants().any(|n| n.has_tag_name("error")
        && n.attribute("message")
            .is_some_and(|m| m.contains("configs/missing.toml"))));
}

#[test]
fn cascade_rules_beyond_a_scene_s_cascades_are_skipped_with_a_note() {
    for scene in ["indoor", "top_down", "open_world", "default"] {
        let out = Command::new(bin())
            .args([
                "check",
                &format!("configs/{scene}.toml"),
                "--thresholds",
                "configs/thresholds.toml",
            ])
            .current_dir(repo(""))
            .output()
            .unwrap();
        let code = out.status.code().unwrap();
        assert!(
            code == 0 || code == 1,
            "{scene}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn several_motion_paths_are_walked_and_the_summary_takes_the_worst() {
    use crate::common::{config, with};
    use csm_lab::analysis::{analyze, AnalysisOptions};
    let one = |path: &str, step: &str| {
        let c = config(&with(&[
            ("shadow.fit", "fit = \"aabb\""),
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", &format!("step = {step}")),
        ]));
        analyze(&c, &AnalysisOptions::full()).summary
    };
    let strafe = one("strafe", "0.05");
    let yaw = one("yaw", "0.5");
    let both_text = with(&[
        ("shadow.fit", "fit = \"aabb\""),
        ("motion.path", "paths = [\"strafe\", \"yaw\"]\nsteps = [0.05, 0.5]"),
    ]);
    let both = analyze(&config(&both_text), &AnalysisOptions::full());
    let s = &both.summary;
    assert_eq!(s.shimmer_snapped, strafe.shimmer_snapped.max(yaw.shimmer_snapped));
    assert_eq!(s.shimmer_unsnapped, strafe.shimmer_unsnapped.max(yaw.shimmer_unsnapped));
    assert_eq!(
        s.shimmer, s.shimmer_snapped,
        "snap = true: shimmer is the snapped value"
    );
    assert_eq!(s.size_jitter, strafe.size_jitter.max(yaw.size_jitter));
    assert_eq!(
        s.coverage_violations,
        strafe.coverage_violations + yaw.coverage_violations
    );
    // The tight AABB is still under strafe and shimmers under yaw: one gate sees both.
    assert!(strafe.shimmer_snapped < 1e-9 && yaw.shimmer_snapped > 1e-3);
    // shimmer.csv has rows of both paths.
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("two.toml");
    std::fs::write(&cfg, &both_text).unwrap();
    let out = Command::new(bin())
        .args([
            "analyze",
            cfg.to_str().unwrap(),
            "--out",
            dir.path().join("o").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let csv = std::fs::read_to_string(dir.path().join("o/shimmer.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(",path"));
    for p in ["strafe", "yaw"] {
        assert!(csv.lines().any(|l| l.ends_with(&format!(",{p}"))), "{p}");
    }
    // `path` and `paths` together, or steps that do not match, are config errors.
    for bad in [
        with(&[("motion.paths", "paths = [\"yaw\"]")]),
        with(&[("motion.path", "paths = [\"strafe\", \"yaw\"]\nsteps = [0.05]")]),
        with(&[("motion.path", "paths = [\"strafe\", \"strafe\"]")]),
    ] {
        let e = csm_lab::Config::from_toml_str(&bad, "t.toml", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("motion.paths") || e.contains("motion.steps"), "{e}");
    }
    // With snap = false, `shimmer` is the unsnapped value.
    let nosnap = with(&[
        ("shadow.snap", "snap = false"),
        ("motion.path", "paths = [\"strafe\", \"yaw\"]\nsteps = [0.05, 0.5]"),
    ]);
    let s = analyze(&config(&nosnap), &AnalysisOptions::summary_only()).summary;
    assert_eq!(s.shimmer, s.shimmer_unsnapped);
}

#[test]
fn unknown_metric_names_suggest_registry_names_and_synonyms() {
    let dir = tempfile::tempdir().unwrap();
    for (name, expected) in [
        ("shimmer_rms", "shimmer"),
        ("shimmer_snap", "shimmer_snapped"),
        ("coverage", "coverage_violations"),
    ] {
        let t = dir.path().join("t.toml");
        std::fs::write(&t, format!("[[rule]]\nmetric = \"{name}\"\nmax = 1\n")).unwrap();
        let out = Command::new(bin())
            .args(["check", "configs/default.toml", "--thresholds", t.to_str().unwrap()])
            .current_dir(repo(""))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(&format!("did you mean \"{expected}\"")), "{err}");
    }
}
