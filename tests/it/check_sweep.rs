//! Rules over sweep rows and sweep.csv baselines, on hand-made tables, plus the per-depth
//! rules against the sampled density profile of real analyses.

use crate::common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{with, BASE};
use csm_lab::commands::check::baseline::{Tolerance, Tolerances, Verdict};
use csm_lab::commands::check::evaluate::{evaluate, Status};
use csm_lab::commands::check::metric::SummaryMetric;
use csm_lab::commands::check::sweep::{
    compare_rows, evaluate_rows, parse_sweep_csv, sweep_rows_for, SweepKey, SweepRow,
};
use csm_lab::commands::check::Thresholds;
use csm_lab::{analyze, AnalysisOptions};

fn key(lambda: f64, cascades: u32, resolution: u32, fit: &str) -> SweepKey {
    SweepKey {
        lambda,
        cascades,
        resolution,
        fit: fit.to_string(),
        split_range: csm_lab::config::SplitRange::Bounds,
        knob: None,
        distance: None,
        sun: None,
        light_update: None,
        update_every: None,
    }
}

fn row(k: SweepKey, metrics: &[(&'static str, f64)]) -> SweepRow {
    SweepRow {
        recommended: false,
        key: k,
        metrics: metrics.iter().map(|&(n, v)| (n, v)).collect(),
    }
}

fn rules(text: &str) -> Thresholds {
    Thresholds::from_toml_str(text, "t.toml").unwrap()
}

#[test]
fn sweep_rows_are_judged_per_configuration_with_only_summary_rules_applying() {
    let t = rules(
        r#"
[[rule]]
metric = "max_aliasing"
max = 8
[[rule]]
metric = "memory_bytes"
max = 70000000
[[rule]]
metric = "texel_size"
cascade = 0
max = 0.01
[[rule]]
metric = "aliasing"
depth = [1, 10]
max = 2
[[rule]]
metric = "size_jitter"
max = 0.1
"#,
    );
    let rows = vec![
        // Passes both applicable rules; size_jitter absent.
        row(
            key(0.75, 4, 2048, "sphere"),
            &[("max_aliasing", 7.5), ("memory_bytes", 67108864.0)],
        ),
        // Fails on aliasing.
        row(
            key(0.5, 4, 2048, "sphere"),
            &[("max_aliasing", 12.0), ("memory_bytes", 67108864.0)],
        ),
        // Fails on memory, exactly at the aliasing limit (passes that one).
        row(
            key(0.75, 8, 2048, "aabb"),
            &[
                ("max_aliasing", 8.0),
                ("memory_bytes", 134217728.0),
                ("size_jitter", 0.5),
            ],
        ),
    ];
    let reports = evaluate_rows(&t.rules, &rows);
    assert_eq!(reports.len(), 3);
    let passed: Vec<bool> = reports.iter().map(|r| r.passed()).collect();
    assert_eq!(passed, [true, false, false]);
    let st = |i: usize| -> Vec<Status> { reports[i].results.iter().map(|r| r.status).collect() };
    use Status::*;
    assert_eq!(st(0), [Pass, Pass, NotApplicable, NotApplicable, NotApplicable]);
    assert_eq!(st(1), [Fail, Pass, NotApplicable, NotApplicable, NotApplicable]);
    assert_eq!(st(2), [Pass, Fail, NotApplicable, NotApplicable, Fail]);
    // The numbers: margin = limit - actual.
    let j = reports[1].results[0].judgement.unwrap();
    assert_eq!((j.actual.value, j.limit, j.margin), (12.0, 8.0, -4.0));
    let j = reports[2].results[0].judgement.unwrap();
    assert_eq!(j.margin, 0.0);
    // Not-applicable results say why, per kind.
    assert!(reports[0].results[2].note.as_ref().unwrap().contains("per-cascade"));
    assert!(reports[0].results[3].note.as_ref().unwrap().contains("per-depth"));
    assert!(reports[0].results[4].note.as_ref().unwrap().contains("size_jitter"));
    assert_eq!(reports[2].key, key(0.75, 8, 2048, "aabb"));
}

#[test]
fn sweep_tables_are_compared_by_key_whatever_the_row_and_column_order() {
    let base_csv = "\
lambda,cascades,resolution,fit,z_lo,z_hi,max_aliasing,mean_aliasing,mean_log_aliasing,undersampled_fraction,shimmer_snapped,shimmer_unsnapped,size_jitter,coverage_violations,memory_bytes
0.5,4,2048,sphere,0.1,150,10,2,20,1,0,0.4,0,0,67108864
0.75,4,2048,sphere,0.1,150,8,2,15,1,0,0.4,0,0,67108864
0.75,4,1024,aabb,0.1,150,16,4,30,1,0.2,0.4,0.01,3,16777216
";
    // Current: other column order, an extra column, one row changed, one new, one dropped.
    let cur_csv = "\
fit,lambda,resolution,cascades,max_aliasing,mean_aliasing,mean_log_aliasing,undersampled_fraction,shimmer_snapped,shimmer_unsnapped,size_jitter,coverage_violations,memory_bytes,z_lo,z_hi,wall_seconds
sphere,0.75,2048,4,8.1,1.5,15,1,0,0.4,0,0,67108864,0.1,150,3.2
aabb,0.75,1024,4,16,4,30,1,0.2,0.4,0.01,5,16777216,0.1,140,1.0
sphere,0.9,2048,4,6,2,12,1,0,0.4,0,0,67108864,0.1,150,2.0
";
    let base = parse_sweep_csv(base_csv, Path::new("base.csv")).unwrap();
    let cur = parse_sweep_csv(cur_csv, Path::new("cur.csv")).unwrap();
    assert_eq!(base.len(), 3);
    assert_eq!(cur[0].key, key(0.75, 4, 2048, "sphere"));
    assert_eq!(cur[0].metrics["mean_aliasing"], 1.5);
    assert!(
        !cur[0].metrics.contains_key("wall_seconds"),
        "unknown columns are ignored"
    );
    assert_eq!(cur[0].metrics.len(), 11, "every summary metric but cascades_needed");

    let tol = Tolerances {
        default: Tolerance {
            relative: 0.02,
            absolute: 1e-9,
        },
        per_metric: BTreeMap::from([(
            SummaryMetric::named("coverage_violations"),
            Tolerance {
                relative: 0.0,
                absolute: 1.0,
            },
        )]),
    };
    let cmp = compare_rows(&cur, &base, &tol).unwrap();
    // Matched in key order: (0.75, 4, 1024, aabb) before (0.75, 4, 2048, sphere).
    let matched: Vec<&SweepKey> = cmp.matched.iter().map(|r| &r.key).collect();
    assert_eq!(matched, [&key(0.75, 4, 1024, "aabb"), &key(0.75, 4, 2048, "sphere")]);
    assert_eq!(cmp.only_current, [key(0.9, 4, 2048, "sphere")]);
    assert_eq!(cmp.only_baseline, [key(0.5, 4, 2048, "sphere")]);

    let verdicts = |i: usize| -> BTreeMap<&'static str, Verdict> {
        cmp.matched[i]
            .comparisons
            .iter()
            .map(|c| (c.metric.name(), c.verdict))
            .collect()
    };
    let aabb = verdicts(0);
    // Coverage 3 -> 5 with an absolute tolerance of 1: regressed; z_hi moved: changed.
    assert_eq!(aabb["coverage_violations"], Verdict::Regressed);
    assert_eq!(aabb["z_hi"], Verdict::Changed);
    assert_eq!(aabb["max_aliasing"], Verdict::Unchanged);
    let sphere = verdicts(1);
    // 8 -> 8.1 is +1.25 %, inside 2 %; mean 2 -> 1.5 improved.
    assert_eq!(sphere["max_aliasing"], Verdict::Unchanged);
    assert_eq!(sphere["mean_aliasing"], Verdict::Improved);
    assert_eq!(cmp.count(Verdict::Regressed), 1);
    assert_eq!(cmp.count(Verdict::Improved), 1);
    let c = cmp.matched[1]
        .comparisons
        .iter()
        .find(|c| c.metric == SummaryMetric::named("max_aliasing"))
        .unwrap();
    assert_eq!((c.baseline, c.current), (Some(8.0), Some(8.1)));
    assert!((c.tolerance - 0.16).abs() < 1e-15);
}

#[test]
fn a_sweep_table_with_a_configuration_twice_is_an_error() {
    let rows = vec![
        row(key(0.5, 4, 2048, "sphere"), &[("max_aliasing", 1.0)]),
        row(key(0.5, 4, 2048, "sphere"), &[("max_aliasing", 2.0)]),
    ];
    let e = compare_rows(&rows, &rows[..1], &Tolerances::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains("lambda=0.5 cascades=4 resolution=2048 fit=sphere"),
        "{e}"
    );
}

#[test]
fn sweep_rows_are_the_sweep_grid_each_equal_to_its_own_analysis() {
    let text = format!(
        "{BASE}\n[sweep]\nlambda = [0.5, 0.75]\ncascades = [2, 4]\nresolution = [1024]\nfit = [\"sphere\", \"aabb\"]\n"
    );
    let config = common::config(&text);
    let rows = sweep_rows_for(&config).unwrap();
    assert_eq!(rows.len(), 8, "2 λ x 2 counts x 1 resolution x 2 fits");
    assert_eq!(rows[0].key, key(0.5, 2, 1024, "sphere"));
    assert_eq!(rows[7].key, key(0.75, 4, 1024, "aabb"));
    for row in &rows {
        let mut c = config.clone();
        c.shadow.lambda = row.key.lambda;
        c.shadow.cascades = row.key.cascades as usize;
        c.shadow.resolution = row.key.resolution;
        c.shadow.fit = if row.key.fit == "sphere" {
            csm_lab::config::Fit::Sphere
        } else {
            csm_lab::config::Fit::Aabb
        };
        let full = analyze(&c, &AnalysisOptions::full());
        let values = row.summary_values();
        // Every metric the full analysis measured but seam_crossings (not a sweep row's), and
        // nothing unmeasured (no ground truth here): never a 0 standing in for a value.
        let measured: Vec<SummaryMetric> = SummaryMetric::all()
            .filter(|m| m.measured(&full.summary) && m.name() != "seam_crossings")
            .collect();
        assert_eq!(
            values.keys().copied().collect::<Vec<_>>(),
            measured,
            "{}",
            row.key.label()
        );
        assert!(!values.contains_key(&SummaryMetric::named("acne_fraction")));
        for m in measured {
            assert_eq!(values[&m], m.value(&full.summary), "{} {}", row.key.label(), m.name());
        }
    }
}

/// Per-depth rules on real analyses against the density profile `analyze` samples (log-spaced
/// depths plus both sides of every split): the exact extremes bound every sample and are
/// within rounding of the nearest one.
#[test]
fn per_depth_extremes_bound_the_sampled_density_profile_of_real_scenes() {
    let scenes = [
        BASE.to_string(),
        with(&[("shadow.fit", "fit = \"aabb\""), ("shadow.cascades", "cascades = 6")]),
        with(&[("shadow.lambda", "lambda = 0.2"), ("camera.near", "near = 0.5")]),
        with(&[
            ("shadow.fit_depth_to_scene", "fit_depth_to_scene = false"),
            ("shadow.cascades", "cascades = 2"),
        ]),
    ];
    let thresholds = rules(
        r#"
[[rule]]
metric = "aliasing"
depth = [3, 80]
max = 1e9
min = 0
[[rule]]
metric = "texels_per_pixel"
depth = [3, 80]
max = 1e9
min = 0
[[rule]]
metric = "aliasing"
max = 1e9
min = 0
"#,
    );
    for text in &scenes {
        let mut config = common::config(text);
        config.analysis.density_samples = 50_000;
        let a = analyze(&config, &AnalysisOptions::full());
        let ranges = [(3.0, 80.0), (3.0, 80.0), (a.summary.z_lo, a.summary.z_hi)];
        for (rule, (lo, hi)) in thresholds.rules.iter().zip(ranges) {
            let result = evaluate(rule, &a).unwrap();
            let samples: Vec<f64> = a
                .density
                .iter()
                .filter(|s| s.depth >= lo && s.depth <= hi)
                .map(|s| {
                    if rule.target.metric_name() == "aliasing" {
                        s.aliasing
                    } else {
                        s.texels_per_pixel
                    }
                })
                .collect();
            let smax = samples.iter().cloned().fold(f64::MIN, f64::max);
            let smin = samples.iter().cloned().fold(f64::MAX, f64::min);
            // Both limits are far away, so the judged side is the max; get both extremes
            // from one-sided copies of the rule.
            let mut max_only = rule.clone();
            max_only.min = None;
            let mut min_only = rule.clone();
            min_only.max = None;
            let emax = evaluate(&max_only, &a).unwrap().judgement.unwrap().actual.value;
            let emin = evaluate(&min_only, &a).unwrap().judgement.unwrap().actual.value;
            assert_eq!(result.status, Status::Pass);
            // The profile's log spacing leaves gaps of ln(z_hi/z_lo)/50k, under 5e-4 here.
            assert!(
                emax >= smax * (1.0 - 1e-12) && emax <= smax * (1.0 + 5e-4),
                "{emax} vs {smax}"
            );
            assert!(
                emin <= smin * (1.0 + 1e-12) && emin >= smin * (1.0 - 5e-4),
                "{emin} vs {smin}"
            );
        }
    }
}
