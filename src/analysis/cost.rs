//! What the configured setting costs to render, per cascade and in total (frame 0): the counts
//! of `csm_core::cost`, the cleared texels and bytes, and the cost model (docs/cost.md).

use crate::config::{Config, CostCull};
use csm_core::cascades::{LightPose, Rig};
use csm_core::cost::{self, CasterVolume, CostCounts, CostModel, ReceiverBox};
use csm_core::fitting::Window;
use csm_core::visibility::{SceneGeometry, Visibility};
use rayon::prelude::*;

/// The default weights of the cost model: relative costs of one draw call, one triangle, one
/// fragment and one cleared texel, of the order of nanoseconds on a desktop GPU (docs/cost.md
/// says where the orders come from). Only their ratios matter: `cost_index` divides by the
/// configured setting's value, and no time is ever printed from them.
pub(crate) const DEFAULT_MODEL: CostModel = CostModel {
    per_draw: 2000.0,
    per_triangle: 0.5,
    per_fragment: 0.01,
    per_texel_cleared: 0.002,
};

/// Bytes per texel of a depth map (32-bit depth, as `memory_bytes`).
pub(crate) const BYTES_PER_TEXEL: u64 = 4;

/// One cascade's cost. Serde writes it flat, under the registry's names (the per-cascade
/// objects of `summary.json`).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct CascadeCost {
    /// The counts; None without scene geometry (nothing to count).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub counts: Option<CostCounts>,
    pub texels_cleared: u64,
    pub bytes_written: u64,
    /// This cascade's share of the configured setting's cost (the cascades' shares add up to
    /// the setting's `cost_index`); None without geometry.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cost_index: Option<f64>,
    /// Milliseconds from the calibrated coefficients (`[cost] ns_per_*`); None uncalibrated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shadow_ms: Option<f64>,
    /// The means over the camera path ([`path_means`]); None when not measured.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub means: Option<CostMeans>,
}

impl CascadeCost {
    /// The model's value with the default weights (relative units); None without geometry.
    pub(crate) fn model(&self) -> Option<f64> {
        self.counts.map(|c| model_of(&DEFAULT_MODEL, &c, self.texels_cleared))
    }
}

/// The totals of a setting (the default: nothing measured, for hand-made summaries in tests).
/// Serde writes it flat under the registry's names (a shard's rows carry it so).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct CostSummary {
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub counts: Option<CostCounts>,
    pub texels_cleared: u64,
    pub bytes_written: u64,
    /// The model's value over the configured setting's: 1 for the configured setting itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cost_index: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadow_ms: Option<f64>,
    /// The means over the camera path ([`path_means`]); None when not measured.
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub means: Option<CostMeans>,
}

/// What is rendered per frame on average along the camera path(s): the mean over every frame
/// of every motion path of the sum, over the cascades rendered in that frame, of their counts
/// for that frame's windows. A cascade held by `[shadow] update_every` renders nothing in its
/// stale frames, so its share is its counts over the frames that render it, times the share
/// of frames that do (about 1 / update_every): what caching saves. See docs/cost.md.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct CostMeans {
    pub caster_objects_mean: f64,
    pub caster_triangles_mean: f64,
    pub caster_triangles_inside_mean: f64,
    pub raster_fragments_mean: f64,
    pub texels_cleared_mean: f64,
    /// The mean model value over the configured setting's frame-0 value (the reference of
    /// `cost_index`); None without a reference.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cost_index_mean: Option<f64>,
    /// The calibrated model of the means, in milliseconds; None uncalibrated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadow_ms_mean: Option<f64>,
}

impl CostMeans {
    /// The default model's value of the means (relative units).
    fn model(&self) -> f64 {
        self.model_with(&DEFAULT_MODEL)
    }

    fn model_with(&self, m: &CostModel) -> f64 {
        m.of(
            self.caster_objects_mean,
            self.caster_triangles_mean,
            self.raster_fragments_mean,
            self.texels_cleared_mean,
        )
    }

    fn add(&mut self, o: &CostMeans) {
        self.caster_objects_mean += o.caster_objects_mean;
        self.caster_triangles_mean += o.caster_triangles_mean;
        self.caster_triangles_inside_mean += o.caster_triangles_inside_mean;
        self.raster_fragments_mean += o.raster_fragments_mean;
        self.texels_cleared_mean += o.texels_cleared_mean;
    }

    /// Sets `cost_index_mean` against `reference` and `shadow_ms_mean` from `calibration`.
    fn finish(&mut self, reference: Option<f64>, calibration: Option<CostModel>) {
        let model = self.model();
        self.cost_index_mean = reference.filter(|&r| r > 0.0).map(|r| model / r);
        self.shadow_ms_mean = calibration.map(|m| self.model_with(&m) * 1e-6);
    }
}

impl CostSummary {
    /// The model's value with the default weights (relative units; not an output); None
    /// without geometry.
    pub(crate) fn model(&self) -> Option<f64> {
        self.counts.map(|c| model_of(&DEFAULT_MODEL, &c, self.texels_cleared))
    }

    /// Sets `cost_index` (and `cost_index_mean`) against a reference setting's model value
    /// (the configured setting's frame 0).
    pub(crate) fn normalise(&mut self, reference: Option<f64>) {
        self.cost_index = match (self.model(), reference) {
            (Some(m), Some(r)) if r > 0.0 => Some(m / r),
            _ => None,
        };
        if let Some(means) = self.means.as_mut() {
            let model = means.model();
            means.cost_index_mean = reference.filter(|&r| r > 0.0).map(|r| model / r);
        }
    }
}

/// The model's value of a set of counts and cleared texels.
fn model_of(m: &CostModel, c: &CostCounts, cleared: u64) -> f64 {
    m.of(
        c.caster_objects as f64,
        c.caster_triangles as f64,
        c.raster_fragments,
        cleared as f64,
    )
}

/// Cascade `i`'s caster volume for the frame of `lp` and its window `w`.
pub fn volume(config: &Config, rig: &Rig, i: usize, lp: &LightPose, w: &Window) -> CasterVolume {
    volume_from(config, rig, i, lp, w, &mut None)
}

/// [`volume`], bit for bit, with a hint for the light far ([`Rig::light_far_from`]: the same
/// variable for cascade `i` along a path).
fn volume_from(
    config: &Config,
    rig: &Rig,
    i: usize,
    lp: &LightPose,
    w: &Window,
    hint: &mut Option<csm_core::geometry::MaxCandidate>,
) -> CasterVolume {
    let basis = rig.basis(i, lp);
    let (scene_near, _) = cost::light_depth_extent(&basis, &config.scene);
    let far = rig.light_far_from(i, lp, w, &config.scene, hint);
    let lo = w.min();
    let hi = lo + glam::DVec2::new(w.width(), w.height());
    CasterVolume {
        basis,
        lo: lo.extend(scene_near),
        hi: hi.extend(far),
        texel: w.texel,
    }
}

/// The padding of the receivers' box for culling, in world units (across the light, along it):
/// the filter's reach (half the PCF kernel, one more texel for a bilinear tap, half a texel for
/// the texel a point falls in) plus the normal offset across the light; the normal offset and
/// the depth bias (and one texel for the depth format's rounding) along it. See docs/cost.md.
fn cull_padding(config: &Config, texel: f64) -> (f64, f64) {
    let t = &config.truth;
    let normal = t.normal_bias.unwrap_or(0.0).abs().max(1.0);
    let filter = 0.5 * t.pcf as f64 + 1.5;
    let xy = (filter + normal) * texel;
    let z = (normal + 1.0) * texel + t.depth_bias.unwrap_or(0.0).abs();
    (xy, z)
}

/// The visible receivers of `vis` in the light basis of `light`: every lit-facing sample's
/// view depth and light-space point, sorted by depth once per pass and basis (see
/// [`cost::ReceiverIndex`]).
fn receiver_index(light: &cost::LightScene, vis: &Visibility) -> std::sync::Arc<cost::ReceiverIndex> {
    light.receiver_index(&vis.view, || {
        let terms = vis.view.ray_terms();
        cost::ReceiverIndex::new(vis.samples.iter().enumerate().filter_map(|(k, s)| {
            let s = s.filter(|s| s.lit)?;
            Some((s.depth, light.basis.to_light(terms.point(k, s.depth))))
        }))
    })
}

/// The objects cascade `i` keeps under receiver-aware culling (one flag per object): those
/// whose bounds, extruded along the light to the scene's far side, meet the padded box of the
/// cascade's visible receivers. None: culling is off.
pub fn kept_objects(
    config: &Config,
    rig: &Rig,
    i: usize,
    v: &CasterVolume,
    scene: &SceneGeometry,
    vis: &Visibility,
) -> Option<Vec<bool>> {
    if config.cost.cull != CostCull::Receivers {
        return None;
    }
    let light = scene.light_scene(&v.basis);
    let intervals: Vec<(f64, f64)> = rig.covered_intervals(i).collect();
    let (pad_xy, pad_z) = cull_padding(config, v.texel.x.max(v.texel.y));
    let (lo, hi) = receiver_index(&light, vis).bounds(&intervals);
    let target = ReceiverBox::padded(lo, hi, pad_xy, pad_z);
    let (_, scene_far) = cost::light_depth_extent(&v.basis, &config.scene);
    Some(
        (0..scene.mesh.objects.len())
            .map(|k| {
                let (lo, hi) = light.object_box(k);
                target.is_some_and(|t| t.shadowed_by(lo, hi, scene_far))
            })
            .collect(),
    )
}

/// The scene whose casters are counted: the config's geometry, unless `[cost] counts = false`.
fn counted(config: &Config) -> Option<&SceneGeometry> {
    config
        .geometry
        .as_ref()
        .filter(|_| config.cost.counts)
        .map(|g| &*g.scene)
}

/// Whether the means over the camera path are measured for `config` when asked: with scene
/// geometry, without culling (the visible receivers are frame 0's only), and for a pipeline
/// whose light basis stays put along the path (a still light and a basis that does not follow
/// the camera: each frame then reads the scene in the same light basis). docs/cost.md.
pub(crate) fn means_measurable(config: &Config, rig: Option<&Rig>) -> bool {
    counted(config).is_some()
        && config.cost.cull == CostCull::None
        && !config.motion.light.moves()
        && rig.is_none_or(|r| r.fixed_basis())
}

/// Frames whose counts [`path_means`] holds at once (bounded memory on long paths).
const MEANS_CHUNK: usize = 4096;

/// Bytes of rectangle parts [`path_means`] keeps at most (it forgets them all past this).
const RECT_PARTS_BYTES: usize = 16 << 20;

/// Consecutive frames [`path_means`] gives one thread, so that each frame's light far starts
/// from the candidate of the frame before.
const FAR_RUN: usize = 256;

/// A hasher for [`rect_key`]s (five words of float bits; no adversary): a multiply-rotate
/// mix per word and a final fold of the high bits, in place of the default SipHash.
#[derive(Default, Clone, Copy)]
struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            self.write_u64(u64::from_le_bytes(w));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn finish(&self) -> u64 {
        // The high bits folded down: the table indexes by the low ones.
        let x = (self.0 ^ (self.0 >> 33)).wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^ (x >> 29)
    }
}

type KeyHash = std::hash::BuildHasherDefault<KeyHasher>;

/// The key of a volume's rectangle and light near: what [`cost::LightScene::rect_part`] reads.
fn rect_key(v: &CasterVolume) -> [u64; 5] {
    [v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y].map(f64::to_bits)
}

/// Each cascade's means over every frame of every motion path (see [`CostMeans`]): in frame
/// `t` of a path (counted from 0 on each path) cascade `i` is rendered when `t` is a multiple
/// of its cadence `every[i]` (empty: every frame), with that frame's window. `cost_index_mean`
/// and `shadow_ms_mean` are left to [`CostMeans::finish`].
///
/// Each frame's counts are [`cost::LightScene::counts_all`]'s, bit for bit, made in two
/// parts: what depends only on a window's rectangle ([`cost::LightScene::rect_part`]) once
/// per rectangle met (a snapped window's rectangle recurs along a path, the light far does
/// not), then per frame the part that reads the far ([`cost::LightScene::counts_in`]).
pub(crate) fn path_means(config: &Config, rig: &Rig, every: &[usize]) -> Vec<CostMeans> {
    let m = rig.cascade_count();
    let Some(scene) = counted(config) else {
        return vec![CostMeans::default(); m];
    };
    let setup = config.setup();
    let motions = std::iter::once(setup.motion.clone()).chain(config.extra_motions().into_iter().map(|(_, m)| m));
    let mut sums = vec![CostCounts::default(); m];
    let mut cleared = vec![0u64; m];
    let mut frames = 0u64;
    // One frame's volumes for the cascades it renders (None: held by the cadence); `hints`
    // carries each cascade's light-far candidate from the frame before.
    let frame = |t: usize, pose: &csm_core::geometry::CameraPose, hints: &mut [Option<_>]| {
        let lp = LightPose::new(&rig.light, pose);
        (0..m)
            .map(|i| {
                (t % every.get(i).copied().unwrap_or(1).max(1) == 0).then(|| {
                    let w = rig.window(i, &lp, config.shadow.snap);
                    let v = volume_from(config, rig, i, &lp, &w, &mut hints[i]);
                    (v, w.resolution as u64 * w.resolution as u64)
                })
            })
            .collect::<Vec<Option<(CasterVolume, u64)>>>()
    };
    let mut parts: std::collections::HashMap<[u64; 5], cost::RectPart, KeyHash> = Default::default();
    let mut parts_bytes = 0;
    for motion in motions {
        let mut poses = csm_core::motion::poses(&setup.camera, &motion).enumerate().peekable();
        // Frames are counted in parallel, a bounded chunk at a time, and summed in frame order:
        // the sums (fragments are f64) are the serial ones, bit for bit, at any thread count.
        while poses.peek().is_some() {
            let chunk: Vec<_> = poses
                .by_ref()
                .take(MEANS_CHUNK)
                .map(|(t, p)| (t, p.expect("validated when the config was loaded")))
                .collect();
            // Runs of consecutive frames in parallel, each run in order (its hints follow it).
            let runs: Vec<Vec<_>> = chunk
                .par_chunks(FAR_RUN)
                .map(|run| {
                    let mut hints = vec![None; m];
                    run.iter().map(|(t, pose)| frame(*t, pose, &mut hints)).collect()
                })
                .collect();
            let volumes: Vec<_> = runs.into_iter().flatten().collect();
            // The light scene of the path's basis (a fixed basis: `means_measurable`).
            let Some(light) = volumes
                .iter()
                .flatten()
                .flatten()
                .next()
                .map(|(v, _)| scene.light_scene(&v.basis))
            else {
                frames += volumes.len() as u64;
                continue;
            };
            if parts_bytes > RECT_PARTS_BYTES {
                parts.clear();
                parts_bytes = 0;
            }
            // The rectangles not met before, each once, made in parallel.
            let mut new: Vec<&CasterVolume> = Vec::new();
            let mut asked: std::collections::HashSet<_, KeyHash> = Default::default();
            for (v, _) in volumes.iter().flatten().flatten() {
                let key = rect_key(v);
                if v.basis == light.basis && !parts.contains_key(&key) && asked.insert(key) {
                    new.push(v);
                }
            }
            let made: Vec<_> = new.par_iter().map(|v| (rect_key(v), light.rect_part(v))).collect();
            parts_bytes += made.iter().map(|(_, p)| p.bytes()).sum::<usize>();
            parts.extend(made);
            let counted: Vec<Vec<Option<(CostCounts, u64)>>> = volumes
                .par_iter()
                .map(|per_cascade| {
                    per_cascade
                        .iter()
                        .map(|c| {
                            c.as_ref().map(|(v, texels)| {
                                let counts = match parts.get(&rect_key(v)) {
                                    Some(part) if v.basis == light.basis => light.counts_in(&scene.mesh, v, part),
                                    _ => scene.light_scene(&v.basis).counts_all(&scene.mesh, v),
                                };
                                (counts, *texels)
                            })
                        })
                        .collect()
                })
                .collect();
            for per_cascade in counted {
                frames += 1;
                for (i, c) in per_cascade.into_iter().enumerate() {
                    if let Some((counts, texels)) = c {
                        sums[i].add(&counts);
                        cleared[i] += texels;
                    }
                }
            }
        }
    }
    let f = frames.max(1) as f64;
    (0..m)
        .map(|i| CostMeans {
            caster_objects_mean: sums[i].caster_objects as f64 / f,
            caster_triangles_mean: sums[i].caster_triangles as f64 / f,
            caster_triangles_inside_mean: sums[i].caster_triangles_inside as f64 / f,
            raster_fragments_mean: sums[i].raster_fragments / f,
            texels_cleared_mean: cleared[i] as f64 / f,
            cost_index_mean: None,
            shadow_ms_mean: None,
        })
        .collect()
}

/// The cost of every cascade of frame 0 (windows `windows0` in the frame of `lp0`) and the
/// totals, the totals' `cost_index` 1 (the configured setting). With `means` (the cascades'
/// [`path_means`]) the means over the path too, against the same reference.
pub(crate) fn measure(
    config: &Config,
    rig: &Rig,
    lp0: &LightPose,
    windows0: &[Window],
    vis: Option<&Visibility>,
    means: Option<Vec<CostMeans>>,
) -> (Vec<CascadeCost>, CostSummary) {
    let geometry = counted(config);
    let calibration = config.cost.calibration;
    let mut cascades: Vec<CascadeCost> = windows0
        .iter()
        .enumerate()
        .map(|(i, w)| {
            let cleared = w.resolution as u64 * w.resolution as u64;
            let counts = geometry.map(|scene| {
                let v = volume(config, rig, i, lp0, w);
                let light = scene.light_scene(&v.basis);
                let kept = vis.and_then(|vis| kept_objects(config, rig, i, &v, scene, vis));
                match kept {
                    Some(kept) => light.counts(&scene.mesh, &v, |k| kept[k]),
                    None => together(&v).unwrap_or_else(|| light.counts_all(&scene.mesh, &v)),
                }
            });
            CascadeCost {
                counts,
                texels_cleared: cleared,
                bytes_written: cleared * BYTES_PER_TEXEL,
                cost_index: None,
                shadow_ms: calibration.and_then(|m| counts.map(|c| model_of(&m, &c, cleared) * 1e-6)),
                means: means.as_ref().map(|x| x[i]),
            }
        })
        .collect();
    let mut total = CostSummary {
        counts: geometry.map(|_| {
            let mut t = CostCounts::default();
            for c in cascades.iter().filter_map(|c| c.counts.as_ref()) {
                t.add(c);
            }
            t
        }),
        texels_cleared: cascades.iter().map(|c| c.texels_cleared).sum(),
        bytes_written: cascades.iter().map(|c| c.bytes_written).sum(),
        cost_index: None,
        shadow_ms: calibration
            .and(geometry)
            .map(|_| cascades.iter().filter_map(|c| c.shadow_ms).sum()),
        means: means.as_ref().map(|x| {
            let mut t = CostMeans::default();
            for c in x {
                t.add(c);
            }
            t
        }),
    };
    let reference = total.model();
    total.normalise(reference);
    if let Some(t) = total.means.as_mut() {
        t.finish(reference, calibration);
    }
    for c in cascades.iter_mut() {
        c.cost_index = match (c.model(), reference) {
            (Some(m), Some(t)) if t > 0.0 => Some(m / t),
            _ => None,
        };
        if let Some(x) = c.means.as_mut() {
            x.finish(reference, calibration);
        }
    }
    (cascades, total)
}

/// The key of a volume among the counts made together: its basis and its exact bits.
type TogetherKey = [u64; 17];

fn together_key(v: &CasterVolume) -> TogetherKey {
    let b = &v.basis;
    [
        b.x.x, b.x.y, b.x.z, b.y.x, b.y.y, b.y.z, b.z.x, b.z.y, b.z.z, v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z,
        v.texel.x, v.texel.y,
    ]
    .map(f64::to_bits)
}

thread_local! {
    /// The frame-0 counts [`count_together`] made for the settings this thread evaluates next.
    static TOGETHER: std::cell::RefCell<std::collections::HashMap<TogetherKey, CostCounts>> =
        std::cell::RefCell::new(std::collections::HashMap::new());
}

/// The counts [`count_together`] made for the volume `v` on this thread, if any: the same as
/// [`cost::LightScene::counts_all`]'s, bit for bit.
fn together(v: &CasterVolume) -> Option<CostCounts> {
    TOGETHER.with_borrow(|t| t.get(&together_key(v)).copied())
}

/// Counts, together, the frame-0 caster volumes of `configs` (settings that differ in
/// resolution alone, evaluated next on this thread), for [`measure`] to read: cascade `i` of
/// each setting has the same slice and light depth range, and windows that differ by a
/// sub-texel shift, so one walk of each object's tree serves them all
/// ([`cost::LightScene::counts_all_many`]). Forgets what it made for the previous settings.
/// Nothing is made without counts, with culling (counted per setting against its receivers)
/// or for a single setting.
pub(crate) fn count_together(configs: &[&Config]) {
    TOGETHER.with_borrow_mut(|t| t.clear());
    let Some(first) = configs.first() else {
        return;
    };
    let Some(scene) = counted(first).filter(|_| configs.len() > 1 && first.cost.cull == CostCull::None) else {
        return;
    };
    // Per setting, its frame-0 volumes (as `analyze` makes them), nearest cascade first.
    let volumes: Vec<Vec<CasterVolume>> = configs
        .iter()
        .map(|config| {
            let Some(rig) = super::rig(config) else {
                return Vec::new();
            };
            let pose0 = config.camera.pose();
            let lp0 = LightPose::new(&rig.light, &pose0);
            (0..rig.cascade_count())
                .map(|i| volume(config, &rig, i, &lp0, &rig.window(i, &lp0, config.shadow.snap)))
                .collect()
        })
        .collect();
    // Cascade i of every setting in a row, so that one cascade's volumes are walked together.
    let deepest = volumes.iter().map(Vec::len).max().unwrap_or(0);
    let mut ordered: Vec<CasterVolume> = Vec::new();
    for i in 0..deepest {
        ordered.extend(volumes.iter().filter_map(|v| v.get(i).copied()));
    }
    let mut made = std::collections::HashMap::new();
    // One light scene per basis (a preset's basis may differ per cascade).
    let mut left = ordered;
    while let Some(basis) = left.first().map(|v| v.basis) {
        let (same, rest): (Vec<_>, Vec<_>) = left.into_iter().partition(|v| v.basis == basis);
        let counts = scene.light_scene(&basis).counts_all_many(&scene.mesh, &same);
        made.extend(same.iter().map(together_key).zip(counts));
        left = rest;
    }
    TOGETHER.with_borrow_mut(|t| *t = made);
}

/// The cost of a setting that needs no cascade: nothing is rendered (in any frame, when the
/// means over the path are asked for).
pub(crate) fn nothing(config: &Config, means: bool) -> CostSummary {
    let geometry = counted(config).is_some();
    CostSummary {
        counts: geometry.then(CostCounts::default),
        texels_cleared: 0,
        bytes_written: 0,
        cost_index: None,
        shadow_ms: config.cost.calibration.and(geometry.then_some(0.0)),
        means: (means && means_measurable(config, None)).then(|| CostMeans {
            shadow_ms_mean: config.cost.calibration.map(|_| 0.0),
            ..CostMeans::default()
        }),
    }
}

/// The cost model's value of the configured setting at frame 0 (the `cost_index` reference
/// of a sweep's rows); None without geometry or when the scene needs no cascade.
pub(crate) fn configured_model(config: &Config) -> Option<f64> {
    let rig = super::rig(config)?;
    let pose0 = config.camera.pose();
    let lp0 = LightPose::new(&rig.light, &pose0);
    let windows0: Vec<Window> = (0..rig.cascade_count())
        .map(|i| rig.window(i, &lp0, config.shadow.snap))
        .collect();
    let vis = config.setup().visibility();
    measure(config, &rig, &lp0, &windows0, vis.as_deref(), None).1.model()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The means by the plain definition: every frame of every path, each cascade it renders
    /// counted on its own ([`cost::LightScene::counts_all`] of the frame's volume, its light far
    /// computed afresh), summed in frame order.
    fn direct_means(config: &Config, rig: &Rig, every: &[usize]) -> Vec<(CostCounts, u64)> {
        assert!(config.extra_motions().is_empty(), "one motion path");
        let scene = counted(config).expect("a scene with geometry");
        let setup = config.setup();
        let m = rig.cascade_count();
        let mut sums = vec![(CostCounts::default(), 0u64); m];
        for (t, pose) in csm_core::motion::poses(&setup.camera, &setup.motion).enumerate() {
            let lp = LightPose::new(&rig.light, &pose.unwrap());
            for (i, sum) in sums.iter_mut().enumerate() {
                if t % every.get(i).copied().unwrap_or(1) == 0 {
                    let w = rig.window(i, &lp, config.shadow.snap);
                    let v = volume(config, rig, i, &lp, &w);
                    sum.0.add(&scene.light_scene(&v.basis).counts_all(&scene.mesh, &v));
                    sum.1 += w.resolution as u64 * w.resolution as u64;
                }
            }
        }
        sums
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

        /// [`path_means`] (rectangle parts met once, light fars from the frame before's
        /// candidate, runs of frames in parallel) equals the plain definition bit for bit on
        /// random paths: every motion, steps, lengths across the runs' and chunks' ends, lights,
        /// fits, snapping and cadences.
        #[test]
        fn the_path_means_equal_a_direct_count_of_every_frame(
            path in prop::sample::select(vec!["strafe", "dolly", "yaw", "pitch", "orbit", "still"]),
            step in 0.002..0.4f64,
            frames in 1usize..700,
            light in (-1.0..1.0f64, -1.0..-0.3f64, -1.0..1.0f64),
            sphere in any::<bool>(),
            snap in any::<bool>(),
            every in prop::collection::vec(1usize..4, 4),
        ) {
            let text = include_str!("../../configs/default.toml")
                .replace("direction = [-0.4, -1.0, -0.3]", &format!("direction = [{}, {}, {}]", light.0, light.1, light.2))
                .replace("fit = \"sphere\"", if sphere { "fit = \"sphere\"" } else { "fit = \"aabb\"" })
                .replace("snap = true", &format!("snap = {snap}"))
                .replace("path = \"strafe\"\nframes = 240\nstep = 0.05", &format!("path = \"{path}\"\nframes = {frames}\nstep = {step}"));
            let wanted = format!("path = \"{path}\"\nframes = {frames}\n");
            prop_assert!(text.contains(&wanted));
            let config = match Config::from_toml_str(&text, "t.toml", None) {
                Ok(config) => config,
                // A pitch long enough to turn the view through camera.up is refused by the
                // loader (`motion.step`): not a path to count.
                Err(e) if format!("{e:?}").contains("motion.step") => {
                    return Err(TestCaseError::reject("the path turns the view through camera.up"));
                }
                Err(e) => panic!("{e}"),
            };
            let rig = crate::analysis::rig(&config).unwrap();
            prop_assert!(means_measurable(&config, Some(&rig)));
            let direct = direct_means(&config, &rig, &every);
            let fast = path_means(&config, &rig, &every);
            let f = frames as f64;
            for (d, x) in direct.iter().zip(&fast) {
                prop_assert_eq!(x.caster_objects_mean.to_bits(), (d.0.caster_objects as f64 / f).to_bits());
                prop_assert_eq!(x.caster_triangles_mean.to_bits(), (d.0.caster_triangles as f64 / f).to_bits());
                prop_assert_eq!(x.caster_triangles_inside_mean.to_bits(), (d.0.caster_triangles_inside as f64 / f).to_bits());
                prop_assert_eq!(x.raster_fragments_mean.to_bits(), (d.0.raster_fragments / f).to_bits());
                prop_assert_eq!(x.texels_cleared_mean.to_bits(), (d.1 as f64 / f).to_bits());
            }
            prop_assert!(direct.iter().any(|d| d.0.caster_triangles_inside > 0));
        }
    }
}
