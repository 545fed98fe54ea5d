//! Writing results: a small exporter trait, CSV/JSON renderers, and atomic file writes.
//!
//! Every file is rendered to memory first; only when all of them rendered does anything touch
//! the disk, and each file is written to a temporary file in the same directory and renamed
//! over the target. A crash, a full disk or a bad value therefore never leaves a half-written
//! CSV where a CI job will read it, and the previous files stay whole.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::analysis::Analysis;
use crate::error::{ensure_finite, Error, Result};

/// Renders one output file from some data.
pub trait Exporter<T: ?Sized> {
    fn file_name(&self) -> &'static str;
    fn render(&self, data: &T) -> Result<Vec<u8>>;
}

/// Writes `bytes` to `path` atomically: temporary file in the same directory, flush, fsync,
/// rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!(
            ".{}.",
            path.file_name().map(|s| s.to_string_lossy()).unwrap_or_default()
        ))
        .suffix(".tmp")
        .tempfile_in(&dir)
        .map_err(|e| Error::write(path, e))?;
    tmp.write_all(bytes).map_err(|e| Error::write(path, e))?;
    // Temporary files are created private (0600); the result should be an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| Error::write(path, e))?;
    }
    tmp.as_file().sync_all().map_err(|e| Error::write(path, e))?;
    tmp.persist(path).map_err(|e| Error::write(path, e.error))?;
    Ok(())
}

/// Creates `dir` (and parents) with a message that names it.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))
}

/// Renders every exporter, then writes all files atomically into `dir`. Returns the paths.
pub fn export_all<T: ?Sized>(dir: &Path, data: &T, exporters: &[&dyn Exporter<T>]) -> Result<Vec<PathBuf>> {
    let rendered = exporters
        .iter()
        .map(|e| Ok((e.file_name(), e.render(data)?)))
        .collect::<Result<Vec<_>>>()?;
    write_files(dir, &rendered)
}

/// Rendered files: (file name, bytes).
pub type RenderedFiles = Vec<(String, Vec<u8>)>;

/// Writes already-rendered files atomically into `dir`.
pub fn write_files<N: AsRef<str>>(dir: &Path, files: &[(N, Vec<u8>)]) -> Result<Vec<PathBuf>> {
    ensure_dir(dir)?;
    files
        .iter()
        .map(|(name, bytes)| {
            let path = dir.join(name.as_ref());
            write_atomic(&path, bytes)?;
            Ok(path)
        })
        .collect()
}

/// A finite number formatted for CSV/JSON: shortest round-trip representation.
pub fn num(what: &str, v: f64) -> Result<String> {
    Ok(format!("{}", ensure_finite(what, v)?))
}

/// CSV bytes from a header and rows of already formatted fields.
pub fn csv_bytes(header: &[&str], rows: &[Vec<String>]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let wrap = |e: csv::Error| Error::Other(format!("CSV encoding failed: {e}"));
    w.write_record(header).map_err(wrap)?;
    for r in rows {
        w.write_record(r).map_err(wrap)?;
    }
    w.into_inner()
        .map_err(|e| Error::Other(format!("CSV encoding failed: {e}")))
}

/// Recursively refuses NaN/infinity in a JSON value (serde_json would write `null`).
pub fn check_json_finite(what: &str, v: &serde_json::Value) -> Result<()> {
    match v {
        serde_json::Value::Number(n) => {
            if let Some(f) = n.as_f64() {
                ensure_finite(what, f)?;
            }
            Ok(())
        }
        serde_json::Value::Null => Err(Error::NonFinite {
            what: what.to_string(),
            value: f64::NAN,
        }),
        serde_json::Value::Array(a) => a.iter().try_for_each(|x| check_json_finite(what, x)),
        serde_json::Value::Object(o) => o
            .iter()
            .try_for_each(|(k, x)| check_json_finite(&format!("{what}.{k}"), x)),
        _ => Ok(()),
    }
}

/// Pretty JSON with a trailing newline, after checking every number is finite.
pub fn json_bytes(what: &str, v: &serde_json::Value) -> Result<Vec<u8>> {
    check_json_finite(what, v)?;
    let mut out = serde_json::to_vec_pretty(v).map_err(|e| Error::Other(format!("JSON encoding failed: {e}")))?;
    out.push(b'\n');
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// The files `analyze` writes
// ---------------------------------------------------------------------------------------------

pub struct CascadesCsv;
pub struct DensityCsv;
pub struct ShimmerCsv;
pub struct SummaryJson;

pub const CASCADES_COLUMNS: [&str; 20] = [
    "cascade",
    "near",
    "far",
    "radius",
    "width",
    "height",
    "texel_size",
    "centre_x",
    "centre_y",
    "centre_x_texels",
    "centre_y_texels",
    "light_near",
    "light_far",
    "coverage_violations",
    "coverage_worst_texels",
    "min_slack_texels",
    "max_aliasing",
    "min_aliasing",
    "lookup_error_max",
    "lookup_error_rms",
];

impl Exporter<Analysis> for CascadesCsv {
    fn file_name(&self) -> &'static str {
        "cascades.csv"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        let rows = a
            .cascades
            .iter()
            .map(|c| {
                Ok(vec![
                    c.cascade.to_string(),
                    num("near", c.near)?,
                    num("far", c.far)?,
                    num("radius", c.radius)?,
                    num("width", c.width)?,
                    num("height", c.height)?,
                    num("texel_size", c.texel_size)?,
                    num("centre_x", c.centre_x)?,
                    num("centre_y", c.centre_y)?,
                    num("centre_x_texels", c.centre_x_texels)?,
                    num("centre_y_texels", c.centre_y_texels)?,
                    num("light_near", c.light_near)?,
                    num("light_far", c.light_far)?,
                    c.coverage_violations.to_string(),
                    num("coverage_worst_texels", c.coverage_worst_texels)?,
                    num("min_slack_texels", c.min_slack_texels)?,
                    num("max_aliasing", c.max_aliasing)?,
                    num("min_aliasing", c.min_aliasing)?,
                    num("lookup_error_max", c.lookup_error_max)?,
                    num("lookup_error_rms", c.lookup_error_rms)?,
                ])
            })
            .collect::<Result<Vec<_>>>()?;
        csv_bytes(&CASCADES_COLUMNS, &rows)
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

impl Exporter<Analysis> for ShimmerCsv {
    fn file_name(&self) -> &'static str {
        "shimmer.csv"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        let mut rows = Vec::new();
        for path in [a.snapped(), a.unsnapped()].into_iter().flatten() {
            for f in &path.frames {
                rows.push(vec![
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
                ]);
            }
        }
        csv_bytes(
            &[
                "frame",
                "cascade",
                "snap",
                "size_change",
                "phase_drift_rms",
                "phase_drift_max",
                "cell_flips",
            ],
            &rows,
        )
    }
}

/// The JSON document of `summary.json` (also what `--format json` prints).
pub fn summary_value(a: &Analysis) -> serde_json::Value {
    let s = &a.summary;
    let mut v = serde_json::json!({
        "tool": format!("csm-lab {}", env!("CARGO_PKG_VERSION")),
        "config": a.config.path.as_ref().map(|p| p.display().to_string()),
        "name": a.config.name,
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
    let flat = serde_json::to_value(s).expect("plain struct");
    for (k, x) in flat.as_object().expect("object") {
        obj.insert(k.clone(), x.clone());
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
    let path_json = |p: Option<&crate::shimmer::PathResult>| {
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
    obj.insert(
        "shimmer".into(),
        serde_json::json!({
            "frames": a.config.motion.frames,
            "path": a.config.motion.path.name(),
            "snapped": path_json(a.snapped()),
            "unsnapped": path_json(a.unsnapped()),
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

/// The terminal summary of one analysis.
pub fn summary_table(a: &Analysis) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let s = &a.summary;
    let c = &a.config;
    if let Some(p) = &a.preset {
        let _ = writeln!(
            out,
            "{}: preset {}: {} cascades x {}^2, shadow distance {}",
            c.name, p.name, c.shadow.cascades, c.shadow.resolution, c.shadow.max_distance
        );
        let _ = writeln!(out, "  split: {}", p.split_rule);
        let _ = writeln!(out, "  fit: {}; snap: {}", p.fit, p.snap);
        let _ = writeln!(out, "  light depth: {}", p.light_depth_rule);
        for n in &p.notes {
            let _ = writeln!(out, "  note: {n}");
        }
    } else {
        let _ = writeln!(
            out,
            "{}: {} cascades x {}^2, lambda {}, fit {}, snap {}",
            c.name,
            c.shadow.cascades,
            c.shadow.resolution,
            c.shadow.lambda,
            c.shadow.fit,
            if c.shadow.snap { "on" } else { "off" }
        );
    }
    if !s.cascades_needed {
        let _ = writeln!(
            out,
            "no cascades needed: the scene bounds are not visible between near = {} and the shadow distance {}",
            c.camera.near,
            c.shadow_far()
        );
        return out;
    }
    let _ = writeln!(
        out,
        "depth range {:.4} .. {:.4}{}",
        s.z_lo,
        s.z_hi,
        if a.preset.is_some() {
            " (the view depths that read the preset's cascades)"
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
            "{:>7} {:>10.4} {:>10.4} {:>10.4} {:>10.6} {:>11.4} {:>11.4} {:>9}",
            r.cascade, r.near, r.far, r.width, r.texel_size, r.max_aliasing, r.min_aliasing, r.coverage_violations
        );
    }
    let rows: [(&str, String, &str); 9] = [
        (
            "max_aliasing",
            format!("{:.4}", s.max_aliasing),
            "worst texel/pixel ratio (at a cascade's near edge)",
        ),
        ("mean_aliasing", format!("{:.4}", s.mean_aliasing), "mean over depth"),
        (
            "mean_log_aliasing",
            format!("{:.4}", s.mean_log_aliasing),
            "mean over log depth",
        ),
        (
            "undersampled_fraction",
            format!("{:.4}", s.undersampled_fraction),
            "share of depth with aliasing > 1",
        ),
        (
            "shimmer_snapped",
            format!("{:.3e}", s.shimmer_snapped),
            "RMS sub-texel drift per frame, snapped (texels)",
        ),
        (
            "shimmer_unsnapped",
            format!("{:.3e}", s.shimmer_unsnapped),
            "the same without snapping",
        ),
        (
            "size_jitter",
            format!("{:.3e}", s.size_jitter),
            "largest texel-size change between frames",
        ),
        (
            "coverage_violations",
            s.coverage_violations.to_string(),
            "slice corners outside their window",
        ),
        (
            "memory_bytes",
            s.memory_bytes.to_string(),
            "cascades x resolution^2 x 4",
        ),
    ];
    for (k, v, what) in rows {
        let _ = writeln!(out, "  {k:<22} {v:>12}  {what}");
    }
    if c.shadow.precision == crate::precision::Precision::F32 {
        let _ = writeln!(
            out,
            "  precision f32, snap_space {}: shimmer, size jitter and coverage above measure the emulated binary32 pipeline",
            c.shadow.snap_space
        );
        for (k, v, what) in [
            (
                "lookup_error_max",
                s.lookup_error_max,
                "S7: largest |s_f32 - s_exact| lookup error (texels)",
            ),
            ("lookup_error_rms", s.lookup_error_rms, "RMS of S7 (texels)"),
        ] {
            let _ = writeln!(out, "  {k:<22} {:>12}  {what}", format!("{v:.3e}"));
        }
    }
    if let Some(p) = &a.preset {
        let worst = a
            .configured_path()
            .map_or(0.0, |r| r.coverage.worst_texels.iter().cloned().fold(0.0, f64::max));
        for (k, v, what) in [
            (
                "coverage_worst_texels",
                format!("{worst:.4}"),
                "how far the worst corner lies outside its window",
            ),
            (
                "receivers_outside_depth",
                format!("{:.4}", p.receivers_outside_depth),
                "receiver depth outside the light depth range (world units)",
            ),
            (
                "casters_outside_depth",
                format!("{:.4}", p.casters_outside_depth),
                "caster depth lost in front of the light depth range",
            ),
        ] {
            let _ = writeln!(out, "  {k:<22} {v:>12}  {what}");
        }
    }
    out
}
