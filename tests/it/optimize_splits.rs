//! `sweep --optimize-splits`: the optimum is never worse than any λ of the grid, finds a
//! known optimum, pastes back to the same objective, and bad input is refused clearly.

use std::process::Command;

use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::commands::sweep::grid::{self, Grid};
use csm_lab::commands::sweep::optimize::{evaluate, optimize, Optimized};
use csm_lab::commands::sweep::rank::{self, acceptable};
use csm_lab::commands::sweep::run::{self, Row};
use csm_lab::config::sweep_spec::SweepAxes;
use csm_lab::Config;

use crate::common::{config, with};

/// Sweep `c` over `lambda` × `cascades` × `resolution` and optimise its splits.
fn run(c: &Config, lambda: &str, cascades: &str, resolution: &str) -> (Vec<Row>, Optimized) {
    let overrides = SweepAxes {
        lambda: c
            .shadow
            .preset
            .is_none()
            .then(|| grid::parse_lambda_spec(lambda).unwrap()),
        cascades: Some(grid::parse_cascades_spec(cascades).unwrap()),
        resolution: Some(grid::parse_resolution_spec(resolution).unwrap()),
        ..SweepAxes::default()
    };
    let grid = Grid::resolve(c, &overrides).unwrap();
    let rows = run::run(c, &grid, None, &|| {}).unwrap();
    let o = optimize(c, &grid, &rows, rank::default_objective(c), None).unwrap();
    (rows, o)
}

/// Never worse than every λ of the grid: for each cascade count and resolution, the optimum is
/// acceptable and its objective is at most that of every acceptable grid row of the group.
#[test]
fn the_optimum_is_never_worse_than_any_lambda_of_the_grid() {
    let cases = [
        // Bounds only (mean aliasing), sphere and box fits, another camera.
        with(&[]),
        with(&[("shadow.fit", "fit = \"aabb\"")]),
        with(&[
            ("camera.position", "position = [30.0, 60.0, 40.0]"),
            ("camera.near", "near = 0.5"),
        ]),
        // Geometry (the 95th percentile of the per-pixel aliasing on screen).
        with(&[
            ("scene.ground", "ground = 0.0"),
            ("screen.width", "width = 480"),
            ("screen.height", "height = 270"),
        ]),
    ];
    for text in &cases {
        let c = config(text);
        let objective = rank::default_objective(&c);
        let (rows, o) = run(&c, "0:1:0.1", "1..4", "512,2048");
        // Counts 2, 3 and 4 at two resolutions.
        assert_eq!(o.groups.len(), 6, "{text}");
        assert!(o.notes.iter().any(|n| n.contains("one cascade")));
        for g in &o.groups {
            let best = objective.value(&g.best.summary);
            assert!(acceptable(&Row {
                setting: g.setting,
                summary: g.best.summary.clone()
            }));
            let group: Vec<&Row> = rows
                .iter()
                .filter(|r| r.setting.cascades == g.setting.cascades && r.setting.resolution == g.setting.resolution)
                .collect();
            assert_eq!(group.len(), 11);
            for r in group.iter().filter(|r| acceptable(r)) {
                let v = objective.value(&r.summary);
                assert!(
                    best <= v,
                    "{} x {}: optimum {best} > λ {} at {v}",
                    g.setting.cascades,
                    g.setting.resolution,
                    r.setting.lambda
                );
            }
            // The start is the best row of the group, and the search improved on it.
            let start = group
                .iter()
                .filter(|r| acceptable(r))
                .map(|r| objective.value(&r.summary))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(objective.value(&g.start.summary), start);
            assert!(
                best < start,
                "{} x {}: no gain",
                g.setting.cascades,
                g.setting.resolution
            );
            assert!(g.best.fractions.windows(2).all(|w| w[0] < w[1]));
            assert!(g.evaluations > 10 && g.evaluations < 2000, "{}", g.evaluations);
        }
    }
}

/// A case with a known optimum: two cascades, bounds only, mean aliasing. The objective is a
/// function of the one split; an exhaustive scan of 4,001 splits, refined by golden-section
/// search, finds its minimum independently of the optimiser, which must land on it: the
/// fraction to 1e-3 (relative) and the objective to 1e-6 (relative: the printed fractions
/// have 4 significant digits, and the objective is flat to second order at its minimum).
#[test]
fn two_cascades_find_the_exhaustive_optimum() {
    for (text, res) in [
        (with(&[]), 2048),
        (
            with(&[("camera.near", "near = 1.0"), ("camera.fov_y_deg", "fov_y_deg = 40.0")]),
            1024,
        ),
    ] {
        let c = config(&text);
        let (_, o) = run(&c, "0:1:0.05", "2", &res.to_string());
        let g = &o.groups[0];
        let point = c.with_cascades(2).unwrap().with_resolution(res).unwrap();
        let f = |p: f64| evaluate(&point, &[p]).unwrap().mean_aliasing;
        let n = 4000;
        let (mut best_p, mut best_v) = (0.0, f64::INFINITY);
        for i in 1..n {
            // Log-spaced over the range, where the optimum lies near the camera.
            let p = (10f64.powf(-4.0 + 4.0 * i as f64 / n as f64)).min(0.999);
            let v = f(p);
            if v < best_v {
                (best_p, best_v) = (p, v);
            }
        }
        let (mut a, mut b) = (
            best_p * 10f64.powf(-4.0 / n as f64),
            best_p * 10f64.powf(4.0 / n as f64),
        );
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let (x1, x2) = (b - phi * (b - a), a + phi * (b - a));
            if f(x1) < f(x2) {
                b = x2;
            } else {
                a = x1;
            }
        }
        let p_star = 0.5 * (a + b);
        let v_star = f(p_star);
        let got = g.best.fractions[0];
        assert!(((got - p_star) / p_star).abs() < 1e-3, "split {got} vs {p_star}");
        let v = g.best.summary.mean_aliasing;
        assert!(v >= v_star * (1.0 - 1e-9), "{v} below the scanned minimum {v_star}?");
        assert!((v - v_star) / v_star < 1e-6, "objective {v} vs {v_star}");
    }
}

/// The printed fractions, pasted into a config file, reproduce the reported objective exactly:
/// csm-lab's `shadow.splits`, and each preset's own split knob.
#[test]
fn pasted_fractions_reproduce_the_objective() {
    let base = with(&[
        ("scene.ground", "ground = 0.0"),
        ("screen.width", "width = 480"),
        ("screen.height", "height = 270"),
    ]);
    let c = config(&base);
    let objective = rank::default_objective(&c);
    let (_, o) = run(&c, "0:1:0.1", "3", "1024");
    let g = &o.groups[0];
    let list = g
        .best
        .fractions
        .iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    let pasted = config(&csm_lab_text(&base, 3, 1024, &list));
    let a = analyze(&pasted, &AnalysisOptions::summary_only());
    assert_eq!(objective.value(&a.summary), objective.value(&g.best.summary));
    assert_eq!(a.summary, g.best.summary);

    for (preset, counts) in [
        ("unity", "2,4"),
        ("unity-urp", "2..4"),
        ("godot", "2,4"),
        ("filament", "2..4"),
        ("bevy", "2..4"),
    ] {
        let text = with(&[
            ("scene.ground", "ground = 0.0"),
            ("screen.width", "width = 480"),
            ("screen.height", "height = 270"),
            ("shadow.preset", &format!("preset = \"{preset}\"")),
        ]);
        let c = config(&text);
        let (_, o) = run(&c, "", counts, "1024");
        assert!(!o.groups.is_empty());
        for g in &o.groups {
            let p = c.shadow.preset.as_ref().unwrap();
            let paste =
                csm_lab::presets::paste_lines(&p.knobs, g.setting.cascades, c.shadow.max_distance, &g.best.fractions)
                    .unwrap();
            let mut t = with(&[
                ("scene.ground", "ground = 0.0"),
                ("screen.width", "width = 480"),
                ("screen.height", "height = 270"),
                ("shadow.preset", &format!("preset = \"{preset}\"")),
                ("shadow.cascades", &format!("cascades = {}", g.setting.cascades)),
                ("shadow.resolution", "resolution = 1024"),
            ]);
            t.push_str(&paste);
            t.push('\n');
            let pasted = config(&t);
            let a = analyze(&pasted, &AnalysisOptions::summary_only());
            assert_eq!(
                objective.value(&a.summary),
                objective.value(&g.best.summary),
                "{preset} x {}:\n{paste}",
                g.setting.cascades
            );
            // The start is the best practical split, which the optimum beats.
            assert!(objective.value(&g.best.summary) < objective.value(&g.start.summary));
            if let Some(conf) = &g.configured {
                assert!(objective.value(&g.best.summary) <= objective.value(&conf.summary));
            }
        }
    }
}

fn csm_lab_text(base: &str, cascades: usize, res: u32, list: &str) -> String {
    let mut t = base.replace("cascades = 4", &format!("cascades = {cascades}"));
    t = t.replace("resolution = 2048", &format!("resolution = {res}"));
    t.replace("lambda = 0.75", &format!("splits = [{list}]"))
}

fn cli(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_csm-lab")).args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_command_writes_the_table_and_is_the_same_at_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("scene.toml");
    std::fs::write(&cfg, with(&[])).unwrap();
    let mut csvs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("t{threads}"));
        let (code, stdout, stderr) = cli(&[
            "sweep",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--optimize-splits",
            "--cascades",
            "1..4",
            "--resolution",
            "1024,2048",
            "--lambda",
            "0:1:0.1",
            "--no-plots",
            "--quiet",
            "--threads",
            threads,
        ]);
        assert_eq!(code, Some(0), "{stderr}");
        assert!(stdout.contains("Free splits (mean_aliasing"), "{stdout}");
        assert!(stdout.contains("With free splits, split fractions ("), "{stdout}");
        let csv = std::fs::read_to_string(out.join("optimized_splits.csv")).unwrap();
        assert_eq!(csv.lines().count(), 1 + 6, "{csv}");
        let rec: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("recommendation.json")).unwrap()).unwrap();
        assert_eq!(rec["optimized_splits"]["groups"].as_array().unwrap().len(), 6);
        let html = std::fs::read_to_string(out.join("report.html")).unwrap();
        assert!(html.contains("<h2>Free splits</h2>") && html.contains("splits = ["));
        csvs.push(csv);
    }
    assert_eq!(csvs[0], csvs[1]);
    // `[sweep] optimize_splits = true` does the same as the flag.
    let cfg2 = dir.path().join("scene2.toml");
    std::fs::write(
        &cfg2,
        format!("{}\n[sweep]\noptimize_splits = true\nlambda = {{ start = 0.0, end = 1.0, step = 0.1 }}\ncascades = [1, 2, 3, 4]\nresolution = [1024, 2048]\n", with(&[])),
    )
    .unwrap();
    let out = dir.path().join("key");
    let (code, _, stderr) = cli(&[
        "sweep",
        cfg2.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-plots",
        "--quiet",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(out.join("optimized_splits.csv")).unwrap(),
        csvs[0]
    );
}

#[test]
fn bad_input_is_refused_naming_the_flag_key_and_preset() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("scene.toml");
    std::fs::write(&cfg, with(&[])).unwrap();
    let c = cfg.to_str().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    for preset in ["unreal", "threejs", "eevee", "dart", "learnopengl", "unity-sample"] {
        let (code, _, stderr) = cli(&[
            "sweep",
            c,
            "--out",
            o,
            "--optimize-splits",
            "--preset",
            preset,
            "--quiet",
        ]);
        assert_eq!(code, Some(2), "{preset}: {stderr}");
        assert!(
            stderr.contains("--optimize-splits")
                && stderr.contains(&format!("the {preset} preset"))
                && stderr.contains("not free"),
            "{stderr}"
        );
        assert!(stderr.contains("bevy, godot, unity, unity-urp, filament"), "{stderr}");
    }
    assert!(!out.exists(), "nothing is written on an error");
    let (code, _, stderr) = cli(&["sweep", c, "--out", o, "--optimize-splits", "--shard", "1/2", "--quiet"]);
    assert_eq!(code, Some(2));
    assert!(
        stderr.contains("--optimize-splits") && stderr.contains("unsharded"),
        "{stderr}"
    );

    // shadow.splits: the count, the order and the range, each naming the key and the value.
    for (line, why) in [
        ("splits = [0.1, 0.3]", "got 2 for 4 cascades"),
        ("splits = [0.1, 0.3, 0.2]", "strictly increasing"),
        ("splits = [0.0, 0.3, 0.6]", "strictly between 0 and 1"),
        ("splits = [0.1, 0.3, 1.0]", "strictly between 0 and 1"),
        ("splits = [0.1, 0.1, 0.5]", "strictly increasing"),
    ] {
        let e = Config::from_toml_str(&with(&[("shadow.splits", line)]), "t.toml", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("shadow.splits") && e.contains(why), "{line}: {e}");
        assert!(e.contains(&line["splits = ".len()..]), "the value as written: {e}");
    }
    // bevy.bounds: one per cascade but the last, inside (minimum_distance, max_distance).
    let bevy = |line: &str| {
        Config::from_toml_str(
            &format!("{}\n[bevy]\n{line}\n", with(&[("shadow.preset", "preset = \"bevy\"")])),
            "t.toml",
            None,
        )
    };
    assert!(bevy("bounds = [5.0, 20.0, 60.0]").is_ok());
    for (line, why) in [
        ("bounds = [5.0, 20.0]", "3 far bounds"),
        ("bounds = [5.0, 20.0, 200.0]", "maximum distance (150)"),
        ("bounds = [0.05, 20.0, 60.0]", "bevy.minimum_distance (0.1)"),
        ("bounds = [20.0, 5.0, 60.0]", "strictly increasing"),
    ] {
        let e = bevy(line).unwrap_err().to_string();
        assert!(e.contains("bevy.bounds") && e.contains(why), "{line}: {e}");
    }
    // A type error points at the line.
    let e = Config::from_toml_str(&with(&[("shadow.splits", "splits = \"0.1\"")]), "t.toml", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("splits"), "{e}");
}

/// Explicit fractions place the boundaries exactly, replace λ, and a preset notes it ignores them.
#[test]
fn explicit_splits_place_the_boundaries() {
    let c = config(&with(&[("shadow.splits", "splits = [0.05, 0.2, 0.5]")]));
    let a = analyze(&c, &AnalysisOptions::summary_only());
    let rig = a.rig().unwrap();
    let (lo, hi) = (rig.splits[0], rig.splits[4]);
    for (i, p) in [0.05, 0.2, 0.5].iter().enumerate() {
        assert_eq!(rig.splits[i + 1], lo + (hi - lo) * p);
    }
    // The same splits as λ would give, through the fractions, give the same analysis.
    let l = config(&with(&[]));
    let s = analyze(&l, &AnalysisOptions::summary_only())
        .rig()
        .unwrap()
        .splits
        .clone();
    let fr: Vec<String> = s[1..4]
        .iter()
        .map(|d| ((d - s[0]) / (s[4] - s[0])).to_string())
        .collect();
    let same = config(&with(&[("shadow.splits", &format!("splits = [{}]", fr.join(", ")))]));
    let b = analyze(&same, &AnalysisOptions::summary_only());
    for (x, y) in b.rig().unwrap().splits.iter().zip(&s) {
        assert!((x - y).abs() <= 1e-12 * y, "{x} vs {y}");
    }
    // A sweep point's λ replaces them; another count drops them.
    assert!(c.with_lambda(0.5).unwrap().shadow.splits.is_none());
    assert!(c.with_cascades(3).unwrap().shadow.splits.is_none());
    assert!(c.with_cascades(4).unwrap().shadow.splits.is_some());
    let p = config(&with(&[
        ("shadow.splits", "splits = [0.05, 0.2, 0.5]"),
        ("shadow.preset", "preset = \"unity\""),
    ]));
    let notes = &p.shadow.preset.as_ref().unwrap().notes;
    assert!(
        notes.iter().any(|n| n.starts_with("shadow.splits ignored")),
        "{notes:?}"
    );
}

/// Worst-case aliasing with two cascades has an exact optimum: the split where both cascades'
/// near-edge aliasing are equal (cascade 0's grows with the split, cascade 1's falls). Found
/// here by bisection on that difference; the optimiser, minimising `max_aliasing`, lands on
/// it to 1e-3 in the split and 1e-3 in the objective.
#[test]
fn two_cascades_equalise_the_worst_case() {
    let text = format!("{}\n[sweep]\nobjective = \"max_aliasing\"\n", with(&[]));
    let c = config(&text);
    let (_, o) = run(&c, "0:1:0.05", "2", "2048");
    let g = &o.groups[0];
    let point = c.with_cascades(2).unwrap().with_resolution(2048).unwrap();
    let edges = |p: f64| {
        let cfg = point.with_splits(&[p]).unwrap();
        let a = analyze(&cfg, &AnalysisOptions::summary_only());
        let m = &a.aggregates().unwrap().cascade_max_aliasing;
        (m[0], m[1])
    };
    let (mut lo, mut hi) = (1e-6, 0.999);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        let (a, b) = edges(mid);
        if a < b {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p_star = 0.5 * (lo + hi);
    let (a, b) = edges(p_star);
    assert!((a - b).abs() < 1e-6 * a, "{a} {b}");
    let got = g.best.fractions[0];
    assert!(((got - p_star) / p_star).abs() < 1e-3, "split {got} vs {p_star}");
    let v = g.best.summary.max_aliasing;
    assert!(v >= a * (1.0 - 1e-9) && (v - a) / a < 1e-3, "{v} vs {a}");
    // Never worse than the best λ of the grid (which lands within 1e-3 of the optimum here).
    assert!(
        v <= g.start.summary.max_aliasing,
        "{v} vs {}",
        g.start.summary.max_aliasing
    );
}

/// `[sweep] optimize_splits` with `--shard`: each shard leaves the search out (with a note) and
/// `merge` runs it on the joined rows, so the merged files equal the unsharded sweep's.
#[test]
fn shards_leave_the_search_to_merge() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("scene.toml");
    std::fs::write(
        &cfg,
        format!(
            "{}\n[sweep]\noptimize_splits = true\nlambda = [0.0, 0.5, 1.0]\ncascades = [1, 2, 3]\nresolution = [1024]\n",
            with(&[])
        ),
    )
    .unwrap();
    let c = cfg.to_str().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (code, _, stderr) = cli(&["sweep", c, "--out", &path("whole"), "--no-plots", "--quiet"]);
    assert_eq!(code, Some(0), "{stderr}");
    for k in ["1/2", "2/2"] {
        let (code, _, stderr) = cli(&[
            "sweep",
            c,
            "--out",
            &path(&format!("s{}", &k[..1])),
            "--no-plots",
            "--shard",
            k,
        ]);
        assert_eq!(code, Some(0), "{stderr}");
        assert!(stderr.contains("sweep.optimize_splits left out"), "{stderr}");
        assert!(!dir
            .path()
            .join(format!("s{}", &k[..1]))
            .join("optimized_splits.csv")
            .exists());
    }
    let (code, _, stderr) = cli(&[
        "merge",
        &path("s1"),
        &path("s2"),
        "--out",
        &path("merged"),
        "--no-plots",
        "--quiet",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    for f in ["optimized_splits.csv", "recommendation.json", "sweep.csv", "report.md"] {
        assert_eq!(
            std::fs::read(dir.path().join("whole").join(f)).unwrap(),
            std::fs::read(dir.path().join("merged").join(f)).unwrap(),
            "{f}"
        );
    }
}

/// Split fractions are written to JSON (`recommendation.json`, the engine files) as a plain
/// array of numbers.
#[test]
fn split_fractions_serialize_as_a_plain_array() {
    let f = csm_core::free_splits::SplitFractions::new(&[0.25, 0.5]).unwrap();
    assert_eq!(serde_json::to_string(&f).unwrap(), "[0.25,0.5]");
}
