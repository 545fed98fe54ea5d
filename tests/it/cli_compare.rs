//! `csm-lab compare` and `analyze --preset` as a user runs them: files, formats, messages.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::read_csv;
use common::BASE;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn write_config(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn compare(text: &str, args: &[&str]) -> (Output, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), text);
    let out = bin()
        .arg("compare")
        .arg(&cfg)
        .args(args)
        .arg("--out")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    (out, dir)
}

const FILES: [&str; 7] = [
    "compare.csv",
    "compare_density.svg",
    "compare_density.png",
    "compare_shimmer.svg",
    "compare_shimmer.png",
    "compare.html",
    "compare.md",
];

#[test]
fn compare_writes_one_csv_row_per_preset_and_every_file() {
    let (out, dir) = compare(BASE, &["--presets", "bevy,godot,unreal,threejs,dart"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let o = dir.path().join("out");
    for f in FILES {
        assert!(o.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(o.join("compare.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "preset,lambda,cascades,resolution,fit,z_lo,z_hi,max_aliasing,mean_aliasing,mean_log_aliasing,\
undersampled_fraction,shimmer,shimmer_snapped,shimmer_unsnapped,size_jitter,coverage_violations,memory_bytes,\
overlap_area_fraction,texels_cleared,bytes_written,snaps,coverage_worst_texels,min_slack_texels,receivers_outside_depth,\
casters_outside_depth"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let names: Vec<&str> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(names, ["bevy", "godot", "unreal", "threejs", "dart"]);
    for r in &rows {
        assert_eq!(r.len(), 25);
        // [shadow] of BASE overrides the presets' counts and sizes.
        assert_eq!((r[2], r[3]), ("4", "2048"), "{r:?}");
    }
    // λ only for presets that have one: three.js is practical with λ fixed at 0.5, dart 0.5.
    assert_eq!((rows[0][1], rows[3][1], rows[4][1]), ("", "0.5", "0.5"));
    assert_eq!((rows[0][4], rows[1][4]), ("diameter-ceil", "sphere-average+border"));
    // The rows are what `analyze --preset` computes.
    let cfg = dir.path().join("scene.toml");
    let choice = csm_lab::presets::PresetChoice {
        name: Some(csm_lab::presets::PresetName::Unreal),
        ..Default::default()
    };
    let c = csm_lab::Config::load_with_preset(&cfg, &choice).unwrap();
    let a = csm_lab::analyze(&c, &csm_lab::AnalysisOptions::summary_only());
    assert_eq!(rows[2][7].parse::<f64>().unwrap(), a.summary.max_aliasing);
    assert_eq!(rows[2][13].parse::<f64>().unwrap(), a.summary.shimmer_unsnapped);

    for f in ["compare_density.svg", "compare_shimmer.svg"] {
        let text = std::fs::read_to_string(o.join(f)).unwrap();
        roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(!text.contains("NaN"));
    }
    for f in ["compare_density.png", "compare_shimmer.png"] {
        let bytes = std::fs::read(o.join(f)).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert!(
            info.width >= 800 && info.height >= 300,
            "{f}: {}x{}",
            info.width,
            info.height
        );
        // Not a blank image.
        assert!(buf.iter().any(|&b| b < 128), "{f} is blank");
    }
    let html = std::fs::read_to_string(o.join("compare.html")).unwrap();
    for external in ["http", "src=", "<link", "@import", "url("] {
        assert!(
            !html.contains(external),
            "compare.html refers to something external: {external}"
        );
    }
    assert_eq!(html.matches("<svg").count(), 2, "both figures inline");
    assert!(html.contains("csm-lab compare") && html.contains("<table>"));
    let md = std::fs::read_to_string(o.join("compare.md")).unwrap();
    assert!(md.contains("| preset |") && md.contains("### bevy") && md.contains("compare_density.svg"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    // 7 files, and one engine settings file per preset compared (5).
    assert!(stdout.contains("bevy") && stdout.contains("wrote 12 files"), "{stdout}");
    for p in ["bevy", "godot", "unreal", "threejs", "dart"] {
        assert!(o.join(format!("recommendation.{p}.txt")).is_file(), "{p}");
    }
}

#[test]
fn compare_with_defaults_runs_every_preset_at_its_own_settings() {
    let (out, dir) = compare(BASE, &["--presets", "unity-urp,learnopengl,filament", "--defaults"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let csv = std::fs::read_to_string(dir.path().join("out/compare.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    // URP: 1 cascade of 2048; learnopengl: 3 fixed cascades; Filament: 1 cascade of 1024.
    let got: Vec<(&str, &str)> = rows.iter().map(|r| (r[2].as_str(), r[3].as_str())).collect();
    assert_eq!(got, [("1", "2048"), ("3", "2048"), ("1", "1024")]);
    let md = std::fs::read_to_string(dir.path().join("out/compare.md")).unwrap();
    assert!(md.contains("--defaults"));
}

#[test]
fn a_count_an_engine_does_not_offer_falls_back_to_its_default_in_compare() {
    let text = common::with(&[("shadow.cascades", "cascades = 3")]);
    let (out, dir) = compare(&text, &["--presets", "godot,unreal"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let md = std::fs::read_to_string(dir.path().join("out/compare.md")).unwrap();
    assert!(
        md.contains("shadow.cascades = 3 is not offered by godot (1, 2, 4): its default 4 is used"),
        "{md}"
    );
    let csv = std::fs::read_to_string(dir.path().join("out/compare.csv")).unwrap();
    let counts: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap()).collect();
    assert_eq!(counts, ["4", "3"]);
    // analyze with that preset keeps it an error naming the key.
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), &text);
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--preset", "godot", "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("shadow.cascades"), "{}", stderr(&out));
}

#[test]
fn compare_output_is_byte_identical_between_runs() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), BASE);
    for o in ["a", "b"] {
        let out = bin()
            .args([
                "compare",
                cfg.to_str().unwrap(),
                "--presets",
                "eevee,filament,learnopengl",
                "--out",
            ])
            .arg(dir.path().join(o))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    }
    for f in FILES {
        assert_eq!(
            std::fs::read(dir.path().join("a").join(f)).unwrap(),
            std::fs::read(dir.path().join("b").join(f)).unwrap(),
            "{f} differs"
        );
    }
}

#[test]
fn an_unknown_preset_name_lists_the_valid_ones_and_suggests_the_closest() {
    let (out, dir) = compare(BASE, &["--presets", "bevy,unrel"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--presets") && err.contains("\"unrel\"") && err.contains("did you mean \"unreal\""),
        "{err}"
    );
    assert!(err.contains("dart, threejs, unity-sample"), "{err}");
    assert!(!dir.path().join("out").exists(), "no output on error");

    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), BASE);
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--preset", "godto", "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--preset") && err.contains("did you mean \"godot\""),
        "{err}"
    );
}

#[test]
fn an_engine_table_for_a_preset_not_compared_is_an_error_naming_it() {
    let text = format!("{BASE}\n[godot]\nblend_splits = true\n");
    let (out, _dir) = compare(&text, &["--presets", "bevy,threejs"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("[godot]") && err.contains("scene.toml:"), "{err}");
    // With godot in the list, its table applies to it.
    let (out, _dir) = compare(&text, &["--presets", "bevy,godot"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

#[test]
fn analyze_with_a_preset_prints_its_rules_and_writes_them_to_the_summary() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), BASE);
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--preset", "learnopengl", "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("preset learnopengl") && stdout.contains("off-by-one"),
        "{stdout}"
    );
    assert!(stdout.contains("note: shadow.cascades = 4 ignored"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["preset"]["name"], "learnopengl");
    assert_eq!(summary["preset"]["selection"].as_array().unwrap().len(), 3);
    assert!(summary["coverage_violations"].as_u64().unwrap() > 0);
    assert_eq!(summary["inputs"]["shadow"]["preset"]["name"], "learnopengl");
    // Without a preset, summary.json has no preset key at all.
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--out"])
        .arg(dir.path().join("p"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("p/summary.json")).unwrap()).unwrap();
    assert!(summary.get("preset").is_none() && summary["inputs"]["shadow"].get("preset").is_none());
}

#[test]
fn compare_shows_every_engine_in_binary32_far_from_the_origin() {
    let text = common::with(&[
        ("shadow.precision", "precision = \"f32\""),
        ("scene.world_offset", "world_offset = [1e5, 0.0, 0.0]"),
    ]);
    let all: Vec<&str> = csm_lab::presets::PresetName::ALL.iter().map(|p| p.as_str()).collect();
    let (out, dir) = compare(&text, &["--presets", &all.join(",")]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let csv = std::fs::read_to_string(dir.path().join("out/compare.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), all.len(), "one row per engine");
    for (row, name) in rows.iter().zip(&all) {
        assert_eq!(row[0], *name);
        for (h, cell) in header.iter().zip(row).skip(1) {
            if let Ok(x) = cell.parse::<f64>() {
                assert!(x.is_finite(), "{name}: {h} = {cell}");
            }
        }
        // The same engine analysed alone: its binary32 lookup is off by a measurable, finite
        // amount at 1e5 units (exactly 0 in f64).
        let choice = csm_lab::presets::PresetChoice {
            name: csm_lab::presets::PresetName::parse(name),
            ..Default::default()
        };
        let config = csm_lab::Config::from_toml_str_with_preset(&text, "scene.toml", None, &choice).unwrap();
        let a = csm_lab::analyze(&config, &csm_lab::AnalysisOptions::summary_only());
        let lookup = a.summary.lookup_error_max;
        if *name == "unity-sample" {
            // Its windows stay on the light-space axis through the origin: 1e5 units away no
            // receiver falls inside one, so there is no lookup to be wrong, and the slices
            // are not covered.
            assert_eq!(lookup, 0.0);
            assert!(a.summary.coverage_violations > 0);
        } else {
            assert!(lookup.is_finite() && lookup > 0.1, "{name}: lookup error {lookup}");
        }
    }
}

#[test]
fn compare_names_the_best_valid_preset_by_the_objective_and_lists_the_invalid_apart() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let out = bin()
        .current_dir(root)
        .args(["compare", "configs/default.toml", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // From compare.csv alone: valid = no missed slice corner and no clipped receiver; the scene
    // has geometry, so the objective is the on-screen 95th percentile.
    let (header, rows) = read_csv(&out_dir.join("compare.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let f = |r: &Vec<String>, n: &str| r[col(n)].parse::<f64>().unwrap();
    let (valid, invalid): (Vec<&Vec<String>>, Vec<&Vec<String>>) = rows
        .iter()
        .partition(|r| f(r, "coverage_violations") == 0.0 && f(r, "receivers_outside_depth") == 0.0);
    assert!(
        valid.len() >= 2 && !invalid.is_empty(),
        "{} valid, {} invalid",
        valid.len(),
        invalid.len()
    );
    let mut ranked = valid.clone();
    ranked.sort_by(|a, b| f(a, "visible_aliasing_p95").total_cmp(&f(b, "visible_aliasing_p95")));
    let (best, runner) = (&ranked[0][col("preset")], &ranked[1][col("preset")]);
    let (vb, vr) = (
        f(ranked[0], "visible_aliasing_p95"),
        f(ranked[1], "visible_aliasing_p95"),
    );
    assert!(vb <= vr);
    let md = std::fs::read_to_string(out_dir.join("compare.md")).unwrap();
    let verdicts: Vec<&str> = md.lines().filter(|l| l.contains("best")).collect();
    assert_eq!(verdicts.len(), 1, "{md}");
    let line = verdicts[0];
    assert!(
        line.starts_with(&format!("best: {best} (visible_aliasing_p95 "))
            && line.contains(&format!("the runner-up {runner} (")),
        "{line}"
    );
    // By how much: the percentage the line states is (runner - best) / runner (or a tie).
    if vr == vb {
        assert!(line.contains(&format!("tied with the runner-up {runner} (")), "{line}");
    } else {
        let pct: f64 = line
            .split(" % lower than")
            .next()
            .unwrap()
            .rsplit(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            (pct - 100.0 * (vr - vb) / vr).abs() < 0.01 * pct.max(1.0),
            "{pct} vs {}",
            100.0 * (vr - vb) / vr
        );
    }
    assert!(line.contains(&format!("of {} valid entries", valid.len())), "{line}");
    // Every invalid preset is listed apart with its reason, and never wins.
    let apart = &md[md.find("Invalid, not ranked:").expect("the invalid list")..];
    for r in &invalid {
        let name = &r[col("preset")];
        assert_ne!(name, best);
        assert!(apart.contains(&format!("- {name}: ")), "{name}: {apart}");
    }
    let html = std::fs::read_to_string(out_dir.join("compare.html")).unwrap();
    assert!(html.contains(&format!("best: {best} (")) && html.contains("INVALID, not ranked:"));
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!("best: {best} (")));
}
