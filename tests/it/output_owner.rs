//! An output directory has an owner: a run removes only what it can prove csm-lab wrote (a
//! staging directory with a valid marker), never a user's files whatever their names, and two
//! runs into one directory (in one PID namespace or two) write one after the other: one whole
//! set in the end, or a clear message for the one that does not wait.

use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::common::files;
use csm_lab::output::DirLock;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn sweep_args(out: &Path, lambda: &str) -> Vec<String> {
    [
        "sweep",
        concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml"),
        "--quiet",
        "--no-plots",
        "--lambda",
        lambda,
        "--out",
        out.to_str().unwrap(),
    ]
    .map(str::to_string)
    .to_vec()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_run_never_removes_user_files_that_look_like_temporaries_or_staging_directories() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join(".sweep.csv.backup.tmp"), "backup").unwrap();
    std::fs::write(out.join(".report.md.draft1.tmp"), "draft").unwrap();
    let mywork = out.join(".csm-lab-staging-999999-mywork");
    std::fs::create_dir(&mywork).unwrap();
    std::fs::write(mywork.join("notes"), "notes").unwrap();
    let o = bin().args(sweep_args(&out, "0.5,0.75")).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(out.join(".sweep.csv.backup.tmp")).unwrap(),
        "backup"
    );
    assert_eq!(
        std::fs::read_to_string(out.join(".report.md.draft1.tmp")).unwrap(),
        "draft"
    );
    assert_eq!(std::fs::read_to_string(mywork.join("notes")).unwrap(), "notes");
    assert!(out.join("sweep.csv").is_file());
    assert!(!stderr(&o).contains("removed"), "{}", stderr(&o));
}

#[test]
fn a_run_that_does_not_wait_says_another_run_is_writing_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let held = DirLock::acquire(&out).unwrap();
    let o = bin()
        .args(sweep_args(&out, "0.5,0.75"))
        .arg("--no-wait")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("another csm-lab run is writing") && e.contains(out.to_str().unwrap()),
        "{e}"
    );
    assert!(files(&out).is_empty(), "{:?}", files(&out).keys());
    // Without --no-wait the run waits for the lock and then writes its whole set.
    let child = bin()
        .args(sweep_args(&out, "0.5,0.75"))
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert!(files(&out).is_empty(), "wrote while another run held the directory");
    drop(held);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("waiting for it to finish"), "{}", stderr(&o));
    assert!(files(&out).contains_key("sweep.csv"));
}

/// Two runs into one directory at once: both succeed in turn and the directory holds one whole
/// set (the one of the run that wrote last), byte for byte that run's set written alone.
#[test]
fn two_concurrent_runs_into_one_directory_leave_one_whole_set() {
    let dir = tempfile::tempdir().unwrap();
    let (a_dir, b_dir, out) = (dir.path().join("a"), dir.path().join("b"), dir.path().join("out"));
    for (d, l) in [(&a_dir, "0.25,0.5"), (&b_dir, "0.5,0.75")] {
        let o = bin().args(sweep_args(d, l)).output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    let (a, b) = (files(&a_dir), files(&b_dir));
    assert_ne!(a, b);
    for trial in 0..3 {
        let _ = std::fs::remove_dir_all(&out);
        let one = bin()
            .args(sweep_args(&out, "0.25,0.5"))
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let two = bin()
            .args(sweep_args(&out, "0.5,0.75"))
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (o1, o2) = (one.wait_with_output().unwrap(), two.wait_with_output().unwrap());
        assert_eq!(o1.status.code(), Some(0), "{}", stderr(&o1));
        assert_eq!(o2.status.code(), Some(0), "{}", stderr(&o2));
        let now = files(&out);
        assert!(now == a || now == b, "trial {trial}: a mixed set");
        let leftovers: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".csm-lab-staging-"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
    }
}

/// The same across PID namespaces (a CI container sharing a volume with the host): the lock is
/// the kernel's, not a process id, so a run in another namespace sees this one's lock. Needs
/// `unshare` with the right to make a PID namespace; skipped with a printed reason otherwise.
#[cfg(target_os = "linux")]
#[test]
fn a_run_in_another_pid_namespace_sees_the_lock() {
    let probe = Command::new("unshare")
        .args(["--pid", "--fork", "--mount-proc", "true"])
        .output();
    match probe {
        Ok(o) if o.status.success() => {}
        Ok(o) => {
            eprintln!(
                "SKIPPED a_run_in_another_pid_namespace_sees_the_lock: `unshare --pid --fork --mount-proc true` failed here ({})",
                String::from_utf8_lossy(&o.stderr).trim()
            );
            return;
        }
        Err(e) => {
            eprintln!("SKIPPED a_run_in_another_pid_namespace_sees_the_lock: no `unshare` command ({e})");
            return;
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let namespaced = |extra: &[&str]| {
        Command::new("unshare")
            .args(["--pid", "--fork", "--mount-proc", env!("CARGO_BIN_EXE_csm-lab")])
            .args(&sweep_args(&out, "0.5,0.75")[..])
            .args(extra)
            .output()
            .unwrap()
    };
    // This process (the host namespace) holds the directory; the namespaced run cannot take it.
    let held = DirLock::acquire(&out).unwrap();
    let o = namespaced(&["--no-wait"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("another csm-lab run is writing"), "{}", stderr(&o));
    drop(held);
    // A namespaced run's staging directory, with its marker and a live lock, is not touched by
    // a host run: run both at once, both succeed in turn, one whole set remains.
    let host = bin()
        .args(sweep_args(&out, "0.25,0.5"))
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = namespaced(&[]);
    let h = host.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(h.status.code(), Some(0), "{}", stderr(&h));
    assert!(files(&out).contains_key("sweep.csv"));
}
