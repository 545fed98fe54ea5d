//! The ground-truth pass over a level of views (docs/ground-truth.md, "Over a level of
//! views"): each judged view measured as if it were the camera ([`ground_truth::run`] on the
//! view's config), and the level's acne, edge, leak and flicker values pooled from the views'
//! counts, each view weighted as the screen statistics weigh it.

use super::ground_truth::{self, GroundTruth, TruthSummary};
use super::{config_for_view, rig, Summary};
use crate::config::Config;
use csm_core::screen::{pooled_share, view_weight_steps};
use csm_core::truth::ErrorKind;

/// The most views the ground truth judges: a pass costs about a second of one core per view
/// on the default scene, so a level of more views judges this many of them.
pub(crate) const MAX_JUDGED: usize = 8;

/// The views (indices into the config's views, ascending) the ground truth judges out of `n`:
/// every one when `n <= MAX_JUDGED`, else `floor(k · n / MAX_JUDGED)` for `k = 0, 1, …,
/// MAX_JUDGED − 1`: evenly spaced by index, the first view always among them. It depends on the
/// count alone, so every setting of a sweep judges the same views.
pub(crate) fn judged(n: usize) -> Vec<usize> {
    if n <= MAX_JUDGED {
        (0..n).collect()
    } else {
        (0..MAX_JUDGED).map(|k| k * n / MAX_JUDGED).collect()
    }
}

/// The names of the views a config's ground truth judges (empty without configured views).
pub(crate) fn judged_names(config: &Config) -> Vec<String> {
    judged(config.views.len())
        .into_iter()
        .map(|k| config.views[k].name.clone())
        .collect()
}

/// How `count` judged views of a level of `of` were chosen, in words: "every view", or
/// "evenly spaced by index, at most 8".
pub(crate) fn chosen(count: usize, of: usize) -> String {
    if count == of {
        "every view".to_string()
    } else {
        format!("evenly spaced by index, at most {MAX_JUDGED}")
    }
}

/// The rule of [`judged`] in words, for the outputs.
pub(crate) const RULE: &str = "every view up to 8; of more views, views floor(k * N / 8) for k = 0..7 \
                               (0-based, in the config's order: evenly spaced by index)";

/// What one pass counted: the denominators and numerators of its summary's fractions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct TruthCounts {
    /// Receivers a window covers at frame 0, and those of them with each error.
    pub(crate) covered: u64,
    pub(crate) acne: u64,
    pub(crate) edge: u64,
    pub(crate) leak: u64,
    /// Per snap mode (snapped, unsnapped): receiver steps counted, state changes, and the
    /// changes at shadow edges.
    pub(crate) steps: [u64; 2],
    pub(crate) flips: [u64; 2],
    pub(crate) edge_flips: [u64; 2],
}

impl TruthCounts {
    /// The counts behind a pass's summary.
    pub(crate) fn of(g: &GroundTruth) -> TruthCounts {
        let covered: Vec<_> = g.zero.iter().filter(|p| p.map_lit.is_some()).collect();
        let count = |k: ErrorKind| covered.iter().filter(|p| p.error() == Some(k)).count() as u64;
        let mut c = TruthCounts {
            covered: covered.len() as u64,
            acne: count(ErrorKind::Acne),
            edge: count(ErrorKind::Edge),
            leak: count(ErrorKind::Leak),
            ..TruthCounts::default()
        };
        for (m, f) in [&g.snapped, &g.unsnapped].into_iter().enumerate() {
            c.steps[m] = f.steps.iter().map(|&x| u64::from(x)).sum();
            c.flips[m] = f.flips.iter().map(|&x| u64::from(x)).sum();
            // The pass keeps the edge changes as their rate e / n, rounded once; for counts below
            // 2^51, rate × n is within a quarter of e, so rounding gives e back exactly.
            c.edge_flips[m] = (f.s5_edge * c.steps[m] as f64).round() as u64;
        }
        c
    }
}

/// The level's summary from the judged views' counts, each with its weight in whole steps:
/// every fraction is `Σ s_v · numerator_v / Σ s_v · denominator_v` (exact integer sums, one
/// rounding). The steps are divided by their greatest common divisor first, so views of equal
/// weight pool as plain counts and one view gives its own summary bit for bit.
pub(crate) fn pool(parts: &[(TruthCounts, u64)]) -> TruthSummary {
    let g = parts.iter().fold(0, |g, p| gcd(g, p.1)).max(1);
    let share = |num: &dyn Fn(&TruthCounts) -> u64, den: &dyn Fn(&TruthCounts) -> u64| {
        let v: Vec<(u64, u64, u64)> = parts.iter().map(|(c, s)| (num(c), den(c), s / g)).collect();
        pooled_share(&v)
    };
    let covered = |c: &TruthCounts| c.covered;
    let flicker = |m: usize| {
        (
            share(&|c| c.flips[m], &|c| c.steps[m]),
            share(&|c| c.edge_flips[m], &|c| c.steps[m]),
            share(&|c| c.flips[m] - c.edge_flips[m], &|c| c.steps[m]),
        )
    };
    let (s, se, sa) = flicker(0);
    let (u, ue, ua) = flicker(1);
    TruthSummary {
        acne_fraction: share(&|c| c.acne, &covered),
        edge_error_fraction: share(&|c| c.edge, &covered),
        leak_fraction: share(&|c| c.leak, &covered),
        flicker_snapped: s,
        flicker_unsnapped: u,
        flicker_edge_snapped: se,
        flicker_edge_unsnapped: ue,
        flicker_acne_snapped: sa,
        flicker_acne_unsnapped: ua,
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// How many frames [`apply`] walks for `config` (both snap modes of every judged view): the
/// progress bar's share of the views' passes.
pub(crate) fn frames(config: &Config) -> u64 {
    let setup = config.setup();
    let per_view = 2 * csm_core::motion::poses(&setup.camera, &setup.motion).len() as u64;
    per_view * judged(config.views.len()).len() as u64
}

/// Runs the pass on each judged view of a level (`config.views` not empty, the pass asked for)
/// and pools it into `summary`: [`Summary::truth`] becomes the level's, and each judged view of
/// [`Summary::views`] keeps its own. `camera` is `[camera]`'s pass, reused for a view standing
/// exactly where `[camera]` stands. A judged view whose setting needs no cascades has no pass
/// (and adds nothing); when no judged view has one the summary has no ground truth.
pub(crate) fn apply(
    config: &Config,
    summary: &mut Summary,
    camera: Option<&GroundTruth>,
    on_frames: &(dyn Fn(u64) + Sync),
) {
    if summary.views.len() != config.views.len() {
        return;
    }
    let setup = config.setup();
    let per_view = 2 * csm_core::motion::poses(&setup.camera, &setup.motion).len() as u64;
    let mut parts = Vec::new();
    for k in judged(config.views.len()) {
        let view = &config.views[k];
        let counted = match camera.filter(|_| view.camera == config.camera) {
            Some(g) => {
                on_frames(per_view);
                Some((g.summary, TruthCounts::of(g)))
            }
            None => {
                let vc = config_for_view(config, view);
                // Only the pooled counts are read from a view's pass: no texel-read tally.
                let pass = rig(&vc).and_then(|r| ground_truth::run(&vc, &r, false, on_frames));
                if pass.is_none() {
                    // Nothing walked: the bar still moves by the view's share.
                    on_frames(per_view);
                }
                pass.map(|g| (g.summary, TruthCounts::of(&g)))
            }
        };
        let v = &mut summary.views[k];
        v.judged = true;
        v.truth = counted.map(|c| c.0);
        if let Some((_, c)) = counted {
            parts.push((c, view_weight_steps(view.weight)));
        }
    }
    summary.truth = (!parts.is_empty()).then(|| pool(&parts));
}

/// A small level for the crate's tests: the default camera over a ground and a box, a
/// 640 × 360 screen, two cascades, and three views that each see the lit ground.
#[cfg(test)]
pub(crate) const TEST_LEVEL: &str = r#"
camera = { position = [0.0, 10.0, 0.0], target = [0.0, 0.0, -50.0], fov_y_deg = 60.0, near = 0.1, far = 1000.0 }
screen = { width = 640, height = 360 }
[light]
direction = [-0.4, -1.0, -0.3]
[scene]
min = [-200.0, 0.0, -200.0]
max = [200.0, 40.0, 200.0]
ground = 0.0
[[scene.box]]
min = [15.0, 0.0, -70.0]
max = [35.0, 25.0, -45.0]
[shadow]
max_distance = 150.0
cascades = 2
resolution = 1024
[[view]]
name = "street"
position = [5.0, 1.7, 10.0]
target = [-20.0, 2.0, -60.0]
[[view]]
name = "roof"
position = [40.0, 30.0, 20.0]
target = [0.0, 0.0, -80.0]
[[view]]
name = "corner"
position = [-60.0, 8.0, -20.0]
target = [10.0, 0.0, -100.0]
"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_judged_views_are_all_of_a_few_and_evenly_spaced_of_many() {
        assert_eq!(judged(0), Vec::<usize>::new());
        assert_eq!(judged(3), [0, 1, 2]);
        assert_eq!(judged(8), (0..8).collect::<Vec<_>>());
        // floor(k · n / 8) by hand.
        assert_eq!(judged(9), [0, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(judged(10), [0, 1, 2, 3, 5, 6, 7, 8]);
        assert_eq!(judged(20), [0, 2, 5, 7, 10, 12, 15, 17]);
        assert_eq!(judged(100), [0, 12, 25, 37, 50, 62, 75, 87]);
        for n in 9..500 {
            let j = judged(n);
            assert_eq!(j.len(), MAX_JUDGED);
            assert!(j.windows(2).all(|w| w[0] < w[1]) && j[7] < n, "{n}: {j:?}");
        }
    }

    /// The progress bar's length counts `[camera]`'s pass and each judged view's (both snap
    /// modes), and the passes report every frame: the bar ends full. A view at `[camera]`'s
    /// pose reuses its pass and still moves the bar by its share.
    #[test]
    fn the_views_passes_report_every_frame_to_the_progress_bar() {
        use crate::analysis::{analyze_with_progress, frames_walked, frames_walked_with, AnalysisOptions};
        use std::sync::atomic::{AtomicU64, Ordering};
        let text = TEST_LEVEL.replace("[[view]]\nname = \"street\"", "[[view]]\nname = \"here\"\nposition = [0.0, 10.0, 0.0]\ntarget = [0.0, 0.0, -50.0]\n[[view]]\nname = \"street\"")
            + "[motion]\npath = \"strafe\"\nframes = 9\n[analysis]\nground_truth = true\nscreen_scale = 0.25\n";
        let c = Config::from_toml_str(&text, "t.toml", None).unwrap();
        assert_eq!(c.views.len(), 4);
        let opts = AnalysisOptions::full();
        assert_eq!(frames_walked_with(&c, &opts), frames_walked(&c) + 5 * 2 * 9);
        let seen = AtomicU64::new(0);
        let a = analyze_with_progress(&c, &opts, &|n| {
            seen.fetch_add(n, Ordering::Relaxed);
        });
        assert!(a.summary.views.iter().all(|v| v.judged && v.truth.is_some()));
        // The view standing where [camera] stands has [camera]'s own values.
        assert_eq!(a.summary.views[0].truth, a.ground_truth.as_ref().map(|g| g.summary));
        assert_eq!(seen.load(Ordering::Relaxed), frames_walked_with(&c, &opts));
    }

    fn counts(seed: u64) -> TruthCounts {
        let mut r = csm_core::rng::SplitMix64::new(seed);
        let mut n = |hi: u64| (r.unit() * hi as f64) as u64;
        let covered = 1000 + n(50_000);
        let steps = [1 + n(5_000_000), 1 + n(5_000_000)];
        let flips = [n(steps[0] / 10), n(steps[1] / 10)];
        TruthCounts {
            covered,
            acne: n(covered / 100),
            edge: n(covered / 100),
            leak: n(covered / 1000),
            steps,
            flips,
            edge_flips: [n(flips[0] + 1).min(flips[0]), n(flips[1] + 1).min(flips[1])],
        }
    }

    /// The pool equals sums of weighted counts computed here in 128-bit integers and divided
    /// once; one view, or views of one weight, pool as plain counts.
    #[test]
    fn the_pool_is_the_weighted_sum_of_counts() {
        for seed in 0..200u64 {
            let views = 1 + (seed % 6) as usize;
            let parts: Vec<(TruthCounts, u64)> = (0..views)
                .map(|v| (counts(seed * 31 + v as u64), view_weight_steps(0.5 + (v % 3) as f64)))
                .collect();
            let p = pool(&parts);
            let brute = |f: &dyn Fn(&TruthCounts) -> (u64, u64)| {
                let (mut a, mut b) = (0u128, 0u128);
                for (c, s) in &parts {
                    let (x, y) = f(c);
                    a += x as u128 * *s as u128;
                    b += y as u128 * *s as u128;
                }
                a as f64 / b as f64
            };
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-15 * y.abs().max(1e-300);
            assert!(close(p.acne_fraction, brute(&|c| (c.acne, c.covered))));
            assert!(close(p.edge_error_fraction, brute(&|c| (c.edge, c.covered))));
            assert!(close(p.leak_fraction, brute(&|c| (c.leak, c.covered))));
            assert!(close(p.flicker_snapped, brute(&|c| (c.flips[0], c.steps[0]))));
            assert!(close(p.flicker_unsnapped, brute(&|c| (c.flips[1], c.steps[1]))));
            assert!(close(
                p.flicker_edge_unsnapped,
                brute(&|c| (c.edge_flips[1], c.steps[1]))
            ));
            assert!(close(
                p.flicker_acne_snapped,
                brute(&|c| (c.flips[0] - c.edge_flips[0], c.steps[0]))
            ));
            // One view: its own fractions, as the pass divides them.
            let (c, _) = parts[0];
            let one = pool(&[(c, view_weight_steps(3.7))]);
            assert_eq!(one.acne_fraction, c.acne as f64 / c.covered as f64);
            assert_eq!(one.flicker_unsnapped, c.flips[1] as f64 / c.steps[1] as f64);
            // Equal weights: plain counts.
            let same: Vec<_> = parts.iter().map(|(c, _)| (*c, view_weight_steps(2.5))).collect();
            let total = |f: &dyn Fn(&TruthCounts) -> u64| same.iter().map(|(c, _)| f(c)).sum::<u64>() as f64;
            assert_eq!(pool(&same).leak_fraction, total(&|c| c.leak) / total(&|c| c.covered));
        }
        // Nothing covered: 0, as the single pass says.
        assert_eq!(pool(&[(TruthCounts::default(), 1)]).acne_fraction, 0.0);
    }
}
