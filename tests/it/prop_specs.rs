//! Sweep specs and thresholds files against generated input: decimal ranges over numbers of
//! every magnitude, `[sweep]` tables of any shape, and thresholds files of random rules. Never
//! a panic; a range's values are in order, within [start, end], and at most the limit; a
//! sweep table is either accepted with every value allowed or refused naming `sweep.`.

use crate::common;

use std::panic::{catch_unwind, AssertUnwindSafe};

use csm_lab::commands::check::thresholds::Thresholds;
use csm_lab::config::sweep_spec::{decimal_range, MAX_RANGE_VALUES};
use csm_lab::Config;
use proptest::prelude::*;

/// Numbers of every magnitude, both signs, and the awkward ones.
fn any_number() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-1e3f64..1e3),
        (0.0f64..1.0),
        (-40i32..40, 1u32..1000).prop_map(|(e, m)| m as f64 * 10f64.powi(e)),
        (-330i32..310, any::<bool>()).prop_map(|(e, neg)| if neg { -(10f64.powi(e)) } else { 10f64.powi(e) }),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE),
        Just(5e-324),
        Just(0.0),
    ]
}

fn toml_num(x: f64) -> String {
    // TOML needs a dot or an exponent for a float.
    let s = format!("{x:e}");
    if s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn decimal_ranges_never_panic_and_stay_in_bounds(start in any_number(), end in any_number(), step in any_number()) {
        let r = catch_unwind(|| decimal_range(start, end, step));
        prop_assert!(r.is_ok(), "panicked on {start} {end} {step}");
        if let Ok(Ok(v)) = r {
            prop_assert!(!v.is_empty());
            prop_assert!(v.len() as u64 <= MAX_RANGE_VALUES);
            prop_assert_eq!(v[0], start);
            prop_assert!(v.iter().all(|x| x.is_finite() && *x >= start && *x <= end));
            prop_assert!(v.windows(2).all(|w| w[0] < w[1]) || v.len() == 1, "not increasing");
        }
    }

    #[test]
    fn sweep_tables_are_accepted_only_with_allowed_values(
        start in any_number(), end in any_number(), step in any_number(),
        list in proptest::collection::vec(any_number(), 0..6),
        which in 0usize..3, as_range in any::<bool>(),
    ) {
        let key = ["lambda", "cascades", "resolution"][which];
        let value = if as_range {
            format!("{{ start = {}, end = {}, step = {} }}", toml_num(start), toml_num(end), toml_num(step))
        } else {
            format!("[{}]", list.iter().map(|x| toml_num(*x)).collect::<Vec<_>>().join(", "))
        };
        let text = common::with(&[(&format!("sweep.{key}"), &format!("{key} = {value}"))]);
        let r = catch_unwind(AssertUnwindSafe(|| Config::from_toml_str(&text, "t.toml", None)));
        prop_assert!(r.is_ok(), "panicked on {key} = {value}");
        match r.unwrap() {
            Ok(c) => {
                let s = c.sweep.unwrap().axes;
                match key {
                    "lambda" => prop_assert!(s.lambda.unwrap().values.iter().all(|x| (0.0..=1.0).contains(x))),
                    "cascades" => prop_assert!(s.cascades.unwrap().values.iter().all(|x| (1..=16).contains(x))),
                    _ => prop_assert!(s.resolution.unwrap().values.iter().all(|x| (16..=16384).contains(x))),
                }
            }
            Err(e) => {
                let m = e.to_string();
                prop_assert!(m.starts_with("t.toml:"), "{m}");
                prop_assert!(!m.contains("internal error") && !m.contains("RawAxis"), "{m}");
            }
        }
    }

    #[test]
    fn thresholds_files_of_random_rules_never_panic(
        rules in proptest::collection::vec(
            (0usize..6, any_number(), proptest::option::of(-2i64..20), proptest::option::of((any_number(), any_number()))),
            0..30,
        ),
    ) {
        let metrics = ["max_aliasing", "mean_aliasing", "texel_size", "aliasing", "coverage_violations", "nonsense"];
        let mut text = String::new();
        for (m, bound, cascade, depth) in &rules {
            text.push_str(&format!("[[rule]]\nmetric = \"{}\"\nmax = {}\n", metrics[*m], toml_num(*bound)));
            if let Some(c) = cascade {
                text.push_str(&format!("cascade = {c}\n"));
            }
            if let Some((lo, hi)) = depth {
                text.push_str(&format!("depth = [{}, {}]\n", toml_num(*lo), toml_num(*hi)));
            }
        }
        let r = catch_unwind(|| Thresholds::from_toml_str(&text, "t.toml"));
        prop_assert!(r.is_ok(), "panicked on\n{text}");
        if let Ok(Err(e)) = r {
            let m = e.to_string();
            prop_assert!(m.starts_with("t.toml"), "{m}");
        }
    }
}
