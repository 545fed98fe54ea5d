//! Rules and baselines over sweep rows: one row per configuration, summary metrics only.
//!
//! A row is a key (`lambda`, `cascades`, `resolution`, `fit`) and a map from metric name to
//! value. Only summary-metric rules apply to a row; per-cascade and per-depth rules are
//! reported as not applicable for every row. A configuration passes when none of the rules
//! that apply to it fails.
//!
//! Baselines: two sweep tables are matched by key and compared metric by metric with the
//! same tolerances as a single summary ([`super::baseline`]). Configurations present in only
//! one of the tables are listed, not judged.

use crate::error::IoError;
use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::path::Path;

use super::baseline::{compare, Comparison, Tolerances, Verdict};
use super::evaluate::{evaluate_values, RuleResult, Status};
use super::metric::SummaryMetric;
use super::thresholds::Rule;
use crate::config::{Config, SplitRange};
use crate::error::{BaselineError, Error, Result};

/// The columns that identify a configuration in `sweep.csv`.
pub(crate) const KEY_COLUMNS: [&str; 4] = ["lambda", "cascades", "resolution", "fit"];

/// Which configuration a row measures.
#[derive(Debug, Clone)]
pub struct SweepKey {
    pub lambda: f64,
    pub cascades: u32,
    pub resolution: u32,
    pub fit: String,
    /// `bounds` or `visible` (the `split_range` column, present with scene geometry; a table
    /// without it has every split on the bounds' range).
    pub split_range: SplitRange,
    /// The preset's split knob, when swept (the column named by its config key,
    /// `unreal.cascade_distribution_exponent`).
    pub knob: Option<f64>,
    /// The shadow distance, when swept (the `shadow.max_distance` column).
    pub distance: Option<f64>,
    /// The sun (azimuth, elevation) in degrees, when swept (the `sun_azimuth_deg` and
    /// `sun_elevation_deg` columns): a row per sun angle, each judged on its own, so a rule
    /// must hold at every sun angle.
    pub sun: Option<(f64, f64)>,
    /// The light update rule, when swept (the `shadow.light_update` column: `every:4`, ...).
    pub light_update: Option<String>,
    /// Cached cascades, when swept (the `shadow.update_every` column: `2`, `1/1/2/4`).
    pub update_every: Option<String>,
}

/// The `sweep.csv` column of a swept shadow distance.
pub(crate) const DISTANCE_COLUMN: &str = "shadow.max_distance";

/// The `sweep.csv` columns of a swept sun: azimuth and elevation, degrees.
pub(crate) const SUN_COLUMNS: [&str; 2] = ["sun_azimuth_deg", "sun_elevation_deg"];
/// The `sweep.csv` column of a swept light update rule.
pub(crate) const LIGHT_UPDATE_COLUMN: &str = "shadow.light_update";
/// The `sweep.csv` column of swept cached cascades.
pub(crate) const UPDATE_EVERY_COLUMN: &str = "shadow.update_every";

impl SweepKey {
    /// `lambda=0.75 cascades=4 resolution=2048 fit=sphere` (and ` split_range=visible` when the
    /// splits divide the visible depths).
    pub fn label(&self) -> String {
        let range = match self.split_range {
            SplitRange::Bounds => "",
            SplitRange::Visible => " split_range=visible",
        };
        let mut extra = String::new();
        if let Some(k) = self.knob {
            extra.push_str(&format!(" knob={k}"));
        }
        if let Some(d) = self.distance {
            extra.push_str(&format!(" distance={d}"));
        }
        if let Some((a, e)) = self.sun {
            extra.push_str(&format!(" sun_azimuth={a} sun_elevation={e}"));
        }
        if let Some(u) = &self.light_update {
            extra.push_str(&format!(" light_update={u}"));
        }
        if let Some(u) = &self.update_every {
            extra.push_str(&format!(" update_every={u}"));
        }
        format!(
            "lambda={} cascades={} resolution={} fit={}{range}{extra}",
            self.lambda, self.cascades, self.resolution, self.fit
        )
    }
}

// Keys compare lambda bit-for-bit in total order, so they can key a BTreeMap.
impl Ord for SweepKey {
    fn cmp(&self, other: &Self) -> Ordering {
        self.lambda
            .total_cmp(&other.lambda)
            .then(self.cascades.cmp(&other.cascades))
            .then(self.resolution.cmp(&other.resolution))
            .then_with(|| self.fit.cmp(&other.fit))
            .then(self.split_range.cmp(&other.split_range))
            .then(opt_cmp(self.knob, other.knob))
            .then(opt_cmp(self.distance, other.distance))
            .then(opt_cmp(self.sun.map(|s| s.0), other.sun.map(|s| s.0)))
            .then(opt_cmp(self.sun.map(|s| s.1), other.sun.map(|s| s.1)))
            .then_with(|| self.light_update.cmp(&other.light_update))
            .then_with(|| self.update_every.cmp(&other.update_every))
    }
}

fn opt_cmp(a: Option<f64>, b: Option<f64>) -> Ordering {
    match (a, b) {
        (Some(a), Some(b)) => a.total_cmp(&b),
        (a, b) => a.is_some().cmp(&b.is_some()),
    }
}

impl PartialOrd for SweepKey {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for SweepKey {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for SweepKey {}

/// One configuration's summary values.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    pub key: SweepKey,
    /// Metric name -> value (booleans as 1/0), the measured metrics only. The names are the
    /// registry's own (`&'static`): a 100,000-row table holds no copy of them.
    pub metrics: BTreeMap<&'static str, f64>,
    /// The sweep recommends this row's setting (`sweep.csv`'s `recommended` column; in a sun
    /// sweep every sun angle's row of the setting).
    pub recommended: bool,
}

impl SweepRow {
    /// The values named like summary metrics; other entries are ignored.
    pub fn summary_values(&self) -> BTreeMap<SummaryMetric, f64> {
        self.metrics
            .iter()
            .filter_map(|(k, v)| SummaryMetric::from_name(k).map(|m| (m, *v)))
            .collect()
    }
}

/// The rules judged on one row.
#[derive(Debug, Clone, PartialEq)]
pub struct RowReport {
    pub key: SweepKey,
    pub results: Vec<RuleResult>,
}

impl RowReport {
    pub(crate) fn count(&self, s: Status) -> usize {
        self.results.iter().filter(|r| r.status == s).count()
    }

    /// No applicable rule failed.
    pub fn passed(&self) -> bool {
        self.count(Status::Fail) == 0
    }
}

/// Whether `key` is the configured setting of `config` (as `csm-lab sweep` finds it: the swept
/// knob and distance, when swept, at their configured values; every sun angle and light update
/// rule of it).
pub(crate) fn is_configured(config: &Config, key: &SweepKey) -> bool {
    let c = &config.shadow;
    let knob = crate::presets::axes(config).knob.map(|k| k.value);
    key.knob.is_none_or(|k| Some(k) == knob)
        && key.distance.is_none_or(|d| d == c.max_distance)
        && key.lambda == c.lambda
        && key.cascades as usize == c.cascades
        && key.resolution == c.resolution
        && key.fit == c.fit.name()
        && key.split_range == SplitRange::of(c.fit_depth_to_visible)
}

/// The rows `check --sweep` gates: what the sweep decides, the recommendation's rows and the
/// configured setting's rows (every row with `all_rows`), and the sentence that says so.
pub(crate) fn gated_rows(config: &Config, rows: Vec<SweepRow>, all_rows: bool) -> (Vec<SweepRow>, String) {
    let total = rows.len();
    if all_rows {
        return (
            rows,
            format!("gated: every one of the {total} configurations of the grid (--all-rows)"),
        );
    }
    let rec = rows.iter().filter(|r| r.recommended).count();
    let conf = rows.iter().filter(|r| is_configured(config, &r.key)).count();
    let both = rows
        .iter()
        .filter(|r| r.recommended && is_configured(config, &r.key))
        .count();
    let kept: Vec<SweepRow> = rows
        .into_iter()
        .filter(|r| r.recommended || is_configured(config, &r.key))
        .collect();
    let what = |n: usize, name: &str| match n {
        0 => format!("no {name} (not in the grid)"),
        1 => format!("the {name}"),
        n => format!("the {name} ({n} rows)"),
    };
    let recommendation = if rec == 0 {
        "no recommendation (the sweep recommends nothing)".to_string()
    } else {
        what(rec, "recommendation")
    };
    let same = if both > 0 && both == rec && both == conf {
        ", which is the configured setting".to_string()
    } else {
        format!(" and {}", what(conf, "configured setting"))
    };
    let text = format!(
        "gated: {recommendation}{same}: {} of the grid's {total} configurations (--all-rows gates every one)",
        kept.len()
    );
    (kept, text)
}

/// Judges every rule on every row, rows in the given order, rules in file order.
pub fn evaluate_rows(rules: &[Rule], rows: &[SweepRow]) -> Vec<RowReport> {
    rows.iter()
        .map(|row| RowReport {
            key: row.key.clone(),
            results: rules.iter().map(|r| evaluate_values(r, &row.metrics)).collect(),
        })
        .collect()
}

/// One configuration present in both tables.
#[derive(Debug, Clone, PartialEq)]
pub struct RowComparison {
    pub key: SweepKey,
    pub comparisons: Vec<Comparison>,
}

/// Two sweep tables compared.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepComparison {
    /// In key order.
    pub matched: Vec<RowComparison>,
    /// Configurations the baseline does not have (new), in key order.
    pub only_current: Vec<SweepKey>,
    /// Configurations the current table does not have (dropped), in key order.
    pub only_baseline: Vec<SweepKey>,
    /// Columns of `sweep.csv` the baseline table lacks (an older sweep.csv): not compared,
    /// reported once.
    pub columns_not_in_baseline: Vec<&'static str>,
}

impl SweepComparison {
    pub fn count(&self, v: Verdict) -> usize {
        self.matched
            .iter()
            .flat_map(|r| &r.comparisons)
            .filter(|c| c.verdict == v)
            .count()
    }
}

fn index_rows<'a>(rows: &'a [SweepRow], which: &str) -> Result<BTreeMap<&'a SweepKey, &'a SweepRow>> {
    let mut map = BTreeMap::new();
    for row in rows {
        if map.insert(&row.key, row).is_some() {
            return Err(BaselineError::DuplicateRow {
                which: which.to_string(),
                key: row.key.label(),
            }
            .into());
        }
    }
    Ok(map)
}

/// Matches rows by key and compares their summary metrics. Duplicate keys are an error.
pub fn compare_rows(current: &[SweepRow], baseline: &[SweepRow], tol: &Tolerances) -> Result<SweepComparison> {
    let cur = index_rows(current, "current")?;
    let base = index_rows(baseline, "baseline")?;
    // Exactly the columns sweep.csv has (the registry's row metrics), and of those only the
    // ones the baseline table has: an older table without a column is not 1,000 regressions.
    let in_base = |m: &SummaryMetric| baseline.first().is_none_or(|b| b.metrics.contains_key(m.name()));
    // The optional columns (shadow_ms, the means over the path) only when the current table
    // has them.
    let in_current = |m: &SummaryMetric| current.first().is_some_and(|r| r.metrics.contains_key(m.name()));
    let columns: Vec<SummaryMetric> = SummaryMetric::all()
        .filter(|m| m.def().in_rows && (!crate::metric::optional_row_column(m.name()) || in_current(m)))
        .collect();
    let mut out = SweepComparison {
        matched: Vec::new(),
        only_current: Vec::new(),
        only_baseline: Vec::new(),
        columns_not_in_baseline: columns.iter().filter(|m| !in_base(m)).map(|m| m.name()).collect(),
    };
    let keep = |v: BTreeMap<SummaryMetric, f64>| -> BTreeMap<SummaryMetric, f64> {
        v.into_iter()
            .filter(|(m, _)| columns.contains(m) && in_base(m))
            .collect()
    };
    for (key, row) in &cur {
        match base.get(key) {
            Some(b) => out.matched.push(RowComparison {
                key: (*key).clone(),
                comparisons: compare(&keep(row.summary_values()), &keep(b.summary_values()), tol),
            }),
            None => out.only_current.push((*key).clone()),
        }
    }
    out.only_baseline = base
        .keys()
        .filter(|k| !cur.contains_key(*k))
        .map(|k| (*k).clone())
        .collect();
    Ok(out)
}

/// Parses `sweep.csv` by column name: the key columns are required, every column named like
/// a summary metric is read (booleans as 1/0), other columns are ignored.
pub fn parse_sweep_csv(text: &str, path: &Path) -> Result<Vec<SweepRow>> {
    let data_err = |line: u64, message: String| {
        Error::from(IoError::DataFile {
            path: path.to_path_buf(),
            line: line as usize,
            message,
        })
    };
    let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| data_err(1, format!("not a CSV table: {e}")))?
        .clone();
    let column = |name: &str| headers.iter().position(|h| h.trim() == name);
    let mut key_idx = [0usize; 4];
    for (slot, name) in key_idx.iter_mut().zip(KEY_COLUMNS) {
        *slot = column(name).ok_or_else(|| {
            data_err(
                1,
                format!(
                    "no `{name}` column; a sweep.csv has the key columns {} and the summary metric columns",
                    KEY_COLUMNS.join(", ")
                ),
            )
        })?;
    }
    let range_idx = column(crate::metric::SPLIT_RANGE_COLUMN);
    // A swept engine knob is the column named by its config key (`<engine>.<knob>`).
    let knob_idx = headers.iter().position(|h| {
        let h = h.trim();
        h.contains('.') && h != DISTANCE_COLUMN && h != LIGHT_UPDATE_COLUMN && h != UPDATE_EVERY_COLUMN
    });
    let distance_idx = column(DISTANCE_COLUMN);
    let sun_idx = column(SUN_COLUMNS[0]).zip(column(SUN_COLUMNS[1]));
    let light_update_idx = column(LIGHT_UPDATE_COLUMN);
    let update_every_idx = column(UPDATE_EVERY_COLUMN);
    let recommended_idx = column("recommended");
    let metric_cols: Vec<(usize, SummaryMetric)> = headers
        .iter()
        .enumerate()
        .filter_map(|(i, h)| SummaryMetric::from_name(h.trim()).map(|m| (i, m)))
        .collect();
    if metric_cols.is_empty() {
        return Err(data_err(
            1,
            "no column is named like a summary metric (max_aliasing, ...)".into(),
        ));
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            data_err(line, format!("malformed CSV row: {e}"))
        })?;
        let line = record.position().map_or(0, |p| p.line());
        let field = |i: usize| record.get(i).unwrap_or("").trim();
        let number = |i: usize, what: &str| -> Result<f64> {
            let s = field(i);
            let v = match s {
                "true" => 1.0,
                "false" => 0.0,
                _ => s
                    .parse::<f64>()
                    .map_err(|_| data_err(line, format!("`{what}` = {s:?} is not a number")))?,
            };
            if v.is_finite() {
                Ok(v)
            } else {
                Err(data_err(line, format!("`{what}` = {s:?} is not a finite number")))
            }
        };
        let int = |i: usize, what: &str| -> Result<u32> {
            let s = field(i);
            s.parse::<u32>()
                .map_err(|_| data_err(line, format!("`{what}` = {s:?} is not a whole number")))
        };
        let key = SweepKey {
            knob: knob_idx.map(|i| number(i, "knob")).transpose()?,
            distance: distance_idx.map(|i| number(i, DISTANCE_COLUMN)).transpose()?,
            sun: match sun_idx {
                Some((a, e)) => Some((number(a, SUN_COLUMNS[0])?, number(e, SUN_COLUMNS[1])?)),
                None => None,
            },
            light_update: light_update_idx.map(|i| field(i).to_string()),
            update_every: update_every_idx.map(|i| field(i).to_string()),
            lambda: number(key_idx[0], "lambda")?,
            cascades: int(key_idx[1], "cascades")?,
            resolution: int(key_idx[2], "resolution")?,
            fit: field(key_idx[3]).to_string(),
            split_range: match range_idx.map(field) {
                None | Some("bounds") => SplitRange::Bounds,
                Some("visible") => SplitRange::Visible,
                Some(other) => {
                    return Err(data_err(
                        line,
                        format!("`split_range` = {other:?} is not a split range: bounds or visible"),
                    ))
                }
            },
        };
        let metrics = metric_cols
            .iter()
            .map(|&(i, m)| Ok((m.name(), number(i, m.name())?)))
            .collect::<Result<BTreeMap<_, _>>>()?;
        let recommended = recommended_idx.is_some_and(|i| field(i) == "true");
        rows.push(SweepRow {
            key,
            metrics,
            recommended,
        });
    }
    Ok(rows)
}

/// Reads a `sweep.csv`.
pub(crate) fn read_sweep_csv(path: &Path) -> Result<Vec<SweepRow>> {
    let text = crate::config::read_bounded(path, 256 << 20, "a sweep CSV")?;
    parse_sweep_csv(&text, path)
}

/// The rows of a `sweep.csv` written for `config` (`check --sweep --sweep-csv FILE`, e.g. a
/// merged sharded sweep), read by column name, refused unless its configurations are exactly
/// the config's grid in grid order, so a table of another config or grid is never judged.
pub(crate) fn sweep_rows_from_csv(config: &Config, path: &Path) -> Result<Vec<SweepRow>> {
    let rows = read_sweep_csv(path)?;
    let grid = crate::commands::sweep::grid::Grid::resolve(config, &crate::config::sweep_spec::SweepAxes::default())?;
    let settings = grid.settings();
    let mismatch = |message: String| {
        Error::from(BaselineError::Mismatch {
            path: path.to_path_buf(),
            message: format!(
                "{message}; --sweep-csv takes the sweep.csv of this config's [sweep] grid \
                 (`csm-lab sweep`, or `csm-lab merge` of its shards)"
            ),
        })
    };
    if rows.len() != settings.len() {
        return Err(mismatch(format!(
            "it has {} configurations and this config's grid has {}",
            rows.len(),
            settings.len()
        )));
    }
    for (i, (row, s)) in rows.iter().zip(&settings).enumerate() {
        let k = &row.key;
        if k.lambda != s.lambda
            || k.cascades as usize != s.cascades
            || k.resolution != s.resolution
            || k.fit != s.fit.name()
            || k.sun != s.sun.map(|x| (x.azimuth_deg, x.elevation_deg))
        {
            return Err(mismatch(format!(
                "row {} is {} where this config's grid has {}",
                i + 1,
                k.label(),
                s.label()
            )));
        }
    }
    Ok(rows)
}

/// The rows `--sweep` judges: every configuration of the config's sweep grid (its `[sweep]`
/// table, or the default grid), run by the sweep runner exactly as `csm-lab sweep` runs it,
/// so each row equals the corresponding line of `sweep.csv`.
pub fn sweep_rows_for(config: &Config) -> Result<Vec<SweepRow>> {
    let grid = crate::commands::sweep::grid::Grid::resolve(config, &crate::config::sweep_spec::SweepAxes::default())?;
    let rows = crate::commands::sweep::run::run(config, &grid, None, &|| {})?;
    // The recommendation, as `csm-lab sweep` makes it (its `recommended` column).
    let result = crate::commands::sweep::SweepResult::new(config.clone(), grid, rows, String::new())?;
    let recommended: Vec<bool> = match (&result.sun, &result.recommendation) {
        (_, None) => Vec::new(),
        (None, Some(rec)) => (0..result.rows.len()).map(|i| i == rec.index).collect(),
        (Some(sun), Some(rec)) => sun.setting_of.iter().map(|&j| j == rec.index).collect(),
    };
    let all = result.sun.as_ref().map_or(result.rows.clone(), |s| s.all.clone());
    Ok(all
        .into_iter()
        .enumerate()
        .map(|(i, r)| SweepRow {
            recommended: recommended.get(i).copied().unwrap_or(false),
            key: SweepKey {
                lambda: r.setting.lambda,
                cascades: r.setting.cascades as u32,
                resolution: r.setting.resolution,
                fit: r.setting.fit.name().to_string(),
                split_range: r.setting.split_range,
                knob: r.setting.knob,
                distance: r.setting.distance,
                sun: r.setting.sun.map(|x| (x.azimuth_deg, x.elevation_deg)),
                light_update: r.setting.light_update.map(crate::config::light_update_label),
                update_every: r.setting.update_every.map(|u| u.label()),
            },
            // Only what was measured: an unmeasured metric has no value (never 0).
            metrics: SummaryMetric::all()
                .filter(|m| m.measured(&r.summary))
                .map(|m| (m.name(), m.value(&r.summary)))
                .collect(),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_order_and_compare_by_value() {
        let k = |lambda: f64, fit: &str| SweepKey {
            lambda,
            cascades: 4,
            resolution: 2048,
            fit: fit.into(),
            split_range: SplitRange::Bounds,
            knob: None,
            distance: None,
            sun: None,
            light_update: None,
            update_every: None,
        };
        assert_eq!(k(0.5, "sphere"), k(0.5, "sphere"));
        assert!(k(0.25, "sphere") < k(0.5, "aabb"));
        assert!(k(0.5, "aabb") < k(0.5, "sphere"));
        assert_eq!(
            k(0.75, "sphere").label(),
            "lambda=0.75 cascades=4 resolution=2048 fit=sphere"
        );
    }

    #[test]
    fn csv_errors_name_the_line_and_the_column() {
        let p = Path::new("s.csv");
        let e = parse_sweep_csv("lambda,cascades,fit,max_aliasing\n0.5,4,sphere,2\n", p).unwrap_err();
        assert!(e.to_string().contains("`resolution`"), "{e}");
        let e = parse_sweep_csv(
            "lambda,cascades,resolution,fit,max_aliasing\n0.5,4,2048,sphere,2\n0.5,4,2048,aabb,x\n",
            p,
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("s.csv:3:") && e.to_string().contains("max_aliasing"),
            "{e}"
        );
        let e = parse_sweep_csv(
            "lambda,cascades,resolution,fit,max_aliasing\n0.5,4.5,2048,sphere,2\n",
            p,
        )
        .unwrap_err();
        assert!(e.to_string().contains("cascades"), "{e}");
        let e = parse_sweep_csv(
            "lambda,cascades,resolution,fit,max_aliasing\n0.5,4,2048,sphere,NaN\n",
            p,
        )
        .unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
        let e = parse_sweep_csv("lambda,cascades,resolution,fit,snap\n0.5,4,2048,sphere,true\n", p).unwrap_err();
        assert!(e.to_string().contains("summary metric"), "{e}");
    }
}
