//! Criterion benchmarks of the ground-truth pictures on the default grid (240 × 135, both snap
//! modes): `shadow.png`, `flicker.png`, the 240-frame `shadow.apng` and the scatter's SVG and
//! PNG. Inputs are synthetic (the visibility pass's receivers lit or shadowed by their own
//! `lit` flag, a moving acne pattern). Run with `cargo bench --bench pictures`; figures are in
//! docs/speed.md.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};

use csm_core::shade::{FlipImage, Shade, ShadeImage};
use csm_lab::config::Config;
use csm_lab::figures::truth::{
    flicker_png, shadow_png, write_animation, AnimationPlan, FlickerVsShimmer, Panel, ShimmerPoint, ANIMATION_CAPS,
};
use csm_lab::figures::Figure;

fn default_images() -> (ShadeImage, ShadeImage, FlipImage) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
    let config = Config::load(&path).expect("configs/default.toml loads");
    let vis = config.setup().visibility().expect("the default scene has geometry");
    let mut snapped = ShadeImage::empty(vis.cols, vis.rows);
    for (k, s) in vis.samples.iter().enumerate() {
        if let Some(s) = s {
            snapped.pixels[k] = if s.lit { Shade::Lit } else { Shade::Shadowed };
        }
    }
    let unsnapped = acne(&snapped, 0);
    let flips = FlipImage {
        cols: vis.cols,
        rows: vis.rows,
        flips: snapped
            .pixels
            .iter()
            .enumerate()
            .map(|(k, s)| (*s != Shade::Empty).then(|| (k % 13) as f64 / 12.0))
            .collect(),
    };
    (snapped, unsnapped, flips)
}

/// Every 7th lit pixel as acne, the pattern moving by one pixel per frame.
fn acne(im: &ShadeImage, frame: usize) -> ShadeImage {
    let mut u = im.clone();
    for (k, p) in u.pixels.iter_mut().enumerate() {
        if *p == Shade::Lit && (k + frame) % 7 == 0 {
            *p = Shade::Acne;
        }
    }
    u
}

fn pictures(c: &mut Criterion) {
    let (snapped, unsnapped, flips) = default_images();
    let mut g = c.benchmark_group("pictures");
    g.sample_size(10);
    g.bench_function("shadow_png/default_grid_two_panels", |b| {
        b.iter(|| black_box(shadow_png(&[Panel::snapped(&snapped), Panel::unsnapped(&unsnapped)]).unwrap()))
    });
    g.bench_function("flicker_png/default_grid_two_panels", |b| {
        b.iter(|| black_box(flicker_png(&[Panel::snapped(&flips), Panel::unsnapped(&flips)]).unwrap()))
    });
    let plan = AnimationPlan::new(
        240,
        snapped.cols,
        snapped.rows,
        &["snapped", "unsnapped"],
        &ANIMATION_CAPS,
    )
    .unwrap();
    g.bench_function("shadow_apng/240_frames_48_shown", |b| {
        b.iter(|| {
            let mut out = Vec::new();
            let frames = (0..240).map(|f| vec![snapped.clone(), acne(&snapped, f)]);
            black_box(write_animation(&plan, frames, &mut out).unwrap())
        })
    });
    let points: Vec<ShimmerPoint> = (0..200)
        .map(|i| {
            let t = i as f64 / 200.0;
            ShimmerPoint {
                s3: t * 0.1,
                s4: t * t,
                s5: if i % 2 == 0 { 0.0 } else { 0.05 * t },
                snapped: i % 2 == 0,
            }
        })
        .collect();
    let fig = FlickerVsShimmer {
        name: "default",
        points: &points,
    };
    g.bench_function("flicker_vs_shimmer/200_points_svg_png", |b| {
        b.iter(|| black_box(fig.to_png().unwrap()))
    });
    g.finish();
}

criterion_group!(benches, pictures);
criterion_main!(benches);
