//! Definitions shown under the reports' tables: every metric column says what it measures, in
//! the words of the metric registry ([`crate::metric`]), so the reports, `check` and the docs
//! share one text.

use crate::metric::SummaryMetric;

/// The definition of summary metric `name` for a column labelled `label`: (label, text).
/// A help text that reads "the same …" (a variant of the metric before it) is completed with
/// the text of the metric it varies.
pub(crate) fn metric(label: &str, name: &str) -> (String, String) {
    let m = SummaryMetric::named(name);
    let unit = m.def().unit;
    let mut text = m.description().to_string();
    if let Some(rest) = text.strip_prefix("the same") {
        let base = if name.starts_with("shimmer") { "shimmer" } else { name };
        let base = SummaryMetric::named(base).description();
        // The variant replaces the base's snap mode by its own.
        const CONFIGURED: &str = " with the configured snapping (`shadow.snap`)";
        text = if base.contains(CONFIGURED) {
            format!("{},{rest}", base.replacen(CONFIGURED, "", 1))
        } else {
            format!("{base};{rest}")
        };
    }
    let unit = if unit.is_empty() || unit == "count" || text.contains(unit) {
        String::new()
    } else {
        format!(", in {unit}")
    };
    (
        label.to_string(),
        format!("`{name}`: {text}{unit}; {}.", m.direction().describe()),
    )
}

/// A definition of a column that is not a registry metric (a setting, a derived column).
pub(crate) fn other(label: &str, text: &str) -> (String, String) {
    (label.to_string(), text.to_string())
}

/// The memory column, shown in MiB.
pub(crate) fn memory(label: &str) -> (String, String) {
    let (l, t) = metric(label, "memory_bytes");
    (l, format!("{t} Shown in MiB (1 MiB = 1,048,576 bytes)."))
}

/// The settings columns of the sweep tables.
pub(crate) fn settings(lambda: bool, fit: bool) -> Vec<(String, String)> {
    let mut v = vec![
        other("cascades", "number of shadow maps the view depth range is split into"),
        other("resolution", "side of each square shadow map, in texels"),
    ];
    if lambda {
        v.push(other(
            "λ",
            "split blend of the practical split scheme: 0 is uniform, 1 is logarithmic",
        ));
    }
    if fit {
        v.push(other(
            "fit",
            "how a cascade's window encloses its slice: sphere (size fixed under rotation) or aabb (tight box)",
        ));
    }
    v
}

/// The definitions as Markdown: one bullet per column.
pub(crate) fn markdown(defs: &[(String, String)]) -> String {
    let mut m = String::new();
    for (k, v) in defs {
        m.push_str(&format!("- *{k}*: {v}\n"));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn definitions_come_from_the_registry() {
        let (l, t) = metric("mean aliasing", "mean_aliasing");
        assert_eq!(l, "mean aliasing");
        assert!(t.contains(SummaryMetric::named("mean_aliasing").description()), "{t}");
        assert!(t.contains("texel / pixel") && t.contains("higher is worse"), "{t}");
        // A variant names what it varies.
        let (_, t) = metric("shimmer snapped", "shimmer_snapped");
        assert!(t.starts_with("`shimmer_snapped`: RMS sub-texel drift"), "{t}");
        assert!(t.contains("with snapping, whatever the config says"), "{t}");
    }
}
