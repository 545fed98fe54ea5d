//! Bugs the property tests (tests/prop_*.rs) and the bench found, one test each.

use crate::common;

use common::{config, with};
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::error::ConfigError;
use csm_lab::{Config, Error};

fn rejected(text: &str) -> String {
    match Config::from_toml_str(text, "t.toml", None) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Yaw and orbit paths were rejected once the camera had turned by 90 degrees: a check meant
/// for pitching over the top also fired when the right axis merely turned.
#[test]
fn a_full_orbit_and_a_full_yaw_are_valid_motions() {
    for path in ["orbit", "yaw"] {
        let text = with(&[
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", "step = 2.0"),
            ("motion.frames", "frames = 200"),
        ]);
        let c = config(&text);
        let poses = c.camera_path().unwrap();
        assert_eq!(poses.len(), 200);
        // 180 frames of 2 degrees is a whole turn: back to the start.
        let d = (poses[180].forward - poses[0].forward).length();
        assert!(d < 1e-9, "{path}: {d}");
        assert!(analyze(&c, &AnalysisOptions::summary_only()).summary.shimmer_snapped < 1e-9);
    }
    // Pitching over the top is still an error.
    let text = with(&[
        ("motion.path", "path = \"pitch\""),
        ("motion.step", "step = 2.0"),
        ("motion.frames", "frames = 200"),
    ]);
    assert!(rejected(&text).contains("motion.step"));
}

/// Without scene fitting, a shadow distance shorter than the near plane gave a reversed split
/// range and the aggregates panicked (f64::clamp with min > max).
#[test]
fn a_shadow_distance_before_the_near_plane_needs_no_cascades() {
    let text = with(&[
        ("camera.near", "near = 9.0"),
        ("shadow.max_distance", "max_distance = 8.3"),
        ("shadow.fit_depth_to_scene", "fit_depth_to_scene = false"),
    ]);
    let a = analyze(&config(&text), &AnalysisOptions::full());
    assert!(!a.summary.cascades_needed);
    assert!(a.rig().is_none());
}

/// fov_y_deg = 2.2e-308 passed "strictly between 0 and 180"; tan(fov/2) underflowed and the
/// aliasing became infinite.
#[test]
fn a_vanishing_field_of_view_is_a_config_error() {
    let msg = rejected(&with(&[("camera.fov_y_deg", "fov_y_deg = 2.2250738585072014e-308")]));
    assert!(msg.contains("camera.fov_y_deg") && msg.contains("0.001"), "{msg}");
    let msg = rejected(&with(&[("camera.fov_y_deg", "fov_y_deg = 179.9999")]));
    assert!(msg.contains("camera.fov_y_deg") && msg.contains("179.999"), "{msg}");
    for ok in ["0.001", "1.0", "179.0", "179.999"] {
        config(&with(&[("camera.fov_y_deg", &format!("fov_y_deg = {ok}"))]));
    }
}

/// near = 2.2e-308 with far = 1000 overflowed (far/near)^(i/M) in the split formula and the
/// analysis panicked.
#[test]
fn a_depth_ratio_beyond_1e12_is_a_config_error() {
    let msg = rejected(&with(&[("camera.near", "near = 2.2250738585072014e-308")]));
    assert!(msg.contains("camera.near") && msg.contains("1e12"), "{msg}");
    // The stress battery's widest range is fine.
    let c = config(&with(&[
        ("camera.near", "near = 1e-4"),
        ("camera.far", "far = 1e6"),
        ("shadow.max_distance", "max_distance = 1e6"),
    ]));
    let a = analyze(&c, &AnalysisOptions::full());
    assert!(a.summary.max_aliasing.is_finite() && a.summary.shimmer_snapped < 1e-9);
}

/// A strafe of -1.26e305 units per frame turned the shimmer metrics into NaN (and then an
/// "internal error" when writing); coordinates beyond 1e9 could do the same.
#[test]
fn positions_and_paths_beyond_1e9_world_units_are_config_errors() {
    let msg = rejected(&with(&[("motion.step", "step = -1.2570138439299002e305")]));
    assert!(msg.contains("motion.step") && msg.contains("1e9"), "{msg}");
    // 60 frames of 1.7e7 is 1.0e9: allowed; of 1.8e7 is not.
    config(&with(&[("motion.step", "step = 1.69e7")]));
    assert!(rejected(&with(&[("motion.step", "step = 1.8e7")])).contains("motion.step"));
    // Rotations take any finite step.
    config(&with(&[
        ("motion.path", "path = \"yaw\""),
        ("motion.step", "step = 1e300"),
    ]));
    for (key, line) in [
        ("camera.position", "position = [2e9, 10.0, 0.0]"),
        ("camera.target", "target = [0.0, -1e10, -50.0]"),
        ("scene.min", "min = [-1e300, 0.0, -200.0]"),
        ("scene.max", "max = [200.0, 40.0, 1e100]"),
        ("camera.far", "far = 1e12"),
    ] {
        let msg = rejected(&with(&[(key, line)]));
        assert!(msg.contains(key) && msg.contains("1e9"), "{msg}");
    }
    // A path file row far away.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("p.csv");
    std::fs::write(&csv, "px,py,pz,tx,ty,tz\n0,10,0,0,0,-50\n0,10,5e9,0,0,-50\n").unwrap();
    let text = with(&[
        ("motion.path", "path = \"file\""),
        ("motion.file", &format!("file = {:?}", csv.display().to_string())),
    ]);
    match Config::from_toml_str(&text, "t.toml", None) {
        Err(e @ Error::Config(ConfigError::Invalid { .. })) => {
            let msg = e.to_string();
            assert!(msg.contains("motion.file") && msg.contains("row 2"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
}

/// The under-sampled share is a fraction: the three.js preset at its defaults on the default
/// scene used to report 1.0000000000000002 (per-cascade lengths summing one ulp over the range).
#[test]
fn the_undersampled_fraction_never_exceeds_one() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
    let choice = csm_lab::presets::PresetChoice {
        name: Some(csm_lab::presets::parse_flag("--preset", "threejs").unwrap()),
        engine_defaults: true,
        ..Default::default()
    };
    let config = csm_lab::Config::load_with_preset(&path, &choice).unwrap();
    let a = csm_lab::analyze(&config, &csm_lab::AnalysisOptions::summary_only());
    assert_eq!(a.summary.undersampled_fraction, 1.0);
}

/// The bundled default scene moved 1e8 units along +x, in binary32, with the given fit.
fn far_f32(fit: &str) -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let text = text
        .split("[sweep]")
        .next()
        .unwrap()
        .replace("frames = 240", "frames = 60");
    let text = text.replace("[scene]\n", "[scene]\nworld_offset = [1e8, 0.0, 0.0]\n");
    let text = text.replace("[shadow]\n", "[shadow]\nprecision = \"f32\"\n");
    text.replace("fit = \"sphere\"", &format!("fit = \"{fit}\""))
        .replace("cascades = 4", "cascades = 3")
        .replace("lambda = 0.75", "lambda = 1.0")
        .replace("resolution = 2048", "resolution = 512")
}

/// `sweep --fit aabb` on an f32 scene far from the origin applied the fit after validation,
/// skipped the binary32 range check that `analyze` makes, and ended in "internal error:
/// shimmer_snapped is not finite". Sweep points are now built by validating constructors.
#[test]
fn sweeping_to_a_fit_binary32_cannot_hold_is_refused_naming_the_key_before_any_work() {
    use csm_lab::commands::sweep::grid::{
        parse_cascades_spec, parse_fit_spec, parse_lambda_spec, parse_resolution_spec, Grid,
    };
    use csm_lab::commands::sweep::run::run;
    use csm_lab::config::sweep_spec::SweepAxes;
    // analyze refuses the AABB version of the file outright.
    let why = rejected(&far_f32("aabb"));
    assert!(why.contains("shadow.precision") && why.contains("collapses"), "{why}");
    // The sphere version is fine, and a sweep of it to the AABB fit is refused the same way.
    let base = config(&far_f32("sphere"));
    let overrides = SweepAxes {
        lambda: Some(parse_lambda_spec("1").unwrap()),
        cascades: Some(parse_cascades_spec("3").unwrap()),
        resolution: Some(parse_resolution_spec("512").unwrap()),
        fit: Some(parse_fit_spec("aabb").unwrap()),
        split_range: None,
        knob: None,
        distance: None,
        sun_azimuth: None,
        sun_elevation: None,
        light_update: None,
        update_every: None,
    };
    let grid = Grid::resolve(&base, &overrides).unwrap();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let err = run(&base, &grid, Some(1), &|| {
        done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap_err()
    .to_string();
    assert!(err.contains("shadow.precision") && err.contains("collapses"), "{err}");
    assert!(!err.contains("internal error"), "{err}");
    assert_eq!(done.into_inner(), 0, "no configuration may be analysed");
    // The constructor itself refuses it, and accepts the fit the file was validated with.
    assert!(base.with_fit(csm_lab::config::Fit::Aabb).is_err());
    assert!(base.with_fit(csm_lab::config::Fit::Sphere).is_ok());
}

/// `precision::along_path` indexed the probe list per cascade and panicked on an empty one,
/// which the f64 walk accepted. Every path model now shares one walk.
#[test]
fn an_empty_probe_list_is_measured_by_every_path_model() {
    use csm_core::precision;
    use csm_core::rig_path;
    use csm_core::scene::SnapSpace;
    use csm_core::shimmer::ShimmerOptions;
    let opts = ShimmerOptions {
        cell_flips: true,
        probe_drift: true,
        frame_rows: true,
    };
    // csm-lab's sphere and box fits (fixed basis), Filament (basis follows the camera),
    // LearnOpenGL (a look-at basis per cascade, selection beyond the fitted slices).
    let texts = [
        with(&[]),
        with(&[("shadow.fit", "fit = \"aabb\"")]),
        with(&[("shadow.preset", "preset = \"filament\"")]),
        with(&[("shadow.preset", "preset = \"learnopengl\"")]),
    ];
    for text in &texts {
        let c = config(text);
        let rig = csm_lab::analysis::rig(&c).unwrap();
        let poses = c.camera_path().unwrap();
        for snapped in [true, false] {
            let r = rig_path::along_path(&rig, &poses, &[], snapped, opts);
            assert!(r.stats.rms.is_finite() && r.stats.max.is_finite());
            for space in [SnapSpace::World, SnapSpace::CameraRelative] {
                let e = precision::along_path(&rig, &poses, &[], space, snapped, opts);
                assert!(e.path.stats.rms.is_finite());
                assert_eq!(e.lookup.max, 0.0);
            }
        }
        let (s, u) = rig_path::along_path_both(&rig, &poses, &[], opts);
        assert!(s.stats.rms.is_finite() && u.stats.rms.is_finite());
    }
}
