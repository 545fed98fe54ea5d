//! "Did you mean ...?": the edit distance between two names and the nearest of a list, for
//! every message that rejects an unknown name (metrics, presets).

/// Levenshtein distance in characters (insert, delete, substitute each cost 1), by `strsim`.
pub(crate) fn edit_distance(a: &str, b: &str) -> usize {
    strsim::levenshtein(a, b)
}

/// The candidate nearest to `name` by edit distance (the first one on ties).
pub(crate) fn closest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    candidates.iter().copied().min_by_key(|c| edit_distance(name, c))
}

/// Words people write for a metric, and the registry name they mean.
pub(crate) const METRIC_SYNONYMS: &[(&str, &str)] = &[
    ("shimmer_rms", "shimmer"),
    ("drift", "shimmer"),
    ("shimmer_snap", "shimmer_snapped"),
    ("shimmer_nosnap", "shimmer_unsnapped"),
    ("jitter", "size_jitter"),
    ("aliasing_max", "max_aliasing"),
    ("aliasing_mean", "mean_aliasing"),
    ("coverage", "coverage_violations"),
    ("memory", "memory_bytes"),
    ("texel", "texel_size"),
    ("slack", "min_slack_texels"),
    ("f32_error", "lookup_error_max"),
    ("lookup_error", "lookup_error_max"),
    ("density", "texels_per_pixel"),
];

/// The registry name an unknown metric name most likely means: a known synonym, else a name
/// that contains it (or that it contains) as whole `_`-separated words, else the nearest by
/// edit distance. Only names in `names` are suggested.
pub(crate) fn metric_suggestion<'a>(name: &str, names: &[&'a str]) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    if let Some(&(_, target)) = METRIC_SYNONYMS.iter().find(|(w, _)| *w == lower) {
        if let Some(n) = names.iter().copied().find(|n| *n == target) {
            return Some(n);
        }
    }
    let words = |s: &str| s.split('_').map(str::to_string).collect::<Vec<_>>();
    let mine = words(&lower);
    let shared = |n: &str| {
        let theirs = words(n);
        mine.iter().filter(|w| theirs.contains(w)).count()
    };
    // Names sharing the most whole words, nearest by edit distance among them.
    let best = names.iter().map(|n| shared(n)).max().unwrap_or(0);
    if best > 0 && best * 2 >= mine.len() {
        let pool: Vec<&'a str> = names.iter().copied().filter(|n| shared(n) == best).collect();
        return closest(&lower, &pool);
    }
    closest(&lower, names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::check::metric::all_names;

    #[test]
    fn metric_suggestions_know_near_synonyms() {
        let names = all_names();
        let s = |n: &str| metric_suggestion(n, &names).unwrap();
        assert_eq!(s("shimmer_rms"), "shimmer");
        assert_eq!(s("shimmer_snap"), "shimmer_snapped");
        assert_eq!(s("snapped_shimmer"), "shimmer_snapped");
        assert_eq!(s("aliasing_max"), "max_aliasing");
        assert_eq!(s("coverage"), "coverage_violations");
        assert_eq!(s("memory"), "memory_bytes");
        assert_eq!(s("max_alising"), "max_aliasing");
        assert_eq!(s("texel_sise"), "texel_size");
        for n in &names {
            assert_eq!(s(n), *n);
        }
    }

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
}
