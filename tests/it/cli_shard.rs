//! `sweep --shard K/N` and `merge` as a user runs them: the shards of a sweep merge into the
//! unsharded sweep's files byte for byte, and a bad set of shards is an error that says which.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::files;
use common::BASE;

/// Runs the binary from the repository root, so `configs/x.toml` reads as a user types it.
fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_csm-lab"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn ok(out: Output) -> Output {
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    out
}

/// Exit 2; the stderr, which must not be a panic.
fn fails_with_2(out: Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked") && !err.contains("internal error"), "{err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn sweep_shard(config: &str, shard: &str, out: &Path) {
    ok(run(&["sweep", config, "--quiet", "--shard", shard, "--out", s(out)]));
}

fn merge(dirs: &[PathBuf], out: &Path) -> Output {
    let mut args = vec!["merge".to_string(), "--out".into(), s(out).into()];
    args.extend(dirs.iter().map(|d| s(d).to_string()));
    bin().args(&args).output().unwrap()
}

/// The bundled configs a sweep runs on (every `configs/*.toml` but the thresholds file).
fn bundled_configs() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut v: Vec<String> = std::fs::read_dir(root)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".toml") && n != "thresholds.toml")
        .map(|n| format!("configs/{n}"))
        .collect();
    v.sort();
    v
}

#[test]
fn merging_1_2_3_or_7_shards_writes_the_unsharded_sweeps_files_byte_for_byte_on_every_bundled_config() {
    let tmp = tempfile::tempdir().unwrap();
    let configs = bundled_configs();
    assert!(configs.len() >= 5, "{configs:?}");
    std::thread::scope(|scope| {
        for config in &configs {
            let base = tmp.path().join(config.replace(['/', '.'], "_"));
            scope.spawn(move || {
                let full = base.join("full");
                ok(run(&["sweep", config, "--quiet", "--out", s(&full)]));
                let expected = files(&full);
                assert!(expected.len() >= 12 && expected.contains_key("report.html"), "{config}");
                let rows = csv::Reader::from_path(full.join("sweep.csv"))
                    .unwrap()
                    .records()
                    .count();
                for n in [1usize, 2, 3, 7] {
                    let dirs: Vec<PathBuf> = (1..=n).map(|k| base.join(format!("s{n}-{k}"))).collect();
                    let mut shard_rows = 0;
                    for (k, dir) in dirs.iter().enumerate() {
                        sweep_shard(config, &format!("{}/{n}", k + 1), dir);
                        shard_rows += csv::Reader::from_path(dir.join("sweep.csv")).unwrap().records().count();
                    }
                    // The slices are disjoint and together are the grid.
                    assert_eq!(shard_rows, rows, "{config}, {n} shards");
                    // Shards are given in any order.
                    let mut given = dirs.clone();
                    given.reverse();
                    let out = base.join(format!("merged{n}"));
                    let o = ok(merge(&given, &out));
                    assert!(String::from_utf8_lossy(&o.stdout).contains(&format!("{rows} configurations")));
                    let got = files(&out);
                    assert_eq!(
                        got.keys().collect::<Vec<_>>(),
                        expected.keys().collect::<Vec<_>>(),
                        "{config}, {n} shards"
                    );
                    for (name, bytes) in &expected {
                        assert!(&got[name] == bytes, "{config}, {n} shards: {name} differs");
                    }
                }
            });
        }
    });
}

/// A small grid of 3 λ × 2 counts × 2 resolutions = 12 configurations, written under `dir`.
fn small_config(dir: &Path, name: &str, far: f64) -> String {
    let text = common::with(&[("camera.far", &format!("far = {far}"))]);
    let text = format!("{text}\n[sweep]\nlambda = [0.5, 0.75, 1.0]\ncascades = [2, 4]\nresolution = [512, 1024]\n");
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    assert!(BASE.contains("far = 1000.0"));
    p.to_str().unwrap().to_string()
}

fn read_csv(path: &Path) -> Vec<Vec<String>> {
    csv::Reader::from_path(path)
        .unwrap()
        .records()
        .map(|r| r.unwrap().iter().map(String::from).collect())
        .collect()
}

#[test]
fn a_shard_holds_every_nth_row_of_the_grid_with_the_unsharded_values() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = small_config(tmp.path(), "small.toml", 1000.0);
    let full = tmp.path().join("full");
    ok(run(&["sweep", &cfg, "--quiet", "--no-plots", "--out", s(&full)]));
    let all = read_csv(&full.join("sweep.csv"));
    assert_eq!(all.len(), 12);
    let shard = tmp.path().join("s2");
    // Plots are not asked away: a shard writes none anyway.
    let out = ok(run(&["sweep", &cfg, "--shard", "2/5", "--out", s(&shard)]));
    let stdout = String::from_utf8_lossy(&out.stdout);
    // Rows 2, 7 and 12 (1-based) of 12, and no verdict.
    assert!(
        stdout.starts_with("small: shard 2 of 5: configurations 2, 7, 12 of 12\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains("`csm-lab merge` of all 5 shard directories decides"),
        "{stdout}"
    );
    for verdict in ["recommended", "Pareto front (", "λ =", "worst"] {
        assert!(!stdout.contains(verdict), "{verdict}: {stdout}");
    }
    // Its rows and manifest, nothing that decides.
    let mut names: Vec<String> = files(&shard).into_keys().collect();
    names.sort();
    assert_eq!(names, ["shard-rows.jsonl", "shard.json", "sweep.csv"]);
    let part = read_csv(&shard.join("sweep.csv"));
    // Rows 1, 6 and 11 (0-based) of the grid: the setting and every metric as unsharded; the
    // pareto and recommended columns (last but one and two) are empty: a slice decides nothing.
    assert_eq!(part.len(), 3);
    for (row, i) in part.iter().zip([1, 6, 11]) {
        let n = row.len();
        assert_eq!(row[..n - 3], all[i][..n - 3], "row {i}");
        assert_eq!((row[n - 3].as_str(), row[n - 2].as_str()), ("", ""), "row {i}");
        assert!(["true", "false"].contains(&all[i][n - 3].as_str()), "row {i}");
        assert_eq!(row[n - 1], all[i][n - 1], "row {i}");
    }
    // --format json prints the manifest (the shard's own account of itself).
    let json = ok(run(&[
        "sweep",
        &cfg,
        "--quiet",
        "--shard",
        "1/1",
        "--format",
        "json",
        "--out",
        s(&tmp.path().join("s1")),
    ]));
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(
        (v["shard"].as_u64(), v["shards"].as_u64(), v["rows"].as_u64()),
        (Some(1), Some(1), Some(12))
    );
    assert!(v.get("recommended").is_none(), "{v}");
    let whole = ok(run(&[
        "sweep",
        &cfg,
        "--quiet",
        "--shard",
        "1/1",
        "--out",
        s(&tmp.path().join("s1t")),
    ]));
    assert!(String::from_utf8_lossy(&whole.stdout).starts_with("small: shard 1 of 1: configurations 1–12 of 12\n"));
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(shard.join("shard.json")).unwrap()).unwrap();
    assert_eq!(manifest["shard"], 2);
    assert_eq!(manifest["shards"], 5);
    assert_eq!(manifest["grid_configurations"], 12);
    assert_eq!(manifest["rows"], 3);
    assert_eq!(manifest["tool"], format!("csm-lab {}", env!("CARGO_PKG_VERSION")));
    assert_eq!(manifest["config_hash"].as_str().unwrap().len(), 16);
}

#[test]
fn a_bad_shard_spec_is_an_error_naming_the_shard_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = small_config(tmp.path(), "small.toml", 1000.0);
    for (spec, says) in [
        ("0/4", "K = 0 is outside 1..=4"),
        ("5/4", "K = 5 is outside 1..=4"),
        ("1/0", "N = 0 shards"),
        ("2", "use K/N"),
        ("a/4", "is not a whole number"),
        ("1/13", "13 shards for a grid of 12 configurations"),
    ] {
        let err = fails_with_2(run(&[
            "sweep",
            &cfg,
            "--quiet",
            "--shard",
            spec,
            "--out",
            s(tmp.path()),
        ]));
        assert!(
            err.contains(&format!("--shard \"{spec}\"")) && err.contains(says),
            "{spec}: {err}"
        );
    }
}

/// Shards 1..=3 of 3 of `cfg` under `dir`.
fn three_shards(cfg: &str, dir: &Path) -> Vec<PathBuf> {
    (1..=3)
        .map(|k| {
            let d = dir.join(format!("shard{k}"));
            ok(run(&[
                "sweep",
                cfg,
                "--quiet",
                "--no-plots",
                "--shard",
                &format!("{k}/3"),
                "--out",
                s(&d),
            ]));
            d
        })
        .collect()
}

#[test]
fn merging_without_a_shard_says_which_shard_is_missing() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = small_config(tmp.path(), "small.toml", 1000.0);
    let d = three_shards(&cfg, tmp.path());
    let out = tmp.path().join("merged");
    let err = fails_with_2(merge(&[d[0].clone(), d[2].clone()], &out));
    assert!(err.contains("missing shard 2 of 3"), "{err}");
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn merging_a_shard_given_twice_names_the_shard_and_both_directories() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = small_config(tmp.path(), "small.toml", 1000.0);
    let d = three_shards(&cfg, tmp.path());
    let copy = tmp.path().join("copy-of-1");
    std::fs::create_dir(&copy).unwrap();
    for f in ["shard.json", "shard-rows.jsonl"] {
        std::fs::copy(d[0].join(f), copy.join(f)).unwrap();
    }
    let err = fails_with_2(merge(
        &[d[0].clone(), d[1].clone(), d[2].clone(), copy.clone()],
        &tmp.path().join("m"),
    ));
    assert!(err.contains("shard 1 of 3 was given twice"), "{err}");
    assert!(err.contains(s(&copy)) && err.contains(s(&d[0])), "{err}");
}

#[test]
fn merging_shards_of_two_configs_says_they_are_of_another_config() {
    let tmp = tempfile::tempdir().unwrap();
    let a = small_config(tmp.path(), "a.toml", 1000.0);
    let b = small_config(tmp.path(), "b.toml", 800.0);
    let da = three_shards(&a, &tmp.path().join("a"));
    let db = three_shards(&b, &tmp.path().join("b"));
    let err = fails_with_2(merge(
        &[da[0].clone(), db[1].clone(), da[2].clone()],
        &tmp.path().join("m"),
    ));
    assert!(err.contains("of another config or sweep than"), "{err}");
    assert!(err.contains(s(&db[1])), "{err}");
}

#[test]
fn merging_after_the_config_changed_or_with_another_version_or_a_plain_directory_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = small_config(tmp.path(), "small.toml", 1000.0);
    let d = three_shards(&cfg, tmp.path());
    // A directory that is not a shard.
    let plain = tmp.path().join("plain");
    std::fs::create_dir(&plain).unwrap();
    let err = fails_with_2(merge(&[d[0].clone(), plain.clone()], &tmp.path().join("m")));
    assert!(err.contains(s(&plain)) && err.contains("not a shard"), "{err}");
    // A shard made by another csm-lab version.
    let manifest = d[1].join("shard.json");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let version = format!("csm-lab {}", env!("CARGO_PKG_VERSION"));
    std::fs::write(&manifest, text.replace(&version, "csm-lab 0.0.1")).unwrap();
    let err = fails_with_2(merge(&d, &tmp.path().join("m")));
    assert!(err.contains("made by csm-lab 0.0.1"), "{err}");
    std::fs::write(&manifest, text).unwrap();
    ok(merge(&d, &tmp.path().join("m")));
    // The config edited after the shards ran.
    let original = std::fs::read_to_string(&cfg).unwrap();
    let edited = original.replace("far = 1000\n", "far = 900\n");
    assert_ne!(edited, original);
    std::fs::write(&cfg, edited).unwrap();
    let err = fails_with_2(merge(&d, &tmp.path().join("m2")));
    assert!(err.contains("is not what the shards ran"), "{err}");
}

#[test]
fn check_judges_a_merged_sweep_csv_exactly_as_it_judges_the_sweep_it_runs_itself() {
    let tmp = tempfile::tempdir().unwrap();
    let small = small_config(tmp.path(), "small.toml", 1000.0);
    let rules = tmp.path().join("rules.toml");
    std::fs::write(
        &rules,
        "[[rule]]\nmetric = \"max_aliasing\"\nmax = 200.0\n[[rule]]\nmetric = \"coverage_violations\"\nmax = 0\n",
    )
    .unwrap();
    // A bounds-only scene with its own rules, and a bundled scene with geometry and the shipped rules.
    for (cfg, thresholds) in [
        (small.as_str(), s(&rules)),
        ("configs/default.toml", "configs/thresholds.toml"),
    ] {
        let d = three_shards(cfg, &tmp.path().join(cfg.replace(['/', '.'], "_")));
        let merged = tmp.path().join("merged");
        ok(merge(&d, &merged));
        let csv = merged.join("sweep.csv");
        for format in ["table", "json"] {
            let direct = run(&["check", cfg, "--thresholds", thresholds, "--sweep", "--format", format]);
            let from_csv = run(&[
                "check",
                cfg,
                "--thresholds",
                thresholds,
                "--sweep",
                "--sweep-csv",
                s(&csv),
                "--format",
                format,
            ]);
            assert!(matches!(direct.status.code(), Some(0 | 1)), "{cfg}");
            assert_eq!(direct.status.code(), from_csv.status.code(), "{cfg}");
            assert!(!direct.stdout.is_empty());
            assert!(
                direct.stdout == from_csv.stdout,
                "{cfg} --format {format}: the reports differ"
            );
        }
    }
    // A sweep.csv of another grid is refused, naming the file.
    let other = small_config(tmp.path(), "other.toml", 1000.0);
    let text = std::fs::read_to_string(&other)
        .unwrap()
        .replace("cascades = [2, 4]", "cascades = [2, 3]");
    std::fs::write(&other, text).unwrap();
    let csv = tmp.path().join("merged").join("sweep.csv");
    let err = fails_with_2(run(&[
        "check",
        &other,
        "--thresholds",
        s(&rules),
        "--sweep",
        "--sweep-csv",
        s(&csv),
    ]));
    assert!(err.contains(s(&csv)) && err.contains("this config's grid"), "{err}");
    // --sweep-csv needs --sweep.
    let out = run(&["check", &small, "--thresholds", s(&rules), "--sweep-csv", s(&csv)]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn the_plain_shell_recipe_in_docs_check_md_runs_verbatim_and_gates_like_check_sweep() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/check.md")).unwrap();
    let at = doc.find("<!-- shard-shell").expect("the shard-shell marker");
    let body = &doc[at..];
    let body = &body[body.find("```sh\n").unwrap() + 6..];
    let script = &body[..body.find("```").unwrap()];
    assert!(script.contains("--shard") && script.contains("csm-lab merge") && script.contains("--sweep-csv"));
    // A fresh directory holding the bundled configs, with csm-lab on the PATH.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir(tmp.path().join("configs")).unwrap();
    for f in ["default.toml", "thresholds.toml"] {
        std::fs::copy(root.join("configs").join(f), tmp.path().join("configs").join(f)).unwrap();
    }
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_csm-lab")).parent().unwrap();
    let path = format!("{}:{}", bin_dir.display(), std::env::var("PATH").unwrap_or_default());
    let out = Command::new("sh")
        .args(["-e", "-c", script])
        .current_dir(tmp.path())
        .env("PATH", &path)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("error"), "{stderr}");
    // The merged files are the unsharded sweep's, and the gate's verdict is check --sweep's.
    let direct = tmp.path().join("direct");
    let o = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(["sweep", "configs/default.toml", "--quiet", "--out", s(&direct)])
        .current_dir(tmp.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(files(&tmp.path().join("out/default")), files(&direct));
    let check = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args([
            "check",
            "configs/default.toml",
            "--thresholds",
            "configs/thresholds.toml",
            "--sweep",
        ])
        .current_dir(tmp.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), check.status.code(), "{stderr}");
    assert!(String::from_utf8_lossy(&out.stdout).ends_with(&*String::from_utf8_lossy(&check.stdout)));
}

#[test]
fn merging_the_shards_of_a_sweep_with_grid_flags_or_a_preset_replays_those_flags() {
    let tmp = tempfile::tempdir().unwrap();
    for (case, flags) in [
        (
            "flags",
            &[
                "--lambda",
                "0,0.5,1",
                "--cascades",
                "2..4",
                "--resolution",
                "1024",
                "--fit",
                "sphere,aabb",
            ][..],
        ),
        (
            "split-ranges",
            &[
                "--lambda",
                "0.5,1",
                "--cascades",
                "2,4",
                "--resolution",
                "1024",
                "--split-range",
                "bounds,visible",
            ][..],
        ),
        ("unity", &["--preset", "unity"][..]),
        ("unity-res", &["--preset", "unity", "--resolution", "512,2048"][..]),
    ] {
        let base = tmp.path().join(case);
        let full = base.join("full");
        let mut args = vec!["sweep", "configs/default.toml", "--quiet", "--out", s(&full)];
        args.extend(flags);
        ok(run(&args));
        let dirs: Vec<PathBuf> = (1..=3).map(|k| base.join(format!("s{k}"))).collect();
        for (k, dir) in dirs.iter().enumerate() {
            let shard = format!("{}/3", k + 1);
            let mut args = vec![
                "sweep",
                "configs/default.toml",
                "--quiet",
                "--no-plots",
                "--threads",
                "1",
            ];
            args.extend(flags);
            args.extend(["--shard", &shard, "--out", s(dir)]);
            ok(run(&args));
        }
        let merged = base.join("merged");
        ok(merge(&dirs, &merged));
        assert_eq!(files(&merged), files(&full), "{case}");
        let command = String::from_utf8(std::fs::read(merged.join("report.md")).unwrap()).unwrap();
        assert!(command.contains("csm-lab sweep configs/default.toml"), "{case}");
    }
}

#[test]
fn a_preset_sweep_over_its_knob_and_distance_merges_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let axes = [
        "--preset",
        "unreal",
        "--cascades",
        "3,4",
        "--resolution",
        "1024,2048",
        "--knob",
        "2,3",
        "--distance",
        "100,150",
    ];
    let full = tmp.path().join("full");
    let mut args = vec!["sweep", "configs/default.toml", "--quiet", "--out", s(&full)];
    args.extend(axes);
    ok(run(&args));
    let expected = files(&full);
    let dirs: Vec<PathBuf> = (1..=3).map(|k| tmp.path().join(format!("s{k}"))).collect();
    for (k, dir) in dirs.iter().enumerate() {
        let shard = format!("{}/3", k + 1);
        let mut args = vec![
            "sweep",
            "configs/default.toml",
            "--quiet",
            "--shard",
            &shard,
            "--out",
            s(dir),
        ];
        args.extend(axes);
        ok(run(&args));
        let manifest = std::fs::read_to_string(dir.join("shard.json")).unwrap();
        assert!(
            manifest.contains("\"knob\": \"2,3\"") && manifest.contains("\"distance\": \"100,150\""),
            "{manifest}"
        );
    }
    let out = tmp.path().join("merged");
    ok(merge(&dirs, &out));
    let got = files(&out);
    assert_eq!(got.keys().collect::<Vec<_>>(), expected.keys().collect::<Vec<_>>());
    for (name, bytes) in &expected {
        assert!(&got[name] == bytes, "{name} differs");
    }
    let csv = String::from_utf8(expected["sweep.csv"].clone()).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 2 * 2 * 2);
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .ends_with("unreal.cascade_distribution_exponent,shadow.max_distance"));
}

#[test]
fn check_sweep_keys_rows_on_a_presets_knob_and_distance_like_its_sweep_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("unreal.toml");
    std::fs::write(
        &cfg,
        format!(
            "{}\n[sweep]\ncascades = [3, 4]\nresolution = [1024]\nknob = [2.0, 3.0]\ndistance = [100.0, 150.0]\n",
            common::with(&[("shadow.preset", "preset = \"unreal\"")])
        ),
    )
    .unwrap();
    let rules = tmp.path().join("rules.toml");
    std::fs::write(&rules, "[[rule]]\nmetric = \"max_aliasing\"\nmax = 200.0\n").unwrap();
    let out = tmp.path().join("out");
    ok(run(&["sweep", s(&cfg), "--quiet", "--no-plots", "--out", s(&out)]));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .ends_with("unreal.cascade_distribution_exponent,shadow.max_distance"));
    for format in ["table", "json"] {
        let direct = run(&[
            "check",
            s(&cfg),
            "--thresholds",
            s(&rules),
            "--sweep",
            "--format",
            format,
        ]);
        let from_csv = run(&[
            "check",
            s(&cfg),
            "--thresholds",
            s(&rules),
            "--sweep",
            "--sweep-csv",
            s(&out.join("sweep.csv")),
            "--format",
            format,
        ]);
        assert!(
            matches!(direct.status.code(), Some(0 | 1)),
            "{}",
            String::from_utf8_lossy(&direct.stderr)
        );
        assert_eq!(
            direct.status.code(),
            from_csv.status.code(),
            "{}",
            String::from_utf8_lossy(&from_csv.stderr)
        );
        assert!(
            direct.stdout == from_csv.stdout,
            "--format {format}: the reports differ"
        );
    }
}

#[test]
fn a_sun_sweeps_shards_merge_into_its_files_byte_for_byte_and_check_reads_its_sun_keys() {
    let tmp = tempfile::tempdir().unwrap();
    // Scene geometry (screen metrics), a small grid and both sun axes from the [sweep] table.
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml"))
        .unwrap()
        .replace("frames = 240", "frames = 20");
    let start = text.find("[sweep]").unwrap();
    let text = format!(
        "{}[sweep]\nlambda = [0.5, 0.75]\ncascades = [2, 4]\nresolution = [1024]\nsun_azimuth = [0.0, 120.0, 240.0]\nsun_elevation = {{ start = 20.0, end = 60.0, step = 40.0 }}\n",
        &text[..start]
    );
    let cfg = tmp.path().join("sun.toml");
    std::fs::write(&cfg, text).unwrap();
    let cfg = s(&cfg).to_string();
    let full = tmp.path().join("full");
    ok(run(&["sweep", &cfg, "--quiet", "--no-plots", "--out", s(&full)]));
    let expected = files(&full);
    assert_eq!(read_csv(&full.join("sweep.csv")).len(), 4 * 6);
    let d = three_shards(&cfg, &tmp.path().join("shards"));
    let merged = tmp.path().join("merged");
    let mut args = vec!["merge", "--no-plots", "--out", s(&merged)];
    args.extend(d.iter().map(|x| s(x)));
    ok(run(&args));
    let got = files(&merged);
    assert_eq!(got.keys().collect::<Vec<_>>(), expected.keys().collect::<Vec<_>>());
    for (name, bytes) in &expected {
        assert!(&got[name] == bytes, "{name} differs");
    }
    // check --sweep judges every (sun, setting) row, the same from the merged CSV.
    let rules = tmp.path().join("rules.toml");
    std::fs::write(&rules, "[[rule]]\nmetric = \"screen_aliasing_p95\"\nmax = 40.0\n").unwrap();
    let direct = run(&["check", &cfg, "--thresholds", s(&rules), "--sweep", "--format", "json"]);
    let csv = merged.join("sweep.csv");
    let from_csv = run(&[
        "check",
        &cfg,
        "--thresholds",
        s(&rules),
        "--sweep",
        "--sweep-csv",
        s(&csv),
        "--format",
        "json",
    ]);
    assert!(matches!(direct.status.code(), Some(0 | 1)));
    assert_eq!(direct.status.code(), from_csv.status.code());
    assert!(direct.stdout == from_csv.stdout);
    let report = String::from_utf8_lossy(&direct.stdout);
    assert!(report.contains("sun_azimuth=240 sun_elevation=60"), "{report}");
}

/// Merge trusts nothing it reads: an edited row is an error naming the shard's rows file and
/// line; a `config_hash` pasted into a shard's manifest (the one merge prints for an edited
/// config) is an error naming the shard, not a merge of stale rows; shard files that are links
/// to a device are refused before they are read.
#[test]
fn edited_rows_pasted_hashes_and_device_links_are_refused_naming_the_shard() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = small_config(tmp.path(), "small.toml", 1000.0);
    let d = three_shards(&cfg, tmp.path());
    let rows = d[1].join("shard-rows.jsonl");
    let text = std::fs::read_to_string(&rows).unwrap();
    // Edit one metric of the row on line 4 (the third row): its memory figure, doubled.
    let lines: Vec<&str> = text.lines().collect();
    let mut row: serde_json::Value = serde_json::from_str(lines[3]).unwrap();
    let memory = row["row"]["summary"]["memory_bytes"].as_u64().unwrap();
    row["row"]["summary"]["memory_bytes"] = (memory * 2).into();
    let mut edited: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    edited[3] = row.to_string();
    std::fs::write(&rows, edited.join("\n") + "\n").unwrap();
    let err = fails_with_2(merge(&d, &tmp.path().join("m")));
    assert!(
        err.contains(&format!("{}:4", s(&rows))) && err.contains("does not match its digest"),
        "{err}"
    );
    std::fs::write(&rows, &text).unwrap();
    ok(merge(&d, &tmp.path().join("m")));
    // The config changes; merge says the new hash; the user pastes it into every manifest.
    let original = std::fs::read_to_string(&cfg).unwrap();
    std::fs::write(&cfg, original.replace("far = 1000\n", "far = 900\n")).unwrap();
    let err = fails_with_2(merge(&d, &tmp.path().join("m2")));
    let new_hash = err
        .split("its config_hash is ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or_else(|| panic!("{err}"))
        .to_string();
    let manifests: Vec<String> = d
        .iter()
        .map(|dir| std::fs::read_to_string(dir.join("shard.json")).unwrap())
        .collect();
    for dir in &d {
        let m = dir.join("shard.json");
        let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&m).unwrap()).unwrap();
        let old = json["config_hash"].as_str().unwrap().to_string();
        let t = std::fs::read_to_string(&m).unwrap();
        std::fs::write(&m, t.replace(&old, &new_hash)).unwrap();
    }
    let err = fails_with_2(merge(&d, &tmp.path().join("m3")));
    assert!(
        err.contains("shard.json") && err.contains("manifest_digest") && err.contains(s(&d[0])),
        "{err}"
    );
    assert!(!tmp.path().join("m3").exists());
    // A rows file that is a link to /dev/zero: refused, not read until memory runs out.
    #[cfg(unix)]
    {
        std::fs::write(&cfg, &original).unwrap();
        for (dir, m) in d.iter().zip(&manifests) {
            std::fs::write(dir.join("shard.json"), m).unwrap();
        }
        let zero = tmp.path().join("zero-shard");
        std::fs::create_dir(&zero).unwrap();
        std::fs::copy(d[0].join("shard.json"), zero.join("shard.json")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", zero.join("shard-rows.jsonl")).unwrap();
        let err = fails_with_2(merge(
            &[zero.clone(), d[1].clone(), d[2].clone()],
            &tmp.path().join("m4"),
        ));
        assert!(err.contains("not a regular file"), "{err}");
    }
}
