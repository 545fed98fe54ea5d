//! Running the README's commands in a fresh clone leaves `git status` clean: without `--out`
//! every command writes under `out/`, which `.gitignore` ignores, and never over the
//! committed samples in `reports/`.

use std::path::Path;
use std::process::Command;

fn git(dir: &Path, args: &[&str]) -> String {
    let o = Command::new("git")
        .args(args)
        .current_dir(dir)
        .env("GIT_AUTHOR_NAME", "t")
        .env("GIT_AUTHOR_EMAIL", "t@example.com")
        .env("GIT_COMMITTER_NAME", "t")
        .env("GIT_COMMITTER_EMAIL", "t@example.com")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "git {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[test]
fn the_readme_commands_leave_a_fresh_clone_clean() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for sub in ["configs", "reports"] {
        copy_dir(&root.join(sub), &d.join(sub));
    }
    std::fs::copy(root.join(".gitignore"), d.join(".gitignore")).unwrap();
    git(d, &["init", "-q"]);
    git(d, &["add", "-A"]);
    git(d, &["commit", "-q", "-m", "clone"]);
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    // The commands the README tells a user to run (the quick start, the commands table and
    // the sections that show outputs), without `--out`.
    let commands: [&[&str]; 7] = [
        &["sweep", "configs/default.toml", "--quiet"],
        &["analyze", "configs/default.toml"],
        &["compare", "configs/default.toml"],
        &["compare", "configs/default.toml", "--defaults"],
        &[
            "check",
            "configs/default.toml",
            "--thresholds",
            "configs/thresholds.toml",
        ],
        &["stress"],
        &["bench", "--repeats", "1"],
    ];
    for c in commands {
        assert!(readme.contains(&format!("csm-lab {}", c[0])) || readme.contains(&format!("-- {}", c[0])));
        let o = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
            .args(c)
            .current_dir(d)
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{c:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert!(d.join("out/default/sweep/report.html").is_file());
    assert!(d.join("out/bench/bench.csv").is_file());
    assert!(d.join("out/stress/stress.csv").is_file());
    assert_eq!(git(d, &["status", "--porcelain"]), "", "the commands changed the clone");
}
