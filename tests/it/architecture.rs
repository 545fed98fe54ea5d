//! The design, checked from the source text (test modules excluded), so a change that breaks it
//! fails here with the file and the line:
//!
//! - the workspace: the math is its own crate (`crates/csm-core`), whose dependencies name no
//!   configuration, file format, CLI or plotting crate, and which uses no other crate of ours;
//! - the layers of the application crate (`src/`) point one way: a top-level module may import
//!   only the modules below it in [`LAYERS`];
//! - no folder of either crate holds an import circle between its files and subfolders (a
//!   folder's own `mod.rs` counts as one more member: a child that imports its parent's items
//!   while the parent imports the child is a circle too).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Bottom to top. A module of the application crate may use any module listed before it (and
/// the core crate, below them all).
const LAYERS: &[&str] = &[
    "error",
    "suggest",
    "output",
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

/// Items the application crate's root re-exports, resolved to the module that defines them.
fn module_of(name: &str) -> &str {
    match name {
        "Error" | "Result" => "error",
        "Config" => "config",
        "Analysis" | "AnalysisOptions" | "Summary" | "analyze" => "analysis",
        other => other,
    }
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
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

/// The module path of a source file: `commands/sweep/mod.rs` → `[commands, sweep]`,
/// `lib.rs` → `[]`.
fn module_path(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel.trim_end_matches(".rs").split('/').map(str::to_string).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// Expands one path that may hold `{…}` groups, nested, into every path it names:
/// `a::{b::X, c}` → `[a, b, X]`, `[a, c]`.
fn expand(text: &str) -> Vec<Vec<String>> {
    let text: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    fn go(s: &str) -> Vec<Vec<String>> {
        match s.find('{') {
            None => vec![s.split("::").filter(|p| !p.is_empty()).map(str::to_string).collect()],
            Some(open) => {
                let prefix: Vec<String> = s[..open]
                    .split("::")
                    .filter(|p| !p.is_empty())
                    .map(str::to_string)
                    .collect();
                let inner = &s[open + 1..s.rfind('}').unwrap_or(s.len())];
                let (mut depth, mut start, mut parts) = (0, 0, Vec::new());
                for (i, ch) in inner.char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            parts.push(&inner[start..i]);
                            start = i + 1;
                        }
                        _ => {}
                    }
                }
                parts.push(&inner[start..]);
                let mut out = Vec::new();
                for p in parts.into_iter().filter(|p| !p.is_empty()) {
                    for tail in go(p) {
                        let mut full = prefix.clone();
                        full.extend(tail.into_iter().filter(|t| t != "self"));
                        out.push(full);
                    }
                }
                out
            }
        }
    }
    go(&text)
}

/// One import: the file, its line, the module path of the file, and the absolute module path
/// it names (within its crate).
#[derive(Debug, Clone, PartialEq)]
struct Use {
    file: String,
    line: usize,
    from: Vec<String>,
    to: Vec<String>,
}

/// Every `crate::…`, `super::…` and `self::…` path outside comments and test modules, and, with
/// `extern` given, every path into that other crate (recorded with `to[0]` = its name).
fn uses(src: &Path, externs: &[&str]) -> Vec<Use> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut out = Vec::new();
    for f in files {
        let rel = f.strip_prefix(src).unwrap().to_string_lossy().replace('\\', "/");
        let from = module_path(&rel);
        let text = std::fs::read_to_string(&f).unwrap();
        let mut code = String::new();
        let mut line_of = Vec::new();
        for (i, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("#[cfg(test)]") {
                break;
            }
            let l = line.split("//").next().unwrap();
            code.push_str(l);
            code.push('\n');
            line_of.extend(std::iter::repeat_n(i + 1, l.len() + 1));
        }
        let mut heads: Vec<&str> = vec!["crate::", "super::", "self::"];
        let extern_heads: Vec<String> = externs.iter().map(|e| format!("{e}::")).collect();
        heads.extend(extern_heads.iter().map(String::as_str));
        let bytes = code.as_bytes();
        let mut k = 0;
        while k < code.len() {
            let Some(head) = heads.iter().find(|h| code[k..].starts_with(**h)) else {
                k += code[k..].chars().next().map_or(1, char::len_utf8);
                continue;
            };
            let prev_ident =
                k > 0 && (bytes[k - 1].is_ascii_alphanumeric() || bytes[k - 1] == b'_' || bytes[k - 1] == b':');
            if prev_ident {
                k += head.len();
                continue;
            }
            // The whole path: identifiers, `::`, and a balanced `{…}` group.
            let start = k;
            let mut end = k;
            let mut depth = 0i32;
            for (i, ch) in code[k..].char_indices() {
                let ok = ch.is_alphanumeric()
                    || ch == '_'
                    || ch == ':'
                    || (depth > 0 && (ch == ',' || ch.is_whitespace() || ch == '*'));
                match ch {
                    '{' => depth += 1,
                    '}' if depth > 0 => {
                        depth -= 1;
                        if depth == 0 {
                            end = k + i + 1;
                            break;
                        }
                    }
                    _ if !ok => break,
                    _ => {}
                }
                end = k + i + ch.len_utf8();
            }
            let path = &code[start..end];
            let line = line_of.get(start).copied().unwrap_or(0);
            for p in expand(path) {
                let to = match p.first().map(String::as_str) {
                    Some("crate") => p[1..].to_vec(),
                    Some("self") => from.iter().cloned().chain(p[1..].iter().cloned()).collect(),
                    Some("super") => {
                        let mut base = from.clone();
                        let mut rest = &p[..];
                        while rest.first().map(String::as_str) == Some("super") {
                            base.pop();
                            rest = &rest[1..];
                        }
                        base.into_iter().chain(rest.iter().cloned()).collect()
                    }
                    _ => p.clone(),
                };
                if !to.is_empty() {
                    out.push(Use {
                        file: rel.clone(),
                        line,
                        from: from.clone(),
                        to,
                    });
                }
            }
            k = end.max(k + 1);
        }
    }
    out
}

fn layer_problems(src: &Path) -> Vec<String> {
    let rank: BTreeMap<&str, usize> = LAYERS.iter().enumerate().map(|(i, m)| (*m, i)).collect();
    let mut problems = Vec::new();
    for u in uses(src, &[]) {
        let (Some(from), Some(to)) = (u.from.first(), u.to.first()) else {
            continue;
        };
        let to = module_of(to);
        if from == to {
            continue;
        }
        let (Some(a), Some(b)) = (rank.get(from.as_str()), rank.get(to)) else {
            problems.push(format!("{}:{}: `{from}` or `{to}` is not in LAYERS", u.file, u.line));
            continue;
        };
        if b > a {
            problems.push(format!("{}:{}: `{from}` uses `{to}`, a layer above it", u.file, u.line));
        }
    }
    problems
}

/// The members of a folder (module path `dir`): its child modules (files and subfolders) and
/// `mod` for the folder's own root file.
fn member(dir: &[String], path: &[String], children: &BTreeSet<String>) -> Option<String> {
    if path.len() < dir.len() || path[..dir.len()] != *dir {
        return None;
    }
    match path.get(dir.len()) {
        Some(c) if children.contains(c) => Some(c.clone()),
        _ => Some("mod".to_string()),
    }
}

/// Import circles inside each folder of a crate's source tree, one line per circle.
fn circles(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    // Folder module path → its child module names.
    let mut folders: BTreeMap<Vec<String>, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let rel = f.strip_prefix(src).unwrap().to_string_lossy().replace('\\', "/");
        let m = module_path(&rel);
        folders.entry(m.clone()).or_default();
        if let Some((last, parent)) = m.split_last() {
            folders.entry(parent.to_vec()).or_default().insert(last.clone());
        }
    }
    let all = uses(src, &[]);
    let mut found = Vec::new();
    for (dir, children) in &folders {
        if children.is_empty() {
            continue;
        }
        let mut edges: BTreeMap<String, BTreeMap<String, (String, usize)>> = BTreeMap::new();
        for u in &all {
            let (Some(a), Some(b)) = (member(dir, &u.from, children), member(dir, &u.to, children)) else {
                continue;
            };
            if a != b {
                edges.entry(a).or_default().entry(b).or_insert((u.file.clone(), u.line));
            }
        }
        // Depth-first search for a back edge; report each circle once, by its smallest member.
        let mut seen_cycles = BTreeSet::new();
        for startn in edges.keys() {
            let mut stack = vec![(startn.clone(), vec![startn.clone()])];
            while let Some((n, trail)) = stack.pop() {
                for (next, _) in edges.get(&n).into_iter().flatten() {
                    if next == startn {
                        let mut c = trail.clone();
                        let min = c.iter().min().unwrap().clone();
                        let at = c.iter().position(|x| *x == min).unwrap();
                        c.rotate_left(at);
                        if seen_cycles.insert(c.clone()) {
                            let hops: Vec<String> = c
                                .iter()
                                .zip(c.iter().cycle().skip(1))
                                .map(|(a, b)| {
                                    let (file, line) = &edges[a][b];
                                    format!("{a} → {b} ({file}:{line})")
                                })
                                .collect();
                            let name = if dir.is_empty() {
                                "(crate root)".to_string()
                            } else {
                                dir.join("/")
                            };
                            found.push(format!("{name}: {}", hops.join(", ")));
                        }
                    } else if !trail.contains(next) && next > startn {
                        let mut t = trail.clone();
                        t.push(next.clone());
                        stack.push((next.clone(), t));
                    }
                }
            }
        }
    }
    found
}

#[test]
fn no_module_imports_a_layer_above_it() {
    let problems = layer_problems(&root().join("src"));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn no_folder_holds_an_import_circle() {
    let mut found = circles(&root().join("crates/csm-core/src"));
    found.extend(circles(&root().join("src")));
    assert!(found.is_empty(), "import circles:\n{}", found.join("\n"));
}

/// The core crate: no path into the application crate, and a dependency list with no
/// configuration, file-format, CLI or plotting crate.
#[test]
fn the_core_is_its_own_crate_and_knows_no_format_or_cli() {
    let core = root().join("crates/csm-core");
    let into_app: Vec<String> = uses(&core.join("src"), &["csm_lab"])
        .into_iter()
        .filter(|u| u.to.first().map(String::as_str) == Some("csm_lab"))
        .map(|u| format!("{}:{}: uses csm_lab", u.file, u.line))
        .collect();
    assert!(into_app.is_empty(), "{}", into_app.join("\n"));

    let out = std::process::Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
            "--manifest-path",
        ])
        .arg(root().join("Cargo.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = meta["packages"].as_array().unwrap();
    let names: BTreeSet<&str> = packages.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, BTreeSet::from(["csm-core", "csm-lab"]), "the workspace's crates");
    let core_pkg = packages.iter().find(|p| p["name"] == "csm-core").unwrap();
    let deps: Vec<&str> = core_pkg["dependencies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["name"].as_str().unwrap())
        .collect();
    const FORBIDDEN: &[&str] = &[
        "csm-lab",
        "toml",
        "toml_edit",
        "csv",
        "serde_json",
        "clap",
        "plotters",
        "resvg",
        "png",
        "gltf",
        "indicatif",
        "tempfile",
        "dejavu",
    ];
    let bad: Vec<&&str> = deps.iter().filter(|d| FORBIDDEN.contains(d)).collect();
    assert!(
        bad.is_empty(),
        "csm-core depends on {bad:?}; its dependencies: {deps:?}"
    );
    let app_pkg = packages.iter().find(|p| p["name"] == "csm-lab").unwrap();
    assert!(
        app_pkg["dependencies"]
            .as_array()
            .unwrap()
            .iter()
            .any(|d| d["name"] == "csm-core"),
        "csm-lab is built on csm-core"
    );
}

/// The checkers themselves, on a scratch tree: an upward use and a circle are reported, with
/// multi-line groups, `super::` and nested groups understood.
#[test]
fn the_checks_see_an_upward_import_and_a_circle() {
    let dir = std::env::temp_dir().join(format!("csm-lab-layers-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("config")).unwrap();
    std::fs::create_dir_all(dir.join("commands/sweep")).unwrap();
    std::fs::write(
        dir.join("config/x.rs"),
        "use crate::error::Error;\n// crate::report in a comment\nuse crate::{\n    output::Exporter,\n    presets::{a, b},\n};\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("commands/sweep/mod.rs"),
        "use self::rank::Choice;\npub struct SweepResult;\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("commands/sweep/rank.rs"),
        "use super::SweepResult;\nuse super::grid::Grid;\n",
    )
    .unwrap();
    std::fs::write(dir.join("commands/sweep/grid.rs"), "pub struct Grid;\n").unwrap();
    let found: Vec<(usize, Vec<String>)> = uses(&dir, &[])
        .into_iter()
        .filter(|u| u.file == "config/x.rs")
        .map(|u| (u.line, u.to))
        .collect();
    let p = |s: &str| s.split("::").map(str::to_string).collect::<Vec<_>>();
    assert_eq!(
        found,
        vec![
            (1, p("error::Error")),
            (3, p("output::Exporter")),
            (3, p("presets::a")),
            (3, p("presets::b"))
        ]
    );
    let problems = layer_problems(&dir);
    let circles = circles(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(
        problems,
        vec!["config/x.rs:3: `config` uses `presets`, a layer above it".to_string(); 2]
    );
    assert_eq!(circles.len(), 1, "{circles:?}");
    assert!(
        circles[0].starts_with("commands/sweep: mod → rank (commands/sweep/mod.rs:1), rank → mod"),
        "{circles:?}"
    );
}
