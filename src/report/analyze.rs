//! What `analyze` writes besides its figures: `cascades.csv`, `density.csv`, `shimmer.csv`,
//! `summary.json`, and the summary printed on stdout.

use std::fmt::Write as _;

use crate::analysis::Analysis;
use crate::error::Result;
use crate::figures;
use crate::metric;
use crate::output::{csv_bytes, json_bytes, num, short_number, Exporter};

/// The files `analyze` writes, in order: its tables, its summary and its figures.
pub(crate) fn exporters() -> Vec<&'static dyn Exporter<Analysis>> {
    vec![
        &CascadesCsv,
        &DensityCsv,
        &ShimmerCsv,
        &SummaryJson,
        &figures::analyze::DensitySvg,
        &figures::analyze::ShimmerSvg,
        &figures::analyze::CascadesSvg,
    ]
}

/// The files `analyze` writes for one analysis: [`exporters`], plus the two camera-view
/// images when the scene has geometry.
pub(crate) fn exporters_for(a: &Analysis) -> Vec<&'static dyn Exporter<Analysis>> {
    let mut v = exporters();
    if a.config.geometry.is_some() {
        v.push(&figures::screen::ScreenAliasingPng);
        v.push(&figures::screen::ScreenCascadesPng);
        v.push(&figures::plan::PlanPng);
    }
    if !a.summary.views.is_empty() {
        v.push(&super::views::ViewsCsv);
    }
    if a.summary.views.len() >= 2 {
        v.push(&super::views::ViewsPng);
    }
    if a.ground_truth.is_some() {
        v.push(&super::ground_truth::BiasCsv);
        v.push(&super::ground_truth::ShadowPng);
        v.push(&super::ground_truth::FlickerPng);
        v.push(&super::ground_truth::ShadowApng);
    }
    v
}

pub struct CascadesCsv;
pub struct DensityCsv;
pub struct ShimmerCsv;
pub struct SummaryJson;

impl Exporter<Analysis> for CascadesCsv {
    fn file_name(&self) -> &'static str {
        "cascades.csv"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        let rows = a
            .cascades
            .iter()
            .map(metric::cascade_fields)
            .collect::<Result<Vec<_>>>()?;
        csv_bytes(
            &metric::cascade_columns(
                a.config.geometry.is_some(),
                a.config.motion.light.moves(),
                a.ground_truth.is_some(),
                a.summary.cache.is_some(),
                a.summary.cost.shadow_ms.is_some(),
                a.summary.cost.means.is_some(),
            ),
            &rows,
        )
    }
}

impl Exporter<Analysis> for DensityCsv {
    fn file_name(&self) -> &'static str {
        "density.csv"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        let rows = a
            .density
            .iter()
            .map(|d| {
                Ok(vec![
                    num("depth", d.depth)?,
                    d.cascade.to_string(),
                    num("texel_size", d.texel_size)?,
                    num("pixel_size", d.pixel_size)?,
                    num("texels_per_pixel", d.texels_per_pixel)?,
                    num("aliasing", d.aliasing)?,
                ])
            })
            .collect::<Result<Vec<_>>>()?;
        csv_bytes(
            &[
                "depth",
                "cascade",
                "texel_size",
                "pixel_size",
                "texels_per_pixel",
                "aliasing",
            ],
            &rows,
        )
    }
}

/// `shimmer.csv`'s columns.
const SHIMMER_COLUMNS: [&str; 8] = [
    "frame",
    "cascade",
    "snap",
    "size_change",
    "phase_drift_rms",
    "phase_drift_max",
    "cell_flips",
    "path",
];

/// One row of `shimmer.csv`: path `name`'s frame row `f`.
fn shimmer_row(name: &str, f: &csm_core::shimmer::FrameShimmer) -> Result<Vec<String>> {
    Ok(vec![
        f.frame.to_string(),
        f.cascade.to_string(),
        f.snapped.to_string(),
        num("size_change", f.size_change)?,
        num("phase_drift_rms", f.phase_drift_rms)?,
        num("phase_drift_max", f.phase_drift_max)?,
        match f.cell_flips {
            Some(v) => num("cell_flips", v)?,
            None => String::new(),
        },
        name.to_string(),
    ])
}

impl Exporter<Analysis> for ShimmerCsv {
    fn file_name(&self) -> &'static str {
        "shimmer.csv"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        let mut rows = Vec::new();
        let first = (a.config.motion.path.name(), a.snapped(), a.unsnapped());
        let extra = a
            .measured()
            .map(|m| {
                m.extra
                    .iter()
                    .map(|e| (e.name, Some(&e.snapped), Some(&e.unsnapped)))
                    .collect::<Vec<_>>()
            })
            .unwrap_or_default();
        for (name, path) in std::iter::once(first)
            .chain(extra)
            .flat_map(|(n, s, u)| [(n, s), (n, u)])
            .filter_map(|(n, p)| p.map(|p| (n, p)))
        {
            for f in &path.frames {
                rows.push(shimmer_row(name, f)?);
            }
        }
        csv_bytes(&SHIMMER_COLUMNS, &rows)
    }
}

/// `shimmer.csv` with every frame's rows (`analyze --all-frames`), written as the path is
/// walked ([`crate::analysis::each_frame_row`]): a path of any length in the memory of one
/// chunk of frames. Without the flag, paths longer than 1,000 frames keep every k-th frame.
pub(crate) struct FullShimmerCsv<'a>(pub &'a crate::config::Config);

impl crate::output::StreamedFile for FullShimmerCsv<'_> {
    fn file_name(&self) -> &str {
        "shimmer.csv"
    }

    fn write_to(&self, out: &mut dyn std::io::Write) -> Result<()> {
        let mut w = csv::Writer::from_writer(out);
        let wrap = |e: csv::Error| crate::output::encode_error("CSV", e);
        w.write_record(SHIMMER_COLUMNS).map_err(wrap)?;
        crate::analysis::each_frame_row(self.0, &crate::analysis::AnalysisOptions::full(), &mut |name, f| {
            w.write_record(shimmer_row(name, f)?).map_err(wrap)
        })?;
        w.flush().map_err(|e| crate::output::encode_error("CSV", e))
    }
}

/// The JSON document of `summary.json` (also what `--format json` prints).
pub fn summary_value(a: &Analysis) -> serde_json::Value {
    let s = &a.summary;
    let mut v = serde_json::json!({
        "tool": format!("csm-lab {}", env!("CARGO_PKG_VERSION")),
        "config": a.config.path.as_ref().map(|p| p.display().to_string()),
        "name": a.config.name,
        "scene_hash": a.config.scene_hash(),
        "inputs": a.config.echo(),
        "cascades_needed": s.cascades_needed,
    });
    let obj = v.as_object_mut().expect("object");
    if obj.get("config").is_some_and(|c| c.is_null()) {
        obj.remove("config");
    }
    if let Some(p) = &a.preset {
        obj.insert("preset".into(), serde_json::to_value(p).expect("plain struct"));
    }
    for (k, x) in metric::summary_json(s) {
        obj.insert(k.into(), x);
    }
    let objective = crate::commands::sweep::rank::default_objective(&a.config);
    if let Some(views) = super::views::json(s, objective) {
        obj.insert("views".into(), views);
    }
    if let Some(judged) = super::views::truth_json(s) {
        obj.insert("ground_truth_views".into(), judged);
    }
    if let Some(g) = &a.ground_truth {
        obj.insert("bias_source".into(), g.bias_source.name().into());
        obj.insert("pcf_filter".into(), g.filter.name().into());
    }
    if !s.cascades_needed {
        obj.insert(
            "message".into(),
            "no cascades needed: the scene bounds are not visible between the near plane and the shadow distance"
                .into(),
        );
        obj.insert("splits".into(), serde_json::json!([]));
        obj.insert("cascades".into(), serde_json::json!([]));
        return v;
    }
    let rig = a.rig().expect("cascades needed");
    let agg = a.aggregates().expect("cascades needed");
    obj.insert("splits".into(), serde_json::json!(rig.splits));
    obj.insert("split_jumps".into(), serde_json::json!(agg.split_jumps));
    obj.insert(
        "cascades".into(),
        serde_json::to_value(&a.cascades).expect("plain struct"),
    );
    let path_json = |p: Option<&csm_core::shimmer::PathResult>| {
        p.map(|p| {
            serde_json::json!({
                "rms": p.stats.rms,
                "max": p.stats.max,
                "size_jitter": p.stats.size_jitter,
                "cell_flip_rate": p.stats.cell_flip_rate,
                "coverage_violations": p.coverage.total(),
                "coverage_worst_texels": p.coverage.worst_texels.iter().cloned().fold(0.0, f64::max),
                "min_slack_texels": p.coverage.min_slack_texels.iter().cloned().fold(f64::INFINITY, f64::min),
            })
        })
    };
    // Per motion path (the flat `shimmer*` keys take the worst of them).
    let mut paths = vec![serde_json::json!({
        "path": a.config.motion.path.name(),
        "snapped": path_json(a.snapped()),
        "unsnapped": path_json(a.unsnapped()),
    })];
    for e in a.measured().map(|m| m.extra.as_slice()).unwrap_or_default() {
        paths.push(serde_json::json!({
            "path": e.name,
            "snapped": path_json(Some(&e.snapped)),
            "unsnapped": path_json(Some(&e.unsnapped)),
        }));
    }
    obj.insert(
        "shimmer_paths".into(),
        serde_json::json!({
            "frames": a.config.motion.frames,
            "paths": paths,
        }),
    );
    obj.insert(
        "light_basis_vertical_fallback".into(),
        rig.light.vertical_fallback.into(),
    );
    v
}

impl Exporter<Analysis> for SummaryJson {
    fn file_name(&self) -> &'static str {
        "summary.json"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        json_bytes("summary", &summary_value(a))
    }
}

/// `analyze`'s per-cascade table of cached cascades: what each cascade's cadence saves (its
/// share of frames rendered) and costs (stale frames with a coverage hole, the growth that
/// closes them, the drift at its updates).
fn cache_table(a: &Analysis, every: &crate::config::UpdateEvery) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "cached cascades (update_every {}, {} snapping, over the motion paths):",
        every.label(),
        if a.config.shadow.snap { "with" } else { "without" }
    );
    let _ = writeln!(
        out,
        "{:>7} {:>7} {:>9} {:>11} {:>9} {:>14} {:>13} {:>12}",
        "cascade", "every", "renders", "stale holes", "share", "margin texels", "margin world", "update drift"
    );
    for r in &a.cascades {
        let Some(x) = &r.cache else { continue };
        let _ = writeln!(
            out,
            "{:>7} {:>7} {:>9} {:>11} {:>9} {:>14} {:>13} {:>12}",
            r.cascade,
            x.update_every,
            short_number(x.update_rate),
            x.figures.stale_coverage_violations,
            short_number(x.figures.stale_coverage_fraction),
            short_number(x.figures.stale_margin),
            short_number(x.figures.stale_margin_world),
            short_number(x.figures.update_drift)
        );
    }
    if let Some(s) = &a.summary.cache {
        let _ = writeln!(
            out,
            "  stale_coverage_violations {} (frames x cascades with a hole); worst cascade's share {}",
            s.figures.stale_coverage_violations,
            short_number(s.figures.stale_coverage_fraction)
        );
    }
    out
}

/// The terminal summary of one analysis.
pub(crate) fn summary_table(a: &Analysis) -> String {
    let mut out = String::new();
    let s = &a.summary;
    let c = &a.config;
    if let Some(p) = &a.preset {
        let _ = writeln!(
            out,
            "{}: preset {}: {} x {}^2, shadow distance {}",
            c.name,
            p.name,
            crate::output::count(c.shadow.cascades as u64, "cascade"),
            c.shadow.resolution,
            c.shadow.max_distance
        );
        let _ = writeln!(out, "  split: {}", p.split_rule);
        let _ = writeln!(out, "  fit: {}; snap: {}", p.fit, p.snap);
        let _ = writeln!(out, "  light depth: {}", p.light_depth_rule);
        for n in &p.notes {
            let _ = writeln!(out, "  note: {n}");
        }
    } else {
        // Explicit split fractions replace λ.
        let split = match &c.shadow.splits {
            Some(f) => format!(
                "split fractions [{}]",
                f.as_slice()
                    .iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None => format!("lambda {}", c.shadow.lambda),
        };
        let _ = writeln!(
            out,
            "{}: {} x {}^2, {split}, fit {}, snap {}",
            c.name,
            crate::output::count(c.shadow.cascades as u64, "cascade"),
            c.shadow.resolution,
            c.shadow.fit,
            if c.shadow.snap { "on" } else { "off" }
        );
    }
    if !s.cascades_needed {
        let _ = writeln!(
            out,
            "no cascades needed: the scene {} not visible between near = {} and the shadow distance {}",
            if c.shadow.fit_depth_to_visible {
                "geometry is"
            } else {
                "bounds are"
            },
            c.camera.near,
            c.shadow_far()
        );
        return out;
    }
    let _ = writeln!(
        out,
        "depth range {} .. {}{}",
        short_number(s.z_lo),
        short_number(s.z_hi),
        if a.preset.is_some() {
            " (the view depths that read the preset's cascades)"
        } else if c.shadow.fit_depth_to_visible {
            " (fitted to the visible geometry)"
        } else if c.shadow.fit_depth_to_scene {
            " (clipped to the scene bounds)"
        } else {
            ""
        }
    );
    let _ = writeln!(
        out,
        "{:>7} {:>10} {:>10} {:>10} {:>10} {:>11} {:>11} {:>9}",
        "cascade", "near", "far", "width", "texel", "max alias", "min alias", "coverage"
    );
    for r in &a.cascades {
        let _ = writeln!(
            out,
            "{:>7} {:>10} {:>10} {:>10} {:>10} {:>11} {:>11} {:>9}",
            r.cascade,
            short_number(r.near),
            short_number(r.far),
            short_number(r.width),
            short_number(r.texel_size),
            short_number(r.max_aliasing),
            short_number(r.min_aliasing),
            r.coverage_violations
        );
    }
    if let Some(every) = a.summary.cache.and(c.shadow.update_every.as_ref()) {
        out.push_str(&cache_table(a, every));
    }
    let f32_block = c.shadow.precision == csm_core::scene::Precision::F32;
    let screen_line = |k: &str| metric::SummaryMetric::named(k).def().screen;
    for (k, v, what) in metric::summary_lines(s, false) {
        if !screen_line(k) {
            let _ = writeln!(out, "  {k:<22} {v:>12}  {what}");
        }
    }
    if let Some(st) = &s.screen {
        let _ = writeln!(out, "{}", screen_heading(a, st));
        for (k, v, what) in metric::summary_lines(s, false) {
            if screen_line(k) {
                let _ = writeln!(out, "  {k:<29} {v:>12}  {what}");
            }
        }
        let objective = crate::commands::sweep::rank::default_objective(c);
        if let Some(line) = super::views::worst_line(s, objective) {
            let _ = writeln!(out, "  {line} (each view's own metrics: views.csv)");
        }
    }
    out.push_str(&cost_table(a));
    if let Some(line) = super::views::truth_line(s) {
        let _ = writeln!(out, "{line}");
    }
    if let Some(g) = &a.ground_truth {
        out.push_str(&super::ground_truth::recommendation(a, g));
    }
    if f32_block {
        let _ = writeln!(
            out,
            "  precision f32, snap_space {}: shimmer, size jitter and coverage above measure the emulated binary32 pipeline",
            c.shadow.snap_space
        );
        for (k, v, what) in metric::summary_lines(s, true) {
            let _ = writeln!(out, "  {k:<22} {v:>12}  {what}");
        }
    }
    if let Some(p) = &a.preset {
        let worst = a
            .configured_path()
            .map_or(0.0, |r| r.coverage.worst_texels.iter().cloned().fold(0.0, f64::max));
        for (k, v, what) in [
            (
                "coverage_worst_texels",
                short_number(worst),
                "how far the worst corner lies outside its window",
            ),
            (
                "receivers_outside_depth",
                short_number(p.receivers_outside_depth),
                "receiver depth outside the light depth range (world units)",
            ),
            (
                "casters_outside_depth",
                short_number(p.casters_outside_depth),
                "caster depth lost in front of the light depth range",
            ),
        ] {
            let _ = writeln!(out, "  {k:<22} {v:>12}  {what}");
        }
    }
    out
}

/// The cost block of `analyze`'s stdout: per cascade and in total, the draw calls, triangles
/// (all, and inside the caster volume), fragments, cleared texels, `cost_index` and, when
/// calibrated, `shadow_ms` (docs/cost.md).
fn cost_table(a: &Analysis) -> String {
    let mut out = String::new();
    let s = &a.summary.cost;
    let ms = s.shadow_ms.is_some();
    let culled = if a.config.cost.cull == crate::config::CostCull::Receivers {
        ", casters culled by receivers"
    } else {
        ""
    };
    let Some(total) = s.counts else {
        let _ = writeln!(
            out,
            "cost (frame 0): {} texels cleared, {} bytes written per update; draws, triangles and fragments {}",
            s.texels_cleared,
            s.bytes_written,
            if a.config.geometry.is_some() {
                "not counted (cost.counts = false)"
            } else {
                "need scene geometry"
            }
        );
        return out;
    };
    let _ = writeln!(out, "cost (frame 0{culled}; docs/cost.md):");
    let _ = write!(
        out,
        "{:>7} {:>7} {:>10} {:>10} {:>12} {:>12} {:>10}",
        "cascade", "draws", "triangles", "inside", "fragments", "cleared", "cost_index"
    );
    let _ = writeln!(
        out,
        "{}",
        if ms {
            format!(" {:>10}", "shadow_ms")
        } else {
            String::new()
        }
    );
    let row = |out: &mut String,
               name: String,
               c: &csm_core::cost::CostCounts,
               cleared: u64,
               index: Option<f64>,
               t: Option<f64>| {
        let _ = write!(
            out,
            "{:>7} {:>7} {:>10} {:>10} {:>12} {:>12} {:>10}",
            name,
            c.caster_objects,
            c.caster_triangles,
            c.caster_triangles_inside,
            short_number(c.raster_fragments),
            cleared,
            index.map_or("n/a".to_string(), short_number)
        );
        let _ = writeln!(
            out,
            "{}",
            t.map_or(String::new(), |t| format!(" {:>10}", short_number(t)))
        );
    };
    for r in &a.cascades {
        if let Some(c) = &r.cost.counts {
            row(
                &mut out,
                r.cascade.to_string(),
                c,
                r.cost.texels_cleared,
                r.cost.cost_index,
                r.cost.shadow_ms,
            );
        }
    }
    row(
        &mut out,
        "total".to_string(),
        &total,
        s.texels_cleared,
        s.cost_index,
        s.shadow_ms,
    );
    if let Some(total) = &s.means {
        let held = if a.summary.cache.is_some() {
            "; a held cascade renders nothing in its stale frames"
        } else {
            ""
        };
        let _ = writeln!(out, "cost per frame, mean over the camera path{held}:");
        let _ = writeln!(
            out,
            "{:>7} {:>7} {:>10} {:>10} {:>12} {:>12} {:>10}{}",
            "cascade",
            "draws",
            "triangles",
            "inside",
            "fragments",
            "cleared",
            "cost_index",
            if ms {
                format!(" {:>10}", "shadow_ms")
            } else {
                String::new()
            }
        );
        let mean_row = |out: &mut String, name: String, m: &crate::analysis::cost::CostMeans| {
            let _ = writeln!(
                out,
                "{:>7} {:>7} {:>10} {:>10} {:>12} {:>12} {:>10}{}",
                name,
                short_number(m.caster_objects_mean),
                short_number(m.caster_triangles_mean),
                short_number(m.caster_triangles_inside_mean),
                short_number(m.raster_fragments_mean),
                short_number(m.texels_cleared_mean),
                m.cost_index_mean.map_or("n/a".to_string(), short_number),
                m.shadow_ms_mean
                    .map_or(String::new(), |t| format!(" {:>10}", short_number(t)))
            );
        };
        for r in &a.cascades {
            if let Some(m) = &r.cost.means {
                mean_row(&mut out, r.cascade.to_string(), m);
            }
        }
        mean_row(&mut out, "total".to_string(), total);
    }
    out
}

/// The non-finite numbers in an analysis's summary document (a non-finite number becomes
/// `null` there, so nulls count too) and the files of `analyze` that refuse to render (they
/// refuse non-finite values): what `stress` checks of every case.
pub(crate) fn output_problems(a: &Analysis) -> (usize, Vec<String>) {
    fn walk(v: &serde_json::Value) -> usize {
        match v {
            serde_json::Value::Null => 1,
            serde_json::Value::Number(n) => n.as_f64().map_or(0, |x| usize::from(!x.is_finite())),
            serde_json::Value::Array(a) => a.iter().map(walk).sum(),
            serde_json::Value::Object(o) => o.values().map(walk).sum(),
            _ => 0,
        }
    }
    let exporters: [&dyn Exporter<Analysis>; 4] = [&CascadesCsv, &DensityCsv, &ShimmerCsv, &SummaryJson];
    let errors = exporters
        .iter()
        .filter_map(|e| e.render(a).err().map(|err| format!("{}: {err}", e.file_name())))
        .collect();
    (walk(&summary_value(a)), errors)
}

/// The heading of the screen block: what was sampled and the visible depths, or why the
/// block is all zero.
fn screen_heading(a: &Analysis, st: &csm_core::screen::ScreenStats) -> String {
    let c = &a.config;
    let view = c.setup().view();
    let (cols, rows) = view.map_or((0, 0), |v| v.grid());
    if st.visible_z_hi <= 0.0 {
        return format!(
            "screen ({cols} x {rows} sampled pixels of {} x {}): the camera sees no scene geometry \
             within the shadow distance; every screen metric is 0",
            c.screen.width, c.screen.height
        );
    }
    format!(
        "screen ({cols} x {rows} sampled pixels of {} x {}; visible geometry at depth {} .. {}{}):",
        c.screen.width,
        c.screen.height,
        short_number(st.visible_z_lo),
        short_number(st.visible_z_hi),
        if c.shadow.fit_depth_to_visible {
            ", splits fitted to it"
        } else {
            ""
        }
    )
}
