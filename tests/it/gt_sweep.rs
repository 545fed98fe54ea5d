//! `sweep --ground-truth` (issue 11 item 5): the sample of rows, S5 beside S3 and S4 in
//! flicker.csv, the flicker_vs_shimmer figure, and its agreement with `analyze --ground-truth`.

use crate::common::files;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

/// A small scene (ground, one box) with a 15-row sweep (5 λ × 3 cascade counts, sphere fit).
fn scene(lambda: f64, cascades: usize, sweep: &str) -> String {
    format!(
        r#"
[camera]
position = [0.0, 6.0, 12.0]
target = [0.0, 0.0, -6.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 60.0
near = 0.1
far = 200.0

[screen]
width = 320
height = 180

[light]
direction = [-0.4, -1.0, -0.3]

[scene]
min = [-60.0, 0.0, -60.0]
max = [60.0, 10.0, 60.0]
ground = 0.0

[[scene.box]]
min = [-2.3, 0.0, -8.7]
max = [1.9, 3.1, -4.4]

[shadow]
max_distance = 60.0
cascades = {cascades}
lambda = {lambda}
resolution = 256
fit = "sphere"
snap = true
depth_bias = 0.05

[motion]
path = "strafe"
frames = 24
step = 0.05

[analysis]
screen_scale = 0.25

{sweep}
"#
    )
}

const SWEEP: &str = "[sweep]\nlambda = [0.0, 0.25, 0.5, 0.75, 1.0]\ncascades = [1, 2, 3]\nresolution = [256]\n";

fn csm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_csm-lab")).args(args).output().unwrap()
}

fn sweep(cfg: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut a = vec![
        "sweep",
        cfg.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    a.extend_from_slice(extra);
    csm(&a)
}

/// flicker.csv as (header, rows of cells); the setting label is quoted and holds commas.
fn flicker_csv(dir: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("flicker.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            let (head, rest) = l.split_once(",\"").unwrap();
            let (_, tail) = rest.split_once("\",").unwrap();
            let cells: Vec<&str> = std::iter::once(head)
                .chain(std::iter::once(""))
                .chain(tail.split(','))
                .collect();
            header
                .iter()
                .cloned()
                .zip(cells.iter().map(|s| s.to_string()))
                .collect()
        })
        .collect()
}

/// The sample rule, computed here: N = 12 rows of M by the golden-ratio sequence
/// frac(k·(√5−1)/2), a taken row moving on to the next free one, then the recommended row in
/// place of its nearest sampled row (the lower on a tie).
fn expected_sample(m: usize, rec: usize) -> Vec<usize> {
    if m <= 12 {
        return (0..m).collect();
    }
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut taken = vec![false; m];
    for k in 0..12 {
        let x = k as f64 * g;
        let mut i = ((x - x.floor()) * m as f64).floor() as usize;
        while taken[i] {
            i = (i + 1) % m;
        }
        taken[i] = true;
    }
    if !taken[rec] {
        let d = (1..m)
            .find(|d| (rec >= *d && taken[rec - d]) || (rec + d < m && taken[rec + d]))
            .unwrap();
        let lower = rec >= d && taken[rec - d];
        taken[if lower { rec - d } else { rec + d }] = false;
        taken[rec] = true;
    }
    (0..m).filter(|&i| taken[i]).collect()
}

#[test]
fn the_sample_rule_matches_an_independent_computation() {
    // The rule over many grid sizes and recommended rows, against the library's.
    for m in [1, 5, 12, 13, 14, 20, 37, 100, 672, 1000] {
        for rec in [0, m / 3, m / 2, m - 1] {
            let got = csm_lab::commands::sweep::flicker::sample_indices(m, Some(rec));
            assert_eq!(got, expected_sample(m, rec), "m = {m}, recommended {rec}");
            assert_eq!(got.len(), m.min(12));
            assert!(got.contains(&rec));
        }
    }
}

#[test]
fn sweep_ground_truth_samples_rows_and_matches_analyze() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("scene.toml");
    std::fs::write(&cfg, scene(0.75, 2, SWEEP)).unwrap();
    let plain = dir.path().join("plain");
    let one = dir.path().join("one");
    let two = dir.path().join("two");
    let o = sweep(&cfg, &plain, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!plain.join("flicker.csv").exists() && !plain.join("flicker_vs_shimmer.svg").exists());
    let o1 = sweep(&cfg, &one, &["--ground-truth", "--threads", "1"]);
    assert!(o1.status.success(), "{}", String::from_utf8_lossy(&o1.stderr));
    let o2 = sweep(&cfg, &two, &["--ground-truth", "--threads", "2"]);
    assert!(o2.status.success());
    // Byte-identical at 1 and 2 threads, stdout included; sweep.csv as without the flag.
    let (f1, f2) = (files(&one), files(&two));
    assert_eq!(f1, f2);
    assert_eq!(
        String::from_utf8_lossy(&o1.stdout).replace(one.to_str().unwrap(), "DIR"),
        String::from_utf8_lossy(&o2.stdout).replace(two.to_str().unwrap(), "DIR")
    );
    assert_eq!(f1["sweep.csv"], files(&plain)["sweep.csv"]);
    for f in ["flicker.csv", "flicker_vs_shimmer.svg", "flicker_vs_shimmer.png"] {
        assert!(f1.contains_key(f), "{f}");
    }

    // The sample: 12 of the 15 rows, by the rule, with the recommended row.
    let sweep_csv = String::from_utf8(f1["sweep.csv"].clone()).unwrap();
    let col = sweep_csv
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|h| h == "recommended")
        .unwrap();
    let rec_row = sweep_csv
        .lines()
        .skip(1)
        .position(|l| l.split(',').nth(col) == Some("true"))
        .expect("a recommended row");
    let rows = flicker_csv(&one);
    let idx: Vec<usize> = rows.iter().map(|r| r["row"].parse().unwrap()).collect();
    assert_eq!(idx, expected_sample(15, rec_row));
    assert_eq!(
        rows.iter().filter(|r| r["recommended"] == "true").count(),
        1,
        "the recommended row is sampled"
    );
    let stdout = String::from_utf8_lossy(&o1.stdout);
    assert!(stdout.contains("S5 computed for 12 of 15 rows"), "{stdout}");
    assert!(stdout.contains("S5 ≈ "), "{stdout}");
    let report = String::from_utf8(f1["report.md"].clone()).unwrap();
    assert!(report.contains("## Does shimmer predict flicker?") && report.contains("S5 computed for 12 of 15 rows"));
    let html = String::from_utf8_lossy(&f1["report.html"]);
    assert!(html.contains("Does shimmer predict flicker?"));
    // The recommended setting's ground-truth pictures are embedded (stills and animation).
    assert!(
        html.contains("<h2>Shadow-map ground truth</h2>"),
        "the pictures' section"
    );
    assert!(
        html.matches("data:image/png;base64,").count() >= 4,
        "camera views and the two stills"
    );
    assert!(html.contains("data:image/apng;base64,") || html.contains("shadow.apng"));

    let mut unsnapped_positive = 0;
    for r in &rows {
        // Snapped sphere fits: the map moves by whole texels with the window, so nothing flips.
        assert_eq!(r["fit"], "sphere");
        assert_eq!(r["flicker_snapped"], "0", "{r:?}");
        if r["flicker_unsnapped"].parse::<f64>().unwrap() > 0.0 {
            unsnapped_positive += 1;
        }
    }
    assert!(unsnapped_positive > 0);

    // A sampled row's S5 is what `analyze --ground-truth` measures for that setting's config.
    for r in [&rows[0], &rows[rows.len() - 1]] {
        let single = dir.path().join(format!("one-{}", r["row"]));
        std::fs::write(
            &single,
            scene(r["lambda"].parse().unwrap(), r["cascades"].parse().unwrap(), ""),
        )
        .unwrap();
        let out = dir.path().join(format!("analyze-{}", r["row"]));
        let a = csm(&[
            "analyze",
            single.to_str().unwrap(),
            "--ground-truth",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
        let s: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        for key in ["flicker_snapped", "flicker_unsnapped"] {
            assert_eq!(
                s[key].as_f64().unwrap(),
                r[key].parse::<f64>().unwrap(),
                "row {} {key}",
                r["row"]
            );
        }
    }
}

#[test]
fn sweep_ground_truth_bad_input_names_the_flag_or_key() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("bare.toml");
    let out = dir.path().join("out");
    // No geometry: refused, naming the flag, exit 2, nothing written.
    let bare = scene(0.75, 2, SWEEP)
        .replace("ground = 0.0\n", "")
        .replace("[[scene.box]]\nmin = [-2.3, 0.0, -8.7]\nmax = [1.9, 3.1, -4.4]\n", "");
    std::fs::write(&cfg, &bare).unwrap();
    let e = sweep(&cfg, &out, &["--ground-truth"]);
    assert_eq!(e.status.code(), Some(2));
    let msg = String::from_utf8_lossy(&e.stderr);
    assert!(msg.contains("--ground-truth") && msg.contains("geometry"), "{msg}");
    assert!(!out.exists());
    // The config key, named as such.
    std::fs::write(&cfg, bare.replace("[sweep]\n", "[sweep]\nground_truth = true\n")).unwrap();
    let e = sweep(&cfg, &out, &[]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("sweep.ground_truth"));
    // A value of the wrong type.
    std::fs::write(
        &cfg,
        scene(
            0.75,
            2,
            &SWEEP.replace("[sweep]\n", "[sweep]\nground_truth = \"yes\"\n"),
        ),
    )
    .unwrap();
    let e = sweep(&cfg, &out, &[]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("ground_truth"));
    // A shard holds only part of the rows.
    std::fs::write(&cfg, scene(0.75, 2, SWEEP)).unwrap();
    let e = sweep(&cfg, &out, &["--ground-truth", "--shard", "1/2"]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("--ground-truth"));
}

#[test]
fn the_config_key_samples_in_a_sweep_and_in_the_merge_of_its_shards_not_in_a_shard() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("scene.toml");
    std::fs::write(
        &cfg,
        scene(0.75, 2, &SWEEP.replace("[sweep]\n", "[sweep]\nground_truth = true\n")),
    )
    .unwrap();
    let full = dir.path().join("full");
    assert!(sweep(&cfg, &full, &[]).status.success());
    assert!(full.join("flicker.csv").exists());
    let shards: Vec<_> = (1..=2).map(|k| dir.path().join(format!("s{k}"))).collect();
    for (k, d) in shards.iter().enumerate() {
        let mut a = vec!["sweep", cfg.to_str().unwrap(), "--out", d.to_str().unwrap()];
        let spec = format!("{}/2", k + 1);
        a.extend(["--shard", &spec]);
        let o = csm(&a);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stderr).contains("note: sweep.ground_truth left out"));
        assert!(!d.join("flicker.csv").exists());
    }
    let merged = dir.path().join("merged");
    let o = csm(&[
        "merge",
        "--quiet",
        "--out",
        merged.to_str().unwrap(),
        shards[0].to_str().unwrap(),
        shards[1].to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (f, m) = (files(&full), files(&merged));
    for name in ["flicker.csv", "flicker_vs_shimmer.svg", "report.md", "sweep.csv"] {
        assert_eq!(f[name], m[name], "{name}");
    }
}
