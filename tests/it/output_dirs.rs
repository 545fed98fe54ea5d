//! Outputs that do not collide (issue 21, item 7): every command writes its own folder under
//! `out/<config name>/` by default, so two commands run one after the other leave both
//! answers on disk, and `--out DIR` writes exactly into `DIR`.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::{files, BASE};

fn run(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}\nstdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The names of the entries of a directory, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The sequence: `sweep --preset unity` recommends a Unity setting and writes it as
/// `recommendation.unity.txt`; `compare` then writes Unity at the compared setting under the
/// same file name. Both stay on disk, the sweep's byte for byte.
#[test]
fn a_unity_sweep_then_compare_leave_both_answers() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("configs")).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(root.join("configs/default.toml"), d.join("configs/default.toml")).unwrap();
    run(d, &["sweep", "configs/default.toml", "--quiet", "--preset", "unity"]);
    let swept = d.join("out/default/sweep-unity/recommendation.unity.txt");
    let recommended = std::fs::read_to_string(&swept).unwrap();
    let sweep_files = files(&d.join("out/default/sweep-unity"));
    assert!(
        recommended.contains("// from: csm-lab sweep configs/default.toml --preset unity"),
        "{recommended}"
    );
    assert!(recommended.contains("the recommended setting"), "{recommended}");

    let printed = run(
        d,
        &["compare", "configs/default.toml", "--quiet", "--presets", "unity,bevy"],
    );
    let stdout = String::from_utf8_lossy(&printed.stdout);
    assert!(stdout.contains("to out/default/compare"), "{stdout}");
    let compared = std::fs::read_to_string(d.join("out/default/compare/recommendation.unity.txt")).unwrap();
    assert!(
        compared.contains("// from: csm-lab compare configs/default.toml"),
        "{compared}"
    );
    assert_ne!(compared, recommended, "two different answers under one name");
    // The sweep's answer is untouched: every file of its folder, byte for byte.
    assert_eq!(std::fs::read_to_string(&swept).unwrap(), recommended);
    assert_eq!(files(&d.join("out/default/sweep-unity")), sweep_files);
    assert_eq!(entries(&d.join("out/default")), ["compare", "sweep-unity"]);
}

/// Each command's default folder, and `--out DIR` exactly.
#[test]
fn each_command_writes_its_own_folder_and_out_writes_exactly_there() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("scene.toml"), BASE).unwrap();
    let small = ["--cascades", "2,4", "--resolution", "1024", "--quiet", "--no-plots"];
    let sweep = |extra: &[&str]| {
        let mut a = vec!["sweep", "scene.toml"];
        a.extend(small);
        a.extend(extra);
        run(d, &a)
    };
    run(d, &["analyze", "scene.toml", "--quiet"]);
    run(d, &["analyze", "scene.toml", "--quiet", "--preset", "bevy"]);
    sweep(&["--lambda", "0,0.5,1"]);
    sweep(&["--preset", "bevy"]);
    sweep(&["--lambda", "0,0.5,1", "--shard", "1/2"]);
    sweep(&["--lambda", "0,0.5,1", "--shard", "2/2"]);
    run(d, &["compare", "scene.toml", "--quiet", "--presets", "bevy,unity"]);
    // An engine settings file read back measures into its own folder.
    run(
        d,
        &[
            "analyze",
            "scene.toml",
            "--quiet",
            "--engine-settings",
            "out/scene/sweep-bevy/recommendation.bevy.txt",
        ],
    );
    let out = d.join("out/scene");
    assert_eq!(
        entries(&out),
        [
            "analyze",
            "analyze-bevy",
            "analyze-bevy-settings",
            "compare",
            "sweep",
            "sweep-bevy"
        ]
    );
    for a in ["analyze", "analyze-bevy", "analyze-bevy-settings"] {
        assert!(out.join(a).join("summary.json").is_file(), "{a}");
    }
    let summary = |a: &str| std::fs::read_to_string(out.join(a).join("summary.json")).unwrap();
    assert!(!summary("analyze").contains("\"preset\""), "{}", summary("analyze"));
    assert!(summary("analyze-bevy").contains("bevy"), "{}", summary("analyze-bevy"));
    assert_eq!(
        entries(&out.join("sweep")),
        [
            "recommendation.json",
            "report.html",
            "report.md",
            "shard-1-of-2",
            "shard-2-of-2",
            "sweep.csv"
        ]
    );
    assert!(out.join("sweep/shard-1-of-2/shard.json").is_file());
    assert!(out.join("sweep-bevy/recommendation.bevy.txt").is_file());
    assert!(out.join("compare/compare.csv").is_file());
    assert!(!out.join("compare/sweep.csv").exists());

    // merge writes where the unsharded sweep does: its files are that sweep's.
    let direct = files(&out.join("sweep"));
    std::fs::remove_file(out.join("sweep/sweep.csv")).unwrap();
    run(
        d,
        &[
            "merge",
            "out/scene/sweep/shard-1-of-2",
            "out/scene/sweep/shard-2-of-2",
            "--quiet",
            "--no-plots",
        ],
    );
    assert_eq!(files(&out.join("sweep")), direct);

    // --out DIR: exactly DIR, no folder added.
    run(d, &["analyze", "scene.toml", "--quiet", "--out", "elsewhere"]);
    assert!(d.join("elsewhere/summary.json").is_file());
    assert!(!d.join("elsewhere/analyze").exists());
}
