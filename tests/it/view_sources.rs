//! Where views come from and their checks, as a user meets them: the errors of `[views]` and
//! `[light] from_gltf`, the inside-geometry error and the no-receiver warning naming the view,
//! and `plan.png` (docs/view-sources.md).

use std::path::Path;
use std::process::{Command, Output};

use crate::common::{with, BASE};

fn analyze(dir: &Path, text: &str) -> Output {
    let cfg = dir.join("scene.toml");
    std::fs::write(&cfg, text).unwrap();
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(["analyze", cfg.to_str().unwrap(), "--quiet", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// BASE with a ground, one box 30 x 20 x 30 and the given extra text.
fn scene(extra: &str) -> String {
    with(&[("scene.ground", "ground = 0.0")])
        + "\n[[scene.box]]\nmin = [-40.0, 0.0, -90.0]\nmax = [-10.0, 20.0, -60.0]\n"
        + extra
}

fn rejected(text: &str, fragments: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(dir.path(), text);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for f in fragments {
        assert!(err.contains(f), "missing {f:?} in: {err}");
    }
    assert!(!dir.path().join("out").exists(), "nothing written on an error");
}

#[test]
fn a_camera_inside_a_box_is_an_error_naming_the_view_and_the_key() {
    let text = scene("").replace("position = [0.0, 10.0, 0.0]", "position = [-25.0, 10.0, -75.0]");
    rejected(
        &text,
        &["camera.position", "view \"camera\"", "inside geometry", "odd number"],
    );
}

#[test]
fn a_view_that_sees_no_receiver_is_a_warning_and_the_run_goes_on() {
    let text = scene("").replace("target = [0.0, 0.0, -50.0]", "target = [0.0, 60.0, -1.0]");
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(dir.path(), &text);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning:") && err.contains("view \"camera\" sees no receiver"),
        "{err}"
    );
    // The default view sees the lit ground: no warning.
    let out = analyze(dir.path(), &scene(""));
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));
}

#[test]
fn views_keys_are_checked_with_their_names() {
    rejected(
        &scene("[views]\nfrom_gltf = true\n"),
        &["views.from_gltf", "scene.gltf", "scene.toml:"],
    );
    rejected(&scene("[views]\nevery = 2\n"), &["views.every", "from_path"]);
    rejected(&scene("[views]\nseed = 2\n"), &["views.seed", "views.sample"]);
    rejected(&scene("[views]\nsample = 0\n"), &["views.sample"]);
    rejected(
        &scene("[views]\nsample = 3\npitch_deg = [10.0, -10.0]\n"),
        &["views.pitch_deg", "lo <= hi"],
    );
    rejected(&scene("[views]\nfrom_path = 3\n"), &["views.from_path", "true"]);
    rejected(&scene("[views]\nfrom_gltf_typo = true\n"), &["from_gltf_typo"]);
    // Without geometry there is nothing to stand on.
    rejected(&format!("{BASE}\n[views]\nsample = 3\n"), &["views.sample", "geometry"]);
    // A light from a glTF needs one, and not with a direction.
    rejected(
        &scene("").replace("direction = [-0.4, -1.0, -0.3]", "from_gltf = true"),
        &["light.from_gltf", "scene.gltf"],
    );
    rejected(
        &scene("").replace(
            "direction = [-0.4, -1.0, -0.3]",
            "direction = [-0.4, -1.0, -0.3]\nfrom_gltf = true",
        ),
        &["light.from_gltf", "not both"],
    );
}

#[test]
fn a_path_file_with_no_rows_is_an_error_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("walk.csv"), "px,py,pz,tx,ty,tz\n").unwrap();
    let out = analyze(dir.path(), &scene("[views]\nfrom_path = \"walk.csv\"\n"));
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("views.from_path") && err.contains("no rows"), "{err}");
}

#[test]
fn a_gltf_without_cameras_is_an_error_naming_views_from_gltf() {
    let dir = tempfile::tempdir().unwrap();
    let village = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/village.gltf");
    std::fs::copy(village, dir.path().join("village.gltf")).unwrap();
    let text = scene("[views]\nfrom_gltf = true\n").replace("[scene]\n", "[scene]\ngltf = \"village.gltf\"\n");
    let out = analyze(dir.path(), &text);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("views.from_gltf") && err.contains("has none"), "{err}");
}

/// The centre of the pixels of exactly `colour` left of `right` (the dot of a view: its fill is
/// the only place that colour is drawn unblended), in PNG pixels.
fn centroid(png: &[u8], colour: [u8; 3], right: u32) -> (f64, f64) {
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for y in 0..info.height {
        for x in 0..right.min(info.width) {
            let o = ((y * info.width + x) * 3) as usize;
            if buf[o..o + 3] == colour {
                sx += f64::from(x);
                sy += f64::from(y);
                n += 1.0;
            }
        }
    }
    assert!(n > 50.0, "the dot has {n} pixels");
    (sx / n, sy / n)
}

#[test]
fn plan_png_puts_the_camera_where_it_stands_with_x_right_and_minus_z_up() {
    // The plan is written with geometry, as a 1000 x 860 PNG (its own size, the size a page shows it); the dot of the one view moves
    // across the page as the camera moves: +x to the right, -z up, linearly and with one scale.
    let dot = [0u8, 114, 178];
    let at = |x: f64, z: f64| {
        let dir = tempfile::tempdir().unwrap();
        let text = scene("")
            .replace(
                "position = [0.0, 10.0, 0.0]",
                &format!("position = [{x:?}, 10.0, {z:?}]"),
            )
            .replace(
                "target = [0.0, 0.0, -50.0]",
                &format!("target = [{x:?}, 0.0, {:?}]", z + 50.0),
            );
        let out = analyze(dir.path(), &text);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let png = std::fs::read(dir.path().join("out/plan.png")).unwrap();
        assert_eq!(&png[16..24], &[0, 0, 0x03, 0xe8, 0, 0, 0x03, 0x5c], "1000 x 860");
        centroid(&png, dot, 770)
    };
    let (o, right, up) = (at(0.0, 0.0), at(100.0, 0.0), at(0.0, -100.0));
    let (left, down) = (at(-100.0, 0.0), at(0.0, 100.0));
    // Right and left of the centre by the same distance; up and down likewise.
    assert!(right.0 - o.0 > 50.0 && (right.1 - o.1).abs() < 0.5, "{o:?} {right:?}");
    assert!(
        ((right.0 - o.0) - (o.0 - left.0)).abs() < 0.75,
        "{left:?} {o:?} {right:?}"
    );
    assert!(o.1 - up.1 > 50.0 && (up.0 - o.0).abs() < 0.5, "{o:?} {up:?}");
    assert!(((o.1 - up.1) - (down.1 - o.1)).abs() < 0.75, "{up:?} {o:?} {down:?}");
    // One scale on both axes.
    assert!(((right.0 - o.0) - (o.1 - up.1)).abs() < 0.75, "{o:?} {right:?} {up:?}");
    // Without geometry there is no plan.
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(dir.path(), BASE);
    assert_eq!(out.status.code(), Some(0));
    assert!(!dir.path().join("out/plan.png").exists());
}
