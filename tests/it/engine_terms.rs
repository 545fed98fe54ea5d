//! `recommendation.<engine>.txt`: each engine's setting in its own configuration language,
//! read back. Every check goes through the text: the setting is written, parsed into the
//! engine's knobs, applied to the config, and the cascades of both are compared.

use std::path::{Path, PathBuf};
use std::process::Command;

use csm_lab::analysis::{analyze, rig, AnalysisOptions};
use csm_lab::app::sweep::{sweep_files, SweepRequest};
use csm_lab::commands::compare::engine_settings;
use csm_lab::commands::sweep::grid::GridFlags;
use csm_lab::commands::terms::EngineSetting;
use csm_lab::presets::{apply_terms, PresetChoice, PresetName};
use csm_lab::Config;

fn default_toml() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml")
}

fn load(p: PresetName) -> Config {
    let choice = PresetChoice {
        name: Some(p),
        lenient_overrides: true,
        ..Default::default()
    };
    Config::load_with_preset(&default_toml(), &choice).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
}

/// The config `s` describes, built in memory (knobs and dims set directly).
fn in_memory(s: &EngineSetting) -> Config {
    let mut c = load(s.preset);
    c.shadow.cascades = s.dims.cascades;
    c.shadow.resolution = s.dims.resolution;
    if let Some(d) = s.dims.max_distance {
        c.shadow.max_distance = d;
    }
    let p = c.shadow.preset.as_mut().unwrap();
    p.knobs = s.knobs.clone();
    c
}

/// The config read back from `s`'s text.
fn through_text(s: &EngineSetting) -> Config {
    let text = csm_lab::report::terms::text(s);
    let mut c = load(s.preset);
    apply_terms(&mut c, &text, "recommendation.txt").unwrap_or_else(|e| panic!("{e}\n{text}"));
    c
}

/// Split distances, fitted slices, window sides, texel sizes and light depth ranges equal to
/// 1e-12 (relative).
fn assert_same_cascades(a: &Config, b: &Config, what: &str) {
    assert_eq!(a.shadow.cascades, b.shadow.cascades, "{what}");
    assert_eq!(a.shadow.resolution, b.shadow.resolution, "{what}");
    assert!(close(a.shadow.max_distance, b.shadow.max_distance), "{what}");
    let (ra, rb) = (rig(a).expect(what), rig(b).expect(what));
    assert_eq!(ra.splits.len(), rb.splits.len(), "{what}");
    for (x, y) in ra.splits.iter().zip(&rb.splits) {
        assert!(close(*x, *y), "{what}: splits {:?} vs {:?}", ra.splits, rb.splits);
    }
    for (x, y) in ra.slices.iter().zip(&rb.slices) {
        assert!(
            close(x.near, y.near) && close(x.far, y.far),
            "{what}: slices {x:?} vs {y:?}"
        );
    }
    for (x, y) in ra.sphere_side.iter().zip(&rb.sphere_side) {
        assert!(
            close(*x, *y),
            "{what}: sides {:?} vs {:?}",
            ra.sphere_side,
            rb.sphere_side
        );
    }
    let opts = AnalysisOptions::summary_only();
    let (aa, ab) = (analyze(a, &opts), analyze(b, &opts));
    assert_eq!(aa.cascades.len(), ab.cascades.len(), "{what}");
    for (x, y) in aa.cascades.iter().zip(&ab.cascades) {
        for (u, v, n) in [
            (x.texel_size, y.texel_size, "texel size"),
            (x.width, y.width, "width"),
            (x.near, y.near, "near"),
            (x.far, y.far, "far"),
            (x.light_near, y.light_near, "light near"),
            (x.light_far, y.light_far, "light far"),
        ] {
            assert!(close(u, v), "{what}: cascade {} {n} {u} vs {v}", x.cascade);
        }
    }
}

#[test]
fn every_engine_reads_its_compare_setting_back_to_the_same_cascades() {
    let presets = PresetName::ALL.to_vec();
    let c = csm_lab::commands::compare::run(&default_toml(), &presets, false, &[]).unwrap();
    let scene = Config::load_scene(&default_toml()).unwrap();
    let settings = engine_settings(&c, &scene).unwrap();
    assert_eq!(settings.len(), PresetName::ALL.len());
    for s in &settings {
        assert_same_cascades(&in_memory(s), &through_text(s), &format!("{} (compare)", s.preset));
    }
}

#[test]
fn free_split_fractions_reproduce_csm_labs_own_cascades() {
    // Godot, Unity, URP and Filament take any fractions; Dart and EEVEE have csm-lab's λ
    // rule on the same range: their closest setting ends where csm-lab's own cascades end.
    let scene = Config::load_scene(&default_toml()).unwrap();
    let own = rig(&scene).unwrap();
    let presets = [
        PresetName::Godot,
        PresetName::Unity,
        PresetName::UnityUrp,
        PresetName::Filament,
        PresetName::Dart,
        PresetName::Eevee,
    ];
    let c = csm_lab::commands::compare::run(&default_toml(), &presets, false, &[]).unwrap();
    for s in engine_settings(&c, &scene).unwrap() {
        let back = through_text(&s);
        let r = rig(&back).unwrap();
        assert_eq!(r.slices.len(), own.slices.len(), "{}", s.preset);
        for (x, y) in r.slices.iter().zip(&own.slices) {
            // The fraction is computed from csm-lab's distance and multiplied back: a few ulps.
            assert!(
                (x.far - y.far).abs() <= 1e-9 * y.far,
                "{}: {} vs {}",
                s.preset,
                x.far,
                y.far
            );
        }
    }
}

#[test]
fn every_engine_reads_its_sweep_recommendation_back_to_the_same_cascades() {
    for p in PresetName::ALL {
        let req = SweepRequest {
            config: default_toml(),
            out: None,
            grid: GridFlags {
                preset: Some(p.to_string()),
                resolution: Some("1024,2048".to_string()),
                ..Default::default()
            },
            threads: None,
            quiet: true,
            no_plots: true,
            format: csm_lab::app::Format::Table,
            shard: None,
            optimize_splits: false,
            ground_truth: false,
        };
        let (result, files, _progress) = sweep_files(&req).unwrap();
        let s = result
            .engine_setting
            .clone()
            .expect("a preset sweep has engine settings");
        let name = format!("recommendation.{p}.txt");
        let written = files.iter().find(|(n, _)| *n == name).expect("the file is in the set");
        assert_eq!(written.1, csm_lab::report::terms::text(&s).into_bytes());
        // The recommended row's config, as the sweep built it, against the text read back.
        let row = result
            .recommended()
            .or_else(|| {
                csm_lab::commands::sweep::rank::no_recommendation(&result.rows, result.budget_mib, result.objective)
                    .closest
                    .map(|i| &result.rows[i])
            })
            .unwrap();
        let built = row.setting.apply(&result.config).unwrap();
        assert_same_cascades(&built, &through_text(&s), &format!("{p} (sweep)"));
    }
}

#[test]
fn every_engine_reads_back_each_count_and_knob_value() {
    for p in PresetName::ALL {
        let base = load(p);
        let engine = p.engine();
        let knobs = base.shadow.preset.as_ref().unwrap().knobs.clone();
        let mut values: Vec<Option<f64>> = vec![None];
        if let Some(k) = engine.knob(&knobs, base.shadow.max_distance) {
            values.extend(k.sweep.iter().map(|&x| Some(x)));
        }
        for n in engine.counts(&knobs).list() {
            for v in &values {
                let mut c = base.clone();
                if csm_lab::presets::set_cascades(&mut c, n).is_err() {
                    continue;
                }
                if let Some(v) = v {
                    csm_lab::presets::set_knob(&mut c, *v).unwrap();
                }
                if csm_lab::presets::check_point(&c).is_err() || rig(&c).is_none() {
                    continue;
                }
                if engine.lambda_key(&knobs).is_some() {
                    // An awkward λ: its digits must survive the text.
                    csm_lab::presets::set_lambda(&mut c, 0.1 + 0.2).unwrap();
                }
                let s = EngineSetting::of(&c, vec!["a test".to_string()]).unwrap();
                assert_same_cascades(&c, &through_text(&s), &format!("{p} {n} cascades, knob {v:?}"));
            }
        }
    }
}

/// A bevy text with one line replaced.
fn bevy_text_with(from: &str, to: &str) -> String {
    let c = load(PresetName::Bevy);
    let s = EngineSetting::of(&c, Vec::new()).unwrap();
    let text = csm_lab::report::terms::text(&s);
    assert!(text.contains(from), "{text}");
    text.replacen(from, to, 1)
}

fn read_error(p: PresetName, text: &str) -> String {
    let mut c = load(p);
    apply_terms(&mut c, text, "rec.txt").unwrap_err().to_string()
}

#[test]
fn malformed_files_name_the_file_line_and_field() {
    let bad_number = bevy_text_with("minimum_distance: 0.1,", "minimum_distance: 0.1x,");
    let e = read_error(PresetName::Bevy, &bad_number);
    assert_eq!(e, "rec.txt:5:23: `minimum_distance`: expected a number, found \"0.1x\"");

    let out_of_range = bevy_text_with("overlap_proportion: 0.2,", "overlap_proportion: 1.5,");
    let e = read_error(PresetName::Bevy, &out_of_range);
    assert!(
        e.starts_with(
            "rec.txt:8:25: `overlap_proportion` (bevy.overlap_proportion): 1.5 is not allowed: a number in [0, 1)"
        ),
        "{e}"
    );

    let bad_count = bevy_text_with("num_cascades: 4,", "num_cascades: 5,");
    let e = read_error(PresetName::Bevy, &bad_count);
    assert!(
        e.starts_with("rec.txt:4:19: `num_cascades` (shadow.cascades): 5 is not allowed: one of 1, 2, 3, 4"),
        "{e}"
    );

    let renamed = bevy_text_with("first_cascade_far_bound:", "first_far_bound:");
    let e = read_error(PresetName::Bevy, &renamed);
    assert!(
        e.starts_with(
            "rec.txt:7:5: `first_cascade_far_bound`: expected `first_cascade_far_bound: <first_cascade_far_bound>,`"
        ),
        "{e}"
    );

    let missing = bevy_text_with(".build();", "");
    let e = read_error(PresetName::Bevy, &missing);
    assert!(
        e.contains(": line: expected `.build();`, found the end of the file"),
        "{e}"
    );

    let extra = bevy_text_with(".build();", ".build();\nlet x = 1;");
    let e = read_error(PresetName::Bevy, &extra);
    assert!(e.starts_with("rec.txt:11:1: line: unexpected \"let x = 1;\""), "{e}");

    let not_pow2 = bevy_text_with("size: 2048", "size: 2000");
    let e = read_error(PresetName::Bevy, &not_pow2);
    assert!(
        e.starts_with("rec.txt:2:55: `size` (shadow.resolution): 2000 is not allowed: a power of two"),
        "{e}"
    );

    // A Godot atlas of 2 × 2 tiles must divide.
    let g = load(PresetName::Godot);
    let text = csm_lab::report::terms::text(&EngineSetting::of(&g, Vec::new()).unwrap())
        .replace("set_size(4096, true)", "set_size(4095, true)");
    let e = read_error(PresetName::Godot, &text);
    assert!(
        e.starts_with("rec.txt:2:51: `directional_shadow_size`: 4095 does not hold 2 × 2 equal tiles"),
        "{e}"
    );
    let text = text
        .replace("set_size(4095, true)", "set_size(4096, true)")
        .replace("SHADOW_PARALLEL_4_SPLITS", "SHADOW_PARALLEL_3_SPLITS");
    let e = read_error(PresetName::Godot, &text);
    assert!(
        e.contains("`directional_shadow_mode`: expected one of \"SHADOW_ORTHOGONAL\""),
        "{e}"
    );

    // Another engine's file, and a file for no engine.
    let e = read_error(PresetName::Godot, &bevy_text_with("", ""));
    assert!(e.contains("the settings are for bevy, but the preset is godot"), "{e}");
    let e = read_error(
        PresetName::Bevy,
        &bevy_text_with("settings for bevy", "settings for bevvy"),
    );
    assert!(
        e.starts_with("rec.txt:1:1: header: unknown engine \"bevvy\"") && e.contains("did you mean \"bevy\"?"),
        "{e}"
    );
}

fn csm_lab(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

#[test]
fn compare_writes_every_engines_file_and_analyze_reads_each_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cmp");
    let o = csm_lab(&[
        "compare",
        "configs/default.toml",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    for p in PresetName::ALL {
        let file = out.join(format!("recommendation.{p}.txt"));
        assert!(stdout.contains(&format!("  recommendation.{p}.txt: ")), "{stdout}");
        let a = dir.path().join(format!("an-{p}"));
        let o = csm_lab(&[
            "analyze",
            "configs/default.toml",
            "--engine-settings",
            file.to_str().unwrap(),
            "--quiet",
            "--format",
            "json",
            "--out",
            a.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{p}: {}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(summary["preset"]["name"], p.as_str(), "{p}");
    }
    // The file names the engine: another --preset is refused, so is an unknown engine.
    let bevy = out.join("recommendation.bevy.txt");
    let o = csm_lab(&[
        "analyze",
        "configs/default.toml",
        "--preset",
        "godot",
        "--engine-settings",
        bevy.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--engine-settings") && err.contains("holds bevy settings, but --preset is godot"),
        "{err}"
    );
    let renamed = dir.path().join("r.txt");
    let text = std::fs::read_to_string(&bevy)
        .unwrap()
        .replace("settings for bevy", "settings for frostbite");
    std::fs::write(&renamed, text).unwrap();
    let o = csm_lab(&[
        "analyze",
        "configs/default.toml",
        "--engine-settings",
        renamed.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("r.txt:1:1: header: unknown engine \"frostbite\"; valid presets are dart"),
        "{err}"
    );
}

#[test]
fn merged_shards_write_and_print_the_unsharded_engine_settings() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let grid = [
        "--preset",
        "godot",
        "--resolution",
        "1024,2048",
        "--no-plots",
        "--quiet",
    ];
    let run = |extra: &[&str]| {
        let mut args = vec!["sweep", "configs/default.toml"];
        args.extend_from_slice(&grid);
        args.extend_from_slice(extra);
        let o = csm_lab(&args);
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    let whole = run(&["--out", &d("whole")]);
    run(&["--shard", "1/2", "--out", &d("s1")]);
    run(&["--shard", "2/2", "--out", &d("s2")]);
    let merged = csm_lab(&[
        "merge",
        &d("s1"),
        &d("s2"),
        "--no-plots",
        "--quiet",
        "--out",
        &d("merged"),
    ]);
    assert_eq!(
        merged.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    let file = |sub: &str| std::fs::read_to_string(dir.path().join(sub).join("recommendation.godot.txt")).unwrap();
    assert_eq!(file("whole"), file("merged"));
    let text = file("whole");
    assert!(text.starts_with("# csm-lab engine settings for godot"), "{text}");
    for o in [&whole, &merged] {
        assert!(String::from_utf8_lossy(&o.stdout).ends_with(&format!("recommendation.godot.txt:\n{text}")));
    }
}
