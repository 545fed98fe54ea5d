//! The `check` command as a CI job runs it: exit codes, rules, baselines, JUnit, messages.
//! Expected values come from the library's analysis of the same config, computed here.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::read_csv;
use common::{with, BASE};
use csm_core::metrics::cascade_at;
use csm_lab::analyze;
use csm_lab::commands::check::evaluate::short;
use csm_lab::commands::check::metric::SummaryMetric;
use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new() -> Self {
        Case {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    fn file(&self, name: &str, text: &str) -> PathBuf {
        let p = self.dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Runs `check CONFIG --thresholds T` with extra arguments. Every case of this file runs
    /// in the other `--format` too, which must give the same exit code: the format never
    /// changes the verdict.
    fn check(&self, config: &Path, thresholds: &Path, extra: &[&str]) -> Output {
        let run = |args: &[&str]| {
            bin()
                .arg("check")
                .arg(config)
                .arg("--thresholds")
                .arg(thresholds)
                .args(args)
                .output()
                .unwrap()
        };
        let out = run(extra);
        let mut other: Vec<&str> = Vec::new();
        let mut i = 0;
        let mut had_format = false;
        while i < extra.len() {
            if extra[i] == "--format" && i + 1 < extra.len() {
                had_format = true;
                other.push("--format");
                other.push(if extra[i + 1] == "json" { "table" } else { "json" });
                i += 2;
            } else {
                other.push(extra[i]);
                i += 1;
            }
        }
        if !had_format {
            other.extend(["--format", "json"]);
        }
        // An invalid `--format` value is its own error case.
        if extra
            .windows(2)
            .any(|w| w[0] == "--format" && !["table", "json"].contains(&w[1]))
        {
            return out;
        }
        let twin = run(&other);
        assert_eq!(
            out.status.code(),
            twin.status.code(),
            "exit code differs between formats for {extra:?} / {other:?}: {}",
            String::from_utf8_lossy(&twin.stderr)
        );
        out
    }

    /// The same with `--format json`, parsed.
    fn check_json(&self, config: &Path, thresholds: &Path, extra: &[&str]) -> (i32, Value) {
        let mut args = vec!["--format", "json"];
        args.extend_from_slice(extra);
        let out = self.check(config, thresholds, &args);
        let code = out.status.code().unwrap();
        assert!(code == 0 || code == 1, "exit {code}: {}", stderr(&out));
        (code, serde_json::from_slice(&out.stdout).unwrap())
    }
}

/// Equal up to JSON round-trip noise: serde_json (without `float_roundtrip`) may read a
/// printed f64 back one ulp off.
fn close(got: f64, expected: f64) {
    assert!(
        (got - expected).abs() <= 4.0 * f64::EPSILON * expected.abs(),
        "{got} != {expected}"
    );
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The library's analysis of a config text (the same options `check` uses).
fn analysis(text: &str) -> csm_lab::Analysis {
    let c = common::config(text);
    analyze(&c, &csm_lab::commands::check::check_options())
}

fn statuses(report: &Value) -> Vec<String> {
    report["rules"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["status"].as_str().unwrap().to_string())
        .collect()
}

/// Asserts exit code 2, no panic, no stdout, and that the message names every fragment.
fn assert_error(out: &Output, fragments: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}\nstdout: {}", stdout(out));
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.stdout.is_empty(), "nothing on stdout on error: {}", stdout(out));
    for f in fragments {
        assert!(err.contains(f), "message {err:?} should mention {f:?}");
    }
}

/// A two-row sweep grid (λ 0.5 and 0.75 at 4 x 2048², sphere) for the `--sweep` tests.
const SMALL_SWEEP: &str = "\n[sweep]\nlambda = [0.5, 0.75]\ncascades = [4]\nresolution = [2048]\n";

#[test]
fn the_shipped_thresholds_pass_on_the_default_scene_with_exit_code_0() {
    let case = Case::new();
    let junit = case.path("report/check.xml");
    let out = case.check(
        &repo("configs/default.toml"),
        &repo("configs/thresholds.toml"),
        &["--junit", junit.to_str().unwrap()],
    );
    assert_eq!(out.status.code(), Some(0), "{}\n{}", stdout(&out), stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("result: PASS"), "{text}");
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let rules = csm_lab::commands::check::Thresholds::load(&repo("configs/thresholds.toml"))
        .unwrap()
        .rules;
    assert!(rules.len() >= 10);
    let cases = doc.descendants().filter(|n| n.has_tag_name("testcase")).count();
    assert_eq!(cases, rules.len());
    assert_eq!(doc.descendants().filter(|n| n.has_tag_name("failure")).count(), 0);
}

#[test]
fn table_output_has_one_line_per_rule_with_actual_limit_margin_and_result() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let a = analysis(BASE);
    let limit = a.summary.mean_aliasing * 1.5;
    let t = case.file(
        "t.toml",
        &format!(
            "[[rule]]\nmetric = \"mean_aliasing\"\nmax = {limit}\n[[rule]]\nmetric = \"texel_size\"\ncascade = 1\nmax = 1\n[[rule]]\nmetric = \"aliasing\"\ndepth = [5, 60]\nmax = 100\n"
        ),
    );
    let out = case.check(&cfg, &t, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let header = text
        .lines()
        .find(|l| l.contains("metric") && l.contains("where"))
        .unwrap();
    for col in ["actual", "limit", "margin", "result"] {
        assert!(header.contains(col), "{header}");
    }
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("  ") && l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert!(lines.iter().all(|l| l.ends_with("PASS")), "{text}");
    assert_eq!(lines.len(), 3, "{text}");
    assert!(lines[0].contains("mean_aliasing") && lines[0].contains("summary"));
    assert!(lines[1].contains("texel_size") && lines[1].contains("cascade 1"));
    assert!(lines[2].contains("aliasing") && lines[2].contains("depth 5..60"));
    let margin = short(limit - a.summary.mean_aliasing);
    assert!(lines[0].contains(&margin), "{} vs {margin}", lines[0]);
    assert!(lines[0].contains(&short(a.summary.mean_aliasing)), "{}", lines[0]);
}

#[test]
fn a_summary_rule_passes_and_fails_on_purpose_with_exit_codes_0_and_1() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let a = analysis(BASE);
    for m in [
        SummaryMetric::named("max_aliasing"),
        SummaryMetric::named("mean_log_aliasing"),
        SummaryMetric::named("shimmer_unsnapped"),
        SummaryMetric::named("memory_bytes"),
    ] {
        let v = m.value(&a.summary);
        assert!(v > 0.0);
        for (factor, code, status) in [(1.01, 0, "pass"), (0.99, 1, "fail")] {
            let t = case.file(
                "t.toml",
                &format!("[[rule]]\nmetric = \"{}\"\nmax = {}\n", m.name(), v * factor),
            );
            let (got, report) = case.check_json(&cfg, &t, &[]);
            assert_eq!(got, code, "{} x{factor}", m.name());
            let r = &report["rules"][0];
            assert_eq!(r["status"], status);
            close(r["actual"].as_f64().unwrap(), v);
            assert_eq!(r["kind"], "summary");
            assert!((r["margin"].as_f64().unwrap() - (v * factor - v)).abs() <= 1e-9 * v);
        }
    }
}

#[test]
fn min_and_max_limits_are_both_enforced() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let v = analysis(BASE).summary.mean_aliasing;
    let rules = [
        (v * 0.8, v * 1.1, "pass", "max"),
        (v * 1.05, v * 2.0, "fail", "min"),
        (v * 0.1, v * 0.95, "fail", "max"),
    ];
    let text: String = rules
        .iter()
        .map(|(lo, hi, _, _)| format!("[[rule]]\nmetric = \"mean_aliasing\"\nmin = {lo}\nmax = {hi}\n"))
        .collect();
    let t = case.file("t.toml", &text);
    let (code, report) = case.check_json(&cfg, &t, &[]);
    assert_eq!(code, 1);
    for (i, (lo, hi, status, bound)) in rules.iter().enumerate() {
        let r = &report["rules"][i];
        assert_eq!(r["status"], *status, "rule {i}");
        assert_eq!(r["bound"], *bound, "rule {i}");
        let expected = if *bound == "max" { hi - v } else { v - lo };
        assert!((r["margin"].as_f64().unwrap() - expected).abs() < 1e-12, "rule {i}");
    }
    // A min alone.
    let t = case.file(
        "t.toml",
        &format!("[[rule]]\nmetric = \"mean_aliasing\"\nmin = {}\n", v * 1.01),
    );
    let (code, report) = case.check_json(&cfg, &t, &[]);
    assert_eq!((code, report["rules"][0]["bound"].as_str()), (1, Some("min")));
}

#[test]
fn per_cascade_rules_pass_and_fail_on_purpose_and_report_the_worst_cascade() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let a = analysis(BASE);
    let t0 = a.cascades[0].texel_size;
    let t2 = a.cascades[2].texel_size;
    // Independent worst cascades: the largest texel and the smallest slack.
    let (widest, _) =
        a.cascades.iter().enumerate().fold(
            (0, f64::MIN),
            |(bi, bv), (i, c)| if c.width > bv { (i, c.width) } else { (bi, bv) },
        );
    let (tightest, slack) = a.cascades.iter().enumerate().fold((0, f64::MAX), |(bi, bv), (i, c)| {
        if c.min_slack_texels < bv {
            (i, c.min_slack_texels)
        } else {
            (bi, bv)
        }
    });
    let widest_width = a.cascades[widest].width;
    let t = case.file(
        "t.toml",
        &format!(
            r#"
[[rule]]
metric = "texel_size"
cascade = 0
max = {pass0}
[[rule]]
metric = "texel_size"
cascade = 2
max = {fail2}
[[rule]]
metric = "width"
max = {fail_all}
[[rule]]
metric = "min_slack_texels"
cascade = "all"
min = {pass_slack}
[[rule]]
metric = "max_aliasing"
cascade = 1
max = {pass_alias}
"#,
            pass0 = t0 * 1.001,
            fail2 = t2 * 0.999,
            fail_all = widest_width * 0.999,
            pass_slack = slack * 0.5,
            pass_alias = a.cascades[1].max_aliasing * 1.001,
        ),
    );
    let (code, report) = case.check_json(&cfg, &t, &[]);
    assert_eq!(code, 1);
    assert_eq!(statuses(&report), ["pass", "fail", "fail", "pass", "pass"]);
    let r = &report["rules"];
    close(r[0]["actual"].as_f64().unwrap(), t0);
    assert_eq!(r[0]["kind"], "cascade");
    close(r[1]["actual"].as_f64().unwrap(), t2);
    assert_eq!(r[1]["at_cascade"], 2);
    assert_eq!(r[2]["at_cascade"].as_u64().unwrap() as usize, widest);
    assert_eq!(r[2]["cascades_examined"], 4);
    close(r[2]["actual"].as_f64().unwrap(), widest_width);
    assert_eq!(r[3]["at_cascade"].as_u64().unwrap() as usize, tightest);
    close(r[3]["actual"].as_f64().unwrap(), slack);
    close(r[4]["actual"].as_f64().unwrap(), a.cascades[1].max_aliasing);
}

/// The largest and smallest aliasing over [lo, hi] by dense sampling, with each split
/// approached from the near side as well.
fn sampled_aliasing(a: &csm_lab::Analysis, lo: f64, hi: f64) -> (f64, f64) {
    let rig = a.rig().unwrap();
    let k = rig.lens.pixels_per_unit_slope(a.config.screen.height);
    let t: Vec<f64> = a.cascades.iter().map(|c| c.texel_size).collect();
    let mut depths: Vec<f64> = (0..=200_000).map(|j| lo + (hi - lo) * j as f64 / 200_000.0).collect();
    for &c in &rig.splits {
        if c > lo && c <= hi {
            depths.extend([c * (1.0 - 1e-13), c]);
        }
    }
    let vals = depths.iter().map(|&d| k * t[cascade_at(&rig.splits, d)] / d);
    vals.fold((f64::MIN, f64::MAX), |(mx, mn), v| (mx.max(v), mn.min(v)))
}

#[test]
fn per_depth_rules_pass_and_fail_on_purpose_with_values_that_match_dense_sampling() {
    let case = Case::new();
    for text in [
        BASE.to_string(),
        with(&[("shadow.fit", "fit = \"aabb\""), ("shadow.lambda", "lambda = 0.4")]),
    ] {
        let cfg = case.file("scene.toml", &text);
        let a = analysis(&text);
        let (lo, hi) = (5.0, 60.0);
        let (smax, _) = sampled_aliasing(&a, lo, hi);
        let t = case.file(
            "t.toml",
            &format!(
                r#"
[[rule]]
metric = "aliasing"
depth = [{lo}, {hi}]
max = {pass_max}
[[rule]]
metric = "aliasing"
depth = [{lo}, {hi}]
max = {fail_max}
[[rule]]
metric = "texels_per_pixel"
depth = [{lo}, {hi}]
min = {pass_min}
[[rule]]
metric = "texels_per_pixel"
depth = [{lo}, {hi}]
min = {fail_min}
[[rule]]
metric = "aliasing"
min = 0
"#,
                pass_max = smax * 1.001,
                fail_max = smax * 0.999,
                pass_min = 0.999 / smax,
                fail_min = 1.001 / smax,
            ),
        );
        let (code, report) = case.check_json(&cfg, &t, &[]);
        assert_eq!(code, 1);
        assert_eq!(statuses(&report), ["pass", "fail", "pass", "fail", "pass"]);
        let r = &report["rules"];
        let exact_max = r[0]["actual"].as_f64().unwrap();
        assert!((exact_max - smax).abs() <= 1e-9 * smax, "{exact_max} vs sampled {smax}");
        assert!((r[2]["actual"].as_f64().unwrap() - 1.0 / smax).abs() <= 1e-9 / smax);
        assert_eq!(r[0]["evaluated_depth"], serde_json::json!([lo, hi]));
        let d = r[0]["at_depth"].as_f64().unwrap();
        assert!((lo..=hi).contains(&d));
        // Over the whole split range the extremes are the summary's and the last cascade's.
        assert_eq!(r[4]["bound"], "min");
        let (fmax, fmin) = sampled_aliasing(&a, a.summary.z_lo, a.summary.z_hi);
        assert!((r[4]["actual"].as_f64().unwrap() - fmin).abs() <= 1e-9 * fmin);
        assert!((a.summary.max_aliasing - fmax).abs() <= 1e-9 * fmax);
    }
}

#[test]
fn a_depth_range_partly_outside_the_split_range_is_clipped_and_says_so() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let a = analysis(BASE);
    let t = case.file(
        "t.toml",
        "[[rule]]\nmetric = \"aliasing\"\ndepth = [100, 5000]\nmax = 1000\n",
    );
    let (code, report) = case.check_json(&cfg, &t, &[]);
    assert_eq!(code, 0);
    let r = &report["rules"][0];
    assert_eq!(r["evaluated_depth"], serde_json::json!([100.0, a.summary.z_hi]));
    assert!(r["note"].as_str().unwrap().contains("clipped"), "{r}");
    let (smax, _) = sampled_aliasing(&a, 100.0, a.summary.z_hi);
    assert!((r["actual"].as_f64().unwrap() - smax).abs() <= 1e-9 * smax);
}

#[test]
fn a_baseline_flags_regressions_and_reports_improvements() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--out"])
        .arg(case.path("before"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let summary_path = case.path("before/summary.json");
    let t = case.file("t.toml", "[[rule]]\nmetric = \"coverage_violations\"\nmax = 0\n");

    // The unedited baseline: nothing moved.
    let (code, report) = case.check_json(&cfg, &t, &["--baseline", summary_path.to_str().unwrap()]);
    assert_eq!(code, 0);
    let cmp = report["baseline"]["comparisons"].as_array().unwrap();
    assert_eq!(cmp.len(), bounds_only_metric_count());
    assert!(cmp.iter().all(|c| c["verdict"] == "unchanged"), "{cmp:?}");

    // Make the past better on max_aliasing (so today regressed) and worse on mean_aliasing
    // and memory (so today improved); move z_hi (no worse direction).
    let mut before: Value = serde_json::from_str(&std::fs::read_to_string(&summary_path).unwrap()).unwrap();
    let now = before.clone();
    before["max_aliasing"] = (now["max_aliasing"].as_f64().unwrap() * 0.9).into();
    before["mean_aliasing"] = (now["mean_aliasing"].as_f64().unwrap() * 1.2).into();
    before["memory_bytes"] = (now["memory_bytes"].as_u64().unwrap() * 2).into();
    before["z_hi"] = (now["z_hi"].as_f64().unwrap() + 10.0).into();
    let edited = case.file("edited.json", &serde_json::to_string_pretty(&before).unwrap());
    let (code, report) = case.check_json(&cfg, &t, &["--baseline", edited.to_str().unwrap()]);
    assert_eq!(code, 1, "a regression exits 1 although every rule passes");
    assert_eq!(statuses(&report), ["pass"]);
    let verdict = |m: &str| {
        let c = report["baseline"]["comparisons"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["metric"] == m)
            .unwrap()
            .clone();
        (c["verdict"].as_str().unwrap().to_string(), c)
    };
    let (v, c) = verdict("max_aliasing");
    assert_eq!(v, "regressed");
    let expected_rel = 1.0 / 0.9 - 1.0;
    assert!((c["relative_change"].as_f64().unwrap() - expected_rel).abs() < 1e-9);
    close(
        c["tolerance"].as_f64().unwrap(),
        0.02 * before["max_aliasing"].as_f64().unwrap(),
    );
    assert_eq!(verdict("mean_aliasing").0, "improved");
    assert_eq!(verdict("memory_bytes").0, "improved");
    assert_eq!(verdict("z_hi").0, "changed");
    assert_eq!(verdict("mean_log_aliasing").0, "unchanged");
    assert_eq!(report["counts"]["regressed"], 1);
    assert_eq!(report["counts"]["improved"], 2);

    // The table says the same.
    let out = case.check(&cfg, &t, &["--baseline", edited.to_str().unwrap()]);
    let text = stdout(&out);
    let line = |m: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(m))
            .unwrap()
            .to_string()
    };
    assert!(line("max_aliasing ").ends_with("REGRESSED"), "{text}");
    assert!(line("mean_aliasing ").ends_with("improved"), "{text}");
    assert!(text.contains("1 metric regressed"), "{text}");
}

#[test]
fn a_per_metric_tolerance_absorbs_a_change_the_default_flags() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let a = analysis(BASE);
    let base = serde_json::json!({
        "max_aliasing": a.summary.max_aliasing / 1.05,
        "mean_aliasing": a.summary.mean_aliasing,
    });
    let b = case.file("b.json", &base.to_string());
    let rule = "[[rule]]\nmetric = \"coverage_violations\"\nmax = 0\n";
    let strict = case.file("strict.toml", &format!("{rule}[baseline]\nrelative = 0.02\n"));
    let loose = case.file(
        "loose.toml",
        &format!("{rule}[baseline]\nrelative = 0.02\n[baseline.metric.max_aliasing]\nrelative = 0.06\n"),
    );
    let (code, report) = case.check_json(&cfg, &strict, &["--baseline", b.to_str().unwrap()]);
    assert_eq!(code, 1);
    // Metrics absent from an older baseline are listed, not judged.
    let cmp = report["baseline"]["comparisons"].as_array().unwrap();
    assert_eq!(
        cmp.iter().filter(|c| c["verdict"] == "not_in_baseline").count(),
        bounds_only_metric_count() - 2
    );
    let (code, _) = case.check_json(&cfg, &loose, &["--baseline", b.to_str().unwrap()]);
    assert_eq!(code, 0);
}

#[test]
fn the_junit_file_parses_as_xml_with_the_right_testcase_and_failure_counts() {
    let case = Case::new();
    // A config name with XML metacharacters ends up in suite and class names.
    let cfg = case.file("a&b<c>'q\".toml", BASE);
    let a = analysis(BASE);
    let t = case.file(
        "t.toml",
        &format!(
            r#"
[[rule]]
metric = "max_aliasing"
max = {fail}
[[rule]]
metric = "texel_size"
cascade = 0
max = 1
[[rule]]
metric = "aliasing"
depth = [5, 60]
max = 0.5
[[rule]]
metric = "coverage_violations"
max = 0
"#,
            fail = a.summary.max_aliasing * 0.5
        ),
    );
    let mut base: Value = serde_json::to_value(&a.summary).unwrap();
    // serde keeps the band share (a shard row stores it); summary.json has it only with geometry.
    base.as_object_mut().unwrap().remove("screen_band_pixel_share");
    base["mean_aliasing"] = (a.summary.mean_aliasing * 0.5).into();
    let b = case.file("b.json", &base.to_string());
    let junit = case.path("out/junit.xml");
    let out = case.check(
        &cfg,
        &t,
        &["--baseline", b.to_str().unwrap(), "--junit", junit.to_str().unwrap()],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap_or_else(|e| panic!("{e}\n{xml}"));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    let cases: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("testcase")).collect();
    let failures: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("failure")).collect();
    // 4 rules + every summary metric compared; 2 rules fail and 1 metric regressed.
    assert_eq!(cases.len(), 4 + bounds_only_metric_count());
    assert_eq!(failures.len(), 3);
    assert_eq!(root.attribute("tests"), Some(cases.len().to_string().as_str()));
    assert_eq!(root.attribute("failures"), Some("3"));
    let suites: Vec<_> = root.children().filter(|n| n.has_tag_name("testsuite")).collect();
    assert_eq!(suites.len(), 2);
    assert_eq!(suites[0].attribute("tests"), Some("4"));
    assert_eq!(suites[0].attribute("failures"), Some("2"));
    assert!(suites[0].attribute("name").unwrap().contains("a&b<c>'q\""));
    assert_eq!(cases[0].attribute("classname"), Some("csm-lab.check.a&b<c>'q\""));
    // Failure messages carry the numbers.
    let msg = failures[0].attribute("message").unwrap();
    assert!(
        msg.contains("max_aliasing") && msg.contains(&short(a.summary.max_aliasing)),
        "{msg}"
    );
    assert!(failures[0]
        .text()
        .unwrap()
        .contains(&a.summary.max_aliasing.to_string()));
    let regressed = failures[2].attribute("message").unwrap();
    assert!(
        regressed.contains("mean_aliasing") && regressed.contains("regressed"),
        "{regressed}"
    );
    // Written atomically: no temporary file left beside it.
    let names: Vec<String> = std::fs::read_dir(case.path("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["junit.xml"]);
}

#[test]
fn an_unknown_metric_suggests_the_closest_name() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    for (typo, expected) in [
        ("max_alising", "max_aliasing"),
        ("texelsize", "texel_size"),
        ("shimer_snapped", "shimmer_snapped"),
        ("texels_per_pixl", "texels_per_pixel"),
    ] {
        let t = case.file("t.toml", &format!("[[rule]]\nmax = 1\nmetric = \"{typo}\"\n"));
        let out = case.check(&cfg, &t, &[]);
        assert_error(
            &out,
            &[
                "t.toml:3:10",
                "rule[1].metric",
                typo,
                &format!("did you mean \"{expected}\""),
            ],
        );
    }
}

#[test]
fn a_malformed_thresholds_file_reports_its_line_and_column() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    let junit = case.path("j.xml");
    for (text, fragments) in [
        ("[[rule]]\nmetric = \"max_aliasing\"\nmax = = 2\n", vec!["t.toml:3:7"]),
        (
            "[[rule]]\nmetric = \"max_aliasing\"\nmax = 2\nlimit = 3\n",
            vec!["t.toml:4:1", "limit"],
        ),
        ("[[rule]]\nmetric = \"max_aliasing\"\nmax = \"2\"\n", vec!["t.toml:3:7"]),
        ("[rule]\nmetric = \"max_aliasing\"\n", vec!["t.toml:1:1"]),
        (
            "[[rule]]\nmetric = \"max_aliasing\"\nmin = 5\nmax = 2\n",
            vec!["t.toml:4:7", "rule[1].max"],
        ),
        (
            "[[rule]]\nmetric = \"aliasing\"\ndepth = [0, 2]\nmax = 2\n",
            vec!["t.toml:3:9", "rule[1].depth"],
        ),
        (
            "[baseline]\nrelative = 0.02\nabsolut = 1\n",
            vec!["t.toml:3:1", "absolut"],
        ),
    ] {
        let t = case.file("t.toml", text);
        let out = case.check(&cfg, &t, &["--junit", junit.to_str().unwrap()]);
        assert_error(&out, &fragments);
        // The JUnit file reports the error (never an earlier pass).
        let xml = std::fs::read_to_string(&junit).unwrap();
        let doc = roxmltree::Document::parse(&xml).unwrap();
        assert_eq!(doc.root_element().attribute("errors"), Some("1"));
        std::fs::remove_file(&junit).unwrap();
    }
}

#[test]
fn errors_exit_2_and_never_1() {
    let case = Case::new();
    let cfg = case.file("scene.toml", BASE);
    // A rule that would fail: an error elsewhere must still win with exit code 2.
    let failing = case.file("t.toml", "[[rule]]\nmetric = \"max_aliasing\"\nmax = 0.001\n");
    let bad_config = case.file("bad.toml", &with(&[("shadow.cascades", "cascades = 0")]));
    assert_error(&case.check(&bad_config, &failing, &[]), &["shadow.cascades"]);
    assert_error(
        &case.check(&case.path("missing.toml"), &failing, &[]),
        &["missing.toml"],
    );
    assert_error(&case.check(&cfg, &case.path("none.toml"), &[]), &["none.toml"]);
    let p = case.path("nope.json");
    assert_error(
        &case.check(&cfg, &failing, &["--baseline", p.to_str().unwrap()]),
        &["nope.json"],
    );
    let garbage = case.file("garbage.json", "{ not json");
    assert_error(
        &case.check(&cfg, &failing, &["--baseline", garbage.to_str().unwrap()]),
        &["garbage.json", "not valid JSON"],
    );
    let wrong = case.file("wrong.json", "{\"max_aliasing\": \"high\"}");
    assert_error(
        &case.check(&cfg, &failing, &["--baseline", wrong.to_str().unwrap()]),
        &["max_aliasing", "not a number"],
    );
    let cascade = case.file("c.toml", "[[rule]]\nmetric = \"texel_size\"\ncascade = 4\nmax = 1\n");
    // A cascade the scene does not have: the rule is skipped with a note, not an error.
    let out = case.check(&cfg, &cascade, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).contains("skipped: scene has 4 cascades (indices 0..=3), the rule names cascade 4"));
    let depth = case.file(
        "d.toml",
        "[[rule]]\nmetric = \"aliasing\"\ndepth = [400, 500]\nmax = 1\n",
    );
    assert_error(
        &case.check(&cfg, &depth, &[]),
        &["d.toml:3:9", "rule[1].depth", "split range"],
    );
    let empty = case.file("e.toml", "# nothing\n");
    assert_error(&case.check(&cfg, &empty, &[]), &["--thresholds", "nothing to check"]);
    let out = bin().args(["check", cfg.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "a missing flag is a usage error");
    let out = case.check(&cfg, &failing, &["--format", "xml"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_scene_without_cascades_judges_summary_metrics_as_zero_and_skips_the_rest() {
    let case = Case::new();
    // The scene is behind the camera: nothing to shadow.
    let text = with(&[
        ("scene.min", "min = [-10.0, 0.0, 100.0]"),
        ("scene.max", "max = [10.0, 5.0, 120.0]"),
    ]);
    assert!(!analysis(&text).summary.cascades_needed);
    let cfg = case.file("scene.toml", &text);
    let t = case.file(
        "t.toml",
        "[[rule]]\nmetric = \"max_aliasing\"\nmax = 0\n[[rule]]\nmetric = \"texel_size\"\ncascade = 9\nmax = 1\n[[rule]]\nmetric = \"aliasing\"\ndepth = [1, 2]\nmax = 1\n",
    );
    let (code, report) = case.check_json(&cfg, &t, &[]);
    assert_eq!(code, 0);
    assert_eq!(statuses(&report), ["pass", "not_applicable", "not_applicable"]);
    assert_eq!(report["rules"][0]["actual"].as_f64(), Some(0.0));
    assert!(report["rules"][1]["note"].as_str().unwrap().contains("no cascades"));
    // Requiring cascades makes it fail.
    let t = case.file("t.toml", "[[rule]]\nmetric = \"cascades_needed\"\nmin = 1\n");
    let (code, report) = case.check_json(&cfg, &t, &[]);
    assert_eq!((code, statuses(&report)), (1, vec!["fail".to_string()]));
}

#[test]
fn sweep_mode_judges_summary_rules_per_row_and_marks_the_others_not_applicable() {
    let case = Case::new();
    let cfg = case.file("scene.toml", &format!("{BASE}{SMALL_SWEEP}"));
    let a = analysis(BASE);
    let b = analysis(&with(&[("shadow.lambda", "lambda = 0.5")]));
    // A limit between the two rows' values: λ = 0.75 passes, λ = 0.5 fails.
    let (lo, hi) = (a.summary.mean_aliasing, b.summary.mean_aliasing);
    assert!(lo < hi);
    let t = case.file(
        "t.toml",
        &format!(
            "[[rule]]\nmetric = \"mean_aliasing\"\nmax = {}\n[[rule]]\nmetric = \"texel_size\"\ncascade = 0\nmax = 0\n[[rule]]\nmetric = \"aliasing\"\nmax = 0\n",
            0.5 * (lo + hi)
        ),
    );
    let junit = case.path("s.xml");
    let (code, report) = case.check_json(&cfg, &t, &["--sweep", "--all-rows", "--junit", junit.to_str().unwrap()]);
    // The per-cascade and per-depth rules would fail, but they do not apply to sweep rows;
    // the λ = 0.5 row fails the summary rule.
    assert_eq!(code, 1);
    assert_eq!(report["mode"], "sweep");
    let rows = report["configurations"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["key"]["lambda"].as_f64(), Some(0.5));
    assert_eq!(rows[0]["passed"], false);
    assert_eq!(rows[1]["passed"], true);
    assert_eq!(rows[1]["key"]["lambda"].as_f64(), Some(0.75));
    assert_eq!(rows[1]["key"]["fit"], "sphere");
    let st: Vec<&str> = rows[1]["rules"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["status"].as_str().unwrap())
        .collect();
    assert_eq!(st, ["pass", "not_applicable", "not_applicable"]);
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    assert!(doc.descendants().filter(|n| n.has_tag_name("testcase")).count() >= 3);
    assert!(doc.descendants().any(|n| n.has_tag_name("skipped")));
    assert!(doc.descendants().any(|n| n.has_tag_name("failure")));

    // Only non-applicable rules and no baseline: nothing to check is an error.
    let t2 = case.file("t2.toml", "[[rule]]\nmetric = \"texel_size\"\nmax = 1\n");
    assert_error(&case.check(&cfg, &t2, &["--sweep"]), &["--sweep", "nothing to check"]);
}

#[test]
fn sweep_mode_compares_with_a_sweep_csv_baseline_by_key() {
    let case = Case::new();
    let cfg = case.file("scene.toml", &format!("{BASE}{SMALL_SWEEP}"));
    let s = analysis(BASE).summary;
    let t = case.file("t.toml", "[[rule]]\nmetric = \"coverage_violations\"\nmax = 0\n");
    // Columns in another order than the sweep writes them, plus one the check ignores; the
    // matching row claims a better max_aliasing in the past, another row is not in this sweep.
    let csv = format!(
        "fit,resolution,cascades,lambda,notes,max_aliasing,mean_aliasing,memory_bytes\n\
         sphere,2048,4,0.25,x,1,1,1\n\
         sphere,2048,4,0.75,y,{},{},{}\n",
        s.max_aliasing * 0.8,
        s.mean_aliasing,
        s.memory_bytes * 2
    );
    let b = case.file("sweep.csv", &csv);
    let (code, report) = case.check_json(&cfg, &t, &["--sweep", "--baseline", b.to_str().unwrap()]);
    assert_eq!(code, 1);
    let base = &report["baseline"];
    assert_eq!(base["matched"].as_array().unwrap().len(), 1);
    assert_eq!(base["only_baseline"][0]["lambda"].as_f64(), Some(0.25));
    assert_eq!(base["only_current"].as_array().unwrap().len(), 1);
    assert_eq!(base["only_current"][0]["lambda"].as_f64(), Some(0.5));
    let cmp = base["matched"][0]["comparisons"].as_array().unwrap();
    let verdict = |m: &str| {
        cmp.iter().find(|c| c["metric"] == m).unwrap()["verdict"]
            .as_str()
            .unwrap()
            .to_string()
    };
    assert_eq!(verdict("max_aliasing"), "regressed");
    assert_eq!(verdict("mean_aliasing"), "unchanged");
    assert_eq!(verdict("memory_bytes"), "improved");
    // A column the baseline table lacks is not compared; it is named once.
    assert!(cmp.iter().all(|c| c["metric"] != "size_jitter"));
    let missing = base["columns_not_in_baseline"].as_array().unwrap();
    assert!(missing.iter().any(|c| c == "size_jitter"), "{missing:?}");
    assert!(missing.iter().all(|c| c != "max_aliasing"));
    // A summary.json is not a sweep table.
    let j = case.file("summary.json", "{\"max_aliasing\": 1}");
    assert_error(
        &case.check(&cfg, &t, &["--sweep", "--baseline", j.to_str().unwrap()]),
        &["lambda", "sweep.csv"],
    );
}

#[test]
fn the_same_input_gives_byte_identical_reports() {
    let case = Case::new();
    // The shipped rules include screen rules: a scene with geometry.
    let cfg = repo("configs/default.toml");
    let t = repo("configs/thresholds.toml");
    let mut outputs = Vec::new();
    for name in ["a.xml", "b.xml"] {
        let j = case.path(name);
        let out = case.check(&cfg, &t, &["--format", "json", "--junit", j.to_str().unwrap()]);
        outputs.push((out.stdout, std::fs::read(j).unwrap()));
    }
    assert_eq!(outputs[0], outputs[1]);
    let text = String::from_utf8(outputs[0].0.clone()).unwrap();
    assert!(!text.contains("NaN") && !text.contains("null"), "{text}");
}

/// The summary metrics of a scene without geometry (the screen metrics exist only with it).
/// The metrics of a bounds-only summary under a still light (no screen or light_* metrics).
fn bounds_only_metric_count() -> usize {
    SummaryMetric::all()
        .filter(|m| !m.def().screen && !m.name().starts_with("light_crawl") && !m.name().starts_with("light_jump"))
        .count()
}

/// The `[[rule]]`s of a thresholds file: (metric, bound, limit).
fn rules_of(path: &Path) -> Vec<(String, String, f64)> {
    let v: toml::Value = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["rule"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let t = r.as_table().unwrap();
            let (bound, lim) = t.iter().find(|(k, _)| *k == "min" || *k == "max").unwrap();
            let lim = lim.as_float().or_else(|| lim.as_integer().map(|i| i as f64)).unwrap();
            (t["metric"].as_str().unwrap().to_string(), bound.clone(), lim)
        })
        .collect()
}

#[test]
fn init_on_a_bounds_only_run_limits_only_what_was_measured_with_limits_that_can_fail() {
    let case = Case::new();
    let cfg = case.file("bounds.toml", BASE);
    let gate = case.path("gate.toml");
    let out = bin().arg("check").arg(&cfg).arg("--init").arg(&gate).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let rules = rules_of(&gate);
    let names: Vec<&str> = rules.iter().map(|r| r.0.as_str()).collect();
    // No ground truth, no geometry, a still light: none of their metrics is limited.
    for unmeasured in [
        "acne_fraction",
        "leak_fraction",
        "flicker_snapped",
        "flicker_unsnapped",
        "light_crawl",
        "light_jump",
        "screen_aliasing_p95",
        "screen_undersampled_fraction",
    ] {
        assert!(!names.contains(&unmeasured), "{unmeasured}: {names:?}");
    }
    let text = std::fs::read_to_string(&gate).unwrap();
    assert!(
        text.contains("# Not measured for this config, so not limited"),
        "{text}"
    );
    assert!(text.contains("acne_fraction"), "{text}");
    // Memory is discrete: 4 cascades of 2048² 32-bit texels, exactly.
    let memory = rules.iter().find(|r| r.0 == "memory_bytes").unwrap();
    assert_eq!((memory.1.as_str(), memory.2), ("max", (4 * 2048 * 2048 * 4) as f64));
    // A fraction at its bound gets no rule; any other fraction's limit stays below 1.
    let a = analysis(BASE);
    let under = a.summary.undersampled_fraction;
    assert_eq!(names.contains(&"undersampled_fraction"), under < 1.0, "{under}");
    for (name, bound, lim) in &rules {
        if name.ends_with("_fraction") && bound == "max" {
            assert!(*lim < 1.0, "{name} max {lim}");
        }
    }
    // The gate passes today, and every rule on a real value fails 10 % worse (5 % headroom).
    let pass = case.check(&cfg, &gate, &[]);
    assert_eq!(pass.status.code(), Some(0), "{}", stdout(&pass));
    let mean = rules.iter().find(|r| r.0 == "mean_aliasing").unwrap();
    assert!(
        mean.2 > a.summary.mean_aliasing && mean.2 < a.summary.mean_aliasing * 1.1,
        "{mean:?}"
    );
}

#[test]
fn a_rule_on_an_unmeasured_metric_is_an_error_naming_the_rule_and_how_to_measure_it() {
    let case = Case::new();
    let cfg = case.file("bounds.toml", BASE);
    for (metric, how) in [
        ("acne_fraction", "[analysis] ground_truth = true"),
        ("flicker_snapped", "[analysis] ground_truth = true"),
        ("screen_aliasing_p95", "scene geometry"),
        ("light_crawl", "moving light"),
    ] {
        let rules = case.file(
            "rules.toml",
            &format!(
                "[[rule]]\nmetric = \"mean_aliasing\"\nmax = 100.0\n\n[[rule]]\nmetric = \"{metric}\"\nmax = 0.5\n"
            ),
        );
        let out = case.check(&cfg, &rules, &[]);
        assert_eq!(out.status.code(), Some(2), "{metric}: {}", stdout(&out));
        let err = stderr(&out);
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            err.contains("rule[2].metric") && err.contains(metric) && err.contains(how),
            "{metric}: {err}"
        );
        assert!(err.contains("rules.toml:5:1"), "{metric}: {err}");
        assert!(!stdout(&out).contains("PASS"), "{metric}");
    }
    // A per-cascade ground-truth metric likewise.
    let rules = case.file(
        "rules.toml",
        "[[rule]]\nmetric = \"bias_needed\"\ncascade = 0\nmax = 0.5\n",
    );
    let err = stderr(&case.check(&cfg, &rules, &[]));
    assert!(
        err.contains("rule[1].metric") && err.contains("bias_needed") && err.contains("ground_truth = true"),
        "{err}"
    );
}

#[test]
fn check_sweep_gates_the_recommendation_and_the_configured_setting_unless_all_rows() {
    let case = Case::new();
    let cfg = repo("configs/default.toml");
    let t = repo("configs/thresholds.toml");
    // What the sweep decides, read from its own sweep.csv.
    let out_dir = case.path("sweep");
    let o = bin()
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--quiet",
            "--no-plots",
            "--out",
            out_dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (header, rows) = read_csv(&out_dir.join("sweep.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let label = |r: &Vec<String>| {
        let range = if r[col("split_range")] == "visible" {
            " split_range=visible"
        } else {
            ""
        };
        format!(
            "lambda={} cascades={} resolution={} fit={}{range}",
            r[col("lambda")],
            r[col("cascades")],
            r[col("resolution")],
            r[col("fit")]
        )
    };
    // configs/default.toml configures λ 0.75, 4 cascades of 2048², sphere, bounds.
    let configured = "lambda=0.75 cascades=4 resolution=2048 fit=sphere";
    let recommended: Vec<String> = rows
        .iter()
        .filter(|r| r[col("recommended")] == "true")
        .map(label)
        .collect();
    assert_eq!(recommended.len(), 1);
    assert_ne!(recommended[0], configured);
    assert!(rows.iter().any(|r| label(r) == configured));
    let (_, report) = case.check_json(&cfg, &t, &["--sweep"]);
    let labels: Vec<&str> = report["configurations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["label"].as_str().unwrap())
        .collect();
    let mut expected = vec![recommended[0].as_str(), configured];
    expected.sort_unstable();
    let mut got = labels.clone();
    got.sort_unstable();
    assert_eq!(got, expected);
    assert_eq!(
        report["gated"],
        format!(
            "gated: the recommendation and the configured setting: 2 of the grid's {} configurations (--all-rows gates every one)",
            rows.len()
        )
    );
    let table = stdout(&case.check(&cfg, &t, &["--sweep"]));
    assert!(
        table.contains("gated: the recommendation and the configured setting: 2 of the grid's"),
        "{table}"
    );
    // --all-rows judges every row of the grid.
    let (_, all) = case.check_json(&cfg, &t, &["--sweep", "--all-rows"]);
    assert_eq!(all["configurations"].as_array().unwrap().len(), rows.len());
}
