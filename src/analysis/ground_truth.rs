//! The ground-truth pass of one analysis: frame 0's receivers sampled through the maps with the
//! configured bias (acne, leaks, the bias needed per cascade, peter-panning) and S5 flicker along
//! the motion path in both snap modes, with the pictures' data (frame-0 states, flip rates and
//! every k-th frame's states). The math is [`csm_core::truth`].

use crate::config::{BiasMode, Config};
use crate::presets::bias::{engine_bias, engine_filter, EngineBias};
use csm_core::cascades::{LightPose, Rig};
use csm_core::scene::Precision;
use csm_core::shade::{FlipImage, ShadeImage};
use csm_core::truth::{
    self, Bias, Binary32, CacheStats, CascadeTruth, Flicker, PcfFilter, PointZero, Receiver, Sampling,
};

/// At most this many frames of the path are kept as pictures for the animation (every k-th).
pub(crate) const ANIMATION_FRAMES: usize = 24;

/// The flat ground-truth metrics of the summary.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TruthSummary {
    pub acne_fraction: f64,
    pub edge_error_fraction: f64,
    pub leak_fraction: f64,
    pub flicker_snapped: f64,
    pub flicker_unsnapped: f64,
    pub flicker_edge_snapped: f64,
    pub flicker_edge_unsnapped: f64,
    pub flicker_acne_snapped: f64,
    pub flicker_acne_unsnapped: f64,
}

/// Where the bias the pass sampled with came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BiasSource {
    /// The `[shadow]` bias keys.
    Configured,
    /// The preset engine's default bias rule.
    Engine,
    /// csm-lab's recommended depth bias per cascade (the default without keys or an engine
    /// rule, or `[shadow] bias = "recommended"`).
    Recommended,
    /// No bias (`[shadow] bias = "none"` or `analyze --raw-bias`).
    None,
}

impl BiasSource {
    pub fn name(self) -> &'static str {
        match self {
            BiasSource::Configured => "configured",
            BiasSource::Engine => "engine",
            BiasSource::Recommended => "recommended",
            BiasSource::None => "none",
        }
    }
}

/// One snap mode's pictures.
#[derive(Debug, Clone, PartialEq)]
pub struct ModePictures {
    /// Frame 0's states.
    pub frame0: ShadeImage,
    /// How often each receiver pixel flipped along the path.
    pub flips: FlipImage,
    /// Every k-th frame's states (k = ceil(frames / [`ANIMATION_FRAMES`])), with its frame index.
    pub animation: Vec<(usize, ShadeImage)>,
}

/// Everything the pass measured.
#[derive(Debug, Clone)]
pub struct GroundTruth {
    pub summary: TruthSummary,
    /// Per cascade, frame 0 with the configured snap mode.
    pub cascades: Vec<CascadeTruth>,
    /// The bias each cascade was sampled with (world units; normal offset in texels).
    pub bias: Vec<Bias>,
    /// Where that bias came from.
    pub bias_source: BiasSource,
    /// The filter of each PCF tap.
    pub filter: PcfFilter,
    pcf: u32,
    /// Frame 0's light depth range per cascade (the depth formats' range).
    pub ranges: Vec<(f64, f64)>,
    /// Texel size per cascade at frame 0.
    pub texel: Vec<f64>,
    /// The engine's bias rule, when the preset's bias is modelled and no `[shadow]` bias key
    /// replaced it (the recommendation is given in its setting; the pass sampled with it when
    /// `bias_source` is `engine`).
    pub engine: Option<EngineBias>,
    pub receivers: usize,
    pub snapped: Flicker,
    pub unsnapped: Flicker,
    pub pictures_snapped: ModePictures,
    pub pictures_unsnapped: ModePictures,
    /// Texel reads and rays of the whole pass (0 when the analysis did not ask for them,
    /// [`crate::analysis::AnalysisOptions::texel_counts`]).
    pub cache: CacheStats,
    /// The receiver points (frame 0's lit-facing pixels).
    pub points: Vec<Receiver>,
    /// Frame 0's answers (configured snap mode), one per receiver.
    pub zero: Vec<PointZero>,
}

impl GroundTruth {
    /// The PCF kernel width the pass sampled with.
    pub(crate) fn pcf(&self) -> u32 {
        self.pcf
    }

    /// A cascade's recommended depth bias (configured format) in the engine's own unit, or in
    /// world units without an engine rule.
    /// None when the cascade has too few receivers.
    pub(crate) fn recommended_own(&self, i: usize, format: truth::DepthFormat) -> Option<f64> {
        let c = &self.cascades[i];
        let world = c.depth_bias?[DepthFormatIndex::of(format)];
        Some(match &self.engine {
            Some(e) => e.own_value(world, self.texel[i], self.ranges[i].1 - self.ranges[i].0),
            None => world,
        })
    }
}

struct DepthFormatIndex;

impl DepthFormatIndex {
    fn of(f: truth::DepthFormat) -> usize {
        truth::DepthFormat::ALL.iter().position(|x| *x == f).unwrap_or(2)
    }
}

/// Most texel reads the pass may be asked for, estimated before any work ([`cost`]): 2^30,
/// about 17 times the default scene's estimate (62 million; docs/speed.md gives its time).
pub const MAX_TEXEL_READS: u64 = 1 << 30;

/// The pass's size, estimated before any work from the settings alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cost {
    /// Sampled pixels of the visibility pass: at most this many receivers.
    pub pixels: u64,
    /// Frames of the first motion path.
    pub frames: u64,
    /// Texels one lookup reads: `pcf²`, four times that with the bilinear filter.
    pub per_lookup: u64,
    /// `pixels × (frames + 2) × 2 × per_lookup` (every receiver looked up in every frame of both
    /// snap modes, plus frame 0's two passes), saturating: an upper bound of the texel reads.
    pub reads: u64,
}

/// The filter the pass samples with: `[shadow] pcf_filter`, else the preset engine's, else
/// bilinear.
fn filter_of(config: &Config) -> PcfFilter {
    let preset = config.shadow.preset.as_ref().map(|p| p.name);
    config
        .truth
        .pcf_filter
        .unwrap_or_else(|| preset.map_or(PcfFilter::Bilinear, engine_filter))
}

/// [`Cost`] of a config's pass.
pub fn cost(config: &Config) -> Cost {
    let scale = config.analysis.screen_scale();
    let n = |x: u32| ((f64::from(x) * scale).round() as u64).clamp(1, u64::from(x.max(1)));
    let pixels = n(config.screen.width).saturating_mul(n(config.screen.height));
    let setup = config.setup();
    let frames = csm_core::motion::poses(&setup.camera, &setup.motion).len() as u64;
    let taps = u64::from(config.truth.pcf).pow(2);
    let per_lookup = if filter_of(config) == PcfFilter::Bilinear {
        4 * taps
    } else {
        taps
    };
    let reads = pixels
        .saturating_mul(frames.saturating_add(2))
        .saturating_mul(2)
        .saturating_mul(per_lookup);
    Cost {
        pixels,
        frames,
        per_lookup,
        reads,
    }
}

/// Refuses, before any work, a pass whose estimated texel reads exceed [`MAX_TEXEL_READS`],
/// naming `source` (the key or flag that asked for the pass), the estimate and the keys that
/// lower it.
pub(crate) fn cost_fits(config: &Config, source: &str) -> crate::error::Result<()> {
    let c = cost(config);
    if c.reads <= MAX_TEXEL_READS {
        return Ok(());
    }
    // The scale at which the estimate fits (reads grow with the scale squared).
    let fits = config.analysis.screen_scale() * (MAX_TEXEL_READS as f64 / c.reads as f64).sqrt();
    Err(crate::error::GridError::Unusable {
        context: source.to_string(),
        message: format!(
            "the ground-truth pass would read about {} texels ({} sampled pixels x ({} frames + 2) x 2 snap modes x {} \
             texels per lookup), more than its limit of {MAX_TEXEL_READS}; lower analysis.screen_scale (at most {} \
             fits), motion.frames or shadow.pcf, or use pcf_filter = \"nearest\"",
            c.reads,
            c.pixels,
            c.frames,
            c.per_lookup,
            (fits * 1e4).floor() / 1e4,
        ),
    }
    .into())
}

/// The pass for a config whose scene has geometry and cascades; None otherwise. `on_frames`
/// hears of every frame walked (both snap modes: `2 × frames` in all). The texel counts
/// ([`GroundTruth::cache`]) are taken only when `counts` is set (0 otherwise).
pub(crate) fn run(config: &Config, rig: &Rig, counts: bool, on_frames: &(dyn Fn(u64) + Sync)) -> Option<GroundTruth> {
    let setup = config.setup();
    let vis = setup.visibility()?;
    let scene = &setup.geometry.as_ref()?.scene;
    let pose0 = config.camera.pose();
    let lp0 = LightPose::new(&rig.light, &pose0);
    let m = rig.cascade_count();
    let snap = config.shadow.snap;
    let windows0: Vec<_> = (0..m).map(|i| rig.window(i, &lp0, snap)).collect();
    let ranges: Vec<(f64, f64)> = windows0
        .iter()
        .enumerate()
        .map(|(i, w)| {
            let d = rig.light_depth(i, &lp0, w, &config.scene);
            (d.near, d.far)
        })
        .collect();
    let texel: Vec<f64> = windows0.iter().map(|w| w.texel_size()).collect();
    let t = &config.truth;
    let preset = config.shadow.preset.as_ref().map(|p| p.name);
    let filter = filter_of(config);
    let engine = if t.bias_written() {
        None
    } else {
        preset.and_then(engine_bias)
    };
    let bias_source = match (t.bias_mode, t.bias_written(), &engine) {
        (Some(BiasMode::None), _, _) => BiasSource::None,
        (Some(BiasMode::Recommended), _, _) => BiasSource::Recommended,
        (None, true, _) => BiasSource::Configured,
        (None, false, Some(_)) => BiasSource::Engine,
        (None, false, None) => BiasSource::Recommended,
    };
    let unbiased = Sampling {
        bias: vec![Bias::ZERO; m],
        format: Some(t.depth_format),
        ranges: ranges.clone(),
        pcf: t.pcf,
        filter,
        binary32: (config.shadow.precision == Precision::F32)
            .then(|| Binary32::new(rig, config.shadow.snap_space, config.scene)),
    };
    // The receivers and their exact answers: cast once per view and light, shared by a
    // sweep's rows.
    let exact = truth::exact_of(scene, &vis, rig.light.z);
    let points: Vec<Receiver> = exact.points.clone();
    let maps = || truth::ShadowMaps::new(scene).counting(counts);
    // Frame 0's answers with a given sampling, from the shared exact answers.
    let frame_zero =
        |s: &Sampling| truth::frame_zero_exact(maps(), rig, &rig.light, &pose0, snap, &points, &exact.occluders, s);
    let away = truth::away_pixels(&vis);
    let mut zero_stats = CacheStats::default();
    let bias: Vec<Bias> = match bias_source {
        BiasSource::None => unbiased.bias.clone(),
        BiasSource::Configured => vec![
            Bias {
                depth: t.depth_bias.unwrap_or(0.0),
                slope: t.slope_bias.unwrap_or(0.0),
                normal: t.normal_bias.unwrap_or(0.0),
                ..Bias::ZERO
            };
            m
        ],
        BiasSource::Engine => {
            let e = engine.expect("an engine rule");
            (0..m)
                .map(|i| e.rule.for_cascade(texel[i], ranges[i].1 - ranges[i].0))
                .collect()
        }
        BiasSource::Recommended => {
            // The bias needed comes from the unbiased lookups; the pass then samples with it.
            let (zero, stats) = frame_zero(&unbiased);
            zero_stats.add(stats);
            let needed: Vec<Option<f64>> = truth::cascade_truth(&zero, m, &unbiased)
                .iter()
                .map(|c| c.chosen_bias)
                .collect();
            recommended_bias(&needed, &texel).into_iter().map(Bias::depth).collect()
        }
    };
    let sampling = Sampling {
        bias: bias.clone(),
        ..unbiased
    };
    let (zero, stats) = frame_zero(&sampling);
    zero_stats.add(stats);
    let truly_lit: Vec<bool> = zero.iter().map(|p| p.truly_lit).collect();
    let cascades = truth::cascade_truth(&zero, m, &sampling);
    let [acne, edge, leak] = truth::error_fractions(&zero).unwrap_or([0.0; 3]);

    let frames = csm_core::motion::poses(&setup.camera, &setup.motion).len();
    let every = frames.div_ceil(ANIMATION_FRAMES).max(1);
    // Cached cascades hold their maps between updates (empty: every frame).
    let every_cascade = crate::analysis::cadence(config, rig);
    let (cols, rows) = (vis.cols, vis.rows);
    // Both snap modes in one pass over the receivers per frame (they share each receiver's
    // cascade); each mode's pictures from its own states.
    let poses = csm_core::motion::poses(&setup.camera, &setup.motion).map_while(|p| p.ok());
    let mut frame0 = [ShadeImage::empty(cols, rows), ShadeImage::empty(cols, rows)];
    let mut animation: [Vec<_>; 2] = [Vec::new(), Vec::new()];
    let mut walked = truth::flicker_walks(
        vec![(maps(), true), (maps(), false)],
        rig,
        &rig.light,
        poses,
        &points,
        &sampling,
        csm_core::walk::Cadence {
            every: &every_cascade,
            first_frame: 0,
        },
        &mut |w, k, states| {
            on_frames(1);
            if k == 0 {
                frame0[w] = truth::shade_image(cols, rows, &away, &points, &truly_lit, states);
            }
            if k % every == 0 {
                animation[w].push((k, truth::shade_image(cols, rows, &away, &points, &truly_lit, states)));
            }
        },
    );
    let (unsnapped, snapped) = (walked.pop().expect("two walks"), walked.pop().expect("two walks"));
    let [frame0_snapped, frame0_unsnapped] = frame0;
    let [animation_snapped, animation_unsnapped] = animation;
    let pictures_snapped = ModePictures {
        frame0: frame0_snapped,
        flips: truth::flip_image(cols, rows, &points, &snapped),
        animation: animation_snapped,
    };
    let pictures_unsnapped = ModePictures {
        frame0: frame0_unsnapped,
        flips: truth::flip_image(cols, rows, &points, &unsnapped),
        animation: animation_unsnapped,
    };
    let mut cache = zero_stats;
    cache.add(snapped.stats);
    cache.add(unsnapped.stats);
    Some(GroundTruth {
        summary: TruthSummary {
            acne_fraction: acne,
            edge_error_fraction: edge,
            leak_fraction: leak,
            flicker_snapped: snapped.s5,
            flicker_unsnapped: unsnapped.s5,
            flicker_edge_snapped: snapped.s5_edge,
            flicker_edge_unsnapped: unsnapped.s5_edge,
            flicker_acne_snapped: snapped.s5_acne,
            flicker_acne_unsnapped: unsnapped.s5_acne,
        },
        cascades,
        bias,
        bias_source,
        filter,
        pcf: t.pcf,
        ranges,
        texel,
        engine,
        receivers: points.len(),
        snapped,
        unsnapped,
        pictures_snapped,
        pictures_unsnapped,
        cache,
        points,
        zero,
    })
}

/// The depth bias each cascade samples with when csm-lab recommends it: the cascade's own
/// `bias_needed` (`needed[i]`), or for a cascade with too few receivers to have one, the
/// largest of the others scaled by the ratio of texel sizes (on a plane the bias needed is
/// proportional to the texel size); 0 when no cascade has one.
pub(crate) fn recommended_bias(needed: &[Option<f64>], texel: &[f64]) -> Vec<f64> {
    (0..needed.len())
        .map(|i| {
            needed[i].unwrap_or_else(|| {
                needed
                    .iter()
                    .zip(texel)
                    .filter_map(|(b, t)| b.map(|b| if *t > 0.0 { b * texel[i] / t } else { b }))
                    .fold(0.0, f64::max)
            })
        })
        .collect()
}

/// One configuration's proxies and its measured flicker, per snap mode: the points of the
/// flicker-versus-shimmer figure.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FlickerPoint {
    pub snapped: bool,
    /// S3: RMS sub-texel drift (texels per frame).
    pub s3: f64,
    /// S4: probe cell-flip rate (None when not computed).
    pub s4: Option<f64>,
    /// S5: measured state changes per receiver and frame step.
    pub s5: f64,
    /// The part of S5 at shadow edges (`flicker_edge_*`).
    pub s5_edge: f64,
    /// Where the bias the pass sampled with came from.
    pub bias_source: BiasSource,
}

/// The (S3, S4, S5) points of configurations (both snap modes each), each analysed with
/// cell flips and the ground-truth pass; configurations without geometry or cascades give
/// none. A sweep's rows (or a sample of them) passed here give the figure's data.
pub fn flicker_points(configs: &[Config]) -> Vec<FlickerPoint> {
    use rayon::prelude::*;
    configs
        .par_iter()
        .map(|c| points_of(&analyze_for_flicker(c)))
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// One configuration analysed as [`flicker_points`] does: cell flips and the ground-truth
/// pass (when the scene has geometry).
pub(crate) fn analyze_for_flicker(c: &Config) -> crate::analysis::Analysis {
    let opts = crate::analysis::AnalysisOptions {
        cell_flips: true,
        ground_truth: true,
        ..crate::analysis::AnalysisOptions::summary_only()
    };
    let mut c = c.clone();
    c.truth.enabled = c.geometry.is_some();
    crate::analysis::analyze(&c, &opts)
}

/// The (S3, S4, S5) points of an analysis from [`analyze_for_flicker`]: snapped, then
/// unsnapped; none without the pass or cascades. S5 is the summary's: `[camera]`'s, or a
/// level's pooled over its judged views.
pub(crate) fn points_of(a: &crate::analysis::Analysis) -> Vec<FlickerPoint> {
    match (&a.ground_truth, a.summary.truth, a.snapped(), a.unsnapped()) {
        (Some(g), Some(t), Some(s), Some(u)) => vec![
            FlickerPoint {
                snapped: true,
                s3: s.stats.rms,
                s4: s.stats.cell_flip_rate,
                s5: t.flicker_snapped,
                s5_edge: t.flicker_edge_snapped,
                bias_source: g.bias_source,
            },
            FlickerPoint {
                snapped: false,
                s3: u.stats.rms,
                s4: u.stats.cell_flip_rate,
                s5: t.flicker_unsnapped,
                s5_edge: t.flicker_edge_unsnapped,
                bias_source: g.bias_source,
            },
        ],
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{analyze_with_progress, frames_walked_with, AnalysisOptions};
    use std::sync::atomic::{AtomicU64, Ordering};

    /// The progress bar's length counts the pass's frames, and the pass reports every one: the
    /// bar ends full.
    #[test]
    fn the_pass_reports_every_frame_it_walks_to_the_progress_bar() {
        let text = r#"
camera = { position = [0.0, 6.0, 12.0], target = [0.0, 0.0, -6.0], fov_y_deg = 60.0, near = 0.1, far = 200.0 }
screen = { width = 160, height = 90 }
[light]
direction = [-0.4, -1.0, -0.3]
[scene]
min = [-60.0, 0.0, -60.0]
max = [60.0, 10.0, 60.0]
ground = 0.0
[[scene.box]]
min = [-2.3, 0.0, -8.7]
max = [1.9, 3.1, -4.4]
[shadow]
max_distance = 60.0
cascades = 2
resolution = 256
[motion]
path = "strafe"
frames = 17
[analysis]
ground_truth = true
"#;
        let c = Config::from_toml_str(text, "t.toml", None).unwrap();
        let opts = AnalysisOptions::full();
        let without = crate::analysis::frames_walked(&c);
        assert_eq!(frames_walked_with(&c, &opts), without + 2 * 17);
        let seen = AtomicU64::new(0);
        let a = analyze_with_progress(&c, &opts, &|n| {
            seen.fetch_add(n, Ordering::Relaxed);
        });
        assert!(a.ground_truth.is_some());
        assert_eq!(seen.load(Ordering::Relaxed), frames_walked_with(&c, &opts));
    }
}
