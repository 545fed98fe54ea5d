//! Shared helpers for the integration tests.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::Path;

use csm_lab::Config;

/// The default outdoor scene as text, so tests can edit one line at a time.
pub const BASE: &str = r#"
[camera]
position = [0.0, 10.0, 0.0]
target = [0.0, 0.0, -50.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 60.0
near = 0.1
far = 1000.0

[screen]
width = 1920
height = 1080

[light]
direction = [-0.4, -1.0, -0.3]

[scene]
min = [-200.0, 0.0, -200.0]
max = [200.0, 40.0, 200.0]

[shadow]
max_distance = 150.0
cascades = 4
lambda = 0.75
resolution = 2048
fit = "sphere"
snap = true
fit_depth_to_scene = true

[motion]
path = "strafe"
frames = 60
step = 0.05
"#;

/// BASE with `key = ...` lines replaced (keys must be unique in BASE) or appended to a table.
pub fn with(edits: &[(&str, &str)]) -> String {
    let mut text = BASE.to_string();
    for (key, line) in edits {
        let (table, name) = key.split_once('.').unwrap();
        let mut out = Vec::new();
        let mut current = String::new();
        let mut done = false;
        for l in text.lines() {
            let t = l.trim();
            if t.starts_with('[') {
                if current == table && !done {
                    out.push(line.to_string());
                    done = true;
                }
                current = t.trim_matches(|c| c == '[' || c == ']').to_string();
            }
            if current == table && (t.starts_with(&format!("{name} =")) || t.starts_with(&format!("{name}="))) {
                if !done {
                    out.push(line.to_string());
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
            out.push(line.to_string());
        }
        text = out.join("\n");
        text.push('\n');
    }
    text
}

pub fn config(text: &str) -> Config {
    Config::from_toml_str(text, "test.toml", None).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Every regular file directly in `dir`: name → bytes.
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_file())
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// A CSV file as its header and its rows of cells.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

/// Standard base64 decoding (the page's data URIs), written here.
pub fn unbase64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let mut out = Vec::new();
    for chunk in s.as_bytes().chunks(4) {
        let n = chunk.iter().take_while(|c| **c != b'=').count();
        let mut v = 0u32;
        for (i, c) in chunk.iter().enumerate() {
            v |= u32::from(if i < n { val(*c) } else { 0 }) << (18 - 6 * i);
        }
        for i in 0..n - 1 {
            out.push((v >> (16 - 8 * i)) as u8);
        }
    }
    out
}
