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

/// 10^5 copies of one triangle overflowed the BVH builder's stack after minutes (a tree as
/// deep as the copies); identical boxes made every ray visit every copy. The BVH keeps each
/// distinct binary32 triangle once and leaves out those of zero area once rounded: the hits
/// are those of the mesh without copies, reported by the first copy's index.
#[test]
fn coincident_triangles_build_a_bvh_of_one_and_hit_as_one() {
    use csm_core::geometry::Aabb;
    use csm_core::mesh::Mesh;
    use csm_core::visibility::SceneGeometry;
    use glam::DVec3;
    let tri = [
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(1.0, 0.0, -1.0),
        DVec3::new(0.0, 0.0, 1.0),
    ];
    let mut m = Mesh::default();
    for k in 0..100_000 {
        // The same triangle, its vertices in turn rotated (the same triangle to a ray).
        let r = k % 3;
        m.push([tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]]);
    }
    // A sliver whose binary32 vertices are collinear (its f64 area is not zero): the third
    // vertex is 0.1 off the line, and binary32 steps are 0.5 at 5e6.
    m.push([
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1e7, 1e7, 0.0),
        DVec3::new(5e6, 5e6 + 0.1, 0.0),
    ]);
    assert_eq!(m.triangles.len(), 100_001);
    let scene = SceneGeometry::new(m);
    let d = scene.bvh_dropped();
    assert_eq!((d.duplicates, d.degenerate), (99_999, 1));
    // A ray down through the triangle hits it at the first copy, 2 units below the origin.
    let hit = scene
        .first_hit(DVec3::new(0.1, 2.0, 0.0), DVec3::NEG_Y, 0.0, 10.0)
        .unwrap();
    assert_eq!((hit.triangle, hit.t), (0, 2.0));
    // Beside it: nothing.
    assert!(scene
        .first_hit(DVec3::new(3.0, 2.0, 0.0), DVec3::NEG_Y, 0.0, 10.0)
        .is_none());

    // 10^4 identical boxes hit as one box: every ray of a grid gives the single box's
    // distance, at a triangle of the first copy (index below 12).
    let b = Aabb {
        min: DVec3::new(-1.0, 0.0, -2.0),
        max: DVec3::new(1.5, 3.0, 2.0),
    };
    let (mut many, mut one) = (Mesh::default(), Mesh::default());
    one.add_box(&b);
    for _ in 0..10_000 {
        many.add_box(&b);
    }
    let (many, one) = (SceneGeometry::new(many), SceneGeometry::new(one));
    assert_eq!(many.bvh_dropped().duplicates, 9_999 * 12);
    let mut hits = 0;
    for i in 0..20 {
        for j in 0..20 {
            let o = DVec3::new(-3.0 + 0.3 * i as f64, 1.0 + 0.05 * j as f64, -6.0);
            let dir = DVec3::new(0.1, -0.02, 1.0).normalize();
            let (a, e) = (many.first_hit(o, dir, 0.0, 50.0), one.first_hit(o, dir, 0.0, 50.0));
            assert_eq!(
                a.map(|h| (h.t, h.triangle)),
                e.map(|h| (h.t, h.triangle)),
                "ray {i} {j}"
            );
            hits += a.is_some() as usize;
        }
    }
    assert!(hits > 100 && hits < 400, "{hits}");
}

/// A config of identical boxes runs and says on stderr what the BVH left out.
#[test]
fn identical_boxes_in_a_config_are_reported_as_left_out_of_the_bvh() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = String::new();
    for _ in 0..500 {
        boxes.push_str("\n[[scene.box]]\nmin = [-5.0, 0.0, -40.0]\nmax = [5.0, 8.0, -30.0]\n");
    }
    let text = format!("{}{boxes}", with(&[("scene.ground", "ground = 0.0")]));
    let cfg = write(dir.path(), "boxes.toml", &text);
    let out = bin()
        .args(["analyze", &cfg, "--quiet", "--out"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let e = stderr(&out);
    assert!(
        e.contains("leaves out 5988 duplicate triangle(s)") && e.contains("and 0 of zero area"),
        "{e}"
    );
}

/// The ground-truth pass is refused before any work when its estimated texel reads exceed the
/// limit, with the estimate and the keys that lower it: at `screen_scale = 1` on the default
/// scene it ran past a minute at 979 MB, and a 10^5-frame path ran on with no end in sight.
#[test]
fn a_ground_truth_pass_beyond_its_limit_is_refused_up_front_with_the_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, edits: &[(&str, &str)], flag: bool| {
        let mut e = vec![("scene.ground", "ground = 0.0")];
        e.extend_from_slice(edits);
        let cfg = write(dir.path(), name, &with(&e));
        let mut cmd = bin();
        cmd.args(["analyze", &cfg, "--quiet", "--out"])
            .arg(dir.path().join(format!("out-{name}")));
        if flag {
            cmd.arg("--ground-truth");
        }
        cmd.output().unwrap()
    };
    // 1920 x 1080 sampled pixels x (240 + 2) frames x 2 modes x 4 texels (bilinear 1x1).
    let o = run(
        "full.toml",
        &[
            ("analysis.screen_scale", "screen_scale = 1.0"),
            ("motion.frames", "frames = 240"),
        ],
        true,
    );
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("--ground-truth")
            && e.contains(&format!("about {} texels", 2_073_600u64 * 242 * 2 * 4))
            && e.contains("2073600 sampled pixels x (240 frames + 2) x 2 snap modes x 4 texels per lookup")
            && e.contains("analysis.screen_scale (at most 0.5171 fits), motion.frames or shadow.pcf"),
        "{e}"
    );
    assert!(
        !dir.path().join("out-full.toml").exists(),
        "no output before the refusal"
    );
    // A long path, asked for by the config key: 240 x 135 pixels x (100000 + 2) frames.
    let o = run(
        "long.toml",
        &[
            ("motion.frames", "frames = 100000"),
            ("analysis.ground_truth", "ground_truth = true"),
        ],
        false,
    );
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("analysis.ground_truth") && e.contains(&format!("about {} texels", 32_400u64 * 100_002 * 8)),
        "{e}"
    );
    // Within the limit (the same path at 60 frames) the pass runs.
    let o = run("fits.toml", &[], true);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The estimate bounds the texel reads the pass makes (each receiver is a sampled pixel,
/// looked up at most once per frame and snap mode), and is not far above them.
#[test]
fn the_ground_truth_cost_estimate_bounds_the_reads_made() {
    use csm_lab::analysis::ground_truth::cost;
    use csm_lab::config::Config;
    for (pcf, filter) in [(1, "bilinear"), (3, "nearest"), (3, "bilinear")] {
        let text = with(&[
            ("scene.ground", "ground = 0.0"),
            ("shadow.pcf", &format!("pcf = {pcf}")),
            ("shadow.pcf_filter", &format!("pcf_filter = \"{filter}\"")),
            ("motion.frames", "frames = 12"),
            ("analysis.screen_scale", "screen_scale = 0.05"),
            ("analysis.ground_truth", "ground_truth = true"),
        ]);
        let c = Config::from_toml_str(&text, "t.toml", None).unwrap();
        let est = cost(&c);
        assert_eq!(est.pixels, 96 * 54);
        assert_eq!(est.frames, 12);
        assert_eq!(est.per_lookup, pcf * pcf * if filter == "bilinear" { 4 } else { 1 });
        let a = csm_lab::analyze(&c, &csm_lab::AnalysisOptions::full());
        let reads = a.ground_truth.as_ref().unwrap().cache.reads;
        assert!(reads <= est.reads && reads * 4 >= est.reads, "{reads} of {est:?}");
    }
}

/// `sweep configs/indoor.toml --fit aabb`: no configuration can qualify (a tight box under a
/// turning camera changes size every frame), and the first frames of the path prove it; the
/// sweep says so before running (it took 14 to 60 s to reach the same verdict).
#[test]
fn a_sweep_where_nothing_can_qualify_fails_before_running() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = bin()
        .args([
            "sweep",
            "configs/indoor.toml",
            "--fit",
            "aabb",
            "--no-plots",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains(
            "Nothing qualifies: of 672 configurations, 0 miss slice corners (coverage_violations > 0) and 672 shimmer \
             when snapped (shimmer_snapped > 0.001 texel), which the first 8 of the path's 180 frames already show"
        ),
        "{e}"
    );
    assert!(!out.join("sweep.csv").exists());
    // A grid where a row qualifies runs as before.
    let o = bin()
        .args([
            "sweep",
            "configs/indoor.toml",
            "--cascades",
            "2",
            "--resolution",
            "512",
            "--no-plots",
            "--quiet",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("sweep.csv").exists());
}

/// The bound the check rests on, against full analyses: the first 8 frames' squared drifts
/// over `(F − 1) m` never exceed the whole path's snapped S3², and each row the bound refuses
/// really shimmers; a first-frames coverage violation stays in the whole path.
#[test]
fn the_first_frames_bound_snapped_shimmer_and_coverage_from_below() {
    use csm_lab::{analyze, AnalysisOptions, Config};
    let base = std::fs::read_to_string("configs/indoor.toml").unwrap();
    let mut refused = 0;
    for (fit, snap, cascades, resolution, path) in [
        ("aabb", true, 2, 512, "yaw"),
        ("aabb", true, 4, 2048, "strafe"),
        ("aabb", true, 3, 1024, "orbit"),
        ("sphere", true, 3, 1024, "yaw"),
        ("sphere", false, 2, 512, "dolly"),
    ] {
        let text = base
            .replace("fit = \"sphere\"", &format!("fit = \"{fit}\""))
            .replace("snap = true", &format!("snap = {snap}"))
            .replace("cascades = 3", &format!("cascades = {cascades}"))
            .replace("resolution = 1024", &format!("resolution = {resolution}"))
            .replace("path = \"yaw\"", &format!("path = \"{path}\""));
        let full = Config::from_toml_str(&text, "indoor.toml", None).unwrap();
        let frames = full.motion.frames;
        let prefix = Config::from_toml_str(&text.replace("frames = 180", "frames = 8"), "indoor.toml", None).unwrap();
        let opts = AnalysisOptions {
            frame_rows: true,
            ..AnalysisOptions::summary_only()
        };
        let (a, p) = (analyze(&full, &opts), analyze(&prefix, &opts));
        let sum: f64 = p
            .snapped()
            .unwrap()
            .frames
            .iter()
            .map(|f| f.phase_drift_rms.powi(2))
            .sum();
        let bound = (sum / ((frames - 1) * cascades) as f64).sqrt();
        let s3 = a.summary.shimmer_snapped;
        assert!(bound <= s3 * (1.0 + 1e-12), "{fit} {path}: bound {bound} above S3 {s3}");
        if bound > 1e-3 {
            refused += 1;
            assert!(s3 > 1e-3);
        }
        if p.summary.coverage_violations > 0 {
            assert!(a.summary.coverage_violations >= p.summary.coverage_violations);
        }
    }
    assert!(refused >= 2, "{refused}");
}
