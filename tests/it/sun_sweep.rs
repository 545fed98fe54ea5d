//! Sun-angle sweeps (`--sun-azimuth`, `--sun-elevation`): every row equals `analyze` of the
//! config with that light direction written in the file; a sphere fit's texel size does not
//! depend on the light; each setting is judged by its worst sun; bad angles are refused naming
//! the flag or key.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::{self, BASE};
use csm_core::sun::SunAngles;
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::commands::sweep::grid::{Grid, GridFlags};
use csm_lab::commands::sweep::run::Row;
use csm_lab::commands::sweep::{rank, run, SweepResult};
use csm_lab::metric::SummaryMetric;
use csm_lab::Config;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_csm-lab"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

/// Exit 2; the stderr, which must not be a panic.
fn fails_with_2(out: Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked") && !err.contains("internal error"), "{err}");
    err
}

/// The rows of a sweep of `config` with the flags given (as `sweep` runs them).
fn sweep_rows(config: &Config, flags: &GridFlags) -> (Grid, Vec<Row>) {
    let grid = Grid::resolve(config, &flags.overrides().unwrap()).unwrap();
    let rows = run::run(config, &grid, Some(2), &|| {}).unwrap();
    (grid, rows)
}

fn flags(azimuth: Option<&str>, elevation: Option<&str>) -> GridFlags {
    GridFlags {
        lambda: Some("0.75".into()),
        cascades: Some("2,4".into()),
        resolution: Some("1024".into()),
        fit: Some("sphere,aabb".into()),
        sun_azimuth: azimuth.map(String::from),
        sun_elevation: elevation.map(String::from),
        ..GridFlags::default()
    }
}

/// `text` with its `direction = [...]` line of `[light]` replaced by `d`, written as a user
/// would (each number's shortest round-trip decimal).
fn with_direction(text: &str, d: glam::DVec3) -> String {
    let line = format!("direction = [{:?}, {:?}, {:?}]", d.x, d.y, d.z);
    let mut done = false;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            if !done && l.trim_start().starts_with("direction =") {
                done = true;
                line.clone()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(done, "no direction line");
    out.join("\n")
}

#[test]
fn a_sphere_fits_texel_size_and_aliasing_do_not_change_across_a_sun_sweep_bounds_only() {
    let config = common::config(BASE);
    let (_, rows) = sweep_rows(&config, &flags(Some("0:330:30"), Some("10:90:20")));
    assert_eq!(rows.len(), 12 * 5 * 4, "12 azimuths × 5 elevations × 2 counts × 2 fits");
    // The texel sizes under the configured light, analysed on their own.
    for cascades in [2usize, 4] {
        let base = config
            .with_sweep_point(
                0.75,
                cascades,
                1024,
                csm_lab::config::Fit::Sphere,
                csm_lab::config::SplitRange::Bounds,
            )
            .unwrap();
        let reference = analyze(&base, &AnalysisOptions::full());
        let texels: Vec<f64> = reference.cascades.iter().map(|c| c.texel_size).collect();
        assert_eq!(texels.len(), cascades);
        let mut seen = 0;
        for row in rows
            .iter()
            .filter(|r| r.setting.cascades == cascades && r.setting.fit == csm_lab::config::Fit::Sphere)
        {
            let a = analyze(&row.setting.apply(&config).unwrap(), &AnalysisOptions::full());
            let got: Vec<f64> = a.cascades.iter().map(|c| c.texel_size).collect();
            assert_eq!(got, texels, "{}", row.setting.label());
            // And so every density metric is the configured light's, bit for bit.
            for (x, y) in [
                (row.summary.max_aliasing, reference.summary.max_aliasing),
                (row.summary.mean_aliasing, reference.summary.mean_aliasing),
                (row.summary.mean_log_aliasing, reference.summary.mean_log_aliasing),
                (
                    row.summary.undersampled_fraction,
                    reference.summary.undersampled_fraction,
                ),
                (row.summary.z_lo, reference.summary.z_lo),
                (row.summary.z_hi, reference.summary.z_hi),
            ] {
                assert_eq!(x.to_bits(), y.to_bits(), "{}", row.setting.label());
            }
            seen += 1;
        }
        assert_eq!(seen, 60);
    }
    // The AABB fit's texel size does change with the sun (so the test above could fail).
    let aabb: Vec<f64> = rows
        .iter()
        .filter(|r| r.setting.fit == csm_lab::config::Fit::Aabb && r.setting.cascades == 4)
        .map(|r| r.summary.mean_aliasing)
        .collect();
    assert!(aabb.iter().any(|&m| m != aabb[0]), "{aabb:?}");
}

#[test]
fn every_row_of_a_sun_sweep_equals_analyze_of_the_config_with_that_light_written_in_the_file() {
    // Bounds only and with scene geometry (screen metrics), both fits.
    let default_toml = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml"))
        .unwrap()
        .replace("frames = 240", "frames = 30");
    for text in [BASE.to_string(), default_toml] {
        let config = common::config(&text);
        let (grid, rows) = sweep_rows(&config, &flags(Some("0,135,290"), Some("15,60")));
        assert_eq!(rows.len(), 6 * grid.settings_per_sun());
        for row in &rows {
            let sun = row.setting.sun.expect("a sun sweep's rows carry their sun");
            // The light direction from the compass angles, independently of csm-lab.
            let (a, e) = (sun.azimuth_deg.to_radians(), sun.elevation_deg.to_radians());
            let toward_sun = glam::DVec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos());
            let d = -toward_sun;
            assert!((d - SunAngles::of_light_direction(d).light_direction()).length() < 1e-12);
            let s = &row.setting;
            let c = common::config(&with_direction(&text, d))
                .with_sweep_point(s.lambda, s.cascades, s.resolution, s.fit, s.split_range)
                .unwrap();
            assert_eq!(c.light_direction, row.setting.apply(&config).unwrap().light_direction);
            let direct = analyze(&c, &AnalysisOptions::summary_only());
            assert_eq!(direct.summary, row.summary, "{}", s.label());
        }
        // The screen metrics do change with the sun (the test sees them).
        if config.geometry.is_some() {
            let p95: Vec<f64> = rows
                .iter()
                .map(|r| r.summary.screen.as_ref().unwrap().aliasing_p95)
                .collect();
            assert!(p95.iter().any(|&x| x != p95[0]));
        }
    }
}

#[test]
fn one_sun_axis_keeps_the_other_at_the_configured_lights_angle() {
    let config = common::config(BASE);
    // Light (-0.4, -1, -0.3): the sun stands toward (0.4, 1, 0.3), i.e. east (+X) and south
    // (+Z) of the zenith: elevation atan(1 / 0.5), azimuth 180° − atan(0.4 / 0.3).
    let elevation = 1.0f64.atan2(0.5).to_degrees();
    let azimuth = 180.0 - 0.4f64.atan2(0.3).to_degrees();
    let (_, rows) = sweep_rows(&config, &flags(Some("0:90:45"), None));
    assert_eq!(rows.len(), 3 * 4);
    for r in &rows {
        let sun = r.setting.sun.unwrap();
        assert!((sun.elevation_deg - elevation).abs() < 1e-12, "{sun:?}");
    }
    let (_, rows) = sweep_rows(&config, &flags(None, Some("20,40")));
    assert_eq!(rows.len(), 2 * 4);
    for r in &rows {
        let sun = r.setting.sun.unwrap();
        assert!((sun.azimuth_deg - azimuth).abs() < 1e-12, "{sun:?}");
    }
}

#[test]
fn each_setting_is_judged_by_its_worst_sun_and_the_recommendation_by_those_worst_cases() {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml"))
        .unwrap()
        .replace("frames = 240", "frames = 30");
    for text in [BASE.to_string(), text] {
        let config = common::config(&text);
        let (grid, rows) = sweep_rows(&config, &flags(Some("0:300:60"), Some("10,45,80")));
        let result = SweepResult::new(config.clone(), grid, rows.clone(), String::new()).unwrap();
        let objective = result.objective;
        let sun = result.sun.as_ref().unwrap();
        // Every row as run, its cost_index now against the configured setting's (run gives
        // each row its own 1).
        let without_index = |rows: &[csm_lab::commands::sweep::run::Row]| {
            rows.iter()
                .cloned()
                .map(|mut r| {
                    r.summary.cost.cost_index = None;
                    r
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(without_index(&sun.all), without_index(&rows));
        assert_eq!(result.rows.len(), 4, "2 counts × 2 fits");
        // Independently: group the rows by their setting, take the maximum objective.
        let mut worst_rows = Vec::new();
        for judged in &result.rows {
            let same = |r: &&Row| {
                r.setting.cascades == judged.setting.cascades
                    && r.setting.fit == judged.setting.fit
                    && r.setting.lambda == judged.setting.lambda
            };
            let mine: Vec<&Row> = rows.iter().filter(same).collect();
            assert_eq!(mine.len(), 18, "6 azimuths × 3 elevations");
            let max = mine
                .iter()
                .map(|r| objective.value(&r.summary))
                .fold(f64::NEG_INFINITY, f64::max);
            let first_worst = mine.iter().find(|r| objective.value(&r.summary) == max).unwrap();
            assert_eq!(judged.setting.sun, first_worst.setting.sun);
            assert_eq!(objective.value(&judged.summary), max);
            let most = |f: &dyn Fn(&Row) -> f64| mine.iter().map(|r| f(r)).fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(judged.summary.max_aliasing, most(&|r| r.summary.max_aliasing));
            if let Some(st) = &judged.summary.screen {
                assert_eq!(
                    st.aliasing_max,
                    most(&|r| r.summary.screen.as_ref().unwrap().aliasing_max)
                );
            }
            assert_eq!(judged.summary.shimmer_snapped, most(&|r| r.summary.shimmer_snapped));
            assert_eq!(judged.summary.shimmer, most(&|r| r.summary.shimmer));
            assert_eq!(
                judged.summary.coverage_violations as f64,
                most(&|r| r.summary.coverage_violations as f64)
            );
            worst_rows.push(judged.clone());
        }
        // The recommendation and the front are those of the worst cases.
        assert_eq!(
            result.recommendation,
            rank::recommend_by(
                &worst_rows,
                result.budget_mib,
                objective,
                csm_lab::metric::SummaryMetric::named(if config.geometry.is_some() {
                    "screen_aliasing_max"
                } else {
                    "max_aliasing"
                })
            )
        );
        assert_eq!(result.front, rank::pareto_front_by(&worst_rows, objective));
        // The default objective: the contrast-weighted screen p95 with geometry, mean aliasing
        // without.
        let want = if config.geometry.is_some() {
            "visible_aliasing_p95"
        } else {
            "mean_aliasing"
        };
        assert_eq!(objective, SummaryMetric::named(want));
    }
}

#[test]
fn a_sun_sweep_writes_every_row_the_sun_figure_and_names_the_worst_sun() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("sun.toml");
    std::fs::write(&cfg, BASE).unwrap();
    let out = tmp.path().join("out");
    let o = run(&[
        "sweep",
        cfg.to_str().unwrap(),
        "--quiet",
        "--lambda",
        "0.75",
        "--cascades",
        "4",
        "--resolution",
        "2048",
        "--fit",
        "sphere,aabb",
        "--sun-azimuth",
        "0:345:15",
        "--sun-elevation",
        "5:85:5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("each under 408 sun angles (24 azimuths × 17 elevations)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("judged at its worst of 408 sun angles: sun azimuth"),
        "{stdout}"
    );
    assert!(
        stdout.contains("note: bounds only:") && stdout.contains("texel size"),
        "{stdout}"
    );
    let mut reader = csv::Reader::from_path(out.join("sweep.csv")).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        header[header.len() - 3..],
        ["sun_azimuth_deg", "sun_elevation_deg", "worst_sun"]
    );
    let records: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
    assert_eq!(records.len(), 816);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    // One worst row per setting, and it holds the largest mean aliasing of its setting.
    for fit in ["sphere", "aabb"] {
        let mine: Vec<&csv::StringRecord> = records.iter().filter(|r| &r[col("fit")] == fit).collect();
        assert_eq!(mine.len(), 408);
        let worst: Vec<&&csv::StringRecord> = mine.iter().filter(|r| &r[col("worst_sun")] == "true").collect();
        assert_eq!(worst.len(), 1);
        let mean = |r: &csv::StringRecord| r[col("mean_aliasing")].parse::<f64>().unwrap();
        let max = mine.iter().map(|r| mean(r)).fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(mean(worst[0]), max);
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("recommendation.json")).unwrap()).unwrap();
    assert_eq!(json["sun_angles"], 408);
    assert!(json["recommended"]["worst_sun"]["azimuth_deg"].is_number());
    assert!(json["light_independent"].as_str().unwrap().contains("sphere fit"));
    for f in ["quality_vs_sun.svg", "quality_vs_sun.png"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 1000, "{f}");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // The sun figure is in the page (inlined), after the section that names the worst sun.
    assert!(html.contains("<h2>Sun angles</h2>") && html.contains("its worst sun marked"));
    assert!(html.contains("sun azimuth, degrees from north toward east"));
    let svg = std::fs::read_to_string(out.join("quality_vs_sun.svg")).unwrap();
    assert!(svg.contains("sun azimuth, degrees from north toward east") && svg.contains("sun elevation, degrees"));
}

#[test]
fn sun_sweeps_are_byte_identical_at_any_thread_count() {
    let tmp = tempfile::tempdir().unwrap();
    let files = |threads: &str| {
        let out = tmp.path().join(threads);
        let o = run(&[
            "sweep",
            "configs/default.toml",
            "--quiet",
            "--no-plots",
            "--lambda",
            "0.5,0.75",
            "--cascades",
            "3,4",
            "--resolution",
            "1024",
            "--sun-azimuth",
            "0:270:90",
            "--sun-elevation",
            "20,70",
            "--threads",
            threads,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        ["sweep.csv", "recommendation.json", "report.md"].map(|f| std::fs::read(out.join(f)).unwrap())
    };
    assert!(files("1") == files("2"));
}

#[test]
fn bad_sun_angles_name_the_flag_or_the_key() {
    for (flag, spec, words) in [
        ("--sun-elevation", "0", "(0, 90]"),
        ("--sun-elevation", "95", "(0, 90]"),
        ("--sun-elevation", "5:85:0", "step must be > 0"),
        ("--sun-elevation", "0:85:5", "(0, 90]"),
        ("--sun-elevation", "20,20", "listed twice"),
        ("--sun-azimuth", "360", "[0, 360)"),
        ("--sun-azimuth", "-15", "[0, 360)"),
        ("--sun-azimuth", "0:345:0", "step must be > 0"),
        ("--sun-azimuth", "north", "not a number"),
    ] {
        let err = fails_with_2(run(&["sweep", "configs/default.toml", "--quiet", flag, spec]));
        assert!(err.contains(flag) && err.contains(words), "{flag} {spec}: {err}");
    }
    let tmp = tempfile::tempdir().unwrap();
    for (line, key, words) in [
        ("sun_elevation = [0.0, 30.0]", "sweep.sun_elevation", "(0, 90]"),
        ("sun_elevation = [95.0]", "sweep.sun_elevation", "(0, 90]"),
        (
            "sun_elevation = { start = 5.0, end = 85.0, step = 0.0 }",
            "sweep.sun_elevation",
            "step must be > 0",
        ),
        ("sun_azimuth = [0.0, 360.0]", "sweep.sun_azimuth", "[0, 360)"),
    ] {
        let cfg = tmp.path().join("bad.toml");
        std::fs::write(&cfg, format!("{BASE}\n[sweep]\n{line}\n")).unwrap();
        let err = fails_with_2(run(&["sweep", cfg.to_str().unwrap(), "--quiet"]));
        assert!(err.contains(key) && err.contains(words), "{line}: {err}");
    }
    // The validating constructor refuses a zero light direction, naming the key.
    let config = common::config(BASE);
    let e = config.with_light_direction(glam::DVec3::ZERO).unwrap_err().to_string();
    assert!(e.contains("light.direction"), "{e}");
}

/// The contrast-weighted p95 (`visible_aliasing_p95`, the default objective with geometry)
/// over 1-degree steps of the sun's azimuth on the default scene. Near the zenith (85 degrees,
/// the case: camera-facing walls turning from N.L = +0.09 to facing away) it changes by
/// under 1 % per step where the unweighted p95 jumps by over 90 %. Lower suns still move it
/// by up to about half where the aliasing's distribution has a gap between walls and ground (a
/// nearest-rank percentile steps across a gap), but always by much less than the unweighted one.
#[test]
fn the_visible_p95_changes_smoothly_over_one_degree_sun_steps() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml");
    let config = Config::from_toml_str(&std::fs::read_to_string(path).unwrap(), "default.toml", None).unwrap();
    let p95 = SummaryMetric::named("visible_aliasing_p95");
    let raw = SummaryMetric::named("screen_aliasing_p95");
    assert_eq!(rank::default_objective(&config), p95);
    for elevation in ["85", "60", "30", "15"] {
        let f = GridFlags {
            lambda: Some("0.75".into()),
            cascades: Some("4".into()),
            resolution: Some("2048".into()),
            fit: Some("sphere".into()),
            sun_azimuth: Some("0:359:1".into()),
            sun_elevation: Some(elevation.into()),
            ..GridFlags::default()
        };
        let (_, rows) = sweep_rows(&config, &f);
        assert_eq!(rows.len(), 360);
        // The largest relative change between neighbouring azimuths, around the circle.
        let jump = |m: SummaryMetric| {
            (0..rows.len())
                .map(|k| {
                    let a = m.value(&rows[k].summary);
                    let b = m.value(&rows[(k + 1) % rows.len()].summary);
                    (a - b).abs() / a.max(b)
                })
                .fold(0.0f64, f64::max)
        };
        let (visible, unweighted) = (jump(p95), jump(raw));
        assert!(
            unweighted > 0.9,
            "elevation {elevation}: unweighted p95 jumps by {unweighted}"
        );
        assert!(
            visible < unweighted / 1.5,
            "elevation {elevation}: visible {visible}, unweighted {unweighted}"
        );
        if elevation == "85" {
            assert!(visible < 0.01, "near the zenith: {visible}");
        }
    }
}
