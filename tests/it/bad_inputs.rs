//! Issue #13's bad inputs: each is a clear error (exit 2) naming the key, flag or file,
//! never a panic, a silent change or an "internal error".

use crate::common;

use std::path::Path;
use std::process::{Command, Output};

use common::{with, BASE};
use csm_lab::config::sweep_spec::{decimal_range, MAX_RANGE_VALUES};
use csm_lab::Config;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn rejected(text: &str) -> String {
    match Config::from_toml_str(text, "t.toml", None) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Exit code 2 and stderr, with no panic and no internal error.
fn fails_with_2(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked") && !err.contains("internal error"), "{err}");
    err
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn a_range_whose_step_dwarfs_its_span_is_one_value_not_a_panic() {
    assert_eq!(decimal_range(1e-35, 1000.0, 709347840558070.0).unwrap(), vec![1e-35]);
    let c = common::config(&with(&[(
        "sweep.lambda",
        "lambda = { start = 1e-35, end = 1000.0, step = 709347840558070.0 }",
    )]));
    assert_eq!(c.sweep.unwrap().axes.lambda.unwrap().values, vec![1e-35]);
}

#[test]
fn a_lambda_range_far_above_one_is_rejected_not_wrapped_into_range() {
    assert_eq!(decimal_range(10209.0, 10209.0, 1e-35).unwrap(), vec![10209.0]);
    let err = rejected(&with(&[(
        "sweep.lambda",
        "lambda = { start = 10209.0, end = 10209.0, step = 1e-35 }",
    )]));
    assert!(
        err.contains("sweep.lambda") && err.contains("10209 is outside [0, 1]"),
        "{err}"
    );
}

#[test]
fn a_range_of_too_many_values_is_refused_from_its_spec() {
    let err = decimal_range(0.0, 1.0, 0.00000001).map(|v| v.len()).unwrap_err();
    assert!(err.contains("at most 10000000"), "{err}");
    let err = decimal_range(-1e300, 1e300, 1e-300).unwrap_err();
    assert!(err.contains("at most"), "{err}");
    // Exactly at the limit's edge: 0..=9_999_999 is allowed, one more is not.
    assert_eq!(
        decimal_range(0.0, (MAX_RANGE_VALUES - 1) as f64, 1.0).unwrap().len(),
        10_000_000
    );
    assert!(decimal_range(0.0, MAX_RANGE_VALUES as f64, 1.0).is_err());
}

#[test]
fn decimal_ranges_stay_exact() {
    let v = decimal_range(0.0, 1.0, 0.05).unwrap();
    assert_eq!(v.len(), 21);
    assert_eq!(v[20], 1.0);
    assert_eq!(v[3], 0.15);
    assert_eq!(decimal_range(1e-35, 3e-35, 1e-35).unwrap(), vec![1e-35, 2e-35, 3e-35]);
    assert_eq!(
        decimal_range(-0.5, 0.5, 0.25).unwrap(),
        vec![-0.5, -0.25, 0.0, 0.25, 0.5]
    );
}

#[test]
fn a_sweep_axis_of_the_wrong_shape_names_no_internal_type() {
    let err = rejected(&with(&[("sweep.lambda", "lambda = \"all\"")]));
    assert!(!err.contains("RawAxis") && !err.contains("untagged"), "{err}");
    assert!(err.contains("a list of numbers") && err.starts_with("t.toml:"), "{err}");
    let err = rejected(&with(&[("sweep.lambda", "lambda = { start = 0.0, end = 1.0 }")]));
    assert!(err.contains("no step"), "{err}");
}

#[test]
fn a_three_vector_with_extra_elements_is_rejected() {
    for (key, line) in [
        ("camera.position", "position = [0, 10, 0, 1]"),
        ("camera.position", "position = [0, 10, 0, 1, 2, \"x\", true]"),
        ("camera.up", "up = [0, 1, 0, 0]"),
        ("light.direction", "direction = [-0.4, -1.0, -0.3, 9]"),
        ("scene.min", "min = [-200.0, 0.0, -200.0, 1]"),
        ("scene.world_offset", "world_offset = [1, 2, 3, 4]"),
    ] {
        let err = rejected(&with(&[(key, line)]));
        assert!(err.contains("exactly three numbers"), "{line}: {err}");
        let n = common::with(&[(key, line)]).lines().position(|l| l == line).unwrap() + 1;
        assert!(err.starts_with(&format!("t.toml:{n}:")), "{line}: {err}");
    }
    let err = rejected(&with(&[("camera.position", "position = [0, 10]")]));
    assert!(err.contains("exactly three numbers"), "{err}");
}

#[test]
fn a_zero_up_vector_is_printed_as_numbers_not_as_an_internal_type() {
    let err = rejected(&with(&[("camera.up", "up = [0.0, 0.0, 0.0]")]));
    assert!(err.contains("camera.up") && err.contains("[0.0, 0.0, 0.0]"), "{err}");
    assert!(!err.contains("DVec3"), "{err}");
}

#[test]
fn a_motion_file_without_the_file_path_is_rejected() {
    let err = rejected(&with(&[("motion.file", "file = \"poses.csv\"")]));
    assert!(err.contains("motion.file") && err.contains("path = \"file\""), "{err}");
}

#[test]
fn a_zero_motion_step_is_rejected() {
    let err = rejected(&with(&[("motion.step", "step = 0.0")]));
    assert!(err.contains("motion.step") && err.contains("non-zero"), "{err}");
}

#[test]
fn a_bad_motion_file_row_names_the_file_and_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("poses.csv");
    std::fs::write(&csv, "px,py,pz,tx,ty,tz\n0,10,0,0,0,-50\n0,10,0,0,10,0\n").unwrap();
    let text = BASE.replace(
        "path = \"strafe\"\nframes = 60\nstep = 0.05",
        &format!("path = \"file\"\nfile = {:?}", csv.to_str().unwrap()),
    );
    let err = rejected(&text);
    assert!(err.contains("poses.csv line 3 (frame 1)"), "{err}");
    assert!(!err.contains("0.05"), "{err}");
}

#[test]
fn a_motion_file_of_too_many_rows_is_refused_while_it_streams() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("long.csv");
    let mut text = String::from("px,py,pz,tx,ty,tz\n");
    for i in 0..1_000_001 {
        text.push_str(&format!("{},1,0,0,0,-5\n", i % 7));
    }
    std::fs::write(&csv, text).unwrap();
    let err = csm_lab::config::read_path_file(&csv).unwrap_err().to_string();
    assert!(
        err.contains("long.csv:1000002") && err.contains("at most 1000000"),
        "{err}"
    );
}

#[test]
fn a_config_larger_than_the_limit_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let big = format!("{BASE}\n{}", "# padding\n".repeat(500_000));
    let p = write(dir.path(), "big.toml", &big);
    let out = bin().args(["analyze", &p]).output().unwrap();
    let err = fails_with_2(&out);
    assert!(
        err.contains("big.toml") && err.contains("too large for a config file"),
        "{err}"
    );
}

#[cfg(unix)]
#[test]
fn dev_zero_as_a_config_fails_at_once() {
    let t = std::time::Instant::now();
    let out = bin().args(["analyze", "/dev/zero"]).output().unwrap();
    let err = fails_with_2(&out);
    assert!(err.contains("/dev/zero"), "{err}");
    assert!(t.elapsed().as_secs() < 10);
}

#[test]
fn flags_given_negative_numbers_name_the_flag() {
    let out = bin()
        .args(["sweep", "configs/default.toml", "--lambda", "-0.5"])
        .output()
        .unwrap();
    assert!(fails_with_2(&out).contains("--lambda"));
    let out = bin()
        .args(["sweep", "configs/default.toml", "--cascades", "-1"])
        .output()
        .unwrap();
    assert!(fails_with_2(&out).contains("--cascades"));
    let out = bin()
        .args(["sweep", "configs/default.toml", "--threads", "-1"])
        .output()
        .unwrap();
    assert!(fails_with_2(&out).contains("--threads"));
    let out = bin().args(["stress", "--cases", "-1"]).output().unwrap();
    assert!(fails_with_2(&out).contains("--cases"));
}

#[test]
fn thread_counts_beyond_256_are_refused() {
    let out = bin()
        .args(["sweep", "configs/default.toml", "--threads", "10000"])
        .output()
        .unwrap();
    let err = fails_with_2(&out);
    assert!(err.contains("--threads") && err.contains("1..=256"), "{err}");
}

#[test]
fn a_config_named_dots_toml_writes_beside_itself_not_into_the_working_directory() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "...toml", BASE);
    let out = bin()
        .args(["analyze", &p, "--format", "json"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    names.sort();
    for n in &names {
        assert!(n == "...toml" || dir.path().join(n).is_dir(), "{names:?}");
    }
    assert!(dir.path().join("out/config").is_dir(), "{names:?}");
}

#[test]
fn stress_with_no_random_cases_or_the_largest_seed_writes_no_non_finite_text() {
    for args in [
        ["--cases", "0", "--seed", "1"],
        ["--cases", "3", "--seed", "18446744073709551615"],
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = bin()
            .arg("stress")
            .args(args)
            .args(["--out", dir.path().to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
        let mut r = csv::Reader::from_path(dir.path().join("stress.csv")).unwrap();
        let note = r.headers().unwrap().iter().position(|h| h == "note").unwrap();
        for row in r.records() {
            let row = row.unwrap();
            for (i, cell) in row.iter().enumerate() {
                if i == note {
                    continue;
                }
                if let Ok(x) = cell.parse::<f64>() {
                    assert!(x.is_finite(), "{args:?}: {cell} in {row:?}");
                }
            }
        }
    }
}

#[test]
fn the_committed_stress_csv_holds_no_non_finite_number() {
    let text = std::fs::read_to_string("reports/stress/stress.csv").unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    for row in r.records() {
        for cell in row.unwrap().iter() {
            if let Ok(x) = cell.parse::<f64>() {
                assert!(x.is_finite(), "{cell}");
            }
        }
    }
}

fn analyze_into(config: &str, out: &Path) {
    let o = bin()
        .args(["analyze", config, "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_baseline_of_another_scene_is_an_error_not_a_regression() {
    let dir = tempfile::tempdir().unwrap();
    analyze_into("configs/indoor.toml", dir.path());
    let base = dir.path().join("summary.json");
    let text = std::fs::read_to_string(&base).unwrap();
    assert!(text.contains("\"scene_hash\""), "{text}");
    let out = bin()
        .args([
            "check",
            "configs/default.toml",
            "--thresholds",
            "configs/thresholds.toml",
            "--baseline",
        ])
        .arg(&base)
        .output()
        .unwrap();
    let err = fails_with_2(&out);
    assert!(err.contains("summary.json") && err.contains("another scene"), "{err}");
    // Its own baseline is accepted (and, unchanged, passes).
    let t = dir.path().join("t.toml");
    std::fs::write(&t, "[[rule]]\nmetric = \"max_aliasing\"\nmax = 1000.0\n").unwrap();
    let out = bin()
        .args(["check", "configs/indoor.toml", "--thresholds"])
        .arg(&t)
        .arg("--baseline")
        .arg(&base)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn a_baseline_holding_1e308_is_an_error_not_a_regression() {
    let dir = tempfile::tempdir().unwrap();
    analyze_into("configs/default.toml", dir.path());
    let base = dir.path().join("summary.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&base).unwrap()).unwrap();
    v["max_aliasing"] = serde_json::json!(1e308);
    std::fs::write(&base, v.to_string()).unwrap();
    let out = bin()
        .args([
            "check",
            "configs/default.toml",
            "--thresholds",
            "configs/thresholds.toml",
            "--baseline",
        ])
        .arg(&base)
        .output()
        .unwrap();
    let err = fails_with_2(&out);
    assert!(
        err.contains("1e308") || err.contains("1e+308") || err.contains("100000000"),
        "{err}"
    );
}

fn rules(n: usize) -> String {
    (0..n)
        .map(|i| format!("[[rule]]\nmetric = \"max_aliasing\"\nmax = {}.0\n", 1000 + i))
        .collect()
}

#[test]
fn a_thresholds_file_of_ten_thousand_rules_is_read_in_linear_time() {
    use csm_lab::commands::check::thresholds::{Thresholds, MAX_RULES};
    let t = std::time::Instant::now();
    let th = Thresholds::from_toml_str(&rules(MAX_RULES), "t.toml").unwrap();
    assert_eq!(th.rules.len(), 10_000);
    // Quadratic location lookups took minutes at 40,000 rules; this is well under a second
    // in release and a few seconds in a debug build.
    assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
    // An error in the last rule still names its line.
    let mut text = rules(MAX_RULES - 1);
    text.push_str("[[rule]]\nmetric = \"max_aliasng\"\nmax = 1.0\n");
    let err = Thresholds::from_toml_str(&text, "t.toml").unwrap_err().to_string();
    assert!(err.contains(&format!("t.toml:{}:10", 3 * MAX_RULES - 1)), "{err}");
}

#[test]
fn a_thresholds_file_of_more_rules_than_the_limit_is_refused_before_validation() {
    use csm_lab::commands::check::thresholds::{Thresholds, MAX_RULES};
    let err = Thresholds::from_toml_str(&rules(MAX_RULES + 1), "t.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("t.toml") && err.contains("rule") && err.contains("at most 10000"),
        "{err}"
    );
}

#[test]
fn a_shadow_distance_beyond_the_world_bound_is_rejected_with_every_preset() {
    let text = with(&[("shadow.max_distance", "max_distance = 1e155")]);
    let err = rejected(&text);
    assert!(
        err.contains("shadow.max_distance") && err.contains("at most 1e9"),
        "{err}"
    );
}

#[test]
fn an_engine_distance_knob_beyond_the_world_bound_is_rejected_by_name() {
    let text = format!(
        "{}\n[learnopengl]\npad_xy = 1e300\n",
        with(&[("shadow.preset", "preset = \"learnopengl\"")])
    );
    let err = rejected(&text);
    assert!(
        err.contains("learnopengl.pad_xy") && err.contains("[0, 1000000000]"),
        "{err}"
    );
    assert!(!err.contains("internal error"), "{err}");
}

#[test]
fn a_killed_runs_stale_temporaries_are_removed_by_the_next_run_and_nothing_else_is_touched() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let stale = [".cascades.csv.N629vS.tmp", ".summary.json.a1B2c3.tmp"];
    let others = [
        "notes.txt",
        ".cascades.csv.tmp",
        ".cascades.csv.toolong1.tmp",
        ".mine.csv.N629vS.tmp",
        "cascades.csv.N629vS.tmp",
    ];
    for n in stale.iter().chain(&others) {
        std::fs::write(out.join(n), "left over").unwrap();
    }
    let o = bin()
        .args(["analyze", "configs/default.toml", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.matches("removed 2 stale temporary files").count(), 1, "{err}");
    for n in stale {
        assert!(!out.join(n).exists(), "{n} is still there");
    }
    for n in others {
        assert_eq!(
            std::fs::read_to_string(out.join(n)).unwrap(),
            "left over",
            "{n} was touched"
        );
    }
    // A clean directory: nothing said.
    let o = bin()
        .args(["analyze", "configs/default.toml", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("stale"));
}

#[test]
fn only_the_write_pattern_counts_as_a_temporary() {
    use csm_lab::output::is_temporary_of;
    assert!(is_temporary_of(".sweep.csv.N629vS.tmp", "sweep.csv"));
    assert!(!is_temporary_of(".sweep.csv.N629v.tmp", "sweep.csv"));
    assert!(!is_temporary_of(".sweep.csv.N6-9vS.tmp", "sweep.csv"));
    assert!(!is_temporary_of("sweep.csv.N629vS.tmp", "sweep.csv"));
    assert!(!is_temporary_of(".sweep.csv.N629vS.tmp", "sweep.cs"));
    assert!(!is_temporary_of(".sweep.csv.N629vS.tmpx", "sweep.csv"));
}

#[test]
fn a_long_path_keeps_a_bounded_number_of_frame_rows_and_exact_summaries() {
    use csm_core::shimmer::{frame_row_stride, MAX_FRAME_ROWS};
    use csm_lab::analysis::{analyze, AnalysisOptions};
    assert_eq!(frame_row_stride(240), 1);
    assert_eq!(frame_row_stride(MAX_FRAME_ROWS), 1);
    assert_eq!(frame_row_stride(MAX_FRAME_ROWS + 1), 2);
    assert_eq!(frame_row_stride(1_000_000), 1_000);
    let long = common::config(&with(&[
        ("motion.path", "path = \"yaw\""),
        ("motion.frames", "frames = 30001"),
        ("motion.step", "step = 0.01"),
    ]));
    let a = analyze(&long, &AnalysisOptions::full());
    let s = a.snapped().unwrap();
    let cascades = a.cascades.len();
    // Stride ceil(30001 / 1000) = 31: frames 31, 62, ..., 29977 (967 of them) for every cascade.
    assert_eq!(s.frames.len(), 967 * cascades);
    assert!(s.frames.iter().all(|f| f.frame % 31 == 0));
    // The summary uses every frame: the same as with rows off.
    let b = analyze(&long, &AnalysisOptions::summary_only());
    assert_eq!(a.summary.shimmer_snapped, b.summary.shimmer_snapped);
    assert_eq!(a.summary.shimmer_unsnapped, b.summary.shimmer_unsnapped);
}

#[test]
fn a_vector_of_the_wrong_length_or_type_names_its_key_and_line() {
    for (key, line, says) in [
        ("camera.position", "position = [0, 10]", "invalid length 2"),
        ("camera.up", "up = [0, 1]", "invalid length 2"),
        ("light.direction", "direction = [1]", "invalid length 1"),
        ("scene.min", "min = []", "invalid length 0"),
        ("scene.max", "max = [1, 2, 3, 4]", "invalid length 4"),
        ("camera.target", "target = [0, \"x\", 1]", "invalid type"),
        ("camera.fov_y_deg", "fov_y_deg = \"wide\"", "invalid type"),
    ] {
        let text = with(&[(key, line)]);
        let n = text.lines().position(|l| l == line).unwrap() + 1;
        let err = rejected(&text);
        assert!(
            err.starts_with(&format!("t.toml:{n}:")) && err.contains(&format!("`{key}`: {says}")),
            "{line}: {err}"
        );
    }
    // The same through the binary: exit 2, the key on stderr.
    let dir = tempfile::tempdir().unwrap();
    let cfg = write(
        dir.path(),
        "short.toml",
        &with(&[("camera.position", "position = [0, 10]")]),
    );
    let out = bin()
        .args(["analyze", &cfg, "--out", dir.path().join("out").to_str().unwrap()])
        .output()
        .unwrap();
    let err = fails_with_2(&out);
    assert!(err.contains("`camera.position`: invalid length 2"), "{err}");
}
