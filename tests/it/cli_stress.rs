//! The `stress` command as a user runs it: exit codes, `stress.csv`, determinism.

use std::path::Path;
use std::process::{Command, Output};

fn stress(out: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .arg("stress")
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn stress_passes_the_default_battery_and_writes_one_row_per_case() {
    let dir = tempfile::tempdir().unwrap();
    let out = stress(dir.path(), &["--cases", "12", "--seed", "3"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let n = csm_lab::commands::stress::battery().len() + 12;
    assert!(stdout.contains(&format!("{n} cases, {n} passed, 0 failed")), "{stdout}");
    let text = std::fs::read_to_string(dir.path().join("stress.csv")).unwrap();
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header, csm_lab::report::stress::stress_columns());
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), n, "one row per case");
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let first_result = col("cascades_needed");
    for r in &rows {
        assert_eq!(&r[col("status")], "pass", "{r:?}");
        assert_eq!(&r[col("failed_invariants")], "");
        // Result columns hold finite numbers or nothing (not applicable).
        for (k, field) in r.iter().enumerate().skip(first_result + 1).take(11) {
            if !field.is_empty() {
                let v: f64 = field.parse().unwrap_or_else(|_| panic!("{} = {field:?}", header[k]));
                assert!(v.is_finite(), "{} = {field}", header[k]);
            }
        }
    }
    // The f32 residuals are there, not hidden: world-anchored f32 at 1e6 drifts.
    let at_1e6 = rows.iter().find(|r| &r[0] == "world offset 1e6").unwrap();
    let drift: f64 = at_1e6[col("f32_world_drift_max")].parse().unwrap();
    let relative: f64 = at_1e6[col("f32_relative_drift_max")].parse().unwrap();
    let stabilised: f64 = at_1e6[col("stabilised_shimmer_max")].parse().unwrap();
    assert!(drift > 0.1 && relative < 1e-2 && stabilised < 1e-9, "{at_1e6:?}");
    // Invalid-by-design inputs are recorded as such.
    let nan = rows.iter().find(|r| &r[0] == "non-finite world offset").unwrap();
    assert_eq!(&nan[1], "rejected (scene.world_offset)");
    assert_eq!(&nan[col("status")], "pass");
    assert!(nan[col("note")].contains("`scene.world_offset` = [NaN"), "{nan:?}");
    // That note, quoting the rejected input, is the only place "NaN" appears; the inputs of
    // valid cases are finite numbers (or names and flags).
    for r in &rows {
        for (k, field) in r.iter().enumerate() {
            assert!(!field.contains("NaN") || header[k] == "note", "{} = {field}", header[k]);
            if &r[1] == "valid" && (2..first_result).contains(&k) {
                let v = field.parse::<f64>();
                assert!(v.map_or(true, |v| v.is_finite()), "{} = {field}", header[k]);
                assert!(!["nan", "inf", "-inf"].contains(&field), "{} = {field}", header[k]);
            }
        }
    }
}

#[test]
fn stress_output_depends_only_on_the_seed() {
    let dir = tempfile::tempdir().unwrap();
    let read = |sub: &str| std::fs::read(dir.path().join(sub).join("stress.csv")).unwrap();
    for (sub, seed) in [("a", "5"), ("b", "5"), ("c", "6")] {
        let out = stress(&dir.path().join(sub), &["--cases", "10", "--seed", seed]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    }
    assert!(read("a") == read("b"), "same seed, same bytes");
    assert!(read("a") != read("c"), "another seed, other random cases");
    // The fixed battery alone with --cases 0.
    let out = stress(&dir.path().join("d"), &["--cases", "0"]);
    assert_eq!(out.status.code(), Some(0));
    let rows = String::from_utf8(read("d")).unwrap().lines().count() - 1;
    assert_eq!(rows, csm_lab::commands::stress::battery().len());
}

#[test]
fn a_violated_f32_drift_limit_exits_1_and_names_the_invariant() {
    let dir = tempfile::tempdir().unwrap();
    let out = stress(dir.path(), &["--cases", "0", "--max-f32-drift", "0.01"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("FAILED f32_drift_limit"));
    let text = std::fs::read_to_string(dir.path().join("stress.csv")).unwrap();
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
    let n = csm_lab::report::stress::stress_columns().len();
    let (failed, status) = (n - 3, n - 2);
    let get = |name: &str| rows.iter().find(|r| &r[0] == name).unwrap();
    assert_eq!(
        (&get("world offset 1e5")[failed], &get("world offset 1e5")[status]),
        ("f32_drift_limit", "fail")
    );
    assert_eq!(&get("baseline")[status], "pass");
}

#[test]
fn bad_stress_flags_and_unwritable_output_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    for (args, fragment) in [
        (vec!["--cases", "100001"], "--cases"),
        (vec!["--max-f32-drift", "-1"], "--max-f32-drift"),
        (vec!["--max-f32-drift", "nan"], "--max-f32-drift"),
        (vec!["--seed", "x"], "--seed"),
    ] {
        let out = stress(dir.path(), &args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = stderr(&out);
        assert!(err.contains(fragment) && !err.contains("panicked"), "{args:?}: {err}");
    }
    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    let out = stress(&file, &["--cases", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("cannot write"), "{}", stderr(&out));
}
