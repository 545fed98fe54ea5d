//! Regression tests of issue 25's reliability cases that are not about glTF (`bad_gltf.rs`) or
//! output directories (`output_owner.rs`): a JUnit file that never says pass for a run that did
//! not finish, bounded inputs, preset and engine-settings values the arithmetic cannot carry.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::{with, BASE};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// `errors` and `failures` of a JUnit file's root.
fn junit_counts(path: &Path) -> (String, String) {
    let xml = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let root = doc.root_element();
    (
        root.attribute("errors").unwrap().to_string(),
        root.attribute("failures").unwrap().to_string(),
    )
}

#[cfg(unix)]
#[test]
fn a_check_killed_mid_run_leaves_a_junit_file_that_does_not_say_pass() {
    let dir = tempfile::tempdir().unwrap();
    let t = write(dir.path(), "t.toml", "[[rule]]\nmetric = \"max_aliasing\"\nmax = 1e9\n");
    let quick = write(dir.path(), "quick.toml", BASE);
    let junit = dir.path().join("junit.xml");
    let j = junit.to_str().unwrap();
    // A passing run first: the file a CI would read says pass.
    let o = bin()
        .args(["check", &quick, "--thresholds", &t, "--junit", j])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(junit_counts(&junit), ("0".to_string(), "0".to_string()));
    // A long run (300,000 frames), killed as soon as it has started.
    let slow = write(dir.path(), "slow.toml", &with(&[("motion.frames", "frames = 300000")]));
    let mut child = bin()
        .args(["check", &slow, "--thresholds", &t, "--junit", j])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while junit_counts(&junit).0 == "0" {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run never marked its JUnit file"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before the file changed"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(junit_counts(&junit).0, "1");
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.contains("has not finished"), "{xml}");
    // A run that finishes replaces the marker with its report.
    let o = bin()
        .args(["check", &quick, "--thresholds", &t, "--junit", j])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(junit_counts(&junit), ("0".to_string(), "0".to_string()));
}

#[test]
fn a_sampled_pixel_count_beyond_the_limit_is_refused_up_front_with_the_estimate() {
    use csm_lab::config::Config;
    let load = |edits: &[(&str, &str)]| {
        let mut e = vec![("scene.ground", "ground = 0.0")];
        e.extend_from_slice(edits);
        Config::from_toml_str(&with(&e), "scene.toml", None)
    };
    // The largest screen at the default scale (0.125): 131072² pixels, about 687 GB.
    let e = load(&[
        ("screen.width", "width = 1048576"),
        ("screen.height", "height = 1048576"),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("analysis.screen_scale")
            && e.contains("131072 x 131072 = 17179869184 pixels")
            && e.contains("687.2 GB"),
        "{e}"
    );
    // 16384² at scale 1: 268435456 pixels; the scale that fits is sqrt(2^25 / 2^28).
    let e = load(&[
        ("screen.width", "width = 16384"),
        ("screen.height", "height = 16384"),
        ("analysis.screen_scale", "screen_scale = 1.0"),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("268435456 pixels") && e.contains("at most 0.3535"), "{e}");
    // At the limit: 8K at scale 1 is accepted.
    load(&[
        ("screen.width", "width = 7680"),
        ("screen.height", "height = 4320"),
        ("analysis.screen_scale", "screen_scale = 1.0"),
    ])
    .unwrap();
    // Without geometry nothing is sampled, and nothing is refused.
    Config::from_toml_str(
        &with(&[
            ("screen.width", "width = 1048576"),
            ("screen.height", "height = 1048576"),
        ]),
        "scene.toml",
        None,
    )
    .unwrap();
}

#[test]
fn a_range_whose_exact_count_overflows_is_an_error_naming_the_key() {
    use csm_lab::config::sweep_spec::decimal_range;
    // 1e-39 .. 1 step 0.5: the decimal form needs 10^39, beyond an i128.
    let e = decimal_range(1e-39, 1.0, 0.5).unwrap_err();
    assert!(e.contains("decades apart"), "{e}");
    // A step beyond the span is the start alone, as before.
    assert_eq!(decimal_range(1e-39, 1.0, 1e30).unwrap(), vec![1e-39]);
    let text = format!(
        "{}\n[sweep]\nlambda = {{ start = 1e-39, end = 1.0, step = 0.5 }}\n",
        with(&[("scene.ground", "ground = 0.0")])
    );
    let e = csm_lab::config::Config::from_toml_str(&text, "scene.toml", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("sweep.lambda") && e.contains("decades apart"), "{e}");
}

#[test]
fn a_path_file_with_a_huge_first_line_is_quoted_to_200_characters() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("path.csv");
    std::fs::write(&p, format!("{}\n", "x".repeat(1_000_000))).unwrap();
    let e = csm_lab::config::read_path_file(&p).unwrap_err().to_string();
    assert!(e.len() < 600, "{} bytes", e.len());
    assert!(
        e.contains(&"x".repeat(200)) && e.contains("1000000 characters in all"),
        "{e}"
    );
    // A field too.
    std::fs::write(&p, format!("px,py,pz,tx,ty,tz\n0,0,0,0,0,{}\n", "9".repeat(400) + "z")).unwrap();
    let e = csm_lab::config::read_path_file(&p).unwrap_err().to_string();
    assert!(e.len() < 600 && e.contains("401 characters in all"), "{e}");
}
