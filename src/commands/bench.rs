//! `csm-lab bench`: run time against error for every quantity the tool estimates by sampling.
//!
//! Most of what csm-lab reports is closed form (splits, windows, aliasing aggregates, coverage,
//! S3 whenever a window keeps its size). Three knobs control sampled estimates, and each is
//! measured here against an exact value or a much denser run:
//!
//! * **Density profile** (`analysis.density_samples`, log-spaced depths in `density.csv`).
//!   Integrating the profile (trapezoid rule, in depth and in log depth; linear interpolation
//!   of the crossing at aliasing 1) should give back the closed-form mean aliasing, mean log
//!   aliasing and under-sampled fraction of [`csm_core::metrics::aggregates`].
//! * **Probes** (`analysis.probes`, world-fixed receivers per cascade). S4 under an unsnapped
//!   strafe has the closed form `|dx| + |dy| - |dx||dy|` per frame pair (sub-texel shift
//!   `(dx, dy)` from the window origins); S3 (RMS and max) under a yaw of the tight AABB fit,
//!   where the texel size changes every frame so the closed form does not apply, is compared
//!   with a run of [`DENSE_PROBES`] probes.
//! * **Frames** (`motion.frames`). Unsnapped S3 of the sphere fit along a yaw drifts by a
//!   heading-dependent amount each frame; the RMS over the first N frames is compared with the
//!   RMS over [`REFERENCE_TURNS`] whole turns.
//!
//! Errors are relative (`|estimate - reference| / |reference|`; absolute when the reference is
//! 0) and deterministic; times are the best of several repetitions, per evaluation, and vary
//! from run to run and machine to machine.

use std::time::Instant;

use crate::config::{Config, Fit, MotionPath};
use crate::error::{Error, GridError, Result};
use csm_core::cascades::{LightPose, Rig};
use csm_core::metrics::{self, DensitySample};
use csm_core::rig_path;
use csm_core::shimmer::{wrap, ShimmerOptions};
use csm_core::walk::PathModel;

/// The relative error the summary table asks each metric to reach.
pub(crate) const TARGET_ERROR: f64 = 1e-3;

/// Largest probe count measured: 2^12 per cascade.
pub(crate) const MAX_PROBES_LOG2: u32 = 12;

/// Probes per cascade of the dense S3 reference run (8x the largest count measured).
pub(crate) const DENSE_PROBES: usize = 1 << 15;

/// Whole turns of the frame-count reference path.
pub(crate) const REFERENCE_TURNS: usize = 16;

/// Yaw step of the probe (AABB) and frame-count metrics, degrees per frame (the indoor
/// example's step): a whole turn is 1440 frames.
pub(crate) const YAW_STEP_DEG: f64 = 0.25;

/// One measured point: a metric at one sample count.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BenchRow {
    pub metric: &'static str,
    pub samples: usize,
    /// Best wall-clock time of one evaluation at this sample count.
    pub seconds: f64,
    pub estimate: f64,
    pub reference: f64,
    /// Relative error (absolute when the reference is 0).
    pub error: f64,
}

impl BenchRow {
    /// One measurement: its error is the relative error of `estimate` against `reference`.
    pub(crate) fn measured(metric: &'static str, samples: usize, seconds: f64, estimate: f64, reference: f64) -> Self {
        BenchRow {
            metric,
            samples,
            seconds,
            estimate,
            reference,
            error: relative_error(estimate, reference),
        }
    }
}

/// What one metric measures.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MetricInfo {
    pub name: &'static str,
    /// The setting that controls the sample count.
    pub knob: &'static str,
    /// What one sample is.
    pub unit: &'static str,
    /// The sample count the tool uses by default.
    pub default: usize,
    /// How the metric's scene differs from the measured config, if it does.
    pub note: String,
}

/// Everything `bench` measured.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BenchReport {
    pub scene: String,
    pub metrics: Vec<MetricInfo>,
    pub rows: Vec<BenchRow>,
}

/// Relative error, or absolute when the reference is exactly 0.
pub(crate) fn relative_error(estimate: f64, reference: f64) -> f64 {
    if reference == 0.0 {
        (estimate - reference).abs()
    } else {
        ((estimate - reference) / reference).abs()
    }
}

/// Best time of one call of `f`, in seconds, and the value of its first call. After the
/// first call, calls are batched so one batch lasts at least about a millisecond (the clock's
/// granularity stays negligible), and the best of `repeats` timings is kept (the run least
/// disturbed by other work on the machine).
pub(crate) fn best_time<T>(repeats: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let start = Instant::now();
    let value = f();
    let once = start.elapsed().as_secs_f64();
    let batch = if once > 1e-3 {
        1
    } else {
        ((1e-3 / once.max(1e-8)).ceil() as usize).min(100_000)
    };
    let mut best = once;
    for _ in 1..repeats {
        let t = Instant::now();
        for _ in 0..batch {
            std::hint::black_box(f());
        }
        best = best.min(t.elapsed().as_secs_f64() / batch as f64);
    }
    (best, value)
}

/// Mean aliasing over depth, mean over log depth and under-sampled fraction recovered from a
/// density profile: trapezoid rule in `d` and in `ln d` between consecutive samples (the
/// profile holds both sides of every split, so no trapezoid straddles a jump), and linear
/// interpolation of where the aliasing crosses 1.
pub(crate) fn integrate_profile(profile: &[DensitySample], z_lo: f64, z_hi: f64) -> (f64, f64, f64) {
    let (mut mean, mut mean_log, mut under) = (0.0, 0.0, 0.0);
    for pair in profile.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let h = b.depth - a.depth;
        if h <= 0.0 {
            continue;
        }
        let avg = 0.5 * (a.aliasing + b.aliasing);
        mean += h * avg;
        mean_log += (b.depth / a.depth).ln() * avg;
        under += match (a.aliasing > 1.0, b.aliasing > 1.0) {
            (true, true) => h,
            (false, false) => 0.0,
            // Share of the step on the > 1 side of the crossing.
            (true, false) => h * (a.aliasing - 1.0) / (a.aliasing - b.aliasing),
            (false, true) => h * (b.aliasing - 1.0) / (b.aliasing - a.aliasing),
        };
    }
    let span = z_hi - z_lo;
    (mean / span, mean_log / (z_hi / z_lo).ln(), under / span)
}

/// Sample counts 2^lo ..= 2^hi, plus the tool's default for the knob when it lies in that
/// range (so the table can show the default's own error and time).
fn counts(lo: u32, hi: u32, default: usize) -> Vec<usize> {
    let mut out: Vec<usize> = (lo..=hi).map(|k| 1usize << k).collect();
    if (1 << lo..=1 << hi).contains(&default) {
        out.push(default);
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The config moving along `path` (a rotation of `step_deg` degrees per frame) with `fit`,
/// through the validating constructors.
fn with_path(config: &Config, path: MotionPath, step_deg: f64, frames: usize, fit: Fit) -> Result<Config> {
    config.with_fit(fit)?.with_motion(path, frames, step_deg)
}

fn poses_of(config: &Config) -> Result<Vec<csm_core::geometry::CameraPose>> {
    config.camera_path().map_err(|(frame, why)| {
        unusable(format!(
            "the {} path of this camera is invalid at frame {frame} ({why}); use a camera that is not looking straight up or down",
            config.motion.path.name()
        ))
    })
}

/// A scene `bench` cannot measure.
fn unusable(message: String) -> Error {
    GridError::Unusable {
        context: "bench".to_string(),
        message,
    }
    .into()
}

const NO_PROBE_OPTIONS: ShimmerOptions = ShimmerOptions {
    cell_flips: false,
    probe_drift: false,
    frame_rows: false,
};

/// Each cascade's texel size for the config's own camera, as `analyze` measures it.
fn frame0_texels(config: &Config, rig: &Rig) -> Vec<f64> {
    let lp0 = LightPose::new(&rig.light, &config.camera.pose());
    (0..rig.cascade_count())
        .map(|i| rig.window(i, &lp0, config.shadow.snap).texel_size())
        .collect()
}

/// The power-of-two resolution whose closed-form under-sampled fraction is closest to 1/2,
/// so the profile has an aliasing-1 crossing to find (at many settings the whole range is
/// under-sampled and any profile gives the exact fraction 1).
pub(crate) fn crossing_resolution(config: &Config) -> u32 {
    let mut best = (f64::INFINITY, config.shadow.resolution);
    for k in 4..=14 {
        let Ok(c) = config.with_resolution(1 << k) else {
            continue;
        };
        if let Some(rig) = crate::analysis::rig(&c) {
            let k_px = rig.lens.pixels_per_unit_slope(c.screen.height);
            let f = metrics::aggregates(&rig.splits, &frame0_texels(&c, &rig), k_px).undersampled_fraction;
            if (f - 0.5).abs() < best.0 {
                best = ((f - 0.5).abs(), c.shadow.resolution);
            }
        }
    }
    best.1
}

/// Density-profile metrics: mean and mean-log aliasing at the config's settings, the
/// under-sampled fraction at [`crossing_resolution`].
fn bench_density(config: &Config, crossing: u32, repeats: usize, rows: &mut Vec<BenchRow>) -> Result<()> {
    let at_crossing = config.with_resolution(crossing)?;
    for (c, metrics_here) in [
        (config, &["density_mean_aliasing", "density_mean_log_aliasing"][..]),
        (&at_crossing, &["density_undersampled_fraction"][..]),
    ] {
        let rig = crate::analysis::rig(c).expect("checked by the caller");
        let texel = frame0_texels(c, &rig);
        let k = rig.lens.pixels_per_unit_slope(c.screen.height);
        let agg = metrics::aggregates(&rig.splits, &texel, k);
        let (z_lo, z_hi) = (rig.splits[0], rig.splits[rig.cascade_count()]);
        for n in counts(1, 14, config.analysis.density_samples) {
            let (seconds, (mean, mean_log, under)) = best_time(repeats, || {
                let p = metrics::density_profile(&rig.splits, &texel, &rig.lens, c.screen.height, n);
                integrate_profile(&p, z_lo, z_hi)
            });
            for (metric, estimate, reference) in [
                ("density_mean_aliasing", mean, agg.mean_aliasing),
                ("density_mean_log_aliasing", mean_log, agg.mean_log_aliasing),
                ("density_undersampled_fraction", under, agg.undersampled_fraction),
            ] {
                if metrics_here.contains(&metric) {
                    rows.push(BenchRow::measured(metric, n, seconds, estimate, reference));
                }
            }
        }
    }
    Ok(())
}

/// S4 under the config's camera strafing unsnapped, against its closed form.
fn bench_cell_flips(config: &Config, repeats: usize, rows: &mut Vec<BenchRow>) -> Result<()> {
    // The config's own strafe step, or 0.05 world units per frame for other paths.
    let step = match config.motion.path {
        MotionPath::Strafe => config.motion.step,
        _ => 0.05,
    };
    let c = config.with_motion(MotionPath::Strafe, config.motion.frames, step)?;
    let rig = crate::analysis::rig(&c).expect("checked by the caller");
    let poses = poses_of(&c)?;
    // Closed form per frame pair and cascade, from the window origins alone.
    let m = rig.cascade_count();
    let mut sum = 0.0;
    let mut pairs = 0usize;
    let mut prev: Vec<Option<csm_core::fitting::Window>> = vec![None; m];
    let mut model = rig_path::RigPath::new(&rig, &[]);
    csm_core::walk::each_cascade_frame(&mut model, &poses, |model, _t, i, shared| {
        let w = model.window(i, shared, false).window;
        if let Some(p) = prev[i] {
            let dx = wrap(p.origin_texels.x - w.origin_texels.x).abs();
            let dy = wrap(p.origin_texels.y - w.origin_texels.y).abs();
            sum += dx + dy - dx * dy;
            pairs += 1;
        }
        prev[i] = Some(w);
    });
    let reference = sum / pairs as f64;
    let opts = ShimmerOptions {
        cell_flips: true,
        ..NO_PROBE_OPTIONS
    };
    let pose0 = c.camera.pose();
    for n in counts(0, MAX_PROBES_LOG2, config.analysis.probes) {
        let (seconds, result) = best_time(repeats, || {
            let probes = rig_path::probes(&rig, &pose0, &c.scene, n);
            rig_path::along_path(&rig, &poses, &probes, false, opts)
        });
        let estimate = result.stats.cell_flip_rate.expect("requested");
        rows.push(BenchRow::measured(
            "s4_cell_flips_strafe",
            n,
            seconds,
            estimate,
            reference,
        ));
    }
    Ok(())
}

/// S3 RMS and max of the snapped tight AABB fit under a yaw, against a dense probe run.
fn bench_aabb_drift(config: &Config, repeats: usize, rows: &mut Vec<BenchRow>) -> Result<()> {
    let c = with_path(config, MotionPath::Yaw, YAW_STEP_DEG, config.motion.frames, Fit::Aabb)?;
    let rig = crate::analysis::rig(&c).expect("checked by the caller");
    let poses = poses_of(&c)?;
    let pose0 = c.camera.pose();
    let measure = |n: usize| {
        let probes = rig_path::probes(&rig, &pose0, &c.scene, n);
        rig_path::along_path(&rig, &poses, &probes, true, NO_PROBE_OPTIONS).stats
    };
    let dense = measure(DENSE_PROBES);
    for n in counts(0, MAX_PROBES_LOG2, config.analysis.probes) {
        let (seconds, stats) = best_time(repeats, || measure(n));
        for (metric, estimate, reference) in [
            ("s3_rms_aabb_yaw", stats.rms, dense.rms),
            ("s3_max_aabb_yaw", stats.max, dense.max),
        ] {
            rows.push(BenchRow::measured(metric, n, seconds, estimate, reference));
        }
    }
    Ok(())
}

/// Unsnapped S3 RMS of the sphere fit over the first N frames of a yaw, against whole turns.
fn bench_frames(config: &Config, repeats: usize, rows: &mut Vec<BenchRow>) -> Result<()> {
    let turn = (360.0 / YAW_STEP_DEG).round() as usize;
    let long = with_path(
        config,
        MotionPath::Yaw,
        YAW_STEP_DEG,
        REFERENCE_TURNS * turn + 1,
        Fit::Sphere,
    )?;
    let rig = crate::analysis::rig(&long).expect("checked by the caller");
    let reference = {
        let poses = poses_of(&long)?;
        rig_path::along_path(&rig, &poses, &[], false, NO_PROBE_OPTIONS)
            .stats
            .rms
    };
    for n in counts(1, 14, config.motion.frames) {
        let c = with_path(config, MotionPath::Yaw, YAW_STEP_DEG, n, Fit::Sphere)?;
        let (seconds, estimate) = best_time(repeats, || -> Result<f64> {
            let poses = poses_of(&c)?;
            Ok(rig_path::along_path(&rig, &poses, &[], false, NO_PROBE_OPTIONS)
                .stats
                .rms)
        });
        let estimate = estimate?;
        rows.push(BenchRow::measured("s3_rms_frames_yaw", n, seconds, estimate, reference));
    }
    Ok(())
}

/// How many measurement groups [`run_with_progress`] reports.
pub(crate) const BENCH_STEPS: u64 = 4;

/// [`run`], calling `on_step` after each of its [`BENCH_STEPS`] measurement groups.
pub(crate) fn run_with_progress(config: &Config, repeats: usize, on_step: &dyn Fn()) -> Result<BenchReport> {
    let Some(rig) = crate::analysis::rig(config) else {
        return Err(unusable(format!(
            "{} needs no cascades (the scene is not visible within the shadow distance), so there is nothing to sample; use a scene the camera sees",
            config.name
        )));
    };
    drop(rig);
    let crossing = crossing_resolution(config);
    let mut rows = Vec::new();
    bench_density(config, crossing, repeats, &mut rows)?;
    on_step();
    bench_cell_flips(config, repeats, &mut rows)?;
    on_step();
    bench_aabb_drift(config, repeats, &mut rows)?;
    on_step();
    bench_frames(config, repeats, &mut rows)?;
    on_step();
    let a = &config.analysis;
    let turn = (360.0 / YAW_STEP_DEG).round() as usize;
    let metric = |name, knob, unit, default, note: String| MetricInfo {
        name,
        knob,
        unit,
        default,
        note,
    };
    let density = |name, note| metric(name, "analysis.density_samples", "depths", a.density_samples, note);
    let probes = |name, note| metric(name, "analysis.probes", "probes per cascade", a.probes, note);
    let aabb_yaw = format!("fit aabb, snapped, yaw {YAW_STEP_DEG} deg/frame, reference {DENSE_PROBES} probes");
    Ok(BenchReport {
        scene: config.name.clone(),
        metrics: vec![
            density("density_mean_aliasing", String::new()),
            density("density_mean_log_aliasing", String::new()),
            density(
                "density_undersampled_fraction",
                format!("at resolution {crossing} (under-sampled fraction closest to 1/2)"),
            ),
            probes("s4_cell_flips_strafe", "unsnapped strafe, closed-form reference".to_string()),
            probes("s3_rms_aabb_yaw", aabb_yaw.clone()),
            probes("s3_max_aabb_yaw", aabb_yaw),
            metric(
                "s3_rms_frames_yaw",
                "motion.frames",
                "frames",
                config.motion.frames,
                format!(
                    "fit sphere, unsnapped, yaw {YAW_STEP_DEG} deg/frame, reference {REFERENCE_TURNS} turns ({} frames)",
                    REFERENCE_TURNS * turn + 1
                ),
            ),
        ],
        rows,
    })
}

impl BenchReport {
    pub(crate) fn rows_of<'a>(&'a self, metric: &'a str) -> impl Iterator<Item = &'a BenchRow> + 'a {
        self.rows.iter().filter(move |r| r.metric == metric)
    }

    fn rows_named(&self, metric: &str) -> Vec<&BenchRow> {
        self.rows.iter().filter(|r| r.metric == metric).collect()
    }

    /// The smallest sample count whose error is at most `target` and stays so at every larger
    /// count measured (a Monte Carlo estimate can dip below the target by luck).
    pub(crate) fn first_reaching(&self, metric: &str, target: f64) -> Option<&BenchRow> {
        let rows = self.rows_named(metric);
        let mut first = None;
        for r in rows.iter().rev() {
            if r.error <= target {
                first = Some(*r);
            } else {
                break;
            }
        }
        first
    }

    /// The row measured at a sample count, if any.
    pub(crate) fn at(&self, metric: &str, samples: usize) -> Option<&BenchRow> {
        self.rows_named(metric).into_iter().find(|r| r.samples == samples)
    }
}

/// The scene `bench` measures when no `--config` is given.
pub(crate) const DEFAULT_SCENE: &str = include_str!("../../configs/default.toml");

#[cfg(test)]
mod tests {
    use super::*;
    use csm_core::geometry::Lens;
    use csm_core::splits::practical;

    /// The trapezoid integrals of a profile converge on the closed forms as the profile
    /// gets denser (second order: 4x fewer error per doubling, within a margin).
    #[test]
    fn integrated_profile_converges_on_the_closed_form_aggregates() {
        let lens = Lens::new(1.0, 1.6);
        let s = practical(0.5, 300.0, 4, 0.6);
        let t = [0.004, 0.02, 0.06, 0.2];
        let k = lens.pixels_per_unit_slope(1080);
        let agg = metrics::aggregates(&s, &t, k);
        assert!(agg.undersampled_fraction > 0.05 && agg.undersampled_fraction < 0.95);
        let err = |n: usize| {
            let p = metrics::density_profile(&s, &t, &lens, 1080, n);
            let (m, ml, u) = integrate_profile(&p, 0.5, 300.0);
            [
                relative_error(m, agg.mean_aliasing),
                relative_error(ml, agg.mean_log_aliasing),
                relative_error(u, agg.undersampled_fraction),
            ]
        };
        let (coarse, fine) = (err(256), err(1024));
        for j in 0..3 {
            assert!(fine[j] < 1e-3, "{j}: {fine:?}");
            assert!(fine[j] < coarse[j] / 8.0, "{j}: {coarse:?} -> {fine:?}");
        }
    }

    /// 128 depths suffice for the default scene, but the trapezoid error grows with
    /// (ln(z_hi / z_lo) / n)^2: the default 512 keeps the stress battery's widest range
    /// (1e-4 .. 1e6) and the widest the loader accepts (far / near = 1e12) within the target,
    /// which 128 does not.
    #[test]
    fn the_default_density_samples_reach_the_target_up_to_the_widest_depth_ratio() {
        let lens = Lens::new(60f64.to_radians(), 16.0 / 9.0);
        for (n, f) in [(1e-4, 1e6), (1e-4, 1e8)] {
            for cascades in [1, 4, 16] {
                let s = practical(n, f, cascades, 0.75);
                let t: Vec<f64> = s
                    .windows(2)
                    .map(|w| 2.0 * csm_core::fitting::minimal_sphere(w[0], w[1], lens.k2()).radius / 2048.0)
                    .collect();
                let agg = metrics::aggregates(&s, &t, lens.pixels_per_unit_slope(1080));
                let err = |count: usize| {
                    let p = metrics::density_profile(&s, &t, &lens, 1080, count);
                    let (m, ml, _) = integrate_profile(&p, n, f);
                    relative_error(m, agg.mean_aliasing).max(relative_error(ml, agg.mean_log_aliasing))
                };
                let default = crate::config::AnalysisSettings::default().density_samples;
                assert!(err(default) < TARGET_ERROR, "{f}/{n}, {cascades}: {}", err(default));
                assert!(err(128) > TARGET_ERROR, "{f}/{n}, {cascades}: {}", err(128));
            }
        }
    }

    #[test]
    fn relative_error_is_absolute_against_zero() {
        assert_eq!(relative_error(1.5, 1.0), 0.5);
        assert_eq!(relative_error(0.25, 0.0), 0.25);
        assert_eq!(relative_error(-2.0, -4.0), 0.5);
    }

    fn row(samples: usize, error: f64) -> BenchRow {
        BenchRow {
            metric: "m",
            samples,
            seconds: 1e-6 * samples as f64,
            estimate: 0.0,
            reference: 0.0,
            error,
        }
    }

    #[test]
    fn the_first_count_reaching_the_target_must_stay_below_it() {
        let report = BenchReport {
            scene: "x".into(),
            metrics: Vec::new(),
            rows: vec![row(1, 0.1), row(2, 5e-4), row(4, 2e-3), row(8, 9e-4), row(16, 1e-4)],
        };
        assert_eq!(report.first_reaching("m", 1e-3).map(|r| r.samples), Some(8));
        assert_eq!(report.first_reaching("m", 1e-5), None);
        assert_eq!(report.first_reaching("m", 1.0).map(|r| r.samples), Some(1));
    }
}
