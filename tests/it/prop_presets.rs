//! Presets and engine settings files against generated values: every engine's TOML table with
//! random keys of its own and values of every magnitude and shape, and every engine's settings
//! file (`recommendation.<engine>.txt`) with its numbers replaced. Loading gives a config or an
//! error naming a key; a loaded config analyses and renders its files without a panic and
//! without an "internal error" (a non-finite value caught at the output guard): validation
//! must refuse what the arithmetic cannot carry.

use std::panic::{catch_unwind, AssertUnwindSafe};

use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::output::Exporter;
use csm_lab::presets::PresetName;
use csm_lab::report::analyze as analyze_files;
use csm_lab::Config;
use proptest::prelude::*;

use crate::common::{with, BASE};

/// The base scene with a ground (so the screen pass runs), short (8 frames) and on a small
/// screen so that each case analyses quickly.
fn base() -> String {
    with(&[
        ("motion.frames", "frames = 8"),
        ("scene.ground", "ground = 0.0"),
        ("screen.width", "width = 96"),
        ("screen.height", "height = 54"),
    ])
}

/// Numbers of every magnitude and sign, and the values engines and arithmetic trip over.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-1e3f64..1e3),
        (0.0f64..1.0),
        (-330i32..309, any::<bool>()).prop_map(|(e, neg)| if neg { -(10f64.powi(e)) } else { 10f64.powi(e) }),
        Just(1e155),
        Just(1e308),
        Just(-1e308),
        Just(999_999_999.9),
        Just(1e-9),
        Just(5e-324),
        Just(0.0),
    ]
}

/// A TOML float (a dot or an exponent).
fn toml_num(x: f64) -> String {
    let s = format!("{x:e}");
    if s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

fn array(v: &[f64]) -> String {
    format!("[{}]", v.iter().map(|x| toml_num(*x)).collect::<Vec<_>>().join(", "))
}

/// A TOML value: a number, an array of 0 to 5 numbers, a boolean or a string.
fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => number().prop_map(toml_num),
        1 => (-5i64..70000).prop_map(|i| i.to_string()),
        2 => proptest::collection::vec(number(), 0..6).prop_map(|v| array(&v)),
        // Increasing positive lists (split planes, distances, fractions), often ending huge.
        3 => proptest::collection::vec(number(), 1..6).prop_map(|v| {
            let mut v: Vec<f64> = v.into_iter().map(f64::abs).filter(|x| *x > 0.0).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            array(&v)
        }),
        1 => any::<bool>().prop_map(|b| b.to_string()),
        1 => prop_oneof![Just("\"practical\""), Just("\"x\""), Just("\"\"")].prop_map(str::to_string),
    ]
}

/// The keys of an engine's `[name]` table, as its own "unknown field" error lists them (so
/// the fuzzer follows the tables without a copy of their fields).
fn table_keys(name: &str) -> Vec<String> {
    let text = format!(
        "{}\n[{name}]\nzzz_not_a_key = 1\n",
        base().replace("[shadow]\n", &format!("[shadow]\npreset = \"{name}\"\n"))
    );
    let e = Config::from_toml_str(&text, "scene.toml", None)
        .expect_err("an unknown key is an error")
        .to_string();
    let list = e.split("expected").nth(1).unwrap_or_else(|| panic!("{name}: {e}"));
    list.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// Analyses a loaded config and renders analyze's files: the first panic or internal error.
fn analyses_cleanly(c: &Config) -> Result<(), String> {
    let r = catch_unwind(AssertUnwindSafe(|| {
        let a = analyze(c, &AnalysisOptions::full());
        let exporters: [&dyn Exporter<_>; 3] = [
            &analyze_files::CascadesCsv,
            &analyze_files::ShimmerCsv,
            &analyze_files::SummaryJson,
        ];
        for e in exporters {
            e.render(&a).map_err(|err| format!("{}: {err}", e.file_name()))?;
        }
        Ok::<(), String>(())
    }));
    match r {
        Err(_) => Err("the analysis panicked".to_string()),
        Ok(r) => r,
    }
}

/// Loading `load` (a panic is a failure) and, when it gives a config, analysing it.
fn check(load: impl FnOnce() -> Result<Config, csm_lab::Error>) -> Result<(), String> {
    match catch_unwind(AssertUnwindSafe(load)) {
        Err(_) => Err("loading panicked".to_string()),
        Ok(Err(e)) => {
            let m = e.to_string();
            if m.is_empty() || m.contains("internal error") {
                Err(format!("a bad error: {m:?}"))
            } else {
                Ok(())
            }
        }
        Ok(Ok(c)) => analyses_cleanly(&c),
    }
}

/// The engine settings files `compare --defaults` writes for the default scene, one per engine.
fn settings_file(p: PresetName) -> String {
    let path = format!(
        "{}/tests/golden/sweep_compare_stress/compare_default_defaults/out/recommendation.{p}.txt",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// `text` with its `k`-th number (in the file's settings lines, not its comments) replaced.
fn replace_number(text: &str, k: usize, with: &str) -> String {
    let mut out = String::new();
    let mut seen = 0;
    for line in text.split_inclusive('\n') {
        let t = line.trim_start();
        if t.starts_with('#') || t.starts_with("//") {
            out.push_str(line);
            continue;
        }
        let b = line.as_bytes();
        let mut i = 0;
        while i < b.len() {
            let starts = (b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit)))
                && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
            if starts {
                let mut j = i + 1;
                while j < b.len() && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E' | b'-' | b'+')) {
                    j += 1;
                }
                if seen == k {
                    out.push_str(with);
                } else {
                    out.push_str(&line[i..j]);
                }
                seen += 1;
                i = j;
            } else {
                out.push(b[i] as char);
                i += 1;
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn preset_tables_with_any_values_load_or_name_a_key_and_never_fail_inside(
        which in 0usize..PresetName::ALL.len(),
        picks in proptest::collection::vec((any::<proptest::sample::Index>(), value()), 1..4),
    ) {
        let p = PresetName::ALL[which];
        let keys = table_keys(p.as_str());
        let mut table = format!("\n[{p}]\n");
        let mut used = std::collections::BTreeSet::new();
        for (k, v) in &picks {
            let key = k.get(&keys);
            if used.insert(key.clone()) {
                table.push_str(&format!("{key} = {v}\n"));
            }
        }
        let text = base().replace("[shadow]\n", &format!("[shadow]\npreset = \"{p}\"\n")) + &table;
        let r = check(|| Config::from_toml_str(&text, "scene.toml", None));
        prop_assert!(r.is_ok(), "{}:\n{table}", r.unwrap_err());
    }

    #[test]
    fn engine_settings_files_with_any_numbers_load_or_name_a_key_and_never_fail_inside(
        which in 0usize..PresetName::ALL.len(),
        edits in proptest::collection::vec((0usize..40, number(), 0usize..4), 1..3),
    ) {
        let p = PresetName::ALL[which];
        let mut text = settings_file(p);
        for (k, x, form) in &edits {
            let v = match form {
                0 => toml_num(*x),
                1 => format!("{x}"),
                2 => format!("{}, 7.0", toml_num(*x)),
                _ => format!("{x}f"),
            };
            text = replace_number(&text, *k, &v);
        }
        let dir = tempfile::tempdir().unwrap();
        let config = dir.path().join("scene.toml");
        std::fs::write(&config, base()).unwrap();
        let settings = dir.path().join(format!("recommendation.{p}.txt"));
        std::fs::write(&settings, &text).unwrap();
        let r = check(|| csm_lab::app::load_with_engine_settings(&config, None, &settings));
        prop_assert!(r.is_ok(), "{}:\n{text}", r.unwrap_err());
    }
}

#[test]
fn the_issues_preset_and_settings_cases_are_errors_naming_their_keys() {
    let dir = tempfile::tempdir().unwrap();
    let preset = |p: &str, table: &str| {
        let text = format!(
            "{}\n[{p}]\n{table}\n",
            BASE.replace("[shadow]\n", &format!("[shadow]\npreset = \"{p}\"\n"))
        );
        Config::from_toml_str(&text, "scene.toml", None)
            .unwrap_err()
            .to_string()
    };
    let e = preset("learnopengl", "planes = [0.1, 13.4, 34.8, 1e155]");
    assert!(e.contains("learnopengl.planes") && e.contains("at most 1e9"), "{e}");
    let e = preset("eevee", "lamp_position = [1e308, 148.0, 38.4]");
    assert!(e.contains("eevee.lamp_position") && e.contains("±1e9"), "{e}");
    let e = preset("eevee", "lamp_position = [1.0, 148.0, 38.4, 4.0]");
    assert!(e.contains("eevee.lamp_position") && e.contains("exactly three"), "{e}");
    let e = preset("learnopengl", "light_position = [1.0, 2.0]");
    assert!(
        e.contains("learnopengl.light_position") && e.contains("exactly three"),
        "{e}"
    );
    let e = preset("eevee", "clip_end = 1e300");
    assert!(e.contains("eevee.clip_end"), "{e}");
    let e = preset("threejs", "lightFar = 1e300");
    assert!(e.contains("threejs.light_far") || e.contains("lightFar"), "{e}");
    // The same in an engine settings file: the file's line and the key.
    let config = dir.path().join("scene.toml");
    std::fs::write(&config, base()).unwrap();
    let settings = dir.path().join("recommendation.eevee.txt");
    let text = settings_file(PresetName::ALL.into_iter().find(|p| p.as_str() == "eevee").unwrap());
    let line = text.lines().position(|l| l.starts_with("lamp_position")).unwrap() + 1;
    let bad = text
        .lines()
        .map(|l| {
            if l.starts_with("lamp_position") {
                "lamp_position = [1e308, 148.0, 38.4]"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&settings, bad).unwrap();
    let e = csm_lab::app::load_with_engine_settings(&config, None, &settings)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("recommendation.eevee.txt:{line}:")) && e.contains("eevee.lamp_position"),
        "{e}"
    );
}
