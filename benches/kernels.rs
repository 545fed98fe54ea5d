//! Criterion benchmarks of the kernels: one cascade build, one configuration's analysis and the
//! default sweep's compute. Run with `cargo bench --bench kernels`; figures are in docs/speed.md.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use rayon::prelude::*;

use csm_lab::analysis::{analyze, AnalysisOptions, Summary};
use csm_lab::cascades::{LightPose, Rig};
use csm_lab::config::{Config, Fit};
use csm_lab::depth_range;
use csm_lab::geometry::{Lens, LightBasis};
use csm_lab::snapping::SnapRule;
use csm_lab::splits;

fn default_config() -> Config {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
    Config::load(&path).expect("configs/default.toml loads")
}

/// The default sweep's 672 configurations: lambda 0..=1 in steps of 0.05 (i / 20, so each value
/// is the double nearest the decimal), 1..=8 cascades, four resolutions; sphere fit, 240
/// frames. Both snap modes are measured inside every `analyze` call.
fn sweep_configs(base: &Config) -> Vec<Config> {
    let mut out = Vec::with_capacity(672);
    for i in 0..=20 {
        for cascades in 1..=8 {
            for resolution in [512, 1024, 2048, 4096] {
                let mut c = base.clone();
                c.shadow.lambda = i as f64 / 20.0;
                c.shadow.cascades = cascades;
                c.shadow.resolution = resolution;
                c.shadow.fit = Fit::Sphere;
                c.motion.frames = 240;
                out.push(c);
            }
        }
    }
    out
}

fn cascade_build(c: &mut Criterion) {
    let config = default_config();
    let (z_lo, z_hi) = depth_range::for_config(&config)
        .bounds()
        .expect("default scene needs cascades");
    let lens = Lens::new(config.camera.fov_y(), config.screen.aspect());
    let light = LightBasis::new(config.light_direction);
    let lp = LightPose::new(&light, &config.camera.pose());
    let s = &config.shadow;

    // Split + fit (+ the per-cascade sphere sides) + one snapped window: a whole build.
    c.bench_function("cascade_build/split_fit_snap", |b| {
        b.iter(|| {
            let splits = splits::practical(black_box(z_lo), black_box(z_hi), s.cascades, black_box(s.lambda));
            let rig = Rig::new(lens, light, s.fit, s.resolution, SnapRule::default(), splits);
            rig.window(black_box(0), black_box(&lp), true)
        })
    });

    // The per-frame part alone: the camera's light-space frame and one snapped window.
    let rig = Rig::from_config(&config).expect("default scene needs cascades");
    let pose = config.camera.pose();
    c.bench_function("cascade_build/window_per_frame", |b| {
        b.iter(|| {
            let lp = LightPose::new(&rig.light, black_box(&pose));
            rig.window(black_box(3), &lp, black_box(true))
        })
    });
}

fn one_analysis(c: &mut Criterion) {
    let config = default_config();
    c.bench_function("analyze/default_summary_only", |b| {
        b.iter(|| analyze(black_box(&config), &AnalysisOptions::summary_only()).summary)
    });
}

fn default_sweep(c: &mut Criterion) {
    let base = default_config();
    let configs = sweep_configs(&base);
    assert_eq!(configs.len(), 672);
    let mut group = c.benchmark_group("sweep");
    group.sample_size(20);
    group.bench_function("default_672_configs", |b| {
        b.iter(|| {
            let rows: Vec<Summary> = configs
                .par_iter()
                .map(|c| analyze(c, &AnalysisOptions::summary_only()).summary)
                .collect();
            black_box(rows)
        })
    });
    // One core: the figure to compare when other work shares the machine.
    group.bench_function("default_672_configs_one_thread", |b| {
        b.iter(|| {
            let rows: Vec<Summary> = configs
                .iter()
                .map(|c| analyze(c, &AnalysisOptions::summary_only()).summary)
                .collect();
            black_box(rows)
        })
    });
    group.finish();
}

criterion_group!(benches, cascade_build, one_analysis, default_sweep);
criterion_main!(benches);
