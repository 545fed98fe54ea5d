//! The layers point one way. Every top-level module of `src/` may import only the modules
//! below it in [`LAYERS`]; the core (`src/core/`) imports nothing but itself. Read from the
//! source text (test modules excluded), so a new import that climbs a layer fails here with
//! the file and the line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Bottom to top. A module may use any module listed before it.
const LAYERS: &[&str] = &[
    "error",
    "suggest",
    "output",
    "core",
    "config",
    "presets",
    "analysis",
    "metric",
    "load",
    "commands",
    "drift_table",
    "figures",
    "report",
    "app",
    "cli",
];

/// Short paths re-exported by `lib.rs`, resolved to the module they name.
fn module_of(name: &str) -> &str {
    match name {
        "cascades" | "depth_range" | "fitting" | "geometry" | "light_motion" | "mesh" | "metrics" | "motion"
        | "precision" | "rng" | "scene" | "screen" | "seams" | "shade" | "shimmer" | "snapping" | "splits" | "sun"
        | "visibility" | "walk" => "core",
        "bench" | "check" | "compare" | "stress" | "sweep" => "commands",
        "plots" => "figures",
        "Error" | "Result" => "error",
        "Config" => "config",
        "Analysis" | "AnalysisOptions" | "Summary" | "analyze" => "analysis",
        other => other,
    }
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// (file, line number, module used) for every `crate::NAME` outside comments and test modules.
fn uses(src: &Path) -> Vec<(String, usize, String, String)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut out = Vec::new();
    for f in files {
        let rel = f.strip_prefix(src).unwrap().to_string_lossy().replace('\\', "/");
        let top = rel.split('/').next().unwrap().trim_end_matches(".rs").to_string();
        if top == "lib" || top == "main" {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("#[cfg(test)]") {
                break;
            }
            let code = line.split("//").next().unwrap();
            let mut rest = code;
            while let Some(k) = rest.find("crate::") {
                rest = &rest[k + 7..];
                // `crate::{a::X, b}` names several modules at once.
                let names: Vec<String> = match rest.strip_prefix('{') {
                    Some(group) => group
                        .split('}')
                        .next()
                        .unwrap_or("")
                        .split(',')
                        .map(|p| p.trim().split("::").next().unwrap_or("").to_string())
                        .collect(),
                    None => vec![rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect()],
                };
                for name in names.into_iter().filter(|n| !n.is_empty()) {
                    out.push((rel.clone(), i + 1, top.clone(), module_of(&name).to_string()));
                }
            }
        }
    }
    out
}

#[test]
fn no_module_imports_a_layer_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let rank: BTreeMap<&str, usize> = LAYERS.iter().enumerate().map(|(i, m)| (*m, i)).collect();
    let mut problems = Vec::new();
    for (file, line, from, to) in uses(&src) {
        if from == to {
            continue;
        }
        let (Some(a), Some(b)) = (rank.get(from.as_str()), rank.get(to.as_str())) else {
            problems.push(format!("{file}:{line}: `{from}` or `{to}` is not in LAYERS"));
            continue;
        };
        if b > a {
            problems.push(format!("{file}:{line}: `{from}` uses `{to}`, a layer above it"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_core_imports_only_itself() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let outside: Vec<String> = uses(&src)
        .into_iter()
        .filter(|(_, _, from, to)| from == "core" && to != "core")
        .map(|(file, line, _, to)| format!("{file}:{line}: uses `{to}`"))
        .collect();
    assert!(outside.is_empty(), "{}", outside.join("\n"));
}

#[test]
fn the_layer_check_sees_an_upward_import() {
    // The checker itself: an upward use in a scratch tree is reported.
    let dir = std::env::temp_dir().join(format!("csm-lab-layers-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("core")).unwrap();
    std::fs::write(
        dir.join("core/x.rs"),
        "use crate::config::Config;\n// crate::report in a comment\nuse crate::{geometry::Aabb, presets};\n",
    )
    .unwrap();
    let found = uses(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    let at = |line: usize, to: &str| ("core/x.rs".to_string(), line, "core".to_string(), to.to_string());
    assert_eq!(found, vec![at(1, "config"), at(3, "core"), at(3, "presets")]);
}
