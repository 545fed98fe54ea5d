//! "Did you mean ...?": the edit distance between two names and the nearest of a list, for
//! every message that rejects an unknown name (metrics, presets).

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
    use crate::check::metric::all_names;

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
