//! The `sweep` command as a user runs it.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::read_csv;
use common::BASE;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

/// A small but real grid: 3 λ × 3 counts × 2 resolutions × 2 fits = 36 configurations.
fn small_config(dir: &Path) -> PathBuf {
    let text = format!(
        "{BASE}\n[sweep]\nlambda = {{ start = 0.5, end = 1.0, step = 0.25 }}\ncascades = [1, 3, 4]\nresolution = [512, 2048]\nfit = [\"sphere\", \"aabb\"]\nmemory_budget_mib = 32\n"
    );
    let p = dir.join("small.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn sweep(cfg: &Path, out: &Path, extra: &[&str]) -> Output {
    bin()
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ])
        .args(extra)
        .output()
        .unwrap()
}

const FILES: [&str; 12] = [
    "sweep.csv",
    "recommendation.json",
    "heatmap.svg",
    "heatmap.png",
    "density_lambda.svg",
    "density_lambda.png",
    "shimmer_sweep.svg",
    "shimmer_sweep.png",
    "pareto.svg",
    "pareto.png",
    "report.html",
    "report.md",
];

#[test]
fn sweep_output_is_byte_identical_at_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let a = sweep(&cfg, &dir.path().join("t1"), &["--threads", "1"]);
    let b = sweep(&cfg, &dir.path().join("t2"), &["--threads", "2"]);
    assert_eq!(a.status.code(), Some(0), "{}", String::from_utf8_lossy(&a.stderr));
    assert_eq!(b.status.code(), Some(0));
    for f in FILES {
        let x = std::fs::read(dir.path().join("t1").join(f)).unwrap();
        let y = std::fs::read(dir.path().join("t2").join(f)).unwrap();
        assert!(x == y, "{f} differs between 1 and 2 threads");
    }
}

#[test]
fn every_sweep_row_equals_what_analyze_reports_for_that_setting() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let out = dir.path().join("o");
    assert_eq!(sweep(&cfg, &out, &[]).status.code(), Some(0));
    let (header, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(
        header[..16].join(","),
        "lambda,cascades,resolution,fit,z_lo,z_hi,max_aliasing,mean_aliasing,mean_log_aliasing,undersampled_fraction,shimmer,shimmer_snapped,shimmer_unsnapped,size_jitter,coverage_violations,memory_bytes"
    );
    assert_eq!(rows.len(), 36);
    let base = csm_lab::Config::load(&cfg).unwrap();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for row in &rows {
        let mut c = base.clone();
        c.shadow.lambda = row[0].parse().unwrap();
        c.shadow.cascades = row[1].parse().unwrap();
        c.shadow.resolution = row[2].parse().unwrap();
        c.shadow.fit = if row[3] == "sphere" {
            csm_lab::config::Fit::Sphere
        } else {
            csm_lab::config::Fit::Aabb
        };
        let a = csm_lab::analyze(&c, &csm_lab::AnalysisOptions::full());
        let s = &a.summary;
        for (name, v) in [
            ("z_lo", s.z_lo),
            ("z_hi", s.z_hi),
            ("max_aliasing", s.max_aliasing),
            ("mean_aliasing", s.mean_aliasing),
            ("mean_log_aliasing", s.mean_log_aliasing),
            ("undersampled_fraction", s.undersampled_fraction),
            ("shimmer_snapped", s.shimmer_snapped),
            ("shimmer_unsnapped", s.shimmer_unsnapped),
            ("size_jitter", s.size_jitter),
        ] {
            assert_eq!(row[col(name)].parse::<f64>().unwrap(), v, "{name} in {row:?}");
        }
        assert_eq!(row[col("coverage_violations")], s.coverage_violations.to_string());
        assert_eq!(row[col("memory_bytes")], s.memory_bytes.to_string());
        assert_eq!(
            s.memory_bytes,
            c.shadow.cascades as u64 * (c.shadow.resolution as u64).pow(2) * 4
        );
    }
    // And through the binary for one row: analyze's summary.json has the same numbers.
    let mut text = std::fs::read_to_string(&cfg).unwrap();
    text = text
        .replace("cascades = 4\n", "cascades = 3\n")
        .replace("resolution = 2048\n", "resolution = 512\n");
    text = text
        .replace("lambda = 0.75\n", "lambda = 0.5\n")
        .replace("fit = \"sphere\"\n", "fit = \"aabb\"\n");
    let single = dir.path().join("single.toml");
    std::fs::write(&single, text).unwrap();
    let o = bin()
        .args(["analyze", single.to_str().unwrap(), "--format", "json", "--out"])
        .arg(dir.path().join("a"))
        .output()
        .unwrap();
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let row = rows
        .iter()
        .find(|r| r[0] == "0.5" && r[1] == "3" && r[2] == "512" && r[3] == "aabb")
        .unwrap();
    for name in [
        "max_aliasing",
        "mean_aliasing",
        "shimmer_snapped",
        "shimmer_unsnapped",
        "size_jitter",
    ] {
        assert_eq!(
            json[name].as_f64().unwrap(),
            row[col(name)].parse::<f64>().unwrap(),
            "{name}"
        );
    }
}

#[test]
fn pareto_rows_are_non_dominated_and_the_recommendation_fits_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let out = dir.path().join("o");
    assert_eq!(sweep(&cfg, &out, &[]).status.code(), Some(0));
    let (header, rows) = read_csv(&out.join("sweep.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let mem = |r: &Vec<String>| r[col("memory_bytes")].parse::<u64>().unwrap();
    let mean = |r: &Vec<String>| r[col("mean_aliasing")].parse::<f64>().unwrap();
    let front: Vec<&Vec<String>> = rows.iter().filter(|r| r[col("pareto")] == "true").collect();
    assert!(!front.is_empty());
    for f in &front {
        assert!(!rows
            .iter()
            .any(|r| mem(r) <= mem(f) && mean(r) <= mean(f) && (mem(r) < mem(f) || mean(r) < mean(f))));
    }
    let rec: Vec<&Vec<String>> = rows.iter().filter(|r| r[col("recommended")] == "true").collect();
    assert_eq!(rec.len(), 1);
    assert!(mem(rec[0]) <= 32 * 1024 * 1024);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("recommendation.json")).unwrap()).unwrap();
    assert_eq!(json["within_budget"], serde_json::Value::Bool(true));
    assert_eq!(json["recommended"]["mean_aliasing"].as_f64().unwrap(), mean(rec[0]));
    // The recommendation is within 1% of the lowest mean aliasing of the acceptable rows within
    // the budget, and none of those near-ties has a lower max aliasing.
    let max = |r: &Vec<String>| r[col("max_aliasing")].parse::<f64>().unwrap();
    let ok: Vec<&Vec<String>> = rows
        .iter()
        .filter(|r| {
            mem(r) <= 32 * 1024 * 1024
                && r[col("coverage_violations")] == "0"
                && r[col("shimmer_snapped")].parse::<f64>().unwrap() <= 1e-3
        })
        .collect();
    let best = ok.iter().map(|r| mean(r)).fold(f64::INFINITY, f64::min);
    assert!(mean(rec[0]) <= best * 1.01);
    for r in ok.iter().filter(|r| mean(r) <= best * 1.01) {
        assert!(max(r) >= max(rec[0]), "{r:?} is a near-tie with a lower worst case");
    }
}

#[test]
fn figures_parse_and_the_report_is_self_contained() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let out = dir.path().join("o");
    let o = sweep(&cfg, &out, &[]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("recommended"));
    for f in FILES {
        let bytes = std::fs::read(out.join(f)).unwrap();
        if f.ends_with(".svg") {
            roxmltree::Document::parse(std::str::from_utf8(&bytes).unwrap()).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
        if f.ends_with(".png") {
            let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
            let mut reader = decoder.read_info().unwrap_or_else(|e| panic!("{f}: {e}"));
            let mut buf = vec![0; reader.output_buffer_size()];
            let info = reader.next_frame(&mut buf).unwrap();
            assert!(info.width >= 800 && info.height >= 400, "{f}");
            // Not blank: some pixels are far from white.
            assert!(
                buf.chunks(3).filter(|p| p.iter().all(|&c| c < 128)).count() > 1000,
                "{f} looks blank"
            );
        }
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let doc = roxmltree::Document::parse_with_options(
        &html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("report.html is well-formed");
    assert_eq!(doc.root_element().tag_name().name(), "html");
    assert_eq!(
        doc.descendants().filter(|n| n.tag_name().name() == "svg").count(),
        4,
        "four inline figures"
    );
    for n in doc.descendants() {
        for a in n.attributes() {
            if a.name() == "xmlns" || a.namespace().is_some() {
                continue;
            }
            let v = a.value();
            // Nothing is fetched (src); a link may point at a file the sweep wrote beside the
            // page (the full table, sweep.csv).
            assert!(
                a.name() != "src" || v.starts_with('#'),
                "external reference {}={v}",
                a.name()
            );
            assert!(
                a.name() != "href" || v.starts_with('#') || FILES.contains(&v),
                "external reference {}={v}",
                a.name()
            );
            assert!(
                !v.contains("http://") && !v.contains("https://"),
                "external reference {}={v}",
                a.name()
            );
        }
    }
    assert!(!html.contains("<link") && !html.contains("<script") && !html.contains("url("));
    assert!(
        html.contains("csm-lab sweep") && html.contains("--lambda 0.5:1:0.25"),
        "reproducing command"
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Verdict") && md.contains("![") && md.contains("csm-lab sweep"));
}

#[test]
fn command_line_axes_override_the_config_and_bad_specs_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let out = dir.path().join("o");
    let o = sweep(
        &cfg,
        &out,
        &[
            "--lambda",
            "0,1",
            "--cascades",
            "2..3",
            "--resolution",
            "1024",
            "--fit",
            "sphere",
            "--no-plots",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 4);
    assert!(!out.join("heatmap.svg").exists(), "--no-plots writes no figures");
    assert!(out.join("report.html").exists());
    for (flag, value, fragment) in [
        ("--lambda", "0:1", "start:end:step"),
        ("--lambda", "0:1:0", "step must be > 0"),
        ("--lambda", "1:0:0.1", "must be >= start"),
        ("--lambda", "0,2", "outside [0, 1]"),
        ("--cascades", "8..1", "before it starts"),
        ("--cascades", "", "not a whole number"),
        ("--resolution", "1024,x", "not a whole number"),
        ("--fit", "box", "not a fit"),
        ("--threads", "0", "0"),
    ] {
        let o = sweep(&cfg, &dir.path().join("bad"), &[flag, value]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {err}");
        assert!(err.contains(flag) && err.contains(fragment), "{flag} {value}: {err}");
        assert!(!err.contains("panicked"));
    }
    assert!(!dir.path().join("bad").exists());
}

#[test]
fn bad_sweep_tables_and_oversized_grids_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (table, fragment) in [
        ("cascades = []", "sweep.cascades"),
        ("lambda = { start = 0.0, end = 1.0, step = 0.0 }", "step must be > 0"),
        ("lambda = { start = 1.0, end = 0.0, step = 0.1 }", "must be >= start"),
        ("resolution = [1024.5]", "not a whole number"),
        ("fit = [\"box\"]", "box"),
        ("memory_budget_mib = -1", "sweep.memory_budget_mib"),
        ("colour = 3", "colour"),
    ] {
        let p = dir.path().join("bad.toml");
        std::fs::write(&p, format!("{BASE}\n[sweep]\n{table}\n")).unwrap();
        let o = sweep(&p, &dir.path().join("o"), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{table}: {err}");
        assert!(err.contains(fragment), "{table}: {err}");
    }
    let p = dir.path().join("big.toml");
    std::fs::write(&p, format!("{BASE}\n[sweep]\nmax_configs = 100\n")).unwrap();
    let o = sweep(&p, &dir.path().join("o"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        err.contains("672 configurations") && err.contains("max_configs = 100"),
        "{err}"
    );
    assert!(!dir.path().join("o").exists());
}

#[test]
fn a_failed_write_leaves_every_file_whole_and_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let out = dir.path().join("o");
    std::fs::create_dir_all(out.join("report.md")).unwrap(); // a directory where a file must go
    std::fs::write(out.join("sweep.csv"), "OLD\n").unwrap();
    let o = sweep(&cfg, &out, &["--no-plots"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("report.md"));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert!(
        csv == "OLD\n" || csv.lines().count() == 37,
        "sweep.csv is old or whole: {csv:.80}"
    );
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "temporary file left behind: {name}");
    }
    // An output path under a regular file cannot be created: exit 2, nothing written.
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "x").unwrap();
    let o = sweep(&cfg, &blocker.join("sub"), &["--no-plots"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot write"));
}

#[test]
fn a_preset_sweep_varies_only_the_axes_that_engine_has_and_each_row_equals_analyze() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    // EEVEE has a λ (its cascade exponent): λ × counts × resolutions; the fit axis of the
    // [sweep] table is dropped with a note.
    let out = dir.path().join("eevee");
    let o = bin()
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--preset",
            "eevee",
            "--resolution",
            "1024",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("note: sweep.fit"));
    let (header, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 3 * 3, "3 λ x 3 counts x 1 resolution");
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let choice = csm_lab::presets::PresetChoice {
        name: Some(csm_lab::presets::parse_flag("--preset", "eevee").unwrap()),
        ..Default::default()
    };
    let base = csm_lab::Config::load_with_preset(&cfg, &choice).unwrap();
    for row in &rows {
        assert_eq!(row[col("preset")], "eevee");
        let mut c = base.clone();
        csm_lab::presets::set_lambda(&mut c, row[col("lambda")].parse().unwrap()).unwrap();
        csm_lab::presets::set_cascades(&mut c, row[col("cascades")].parse().unwrap()).unwrap();
        csm_lab::presets::set_resolution(&mut c, row[col("resolution")].parse().unwrap()).unwrap();
        let a = csm_lab::analyze(&c, &csm_lab::AnalysisOptions::full());
        assert_eq!(
            row[col("mean_aliasing")].parse::<f64>().unwrap(),
            a.summary.mean_aliasing,
            "{row:?}"
        );
        assert_eq!(
            row[col("shimmer_unsnapped")].parse::<f64>().unwrap(),
            a.summary.shimmer_unsnapped
        );
    }
    let lambdas: std::collections::BTreeSet<String> = rows.iter().map(|r| r[col("lambda")].clone()).collect();
    assert_eq!(lambdas.len(), 3, "the engine's λ is swept");
    // Bevy has no λ and at most 4 cascades: the table's λ axis and counts above 4 are dropped.
    let out = dir.path().join("bevy");
    let o = bin()
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--preset",
            "bevy",
            "--no-plots",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, rows) = read_csv(&out.join("sweep.csv"));
    // ... and its first_cascade_far_bound (10) is swept at ¼, ½, ¾, 1, 1.5, 2 × 10.
    assert_eq!(
        rows.len(),
        3 * 2 * 6,
        "1 λ x counts {{1, 3, 4}} x 2 resolutions x 6 far bounds"
    );
    // Flags the engine cannot take are errors naming the flag.
    for (args, fragment) in [
        (vec!["--preset", "unreal", "--lambda", "0,1"], "--lambda"),
        (vec!["--preset", "bevy", "--fit", "aabb"], "--fit"),
        (vec!["--preset", "bevy", "--cascades", "6"], "--cascades"),
        (vec!["--preset", "bevy", "--resolution", "1000"], "--resolution"),
        (vec!["--preset", "nope"], "--preset"),
    ] {
        let o = bin()
            .args(["sweep", cfg.to_str().unwrap(), "--quiet", "--out"])
            .arg(dir.path().join("bad"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(fragment), "{args:?}: {err}");
    }
    assert!(!dir.path().join("bad").exists());
}

/// The recommended row of a `sweep.csv` and the distinct values of column `axis` (min, max).
fn recommended_and_extremes(csv: &Path, axis: &str) -> (f64, f64, f64) {
    let (header, rows) = read_csv(csv);
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name}: {header:?}"))
    };
    let (a, rec) = (col(axis), col("recommended"));
    let values: Vec<f64> = rows.iter().map(|r| r[a].parse().unwrap()).collect();
    let chosen = rows.iter().find(|r| r[rec] == "true").expect("a recommended row");
    (
        chosen[a].parse().unwrap(),
        values.iter().copied().fold(f64::INFINITY, f64::min),
        values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    )
}

#[test]
fn a_recommendation_at_the_edge_of_a_swept_range_is_named_with_the_range_to_try_and_trying_it_moves_inside() {
    let tmp = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // The default scene ranked by the unweighted screen p95: Bevy's first far bound then sits
    // at the largest value of its default knob axis (under the default visible_aliasing_p95 it
    // lies inside, at 15).
    let configs = tmp.path().join("configs");
    std::fs::create_dir_all(&configs).unwrap();
    for e in std::fs::read_dir(root.join("configs")).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, configs.join(p.file_name().unwrap())).unwrap();
        }
    }
    let text = std::fs::read_to_string(configs.join("default.toml")).unwrap();
    assert!(text.contains("\n[sweep]\n"));
    let text = text.replacen("\n[sweep]\n", "\n[sweep]\nobjective = \"screen_aliasing_p95\"\n", 1);
    std::fs::write(configs.join("default.toml"), text).unwrap();
    let config = configs.join("default.toml");
    let run = |out: &Path, extra: &[&str]| {
        let o = bin()
            .current_dir(root)
            .arg("sweep")
            .arg(&config)
            .args(["--preset", "bevy", "--no-plots", "--out"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        let rec: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("recommendation.json")).unwrap()).unwrap();
        (String::from_utf8_lossy(&o.stdout).to_string(), rec)
    };
    let knob = "bevy.first_cascade_far_bound";
    let first = tmp.path().join("first");
    let (stdout, rec) = run(&first, &[]);
    // From sweep.csv alone: the knob's recommended value is its largest (20 of 2.5 ... 20).
    let (chosen, lo, hi) = recommended_and_extremes(&first.join("sweep.csv"), knob);
    assert_eq!((chosen, lo, hi), (20.0, 2.5, 20.0));
    // Bevy takes at most 4 cascades and 4096² is over the budget: the knob is the only edge.
    let (c, _, c_hi) = recommended_and_extremes(&first.join("sweep.csv"), "cascades");
    assert_eq!((c, c_hi), (4.0, 4.0));
    assert_eq!(rec["range_edges"], serde_json::json!([knob]));
    assert_eq!(rec["range_edge_suggestions"][0]["try"], "--knob 20,25,30,35,40,45");
    assert!(
        stdout.contains(
            "range edge: bevy.first_cascade_far_bound 20 is the largest value swept: the best may lie beyond it; \
             try --knob 20,25,30,35,40,45"
        ),
        "{stdout}"
    );
    let md = std::fs::read_to_string(first.join("report.md")).unwrap();
    assert!(
        md.contains("## Edges of the range\n\n- bevy.first_cascade_far_bound 20 is the largest"),
        "{md}"
    );
    let html = std::fs::read_to_string(first.join("report.html")).unwrap();
    assert!(html.contains("<h2>Edges of the range</h2>"));
    // Sweeping what it suggests finds a better setting inside the new range, with no edge.
    let next = tmp.path().join("next");
    let (stdout, rec2) = run(&next, &["--knob", "20,25,30,35,40,45"]);
    let (chosen2, lo2, hi2) = recommended_and_extremes(&next.join("sweep.csv"), knob);
    assert!(lo2 < chosen2 && chosen2 < hi2, "{chosen2} in [{lo2}, {hi2}]");
    assert_eq!(rec2["range_edges"], serde_json::json!([]));
    assert!(!stdout.contains("range edge"), "{stdout}");
    let objective = |v: &serde_json::Value| v["recommended"]["screen_aliasing_p95"].as_f64().unwrap();
    assert!(
        objective(&rec2) < objective(&rec),
        "{} vs {}",
        objective(&rec2),
        objective(&rec)
    );
}

/// Width and height of a PNG, from its header.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn a_heat_map_of_many_resolutions_draws_six_of_them_and_its_png_stays_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_config(dir.path());
    let out = dir.path().join("o");
    // 9 resolutions × 3 λ × 2 counts × 2 fits: more resolutions than the heat map has panels for.
    let resolutions: Vec<String> = (0..9).map(|i| (512 + 128 * i).to_string()).collect();
    let o = sweep(
        &cfg,
        &out,
        &["--cascades", "2,4", "--resolution", &resolutions.join(",")],
    );
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let rec: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("recommendation.json")).unwrap()).unwrap();
    let focus = rec["recommended"]["resolution"].as_u64().expect("a recommendation");
    let svg = std::fs::read_to_string(out.join("heatmap.svg")).unwrap();
    // The panels' captions name their resolution: "<metric> · <res>² · <fit>".
    let mut shown: Vec<u64> = svg
        .split(" · ")
        .filter_map(|part| part.strip_suffix('²').and_then(|r| r.parse().ok()))
        .collect();
    shown.sort_unstable();
    shown.dedup();
    assert_eq!(shown.len(), 6, "{shown:?}");
    assert!(
        shown.contains(&focus),
        "the recommendation's {focus}² has a panel: {shown:?}"
    );
    let all: Vec<u64> = resolutions.iter().map(|r| r.parse().unwrap()).collect();
    assert!(shown.iter().all(|r| all.contains(r)));
    assert!(
        svg.contains(&format!(
            "Panels for 6 of the 9 resolutions (the red ring&apos;s {focus}² and an even spread"
        )),
        "the note says which panels are drawn"
    );
    // Six panel columns (400 SVG pixels each) and four rows (2 metrics × 2 fits): 2440 × 1310,
    // wider than a page: the PNG is the page's 1280 pixels wide, the height in proportion.
    assert!(svg.starts_with("<svg width=\"2440\" height=\"1310\""), "{}", &svg[..60]);
    let (w, h) = png_size(&std::fs::read(out.join("heatmap.png")).unwrap());
    let scale = 1280.0f32 / 2440.0;
    assert_eq!((w, h), (1280, (1310.0 * scale).ceil() as u32));
    // A figure no wider than a page keeps its own size.
    assert!(std::fs::read_to_string(out.join("pareto.svg"))
        .unwrap()
        .starts_with("<svg width=\"960\" height=\"632\""));
    assert_eq!(png_size(&std::fs::read(out.join("pareto.png")).unwrap()), (960, 632));
}
