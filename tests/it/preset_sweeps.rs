//! `sweep --preset P` on every bundled config succeeds and writes every file, including the
//! presets where nothing is acceptable (`unity-sample`, `learnopengl`): the recommendation
//! then says why nothing qualified and which configuration comes closest. Each writes and
//! prints `recommendation.<engine>.txt`.

use std::path::Path;
use std::process::Command;

const PRESETS: [&str; 11] = [
    "dart",
    "threejs",
    "unity-sample",
    "eevee",
    "learnopengl",
    "bevy",
    "godot",
    "unreal",
    "unity",
    "unity-urp",
    "filament",
];

const FILES: [&str; 12] = [
    "sweep.csv",
    "recommendation.json",
    "report.html",
    "report.md",
    "heatmap.svg",
    "heatmap.png",
    "density_lambda.svg",
    "density_lambda.png",
    "shimmer_sweep.svg",
    "shimmer_sweep.png",
    "pareto.svg",
    "pareto.png",
];

#[test]
fn every_preset_sweeps_every_bundled_config_and_writes_every_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    for scene in ["default", "indoor", "open_world", "top_down"] {
        for p in PRESETS {
            let out = dir.path().join(format!("{scene}-{p}"));
            let o = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
                .args([
                    "sweep",
                    &format!("configs/{scene}.toml"),
                    "--preset",
                    p,
                    "--quiet",
                    "--out",
                ])
                .arg(&out)
                .current_dir(root)
                .output()
                .unwrap();
            assert_eq!(
                o.status.code(),
                Some(0),
                "{scene} {p}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            for f in FILES {
                let len = std::fs::metadata(out.join(f)).map(|m| m.len()).unwrap_or(0);
                assert!(len > 0, "{scene} {p}: {f} missing or empty");
            }
            let rec: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.join("recommendation.json")).unwrap()).unwrap();
            let stdout = String::from_utf8_lossy(&o.stdout);
            match rec.get("recommended") {
                Some(_) => assert!(rec.get("no_recommendation").is_none()),
                None => {
                    let none = &rec["no_recommendation"];
                    assert!(none["why"].as_str().unwrap().starts_with("Nothing qualifies"), "{none}");
                    assert!(none.get("closest").is_some(), "{scene} {p}: {none}");
                    assert!(stdout.contains("Closest:"), "{stdout}");
                }
            }
            // The engine's own settings: written, and printed last on stdout; the closest
            // setting says that it is not recommended.
            let text = std::fs::read_to_string(out.join(format!("recommendation.{p}.txt"))).unwrap();
            assert!(stdout.ends_with(&text), "{scene} {p}: {stdout}");
            assert_eq!(
                text.contains("NOT RECOMMENDED"),
                rec.get("recommended").is_none(),
                "{scene} {p}: {text}"
            );
            // A preset never prints a fit it does not have.
            let line = stdout.lines().find(|l| l.starts_with("recommended")).unwrap();
            assert!(
                !line.contains("sphere fit") && !line.contains("aabb fit"),
                "{scene} {p}: {line}"
            );
        }
    }
}
