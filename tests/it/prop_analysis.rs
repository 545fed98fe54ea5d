//! Properties of the analysis over random cameras, lights, scenes and shadow settings, from
//! the ordinary to the pathological (near 1e-4 with far 1e7, fov 1..179 degrees, aspect
//! 0.05..20, vertical and grazing lights, scenes thinner than a texel, 1e6 units from the
//! origin). Every case goes through the real TOML loader, so it is either a clear error or a
//! config whose analysis is finite, covered and, for the stabilised sphere fit, shimmer-free.

use std::panic::{catch_unwind, AssertUnwindSafe};

use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::config::Fit;
use csm_lab::output::Exporter;
use csm_lab::report::analyze as analyze_files;
use csm_lab::Config;
use proptest::prelude::*;

/// A direction: uniform on the sphere, or one of the cases engines trip over.
fn direction() -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![
        6 => (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        1 => Just((0.0, -1.0, 0.0)),
        1 => Just((0.0, 1.0, 0.0)),
        1 => (-1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, z)| (x, 0.0, z)),
        1 => (-1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, z)| (x, -1e-7, z)),
    ]
    .prop_map(|(x, y, z)| [x, y, z])
}

/// 10^u, u uniform in [lo, hi).
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..hi).prop_map(|u| 10f64.powf(u))
}

#[derive(Debug, Clone)]
struct Case {
    offset: [f64; 3],
    position: [f64; 3],
    view: [f64; 3],
    view_length: f64,
    up: [f64; 3],
    fov: f64,
    height: u32,
    aspect: f64,
    near: f64,
    far_ratio: f64,
    max_distance: Option<f64>,
    light: [f64; 3],
    scene_centre: [f64; 3],
    scene_half: [f64; 3],
    cascades: usize,
    lambda: f64,
    resolution: u32,
    fit: &'static str,
    snap: bool,
    to_scene: bool,
    path: &'static str,
    frames: usize,
    step: f64,
    density: usize,
    probes: usize,
}

fn case() -> impl Strategy<Value = Case> {
    let placement = (
        prop_oneof![Just(0.0), Just(1e3), Just(1e5), Just(1e6), log_uniform(0.0, 6.0)],
        direction(),
        (-200.0f64..200.0, -50.0f64..200.0, -200.0f64..200.0),
        direction(),
        log_uniform(-3.0, 3.0),
        prop_oneof![8 => Just([0.0, 1.0, 0.0]), 1 => direction()],
    );
    let lens = (
        prop_oneof![1.0f64..179.0, Just(1.0), Just(179.0), Just(60.0)],
        16u32..2160,
        prop_oneof![0.05f64..20.0, Just(0.05), Just(20.0), Just(16.0 / 9.0)],
        prop_oneof![log_uniform(-4.0, 1.0), Just(1e-4), Just(0.1)],
        prop_oneof![log_uniform(0.3, 10.0), Just(1e10)],
        // Shadow distance relative to near: 1 in 7 before the near plane.
        proptest::option::of(log_uniform(-1.0, 6.0)),
    );
    let scene = (
        direction(),
        // Where the scene is: anywhere, in front of the camera, or around it.
        prop_oneof![
            (-500.0f64..500.0, -100.0f64..100.0, -500.0f64..500.0).prop_map(|c| (0u8, c)),
            (log_uniform(-1.0, 3.5), (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0))
                .prop_map(|(d, j)| (1u8, (d, j.0, j.1 + j.2))),
            (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0).prop_map(|c| (2u8, c)),
        ],
        (log_uniform(-7.0, 3.0), log_uniform(-7.0, 3.0), log_uniform(-7.0, 3.0)),
    );
    let shadow = (
        prop_oneof![1usize..=16, Just(1), Just(16), Just(4)],
        prop_oneof![0.0f64..=1.0, Just(0.0), Just(1.0)],
        prop_oneof![16u32..=16384, Just(16), Just(16384), Just(2048)],
        prop_oneof![Just("sphere"), Just("aabb")],
        any::<bool>(),
        prop_oneof![3 => Just(true), 1 => Just(false)],
    );
    let motion = (
        prop_oneof![Just("strafe"), Just("dolly"), Just("yaw"), Just("pitch"), Just("orbit")],
        2usize..=6,
        log_uniform(-3.0, 1.3),
        2usize..=48,
        1usize..=12,
    );
    (placement, lens, scene, shadow, motion).prop_map(
        |(
            (offset, odir, position, view, view_length, up),
            (fov, height, aspect, near, far_ratio, max_distance),
            (light, (mode, centre), half),
            (cascades, lambda, resolution, fit, snap, to_scene),
            (path, frames, step, density, probes),
        )| {
            let n = (odir[0] * odir[0] + odir[1] * odir[1] + odir[2] * odir[2])
                .sqrt()
                .max(1e-9);
            let p = [position.0, position.1, position.2];
            let scene_centre = match mode {
                // At distance centre.0 along the view direction, jittered by a tenth of it.
                1 => [0, 1, 2]
                    .map(|i| p[i] + view[i] * centre.0 + 0.1 * centre.0 * [centre.1, centre.2, centre.1 - centre.2][i]),
                // Around the camera (a camera inside the scene when the box is large enough).
                2 => [p[0] + centre.0, p[1] + centre.1, p[2] + centre.2],
                _ => [centre.0, centre.1, centre.2],
            };
            Case {
                offset: odir.map(|c| c / n * offset),
                position: p,
                view,
                view_length,
                up,
                fov,
                height,
                aspect,
                near,
                far_ratio,
                max_distance,
                light,
                scene_centre,
                scene_half: [half.0, half.1, half.2],
                cascades,
                lambda,
                resolution,
                fit,
                snap,
                to_scene,
                path,
                frames,
                step,
                density,
                probes,
            }
        },
    )
}

fn v3(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

impl Case {
    fn toml(&self) -> String {
        let position = add(self.position, self.offset);
        let target = add(position, self.view.map(|c| c * self.view_length));
        let centre = add(self.scene_centre, self.offset);
        let lo = [0, 1, 2].map(|i| centre[i] - self.scene_half[i]);
        let hi = [0, 1, 2].map(|i| centre[i] + self.scene_half[i]);
        let width = ((self.height as f64 * self.aspect).round() as u32).max(1);
        let max_distance = self
            .max_distance
            .map(|d| format!("max_distance = {:?}\n", d * self.near))
            .unwrap_or_default();
        format!(
            "[camera]\nposition = {}\ntarget = {}\nup = {}\nfov_y_deg = {:?}\nnear = {:?}\nfar = {:?}\n\
             [screen]\nwidth = {width}\nheight = {}\n\
             [light]\ndirection = {}\n\
             [scene]\nmin = {}\nmax = {}\n\
             [shadow]\n{max_distance}cascades = {}\nlambda = {:?}\nresolution = {}\nfit = \"{}\"\nsnap = {}\nfit_depth_to_scene = {}\n\
             [motion]\npath = \"{}\"\nframes = {}\nstep = {:?}\n\
             [analysis]\ndensity_samples = {}\nprobes = {}\n",
            v3(position),
            v3(target),
            v3(self.up),
            self.fov,
            self.near,
            (self.near * self.far_ratio).min(1e9),
            self.height,
            v3(self.light),
            v3(lo),
            v3(hi),
            self.cascades,
            self.lambda,
            self.resolution,
            self.fit,
            self.snap,
            self.to_scene,
            self.path,
            self.frames,
            self.step,
            self.density,
            self.probes,
        )
    }
}

/// Every property of one analysed config; returns a description of the first violation.
fn check(c: &Config) -> Result<(), String> {
    let a = analyze(c, &AnalysisOptions::full());
    let s = &a.summary;
    // The summary does not depend on which optional parts were computed (but seam_crossings,
    // which only `seams` computes).
    let quick = analyze(
        c,
        &AnalysisOptions {
            seams: true,
            ..AnalysisOptions::summary_only()
        },
    );
    if quick.summary != *s {
        return Err(format!("summary_only differs: {:?} vs {s:?}", quick.summary));
    }
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
        if !v.is_finite() || v < 0.0 {
            return Err(format!("{name} = {v}"));
        }
    }
    // Every file analyze writes renders (a non-finite value would be an error here).
    let exporters: [&dyn Exporter<_>; 4] = [
        &analyze_files::CascadesCsv,
        &analyze_files::DensityCsv,
        &analyze_files::ShimmerCsv,
        &analyze_files::SummaryJson,
    ];
    for e in exporters {
        e.render(&a).map_err(|err| format!("{}: {err}", e.file_name()))?;
    }
    let Some(rig) = a.rig() else {
        return if s.cascades_needed {
            Err("cascades needed but no rig".into())
        } else {
            Ok(())
        };
    };
    let sp = &rig.splits;
    if sp.len() != c.shadow.cascades + 1 || sp[0] != s.z_lo || sp[sp.len() - 1] != s.z_hi {
        return Err(format!("splits {sp:?} vs [{}, {}]", s.z_lo, s.z_hi));
    }
    if !sp.windows(2).all(|w| w[0] < w[1]) {
        return Err(format!("splits not strictly increasing: {sp:?}"));
    }
    if s.z_lo < c.camera.near || s.z_hi > c.shadow_far() {
        return Err(format!("range [{}, {}] outside [near, shadow far]", s.z_lo, s.z_hi));
    }
    for (mode, p) in [("snapped", a.snapped()), ("unsnapped", a.unsnapped())] {
        let p = p.as_ref().ok_or("missing path result")?;
        if p.coverage.total() != 0 {
            return Err(format!(
                "{mode} coverage violations {:?}, worst {:?} texels",
                p.coverage.violations, p.coverage.worst_texels
            ));
        }
    }
    if c.shadow.fit == Fit::Sphere {
        let sn = a.snapped().unwrap();
        if !(s.shimmer_snapped < 1e-9 && sn.stats.max < 1e-9 && s.size_jitter == 0.0) {
            return Err(format!("stabilised sphere shimmers: {:?}", sn.stats));
        }
        if sn.stats.cell_flip_rate != Some(0.0) {
            return Err(format!("stabilised sphere flips cells: {:?}", sn.stats));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 5000, max_shrink_iters: 2000, .. ProptestConfig::default() })]

    /// No panic; a clear error or a finite, covered, monotone, stable analysis.
    #[test]
    fn random_scenes_give_a_clear_error_or_a_sound_analysis(case in case()) {
        let text = case.toml();
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            match Config::from_toml_str(&text, "case.toml", None) {
                Ok(c) => check(&c).map(|_| true),
                Err(e) => {
                    let msg = e.to_string();
                    if msg.trim().is_empty() { Err("empty error message".to_string()) } else { Ok(false) }
                }
            }
        }));
        match outcome {
            Ok(Ok(_)) => {}
            Ok(Err(why)) => prop_assert!(false, "{}\n{}", why, text),
            Err(_) => prop_assert!(false, "panicked on\n{}", text),
        }
    }
}

/// Most generated cases are valid configs (the property above is not vacuous).
#[test]
fn most_generated_scenes_are_valid_configs() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let strategy = case();
    let (mut valid, mut analysed) = (0, 0);
    for _ in 0..400 {
        let text = strategy.new_tree(&mut runner).unwrap().current().toml();
        if let Ok(c) = Config::from_toml_str(&text, "case.toml", None) {
            valid += 1;
            if analyze(&c, &AnalysisOptions::summary_only()).summary.cascades_needed {
                analysed += 1;
            }
        }
    }
    assert!(valid > 250, "{valid} of 400 valid");
    assert!(analysed > 150, "{analysed} of 400 need cascades");
}
