//! Output sets are all or nothing: a run killed at any moment leaves the previous run's files
//! (or, killed while moving its staged set into place, a staged set the next run completes),
//! never a mix; the next run removes what the killed one left and touches nothing else.

use crate::common::files;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

fn sweep(out: &Path, lambda: &str) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_csm-lab"));
    c.args([
        "sweep",
        concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml"),
        "--quiet",
    ])
    .args(["--lambda", lambda, "--out"])
    .arg(out)
    .stdout(Stdio::null())
    .stderr(Stdio::null());
    c
}

/// Names of the hidden entries csm-lab makes while writing (staging directories, temporaries).
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".csm-lab-staging-") || n.ends_with(".tmp"))
        .collect()
}

#[cfg(unix)]
#[test]
fn a_killed_sweep_never_leaves_a_mixed_set_and_the_next_run_cleans_up() {
    let tmp = tempfile::tempdir().unwrap();
    let (a_dir, b_dir, dir) = (tmp.path().join("a"), tmp.path().join("b"), tmp.path().join("out"));
    assert!(sweep(&a_dir, "0.25,0.5").status().unwrap().success());
    assert!(sweep(&b_dir, "0.5,0.75").status().unwrap().success());
    let (a, b) = (files(&a_dir), files(&b_dir));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    assert!(a.iter().any(|(k, v)| b[k] != *v), "the two sets must differ");
    let mut outcomes = BTreeMap::new();
    for k in 0..14u64 {
        // The previous run's set, and a user's own file beside it.
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for (name, bytes) in &a {
            std::fs::write(dir.join(name), bytes).unwrap();
        }
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        let mut child = sweep(&dir, "0.5,0.75").spawn().unwrap();
        std::thread::sleep(Duration::from_millis(25 * k));
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        let mut now = files(&dir);
        assert_eq!(now.remove("notes.txt").as_deref(), Some(&b"mine"[..]), "kill after {k}");
        let staged_complete = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .any(|p| p.is_dir() && p.join(".complete").is_file());
        let outcome = if now == a {
            "previous set"
        } else if now == b {
            "new set"
        } else {
            // Only a kill in the middle of the renames mixes the sets, and then the staged set
            // is complete: the next run finishes the move.
            assert!(
                staged_complete,
                "kill after {k}: a mixed set without a complete staged set"
            );
            for (name, bytes) in &now {
                assert!(
                    a[name] == *bytes || b[name] == *bytes,
                    "kill after {k}: {name} is neither set's"
                );
            }
            "mid-move"
        };
        *outcomes.entry(outcome).or_insert(0) += 1;
        // The next run: the new set exactly, nothing of the killed run's left, the user's file kept.
        assert!(sweep(&dir, "0.5,0.75").status().unwrap().success());
        let mut after = files(&dir);
        assert_eq!(after.remove("notes.txt").as_deref(), Some(&b"mine"[..]));
        assert!(after == b, "kill after {k}: the next run did not write the new set");
        assert_eq!(leftovers(&dir), Vec::<String>::new(), "kill after {k}");
    }
    eprintln!("kill outcomes: {outcomes:?}");
    // Kills landed before the move at least (a 0 ms kill always does).
    assert!(outcomes.contains_key("previous set"), "{outcomes:?}");
}
