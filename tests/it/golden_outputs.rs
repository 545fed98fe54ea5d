//! Golden outputs: every file the bundled configs and a grid of variants write (plus each
//! command's stdout, stderr and exit code) must stay byte for byte what was recorded.
//!
//! The recorded state is `tests/golden/<group>.tsv` (size and SHA-256 of every file) with
//! copies of the small text files under `tests/golden/<group>/` so that a difference can be
//! shown as a diff. A deliberate change re-records them in the same commit:
//!
//! ```sh
//! CSM_LAB_RECORD_GOLDEN=1 cargo test golden
//! ```
//!
//! On a mismatch the files of the current run are left in `target/golden-actual/<group>/`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use sha2::{Digest, Sha256};

const BIN: &str = env!("CARGO_BIN_EXE_csm-lab");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Text files up to this size are kept verbatim beside the manifest.
const COPY_LIMIT: u64 = 24 * 1024;

/// One run of the binary in its own directory. Paths in the arguments are relative to it, so
/// that nothing machine-specific reaches an output.
struct Case {
    name: String,
    /// Files to create in the case directory: (name, contents).
    files: Vec<(String, String)>,
    args: Vec<String>,
}

fn case(name: &str, files: Vec<(String, String)>, args: &[&str]) -> Case {
    Case {
        name: name.to_string(),
        files,
        args: args.iter().map(|s| s.to_string()).collect(),
    }
}

fn bundled(name: &str) -> (String, String) {
    let path = Path::new(ROOT).join("configs").join(name);
    (name.to_string(), std::fs::read_to_string(&path).unwrap())
}

/// A config's text without its scene geometry (`ground` and the `[[scene.box]]` tables): the
/// bounds-only mode, whose outputs must stay byte-identical to those recorded before the
/// geometry existed.
fn bounds_only(text: &str) -> String {
    let mut out = Vec::new();
    let mut in_box = false;
    for l in text.lines() {
        let t = l.trim();
        if t.starts_with("[[scene.box]]") {
            in_box = true;
            continue;
        }
        if in_box && (t.starts_with("min") || t.starts_with("max") || t.is_empty()) {
            continue;
        }
        in_box = false;
        if t.starts_with("ground =") || t.starts_with("gltf =") {
            continue;
        }
        out.push(l);
    }
    out.join("\n") + "\n"
}

/// A bundled config in the bounds-only mode, under its own name.
fn bundled_bounds_only(name: &str) -> (String, String) {
    let (name, text) = bundled(name);
    (name, bounds_only(&text))
}

/// The default scene in the bounds-only mode with 60 frames and no sweep table, as text to edit.
fn base() -> String {
    let text = std::fs::read_to_string(Path::new(ROOT).join("configs/default.toml")).unwrap();
    let text = bounds_only(text.split("[sweep]").next().unwrap());
    text.replace("frames = 240", "frames = 60")
}

/// The default scene with its geometry, 60 frames and no sweep table.
fn geometry_base() -> String {
    let text = std::fs::read_to_string(Path::new(ROOT).join("configs/default.toml")).unwrap();
    let text = text.split("[sweep]").next().unwrap().to_string();
    text.replace("frames = 240", "frames = 60")
}

/// An `analyze` case of the default scene with geometry, edited.
fn analyze_geometry(name: &str, edits: &[(&str, &str)], extra: &str) -> Case {
    let file = format!("{name}.toml");
    let text = edit(&geometry_base(), edits) + extra;
    case(name, vec![(file.clone(), text)], &["analyze", &file, "--out", "out"])
}

/// `base()` with `table.key = value` lines set (replaced, or appended to their table).
fn edit(text: &str, edits: &[(&str, &str)]) -> String {
    let mut text = text.to_string();
    for (key, value) in edits {
        let (table, name) = key.split_once('.').unwrap();
        let mut out: Vec<String> = Vec::new();
        let mut current = String::new();
        let mut done = false;
        let line = format!("{name} = {value}");
        for l in text.lines() {
            let t = l.trim();
            if t.starts_with('[') {
                if current == table && !done {
                    out.push(line.clone());
                    done = true;
                }
                current = t.trim_matches(|c| c == '[' || c == ']').to_string();
            }
            if current == table && t.split('=').next().map(str::trim) == Some(name) {
                if !done {
                    out.push(line.clone());
                    done = true;
                }
                continue;
            }
            out.push(l.to_string());
        }
        if !done {
            if current != table {
                out.push(format!("[{table}]"));
            }
            out.push(line);
        }
        text = out.join("\n");
        text.push('\n');
    }
    text
}

fn scene(name: &str, edits: &[(&str, &str)]) -> Vec<(String, String)> {
    vec![(format!("{name}.toml"), edit(&base(), edits))]
}

fn analyze(name: &str, edits: &[(&str, &str)]) -> Case {
    let file = format!("{name}.toml");
    case(name, scene(name, edits), &["analyze", &file, "--out", "out"])
}

fn path_csv() -> (String, String) {
    let mut s = String::from("px,py,pz,tx,ty,tz\n");
    for i in 0..20 {
        let t = i as f64;
        writeln!(
            s,
            "{},{},{},{},{},{}",
            0.03 * t,
            10.0 + 0.01 * t,
            -0.02 * t,
            0.5 * t,
            0.0,
            -50.0
        )
        .unwrap();
    }
    ("path.csv".to_string(), s)
}

fn analyze_variants() -> Vec<Case> {
    let mut cases = vec![
        analyze("base", &[]),
        analyze("aabb", &[("shadow.fit", "\"aabb\"")]),
        analyze("nosnap", &[("shadow.snap", "false")]),
        analyze("aabb_nosnap", &[("shadow.fit", "\"aabb\""), ("shadow.snap", "false")]),
        analyze("lambda0_c1", &[("shadow.lambda", "0.0"), ("shadow.cascades", "1")]),
        analyze("lambda1_c8", &[("shadow.lambda", "1.0"), ("shadow.cascades", "8")]),
        analyze("no_scene_clip", &[("shadow.fit_depth_to_scene", "false")]),
        analyze(
            "invisible_scene",
            &[
                ("scene.min", "[500.0, 0.0, 500.0]"),
                ("scene.max", "[600.0, 10.0, 600.0]"),
            ],
        ),
        analyze("bad_fit", &[("shadow.fit", "\"ellipse\"")]),
    ];
    for path in ["dolly", "yaw", "pitch", "orbit"] {
        let step = if path == "dolly" { "0.05" } else { "0.5" };
        for fit in ["sphere", "aabb"] {
            cases.push(analyze(
                &format!("{path}_{fit}"),
                &[
                    ("motion.path", &format!("\"{path}\"")),
                    ("motion.step", step),
                    ("shadow.fit", &format!("\"{fit}\"")),
                ],
            ));
        }
    }
    for fit in ["sphere", "aabb"] {
        let name = format!("file_{fit}");
        let mut files = scene(
            &name,
            &[
                ("motion.path", "\"file\""),
                ("motion.file", "\"path.csv\""),
                ("shadow.fit", &format!("\"{fit}\"")),
            ],
        );
        files.push(path_csv());
        let file = format!("{name}.toml");
        cases.push(case(&name, files, &["analyze", &file, "--out", "out"]));
    }
    for (label, offset) in [
        ("0", "[0.0, 0.0, 0.0]"),
        ("1e5", "[1e5, 0.0, 0.0]"),
        ("1e6", "[1e6, 0.0, 0.0]"),
    ] {
        if label != "0" {
            cases.push(analyze(
                &format!("f64_offset_{label}"),
                &[("scene.world_offset", offset)],
            ));
        }
        for fit in ["sphere", "aabb"] {
            cases.push(analyze(
                &format!("f32_{fit}_offset_{label}"),
                &[
                    ("scene.world_offset", offset),
                    ("shadow.precision", "\"f32\""),
                    ("shadow.fit", &format!("\"{fit}\"")),
                ],
            ));
        }
        cases.push(analyze(
            &format!("f32_camera_relative_offset_{label}"),
            &[
                ("scene.world_offset", offset),
                ("shadow.precision", "\"f32\""),
                ("shadow.snap_space", "\"camera_relative\""),
            ],
        ));
    }
    cases.push(analyze(
        "f32_yaw_aabb_nosnap",
        &[
            ("shadow.precision", "\"f32\""),
            ("shadow.fit", "\"aabb\""),
            ("shadow.snap", "false"),
            ("motion.path", "\"yaw\""),
            ("motion.step", "0.5"),
        ],
    ));
    let mut json = analyze("base_json", &[]);
    json.args.extend(["--format".to_string(), "json".to_string()]);
    cases.push(json);
    cases
}

fn analyze_presets() -> Vec<Case> {
    let mut cases = Vec::new();
    // Every registered engine: a new one gets its golden outputs without a change here.
    for p in csm_lab::presets::PresetName::ALL.map(|p| p.as_str()) {
        let preset = format!("\"{p}\"");
        cases.push(analyze(&format!("preset_{p}"), &[("shadow.preset", &preset)]));
        cases.push(analyze(
            &format!("preset_{p}_yaw"),
            &[
                ("shadow.preset", &preset),
                ("motion.path", "\"yaw\""),
                ("motion.step", "0.5"),
            ],
        ));
        cases.push(analyze(
            &format!("preset_{p}_f32"),
            &[("shadow.preset", &preset), ("shadow.precision", "\"f32\"")],
        ));
    }
    cases
}

fn bundled_runs() -> Vec<Case> {
    let mut cases = Vec::new();
    for name in ["default", "indoor", "open_world", "top_down", "village", "sunset"] {
        let file = format!("{name}.toml");
        let mut files = vec![bundled(&file)];
        if name == "village" {
            files.push(bundled("village.gltf"));
        }
        cases.push(case(
            &format!("analyze_{name}"),
            files.clone(),
            &["analyze", &file, "--out", "out"],
        ));
        cases.push(case(
            &format!("sweep_{name}"),
            files,
            &["sweep", &file, "--quiet", "--out", "out"],
        ));
    }
    cases.push(case(
        "check_default",
        vec![bundled("default.toml"), bundled("thresholds.toml")],
        &[
            "check",
            "default.toml",
            "--thresholds",
            "thresholds.toml",
            "--junit",
            "out/check.xml",
        ],
    ));
    cases
}

fn sweep_compare_stress() -> Vec<Case> {
    let small = [
        "--cascades",
        "2,4",
        "--resolution",
        "1024,2048",
        "--lambda",
        "0,0.5,0.75,1",
    ];
    let mut fits = vec![
        "sweep",
        "default.toml",
        "--quiet",
        "--out",
        "out",
        "--fit",
        "sphere,aabb",
    ];
    fits.extend(small);
    let mut cases = vec![
        case("sweep_default_fits", vec![bundled_bounds_only("default.toml")], &fits),
        case(
            "sweep_default_preset_bevy",
            vec![bundled_bounds_only("default.toml")],
            &["sweep", "default.toml", "--quiet", "--out", "out", "--preset", "bevy"],
        ),
        case(
            "sweep_f32_offset_1e8_aabb",
            scene(
                "far",
                &[
                    ("scene.world_offset", "[1e8, 0.0, 0.0]"),
                    ("shadow.precision", "\"f32\""),
                ],
            ),
            &[
                "sweep",
                "far.toml",
                "--quiet",
                "--out",
                "out",
                "--fit",
                "aabb",
                "--no-plots",
            ],
        ),
        case(
            "check_default_sweep",
            vec![bundled_bounds_only("default.toml"), bundled("thresholds.toml")],
            &["check", "default.toml", "--thresholds", "thresholds.toml", "--sweep"],
        ),
        case(
            "compare_default_defaults",
            vec![bundled_bounds_only("default.toml")],
            &["compare", "default.toml", "--defaults", "--out", "out"],
        ),
        case(
            "compare_default",
            vec![bundled_bounds_only("default.toml")],
            &["compare", "default.toml", "--out", "out"],
        ),
        case("stress", vec![], &["stress", "--out", "out"]),
    ];
    cases.push(case(
        "stress_random",
        vec![],
        &["stress", "--out", "out", "--cases", "8", "--seed", "7"],
    ));
    cases
}

fn sha256(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

fn is_text(name: &str) -> bool {
    [".csv", ".json", ".md", ".txt", ".xml"]
        .iter()
        .any(|e| name.ends_with(e))
}

/// Runs a case and returns its files: every file under `out/` plus stdout, stderr and status.
fn run(case: &Case, scratch: &Path) -> BTreeMap<String, Vec<u8>> {
    let dir = scratch.join(&case.name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in &case.files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let out = Command::new(BIN)
        .args(&case.args)
        .current_dir(&dir)
        .env_remove("RAYON_NUM_THREADS")
        .output()
        .unwrap();
    let mut files = BTreeMap::new();
    files.insert("stdout.txt".to_string(), out.stdout);
    files.insert("stderr.txt".to_string(), out.stderr);
    files.insert(
        "status.txt".to_string(),
        format!("{:?}\n", out.status.code()).into_bytes(),
    );
    let out_dir = dir.join("out");
    if out_dir.is_dir() {
        let mut stack = vec![out_dir.clone()];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else {
                    let rel = p.strip_prefix(&out_dir).unwrap().to_string_lossy().replace('\\', "/");
                    files.insert(format!("out/{rel}"), std::fs::read(&p).unwrap());
                }
            }
        }
    }
    files
}

fn manifest_path(group: &str) -> PathBuf {
    Path::new(ROOT).join("tests/golden").join(format!("{group}.tsv"))
}

fn read_manifest(group: &str) -> BTreeMap<(String, String), (u64, String)> {
    let text = std::fs::read_to_string(manifest_path(group)).unwrap_or_else(|e| {
        panic!(
            "no recorded golden outputs for {group} ({e}); record them with CSM_LAB_RECORD_GOLDEN=1 cargo test golden"
        )
    });
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (
                (f[0].to_string(), f[1].to_string()),
                (f[2].parse().unwrap(), f[3].to_string()),
            )
        })
        .collect()
}

/// First line where two texts differ, for the failure message.
fn first_difference(expected: &[u8], actual: &[u8]) -> String {
    let (e, a) = (String::from_utf8_lossy(expected), String::from_utf8_lossy(actual));
    for (i, (x, y)) in e.lines().zip(a.lines()).enumerate() {
        if x != y {
            return format!("line {}:\n      recorded: {x}\n      now:      {y}", i + 1);
        }
    }
    format!("{} lines recorded, {} now", e.lines().count(), a.lines().count())
}

fn golden(group: &str, cases: Vec<Case>) {
    let scratch = Path::new(ROOT).join("target/golden-scratch").join(group);
    let record = std::env::var_os("CSM_LAB_RECORD_GOLDEN").is_some();
    let copies = Path::new(ROOT).join("tests/golden").join(group);
    let mut actual: BTreeMap<(String, String), Vec<u8>> = BTreeMap::new();
    for c in &cases {
        for (file, bytes) in run(c, &scratch) {
            actual.insert((c.name.clone(), file), bytes);
        }
    }
    if record {
        let _ = std::fs::remove_dir_all(&copies);
        let mut manifest = String::from("# case\tfile\tbytes\tsha256 (see tests/golden_outputs.rs)\n");
        for ((case, file), bytes) in &actual {
            writeln!(manifest, "{case}\t{file}\t{}\t{}", bytes.len(), sha256(bytes)).unwrap();
            if is_text(file) && bytes.len() as u64 <= COPY_LIMIT {
                let p = copies.join(case).join(file);
                std::fs::create_dir_all(p.parent().unwrap()).unwrap();
                std::fs::write(p, bytes).unwrap();
            }
        }
        std::fs::write(manifest_path(group), manifest).unwrap();
        return;
    }
    let recorded = read_manifest(group);
    let mut problems = Vec::new();
    for (key, (size, hash)) in &recorded {
        match actual.get(key) {
            None => problems.push(format!("{}/{}: recorded, not written now", key.0, key.1)),
            Some(bytes) if bytes.len() as u64 != *size || sha256(bytes) != *hash => {
                let copy = copies.join(&key.0).join(&key.1);
                let detail = match std::fs::read(&copy) {
                    Ok(expected) => first_difference(&expected, bytes),
                    Err(_) => format!("{size} bytes recorded, {} now", bytes.len()),
                };
                problems.push(format!("{}/{} differs: {detail}", key.0, key.1));
            }
            Some(_) => {}
        }
    }
    for key in actual.keys() {
        if !recorded.contains_key(key) {
            problems.push(format!("{}/{}: written now, not recorded", key.0, key.1));
        }
    }
    if !problems.is_empty() {
        let keep = Path::new(ROOT).join("target/golden-actual").join(group);
        let _ = std::fs::remove_dir_all(&keep);
        for ((case, file), bytes) in &actual {
            let p = keep.join(case).join(file);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, bytes).unwrap();
        }
        panic!(
            "{} golden output(s) of {group} changed (current files in {}):\n  {}\nIf the change is deliberate, \
             re-record with CSM_LAB_RECORD_GOLDEN=1 cargo test golden and say why in the commit.",
            problems.len(),
            keep.display(),
            problems.join("\n  ")
        );
    }
}

/// A small sweep of `g.toml` (8 configurations).
const SMALL_GEO_SWEEP: [&str; 11] = [
    "sweep",
    "g.toml",
    "--quiet",
    "--out",
    "out",
    "--cascades",
    "2,4",
    "--resolution",
    "1024,2048",
    "--lambda",
    "0.5,0.75",
];

/// Scene geometry: ground, boxes, glTF, splits fitted to the visible depths, a camera that sees
/// nothing, sweeps and compare with screen metrics, and the errors of bad geometry input.
fn geometry_runs() -> Vec<Case> {
    let village = vec![bundled("village.toml"), bundled("village.gltf")];
    let fitted = [("shadow.fit_depth_to_visible", "true")];
    vec![
        case(
            "geo_ground",
            scene("geo_ground", &[("scene.ground", "0.0")]),
            &["analyze", "geo_ground.toml", "--out", "out"],
        ),
        analyze_geometry("geo_boxes", &[], ""),
        analyze_geometry("geo_fit_visible", &fitted, ""),
        analyze_geometry("geo_scale_1", &[("analysis.screen_scale", "1.0")], ""),
        analyze_geometry(
            "geo_sees_nothing",
            &[
                ("camera.target", "[0.0, 200.0, -50.0]"),
                ("shadow.fit_depth_to_visible", "true"),
            ],
            "",
        ),
        analyze_geometry(
            "geo_box_min_above_max",
            &[],
            "\n[[scene.box]]\nmin = [0.0, 5.0, 0.0]\nmax = [1.0, 4.0, 1.0]\n",
        ),
        analyze_geometry("geo_bad_scale", &[("analysis.screen_scale", "1.5")], ""),
        analyze_geometry("geo_missing_gltf", &[("scene.gltf", "\"missing.glb\"")], ""),
        analyze("geo_fit_visible_without_geometry", &fitted),
        case(
            "geo_gltf",
            village.clone(),
            &["analyze", "village.toml", "--out", "out"],
        ),
        case(
            "geo_sweep_small",
            vec![("g.toml".to_string(), geometry_base())],
            &SMALL_GEO_SWEEP,
        ),
        case(
            "geo_sweep_ground_truth",
            vec![("g.toml".to_string(), geometry_base())],
            &[&SMALL_GEO_SWEEP[..], &["--ground-truth"]].concat(),
        ),
        case(
            "geo_sweep_fitted_small",
            vec![("g.toml".to_string(), edit(&geometry_base(), &fitted))],
            &SMALL_GEO_SWEEP,
        ),
        case(
            "geo_sweep_both_split_ranges",
            vec![("g.toml".to_string(), geometry_base())],
            &[
                "sweep",
                "g.toml",
                "--quiet",
                "--out",
                "out",
                "--cascades",
                "2,4",
                "--resolution",
                "1024",
                "--lambda",
                "0.5,0.75",
                "--split-range",
                "bounds,visible",
            ],
        ),
        case(
            "geo_compare",
            vec![("g.toml".to_string(), geometry_base())],
            &["compare", "g.toml", "--out", "out"],
        ),
        case(
            "geo_compare_split_ranges",
            vec![("g.toml".to_string(), geometry_base())],
            &[
                "compare",
                "g.toml",
                "--presets",
                "bevy,unity",
                "--split-range",
                "bounds,visible",
                "--out",
                "out",
            ],
        ),
    ]
}

#[test]
fn golden_geometry_runs_are_unchanged() {
    golden("geometry", geometry_runs());
}

#[test]
fn golden_analyze_variants_are_unchanged() {
    golden("analyze_variants", analyze_variants());
}

#[test]
fn golden_analyze_presets_are_unchanged() {
    golden("analyze_presets", analyze_presets());
}

#[test]
fn golden_bundled_configs_are_unchanged() {
    golden("bundled", bundled_runs());
}

#[test]
fn golden_sweeps_compare_and_stress_are_unchanged() {
    golden("sweep_compare_stress", sweep_compare_stress());
}
