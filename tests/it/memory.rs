//! Peak memory of a walk along a long camera path: flat in the frame count. Measured on the
//! real binary (its peak resident set, from the kernel), not timed.

use crate::common::with;

/// Peak resident set (KiB) of `csm-lab analyze` on the test scene yawing for `frames` frames,
/// read with `wait4` for that one child (not the test process's other children).
#[cfg(target_os = "linux")]
#[allow(clippy::zombie_processes)] // reaped by `wait4`, which `Child::wait` cannot replace here
fn peak_rss_kib(frames: usize, extra: &[&str]) -> i64 {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("yaw.toml");
    let text = with(&[
        ("motion.path", "path = \"yaw\""),
        ("motion.frames", &format!("frames = {frames}")),
    ]);
    std::fs::write(&cfg, text).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(["analyze", cfg.to_str().unwrap(), "--out"])
        .arg(dir.path().join("out"))
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value, and `wait4` fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t, "wait4 failed");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "analyze failed: {status}"
    );
    // The run wrote its files, with every frame in the summary.
    let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    assert!(summary.contains(&format!("\"frames\": {frames}")), "{summary}");
    usage.ru_maxrss
}

#[cfg(target_os = "linux")]
#[test]
fn peak_memory_at_a_hundred_thousand_frames_is_within_ten_percent_of_a_thousand() {
    let small = peak_rss_kib(1_000, &[]);
    let large = peak_rss_kib(100_000, &[]);
    assert!(small > 1_000, "implausible peak {small} KiB");
    assert!(
        (large as f64) <= 1.10 * small as f64,
        "peak RSS {large} KiB at 100,000 frames against {small} KiB at 1,000"
    );
}

/// `--all-frames` streams every frame's rows into shimmer.csv: 800,000 rows at 10^5 frames in
/// the memory of 1,000 frames.
#[cfg(target_os = "linux")]
#[test]
fn every_frame_streamed_keeps_the_peak_memory_of_a_thousand_frames() {
    let small = peak_rss_kib(1_000, &["--all-frames"]);
    let large = peak_rss_kib(100_000, &["--all-frames"]);
    assert!(
        (large as f64) <= 1.10 * small as f64,
        "peak RSS {large} KiB at 100,000 frames (every frame written) against {small} KiB at 1,000"
    );
}
