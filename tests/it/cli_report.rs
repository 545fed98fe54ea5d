//! The reports as a reader meets them: the verdict first, alternatives and rivals, numbers for
//! people, and a bounded page at any grid size.

use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn config(name: &str) -> String {
    format!("{}/configs/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str], out: &Path) -> Output {
    let o = bin().args(args).arg("--out").arg(out).output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The text of a page without its inline figures (their markup is the figures' business).
fn without_svg(html: &str) -> String {
    let mut out = String::new();
    let mut rest = html;
    while let Some(i) = rest.find("<svg") {
        out.push_str(&rest[..i]);
        match rest[i..].find("</svg>") {
            Some(j) => rest = &rest[i + j + 6..],
            None => {
                rest = "";
            }
        }
    }
    out.push_str(rest);
    // Embedded PNGs are base64, not numbers.
    out.split("base64,")
        .enumerate()
        .map(|(k, part)| {
            if k == 0 {
                part
            } else {
                part.split_once('"').map_or("", |x| x.1)
            }
        })
        .collect::<Vec<_>>()
        .join("")
}

/// Numbers printed like a float dump: an exponent of 0 or -10..-19 / 10..19, a "+" exponent,
/// or "0.00e".
fn float_dumps(text: &str) -> Vec<String> {
    let b = text.as_bytes();
    let mut found = Vec::new();
    for i in 1..b.len() {
        if (b[i] == b'e' || b[i] == b'E') && b[i - 1].is_ascii_digit() {
            // The number's start: digits and one point before the 'e', not inside a word.
            let mut s = i;
            while s > 0 && (b[s - 1].is_ascii_digit() || b[s - 1] == b'.') {
                s -= 1;
            }
            if s > 0 && (b[s - 1].is_ascii_alphabetic() || b[s - 1] == b'_' || b[s - 1] == b'#') {
                continue;
            }
            let mut j = i + 1;
            let plus = j < b.len() && b[j] == b'+';
            if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
                j += 1;
            }
            let d0 = j;
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            if j == d0 || (j < b.len() && b[j].is_ascii_alphabetic()) {
                continue;
            }
            let exp: u32 = text[d0..j].parse().unwrap_or(0);
            if plus || exp == 0 || (10..20).contains(&exp) || text[s..i].starts_with("0.00") {
                found.push(text[s..j].to_string());
            }
        }
    }
    found
}

/// Singular counts followed by a plural noun ("1 cascades").
fn bad_plurals(text: &str) -> Vec<String> {
    [
        "cascades",
        "configurations",
        "resolutions",
        "fits",
        "corners",
        "violations",
        "values",
        "counts",
    ]
    .iter()
    .flat_map(|w| {
        let pat = format!(" 1 {w}");
        let starts = text.match_indices(&pat).map(|(i, _)| i).collect::<Vec<_>>();
        starts
            .into_iter()
            .filter(|&i| !text[..i].ends_with(|c: char| c.is_ascii_digit() || c == '.'))
            .map(move |_| pat.trim().to_string())
    })
    .collect()
}

#[test]
fn the_float_dump_and_plural_detectors_catch_what_they_should() {
    assert_eq!(
        float_dumps("x 0.00e0 y 5.24e-14 z 1e+5 ok 2.5e-5 1e-9 1e-3 te0 #e0e0e0"),
        vec!["0.00e0", "5.24e-14", "1e+5"]
    );
    assert_eq!(
        bad_plurals("has 1 cascades and 11 cascades, 1 cascade"),
        vec!["1 cascades"]
    );
}

#[test]
fn a_32000_configuration_sweep_writes_a_report_html_under_1_mib_that_opens_with_the_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big");
    run(
        &["sweep", &config("default.toml"), "--quiet", "--lambda", "0:1:0.001"],
        &out,
    );
    let csv = read(&out.join("sweep.csv"));
    assert_eq!(csv.lines().count(), 1 + 1001 * 8 * 4);
    let size = std::fs::metadata(out.join("report.html")).unwrap().len();
    assert!(size < 1024 * 1024, "report.html is {size} bytes");
    let html = read(&out.join("report.html"));
    // The first section is the verdict, then the alternatives and the rivals, before the scene.
    let pos = |s: &str| html.find(s).unwrap_or_else(|| panic!("{s} missing"));
    let first_h2 = html.find("<h2>").unwrap();
    assert_eq!(first_h2, pos("<h2>Verdict</h2>"));
    assert!(pos("<h2>Verdict</h2>") < pos("<h2>Alternatives</h2>"));
    assert!(pos("<h2>Alternatives</h2>") < pos("<h2>Why the main rivals lost</h2>"));
    assert!(pos("<h2>Why the main rivals lost</h2>") < pos("<h2>Scene</h2>"));
    // The full table is linked, not inlined.
    assert!(html.contains("<a href=\"sweep.csv\">sweep.csv</a>"));
    assert!(html.matches("<tr").count() < 100);
}

#[test]
fn no_report_prints_float_dumps_or_a_singular_with_a_plural() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut texts: Vec<(String, String)> = Vec::new();
    let mut add = |name: &str, text: String| texts.push((name.to_string(), text));
    let o = run(&["sweep", &config("default.toml"), "--quiet"], &d.join("s"));
    add("sweep stdout", String::from_utf8_lossy(&o.stdout).into_owned());
    add("report.html", without_svg(&read(&d.join("s/report.html"))));
    add("report.md", read(&d.join("s/report.md")));
    // One cascade count, one resolution, one fit: every count is 1.
    let o = run(
        &[
            "sweep",
            &config("default.toml"),
            "--quiet",
            "--cascades",
            "1",
            "--resolution",
            "1024",
            "--lambda",
            "0.5",
            "--no-plots",
        ],
        &d.join("one"),
    );
    add(
        "one-point sweep stdout",
        String::from_utf8_lossy(&o.stdout).into_owned(),
    );
    add("one-point report.html", read(&d.join("one/report.html")));
    add("one-point report.md", read(&d.join("one/report.md")));
    // A sweep where nothing qualifies that still runs: with 8 frames the path is too short for
    // the check that stops a sweep whose first frames prove it (reliability.rs tests that).
    let short = d.join("indoor8.toml");
    std::fs::write(
        &short,
        read(Path::new(&config("indoor.toml"))).replace("frames = 180", "frames = 8"),
    )
    .unwrap();
    let o = run(
        &[
            "sweep",
            short.to_str().unwrap(),
            "--quiet",
            "--fit",
            "aabb",
            "--no-plots",
        ],
        &d.join("none"),
    );
    add("failing sweep stdout", String::from_utf8_lossy(&o.stdout).into_owned());
    add("failing report.md", read(&d.join("none/report.md")));
    let o = run(&["compare", &config("default.toml")], &d.join("c"));
    add("compare stdout", String::from_utf8_lossy(&o.stdout).into_owned());
    add("compare.html", without_svg(&read(&d.join("c/compare.html"))));
    add("compare.md", read(&d.join("c/compare.md")));
    let o = run(&["analyze", &config("default.toml")], &d.join("a"));
    add("analyze stdout", String::from_utf8_lossy(&o.stdout).into_owned());
    for (name, text) in &texts {
        assert!(float_dumps(text).is_empty(), "{name}: {:?}", float_dumps(text));
        assert!(bad_plurals(text).is_empty(), "{name}: {:?}", bad_plurals(text));
    }
    // The one-point sweep says "1 cascade", not "1 cascades".
    assert!(texts[4].1.contains("1 cascade of 1024² texels"), "{}", texts[4].1);
}

#[test]
fn the_report_defines_every_column_of_its_tables_from_the_metric_registry() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    run(&["sweep", &config("default.toml"), "--quiet", "--no-plots"], &out);
    let html = read(&out.join("report.html"));
    let table = &html[html.find("<h2>Top configurations</h2>").unwrap()..];
    let header_row = &table[table.find("<tr>").unwrap()..table.find("</tr>").unwrap()];
    let dl = &table[table.find("<dl class=\"defs\">").unwrap()..table.find("</dl>").unwrap()];
    for th in header_row.split("<th").skip(1) {
        let label = th.split_once('>').unwrap().1.split_once("</th").unwrap().0;
        assert!(dl.contains(&format!("<dt>{label}</dt>")), "{label} is not defined");
    }
    // The registry's own words.
    assert!(dl.contains("aliasing ratio averaged over view depth"));
    assert!(dl.contains("slice corners outside their window"));
}

#[test]
fn recommendation_json_lists_alternatives_that_keep_their_promise_and_rivals_with_a_reason() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    run(&["sweep", &config("default.toml"), "--quiet", "--no-plots"], &out);
    let v: serde_json::Value = serde_json::from_str(&read(&out.join("recommendation.json"))).unwrap();
    let rec = &v["recommended"];
    let objective = v["objective_metric"].as_str().unwrap();
    let alts = v["alternatives"].as_array().unwrap();
    assert!(!alts.is_empty());
    for a in alts {
        let x = &a["configuration"];
        let mem = |r: &serde_json::Value| r["memory_bytes"].as_f64().unwrap();
        let obj = |r: &serde_json::Value| r[objective].as_f64().unwrap();
        match a["kind"].as_str().unwrap() {
            "cheaper" => assert!(mem(x) < mem(rec) && a["memory_change_percent"].as_f64().unwrap() < 0.0),
            "sharper" => assert!(obj(x) < obj(rec) * 0.99 && a["objective_change_percent"].as_f64().unwrap() < -1.0),
            "more_stable" => assert!(x["shimmer"].as_f64().unwrap() < rec["shimmer"].as_f64().unwrap()),
            k => panic!("unknown kind {k}"),
        }
        assert!(a["rule"].as_str().unwrap().len() > 20);
        assert_eq!(x["coverage_violations"], 0);
    }
    let rivals = v["rivals"].as_array().unwrap();
    assert!(!rivals.is_empty());
    for r in rivals {
        assert!(r["why"].as_str().unwrap().contains(" lost on ") || r["why"].as_str().unwrap().contains("tied on"));
        assert!(!r["lost_on"].as_str().unwrap().is_empty());
    }
}

#[test]
fn compare_marks_presets_that_miss_slice_corners_as_invalid() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let o = run(
        &["compare", &config("default.toml"), "--presets", "learnopengl,bevy"],
        &out,
    );
    let csv = read(&out.join("compare.csv"));
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "coverage_violations").unwrap();
    let md = read(&out.join("compare.md"));
    let html = read(&out.join("compare.html"));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let mut invalid = 0;
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let misses: u64 = f[col].parse().unwrap();
        let marked = format!("{} (INVALID: {misses} slice corner", f[0]);
        if misses > 0 {
            invalid += 1;
            assert!(md.contains(&marked), "{marked} not in compare.md");
            assert!(html.contains(&marked), "{marked} not in compare.html");
            assert!(stdout.lines().any(|l| l.starts_with(f[0]) && l.contains("INVALID")));
        } else {
            assert!(!md.contains(&format!("{} (INVALID: {misses}", f[0])));
        }
    }
    assert!(
        invalid > 0,
        "learnopengl was expected to miss slice corners on the default scene"
    );
}
