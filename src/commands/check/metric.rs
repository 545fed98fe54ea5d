//! The metrics a threshold rule can limit, what each one means, and which direction is worse.
//!
//! Three kinds:
//! - **summary** metrics: one number per configuration, every field of [`Summary`];
//! - **per-cascade** metrics: one number per cascade, fields of [`CascadeReport`];
//! - **per-depth** metrics: functions of view depth (`aliasing`, `texels_per_pixel`), limited
//!   over a depth range and evaluated exactly by [`super::depth`].
//!
//! `max_aliasing`, `coverage_violations`, `lookup_error_max` and `lookup_error_rms` exist both as
//! summary and as per-cascade metrics;
//! a rule picks the per-cascade one only when it says `cascade = ...`.
//!
//! The "worse" direction is what a baseline comparison uses to call a change a regression or
//! an improvement. [`Direction::Neither`] marks positions (depths, light-space depths) that
//! describe where something is rather than how good it is: they can still be limited by rules,
//! and a baseline reports their changes, but never as regressions.

use crate::analysis::{CascadeReport, Summary};

/// Which way a metric gets worse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    HigherIsWorse,
    LowerIsWorse,
    /// A position, not a quality: changes are reported, never as regressions.
    Neither,
}

impl Direction {
    pub fn describe(self) -> &'static str {
        match self {
            Direction::HigherIsWorse => "higher is worse",
            Direction::LowerIsWorse => "lower is worse",
            Direction::Neither => "neither (a position, not a quality)",
        }
    }

    /// How much worse `current` is than `baseline`, in the metric's units (negative when it
    /// improved); None for [`Direction::Neither`].
    pub fn worsening(self, baseline: f64, current: f64) -> Option<f64> {
        match self {
            Direction::HigherIsWorse => Some(current - baseline),
            Direction::LowerIsWorse => Some(baseline - current),
            Direction::Neither => None,
        }
    }
}

/// A field of [`Summary`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SummaryMetric {
    CascadesNeeded,
    ZLo,
    ZHi,
    MaxAliasing,
    MeanAliasing,
    MeanLogAliasing,
    UndersampledFraction,
    ShimmerSnapped,
    ShimmerUnsnapped,
    SizeJitter,
    CoverageViolations,
    MemoryBytes,
    LookupErrorMax,
    LookupErrorRms,
}

impl SummaryMetric {
    /// In the order of the fields of [`Summary`] (and of `summary.json`'s flat keys).
    pub const ALL: [SummaryMetric; 14] = [
        SummaryMetric::CascadesNeeded,
        SummaryMetric::ZLo,
        SummaryMetric::ZHi,
        SummaryMetric::MaxAliasing,
        SummaryMetric::MeanAliasing,
        SummaryMetric::MeanLogAliasing,
        SummaryMetric::UndersampledFraction,
        SummaryMetric::ShimmerSnapped,
        SummaryMetric::ShimmerUnsnapped,
        SummaryMetric::SizeJitter,
        SummaryMetric::CoverageViolations,
        SummaryMetric::MemoryBytes,
        SummaryMetric::LookupErrorMax,
        SummaryMetric::LookupErrorRms,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SummaryMetric::CascadesNeeded => "cascades_needed",
            SummaryMetric::ZLo => "z_lo",
            SummaryMetric::ZHi => "z_hi",
            SummaryMetric::MaxAliasing => "max_aliasing",
            SummaryMetric::MeanAliasing => "mean_aliasing",
            SummaryMetric::MeanLogAliasing => "mean_log_aliasing",
            SummaryMetric::UndersampledFraction => "undersampled_fraction",
            SummaryMetric::ShimmerSnapped => "shimmer_snapped",
            SummaryMetric::ShimmerUnsnapped => "shimmer_unsnapped",
            SummaryMetric::SizeJitter => "size_jitter",
            SummaryMetric::CoverageViolations => "coverage_violations",
            SummaryMetric::MemoryBytes => "memory_bytes",
            SummaryMetric::LookupErrorMax => "lookup_error_max",
            SummaryMetric::LookupErrorRms => "lookup_error_rms",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    pub fn direction(self) -> Direction {
        match self {
            // Losing the cascades means the scene left the shadowed range; every other metric
            // then reads 0, which must not pass for an improvement.
            SummaryMetric::CascadesNeeded => Direction::LowerIsWorse,
            SummaryMetric::ZLo | SummaryMetric::ZHi => Direction::Neither,
            _ => Direction::HigherIsWorse,
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            SummaryMetric::CascadesNeeded => "1 when the scene is visible within the shadow distance, else 0",
            SummaryMetric::ZLo => "near end of the split range (world units of view depth)",
            SummaryMetric::ZHi => "far end of the split range (world units of view depth)",
            SummaryMetric::MaxAliasing => "worst texel-to-pixel size ratio anywhere (at a cascade's near edge)",
            SummaryMetric::MeanAliasing => "aliasing ratio averaged over view depth",
            SummaryMetric::MeanLogAliasing => "aliasing ratio averaged over log depth",
            SummaryMetric::UndersampledFraction => "share of the depth range where aliasing > 1",
            SummaryMetric::ShimmerSnapped => "RMS sub-texel drift per frame with snapping (texels)",
            SummaryMetric::ShimmerUnsnapped => "RMS sub-texel drift per frame without snapping (texels)",
            SummaryMetric::SizeJitter => "largest relative texel-size change between frames",
            SummaryMetric::CoverageViolations => "slice corners outside their window, all cascades and frames",
            SummaryMetric::MemoryBytes => "cascades x resolution^2 x 4 bytes",
            SummaryMetric::LookupErrorMax => "largest static f32 lookup error S7 (texels; 0 in f64)",
            SummaryMetric::LookupErrorRms => "RMS static f32 lookup error S7 (texels; 0 in f64)",
        }
    }

    /// The metric's value; booleans read 1 (true) or 0 (false), counts as their value.
    pub fn value(self, s: &Summary) -> f64 {
        match self {
            SummaryMetric::CascadesNeeded => f64::from(u8::from(s.cascades_needed)),
            SummaryMetric::ZLo => s.z_lo,
            SummaryMetric::ZHi => s.z_hi,
            SummaryMetric::MaxAliasing => s.max_aliasing,
            SummaryMetric::MeanAliasing => s.mean_aliasing,
            SummaryMetric::MeanLogAliasing => s.mean_log_aliasing,
            SummaryMetric::UndersampledFraction => s.undersampled_fraction,
            SummaryMetric::ShimmerSnapped => s.shimmer_snapped,
            SummaryMetric::ShimmerUnsnapped => s.shimmer_unsnapped,
            SummaryMetric::SizeJitter => s.size_jitter,
            SummaryMetric::CoverageViolations => s.coverage_violations as f64,
            SummaryMetric::MemoryBytes => s.memory_bytes as f64,
            SummaryMetric::LookupErrorMax => s.lookup_error_max,
            SummaryMetric::LookupErrorRms => s.lookup_error_rms,
        }
    }
}

/// Every summary metric of a summary, by name, in [`SummaryMetric::ALL`] order.
pub fn summary_values(s: &Summary) -> Vec<(SummaryMetric, f64)> {
    SummaryMetric::ALL.into_iter().map(|m| (m, m.value(s))).collect()
}

/// A field of [`CascadeReport`] (cascade 0 is the nearest).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CascadeMetric {
    Near,
    Far,
    Radius,
    Width,
    Height,
    TexelSize,
    LightNear,
    LightFar,
    CoverageViolations,
    CoverageWorstTexels,
    MinSlackTexels,
    MaxAliasing,
    MinAliasing,
    LookupErrorMax,
    LookupErrorRms,
}

impl CascadeMetric {
    /// In the order of the fields of [`CascadeReport`] (and of `cascades.csv`).
    pub const ALL: [CascadeMetric; 15] = [
        CascadeMetric::Near,
        CascadeMetric::Far,
        CascadeMetric::Radius,
        CascadeMetric::Width,
        CascadeMetric::Height,
        CascadeMetric::TexelSize,
        CascadeMetric::LightNear,
        CascadeMetric::LightFar,
        CascadeMetric::CoverageViolations,
        CascadeMetric::CoverageWorstTexels,
        CascadeMetric::MinSlackTexels,
        CascadeMetric::MaxAliasing,
        CascadeMetric::MinAliasing,
        CascadeMetric::LookupErrorMax,
        CascadeMetric::LookupErrorRms,
    ];

    pub fn name(self) -> &'static str {
        match self {
            CascadeMetric::Near => "near",
            CascadeMetric::Far => "far",
            CascadeMetric::Radius => "radius",
            CascadeMetric::Width => "width",
            CascadeMetric::Height => "height",
            CascadeMetric::TexelSize => "texel_size",
            CascadeMetric::LightNear => "light_near",
            CascadeMetric::LightFar => "light_far",
            CascadeMetric::CoverageViolations => "coverage_violations",
            CascadeMetric::CoverageWorstTexels => "coverage_worst_texels",
            CascadeMetric::MinSlackTexels => "min_slack_texels",
            CascadeMetric::MaxAliasing => "max_aliasing",
            CascadeMetric::MinAliasing => "min_aliasing",
            CascadeMetric::LookupErrorMax => "lookup_error_max",
            CascadeMetric::LookupErrorRms => "lookup_error_rms",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    pub fn direction(self) -> Direction {
        match self {
            CascadeMetric::Near | CascadeMetric::Far | CascadeMetric::LightNear | CascadeMetric::LightFar => {
                Direction::Neither
            }
            // Less room between the slice and its window edge: closer to a coverage hole.
            CascadeMetric::MinSlackTexels => Direction::LowerIsWorse,
            _ => Direction::HigherIsWorse,
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            CascadeMetric::Near => "view depth where the cascade starts (world units)",
            CascadeMetric::Far => "view depth where the cascade ends (world units)",
            CascadeMetric::Radius => "minimal bounding-sphere radius of the slice (world units)",
            CascadeMetric::Width => "window width in light space (world units)",
            CascadeMetric::Height => "window height in light space (world units)",
            CascadeMetric::TexelSize => "world size of one shadow texel",
            CascadeMetric::LightNear => "light-space depth where the cascade's render starts",
            CascadeMetric::LightFar => "light-space depth where the cascade's render ends",
            CascadeMetric::CoverageViolations => "slice corners outside the window over the path",
            CascadeMetric::CoverageWorstTexels => "farthest a slice corner got outside the window (texels)",
            CascadeMetric::MinSlackTexels => "smallest margin between a slice corner and the window edge (texels)",
            CascadeMetric::MaxAliasing => "aliasing ratio at the cascade's near edge",
            CascadeMetric::MinAliasing => "aliasing ratio at the cascade's far edge",
            CascadeMetric::LookupErrorMax => "largest static f32 lookup error S7 in this cascade (texels)",
            CascadeMetric::LookupErrorRms => "RMS static f32 lookup error S7 in this cascade (texels)",
        }
    }

    pub fn value(self, c: &CascadeReport) -> f64 {
        match self {
            CascadeMetric::Near => c.near,
            CascadeMetric::Far => c.far,
            CascadeMetric::Radius => c.radius,
            CascadeMetric::Width => c.width,
            CascadeMetric::Height => c.height,
            CascadeMetric::TexelSize => c.texel_size,
            CascadeMetric::LightNear => c.light_near,
            CascadeMetric::LightFar => c.light_far,
            CascadeMetric::CoverageViolations => c.coverage_violations as f64,
            CascadeMetric::CoverageWorstTexels => c.coverage_worst_texels,
            CascadeMetric::MinSlackTexels => c.min_slack_texels,
            CascadeMetric::MaxAliasing => c.max_aliasing,
            CascadeMetric::MinAliasing => c.min_aliasing,
            CascadeMetric::LookupErrorMax => c.lookup_error_max,
            CascadeMetric::LookupErrorRms => c.lookup_error_rms,
        }
    }
}

/// A function of view depth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthMetric {
    /// `a(d) = K T_i / d`: shadow texel size over screen pixel size. Higher is worse (blockier).
    Aliasing,
    /// `1 / a(d)`: texels per pixel along one axis. Lower is worse.
    TexelsPerPixel,
}

impl DepthMetric {
    pub const ALL: [DepthMetric; 2] = [DepthMetric::Aliasing, DepthMetric::TexelsPerPixel];

    pub fn name(self) -> &'static str {
        match self {
            DepthMetric::Aliasing => "aliasing",
            DepthMetric::TexelsPerPixel => "texels_per_pixel",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    pub fn direction(self) -> Direction {
        match self {
            DepthMetric::Aliasing => Direction::HigherIsWorse,
            DepthMetric::TexelsPerPixel => Direction::LowerIsWorse,
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            DepthMetric::Aliasing => "shadow texel size over screen pixel size at a view depth",
            DepthMetric::TexelsPerPixel => "screen pixel size over shadow texel size at a view depth",
        }
    }
}

/// Every metric name a rule may use, each once, in catalogue order.
pub fn all_names() -> Vec<&'static str> {
    let mut names: Vec<&'static str> = SummaryMetric::ALL.iter().map(|m| m.name()).collect();
    for n in CascadeMetric::ALL.iter().map(|m| m.name()) {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    names.extend(DepthMetric::ALL.iter().map(|m| m.name()));
    names
}

/// Levenshtein distance in characters (insert, delete, substitute each cost 1).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    // One row of the DP table at a time: prev[j] = distance(a[..i], b[..j]).
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = Vec::with_capacity(b.len() + 1);
        cur.push(i + 1);
        for (j, &cb) in b.iter().enumerate() {
            let substitute = prev[j] + usize::from(ca != cb);
            cur.push(substitute.min(prev[j + 1] + 1).min(cur[j] + 1));
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The candidate nearest to `name` by edit distance (the first one on ties).
pub fn closest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    candidates.iter().copied().min_by_key(|c| edit_distance(name, c))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("", ""), 0);
        assert_eq!(edit_distance("abc", ""), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("max_alising", "max_aliasing"), 1);
        assert_eq!(edit_distance("flaw", "lawn"), 2);
        // Symmetric, and zero only for equal strings.
        for a in all_names() {
            for b in all_names() {
                assert_eq!(edit_distance(a, b), edit_distance(b, a));
                assert_eq!(edit_distance(a, b) == 0, a == b);
            }
        }
    }

    #[test]
    fn closest_name_recovers_single_typos() {
        let names = all_names();
        for n in &names {
            let mid = n.len() / 2;
            // Drop one character, or double it: one edit away from the original.
            for typo in [
                format!("{}{}", &n[..mid], &n[mid + 1..]),
                format!("{}{}", &n[..=mid], &n[mid..]),
            ] {
                let got = closest(&typo, &names).unwrap();
                let at_one: Vec<&str> = names.iter().copied().filter(|c| edit_distance(&typo, c) == 1).collect();
                assert!(at_one.contains(n), "{typo}");
                assert!(names.iter().all(|c| edit_distance(&typo, c) >= 1));
                assert!(at_one.contains(&got), "{typo} -> {got}");
                if at_one.len() == 1 {
                    assert_eq!(got, *n, "{typo}");
                }
            }
        }
        assert_eq!(closest("texel_sise", &names), Some("texel_size"));
        assert_eq!(closest("texel_per_pixel", &names), Some("texels_per_pixel"));
    }

    #[test]
    fn summary_metrics_are_exactly_the_fields_of_summary() {
        let s = Summary {
            cascades_needed: true,
            z_lo: 1.0,
            z_hi: 2.0,
            max_aliasing: 3.0,
            mean_aliasing: 4.0,
            mean_log_aliasing: 5.0,
            undersampled_fraction: 0.25,
            shimmer_snapped: 6.0,
            shimmer_unsnapped: 7.0,
            size_jitter: 8.0,
            coverage_violations: 9,
            memory_bytes: 10,
            lookup_error_max: 11.0,
            lookup_error_rms: 12.0,
        };
        let json = serde_json::to_value(&s).unwrap();
        let keys: Vec<&str> = json.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        let mut names: Vec<&str> = SummaryMetric::ALL.iter().map(|m| m.name()).collect();
        names.sort_unstable();
        let mut keys_sorted = keys.clone();
        keys_sorted.sort_unstable();
        assert_eq!(keys_sorted, names);
        for (m, v) in summary_values(&s) {
            let j = &json[m.name()];
            let expected = j.as_f64().or_else(|| j.as_bool().map(|b| if b { 1.0 } else { 0.0 }));
            assert_eq!(Some(v), expected, "{}", m.name());
        }
    }

    #[test]
    fn cascade_metrics_are_the_numeric_fields_of_cascade_report() {
        let c = CascadeReport {
            cascade: 0,
            near: 1.0,
            far: 2.0,
            radius: 3.0,
            width: 4.0,
            height: 5.0,
            texel_size: 6.0,
            // Window centres are positions, not metrics (cascades.csv only).
            centre_x: 0.25,
            centre_y: 0.5,
            centre_x_texels: 0.75,
            centre_y_texels: 1.25,
            light_near: 7.0,
            light_far: 8.0,
            coverage_violations: 9,
            coverage_worst_texels: 10.0,
            min_slack_texels: 11.0,
            max_aliasing: 12.0,
            min_aliasing: 13.0,
            lookup_error_max: 14.0,
            lookup_error_rms: 15.0,
        };
        let json = serde_json::to_value(&c).unwrap();
        let obj = json.as_object().unwrap();
        assert_eq!(obj.len(), CascadeMetric::ALL.len() + 1, "every field but `cascade`");
        for m in CascadeMetric::ALL {
            assert_eq!(obj[m.name()].as_f64(), Some(m.value(&c)), "{}", m.name());
        }
    }

    #[test]
    fn every_name_resolves_to_its_own_metric() {
        for m in SummaryMetric::ALL {
            assert_eq!(SummaryMetric::from_name(m.name()), Some(m));
        }
        for m in CascadeMetric::ALL {
            assert_eq!(CascadeMetric::from_name(m.name()), Some(m));
        }
        for m in DepthMetric::ALL {
            assert_eq!(DepthMetric::from_name(m.name()), Some(m));
        }
        let names = all_names();
        let mut dedup = names.clone();
        dedup.sort_unstable();
        dedup.dedup();
        assert_eq!(dedup.len(), names.len());
        // Four names are both summary and per-cascade metrics (max_aliasing,
        // coverage_violations, lookup_error_max, lookup_error_rms).
        assert_eq!(names.len(), 14 + 15 - 4 + 2);
    }

    #[test]
    fn worsening_follows_the_direction() {
        assert_eq!(Direction::HigherIsWorse.worsening(1.0, 3.0), Some(2.0));
        assert_eq!(Direction::LowerIsWorse.worsening(1.0, 3.0), Some(-2.0));
        assert_eq!(Direction::Neither.worsening(1.0, 3.0), None);
        assert_eq!(CascadeMetric::MinSlackTexels.direction(), Direction::LowerIsWorse);
        assert_eq!(DepthMetric::TexelsPerPixel.direction(), Direction::LowerIsWorse);
        assert_eq!(SummaryMetric::MaxAliasing.direction(), Direction::HigherIsWorse);
    }
}
