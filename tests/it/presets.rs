//! Engine presets against the reference split vectors of docs/presets.md, hand computations
//! of each split rule, the reference window sizes, the snapping behaviour each engine is known
//! for, the Bevy coverage miss and the three.js fixed light depth range.

use csm_core::cascades::{LightPose, Rig};
use csm_core::fitting::{corner_average_sphere, minimal_sphere, slice_diameter};
use csm_core::geometry::{CameraPose, Lens, LightBasis};
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::config::Config;
use csm_lab::presets::engines::{
    bevy::*, dart::*, eevee::*, filament::*, godot::*, learnopengl::*, threejs::*, unity::*, unreal::*,
};
use csm_lab::presets::*;
use glam::{DQuat, DVec3};

/// A scene without `[shadow]` settings, so every preset runs at its defaults unless `extra`
/// (appended at the end) says otherwise.
fn scene(motion: &str, extra: &str) -> String {
    format!(
        r#"
[camera]
position = [3.0, 10.0, -7.0]
target = [3.0, 0.0, -57.0]
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
[motion]
{motion}
{extra}
"#
    )
}

fn load(text: &str) -> Config {
    Config::from_toml_str(text, "test.toml", None).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn load_err(text: &str) -> String {
    match Config::from_toml_str(text, "test.toml", None) {
        Ok(_) => panic!("expected an error for\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn preset_config(name: &str, shadow: &str, tables: &str) -> Config {
    load(&scene(
        "path = \"strafe\"\nframes = 40\nstep = 0.05",
        &format!("[shadow]\npreset = \"{name}\"\n{shadow}\n{tables}"),
    ))
}

/// The preset's knobs at their defaults, resolved from a config.
fn default_knobs(name: &str) -> Knobs {
    preset_config(name, "", "").shadow.preset.unwrap().knobs.clone()
}

fn assert_close(got: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: {got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= tol, "{what}: {got:?} vs {want:?} (tolerance {tol})");
    }
}

fn fitted_near(l: &Layout) -> Vec<f64> {
    l.fitted.iter().map(|s| s.0).collect()
}

fn fitted_far(l: &Layout) -> Vec<f64> {
    l.fitted.iter().map(|s| s.1).collect()
}

/// Boundaries of a contiguous layout: near of each slice, then the last far.
fn bounds(l: &Layout) -> Vec<f64> {
    let mut b = fitted_near(l);
    b.push(l.fitted.last().unwrap().1);
    assert_eq!(b, l.selection, "contiguous layouts select what they fit");
    b
}

// ---------------------------------------------------------------------------------------------
// Split vectors at the defaults: the reference vectors of docs/presets.md (printed precision) and the exact rule
// ---------------------------------------------------------------------------------------------

#[test]
fn bevy_defaults_give_the_reference_far_and_near_bounds() {
    let c = preset_config("bevy", "", "");
    assert_eq!(
        (c.shadow.cascades, c.shadow.resolution, c.shadow.max_distance),
        (4, 2048, 150.0)
    );
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 150.0, 0.1, 1000.0);
    assert_close(&fitted_far(&l), &[10.0, 24.662, 60.822, 150.0], 5e-4, "far bounds");
    assert_close(&fitted_near(&l), &[0.1, 8.0, 19.730, 48.658], 5e-4, "near bounds");
    // Exact: far_i = 10 * 15^(i/3), near_i = 0.8 * far_{i-1}.
    let far: Vec<f64> = (0..4).map(|i| 10.0 * 15f64.powf(i as f64 / 3.0)).collect();
    assert_close(&fitted_far(&l), &far, 1e-12, "far bounds (rule)");
    assert_close(
        &fitted_near(&l),
        &[0.1, 0.8 * far[0], 0.8 * far[1], 0.8 * far[2]],
        1e-12,
        "near bounds (rule)",
    );
    // Selection: everything nearer than far_0 reads cascade 0; the blend band reads the coarser.
    assert_eq!(l.selection[0], f64::NEG_INFINITY);
    assert_close(
        &l.selection[1..],
        &[0.8 * far[0], 0.8 * far[1], 0.8 * far[2], 150.0],
        1e-12,
        "selection",
    );
}

#[test]
fn godot_defaults_give_the_reference_splits() {
    let c = preset_config("godot", "", "");
    assert_eq!((c.shadow.cascades, c.shadow.max_distance), (4, 100.0));
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 100.0, 0.05, 200.0);
    assert_close(&bounds(&l), &[0.05, 10.045, 20.040, 50.025, 100.0], 1e-9, "splits");
}

#[test]
fn filament_default_positions_and_practical_helper_give_the_reference_splits() {
    let c = preset_config("filament", "", "");
    assert_eq!((c.shadow.cascades, c.shadow.resolution), (1, 1024));
    // shadowFar 0: the camera's far plane.
    assert_eq!(c.shadow.max_distance, 1000.0);
    let k = c.shadow.preset.unwrap().knobs.clone();
    let l = layout(&k, 4, 100.0, 0.1, 1000.0);
    assert_close(
        &bounds(&l),
        &[0.1, 12.588, 25.075, 50.050, 100.0],
        5e-4,
        "default positions",
    );
    let exact: Vec<f64> = [0.0, 0.125, 0.25, 0.5, 1.0].iter().map(|p| 0.1 + 99.9 * p).collect();
    assert_close(&bounds(&l), &exact, 1e-12, "default positions (rule)");
    let practical = FilamentKnobs {
        split_mode: FilamentSplit::Practical,
        lambda: 0.5,
        split_positions: [0.125, 0.25, 0.5],
    };
    let p = filament_positions(&practical, 4, 0.1, 100.0);
    assert_close(&p, &[0.127, 0.265, 0.464], 5e-4, "practical helper");
    let exact: Vec<f64> = (1..4)
        .map(|c| {
            let u = c as f64 / 4.0;
            0.5 * (0.1 * 1000f64.powf(u) - 0.1) / 99.9 + 0.5 * u
        })
        .collect();
    assert_close(&p, &exact, 1e-12, "practical helper (rule)");
}

#[test]
fn unreal_defaults_give_the_reference_splits_and_transition_ends() {
    let c = preset_config("unreal", "", "");
    assert_eq!((c.shadow.cascades, c.shadow.max_distance), (3, 200.0));
    let l = layout(&c.shadow.preset.unwrap().knobs, 3, 200.0, 0.1, 1000.0);
    assert_close(&l.selection, &[0.1, 15.477, 61.608, 200.0], 5e-4, "splits");
    assert_close(
        &fitted_far(&l),
        &[17.015, 66.221, 200.0],
        5e-4,
        "far ends with transition",
    );
    // Exact: weights 1, 3, 9 of 13; far ends extended by 10 % of the cascade's own length.
    let s1 = 0.1 + 199.9 / 13.0;
    let s2 = 0.1 + 4.0 * 199.9 / 13.0;
    assert_close(&l.selection, &[0.1, s1, s2, 200.0], 1e-12, "splits (rule)");
    assert_close(
        &fitted_far(&l),
        &[s1 + 0.1 * (s1 - 0.1), s2 + 0.1 * (s2 - s1), 200.0],
        1e-12,
        "far ends (rule)",
    );
    assert_close(&fitted_near(&l), &[0.1, s1, s2], 1e-12, "near ends");
}

#[test]
fn threejs_practical_breaks_give_the_reference_far_ends() {
    let c = preset_config("threejs", "", "");
    assert_eq!(
        (c.shadow.cascades, c.shadow.resolution, c.shadow.max_distance),
        (3, 2048, 1e5)
    );
    let k = c.shadow.preset.unwrap().knobs.clone();
    let exact = |n: f64, f: f64, m: usize| -> Vec<f64> {
        (1..=m)
            .map(|i| {
                if i == m {
                    return f;
                }
                let u = i as f64 / m as f64;
                0.5 * (n + (f - n) * u) + 0.5 * n * (f / n).powf(u)
            })
            .collect()
    };
    // F = min(camera far, maxFar).
    let l = layout(&k, 4, 1e5, 0.1, 200.0);
    assert_close(
        &fitted_far(&l),
        &[25.372, 52.261, 89.966, 200.0],
        5e-4,
        "n 0.1, F 200, N 4",
    );
    assert_close(&fitted_far(&l), &exact(0.1, 200.0, 4), 1e-9, "n 0.1, F 200, N 4 (rule)");
    assert_eq!(l.fitted[0].0, 0.1, "the first cascade starts at the near plane");
    // r185 selection in the WebGL shader: b (F - n).
    assert_close(
        &l.selection[1..],
        &exact(0.1, 200.0, 4)
            .iter()
            .map(|e| e / 200.0 * 199.9)
            .collect::<Vec<_>>(),
        1e-9,
        "selection",
    );
    let l = layout(&k, 3, 1000.0, 0.1, 5000.0);
    assert_close(&fitted_far(&l), &[167.777, 356.558, 1000.0], 5e-4, "n 0.1, F 1000, N 3");
    assert_close(
        &fitted_far(&l),
        &exact(0.1, 1000.0, 3),
        1e-9,
        "n 0.1, F 1000, N 3 (rule)",
    );
}

#[test]
fn eevee_defaults_give_the_reference_ends_and_fade_starts() {
    let c = preset_config("eevee", "", "");
    assert_eq!(
        (c.shadow.cascades, c.shadow.resolution, c.shadow.max_distance),
        (4, 1024, 200.0)
    );
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 200.0, 0.1, 1000.0);
    assert_close(&fitted_far(&l), &[10.550, 23.588, 53.931, 200.0], 5e-4, "ends");
    assert_close(&fitted_near(&l), &[0.100, 9.505, 22.284, 50.896], 5e-4, "starts");
    let end: Vec<f64> = (1..4)
        .map(|c| {
            let u = c as f64 / 4.0;
            0.8 * 0.1 * 2000f64.powf(u) + 0.2 * (0.1 + 199.9 * u)
        })
        .collect();
    assert_close(&fitted_far(&l), &[end[0], end[1], end[2], 200.0], 1e-12, "ends (rule)");
    let starts = [
        0.1,
        0.9 * end[0] + 0.1 * 0.1,
        0.9 * end[1] + 0.1 * end[0],
        0.9 * end[2] + 0.1 * end[1],
    ];
    assert_close(&fitted_near(&l), &starts, 1e-12, "starts (rule)");
    // The coarser cascade counts in each fade band.
    assert_close(
        &l.selection,
        &[0.1, starts[1], starts[2], starts[3], 200.0],
        1e-12,
        "selection",
    );
}

#[test]
fn unity_and_urp_fractions_give_the_reference_splits() {
    let c = preset_config("unity-urp", "", "");
    assert_eq!(
        (c.shadow.cascades, c.shadow.resolution, c.shadow.max_distance),
        (1, 2048, 50.0)
    );
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 50.0, 0.1, 1000.0);
    assert_close(
        &bounds(&l),
        &[0.1, 3.35, 10.0, 23.35, 50.0],
        1e-9,
        "URP 50 m, 4 cascades",
    );
    let c = preset_config("unity", "", "");
    assert_eq!((c.shadow.cascades, c.shadow.max_distance), (4, 150.0));
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 150.0, 0.1, 1000.0);
    assert_close(
        &bounds(&l),
        &[0.1, 10.05, 30.0, 70.05, 150.0],
        1e-9,
        "built-in 150 m, 4 cascades",
    );
}

#[test]
fn unity_sample_and_learnopengl_give_their_reference_splits() {
    let c = preset_config("unity-sample", "", "");
    assert_eq!((c.shadow.cascades, c.shadow.resolution), (4, 1024));
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 0.0, 0.3, 100.0);
    assert_close(&bounds(&l), &[0.3, 7.0, 20.3, 47.0, 100.0], 1e-9, "unity-sample");

    let c = preset_config("learnopengl", "", "");
    assert_eq!(c.shadow.cascades, 3);
    let l = layout(&c.shadow.preset.unwrap().knobs, 3, 0.0, 1.0, 150.0);
    assert_eq!(l.fitted, vec![(5.0, 15.0), (15.0, 30.0), (30.0, 100.0)]);
    // Off by one: depth <= 5 reads cascade 0 ([5, 15]), (5, 15] cascade 1, beyond 15 cascade 2.
    assert_eq!(
        clip_selection(&l.selection, 1.0, 150.0).unwrap(),
        vec![1.0, 5.0, 15.0, 150.0]
    );
}

#[test]
fn dart_defaults_give_the_practical_reference_splits() {
    let c = preset_config("dart", "", "");
    assert_eq!((c.shadow.cascades, c.shadow.max_distance), (4, 1000.0));
    let l = layout(&c.shadow.preset.unwrap().knobs, 4, 200.0, 0.1, 1000.0);
    // reference, range [0.1, 200], lambda 0.5.
    assert_close(&bounds(&l), &[0.1, 25.372, 52.261, 89.966, 200.0], 5e-4, "lambda 0.5");
    // The last boundary comes from the formula at ratio 1, as in the reference code: far up to rounding.
    assert!((bounds(&l)[4] - 200.0).abs() < 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Split vectors at non-default settings: hand computation from each rule
// ---------------------------------------------------------------------------------------------

#[test]
fn non_default_splits_follow_each_rule() {
    // Bevy: 3 cascades, first 5, max 1000, overlap 0.5, minimum 0.5; and one cascade.
    let k = Knobs::Bevy(BevyKnobs {
        minimum_distance: 0.5,
        first_cascade_far_bound: 5.0,
        overlap_proportion: 0.5,
        bounds: None,
    });
    let l = layout(&k, 3, 1000.0, 0.1, 2000.0);
    let mid = 5.0 * 200f64.sqrt();
    assert_close(&fitted_far(&l), &[5.0, mid, 1000.0], 1e-9, "bevy far");
    assert_close(&fitted_near(&l), &[0.5, 2.5, 0.5 * mid], 1e-9, "bevy near");
    let l = layout(&k, 1, 80.0, 0.1, 2000.0);
    assert_eq!(l.fitted, vec![(0.5, 80.0)]);

    // Godot: PSSM2 with split_1 = 0.3 on [0.1, min(500, 200)]; PSSM4 with blend_splits.
    let k = Knobs::Godot(GodotKnobs {
        splits: [0.3, 0.4, 0.6],
        blend_splits: false,
        pancake_size: 20.0,
    });
    let l = layout(&k, 2, 200.0, 0.1, 500.0);
    assert_close(&bounds(&l), &[0.1, 0.1 + 0.3 * 199.9, 200.0], 1e-9, "godot 2 splits");
    let k = Knobs::Godot(GodotKnobs {
        splits: [0.1, 0.2, 0.5],
        blend_splits: true,
        pancake_size: 20.0,
    });
    let l = layout(&k, 4, 100.0, 1.0, 100.0);
    let d = [1.0, 10.9, 20.8, 50.5, 100.0];
    let want_fitted = vec![(d[0], d[1]), (d[0], d[2]), (d[1], d[3]), (d[2], d[4])];
    for (g, w) in l.fitted.iter().zip(&want_fitted) {
        assert!((g.0 - w.0).abs() < 1e-9 && (g.1 - w.1).abs() < 1e-9, "{:?}", l.fitted);
    }
    assert_close(
        &l.selection,
        &[1.0, 0.9 * d[1], 0.9 * d[2], 0.9 * d[3], 100.0],
        1e-9,
        "godot blend",
    );

    // Filament: uniform helper, 3 cascades on [0.5, 60]; logarithmic helper, 2 on [1, 100].
    let mut fk = FilamentKnobs {
        split_mode: FilamentSplit::Uniform,
        lambda: 0.5,
        split_positions: [0.125, 0.25, 0.5],
    };
    let l = layout(&Knobs::Filament(fk.clone()), 3, 60.0, 0.5, 1000.0);
    assert_close(
        &bounds(&l),
        &[0.5, 0.5 + 59.5 / 3.0, 0.5 + 2.0 * 59.5 / 3.0, 60.0],
        1e-9,
        "filament uniform",
    );
    fk.split_mode = FilamentSplit::Logarithmic;
    let l = layout(&Knobs::Filament(fk), 2, 100.0, 1.0, 1000.0);
    assert_close(&bounds(&l), &[1.0, 10.0, 100.0], 1e-9, "filament log");

    // Unreal: exponent 1 is uniform; exponent 2 weights 1, 2, 4.
    let k = Knobs::Unreal(UnrealKnobs {
        cascade_distribution_exponent: 1.0,
        transition_fraction: 0.2,
    });
    let l = layout(&k, 4, 101.0, 1.0, 1000.0);
    assert_close(&l.selection, &[1.0, 26.0, 51.0, 76.0, 101.0], 1e-9, "unreal exponent 1");
    assert_close(
        &fitted_far(&l),
        &[31.0, 56.0, 81.0, 101.0],
        1e-9,
        "unreal transition 0.2",
    );
    let k = Knobs::Unreal(UnrealKnobs {
        cascade_distribution_exponent: 2.0,
        transition_fraction: 0.0,
    });
    let l = layout(&k, 3, 70.0, 0.0, 1000.0);
    assert_close(&l.selection, &[0.0, 10.0, 30.0, 70.0], 1e-9, "unreal exponent 2");

    // three.js: uniform and logarithmic modes.
    let tk = |mode| {
        Knobs::Threejs(ThreejsKnobs {
            mode,
            light_margin: 200.0,
            light_near: 1.0,
            light_far: 2000.0,
            fade: false,
        })
    };
    let l = layout(&tk(ThreejsMode::Uniform), 2, 101.0, 1.0, 5000.0);
    assert_close(&fitted_far(&l), &[51.0, 101.0], 1e-9, "three.js uniform");
    assert_close(
        &l.selection[1..],
        &[51.0 / 101.0 * 100.0, 100.0],
        1e-9,
        "three.js selection",
    );
    let l = layout(&tk(ThreejsMode::Logarithmic), 2, 1e5, 1.0, 100.0);
    assert_close(&fitted_far(&l), &[10.0, 100.0], 1e-9, "three.js log, F = camera far");

    // EEVEE: lambda 0 and fade 0 on [1, 101]; lambda 1 and fade 0.5 on [1, 1000].
    let ek = |l, fade| {
        Knobs::Eevee(EeveeKnobs {
            cascade_exponent: l,
            fade,
            lamp_position: DVec3::ZERO,
            clip_start: 0.05,
            clip_end: 40.0,
        })
    };
    let l = layout(&ek(0.0, 0.0), 2, 101.0, 1.0, 1000.0);
    assert_eq!(l.fitted, vec![(1.0, 51.0), (51.0, 101.0)]);
    let l = layout(&ek(1.0, 0.5), 3, 5000.0, 1.0, 1000.0);
    assert_close(&fitted_far(&l), &[10.0, 100.0, 1000.0], 1e-9, "eevee log ends");
    assert_close(&fitted_near(&l), &[1.0, 5.5, 55.0], 1e-9, "eevee fade starts");

    // Unity: two cascades at a third; custom four-cascade fractions.
    let k = Knobs::Unity(UnityKnobs {
        cascade2_split: 1.0 / 3.0,
        cascade4_split: [0.1, 0.2, 0.4],
    });
    assert_close(
        &bounds(&layout(&k, 2, 90.0, 0.3, 1000.0)),
        &[0.3, 30.0, 90.0],
        1e-9,
        "unity 2",
    );
    assert_close(
        &bounds(&layout(&k, 4, 100.0, 0.3, 1000.0)),
        &[0.3, 10.0, 20.0, 40.0, 100.0],
        1e-9,
        "unity 4",
    );
    // URP: 2 and 3 cascades at their defaults.
    let k = default_knobs("unity-urp");
    assert_close(
        &bounds(&layout(&k, 2, 80.0, 0.1, 1000.0)),
        &[0.1, 20.0, 80.0],
        1e-9,
        "urp 2",
    );
    assert_close(
        &bounds(&layout(&k, 3, 50.0, 0.1, 1000.0)),
        &[0.1, 5.0, 15.0, 50.0],
        1e-9,
        "urp 3",
    );

    // The unity-sample preset at two other camera ranges.
    let k = default_knobs("unity-sample");
    assert_close(
        &bounds(&layout(&k, 4, 0.0, 1.0, 1000.0)),
        &[1.0, 68.0, 201.0, 468.0, 1000.0],
        1e-9,
        "unity-sample a",
    );
    assert_close(
        &bounds(&layout(&k, 4, 0.0, 0.1, 50.0)),
        &[0.1, 3.45, 10.1, 23.45, 50.0],
        1e-9,
        "unity-sample b",
    );

    // The learnopengl preset with other planes: 2 cascades, and 4.
    let lk = |planes: Vec<f64>| {
        Knobs::LearnOpenGl(LearnOpenGlKnobs {
            planes,
            pad_xy: 2.0,
            pad_z: 10.0,
            light_position: DVec3::ZERO,
        })
    };
    let l = layout(&lk(vec![2.0, 4.0, 8.0]), 0, 0.0, 1.0, 50.0);
    assert_eq!(l.fitted, vec![(2.0, 4.0), (4.0, 8.0)]);
    assert_eq!(clip_selection(&l.selection, 1.0, 50.0).unwrap(), vec![1.0, 2.0, 50.0]);
    let l = layout(&lk(vec![1.0, 10.0, 20.0, 30.0, 40.0]), 0, 0.0, 0.5, 60.0);
    assert_eq!(
        clip_selection(&l.selection, 0.5, 60.0).unwrap(),
        vec![0.5, 1.0, 10.0, 20.0, 60.0]
    );

    // The dart preset: lambda 0 and 1, and the count clamped to 4.
    let dk = |lambda| Knobs::Dart(DartKnobs { lambda });
    assert_close(
        &bounds(&layout(&dk(0.0), 2, 101.0, 1.0, 50.0)),
        &[1.0, 51.0, 101.0],
        1e-9,
        "dart uniform",
    );
    assert_close(
        &bounds(&layout(&dk(1.0), 3, 1000.0, 1.0, 50.0)),
        &[1.0, 10.0, 100.0, 1000.0],
        1e-9,
        "dart log",
    );
    assert_eq!(layout(&dk(0.5), 7, 100.0, 1.0, 50.0).fitted.len(), 4);
}

// ---------------------------------------------------------------------------------------------
// Window sizes
// ---------------------------------------------------------------------------------------------

fn lens(fov_deg: f64, aspect: f64) -> Lens {
    Lens::new(fov_deg.to_radians(), aspect)
}

#[test]
fn bevy_windows_are_the_ceiled_diameters_of_the_reference() {
    let text = scene("", "[shadow]\npreset = \"bevy\"\n").replace("fov_y_deg = 60.0", "fov_y_deg = 45.0");
    let c = load(&text);
    let rig = csm_lab::analysis::rig(&c).unwrap();
    assert_eq!(rig.sphere_side, vec![17.0, 42.0, 103.0, 254.0]);
    let lp = LightPose::new(&rig.light, &c.camera.pose());
    let texel_mm: Vec<f64> = (0..4).map(|i| rig.window(i, &lp, true).texel_size() * 1000.0).collect();
    assert_close(&texel_mm, &[8.301, 20.508, 50.293, 124.023], 5e-4, "texel (mm)");
    // Slack per side from the ceil, in texels, before the floor snap.
    let k2 = rig.lens.k2();
    let slack: Vec<f64> = rig
        .slices
        .iter()
        .zip(&rig.sphere_side)
        .map(|(s, d)| (d - slice_diameter(s.near, s.far, k2)) / 2.0 / (d / 2048.0))
        .collect();
    assert_close(&slack, &[6.16, 7.97, 2.24, 2.16], 5e-3, "slack");
}

#[test]
fn threejs_window_is_the_slice_diameter() {
    let k = default_knobs("threejs");
    let l = layout(&k, 4, 1e5, 0.1, 200.0);
    let ln = lens(60.0, 16.0 / 9.0);
    let rig = rig_for_layout(&k, ln, DVec3::new(-0.4, -1.0, -0.3), 2048, &l, 0.1, 200.0, 1e5).unwrap();
    // reference: 59.758 for [0.1, 25.372] at 60 deg, 16:9; texel 0.029179 at 2048.
    assert!((rig.sphere_side[0] - 59.758).abs() < 5e-4, "{}", rig.sphere_side[0]);
    assert!((rig.sphere_side[0] / 2048.0 - 0.029179).abs() < 5e-7);
    // By hand: max(far-cap diagonal, body diagonal).
    let kk = (ln.tan_h.powi(2) + ln.tan_v.powi(2)).sqrt();
    for (s, side) in rig.slices.iter().zip(&rig.sphere_side) {
        let (n, f) = (s.near, s.far);
        let want = (2.0 * kk * f).max((kk * kk * (f + n).powi(2) + (f - n).powi(2)).sqrt());
        assert!((side - want).abs() < 1e-9 * want);
    }
}

#[test]
fn godot_window_is_the_centroid_sphere_with_one_border_texel() {
    let c = preset_config("godot", "cascades = 1\nmax_distance = 20.0", "").clone();
    let text = scene("", "[shadow]\npreset = \"godot\"\ncascades = 1\nmax_distance = 20.0\n")
        .replace("near = 0.1", "near = 5.0");
    let c2 = load(&text);
    assert_eq!(c.shadow.cascades, 1);
    let rig = csm_lab::analysis::rig(&c2).unwrap();
    assert_eq!((rig.slices[0].near, rig.slices[0].far), (5.0, 20.0));
    // reference: R_avg = 24.71806 for [5, 20] at 60 deg, 16:9; and by hand.
    let ln = lens(60.0, 16.0 / 9.0);
    let r_avg = (ln.k2() * 400.0 + 7.5f64 * 7.5).sqrt();
    assert!((r_avg - 24.71806).abs() < 5e-6);
    assert!((rig.sphere_side[0] - 2.0 * r_avg * 2048.0 / 2046.0).abs() < 1e-9);
    // The round snap in 2-texel steps moves the centre by at most 1 texel: the border absorbs it.
    let lp = LightPose::new(&rig.light, &c2.camera.pose());
    let w = rig.window(0, &lp, true);
    assert_eq!(w.texel_size(), rig.sphere_side[0] / 2048.0);
    assert_eq!(rig.coverage(0, &lp, &w).violations, 0);
}

#[test]
fn unreal_window_is_the_minimal_sphere_with_a_four_texel_border() {
    let text = scene("", "[shadow]\npreset = \"unreal\"\ncascades = 1\nmax_distance = 20.0\n")
        .replace("near = 0.1", "near = 5.0");
    let rig = csm_lab::analysis::rig(&load(&text)).unwrap();
    // reference: R_min = 23.55276 for [5, 20] at 60 deg, 16:9 (far-cap case).
    assert!((rig.sphere_side[0] - 2.0 * 23.55276 * 2048.0 / 2040.0).abs() < 1e-4);
    // Near+far case: fovY 30 deg, aspect 1, [5, 20]: c = 14.2949, R = 9.48606.
    let s = unreal_sphere(5.0, 20.0, &lens(30.0, 1.0));
    assert!(
        (s.centre_depth - 14.2949).abs() < 5e-5 && (s.radius - 9.48606).abs() < 5e-6,
        "{s:?}"
    );
}

#[test]
fn dart_corner_average_costs_the_reference_overhead_over_the_minimal_sphere() {
    let light = DVec3::new(-0.4, -1.0, -0.3);
    let splits = vec![0.1, 5.0, 20.0, 80.0, 200.0];
    for (fov, aspect, ratios) in [
        (60.0, 16.0 / 9.0, [1.08311, 1.04948, 1.04948, 1.03194]),
        (30.0, 1.0, [1.09968, 1.12401, 1.12401, 1.12861]),
    ] {
        let ln = lens(fov, aspect);
        let dart = rig_for_layout(
            &Knobs::Dart(DartKnobs { lambda: 0.5 }),
            ln,
            light,
            2048,
            &Layout::contiguous(splits.clone()),
            0.1,
            1000.0,
            1000.0,
        )
        .unwrap();
        let builtin = Rig::new(
            ln,
            LightBasis::new(light),
            csm_lab::config::Fit::Sphere,
            2048,
            Default::default(),
            splits.clone(),
        );
        for i in 0..4 {
            let r_min = builtin.slices[i].sphere.radius;
            let ratio = dart.sphere_side[i] / (2.0 * r_min);
            assert!((ratio - ratios[i]).abs() < 1e-5, "{fov} deg cascade {i}: {ratio}");
            // Area overhead is the square; against csm-lab's window (half a texel of border).
            let (a, b) = (splits[i], splits[i + 1]);
            let want = corner_average_sphere(a, b, ln.k2()).radius / minimal_sphere(a, b, ln.k2()).radius;
            assert!((ratio - want).abs() < 1e-12);
            let texel_ratio = dart.sphere_side[i] / builtin.sphere_side[i];
            assert!((texel_ratio - ratios[i] * 2047.0 / 2048.0).abs() < 1e-5);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Snapping: stable where the engine is, drifting where it is not
// ---------------------------------------------------------------------------------------------

fn shimmer(name: &str, path: &str, step: f64, tables: &str) -> (f64, f64) {
    let text = scene(
        &format!("path = \"{path}\"\nframes = 30\nstep = {step}"),
        &format!("[shadow]\npreset = \"{name}\"\n{tables}"),
    );
    let a = analyze(&load(&text), &AnalysisOptions::summary_only());
    (a.summary.shimmer_snapped, a.summary.shimmer_unsnapped)
}

#[test]
fn each_preset_snaps_as_its_engine_does_under_strafe_and_yaw() {
    for (name, strafe_stable, yaw_stable) in [
        ("dart", true, true),
        ("threejs", true, true),
        ("eevee", true, true),
        ("bevy", true, true),
        ("godot", true, true),
        ("unreal", true, true),
        ("unity", true, true),
        ("unity-urp", true, true),
        // A basis fixed in the world (+X up reference) and 2-texel fmod snapping.
        ("filament", true, true),
        // No snapping; the window stays on the origin axis (size fixed under strafe only).
        ("unity-sample", true, false),
        // Look-at from a light position: every camera move turns each cascade's basis.
        ("learnopengl", false, false),
    ] {
        for (path, step, stable) in [("strafe", 0.0137, strafe_stable), ("yaw", 0.05, yaw_stable)] {
            let (snapped, unsnapped) = shimmer(name, path, step, "");
            if stable {
                assert!(snapped < 1e-9, "{name} {path}: snapped drift {snapped}");
            } else {
                assert!(snapped > 1e-3, "{name} {path}: expected drift, got {snapped}");
            }
            let snaps = !matches!(name, "unity-sample" | "learnopengl");
            if snaps {
                assert!(unsnapped > 1e-3, "{name} {path}: unsnapped should drift ({unsnapped})");
            } else {
                assert_eq!(snapped, unsnapped, "{name}: no snapping, both modes are the same");
            }
        }
    }
    // Repairing the unity-sample preset's centring makes the (unsnapped) window follow the slice: it drifts.
    let (s, _) = shimmer(
        "unity-sample",
        "strafe",
        0.0137,
        "[unity-sample]\ncentre_on_slice = true",
    );
    assert!(s > 1e-3);
}

/// The per-probe evaluation for bases that follow the camera (the rule Filament used before
/// its fixed +X reference): exactly zero drift and no flips while the basis stays put (strafe),
/// drift and flips once it turns (yaw).
#[test]
fn a_camera_oriented_basis_is_evaluated_probe_by_probe() {
    use csm_core::cascades::BasisRule;
    use csm_core::rig_path::{along_path, probes};
    use csm_core::shimmer::ShimmerOptions;
    let every = ShimmerOptions {
        cell_flips: true,
        probe_drift: true,
        frame_rows: false,
    };
    for (path, stable) in [("strafe", true), ("yaw", false)] {
        let text = scene(
            &format!("path = \"{path}\"\nframes = 20\nstep = 0.05"),
            "[shadow]\npreset = \"filament\"\ncascades = 3",
        );
        let c = load(&text);
        let mut rig = csm_lab::analysis::rig(&c).unwrap();
        rig.scheme.basis = BasisRule::CameraRight;
        assert!(!rig.fixed_basis());
        let poses = c.camera_path().unwrap();
        let pr = probes(&rig, &c.camera.pose(), &c.scene, 128);
        let r = along_path(&rig, &poses, &pr, true, every);
        if stable {
            assert!(r.stats.max < 1e-9, "{path}: {}", r.stats.max);
            assert_eq!(r.stats.cell_flip_rate, Some(0.0));
        } else {
            assert!(r.stats.max > 1e-2, "{path}: {}", r.stats.max);
            assert!(
                r.stats.cell_flip_rate.unwrap() > 0.01,
                "{path}: {:?}",
                r.stats.cell_flip_rate
            );
        }
    }
}

/// Filament's directional shadow basis is a look-to along the light with the world-origin
/// transform's x axis (+X) as the up reference: y is the part of +X perpendicular to the light
/// and x = light x y. It does not turn when the camera yaws (the rule with the camera's right
/// axis as the reference turned it by tens of degrees at 45 degrees of yaw).
#[test]
fn the_filament_window_keeps_its_orientation_when_the_camera_yaws() {
    use csm_core::cascades::{camera_right_basis, BasisRule};
    let c = load(&scene(
        "path = \"yaw\"\nframes = 46\nstep = 1.0",
        "[shadow]\npreset = \"filament\"\ncascades = 4",
    ));
    let rig = csm_lab::analysis::rig(&c).unwrap();
    assert_eq!(rig.scheme.basis, BasisRule::LookToUp(DVec3::X));
    let d = DVec3::new(-0.4, -1.0, -0.3).normalize();
    // Independently: +X with its part along the light removed, and light x y.
    let y = (DVec3::X - d * DVec3::X.dot(d)).normalize();
    let x = d.cross(y);
    let poses = c.camera_path().unwrap();
    assert_eq!(poses.len(), 46);
    let lp0 = LightPose::new(&rig.light, &poses[0]);
    let w0: Vec<_> = (0..4).map(|i| rig.window(i, &lp0, true)).collect();
    for pose in &poses {
        let lp = LightPose::new(&rig.light, pose);
        for (i, w0) in w0.iter().enumerate() {
            let b = rig.basis(i, &lp);
            assert!((b.x - x).length() < 1e-12 && (b.y - y).length() < 1e-12 && (b.z - d).length() < 1e-12);
            // Same texel size and grid orientation in every frame (only the centre moves).
            let w = rig.window(i, &lp, true);
            assert_eq!(w.texel, w0.texel);
            assert_eq!(w.resolution, w0.resolution);
        }
    }
    // The camera-right rule at the last pose (45 degrees of yaw) is turned far from it.
    let last = poses.last().unwrap();
    let first = camera_right_basis(d, poses[0].right).unwrap();
    let turned = camera_right_basis(d, last.right).unwrap();
    let angle = |a: DVec3, b: DVec3| a.dot(b).clamp(-1.0, 1.0).acos().to_degrees();
    assert!((angle(poses[0].right, last.right) - 45.0).abs() < 1e-6);
    let yawed = angle(first.y, turned.y);
    assert!(
        (30.0..50.0).contains(&yawed),
        "camera-right basis turned by {yawed} degrees"
    );
    // The fixed basis and the camera-right one at 45 degrees of yaw are far apart too.
    let apart = angle(y, turned.y);
    assert!(apart > 30.0, "{apart}");
}

/// Filament's near-vertical fallback: with the light within acos(0.999) of +X the up
/// reference becomes (up.z, up.x, up.y) = +Y.
#[test]
fn filament_basis_swaps_its_up_reference_for_a_light_along_x() {
    use csm_core::cascades::look_to_basis;
    for d in [DVec3::X, DVec3::new(1.0, 0.02, -0.01).normalize(), -DVec3::X] {
        let b = look_to_basis(d, DVec3::X).unwrap();
        let y = (DVec3::Y - d * DVec3::Y.dot(d)).normalize();
        assert!((b.y - y).length() < 1e-12, "{d}: {}", b.y);
        assert!((b.x - d.cross(y)).length() < 1e-12);
    }
    // Just outside the cone the +X reference is kept.
    let d = DVec3::new(1.0, 0.1, 0.0).normalize();
    assert!(d.dot(DVec3::X) < 0.999);
    let b = look_to_basis(d, DVec3::X).unwrap();
    assert!((b.y - (DVec3::X - d * d.x).normalize()).length() < 1e-12);
}

#[test]
fn the_eevee_grid_runs_through_the_lamp_and_stays_stable() {
    let text = scene(
        "path = \"orbit\"\nframes = 30\nstep = 0.3",
        "[shadow]\npreset = \"eevee\"\n[eevee]\nlamp_position = [13.37, 42.0, -7.77]",
    );
    let c = load(&text);
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let lamp = rig.light.to_light_xy(DVec3::new(13.37, 42.0, -7.77));
    let lp = LightPose::new(&rig.light, &c.camera.pose());
    for i in 0..rig.cascade_count() {
        let w = rig.window(i, &lp, true);
        // Window edges sit a whole number of texels from the lamp.
        let off = w.min() / w.texel - lamp / w.texel;
        assert!(
            (off.x - off.x.round()).abs() < 1e-6 && (off.y - off.y.round()).abs() < 1e-6,
            "{off}"
        );
    }
    let a = analyze(&c, &AnalysisOptions::summary_only());
    assert!(a.summary.shimmer_snapped < 1e-9 && a.summary.shimmer_unsnapped > 1e-3);
}

// ---------------------------------------------------------------------------------------------
// Coverage: the Bevy miss (docs/presets.md, "Coverage") and seed defects
// ---------------------------------------------------------------------------------------------

/// Uniformly random camera orientations (Shoemake) at random positions.
fn random_poses(seed: u64, count: usize) -> Vec<CameraPose> {
    let mut rng = csm_core::rng::SplitMix64::new(seed);
    let tau = std::f64::consts::TAU;
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let p = DVec3::new(
            rng.range(-1000.0, 1000.0),
            rng.range(-1000.0, 1000.0),
            rng.range(-1000.0, 1000.0),
        );
        let (u1, u2, u3) = (rng.unit(), rng.unit(), rng.unit());
        let q = DQuat::from_xyzw(
            (1.0 - u1).sqrt() * (tau * u2).sin(),
            (1.0 - u1).sqrt() * (tau * u2).cos(),
            u1.sqrt() * (tau * u3).sin(),
            u1.sqrt() * (tau * u3).cos(),
        );
        if let Some(pose) = CameraPose::look_to(p, q * DVec3::NEG_Z, q * DVec3::Y) {
            out.push(pose);
        }
    }
    out
}

#[test]
fn bevy_window_misses_the_slice_by_up_to_one_texel_in_the_constructed_case() {
    let ln = lens(45.0, 16.0 / 9.0);
    let k2 = ln.k2();
    // Far such that the larger diagonal of [8, far] is exactly 40 (not a hair above).
    let mut far = 20.0 / k2.sqrt();
    while slice_diameter(8.0, far, k2) > 40.0 {
        far = f64::from_bits(far.to_bits() - 1);
    }
    let knobs = Knobs::Bevy(BevyKnobs {
        minimum_distance: 8.0,
        first_cascade_far_bound: 10.0,
        overlap_proportion: 0.2,
        bounds: None,
    });
    let light = DVec3::new(0.3, -1.0, 0.2);
    let l = layout(&knobs, 1, far, 8.0, 1000.0);
    let rig = rig_for_layout(&knobs, ln, light, 2048, &l, 8.0, 1000.0, far).unwrap();
    assert_eq!(rig.sphere_side, vec![40.0], "no slack from the ceil");
    let (mut misses, mut worst, mut unsnapped_worst) = (0, 0.0f64, 0.0f64);
    for pose in random_poses(2, 20_000) {
        let lp = LightPose::new(&rig.light, &pose);
        let w = rig.window(0, &lp, true);
        let c = rig.coverage(0, &lp, &w);
        misses += usize::from(c.violations > 0);
        worst = worst.max(c.worst_texels);
        let u = rig.window(0, &lp, false);
        unsnapped_worst = unsnapped_worst.max(rig.coverage(0, &lp, &u).worst_texels);
    }
    // reference: 32 of 20,000 poses, worst 0.82 texel. The floor moves the centre by less
    // than one texel, so no miss can reach a whole texel.
    assert!((10..=100).contains(&misses), "{misses} poses miss");
    assert!(worst > 0.7 && worst < 1.0, "worst miss {worst} texels");
    assert_eq!(unsnapped_worst, 0.0, "centred on the box, the window always covers");

    // The default cascade 1 ([8, 24.66]) keeps about 7 texels of slack (reference: 7.10).
    let knobs = default_knobs("bevy");
    let l = layout(&knobs, 4, 150.0, 0.1, 1000.0);
    let rig = rig_for_layout(&knobs, ln, light, 2048, &l, 0.1, 1000.0, 150.0).unwrap();
    let mut slack = f64::INFINITY;
    for pose in random_poses(5, 20_000) {
        let lp = LightPose::new(&rig.light, &pose);
        let c = rig.coverage(1, &lp, &rig.window(1, &lp, true));
        assert_eq!(c.violations, 0);
        slack = slack.min(c.min_slack_texels);
    }
    assert!(slack > 6.9 && slack < 7.3, "minimum slack {slack}");
}

#[test]
fn seed_defects_show_up_as_coverage_violations() {
    // The learnopengl preset: depths in (15, 30) and beyond 100 read cascade 2, fitted to [30, 100].
    let c = preset_config("learnopengl", "", "");
    let a = analyze(&c, &AnalysisOptions::full());
    let sn = a.configured_path().unwrap();
    assert!(
        sn.coverage.violations[2] > 0 && sn.coverage.worst_texels[2] > 100.0,
        "{:?}",
        sn.coverage
    );
    // The unity-sample preset: windows on the origin axis miss slices far from it; centring repairs it.
    let c = preset_config("unity-sample", "", "");
    assert!(
        analyze(&c, &AnalysisOptions::summary_only())
            .summary
            .coverage_violations
            > 0
    );
    let c = preset_config("unity-sample", "", "[unity-sample]\ncentre_on_slice = true");
    assert_eq!(
        analyze(&c, &AnalysisOptions::summary_only())
            .summary
            .coverage_violations,
        0
    );
    // Engines that reserve a border or enough slack cover their slices on this scene.
    for name in [
        "dart",
        "threejs",
        "eevee",
        "bevy",
        "godot",
        "unreal",
        "unity",
        "unity-urp",
        "filament",
    ] {
        let a = analyze(&preset_config(name, "", ""), &AnalysisOptions::summary_only());
        assert_eq!(a.summary.coverage_violations, 0, "{name}");
    }
}

// ---------------------------------------------------------------------------------------------
// Light depth ranges
// ---------------------------------------------------------------------------------------------

#[test]
fn threejs_fixed_light_range_clips_deep_cascades_by_the_hand_computed_amount() {
    // Light straight down, camera looking level with fovY 90 deg: the last slice [b F, F] spans
    // 2 F tanV = 4000 vertically for F = 2000, against lightFar - lightMargin = 1800.
    let text = r#"
[camera]
position = [0.0, 0.0, 0.0]
target = [0.0, 0.0, -1.0]
fov_y_deg = 90.0
near = 0.1
far = 5000.0
[screen]
width = 1000
height = 1000
[light]
direction = [0.0, -1.0, 0.0]
[scene]
min = [-1e5, -1e5, -1e5]
max = [1e5, 1e5, 1e5]
[shadow]
preset = "threejs"
max_distance = 2000.0
"#
    .to_string();
    let c = load(&text);
    let a = analyze(&c, &AnalysisOptions::full());
    let p = a.preset.as_ref().unwrap();
    let last = p.light_depth.last().unwrap();
    assert!((last.receivers_outside - (4000.0 - 1800.0)).abs() < 1e-6, "{last:?}");
    // Casters: everything up to y = 1e5 above the slice's top (y = 2000) within the window,
    // against lightMargin - lightNear = 199 kept.
    assert!((last.casters_outside - (1e5 - 2000.0 - 199.0)).abs() < 1e-6, "{last:?}");
    assert_eq!(p.receivers_outside_depth, last.receivers_outside);
    // The light range is 1..2000 from a light 200 in front of the top of the slice (light z = -y).
    assert!((last.near - (-2000.0 - 200.0 + 1.0)).abs() < 1e-9 && (last.far - (-2000.0 - 200.0 + 2000.0)).abs() < 1e-9);
    // Bevy keeps casters in front of its slice (unclipped depth): nothing lost.
    let bevy = load(&text.replace("preset = \"threejs\"", "preset = \"bevy\""));
    let p = analyze(&bevy, &AnalysisOptions::full()).preset.unwrap();
    assert_eq!((p.receivers_outside_depth, p.casters_outside_depth), (0.0, 0.0));
}

#[test]
fn eevee_lamp_clip_range_loses_receivers_beyond_clip_end() {
    // The default lamp puts the scene's top at clip_start; the scene is 40 deep along a
    // vertical light, so with clip_end 20 the receivers between 20 and 40 below are lost.
    let text = scene("", "[shadow]\npreset = \"eevee\"\n[eevee]\nclip_end = 20.05")
        .replace("direction = [-0.4, -1.0, -0.3]", "direction = [0.0, -1.0, 0.0]");
    let c = load(&text);
    let a = analyze(&c, &AnalysisOptions::full());
    let p = a.preset.unwrap();
    // Camera at y = 10 looking down to the ground (y = 0): receivers span y in [0, 10 + ...];
    // the range covers y >= 40 - 20 = 20 only, so every receiver below y = 20 is outside.
    for d in &p.light_depth {
        assert!(
            (d.near - (-40.0)).abs() < 1e-9 && (d.far - (-20.0)).abs() < 1e-9,
            "{d:?}"
        );
    }
    assert!(p.receivers_outside_depth > 0.0);
}

// ---------------------------------------------------------------------------------------------
// Configuration: overrides, knob tables, errors
// ---------------------------------------------------------------------------------------------

#[test]
fn shadow_overrides_apply_and_fixed_implementations_say_what_they_ignore() {
    let c = preset_config("bevy", "cascades = 2\nresolution = 1024\nmax_distance = 80.0", "");
    assert_eq!(
        (c.shadow.cascades, c.shadow.resolution, c.shadow.max_distance),
        (2, 1024, 80.0)
    );
    let c = preset_config("learnopengl", "cascades = 4\nmax_distance = 80.0\nlambda = 0.3", "");
    let notes = c.shadow.preset.as_ref().unwrap().notes.join("\n");
    assert_eq!(c.shadow.cascades, 3);
    assert!(notes.contains("shadow.cascades = 4 ignored") && notes.contains("shadow.max_distance = 80 ignored"));
    assert!(notes.contains("shadow.lambda ignored"), "{notes}");
    let c = preset_config("dart", "cascades = 9", "");
    assert_eq!(c.shadow.cascades, 4);
    assert!(c.shadow.preset.unwrap().notes[0].contains("clamped to 4"));
    // The file's preset can be overridden, and --defaults style loading drops [shadow] overrides.
    let text = scene("", "[shadow]\npreset = \"bevy\"\ncascades = 2\n");
    let choice = PresetChoice {
        name: Some(PresetName::Godot),
        also_allowed: vec![],
        engine_defaults: true,
        lenient_overrides: false,
    };
    let c = Config::from_toml_str_with_preset(&text, "t.toml", None, &choice).unwrap();
    let p = c.shadow.preset.clone().unwrap();
    assert_eq!((p.name, c.shadow.cascades), (PresetName::Godot, 4));
    // Knob tables reach the preset.
    let c = preset_config(
        "bevy",
        "",
        "[bevy]\nfirst_cascade_far_bound = 5.0\noverlap_proportion = 0.5",
    );
    let Knobs::Bevy(b) = c.shadow.preset.unwrap().knobs.clone() else {
        panic!()
    };
    assert_eq!((b.first_cascade_far_bound, b.overlap_proportion), (5.0, 0.5));
}

#[test]
fn compare_style_loading_falls_back_to_the_engine_default_with_a_note() {
    let text = scene("", "[shadow]\ncascades = 3\nresolution = 1000\n");
    let choice = |p| PresetChoice {
        name: Some(p),
        lenient_overrides: true,
        ..Default::default()
    };
    let c = Config::from_toml_str_with_preset(&text, "t.toml", None, &choice(PresetName::Godot)).unwrap();
    assert_eq!((c.shadow.cascades, c.shadow.resolution), (4, 1000));
    let notes = c.shadow.preset.unwrap().notes.join("\n");
    assert!(
        notes.contains("shadow.cascades = 3 is not offered by godot (1, 2, 4): its default 4 is used"),
        "{notes}"
    );
    let c = Config::from_toml_str_with_preset(&text, "t.toml", None, &choice(PresetName::Bevy)).unwrap();
    assert_eq!((c.shadow.cascades, c.shadow.resolution), (3, 2048));
    let notes = c.shadow.preset.unwrap().notes.join("\n");
    assert!(
        notes.contains("shadow.resolution = 1000 is not a power of two"),
        "{notes}"
    );
    // Loading for one preset (analyze) keeps these errors.
    let strict = PresetChoice {
        name: Some(PresetName::Godot),
        ..Default::default()
    };
    assert!(Config::from_toml_str_with_preset(&text, "t.toml", None, &strict).is_err());
}

#[test]
fn bad_preset_settings_are_errors_naming_the_key() {
    let e = load_err(&scene("", "[shadow]\npreset = \"bevvy\""));
    assert!(
        e.contains("shadow.preset") && e.contains("did you mean \"bevy\"") && e.contains("test.toml:"),
        "{e}"
    );
    let e = load_err(&scene(
        "",
        "[shadow]\npreset = \"godot\"\n[bevy]\noverlap_proportion = 0.1",
    ));
    assert!(e.contains("[bevy]") && e.contains("\"godot\""), "{e}");
    let e = load_err(&scene("", "[bevy]\noverlap_proportion = 0.1"));
    assert!(e.contains("[bevy]") && e.contains("shadow.preset = \"bevy\""), "{e}");
    let e = load_err(&scene("", "[shadow]\npreset = \"bevy\"\n[bevy]\noverlap = 0.1"));
    assert!(e.contains("unknown field `overlap`") && e.contains("test.toml:"), "{e}");
    let e = load_err(&scene(
        "",
        "[shadow]\npreset = \"bevy\"\n[bevy]\noverlap_proportion = 1.0",
    ));
    assert!(e.contains("bevy.overlap_proportion") && e.contains("[0, 1)"), "{e}");
    let e = load_err(&scene("", "[shadow]\npreset = \"godot\"\ncascades = 3"));
    assert!(e.contains("shadow.cascades") && e.contains("1, 2, 4"), "{e}");
    let e = load_err(&scene("", "[shadow]\npreset = \"filament\"\nresolution = 1000"));
    assert!(e.contains("shadow.resolution") && e.contains("power of two"), "{e}");
    let e = load_err(&scene(
        "",
        "[shadow]\npreset = \"godot\"\n[godot]\nsplits = [0.5, 0.2, 0.7]",
    ));
    assert!(e.contains("godot.splits") && e.contains("increasing"), "{e}");
    let e = load_err(&scene("", "[shadow]\npreset = \"bevy\"\nmax_distance = 5.0"));
    assert!(e.contains("bevy.first_cascade_far_bound"), "{e}");
    let e = load_err(&scene(
        "",
        "[shadow]\npreset = \"threejs\"\n[threejs]\nmode = \"magic\"",
    ));
    assert!(e.contains("`threejs.mode` = \"magic\" is not allowed"), "{e}");
}

#[test]
fn unknown_tables_are_errors_naming_them_with_line_and_column() {
    let text = scene("", "[bevvy]\noverlap_proportion = 0.1");
    let e = load_err(&text);
    let line = line_of(&text, "[bevvy]");
    assert!(
        e.starts_with(&format!("test.toml:{line}:1: unknown field `bevvy`")),
        "{e}"
    );
    assert!(
        e.contains("`camera`") && e.contains("`bevy`") && e.contains("`unity-urp`"),
        "{e}"
    );
    // A wrong type inside an engine table keeps TOML's own line and column.
    let text = scene(
        "",
        "[shadow]\npreset = \"bevy\"\n[bevy]\noverlap_proportion = \"a lot\"",
    );
    let e = load_err(&text);
    assert!(
        e.starts_with(&format!("test.toml:{}:", line_of(&text, "overlap_proportion"))),
        "{e}"
    );
}

/// The line and column of the first line of `text` starting with `prefix`, 1-based.
fn line_of(text: &str, prefix: &str) -> usize {
    text.lines().position(|l| l.starts_with(prefix)).expect("line present") + 1
}

#[test]
fn every_enum_valued_key_names_itself_and_its_values() {
    let cases: [(&str, &str, &str, &str, &str); 7] = [
        (
            "",
            "[shadow]\nfit = \"ellipse\"",
            "fit = ",
            "`shadow.fit` = \"ellipse\"",
            "one of \"sphere\", \"aabb\"",
        ),
        (
            "",
            "[shadow]\nprecision = \"f16\"",
            "precision = ",
            "`shadow.precision` = \"f16\"",
            "one of \"f64\", \"f32\"",
        ),
        (
            "",
            "[shadow]\nsnap_space = \"view\"",
            "snap_space = ",
            "`shadow.snap_space` = \"view\"",
            "one of \"world\", \"camera_relative\"",
        ),
        (
            "",
            "[shadow]\npreset = \"bevvy\"",
            "preset = ",
            "`shadow.preset` = \"bevvy\"",
            "one of \"dart\", \"threejs\"",
        ),
        (
            "path = \"spin\"",
            "",
            "path = ",
            "`motion.path` = \"spin\"",
            "one of \"strafe\", \"dolly\", \"yaw\", \"pitch\", \"orbit\", \"still\", \"file\"",
        ),
        (
            "",
            "[shadow]\npreset = \"threejs\"\n[threejs]\nmode = \"cubic\"",
            "mode = ",
            "`threejs.mode` = \"cubic\"",
            "one of \"uniform\", \"logarithmic\", \"practical\"",
        ),
        (
            "",
            "[shadow]\npreset = \"filament\"\n[filament]\nsplit_mode = \"even\"",
            "split_mode = ",
            "`filament.split_mode` = \"even\"",
            "one of \"positions\", \"uniform\", \"logarithmic\", \"practical\"",
        ),
    ];
    for (motion, extra, line_start, what, allowed) in cases {
        let text = scene(motion, extra);
        let e = load_err(&text);
        let line = line_of(&text, line_start);
        assert!(e.contains(&format!("test.toml:{line}:")), "{e}");
        assert!(e.contains(&format!("{what} is not allowed: {allowed}")), "{e}");
    }
    // Enum values that point at the value itself: the column is the value's.
    let text = scene("", "[shadow]\nfit = \"ellipse\"");
    let line = line_of(&text, "fit = ");
    assert!(load_err(&text).starts_with(&format!("test.toml:{line}:7: ")));
}

/// What cargo shows under an error: the gutter, the source line with its number, carets under
/// `len` characters from 1-based `column`, and the closing gutter (computed here, not by the
/// renderer).
fn caret_excerpt(line: usize, source: &str, column: usize, len: usize) -> String {
    let pad = " ".repeat(line.to_string().len());
    format!(
        "\n{pad} |\n{line} | {source}\n{pad} | {}{}\n{pad} |",
        " ".repeat(column - 1),
        "^".repeat(len)
    )
}

#[test]
fn a_bad_enum_value_shows_the_source_line_with_a_caret_under_the_value() {
    let text = scene("", "[shadow]\nfit = \"ellipse\"");
    let line = line_of(&text, "fit = ");
    let e = load_err(&text);
    // The key, the bad value and what is allowed, then the excerpt: nothing else.
    let first = format!("test.toml:{line}:7: `shadow.fit` = \"ellipse\" is not allowed: one of \"sphere\", \"aabb\"");
    assert_eq!(e, first + &caret_excerpt(line, "fit = \"ellipse\"", 7, 9), "{e}");

    // A value out of range, located at its key: the caret is under the value.
    let text = scene("", "[analysis]\nscreen_scale =  1.5");
    let line = line_of(&text, "screen_scale");
    let e = load_err(&text);
    assert!(
        e.starts_with(&format!("test.toml:{line}:1: `analysis.screen_scale` = 1.5")),
        "{e}"
    );
    assert!(e.ends_with(&caret_excerpt(line, "screen_scale =  1.5", 17, 3)), "{e}");

    // A TOML type error keeps toml's message and gains the excerpt under the value.
    let text = scene("", "[shadow]\ncascades = \"four\"");
    let line = line_of(&text, "cascades");
    let e = load_err(&text);
    assert!(
        e.starts_with(&format!("test.toml:{line}:12: `shadow.cascades`: ")),
        "{e}"
    );
    assert!(e.ends_with(&caret_excerpt(line, "cascades = \"four\"", 12, 6)), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Light basis
// ---------------------------------------------------------------------------------------------

/// Bevy's look-to basis, computed independently: glam's right-handed look-to view matrix has
/// rows right, up and −direction.
fn look_to(d: DVec3) -> (DVec3, DVec3, DVec3) {
    let m = glam::DMat4::look_to_rh(DVec3::ZERO, d.normalize(), DVec3::Y);
    (m.row(0).truncate(), m.row(1).truncate(), -m.row(2).truncate())
}

#[test]
fn bevy_basis_is_looking_to_with_y_up_and_mirrors_csm_lab_x() {
    let mut rng = csm_core::rng::SplitMix64::new(41);
    let mut n = 0;
    while n < 20 {
        let d = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        if d.length() < 0.1 {
            continue;
        }
        n += 1;
        let b = bevy_light_basis(d);
        let (x, y, z) = look_to(d);
        assert!((b.x - x).length() < 1e-12 && (b.y - y).length() < 1e-12, "{d:?}: {b:?}");
        assert!((b.z - z).length() < 1e-12);
        // Against csm-lab's basis: x mirrored, y and z the same.
        let own = LightBasis::new(d);
        assert!((b.x + own.x).length() < 1e-12, "{d:?}");
        assert!((b.y - own.y).length() < 1e-12 && (b.z - own.z).length() < 1e-12);
        assert!(!b.vertical_fallback);
    }
    // Nearly vertical: Bevy keeps +Y as reference where csm-lab has switched to +Z.
    let d = DVec3::new(1e-9, -1.0, 0.0);
    assert!(LightBasis::new(d).vertical_fallback && !bevy_light_basis(d).vertical_fallback);
    assert!((bevy_light_basis(d).x - look_to(d).0).length() < 1e-12);
    // Exactly vertical: right = any_orthonormal_vector(+Y) = -Z, up = back x right.
    let b = bevy_light_basis(DVec3::NEG_Y);
    assert!(b.vertical_fallback);
    assert_eq!(
        (b.x, b.y, b.z),
        (DVec3::new(-0.0, 0.0, -1.0), DVec3::NEG_X, DVec3::NEG_Y)
    );
    let b = bevy_light_basis(DVec3::Y);
    assert_eq!((b.y, b.z), (DVec3::X, DVec3::Y));
}

#[test]
fn bevy_floor_snap_moves_windows_toward_minus_bevy_x_which_is_plus_csm_lab_x() {
    let c = preset_config("bevy", "", "");
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let own = LightBasis::new(c.light_direction);
    let (mut along_own_x, mut moved) = (0.0f64, 0);
    for pose in random_poses(9, 200) {
        let lp = LightPose::new(&rig.light, &pose);
        for i in 0..rig.cascade_count() {
            let centre = |w: &csm_core::fitting::Window| (w.origin_texels + 0.5 * w.resolution as f64) * w.texel;
            let (s, u) = (rig.window(i, &lp, true), rig.window(i, &lp, false));
            let shift = centre(&s) - centre(&u);
            // Floor: never toward +x or +y of Bevy's own basis.
            assert!(shift.x <= 1e-9 * s.texel.x && shift.y <= 1e-9 * s.texel.y, "{shift:?}");
            let world = shift.x * rig.light.x + shift.y * rig.light.y;
            assert!(world.dot(own.x) >= -1e-9, "against csm-lab's x the floor rounds up");
            along_own_x = along_own_x.max(world.dot(own.x));
            moved += usize::from(shift.x < 0.0);
        }
    }
    assert!(moved > 0 && along_own_x > 0.0);
}

// ---------------------------------------------------------------------------------------------
// Sweep support
// ---------------------------------------------------------------------------------------------

#[test]
fn sweep_axes_follow_each_preset_and_set_its_own_knobs() {
    let axes_of = |n: &str| csm_lab::presets::axes(&preset_config(n, "", ""));
    assert_eq!(axes_of("dart").lambda, Some("dart.lambda"));
    assert_eq!(axes_of("eevee").lambda, Some("eevee.cascade_exponent"));
    assert_eq!(axes_of("threejs").lambda, None);
    assert_eq!(axes_of("unreal").lambda, None);
    assert_eq!(axes_of("bevy").lambda, None);
    assert_eq!(axes_of("godot").cascades, vec![1, 2, 4]);
    assert_eq!(axes_of("learnopengl").cascades, vec![3]);
    assert!(axes_of("bevy").resolution_power_of_two && !axes_of("unreal").fit);
    let builtin = csm_lab::presets::axes(&load(&scene("", "")));
    assert!(builtin.fit && builtin.lambda == Some("shadow.lambda"));

    // A lambda sweep point changes the preset's splits exactly as its rule says.
    let mut c = preset_config("dart", "max_distance = 200.0", "");
    set_lambda(&mut c, 1.0).unwrap();
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let want: Vec<f64> = (0..=4).map(|i| 0.1 * 2000f64.powf(i as f64 / 4.0)).collect();
    assert_close(&rig.splits, &want, 1e-9, "dart at lambda 1");
    let mut c = preset_config("threejs", "", "");
    assert!(set_lambda(&mut c, 0.3).unwrap_err().to_string().contains("no λ"));
    let mut c = preset_config("godot", "", "");
    assert!(set_cascades(&mut c, 3).is_err());
    set_cascades(&mut c, 2).unwrap();
    assert_eq!(csm_lab::analysis::rig(&c).unwrap().cascade_count(), 2);
    let mut c = preset_config("bevy", "", "");
    assert!(set_resolution(&mut c, 1000).is_err());
    set_resolution(&mut c, 4096).unwrap();
    assert_eq!(
        analyze(&c, &AnalysisOptions::summary_only()).summary.memory_bytes,
        4 * 4096 * 4096 * 4
    );
}

#[test]
fn every_preset_analyses_to_finite_numbers_on_every_example_scene() {
    for file in ["default", "indoor", "open_world", "top_down"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("configs/{file}.toml"));
        for p in PresetName::ALL {
            // Each preset at its own defaults (the files' [shadow] counts do not fit every engine).
            let choice = PresetChoice {
                name: Some(p),
                engine_defaults: true,
                ..Default::default()
            };
            let c = Config::load_with_preset(&path, &choice).unwrap_or_else(|e| panic!("{file} {p}: {e}"));
            let a = analyze(&c, &AnalysisOptions::full());
            let s = &a.summary;
            for v in [
                s.z_lo,
                s.z_hi,
                s.max_aliasing,
                s.mean_aliasing,
                s.mean_log_aliasing,
                s.shimmer_snapped,
                s.shimmer_unsnapped,
                s.size_jitter,
            ] {
                assert!(v.is_finite(), "{file} {p}: {s:?}");
            }
            let json = csm_lab::report::analyze::summary_value(&a);
            csm_lab::output::check_json_finite("summary", &json).unwrap_or_else(|e| panic!("{file} {p}: {e}"));
            assert_eq!(json["preset"]["name"], p.as_str());
        }
    }
}

/// The learnopengl preset's own scene (docs/presets.md): camera at (15, 20, 20) looking at the origin,
/// fovY 45 deg, 800x600, near 1, far 150; the light orbits the cube at (2.5, 1.5, 0).
fn seed_004_scene(t: f64) -> (String, DVec3) {
    let a = 1.2 * t;
    let light = DVec3::new(2.5 + 2.8 * a.sin(), 6.0, 2.8 * a.cos());
    let text = format!(
        r#"
[camera]
position = [15.0, 20.0, 20.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 45.0
near = 1.0
far = 150.0
[screen]
width = 800
height = 600
[light]
direction = [0.0, -1.0, 0.0]
[scene]
min = [-15.0, -0.5, -15.0]
max = [15.0, 2.5, 15.0]
[shadow]
preset = "learnopengl"
[learnopengl]
light_position = [{}, {}, {}]
"#,
        light.x, light.y, light.z
    );
    (text, light)
}

#[test]
fn seed_004_mirrored_depth_range_puts_cascades_0_and_2_outside_the_depth_range() {
    for t in [0.0, 1.0, 2.5] {
        let (text, eye) = seed_004_scene(t);
        let c = load(&text);
        let rig = csm_lab::analysis::rig(&c).unwrap();
        let pose = c.camera.pose();
        let lp = LightPose::new(&rig.light, &pose);
        for i in 0..3 {
            let corners = csm_core::cascades::slice_corners_world(&rig, i, &pose);
            // The reference code's own arithmetic: glm::lookAt from the light to the corners' centroid,
            // view z = -(distance along the view direction); glm::ortho(.., minZ - 10, maxZ + 10).
            let centroid = corners.iter().copied().sum::<DVec3>() / 8.0;
            let f = (centroid - eye).normalize();
            let zv: Vec<f64> = corners.iter().map(|p| -f.dot(*p - eye)).collect();
            let min_z = zv.iter().cloned().fold(f64::INFINITY, f64::min);
            let max_z = zv.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let (n, fa) = (min_z - 10.0, max_z + 10.0);
            let ndc: Vec<f64> = zv.iter().map(|z| (-2.0 * z - (fa + n)) / (fa - n)).collect();
            // csm-lab's light depth range gives the same mapping.
            let w = rig.window(i, &lp, true);
            let d = rig.light_depth(i, &lp, &w, &c.scene);
            let b = rig.basis(i, &lp);
            for (p, want) in corners.iter().zip(&ndc) {
                let got = -1.0 + 2.0 * (b.z.dot(*p) - d.near) / (d.far - d.near);
                assert!((got - want).abs() < 1e-9, "t {t} cascade {i}: {got} vs {want}");
            }
            let lo = ndc.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = ndc.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            if i == 1 {
                // "Cascade 1 stays inside" at t = 0 and 1 (at t = 2.5 it grazes NDC 1).
                if t < 2.0 {
                    assert!(lo >= -1.0 && hi <= 1.0, "t {t}: {lo}..{hi}");
                }
            } else {
                // reference: "between about 0.8 and 2.6", outside [-1, 1].
                assert!(lo > 0.7 && hi < 2.7 && hi > 1.5, "t {t} cascade {i}: {lo}..{hi}");
            }
        }
    }
}

/// Over random camera orientations, each snapping rule misses its slice by no more than its
/// snap shift minus its border allows: no miss with a border at least the shift (Godot, Unreal,
/// csm-lab's model of Unity), under half a texel with round and no border (dart, EEVEE),
/// under a texel with floor/fmod and too small a border (three.js, Filament); and the metric
/// finds those misses.
#[test]
fn coverage_misses_stay_within_each_snap_rule_bound() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let poses = random_poses(9, 20_000);
    for (p, bound, must_miss) in [
        (PresetName::Dart, 0.5, true),
        (PresetName::Eevee, 0.5, true),
        (PresetName::Threejs, 1.0, true),
        (PresetName::Filament, 1.0, true),
        (PresetName::Bevy, 1.0, false),
        (PresetName::Godot, 0.0, false),
        (PresetName::Unreal, 0.0, false),
        (PresetName::Unity, 0.0, false),
        (PresetName::UnityUrp, 0.0, false),
    ] {
        let choice = PresetChoice {
            name: Some(p),
            engine_defaults: true,
            ..Default::default()
        };
        let c = Config::from_toml_str_with_preset(&text, "default.toml", None, &choice).unwrap();
        let rig = csm_lab::analysis::rig(&c).unwrap();
        let (mut misses, mut worst) = (0, 0.0f64);
        for pose in &poses {
            let lp = LightPose::new(&rig.light, pose);
            for i in 0..rig.cascade_count() {
                let cov = rig.coverage(i, &lp, &rig.window(i, &lp, true));
                misses += usize::from(cov.violations > 0);
                worst = worst.max(cov.worst_texels);
            }
        }
        if bound == 0.0 {
            assert_eq!(misses, 0, "{p}");
        } else {
            assert!(worst < bound, "{p}: worst miss {worst} texels");
        }
        if must_miss {
            assert!(
                misses > 0 && worst > 0.25 * bound,
                "{p}: {misses} misses, worst {worst}"
            );
        }
    }
}

mod random {
    use super::*;
    use proptest::prelude::*;

    fn arb_text() -> impl Strategy<Value = String> {
        (
            (-300.0f64..300.0, 0.5f64..120.0, -300.0f64..300.0),
            (-1.0f64..1.0, -1.0f64..0.3, -1.0f64..1.0),
            (5.0f64..150.0, 0.3f64..3.5, 0.01f64..30.0, 1.5f64..400.0),
            (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            (
                0usize..11,
                proptest::option::of(1usize..9),
                proptest::option::of(1.0f64..3000.0),
            ),
            prop_oneof![Just("strafe"), Just("yaw"), Just("pitch"), Just("orbit"), Just("dolly")],
        )
            .prop_filter("view direction not vertical, light not zero", |(_, d, _, l, ..)| {
                (d.0 * d.0 + d.2 * d.2) > 0.01 && (l.0 * l.0 + l.1 * l.1 + l.2 * l.2) > 0.01
            })
            .prop_map(
                |(p, d, (fov, aspect, near, far_ratio), l, (preset, cascades, dist), path)| {
                    let mut shadow = format!("preset = \"{}\"\n", PresetName::ALL[preset]);
                    if let Some(n) = cascades {
                        shadow += &format!("cascades = {n}\n");
                    }
                    if let Some(m) = dist {
                        shadow += &format!("max_distance = {m}\n");
                    }
                    format!(
                        r#"
[camera]
position = [{}, {}, {}]
target = [{}, {}, {}]
fov_y_deg = {fov}
near = {near}
far = {}
[screen]
width = {}
height = 1000
[light]
direction = [{}, {}, {}]
[scene]
min = [-150.0, 0.0, -150.0]
max = [150.0, 30.0, 150.0]
[shadow]
{shadow}
[motion]
path = "{path}"
frames = 8
step = 0.7
"#,
                        p.0,
                        p.1,
                        p.2,
                        p.0 + d.0 * 10.0,
                        p.1 + d.1 * 10.0,
                        p.2 + d.2 * 10.0,
                        near * far_ratio,
                        (1000.0 * aspect) as u32,
                        l.0,
                        l.1,
                        l.2
                    )
                },
            )
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]

        /// Any camera, light and preset either is a clear config error or analyses to finite
        /// numbers with ordered selection boundaries; stabilised presets never shimmer under
        /// translation.
        #[test]
        fn presets_never_panic_and_report_finite_numbers(text in arb_text()) {
            let c = match Config::from_toml_str(&text, "t.toml", None) {
                Ok(c) => c,
                Err(e) => {
                    let m = e.to_string();
                    prop_assert!(m.contains("is not allowed") || m.contains("t.toml"), "{}", m);
                    return Ok(());
                }
            };
            let a = analyze(&c, &AnalysisOptions::full());
            let json = csm_lab::report::analyze::summary_value(&a);
            prop_assert!(csm_lab::output::check_json_finite("summary", &json).is_ok(), "{}", json);
            if let Some(rig) = a.rig() {
                prop_assert!(rig.splits.windows(2).all(|w| w[0] <= w[1]), "{:?}", rig.splits);
                prop_assert_eq!(rig.splits[0], c.camera.near);
                prop_assert!(*rig.splits.last().unwrap() <= c.camera.far);
                let stable = c.shadow.snap && rig.fixed_basis();
                if stable && c.motion.path.is_translation() {
                    prop_assert!(a.summary.shimmer_snapped < 1e-9, "{}", a.summary.shimmer_snapped);
                }
            }
        }
    }
}

#[test]
fn applying_a_preset_to_a_validated_scene_equals_loading_with_it() {
    let text = scene(
        "",
        "[shadow]\ncascades = 4\n[bevy]\noverlap_proportion = 0.1\n[godot]\nsplits = [0.1, 0.3, 0.6]",
    );
    let scene = csm_lab::config::parse(&text, "test.toml", None).unwrap();
    assert!(scene.shadow.preset.is_none());
    for p in PresetName::ALL {
        let choice = PresetChoice {
            name: Some(p),
            also_allowed: PresetName::ALL.to_vec(),
            engine_defaults: false,
            lenient_overrides: true,
        };
        let mut applied = scene.clone();
        apply(&mut applied, &choice).unwrap();
        let loaded = Config::from_toml_str_with_preset(&text, "test.toml", None, &choice).unwrap();
        assert_eq!(applied, loaded, "{p}");
        assert_eq!(applied.shadow.preset.as_ref().unwrap().name, p);
    }
    // The engine tables of the file reach their own engine.
    let mut bevy = scene.clone();
    apply(
        &mut bevy,
        &PresetChoice {
            name: Some(PresetName::Bevy),
            also_allowed: PresetName::ALL.to_vec(),
            ..Default::default()
        },
    )
    .unwrap();
    let Some(b) = bevy.shadow.preset.as_ref().unwrap().knobs.get::<Bevy>() else {
        panic!("bevy knobs");
    };
    assert_eq!(b.overlap_proportion, 0.1);
}

/// `Rig::light_far` (what the per-frame cost counts use) is `Rig::light_depth`'s far plane, bit
/// for bit, for every preset and csm-lab's own rig, on every frame of a strafe, in both snap
/// modes: the scene rule's shortcut skips only the caster side, which the far plane never reads.
#[test]
fn the_light_far_shortcut_equals_the_light_depth_far_plane_for_every_preset() {
    let own = load(&scene("path = \"strafe\"\nframes = 40\nstep = 0.05", ""));
    let presets = csm_lab::presets::PresetName::ALL
        .iter()
        .map(|p| preset_config(p.as_str(), "", ""));
    for c in std::iter::once(own).chain(presets) {
        let rig = csm_lab::analysis::rig(&c).unwrap();
        for pose in c.camera_path().unwrap() {
            let lp = LightPose::new(&rig.light, &pose);
            for i in 0..rig.cascade_count() {
                for snap in [true, false] {
                    let w = rig.window(i, &lp, snap);
                    let far = rig.light_depth(i, &lp, &w, &c.scene).far;
                    assert_eq!(rig.light_far(i, &lp, &w, &c.scene).to_bits(), far.to_bits());
                }
            }
        }
    }
}
