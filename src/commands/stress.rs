//! `csm-lab stress`: a battery of pathological inputs, each run through the real config
//! validation and analysis, with invariant checks.
//!
//! Every case is written as TOML text and parsed by [`Config::from_toml_str`], so stress
//! exercises exactly the path a user's file takes. A case is either *valid by design* (it
//! must be accepted, and its analysis must satisfy every invariant) or *invalid by design*
//! (it must be rejected with an error that names the offending key).
//!
//! Invariants of a valid case (each a pure check function, unit-tested directly):
//!
//! * `config_accepted`: the validator accepts it;
//! * `finite`: no NaN or infinity anywhere in the analysis (summary, splits, cascades,
//!   density profile, per-frame rows), in f64 and in both f32 snap spaces, and every CSV/JSON
//!   exporter renders (they refuse non-finite values);
//! * `splits_increasing`: split depths strictly increasing (worst value: the smallest gap);
//! * `splits_end_at_range`: the first split is `z_lo` and the last `z_hi`, exactly (worst
//!   value: the larger end error);
//! * `coverage`: no slice corner outside its window in any frame, f64 (worst value: count);
//! * `stabilised_shimmer_f64`: the sphere fit with snapping drifts by less than 1e-9 texel
//!   per frame in f64 (worst value: the largest S3 over the path);
//!
//! Engine presets run too, one case each, in f64 and both f32 snap spaces: they must be
//! accepted and finite with increasing splits; coverage and stabilised shimmer are the
//! engines' own properties (some never snap, some leave corners outside), so they are not
//! checked for a preset.
//! * `f32_drift_limit`, only with `--max-f32-drift`: the f32 drift in either snap space stays
//!   within the given limit.
//!
//! The binary32 residuals (drift and S7 of the emulated pipeline in world and camera-relative
//! space, and the f32 window's coverage) are reported in their own columns: they describe
//! engines, they are not failures of the tool.

use glam::DVec3;
use rayon::prelude::*;

use crate::analysis::{analyze, Analysis, AnalysisOptions};
use crate::config::{Config, Fit};
use crate::error::Result;
use csm_core::rng::SplitMix64;
use csm_core::scene::{Precision, SnapSpace};

/// The largest f64 stabilised drift accepted (texels per frame): rounding residue of an exact
/// snap, far below anything visible (docs/metrics.md, "Shimmer").
pub(crate) const STABILISED_LIMIT: f64 = 1e-9;

/// Everything a case writes into its config file.
#[derive(Debug, Clone, PartialEq)]
pub struct StressInputs {
    pub position: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub fov_y_deg: f64,
    pub near: f64,
    pub far: f64,
    pub width: i64,
    pub height: i64,
    pub light: [f64; 3],
    pub scene_min: [f64; 3],
    pub scene_max: [f64; 3],
    pub world_offset: [f64; 3],
    pub max_distance: f64,
    pub cascades: i64,
    pub lambda: f64,
    pub resolution: i64,
    pub fit: Fit,
    pub snap: bool,
    pub fit_depth_to_scene: bool,
    pub motion: &'static str,
    /// World units per frame (strafe, dolly) or degrees per frame (yaw, pitch, orbit).
    pub step: f64,
    pub frames: i64,
    /// An engine preset (`shadow.preset`), or None for csm-lab's own pipeline.
    pub preset: Option<&'static str>,
}

/// What a case is meant to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expect {
    Valid,
    /// Must be rejected with a message naming this key.
    Rejected {
        key: &'static str,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct StressCase {
    pub name: String,
    pub inputs: StressInputs,
    pub expect: Expect,
}

/// A number as TOML writes it (`nan` and `inf` included, for invalid-by-design cases).
pub(crate) fn toml_f64(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

fn toml_vec(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", toml_f64(v[0]), toml_f64(v[1]), toml_f64(v[2]))
}

/// Probes and density samples per case: enough to exercise every code path, few enough to
/// keep the battery fast.
const CASE_PROBES: usize = 64;
const CASE_DENSITY_SAMPLES: usize = 64;

impl StressInputs {
    /// The default outdoor scene, 24 frames of strafing.
    pub(crate) fn baseline() -> Self {
        StressInputs {
            position: [0.0, 10.0, 0.0],
            target: [0.0, 0.0, -50.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            near: 0.1,
            far: 1000.0,
            width: 1920,
            height: 1080,
            light: [-0.4, -1.0, -0.3],
            scene_min: [-200.0, 0.0, -200.0],
            scene_max: [200.0, 40.0, 200.0],
            world_offset: [0.0; 3],
            max_distance: 150.0,
            cascades: 4,
            lambda: 0.75,
            resolution: 2048,
            fit: Fit::Sphere,
            snap: true,
            fit_depth_to_scene: true,
            motion: "strafe",
            step: 0.05,
            frames: 24,
            preset: None,
        }
    }

    /// The config file of this case, with the given arithmetic and fit.
    pub(crate) fn toml(&self, precision: Precision, space: SnapSpace, fit: Fit) -> String {
        format!(
            "[camera]\nposition = {}\ntarget = {}\nup = {}\nfov_y_deg = {}\nnear = {}\nfar = {}\n\n\
             [screen]\nwidth = {}\nheight = {}\n\n\
             [light]\ndirection = {}\n\n\
             [scene]\nmin = {}\nmax = {}\nworld_offset = {}\n\n\
             [shadow]\nmax_distance = {}\ncascades = {}\nlambda = {}\nresolution = {}\nfit = \"{}\"\nsnap = {}\n\
             fit_depth_to_scene = {}\nprecision = \"{}\"\nsnap_space = \"{}\"\n{}\n\
             [motion]\npath = \"{}\"\nstep = {}\nframes = {}\n\n\
             [analysis]\nprobes = {CASE_PROBES}\ndensity_samples = {CASE_DENSITY_SAMPLES}\n",
            toml_vec(self.position),
            toml_vec(self.target),
            toml_vec(self.up),
            toml_f64(self.fov_y_deg),
            toml_f64(self.near),
            toml_f64(self.far),
            self.width,
            self.height,
            toml_vec(self.light),
            toml_vec(self.scene_min),
            toml_vec(self.scene_max),
            toml_vec(self.world_offset),
            toml_f64(self.max_distance),
            self.cascades,
            toml_f64(self.lambda),
            self.resolution,
            fit,
            self.snap,
            self.fit_depth_to_scene,
            precision,
            space,
            self.preset.map_or(String::new(), |p| format!("preset = \"{p}\"\n")),
            self.motion,
            toml_f64(self.step),
            self.frames,
        )
    }

    pub fn parse(&self, precision: Precision, space: SnapSpace, fit: Fit) -> Result<Config> {
        Config::from_toml_str(&self.toml(precision, space, fit), "stress-case", None)
    }
}

impl StressInputs {
    /// The camera moves along `motion` by `step` per frame.
    fn moving(&mut self, motion: &'static str, step: f64) {
        self.motion = motion;
        self.step = step;
    }
}

fn case(name: &str, edit: impl FnOnce(&mut StressInputs)) -> StressCase {
    let mut inputs = StressInputs::baseline();
    edit(&mut inputs);
    StressCase {
        name: name.to_string(),
        inputs,
        expect: Expect::Valid,
    }
}

fn rejected(name: &str, key: &'static str, edit: impl FnOnce(&mut StressInputs)) -> StressCase {
    StressCase {
        expect: Expect::Rejected { key },
        ..case(name, edit)
    }
}

/// The fixed battery: every pathological input of issue 5, plus inputs that must be rejected.
pub fn battery() -> Vec<StressCase> {
    let huge_scene = |i: &mut StressInputs| {
        i.scene_min = [-1e6, -10.0, -1e6];
        i.scene_max = [1e6, 1000.0, 1e6];
    };
    let mut cases = vec![
        case("baseline", |_| {}),
        case("near 1e-4 far 1e6", |i| {
            i.near = 1e-4;
            i.far = 1e6;
            i.max_distance = 1e6;
            huge_scene(i);
        }),
        case("near 1e-4 far 1e6 unclipped log 16", |i| {
            i.near = 1e-4;
            i.far = 1e6;
            i.max_distance = 1e6;
            i.fit_depth_to_scene = false;
            i.lambda = 1.0;
            i.cascades = 16;
        }),
        case("lambda 0", |i| i.lambda = 0.0),
        case("lambda 1", |i| i.lambda = 1.0),
        case("1 cascade", |i| i.cascades = 1),
        case("16 cascades", |i| i.cascades = 16),
        case("resolution 16", |i| i.resolution = 16),
        case("resolution 16384", |i| i.resolution = 16384),
        case("resolution 1000 (not a power of two)", |i| i.resolution = 1000),
        case("fov 1 deg", |i| i.fov_y_deg = 1.0),
        case("fov 179 deg", |i| i.fov_y_deg = 179.0),
        case("aspect 0.05", |i| i.width = 54),
        case("aspect 20", |i| i.width = 21600),
        case("fov 179 deg aspect 20", |i| {
            i.fov_y_deg = 179.0;
            i.width = 21600;
        }),
        case("light straight down", |i| i.light = [0.0, -1.0, 0.0]),
        case("light straight up", |i| i.light = [0.0, 1.0, 0.0]),
        case("light 1e-7 off vertical", |i| i.light = [1e-7, -1.0, 0.0]),
        case("light grazing (parallel to the ground)", |i| i.light = [1.0, 0.0, 0.0]),
        case("light parallel to the view direction", |i| {
            i.light = [0.0, -10.0, -50.0];
        }),
        case("light against the view direction", |i| i.light = [0.0, 10.0, 50.0]),
        case("camera inside the scene", |i| i.position = [0.0, 20.0, 0.0]),
        case("camera outside the scene", |i| {
            i.position = [0.0, 80.0, 400.0];
            i.target = [0.0, 0.0, 0.0];
            i.max_distance = 1000.0;
        }),
        case("camera far from the scene", |i| {
            i.position = [0.0, 500.0, 20000.0];
            i.target = [0.0, 0.0, 0.0];
            i.far = 1e5;
            i.max_distance = 1e5;
        }),
        case("scene beyond the shadow distance", |i| {
            i.position = [0.0, 500.0, 20000.0];
            i.target = [0.0, 0.0, 0.0];
        }),
        case("scene behind the camera", |i| {
            i.position = [0.0, 10.0, 300.0];
            i.target = [0.0, 10.0, 1000.0];
        }),
        case("shadow distance below near", |i| {
            i.max_distance = 0.05;
            i.fit_depth_to_scene = false;
        }),
        case("scene thinner than a texel", |i| {
            i.scene_min = [-200.0, 0.0, -200.0];
            i.scene_max = [200.0, 1e-6, 200.0];
        }),
        case("scene of zero thickness", |i| {
            i.scene_min = [-200.0, 0.0, -200.0];
            i.scene_max = [200.0, 0.0, 200.0];
        }),
        case("camera looking straight down", |i| {
            i.position = [0.0, 100.0, 0.0];
            i.target = [0.0, 0.0, 0.0];
            i.up = [0.0, 0.0, -1.0];
        }),
        case("aabb fit", |i| i.fit = Fit::Aabb),
        case("aabb fit at 1e6", |i| {
            i.fit = Fit::Aabb;
            i.world_offset = [1e6, 0.0, 1e6];
        }),
        case("no snapping", |i| i.snap = false),
        case("dolly", |i| i.moving("dolly", 0.21)),
        case("yaw", |i| i.moving("yaw", 0.5)),
        case("pitch", |i| i.moving("pitch", 0.5)),
        case("orbit", |i| i.moving("orbit", 2.0)),
        // Millimetre-thin slices 200 km out: valid in f64, but one binary32 step there (1.6 cm)
        // is wider than the slice, so the f32 emulation must refuse rather than emit NaN.
        case("mm AABB slices at 2e5 (beyond binary32)", |i| {
            i.near = 1e-3;
            i.lambda = 1.0;
            i.cascades = 16;
            i.fit = Fit::Aabb;
            i.world_offset = [2e5, 0.0, 2e5];
        }),
    ];
    for offset in [1e3, 1e4, 1e5, 1e6] {
        cases.push(case(&format!("world offset {offset:e}"), |i| {
            i.world_offset = [offset, 0.0, offset];
        }));
    }
    for p in crate::presets::PresetName::ALL {
        cases.push(case(&format!("preset {}", p.as_str()), |i| i.preset = Some(p.as_str())));
    }
    cases.push(case("world offset -1e6 yaw", |i| {
        i.world_offset = [-1e6, -1e3, -1e6];
        i.moving("yaw", 0.5);
    }));
    cases.extend([
        rejected("near 0", "camera.near", |i| i.near = 0.0),
        rejected("far/near 1e13", "camera.near", |i| i.near = i.far * 1e-13),
        rejected("lambda 1.5", "shadow.lambda", |i| i.lambda = 1.5),
        rejected("fov 180 deg", "camera.fov_y_deg", |i| i.fov_y_deg = 180.0),
        rejected("resolution 8", "shadow.resolution", |i| i.resolution = 8),
        rejected("17 cascades", "shadow.cascades", |i| i.cascades = 17),
        rejected("zero light direction", "light.direction", |i| i.light = [0.0; 3]),
        rejected("non-finite world offset", "scene.world_offset", |i| {
            i.world_offset = [f64::NAN, 0.0, 0.0]
        }),
        rejected("infinite far", "camera.far", |i| i.far = f64::INFINITY),
        rejected("scene min above max", "scene.max", |i| i.scene_max[1] = -1.0),
        rejected("up parallel to the view", "camera.up", |i| {
            i.target = [0.0, 0.0, 0.0];
            i.up = [0.0, 1.0, 0.0];
        }),
        rejected("pitch over the top", "motion.step", |i| {
            i.moving("pitch", 10.0);
            i.frames = 30;
        }),
    ]);
    cases
}

/// `n` random valid cases from a seeded generator (deterministic for a seed).
pub(crate) fn random_cases(n: usize, seed: u64) -> Vec<StressCase> {
    let mut rng = SplitMix64::new(seed);
    (0..n).map(|k| random_case(&mut rng, k)).collect()
}

fn random_case(rng: &mut SplitMix64, k: usize) -> StressCase {
    let mut i = StressInputs::baseline();
    let log_uniform = |rng: &mut SplitMix64, lo: f64, hi: f64| 10f64.powf(rng.range(lo, hi));
    let pick = |rng: &mut SplitMix64, n: usize| ((rng.unit() * n as f64) as usize).min(n - 1);
    i.fov_y_deg = rng.range(1.0, 179.0);
    i.height = 1080;
    i.width = ((1080.0 * log_uniform(rng, -1.3, 1.3)).round() as i64).clamp(1, 1 << 20);
    i.near = log_uniform(rng, -4.0, 0.5);
    i.far = i.near * log_uniform(rng, 1.0, 7.0);
    i.max_distance = i.far * log_uniform(rng, -2.0, 0.0);
    i.cascades = 1 + pick(rng, 16) as i64;
    i.lambda = match pick(rng, 10) {
        0 => 0.0,
        1 => 1.0,
        _ => rng.unit(),
    };
    i.resolution = if rng.unit() < 0.5 {
        1 << (4 + pick(rng, 11))
    } else {
        16 + pick(rng, 16384 - 16 + 1) as i64
    };
    i.fit = if rng.unit() < 0.7 { Fit::Sphere } else { Fit::Aabb };
    i.snap = rng.unit() < 0.85;
    i.fit_depth_to_scene = rng.unit() < 0.7;
    // Light: a random direction, sometimes exactly vertical or horizontal.
    i.light = match pick(rng, 10) {
        0 => [0.0, -1.0, 0.0],
        1 => [rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0) + 2.0],
        _ => loop {
            let v = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            if v.length() > 0.1 {
                break v.to_array();
            }
        },
    };
    // Camera: anywhere in a 200-unit cube, looking in a random direction; up = +Y unless the
    // view is within about 2.6 degrees of vertical, then +Z.
    let position = DVec3::new(
        rng.range(-100.0, 100.0),
        rng.range(-100.0, 100.0),
        rng.range(-100.0, 100.0),
    );
    let dir = loop {
        let v = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        if v.length() > 0.1 {
            break v.normalize();
        }
    };
    let target = position + dir * log_uniform(rng, -2.0, 3.0);
    i.position = position.to_array();
    i.target = target.to_array();
    i.up = if dir.y.abs() > 0.999 {
        [0.0, 0.0, 1.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    // Scene: a box of random size (down to 1e-6 thick), usually around a point in view within
    // the shadow distance, sometimes anywhere within 200 units (often out of view).
    let reach = i.far.min(i.max_distance);
    let jitter = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
    let centre = if rng.unit() < 0.8 {
        position + dir * (reach * rng.unit()) + jitter * (0.1 * reach)
    } else {
        position + jitter * 200.0
    };
    let half = DVec3::new(
        log_uniform(rng, -6.0, 4.0),
        log_uniform(rng, -6.0, 4.0),
        log_uniform(rng, -6.0, 4.0),
    );
    i.scene_min = (centre - half).to_array();
    i.scene_max = (centre + half).to_array();
    i.world_offset = std::array::from_fn(|_| {
        if rng.unit() < 0.3 {
            0.0
        } else {
            let s = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
            s * log_uniform(rng, 0.0, 6.0)
        }
    });
    // Motion. Pitch only when the view is at least 45 degrees from vertical, so that at most
    // 32 frames of at most 1 degree never tilt it over the top.
    i.frames = 2 + pick(rng, 31) as i64;
    let (motion, step) = match pick(rng, 5) {
        0 => ("strafe", log_uniform(rng, -4.0, 0.0)),
        1 => ("dolly", log_uniform(rng, -4.0, 0.0)),
        2 => ("yaw", rng.range(0.01, 2.0)),
        3 if dir.y.abs() < 0.7 => ("pitch", rng.range(0.01, 1.0)),
        _ => ("orbit", rng.range(0.01, 2.0)),
    };
    i.motion = motion;
    i.step = step;
    StressCase {
        name: format!("random {k}"),
        inputs: i,
        expect: Expect::Valid,
    }
}

// ---------------------------------------------------------------------------------------------
// Invariant checks: pure functions of computed values
// ---------------------------------------------------------------------------------------------

/// The outcome of one invariant on one case.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Check {
    pub invariant: &'static str,
    /// The worst value seen (its meaning is the invariant's; see the module docs).
    pub worst: f64,
    pub pass: bool,
}

pub(crate) fn check_finite(nonfinite_values: usize) -> Check {
    Check {
        invariant: "finite",
        worst: nonfinite_values as f64,
        pass: nonfinite_values == 0,
    }
}

/// Strictly increasing split depths; the worst value is the smallest gap (NaN-safe: a
/// non-finite or non-positive gap fails).
pub(crate) fn check_splits_increasing(splits: &[f64]) -> Check {
    let gap = splits
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, |m, g| if g.is_nan() { f64::NAN } else { m.min(g) });
    Check {
        invariant: "splits_increasing",
        worst: gap,
        pass: splits.len() >= 2 && gap > 0.0 && gap.is_finite(),
    }
}

/// The splits start at `z_lo` and end at `z_hi`, exactly.
pub(crate) fn check_splits_end_at_range(splits: &[f64], z_lo: f64, z_hi: f64) -> Check {
    let err = match (splits.first(), splits.last()) {
        (Some(a), Some(b)) => (a - z_lo).abs().max((b - z_hi).abs()),
        _ => f64::INFINITY,
    };
    Check {
        invariant: "splits_end_at_range",
        worst: err,
        pass: err == 0.0,
    }
}

pub(crate) fn check_coverage(violations: u64) -> Check {
    Check {
        invariant: "coverage",
        worst: violations as f64,
        pass: violations == 0,
    }
}

/// Stabilised (sphere, snapped) drift in f64, largest over the path.
pub(crate) fn check_stabilised_shimmer(max_drift: f64) -> Check {
    Check {
        invariant: "stabilised_shimmer_f64",
        worst: max_drift,
        pass: max_drift < STABILISED_LIMIT,
    }
}

/// The opt-in f32 gate: the largest f32 drift over both snap spaces.
pub(crate) fn check_f32_drift(max_drift: f64, limit: f64) -> Check {
    Check {
        invariant: "f32_drift_limit",
        worst: max_drift,
        pass: max_drift <= limit,
    }
}

/// Whether a config was accepted, for a case that must be.
pub(crate) fn check_accepted(error: Option<&str>) -> Check {
    Check {
        invariant: "config_accepted",
        worst: if error.is_some() { 1.0 } else { 0.0 },
        pass: error.is_none(),
    }
}

/// An invalid-by-design case: rejected, and the message names the key.
pub(crate) fn check_clear_rejection(error: Option<&str>, key: &str) -> Check {
    let pass = error.is_some_and(|e| e.contains(key));
    Check {
        invariant: "clear_rejection",
        worst: if pass { 0.0 } else { 1.0 },
        pass,
    }
}

/// Counts NaN and infinities in what an analysis computes beyond its written summary: the
/// density profile and the per-frame rows.
pub(crate) fn count_nonfinite(a: &Analysis) -> usize {
    let bad = |xs: &[f64]| xs.iter().filter(|x| !x.is_finite()).count();
    let mut n = 0;
    for d in &a.density {
        n += bad(&[d.depth, d.texel_size, d.pixel_size, d.texels_per_pixel, d.aliasing]);
    }
    for p in [a.snapped(), a.unsnapped()].into_iter().flatten() {
        for f in &p.frames {
            n += bad(&[
                f.size_change,
                f.phase_drift_rms,
                f.phase_drift_max,
                f.cell_flips.unwrap_or(0.0),
            ]);
        }
        n += bad(&p.coverage.worst_texels) + bad(&p.coverage.min_slack_texels);
    }
    n
}

/// What the files of `analyze` would say about an analysis: the non-finite numbers in its
/// summary document and the files that refuse to render. Supplied by the caller (the report
/// layer knows the files), so this module computes without depending on it.
pub(crate) type OutputCheck = fn(&Analysis) -> (usize, Vec<String>);

// ---------------------------------------------------------------------------------------------
// Running cases
// ---------------------------------------------------------------------------------------------

/// The binary32 residuals of one snap space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct F32Residual {
    /// Largest snapped drift per frame (texels).
    pub drift_max: f64,
    /// S7 largest (texels).
    pub lookup_error_max: f64,
    /// Slice corners outside the f32 windows (configured snapping).
    pub coverage_violations: u64,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CaseResult {
    pub case: StressCase,
    pub checks: Vec<Check>,
    /// None when the case was rejected.
    pub cascades_needed: Option<bool>,
    pub f32_world: Option<F32Residual>,
    pub f32_relative: Option<F32Residual>,
    /// Errors and remarks (the rejection message of an invalid case, an f32 refusal).
    pub note: String,
}

impl CaseResult {
    pub(crate) fn pass(&self) -> bool {
        self.checks.iter().all(|c| c.pass)
    }

    pub(crate) fn failed(&self) -> Vec<&'static str> {
        self.checks.iter().filter(|c| !c.pass).map(|c| c.invariant).collect()
    }

    pub(crate) fn check(&self, invariant: &str) -> Option<&Check> {
        self.checks.iter().find(|c| c.invariant == invariant)
    }
}

/// Options of a stress run.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StressOptions {
    /// Fail a case whose f32 drift (either snap space) exceeds this many texels.
    pub max_f32_drift: Option<f64>,
    /// Renders what `analyze` would write and reports what is not finite.
    pub outputs: OutputCheck,
}

fn f32_residual(a: &Analysis) -> F32Residual {
    F32Residual {
        drift_max: a.snapped().map_or(0.0, |p| p.stats.max),
        lookup_error_max: a.summary.lookup_error_max,
        coverage_violations: a.summary.coverage_violations,
    }
}

/// Runs one case: parse, analyse in f64 (and the sphere fit, if the case uses another), in
/// f32 world and f32 camera-relative, and check the invariants.
pub(crate) fn run_case(case: &StressCase, opts: &StressOptions) -> CaseResult {
    let inputs = &case.inputs;
    let mut result = CaseResult {
        case: case.clone(),
        checks: Vec::new(),
        cascades_needed: None,
        f32_world: None,
        f32_relative: None,
        note: String::new(),
    };
    let parsed = inputs.parse(Precision::F64, SnapSpace::World, inputs.fit);
    let error = parsed.as_ref().err().map(|e| e.without_excerpt());
    if let Expect::Rejected { key } = case.expect {
        result.checks.push(check_clear_rejection(error.as_deref(), key));
        result.note = error.unwrap_or_else(|| "accepted, but should have been rejected".into());
        return result;
    }
    result.checks.push(check_accepted(error.as_deref()));
    let Ok(config) = parsed else {
        result.note = error.unwrap_or_default();
        return result;
    };
    let full = AnalysisOptions::full();
    let a = analyze(&config, &full);
    result.cascades_needed = Some(a.summary.cascades_needed);
    let check_outputs = |a: &Analysis| {
        let (n, notes) = (opts.outputs)(a);
        (n + count_nonfinite(a), notes)
    };
    let (mut nonfinite, mut notes) = check_outputs(&a);

    if let Some(rig) = a.rig() {
        result.checks.push(check_splits_increasing(&rig.splits));
        result
            .checks
            .push(check_splits_end_at_range(&rig.splits, a.summary.z_lo, a.summary.z_hi));
    }
    let mut violations = a.summary.coverage_violations;
    // The stabilised configuration: sphere fit, snapped, f64.
    let sphere = if inputs.fit == Fit::Sphere {
        None
    } else {
        match inputs.parse(Precision::F64, SnapSpace::World, Fit::Sphere) {
            Ok(c) => Some(analyze(&c, &full)),
            Err(e) => {
                notes.push(format!("sphere variant: {}", e.without_excerpt()));
                None
            }
        }
    };
    if let Some(s) = &sphere {
        let (n, more) = check_outputs(s);
        nonfinite += n;
        notes.extend(more);
        violations += s.summary.coverage_violations;
    }
    let stabilised = sphere.as_ref().unwrap_or(&a);
    if inputs.preset.is_none() {
        if let Some(p) = stabilised.snapped() {
            result.checks.push(check_stabilised_shimmer(p.stats.max));
        }
        result.checks.push(check_coverage(violations));
    }

    // binary32 residuals, reported; a scene binary32 cannot hold is noted, not failed.
    for space in [SnapSpace::World, SnapSpace::CameraRelative] {
        match inputs.parse(Precision::F32, space, inputs.fit) {
            Ok(c) => {
                let f = analyze(&c, &full);
                let (n, more) = check_outputs(&f);
                nonfinite += n;
                notes.extend(more);
                if f.summary.cascades_needed {
                    let r = Some(f32_residual(&f));
                    match space {
                        SnapSpace::World => result.f32_world = r,
                        SnapSpace::CameraRelative => result.f32_relative = r,
                    }
                }
            }
            Err(e) => notes.push(format!("f32 {space}: {}", e.without_excerpt())),
        }
    }
    result.checks.insert(1, check_finite(nonfinite));
    if let Some(limit) = opts.max_f32_drift {
        let drift = [result.f32_world, result.f32_relative]
            .iter()
            .flatten()
            .map(|r| r.drift_max)
            .fold(0.0, f64::max);
        result.checks.push(check_f32_drift(drift, limit));
    }
    notes.dedup();
    result.note = notes.join("; ");
    result
}

/// [`run`], calling `on_done` after each case (from any thread).
pub(crate) fn run_with_progress(
    cases: &[StressCase],
    opts: &StressOptions,
    on_done: &(dyn Fn() + Sync),
) -> Vec<CaseResult> {
    cases
        .par_iter()
        .map(|c| {
            let r = run_case(c, opts);
            on_done();
            r
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::analyze::output_problems;

    fn test_options() -> StressOptions {
        StressOptions {
            max_f32_drift: None,
            outputs: output_problems,
        }
    }

    #[test]
    fn each_check_fails_on_a_deliberately_broken_value() {
        assert!(check_splits_increasing(&[0.1, 1.0, 10.0]).pass);
        let bad = check_splits_increasing(&[0.1, 0.05, 10.0]);
        assert!(!bad.pass && bad.worst < 0.0, "{bad:?}");
        assert!(!check_splits_increasing(&[0.1, 0.1, 10.0]).pass, "equal splits");
        assert!(!check_splits_increasing(&[0.1, f64::NAN, 10.0]).pass, "NaN split");
        assert!(!check_splits_increasing(&[0.1]).pass, "no cascade");
        assert!(check_splits_end_at_range(&[0.1, 1.0, 10.0], 0.1, 10.0).pass);
        let end = check_splits_end_at_range(&[0.1, 1.0, 10.0], 0.1, 10.5);
        assert!(!end.pass && end.worst == 0.5);
        assert!(!check_splits_end_at_range(&[], 0.1, 10.0).pass);
        assert!(check_coverage(0).pass && !check_coverage(3).pass);
        assert!(check_finite(0).pass && !check_finite(2).pass);
        assert!(check_stabilised_shimmer(4.5e-13).pass);
        assert!(!check_stabilised_shimmer(1e-9).pass && !check_stabilised_shimmer(f64::NAN).pass);
        assert!(check_f32_drift(0.3, 0.5).pass && !check_f32_drift(0.6, 0.5).pass);
        assert!(check_accepted(None).pass && !check_accepted(Some("bad")).pass);
        assert!(check_clear_rejection(Some("x:1:1: `camera.near` = 0 is not allowed"), "camera.near").pass);
        assert!(!check_clear_rejection(Some("something else"), "camera.near").pass);
        assert!(!check_clear_rejection(None, "camera.near").pass, "accepted");
    }

    #[test]
    fn a_non_finite_value_anywhere_in_an_analysis_is_counted_and_refused() {
        let config = StressInputs::baseline()
            .parse(Precision::F64, SnapSpace::World, Fit::Sphere)
            .unwrap();
        let good = analyze(&config, &AnalysisOptions::full());
        let all = |a: &Analysis| {
            let (n, errors) = output_problems(a);
            (n + count_nonfinite(a), errors)
        };
        assert_eq!(all(&good), (0, vec![]));
        let mut a = good.clone();
        a.summary.max_aliasing = f64::NAN;
        assert_eq!(all(&a).0, 1);
        a.density[3].aliasing = f64::INFINITY;
        let crate::analysis::Outcome::Cascades(m) = &mut a.outcome else {
            panic!("the baseline needs cascades")
        };
        m.snapped.frames[0].phase_drift_max = f64::NAN;
        a.cascades[1].light_far = f64::NEG_INFINITY;
        let (n, errors) = all(&a);
        assert_eq!(n, 4);
        assert_eq!(errors.len(), 4, "every exporter refuses: {errors:?}");
        assert!(!check_finite(n).pass);
    }

    #[test]
    fn run_case_checks_every_invariant_and_detects_a_wrong_expectation() {
        let r = run_case(&battery()[0], &test_options());
        let names: Vec<_> = r.checks.iter().map(|c| c.invariant).collect();
        assert_eq!(
            names,
            [
                "config_accepted",
                "finite",
                "splits_increasing",
                "splits_end_at_range",
                "stabilised_shimmer_f64",
                "coverage"
            ]
        );
        assert!(r.pass(), "{r:?}");
        assert!(r.f32_world.is_some() && r.f32_relative.is_some());
        // A valid input labelled invalid-by-design: stress reports the failure.
        let wrong = StressCase {
            name: "mislabelled".into(),
            inputs: StressInputs::baseline(),
            expect: Expect::Rejected { key: "camera.near" },
        };
        let r = run_case(&wrong, &test_options());
        assert!(!r.pass() && r.failed() == ["clear_rejection"]);
        // An opt-in f32 limit of zero fails a case at 1e5 (world f32 drifts there).
        let far = case("far", |i| i.world_offset = [1e5, 0.0, 0.0]);
        let r = run_case(
            &far,
            &StressOptions {
                max_f32_drift: Some(0.0),
                ..test_options()
            },
        );
        assert_eq!(r.failed(), ["f32_drift_limit"]);
        assert!(r.check("f32_drift_limit").unwrap().worst > 0.1);
    }

    #[test]
    fn the_battery_covers_every_pathological_input_of_the_issue() {
        let b = battery();
        let valid: Vec<&StressInputs> = b
            .iter()
            .filter(|c| c.expect == Expect::Valid)
            .map(|c| &c.inputs)
            .collect();
        let has = |f: &dyn Fn(&StressInputs) -> bool| valid.iter().any(|i| f(i));
        assert!(has(&|i| i.near == 1e-4 && i.far == 1e6));
        assert!(has(&|i| i.lambda == 0.0) && has(&|i| i.lambda == 1.0));
        assert!(has(&|i| i.cascades == 1) && has(&|i| i.cascades == 16));
        assert!(has(&|i| i.resolution == 16) && has(&|i| i.resolution == 16384));
        assert!(has(&|i| i.fov_y_deg == 1.0) && has(&|i| i.fov_y_deg == 179.0));
        let aspect = |i: &StressInputs| i.width as f64 / i.height as f64;
        assert!(has(&|i| (aspect(i) - 0.05).abs() < 1e-3) && has(&|i| aspect(i) == 20.0));
        assert!(has(&|i| i.light == [0.0, -1.0, 0.0]) && has(&|i| i.light == [0.0, 1.0, 0.0]));
        assert!(has(&|i| i.light[1] == 0.0), "grazing");
        let along_view = |i: &StressInputs| {
            let v = (DVec3::from(i.target) - DVec3::from(i.position)).normalize();
            DVec3::from(i.light).normalize().dot(v) > 1.0 - 1e-12
        };
        assert!(has(&along_view));
        for o in [0.0, 1e3, 1e4, 1e5, 1e6] {
            assert!(has(&|i| i.world_offset[0].abs() == o), "offset {o}");
        }
        let inside =
            |i: &StressInputs| (0..3).all(|k| i.scene_min[k] <= i.position[k] && i.position[k] <= i.scene_max[k]);
        assert!(has(&inside) && has(&|i| !inside(i)));
        assert!(has(&|i| (DVec3::from(i.position)).length() > 1e4), "far from the scene");
        assert!(has(
            &|i| i.scene_max[1] - i.scene_min[1] <= 1e-6 && i.scene_max[1] > i.scene_min[1]
        ));
        assert!(has(&|i| i.fit == Fit::Aabb));
        assert!(b.iter().filter(|c| c.expect != Expect::Valid).count() >= 5);
    }

    #[test]
    fn random_cases_are_valid_and_depend_only_on_the_seed() {
        let a = random_cases(300, 9);
        assert_eq!(a, random_cases(300, 9));
        assert_ne!(a, random_cases(300, 10));
        for c in &a {
            let parsed = c.inputs.parse(Precision::F64, SnapSpace::World, c.inputs.fit);
            assert!(parsed.is_ok(), "{}: {:?}", c.name, parsed.err());
        }
        // Each of the generator's branches appears.
        for m in ["strafe", "dolly", "yaw", "pitch", "orbit"] {
            assert!(a.iter().any(|c| c.inputs.motion == m), "{m}");
        }
        assert!(a.iter().any(|c| c.inputs.fit == Fit::Aabb) && a.iter().any(|c| !c.inputs.snap));
        assert!(a.iter().any(|c| c.inputs.resolution & (c.inputs.resolution - 1) != 0));
    }

    #[test]
    fn case_toml_goes_through_the_ordinary_validation() {
        let mut i = StressInputs::baseline();
        i.world_offset = [1e6, 0.0, -1e6];
        let c = i.parse(Precision::F32, SnapSpace::CameraRelative, Fit::Aabb).unwrap();
        assert_eq!(c.camera.position, DVec3::new(1e6, 10.0, -1e6));
        assert_eq!(c.shadow.fit, Fit::Aabb);
        assert_eq!(c.shadow.precision, Precision::F32);
        assert_eq!(c.shadow.snap_space, SnapSpace::CameraRelative);
        assert_eq!((c.analysis.probes, c.motion.frames), (CASE_PROBES, 24));
        i.near = f64::NAN;
        let e = i
            .parse(Precision::F64, SnapSpace::World, Fit::Sphere)
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera.near") && e.contains("finite"), "{e}");
    }
}
