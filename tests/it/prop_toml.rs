//! The config loader against generated TOML: key/value soup with random tables, keys, values
//! and syntax errors, and mutations of a valid config (deleted and inserted characters,
//! swapped values, wrong types, huge numbers, nan/inf, duplicated lines, truncation). It must
//! never panic, and must always give a config or an error with a non-empty message; a TOML
//! syntax error carries the line and column where the parser stopped.

use crate::common;

use std::panic::{catch_unwind, AssertUnwindSafe};

use csm_lab::error::ConfigError;
use csm_lab::{Config, Error};
use proptest::prelude::*;

const TABLES: [&str; 8] = [
    "camera", "screen", "light", "scene", "shadow", "motion", "analysis", "extra",
];

const KEYS: [&str; 28] = [
    "position",
    "target",
    "up",
    "fov_y_deg",
    "near",
    "far",
    "width",
    "height",
    "direction",
    "min",
    "max",
    "max_distance",
    "cascades",
    "lambda",
    "resolution",
    "fit",
    "snap",
    "fit_depth_to_scene",
    "path",
    "frames",
    "step",
    "file",
    "density_samples",
    "probes",
    "colour",
    "\"quoted key\"",
    "a.b",
    "",
];

/// Values of every TOML type, the extremes, and malformed ones.
fn value() -> impl Strategy<Value = String> {
    let scalar = prop_oneof![
        any::<i64>().prop_map(|i| i.to_string()),
        (-20i64..20000).prop_map(|i| i.to_string()),
        any::<f64>().prop_map(|f| format!("{f:?}")),
        (-1e3f64..1e3).prop_map(|f| format!("{f:?}")),
        prop_oneof![
            Just("nan"),
            Just("+nan"),
            Just("-nan"),
            Just("inf"),
            Just("+inf"),
            Just("-inf"),
            Just("1e308"),
            Just("1e400"),
            Just("-1e400"),
            Just("1e-400"),
            Just("-0.0"),
            Just("0x10"),
            Just("0o7"),
            Just("0b101"),
            Just("1_000"),
            Just("9223372036854775808"),
            Just("-9223372036854775809"),
            Just("1979-05-27T07:32:00Z"),
            Just("07:32:00"),
            Just("true"),
            Just("false"),
            Just("\"sphere\""),
            Just("\"aabb\""),
            Just("\"strafe\""),
            Just("\"yaw\""),
            Just("\"file\""),
            Just("'literal'"),
            Just("\"\"\"multi\nline\"\"\""),
            Just("{ x = 1 }"),
            Just("{}"),
            Just("[]"),
        ]
        .prop_map(str::to_string),
        "[a-z_ ]{0,8}".prop_map(|s| format!("\"{s}\"")),
        // Malformed.
        prop_oneof![
            Just("1..2"),
            Just("\"unterminated"),
            Just("[1, 2"),
            Just("{ x = "),
            Just("=="),
            Just("tru"),
            Just("1e"),
            Just("--1"),
            Just(".5"),
            Just("5."),
        ]
        .prop_map(str::to_string),
    ];
    (scalar.clone(), proptest::collection::vec(scalar, 0..5), 0u8..8).prop_map(|(s, items, k)| match k {
        0 => format!("[{}]", items.join(", ")),
        1 => format!("[{}", items.join(", ")),
        _ => s,
    })
}

/// One line of soup.
fn line() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => (prop::sample::select(&TABLES[..]), 0u8..6).prop_map(|(t, k)| match k {
            0 => format!("[[{t}]]"),
            1 => format!("[{t}"),
            2 => format!("[{t}.sub]"),
            _ => format!("[{t}]"),
        }),
        8 => (prop::sample::select(&KEYS[..]), value(), 0u8..8).prop_map(|(k, v, s)| match s {
            0 => format!("{k} {v}"),
            1 => format!("{k}={v} # comment"),
            _ => format!("{k} = {v}"),
        }),
        1 => "[ -~]{0,20}",
        1 => Just(String::new()),
        1 => Just("# comment".to_string()),
    ]
}

fn soup() -> impl Strategy<Value = String> {
    proptest::collection::vec(line(), 0..40).prop_map(|lines| lines.join("\n"))
}

/// One edit of a text.
#[derive(Debug, Clone)]
struct Edit {
    kind: u8,
    at: usize,
    len: usize,
    /// Any value, of any type, possibly malformed.
    payload: String,
    other: usize,
    /// Numbers for a replacement of the same type.
    numbers: [f64; 3],
    int: i64,
}

/// A float as TOML writes it: extremes, signed zero, nan and infinities included.
fn toml_float(f: f64) -> String {
    if f.is_nan() {
        "nan".into()
    } else if f.is_infinite() {
        if f > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else {
        format!("{f:?}")
    }
}

fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3f64..1e3,
        1 => any::<f64>(),
        1 => prop::sample::select(&[0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, f64::MAX, f64::MIN_POSITIVE, f64::NAN, f64::INFINITY, f64::NEG_INFINITY][..]),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    (
        prop::sample::select(&[0u8, 0, 1, 1, 2, 2, 3, 3, 5, 6, 7, 7, 7, 7, 7][..]),
        any::<usize>(),
        1usize..6,
        value(),
        any::<usize>(),
        (number(), number(), number()),
        prop_oneof![-5i64..20000, any::<i64>()],
    )
        .prop_map(|(kind, at, len, payload, other, n, int)| Edit {
            kind,
            at,
            len,
            payload,
            other,
            numbers: [n.0, n.1, n.2],
            int,
        })
}

/// A value of the same TOML type as `old`, with new contents.
fn same_type(old: &str, e: &Edit) -> String {
    const WORDS: [&str; 10] = [
        "sphere", "aabb", "strafe", "dolly", "yaw", "pitch", "orbit", "file", "box", "",
    ];
    let old = old.trim();
    if old.starts_with('[') {
        format!(
            "[{}, {}, {}]",
            toml_float(e.numbers[0]),
            toml_float(e.numbers[1]),
            toml_float(e.numbers[2])
        )
    } else if old.starts_with('"') {
        format!("\"{}\"", WORDS[e.other % WORDS.len()])
    } else if old == "true" || old == "false" {
        (old == "false").to_string()
    } else if old.contains('.') {
        toml_float(e.numbers[0])
    } else {
        e.int.to_string()
    }
}

fn char_boundary(text: &str, at: usize) -> usize {
    let mut i = at % (text.len() + 1);
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, e: &Edit) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let value_lines: Vec<usize> = (0..lines.len()).filter(|&i| lines[i].contains(" = ")).collect();
    match e.kind {
        // Delete characters.
        0 => {
            let a = char_boundary(text, e.at);
            let b = char_boundary(text, a + e.len);
            format!("{}{}", &text[..a], &text[b.max(a)..])
        }
        // Insert a value or punctuation somewhere.
        1 => {
            let a = char_boundary(text, e.at);
            let p = if e.other % 2 == 0 {
                e.payload.as_str()
            } else {
                ["=", "[", "]", "\"", "\n", ",", "#"][e.other % 7]
            };
            format!("{}{}{}", &text[..a], p, &text[a..])
        }
        // Swap the values of two keys.
        2 if value_lines.len() >= 2 => {
            let i = value_lines[e.at % value_lines.len()];
            let j = value_lines[e.other % value_lines.len()];
            let (ki, vi) = lines[i].split_once(" = ").unwrap();
            let (kj, vj) = lines[j].split_once(" = ").unwrap();
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            out[i] = format!("{ki} = {vj}");
            out[j] = format!("{kj} = {vi}");
            out.join("\n")
        }
        // Replace a value (wrong types, huge numbers, nan/inf, malformed).
        3 | 4 if !value_lines.is_empty() => {
            let i = value_lines[e.at % value_lines.len()];
            let (k, _) = lines[i].split_once(" = ").unwrap();
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            out[i] = format!("{k} = {}", e.payload);
            out.join("\n")
        }
        // Replace a value by one of the same type: out of range, huge, nan, another word.
        7 if !value_lines.is_empty() => {
            let i = value_lines[e.at % value_lines.len()];
            let (k, v) = lines[i].split_once(" = ").unwrap();
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            out[i] = format!("{k} = {}", same_type(v, e));
            out.join("\n")
        }
        // Duplicate a line.
        5 if !lines.is_empty() => {
            let i = e.at % lines.len();
            let mut out: Vec<&str> = lines.clone();
            out.insert(e.other % (lines.len() + 1), lines[i]);
            out.join("\n")
        }
        // Truncate.
        _ => text[..char_boundary(text, e.at)].to_string(),
    }
}

fn mutated() -> impl Strategy<Value = String> {
    proptest::collection::vec(edit(), 1..3)
        .prop_map(|edits| edits.iter().fold(common::BASE.to_string(), |text, e| apply(&text, e)))
}

/// The loader's contract on any text; returns what is wrong, if anything.
fn check(text: &str) -> Result<(), String> {
    let loaded = catch_unwind(AssertUnwindSafe(|| Config::from_toml_str(text, "gen.toml", None)))
        .map_err(|_| "the loader panicked".to_string())?;
    // Independent oracle for syntax: parse into a plain table.
    let syntax = toml::from_str::<toml::Table>(text).err();
    match loaded {
        Ok(c) => {
            // (The loader may accept what a plain table parse rejects: `step =
            // 9223372036854775808` is read as a float. That is the toml crate's leniency.)
            let finite = [
                c.camera.fov_y_deg,
                c.camera.near,
                c.camera.far,
                c.shadow.lambda,
                c.motion.step,
            ]
            .iter()
            .all(|v| v.is_finite())
                && c.light_direction.is_finite()
                && (c.light_direction.length() - 1.0).abs() < 1e-12;
            if !finite || c.camera.near <= 0.0 || c.camera.far <= c.camera.near {
                return Err(format!("accepted an invalid config: {c:?}"));
            }
            // Small enough to analyse here: the analysis must not panic either.
            if c.motion.frames <= 400 && c.analysis.probes <= 2048 && c.analysis.density_samples <= 20_000 {
                let a = catch_unwind(AssertUnwindSafe(|| {
                    csm_lab::analyze(&c, &csm_lab::AnalysisOptions::full())
                }))
                .map_err(|_| "the analysis panicked".to_string())?;
                let s = &a.summary;
                if ![s.max_aliasing, s.mean_aliasing, s.shimmer_unsnapped, s.z_hi]
                    .iter()
                    .all(|v| v.is_finite())
                {
                    return Err(format!("non-finite summary {s:?}"));
                }
            }
            Ok(())
        }
        Err(e) => {
            let shown = e.to_string();
            if shown.trim().is_empty() {
                return Err("empty error message".into());
            }
            match (&e, syntax) {
                (
                    Error::Config(ConfigError::Toml {
                        line, column, message, ..
                    }),
                    _,
                ) => {
                    // A real place in the text: an existing line, a column at most one past
                    // its end. (With several problems the loader may report any one of them,
                    // a type error before a syntax error further up, for instance.)
                    let width = text.split('\n').nth(line.wrapping_sub(1)).map(|l| l.chars().count());
                    if message.trim().is_empty() || *column < 1 || !matches!(width, Some(w) if *column <= w + 1) {
                        return Err(format!("bad location or message: {shown}"));
                    }
                    if !shown.starts_with(&format!("gen.toml:{line}:{column}: ")) {
                        return Err(format!("no line:column prefix: {shown}"));
                    }
                    Ok(())
                }
                // Text a plain parse rejects but the loader read (a too-large integer as a
                // float) and then refused: the refusal still says where.
                (Error::Config(ConfigError::Invalid { location, .. }), Some(se)) => {
                    if location.starts_with("gen.toml:") && location.matches(':').count() == 3 {
                        Ok(())
                    } else {
                        Err(format!("a syntax error ({se}) reported without line:column: {shown}"))
                    }
                }
                (_, Some(se)) => Err(format!("a syntax error ({se}) reported as {shown}")),
                (Error::Config(ConfigError::Invalid { key, .. }), None) if key.is_empty() => {
                    Err(format!("no key named: {shown}"))
                }
                _ => Ok(()),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, .. ProptestConfig::default() })]

    #[test]
    fn generated_key_value_soup_never_panics_and_errors_say_where(text in soup()) {
        if let Err(why) = check(&text) {
            prop_assert!(false, "{}\n---\n{}", why, text);
        }
    }

    #[test]
    fn mutated_valid_configs_never_panic_and_errors_say_where(text in mutated()) {
        if let Err(why) = check(&text) {
            prop_assert!(false, "{}\n---\n{}", why, text);
        }
    }
}

/// The generators reach every outcome: valid configs, syntax errors and validation errors.
#[test]
fn mutations_produce_valid_configs_syntax_errors_and_validation_errors() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let (mut ok, mut syntax, mut invalid) = (0, 0, 0);
    for _ in 0..600 {
        let text = mutated().new_tree(&mut runner).unwrap().current();
        match Config::from_toml_str(&text, "gen.toml", None) {
            Ok(_) => ok += 1,
            Err(Error::Config(ConfigError::Toml { .. })) => syntax += 1,
            Err(Error::Config(ConfigError::Invalid { .. })) => invalid += 1,
            Err(_) => {}
        }
    }
    assert!(
        ok > 60 && syntax > 100 && invalid > 60,
        "ok {ok}, toml {syntax}, invalid {invalid}"
    );
}
