//! The `bench` command as a user runs it: files, table, determinism of the error columns.

use std::path::Path;
use std::process::{Command, Output};

fn bench(out: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(["bench", "--repeats", "1", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

struct Row {
    metric: String,
    samples: usize,
    seconds: f64,
    error: f64,
    estimate: f64,
    reference: f64,
}

fn rows(dir: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(dir.join("bench.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("metric,samples,seconds,error,estimate,reference"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 6, "{l}");
            let x = |i: usize| f[i].parse::<f64>().unwrap_or_else(|_| panic!("{l}"));
            Row {
                metric: f[0].to_string(),
                samples: f[1].parse().unwrap(),
                seconds: x(2),
                error: x(3),
                estimate: x(4),
                reference: x(5),
            }
        })
        .collect()
}

#[test]
fn bench_writes_csv_and_svg_prints_the_table_and_its_errors_are_deterministic() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let out = bench(&a, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let ra = rows(&a);

    let metrics = [
        "density_mean_aliasing",
        "density_mean_log_aliasing",
        "density_undersampled_fraction",
        "s4_cell_flips_strafe",
        "s3_rms_aabb_yaw",
        "s3_max_aabb_yaw",
        "s3_rms_frames_yaw",
    ];
    for m in metrics {
        let mine: Vec<&Row> = ra.iter().filter(|r| r.metric == m).collect();
        assert!(mine.len() >= 10, "{m}: {} rows", mine.len());
        assert!(mine.windows(2).all(|w| w[0].samples < w[1].samples), "{m}");
        for r in &mine {
            assert!(r.seconds > 0.0 && r.error >= 0.0 && r.estimate.is_finite(), "{m}");
            // The error column is what it says: recomputed from the estimate and reference.
            let rel = ((r.estimate - r.reference) / r.reference).abs();
            assert!((r.error - rel).abs() <= 1e-12 * rel.max(1.0), "{m} {}", r.samples);
        }
        // Each estimate converges: the densest is far better than the sparsest.
        let (first, last) = (mine[0], mine[mine.len() - 1]);
        assert!(
            last.error < 0.05 && last.error < first.error,
            "{m}: {} -> {}",
            first.error,
            last.error
        );
        // The table's "reaches" column: the first count from which every error is <= 1e-3.
        let mut reach = None;
        for r in mine.iter().rev() {
            if r.error <= 1e-3 {
                reach = Some(r.samples);
            } else {
                break;
            }
        }
        let line = stdout
            .lines()
            .find(|l| l.starts_with(m))
            .unwrap_or_else(|| panic!("{stdout}"));
        let col = line.split_whitespace().nth(2).unwrap();
        match reach {
            Some(n) => assert_eq!(col, n.to_string(), "{line}"),
            None => assert!(col.starts_with('>'), "{line}"),
        }
    }
    // The closed-form density aggregates and S4 are reached well within the measured range.
    for m in [
        "density_mean_aliasing",
        "density_mean_log_aliasing",
        "s4_cell_flips_strafe",
    ] {
        let line = stdout.lines().find(|l| l.starts_with(m)).unwrap();
        assert!(!line.split_whitespace().nth(2).unwrap().starts_with('>'), "{line}");
    }

    let svg = std::fs::read_to_string(a.join("bench.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    for text in [
        "relative error",
        "time per evaluation (seconds",
        "s3_rms_aabb_yaw",
        "target",
    ] {
        assert!(svg.contains(text), "bench.svg lacks {text:?}");
    }

    // Timings vary between runs; everything else is the same to the bit.
    let out = bench(&b, &[]);
    assert_eq!(out.status.code(), Some(0));
    let rb = rows(&b);
    assert_eq!(ra.len(), rb.len());
    for (x, y) in ra.iter().zip(&rb) {
        assert_eq!(
            (
                &x.metric,
                x.samples,
                x.error.to_bits(),
                x.estimate.to_bits(),
                x.reference.to_bits()
            ),
            (
                &y.metric,
                y.samples,
                y.error.to_bits(),
                y.estimate.to_bits(),
                y.reference.to_bits()
            )
        );
    }
}

#[test]
fn bench_rejects_zero_repeats_and_a_missing_config_with_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(["bench", "--repeats", "0", "--out"])
        .arg(tmp.path().join("o"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--repeats") && err.contains("1..=1000"), "{err}");
    let out = bench(&tmp.path().join("o"), &["--config", "no/such/scene.toml"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("no/such/scene.toml"), "{err}");
    assert!(!tmp.path().join("o").exists(), "no output on error");
}

#[test]
fn bench_on_a_scene_that_needs_no_cascades_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("away.toml");
    // The camera looks toward +z; the scene lies entirely behind it.
    let text = include_str!("../../configs/default.toml")
        .replace("target = [0.0, 0.0, -50.0]", "target = [0.0, 10.0, 50.0]")
        .replace("max = [200.0, 40.0, 200.0]", "max = [200.0, 40.0, -100.0]");
    assert!(text.contains("[0.0, 10.0, 50.0]") && text.contains("-100.0]"));
    std::fs::write(&cfg, text).unwrap();
    let out = bench(&tmp.path().join("o"), &["--config", cfg.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("needs no cascades"), "{err}");
}
