//! A level of views (issue 22): `[[view]]` entries, the screen metrics pooled over every view's
//! pixels, each view's own, the sweep over a level, and bad `[[view]]` input.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::{self, read_csv, with};
use csm_lab::analysis::{analyze, level_screen, AnalysisOptions};
use csm_lab::Config;

/// The default scene with a ground and three boxes (scene geometry: screen metrics).
pub(crate) fn scene() -> String {
    with(&[("scene.ground", "ground = 0.0")])
        + "\n[[scene.box]]\nmin = [-40.0, 0.0, -90.0]\nmax = [-20.0, 40.0, -60.0]\n\
           [[scene.box]]\nmin = [15.0, 0.0, -70.0]\nmax = [35.0, 25.0, -45.0]\n\
           [[scene.box]]\nmin = [-12.0, 0.0, -160.0]\nmax = [12.0, 30.0, -130.0]\n"
}

/// Three views of the scene: (name, position, target, weight).
pub(crate) const VIEWS: [(&str, [f64; 3], [f64; 3], f64); 3] = [
    ("street", [5.0, 1.7, 10.0], [-20.0, 2.0, -60.0], 1.0),
    ("roof", [40.0, 30.0, 20.0], [0.0, 0.0, -80.0], 2.0),
    ("corner", [-60.0, 8.0, -20.0], [10.0, 0.0, -100.0], 0.5),
];

fn view_entry(name: &str, p: [f64; 3], t: [f64; 3], weight: f64) -> String {
    format!("\n[[view]]\nname = \"{name}\"\nposition = {p:?}\ntarget = {t:?}\nweight = {weight:?}\n")
}

pub(crate) fn level(views: &[(&str, [f64; 3], [f64; 3], f64)]) -> String {
    let mut text = scene();
    for &(n, p, t, w) in views {
        text += &view_entry(n, p, t, w);
    }
    text
}

/// The scene with `[camera]` at the view's pose and no views.
pub(crate) fn camera_at(p: [f64; 3], t: [f64; 3]) -> Config {
    let text = scene()
        .replace("position = [0.0, 10.0, 0.0]", &format!("position = {p:?}"))
        .replace("target = [0.0, 0.0, -50.0]", &format!("target = {t:?}"));
    common::config(&text)
}

fn summary_only() -> AnalysisOptions {
    AnalysisOptions::summary_only()
}

/// Without views nothing changes; with one `[[view]]` at `[camera]`'s pose every metric is
/// today's single-camera value, the screen ones included, bit for bit.
#[test]
fn a_level_of_one_view_at_the_camera_equals_the_single_camera_analysis() {
    let plain = common::config(&scene());
    let one = common::config(&level(&[("camera", [0.0, 10.0, 0.0], [0.0, 0.0, -50.0], 1.0)]));
    let a = analyze(&plain, &AnalysisOptions::full());
    let b = analyze(&one, &AnalysisOptions::full());
    assert!(a.summary.views.is_empty());
    assert_eq!(b.summary.views.len(), 1);
    assert_eq!(b.summary.views[0].screen, *a.summary.screen.as_ref().unwrap());
    assert_eq!(b.summary.views[0].band_pixel_share, a.summary.band_pixel_share);
    let mut s = b.summary.clone();
    s.views.clear();
    assert_eq!(s, a.summary);
    assert_eq!(b.cascades, a.cascades);
}

/// Two identical views (of any equal weight) are one view.
#[test]
fn two_identical_views_equal_one() {
    let (n, p, t, _) = VIEWS[1];
    let one = level_screen(&common::config(&level(&[(n, p, t, 1.0)]))).unwrap();
    let two = level_screen(&common::config(&level(&[("a", p, t, 3.0), ("b", p, t, 3.0)]))).unwrap();
    assert_eq!(two.screen, one.screen);
    assert_eq!(two.band_pixel_share, one.band_pixel_share);
    assert_eq!(two.views[0].screen, one.views[0].screen);
}

/// A served pixel's `(m, N·L)` of a single-camera analysis, from its pass and its cascades
/// (the rig's splits, each cascade's texel size), by a linear search for the cascade.
fn pixels_of(c: &Config) -> Vec<(f64, f64)> {
    let a = analyze(c, &summary_only());
    let vis = c.setup().visibility().unwrap();
    let Some(rig) = a.rig() else {
        return Vec::new();
    };
    let splits = &rig.splits;
    let m = a.cascades.len();
    vis.samples
        .iter()
        .flatten()
        .filter(|s| s.lit && s.depth >= splits[0] && s.depth <= splits[m])
        .map(|s| {
            let mut i = 0;
            while i + 1 < m && s.depth >= splits[i + 1] {
                i += 1;
            }
            (a.cascades[i].texel_size * s.factor, s.contrast)
        })
        .collect()
}

/// The weighted nearest-rank percentile over `(value, weight)` pairs, brute force: sorted by
/// value, the first whose running weight reaches p % of the total (relative 1e-12 slack on the
/// whole-step rounding of the weights).
fn weighted_percentile(values: &mut [(f64, f64)], p: f64) -> f64 {
    values.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = values.iter().map(|x| x.1).sum();
    let mut run = 0.0;
    for &(m, w) in values.iter() {
        run += w;
        if w > 0.0 && run >= p / 100.0 * total * (1.0 - 1e-12) {
            return m;
        }
    }
    values.last().unwrap().0
}

/// The level's screen metrics equal a brute-force pool of the views' pixels, each view
/// analysed alone as the single camera (its own cascades), each pixel carrying its view's
/// weight: the plain percentiles, the N·L-weighted ones, the maxima and the means.
#[test]
fn pooled_statistics_equal_a_brute_force_pool_of_the_single_camera_views() {
    let text = level(&VIEWS);
    let lvl = level_screen(&common::config(&text)).unwrap();
    let mut plain = Vec::new();
    let mut lit = Vec::new();
    for (k, &(name, p, t, w)) in VIEWS.iter().enumerate() {
        let alone = camera_at(p, t);
        // Each view's own statistics are those of the single-camera analysis from its pose.
        let a = analyze(&alone, &summary_only());
        assert_eq!(lvl.views[k].name, name);
        assert_eq!(lvl.views[k].screen, *a.summary.screen.as_ref().unwrap(), "{name}");
        for (m, c) in pixels_of(&alone) {
            plain.push((m, w));
            lit.push((m, w * c));
        }
    }
    assert!(plain.len() > 1000, "{} served pixels", plain.len());
    let l = &lvl.screen;
    for (p, got) in [(50.0, l.aliasing_p50), (95.0, l.aliasing_p95), (99.0, l.aliasing_p99)] {
        assert_eq!(got, weighted_percentile(&mut plain, p), "p{p}");
    }
    for (p, got) in [(50.0, l.visible_p50), (95.0, l.visible_p95), (99.0, l.visible_p99)] {
        assert_eq!(got, weighted_percentile(&mut lit, p), "visible p{p}");
    }
    let max = plain.iter().map(|x| x.0).fold(0.0, f64::max);
    assert_eq!(l.aliasing_max, max);
    let mean = plain.iter().map(|x| x.0 * x.1).sum::<f64>() / plain.iter().map(|x| x.1).sum::<f64>();
    assert!(
        (l.aliasing_mean - mean).abs() <= 1e-12 * mean,
        "{} vs {mean}",
        l.aliasing_mean
    );
    let vmean = lit.iter().map(|x| x.0 * x.1).sum::<f64>() / lit.iter().map(|x| x.1).sum::<f64>();
    assert!(
        (l.visible_mean - vmean).abs() <= 1e-6 * vmean,
        "{} vs {vmean}",
        l.visible_mean
    );
    // The views differ: the pool is not any one view's.
    let p95: Vec<f64> = lvl.views.iter().map(|v| v.screen.aliasing_p95).collect();
    assert!(p95.iter().any(|&x| x != l.aliasing_p95), "{p95:?}");
}

/// A sweep over a level: what each row keeps of each view (its own value of the objective,
/// its worst case, whether it sees a receiver) is that of each view's own sweep (the view as
/// the single camera), every other metric is `[camera]`'s sweep row, and the pooled maximum is
/// the largest of the views'.
#[test]
fn the_sweep_over_views_equals_the_per_view_sweeps() {
    use csm_lab::commands::sweep::grid::Grid;
    use csm_lab::commands::sweep::run::run;
    use csm_lab::config::sweep_spec::SweepAxes;
    // One cascade builds the same cascades at every λ, and the resolutions scale the texel
    // sizes: the rows that share one remembered pool (screen::pool_memo) are checked too.
    let axes = "\n[sweep]\nlambda = [0.25, 0.75]\ncascades = [1, 2, 4]\nresolution = [512, 1024]\n";
    let text = level(&VIEWS) + axes;
    let c = common::config(&text);
    let grid = Grid::resolve(&c, &SweepAxes::default()).unwrap();
    let rows = run(&c, &grid, Some(2), &|| {}).unwrap();
    let camera = common::config(&(scene() + axes));
    let cam_rows = run(&camera, &grid, Some(1), &|| {}).unwrap();
    assert_eq!(rows.len(), 12);
    for (k, &(_, p, t, _)) in VIEWS.iter().enumerate() {
        let alone = camera_at(p, t);
        let own = run(&alone, &grid, Some(1), &|| {}).unwrap();
        for (r, o) in rows.iter().zip(&own) {
            // The sweep's objective (visible_aliasing_p95 with geometry), bit for bit.
            let screen = o.summary.screen.as_ref().unwrap();
            let kept = &r.summary.view_ranks[k];
            assert_eq!(kept.objective.map(f64::to_bits), Some(screen.visible_p95.to_bits()));
            assert_eq!(kept.worst.to_bits(), screen.aliasing_max.to_bits());
            assert_eq!(kept.seen, screen.receiver_fraction > 0.0);
        }
    }
    for (r, o) in rows.iter().zip(&cam_rows) {
        assert!(r.summary.views.is_empty(), "the rows keep no view's full metrics");
        let mut s = r.summary.clone();
        s.view_ranks.clear();
        s.screen = o.summary.screen.clone();
        s.band_pixel_share = o.summary.band_pixel_share;
        assert_eq!(s, o.summary);
        let max = r.summary.view_ranks.iter().map(|v| v.worst).fold(0.0, f64::max);
        assert_eq!(r.summary.screen.as_ref().unwrap().aliasing_max, max);
    }
}

/// A view that sees no receiver (it looks at the sky): a warning naming it, and the run goes
/// on; it has no screen statistics of its own (blank in `views.csv`, no choice of its own, never
/// the worst view), and the level's pool is that of the other views alone.
#[test]
fn a_view_that_sees_no_receiver_is_a_warning_naming_it_and_has_no_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let views = [VIEWS[0], ("sky", [0.0, 2.0, 0.0], [0.1, 100.0, 0.0], 1.0)];
    let text = level(&views) + "\n[sweep]\nlambda = [0.5, 0.75]\ncascades = [2, 4]\nresolution = [1024]\n";
    let cfg = dir.path().join("sky.toml");
    std::fs::write(&cfg, &text).unwrap();
    let out_dir = dir.path().join("out");
    let o = run_cli(&[
        "sweep",
        cfg.to_str().unwrap(),
        "--no-plots",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning:") && stderr.contains("view \"sky\" sees no receiver"),
        "{stderr}"
    );
    assert!(stdout.contains("sky: sees no receiver"), "{stdout}");
    assert!(stdout.contains("the worst view is street"), "{stdout}");
    let (head, rows) = read_csv(&out_dir.join("views.csv"));
    let col = |key: &str| head.iter().position(|h| h == key).unwrap();
    let sky = rows.iter().find(|r| r[0] == "sky").unwrap();
    assert_eq!(sky[col("screen_receiver_fraction")], "0");
    for key in [
        "screen_aliasing_p95",
        "visible_aliasing_p95",
        "screen_aliasing_mean",
        "alone_setting",
        "objective_at_level",
    ] {
        assert_eq!(sky[col(key)], "", "{key}");
    }
    assert_eq!(sky[col("worst")], "false");
    // The level pools the street view's pixels only: its percentiles are the street view's.
    let c = common::config(&text);
    let lvl = level_screen(&c).unwrap();
    assert_eq!(lvl.screen.aliasing_p95, lvl.views[0].screen.aliasing_p95);
    assert_eq!(lvl.screen.visible_p95, lvl.views[0].screen.visible_p95);
    assert!(lvl.screen.receiver_fraction < lvl.views[0].screen.receiver_fraction);
}

fn rejected(text: &str) -> String {
    match Config::from_toml_str(text, "t.toml", None) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Bad `[[view]]` entries: each error names the entry's key, the value and what is allowed,
/// with the line and column.
#[test]
fn bad_view_entries_are_errors_naming_the_key() {
    let good = view_entry("a", [0.0, 5.0, 0.0], [0.0, 0.0, -10.0], 1.0);
    let cases: [(String, &str, &str); 7] = [
        (
            good.clone() + &view_entry("a", [1.0, 5.0, 0.0], [0.0, 0.0, -10.0], 1.0),
            "view[1].name",
            "no other view has",
        ),
        (
            view_entry("b", [0.0, 5.0, 0.0], [0.0, 5.0, 0.0], 1.0),
            "view[0].target",
            "different from view[0].position",
        ),
        (
            view_entry("b", [0.0, 5.0, 0.0], [0.0, 0.0, -10.0], 0.0),
            "view[0].weight",
            "a number > 0",
        ),
        (
            view_entry("b", [0.0, 5.0, 0.0], [0.0, 0.0, -10.0], -2.0),
            "view[0].weight",
            "from 1e-6 to 1e6",
        ),
        (
            view_entry("", [0.0, 5.0, 0.0], [0.0, 0.0, -10.0], 1.0),
            "view[0].name",
            "1 to 64 printable",
        ),
        (
            view_entry("b", [0.0, 5.0, 0.0], [0.0, -5.0, 0.0], 1.0),
            "view[0].target",
            "not parallel to camera.up",
        ),
        (
            good.replace("weight = 1.0", "fov_y_deg = 180.0"),
            "view[0].fov_y_deg",
            "strictly between 0 and 180",
        ),
    ];
    for (entries, key, allowed) in cases {
        let text = scene() + &entries;
        let err = rejected(&text);
        assert!(err.contains(key) && err.contains(allowed), "{key}: {err}");
        assert!(err.contains("t.toml:"), "no line and column: {err}");
    }
    let err = rejected(&(scene() + &good.replace("weight = 1.0", "pitch = 3.0")));
    assert!(err.contains("unknown field `pitch`"), "{err}");
    let err = rejected(&(scene() + &good.replace("name = \"a\"\n", "")));
    assert!(err.contains("missing field `name`"), "{err}");
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

pub(crate) fn run_cli(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn write_level(dir: &Path) -> String {
    let text = level(&VIEWS) + "\n[sweep]\nlambda = [0.25, 0.5, 0.75]\ncascades = [2, 4]\nresolution = [1024, 2048]\n";
    let p = dir.join("level.toml");
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// `sweep` over a level writes `views.csv` (one row per view, the worst marked, each view's
/// own choice), `views.png`, the views in `recommendation.json` and on stdout, the same bytes
/// at one and two threads and from merged shards; `analyze` writes `views.csv` and names
/// the worst view in `summary.json`.
#[test]
fn the_cli_writes_a_levels_files() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_level(dir.path());
    let (o1, o2) = (dir.path().join("t1"), dir.path().join("t2"));
    let a = run_cli(&[
        "sweep",
        &cfg,
        "--quiet",
        "--threads",
        "1",
        "--out",
        o1.to_str().unwrap(),
    ]);
    let b = run_cli(&[
        "sweep",
        &cfg,
        "--quiet",
        "--threads",
        "2",
        "--out",
        o2.to_str().unwrap(),
    ]);
    assert_eq!(a.status.code(), Some(0), "{}", String::from_utf8_lossy(&a.stderr));
    assert_eq!(b.status.code(), Some(0));
    assert_eq!(common::files(&o1), common::files(&o2));
    let stdout = String::from_utf8_lossy(&a.stdout);
    assert!(stdout.contains("worst view is"), "{stdout}");
    let (head, rows) = read_csv(&o1.join("views.csv"));
    assert_eq!(rows.len(), 3);
    assert_eq!(
        head[..9].join(","),
        "name,position_x,position_y,position_z,target_x,target_y,target_z,weight,worst"
    );
    assert!(head.contains(&"visible_aliasing_p95".to_string()) && head.contains(&"level_cost_percent".to_string()));
    assert_eq!(rows.iter().filter(|r| r[8] == "true").count(), 1);
    assert_eq!(rows[1][0], "roof");
    assert_eq!(rows[1][7], "2");
    let rec: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o1.join("recommendation.json")).unwrap()).unwrap();
    assert_eq!(rec["views"]["count"], 3);
    let worst = rec["views"]["worst_view"].as_str().unwrap();
    let worst_row = rows.iter().find(|r| r[8] == "true").unwrap();
    assert_eq!(worst_row[0], worst);
    // The worst view has the largest objective at the level's choice.
    let col = head.iter().position(|h| h == "objective_at_level").unwrap();
    let values: Vec<f64> = rows.iter().map(|r| r[col].parse().unwrap()).collect();
    assert_eq!(
        worst_row[col].parse::<f64>().unwrap(),
        values.iter().cloned().fold(0.0, f64::max)
    );
    assert!(o1.join("views.png").exists());
    assert!(std::fs::read_to_string(o1.join("report.md"))
        .unwrap()
        .contains("## Views"));

    // Shards carry each view's metrics: merging two gives the unsharded files, views.csv and
    // views.png included (`cli_shard` checks every bundled config, configs/level.toml too).
    let (s1, s2) = (dir.path().join("s1"), dir.path().join("s2"));
    for (k, out) in [("1/2", &s1), ("2/2", &s2)] {
        let s = run_cli(&["sweep", &cfg, "--quiet", "--shard", k, "--out", out.to_str().unwrap()]);
        assert_eq!(s.status.code(), Some(0), "{}", String::from_utf8_lossy(&s.stderr));
    }
    let merged = dir.path().join("merged");
    let m = run_cli(&[
        "merge",
        s1.to_str().unwrap(),
        s2.to_str().unwrap(),
        "--quiet",
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(m.status.code(), Some(0), "{}", String::from_utf8_lossy(&m.stderr));
    let (whole, parts) = (common::files(&o1), common::files(&merged));
    for f in [
        "views.csv",
        "views.png",
        "sweep.csv",
        "recommendation.json",
        "report.md",
    ] {
        assert!(
            whole[f] == parts[f],
            "{f} differs between the sweep and its merged shards"
        );
    }

    let out = dir.path().join("an");
    let an = run_cli(&["analyze", &cfg, "--quiet", "--out", out.to_str().unwrap()]);
    assert_eq!(an.status.code(), Some(0), "{}", String::from_utf8_lossy(&an.stderr));
    let (_, rows) = read_csv(&out.join("views.csv"));
    assert_eq!(rows.len(), 3);
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["views"]["count"], 3);
    assert!(out.join("views.png").exists());
}

/// `configs/level.toml` (seven views of the generated town, `configs/town.glb`): the scene has
/// at least 100,000 triangles, `analyze` and `sweep` write a level's files, and the sweep
/// names each view's own choice beside the level's.
#[test]
fn the_bundled_level_runs_on_a_town_of_a_hundred_thousand_triangles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cfg = root.join("configs/level.toml");
    let c = Config::load(&cfg).unwrap();
    let triangles = c.geometry.as_ref().unwrap().scene.mesh.triangles.len();
    assert!(triangles >= 100_000, "{triangles} triangles");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let s = run_cli(&[
        "sweep",
        cfg.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(s.status.code(), Some(0), "{}", String::from_utf8_lossy(&s.stderr));
    let (head, rows) = read_csv(&out.join("views.csv"));
    let names: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        names,
        [
            "avenue_north",
            "avenue_east",
            "crossing",
            "square",
            "rooftop",
            "vantage",
            "corner"
        ]
    );
    let alone = head.iter().position(|h| h == "alone_setting").unwrap();
    assert!(rows.iter().all(|r| !r[alone].is_empty()));
    let (_, sweep_rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(sweep_rows.len(), 21 * 8 * 4);
    for f in ["views.png", "report.html", "report.md", "recommendation.json"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let a = dir.path().join("analyze");
    let r = run_cli(&[
        "analyze",
        cfg.to_str().unwrap(),
        "--quiet",
        "--out",
        a.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(0), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["views"]["count"], 7);
    assert!(summary["visible_aliasing_p95"].as_f64().unwrap() > 0.0);
}
