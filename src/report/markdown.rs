//! Markdown pieces shared by the `.md` reports (`report.md` of `sweep`, `compare.md`).

/// A Markdown table of already formatted cells: columns listed in `left` are left-aligned,
/// the others right-aligned. A `|` inside a cell is escaped.
pub(crate) fn table<S: AsRef<str>>(header: &[&str], rows: &[Vec<S>], left: &[usize]) -> String {
    let cell = |s: &str| s.replace('|', "\\|");
    let line = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
    let mut m = line(header.iter().map(|h| cell(h)).collect());
    let align: Vec<&str> = (0..header.len())
        .map(|j| if left.contains(&j) { "---" } else { "---:" })
        .collect();
    m.push_str(&format!("|{}|\n", align.join("|")));
    for r in rows {
        m.push_str(&line(r.iter().map(|v| cell(v.as_ref())).collect()));
    }
    m
}

#[cfg(test)]
mod tests {
    #[test]
    fn cells_are_aligned_and_escaped() {
        let t = super::table(&["a", "b"], &[vec!["x|y", "1"]], &[0]);
        assert_eq!(t, "| a | b |\n|---|---:|\n| x\\|y | 1 |\n");
    }
}
