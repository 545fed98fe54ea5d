//! Criterion benchmarks of the kernels: one cascade build, one configuration's analysis, the
//! default sweep's compute (with and without the screen metrics), the visibility pass and an
//! engine settings file's fit, writing and reading.
//! Run with `cargo bench --bench kernels`; figures are in docs/speed.md.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec2;

use csm_core::cascades::{LightPose, Rig};
use csm_core::depth_range;
use csm_core::fitting::{minimal_sphere, Window};
use csm_core::geometry::{Lens, LightBasis};
use csm_core::snapping::SnapRule;
use csm_core::splits;
use csm_core::visibility::SceneGeometry;
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::commands::sweep::grid::Grid;
use csm_lab::commands::sweep::run as sweep;
use csm_lab::config::sweep_spec::SweepAxes;
use csm_lab::config::Config;

#[path = "common/terrain.rs"]
mod terrain;
use terrain::terrain;

fn default_config() -> Config {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
    Config::load(&path).expect("configs/default.toml loads")
}

fn cascade_build(c: &mut Criterion) {
    let config = default_config();
    let (z_lo, z_hi) = depth_range::for_setup(&config.setup())
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

    // One cascade: its two split depths, its minimal sphere, the bordered window side, and the
    // snapped window for the configured camera.
    let k2 = lens.k2();
    let (m, i) = (s.cascades, 1usize);
    c.bench_function("cascade_build/one_cascade", |b| {
        b.iter(|| {
            let (lo, hi, lambda) = (black_box(z_lo), black_box(z_hi), black_box(s.lambda));
            let near = lambda * splits::logarithmic(lo, hi, i, m) + (1.0 - lambda) * splits::uniform(lo, hi, i, m);
            let far =
                lambda * splits::logarithmic(lo, hi, i + 1, m) + (1.0 - lambda) * splits::uniform(lo, hi, i + 1, m);
            let sphere = minimal_sphere(near, far, k2);
            let rule = SnapRule::default();
            let side = Window::side_with_border(2.0 * sphere.radius, s.resolution, rule.max_shift_texels());
            let centre = lp.position + lp.forward * sphere.centre_depth;
            Window::centred(centre, DVec2::splat(side), s.resolution, Some(rule))
        })
    });

    // The per-frame part alone: the camera's light-space frame and one snapped window.
    let rig = csm_lab::analysis::rig(&config).expect("default scene needs cascades");
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
    // The sweep exactly as `csm-lab sweep configs/default.toml` computes it: the grid of the
    // config's [sweep] table (21 λ × 8 counts × 4 resolutions, 240 frames, both snap modes).
    let base = default_config();
    let grid = Grid::resolve(&base, &SweepAxes::default()).expect("default grid");
    assert_eq!(grid.len(), 672);
    let mut group = c.benchmark_group("sweep");
    group.sample_size(20);
    group.bench_function("default_672_configs", |b| {
        b.iter(|| black_box(sweep::run(&base, &grid, None, &|| {}).expect("sweep runs")))
    });
    // One core: the figure to compare when other work shares the machine.
    group.bench_function("default_672_configs_one_thread", |b| {
        b.iter(|| black_box(sweep::run(&base, &grid, Some(1), &|| {}).expect("sweep runs")))
    });
    // The same grid with and without scene geometry: the cost of the screen metrics.
    let mut bounds_only = base.clone();
    bounds_only.geometry = None;
    group.bench_function("default_672_configs_bounds_only", |b| {
        b.iter(|| black_box(sweep::run(&bounds_only, &grid, None, &|| {}).expect("sweep runs")))
    });
    group.finish();
}

fn visibility_pass(c: &mut Criterion) {
    let config = default_config();
    let mut setup = config.setup();
    setup
        .geometry
        .as_mut()
        .expect("default scene has geometry")
        .screen_scale = 1.0;
    let view = setup.view().expect("a view");
    let mesh = setup.geometry.as_ref().unwrap().scene.mesh.clone();
    let mut group = c.benchmark_group("visibility");
    group.sample_size(10);
    // One full-HD pass (1920 x 1080 rays), the BVH build included.
    group.bench_function("default_scene_full_hd", |b| {
        b.iter(|| black_box(SceneGeometry::new(mesh.clone()).cast(&view).receivers.len()))
    });
    let big = terrain(224);
    assert!(big.triangles.len() >= 100_000);
    group.bench_function("terrain_100k_triangles_full_hd", |b| {
        b.iter(|| black_box(SceneGeometry::new(big.clone()).cast(&view).receivers.len()))
    });
    group.finish();
    // Traversal alone (which triangle each full-HD primary ray meets; the BVH built once), on
    // one thread: the kernel `scripts/speed/20-rays.sh` pairs with Embree.
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
    let mut group = c.benchmark_group("traversal");
    group.sample_size(10);
    group.throughput(criterion::Throughput::Elements(1920 * 1080));
    for (name, mesh) in [("default_scene_full_hd", mesh), ("terrain_100k_full_hd", big)] {
        let scene = SceneGeometry::new(mesh);
        let _ = scene.bvh_dropped();
        group.bench_function(name, |b| b.iter(|| one.install(|| black_box(scene.trace(&view).len()))));
    }
    group.finish();
}

/// `recommendation.<engine>.txt`: matching Unreal's exponent to csm-lab's cascades (the 1-D
/// fit), and writing a Bevy setting and reading it back.
fn engine_terms(c: &mut Criterion) {
    use csm_lab::commands::terms::EngineSetting;
    use csm_lab::presets::{apply_terms, PresetChoice, PresetName, Target};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
    let load = |p| {
        let choice = PresetChoice {
            name: Some(p),
            lenient_overrides: true,
            ..Default::default()
        };
        Config::load_with_preset(&path, &choice).expect("configs/default.toml loads")
    };
    let own = default_config();
    let rig = csm_lab::analysis::rig(&own).expect("cascades");
    let mut ends = vec![rig.slices[0].near];
    ends.extend(rig.slices.iter().map(|s| s.far));
    let unreal = load(PresetName::Unreal);
    let knobs = unreal.shadow.preset.as_ref().expect("preset").knobs.clone();
    let target = Target {
        ends: &ends,
        distance: 150.0,
        near: own.camera.near,
        far: own.camera.far,
    };
    c.bench_function("engine_terms/unreal_exponent_fit", |b| {
        b.iter(|| {
            let mut k = knobs.clone();
            PresetName::Unreal.engine().match_ends(&mut k, black_box(&target));
            k
        })
    });
    let bevy = load(PresetName::Bevy);
    let setting = EngineSetting::of(&bevy, Vec::new()).expect("preset");
    c.bench_function("engine_terms/bevy_write_and_read_back", |b| {
        b.iter(|| {
            let text = csm_lab::report::terms::text(black_box(&setting));
            let mut c = bevy.clone();
            apply_terms(&mut c, &text, "recommendation.bevy.txt").expect("reads back");
            c
        })
    });
}

/// One sun angle of a sun-angle sweep of the default scene (the configured setting): what each
/// of the 408 angles of `--sun-azimuth 0:345:15 --sun-elevation 5:85:5` costs. Bounds only, it
/// is one analysis; with screen metrics, the rays are cast once (shared by every angle) and each
/// angle shades them (lit flag, geometric factor, receivers sorted) before its analysis.
fn sun_angle(c: &mut Criterion) {
    use csm_lab::commands::sweep::grid::Sun;
    let config = default_config();
    let mut bounds_only = config.clone();
    bounds_only.geometry = None;
    // More angles than the pass cache holds, so every iteration shades afresh.
    let suns: Vec<Sun> = (0..24)
        .map(|k| Sun {
            azimuth_deg: 15.0 * k as f64,
            elevation_deg: 5.0 + 3.0 * k as f64,
        })
        .collect();
    let lit = |base: &Config, k: usize| {
        base.with_light_direction(suns[k % suns.len()].light_direction())
            .expect("a valid light")
    };
    let bounds_configs: Vec<Config> = (0..suns.len()).map(|k| lit(&bounds_only, k)).collect();
    let screen_configs: Vec<Config> = (0..suns.len()).map(|k| lit(&config, k)).collect();
    let _ = screen_configs[0].setup().visibility_hits();
    let mut group = c.benchmark_group("sun");
    let mut k = 0;
    group.bench_function("one_angle_bounds_only", |b| {
        b.iter(|| {
            k += 1;
            black_box(analyze(&bounds_configs[k % suns.len()], &AnalysisOptions::summary_only()).summary)
        })
    });
    group.bench_function("one_angle_screen_metrics", |b| {
        b.iter(|| {
            k += 1;
            black_box(analyze(&screen_configs[k % suns.len()], &AnalysisOptions::summary_only()).summary)
        })
    });
    // The two parts of the visibility pass alone: casting the rays (once per sweep) and
    // shading them under one light (once per angle).
    let setup = config.setup();
    let view = setup.view().expect("a view");
    let scene = setup.geometry.as_ref().unwrap().scene.clone();
    // The rays of a fresh scene, its BVH build included (as a sweep pays it once).
    group.bench_function("visibility_cast_rays", |b| {
        b.iter(|| black_box(SceneGeometry::new(scene.mesh.clone()).hits(&view).len()))
    });
    let hits = scene.hits(&view);
    group.bench_function("visibility_shade_one_light", |b| {
        b.iter(|| {
            k += 1;
            let v = csm_core::visibility::View {
                light: suns[k % suns.len()].light_direction(),
                ..view
            };
            black_box(hits.shade(&v).receivers.len())
        })
    });
    group.finish();
}

/// Ground truth on the default scene: the frame-0 pass (one texel ray and one truth ray per
/// receiver) and one unsnapped path frame (every texel new), reported as rays per second by
/// criterion's throughput; the texel-cache hit rate of a whole 240-frame walk is printed.
fn ground_truth(c: &mut Criterion) {
    use csm_core::truth::{self, DepthFormat, Sampling};
    let config = default_config();
    let setup = config.setup();
    let vis = setup.visibility().expect("default scene has geometry");
    let scene = setup.geometry.as_ref().unwrap().scene.clone();
    let rig = csm_lab::analysis::rig(&config).expect("cascades");
    let pose = config.camera.pose();
    let points = truth::receivers(&scene, &vis);
    let m = rig.cascade_count();
    let s = Sampling {
        bias: vec![truth::Bias::depth(0.05); m],
        format: Some(DepthFormat::D32F),
        ranges: vec![(-500.0, 500.0); m],
        pcf: 1,
        filter: truth::PcfFilter::Bilinear,
        binary32: None,
    };
    let poses = || csm_core::motion::poses(&setup.camera, &setup.motion).map_while(|p| p.ok());
    for snapped in [true, false] {
        let every = csm_core::walk::Cadence::EVERY_FRAME;
        let f = truth::flicker_cached(
            truth::ShadowMaps::new(&scene),
            &rig,
            &rig.light,
            poses(),
            snapped,
            &points,
            &s,
            every,
            &mut |_, _| {},
        );
        println!(
            "ground truth walk, {} frames, snapped {snapped}: {} texel reads, {} rays, cache hit rate {:.4}",
            f.frames,
            f.stats.reads,
            f.stats.rays,
            f.stats.hit_rate()
        );
    }
    let mut group = c.benchmark_group("ground_truth");
    group.sample_size(10);
    // Frame 0: one texel ray and one truth ray per receiver.
    group.throughput(criterion::Throughput::Elements(2 * points.len() as u64));
    group.bench_function("frame0_rays", |b| {
        b.iter(|| {
            black_box(truth::frame_zero(
                truth::ShadowMaps::new(&scene),
                &rig,
                &rig.light,
                &pose,
                true,
                &points,
                &s,
            ))
        })
    });
    // One unsnapped frame after frame 0: every receiver's texel is a new ray.
    let two: Vec<_> = poses().take(2).collect();
    group.throughput(criterion::Throughput::Elements(2 * points.len() as u64));
    group.bench_function("two_unsnapped_frames_rays", |b| {
        b.iter(|| {
            black_box(truth::flicker_cached(
                truth::ShadowMaps::new(&scene),
                &rig,
                &rig.light,
                two.iter().copied(),
                false,
                &points,
                &s,
                csm_core::walk::Cadence::EVERY_FRAME,
                &mut |_, _| {},
            ))
        })
    });
    group.finish();
}

criterion_group!(
    benches,
    cascade_build,
    one_analysis,
    default_sweep,
    visibility_pass,
    engine_terms,
    sun_angle,
    ground_truth
);
criterion_main!(benches);
