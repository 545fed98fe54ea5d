//! Writing results: a small exporter trait, CSV/JSON renderers, and atomic file writes.
//!
//! Every file is rendered to memory first; only when all of them rendered does anything touch
//! the disk, and each file is written to a temporary file in the same directory and renamed
//! over the target. A crash, a full disk or a bad value therefore never leaves a half-written
//! CSV where a CI job will read it, and the previous files stay whole.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{ensure_finite, Error, IoError, Result};

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

/// Whether `entry` is a temporary file [`write_atomic`] makes for `name`:
/// `.{name}.XXXXXX.tmp`, with six ASCII letters or digits.
pub fn is_temporary_of(entry: &str, name: &str) -> bool {
    entry
        .strip_prefix('.')
        .and_then(|r| r.strip_prefix(name))
        .and_then(|r| r.strip_prefix('.'))
        .and_then(|r| r.strip_suffix(".tmp"))
        .is_some_and(|mid| mid.len() == 6 && mid.bytes().all(|b| b.is_ascii_alphanumeric()))
}

/// Removes from `dir` the temporaries a killed run left for the files `names` (only files
/// matching [`is_temporary_of`] one of them; nothing else is touched). Returns how many.
/// Best effort: a file that cannot be removed is left, and the write goes on.
pub fn remove_stale_temporaries(dir: &Path, names: &[&str]) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .filter(|e| {
            let entry = e.file_name().to_string_lossy().into_owned();
            names.iter().any(|n| is_temporary_of(&entry, n))
        })
        .filter(|e| std::fs::remove_file(e.path()).is_ok())
        .count()
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
pub fn write_files<N: AsRef<str> + Sync>(dir: &Path, files: &[(N, Vec<u8>)]) -> Result<Vec<PathBuf>> {
    ensure_dir(dir)?;
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_ref()).collect();
    let removed = remove_stale_temporaries(dir, &names);
    if removed > 0 {
        eprintln!(
            "removed {removed} stale temporary file{} (left by an interrupted run) from {}",
            if removed == 1 { "" } else { "s" },
            dir.display()
        );
    }
    // Each file is written, synced and renamed on its own; in parallel, the syncs overlap
    // (they were most of the wall time of a small sweep). Paths come back in order.
    use rayon::prelude::*;
    files
        .par_iter()
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

fn encode_error(format: &'static str, e: impl std::fmt::Display) -> Error {
    IoError::Encode {
        format,
        message: e.to_string(),
    }
    .into()
}

/// CSV bytes from a header and rows of already formatted fields.
pub fn csv_bytes(header: &[&str], rows: &[Vec<String>]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let wrap = |e: csv::Error| encode_error("CSV", e);
    w.write_record(header).map_err(wrap)?;
    for r in rows {
        w.write_record(r).map_err(wrap)?;
    }
    w.into_inner().map_err(|e| encode_error("CSV", e))
}

/// [`csv_bytes`] from rows formatted one at a time: only one row's fields exist at once, so a
/// 100,000-row table costs its bytes, not a string per field.
pub fn csv_bytes_from(header: &[&str], rows: impl Iterator<Item = Result<Vec<String>>>) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let wrap = |e: csv::Error| encode_error("CSV", e);
    w.write_record(header).map_err(wrap)?;
    for r in rows {
        w.write_record(&r?).map_err(wrap)?;
    }
    w.into_inner().map_err(|e| encode_error("CSV", e))
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
    let mut out = serde_json::to_vec_pretty(v).map_err(|e| encode_error("JSON", e))?;
    out.push(b'\n');
    Ok(out)
}

/// A number for people: "0" for zero, "< 1e-9" for magnitudes below 1e-9, at most four
/// significant digits without trailing zeros ("10", "0.2", "1.967"), scientific notation
/// outside [1e-3, 1e6) ("2.5e-5", "6.711e7").
pub fn short_number(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    if !v.is_finite() {
        return v.to_string();
    }
    if v.abs() < 1e-9 {
        return if v < 0.0 {
            "> -1e-9".to_string()
        } else {
            "< 1e-9".to_string()
        };
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').expect("exponent");
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        return format!("{m}e{e}");
    }
    let digits = (3 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// "1 cascade", "2 cascades", "0 cascades": a count and its noun with the plural right
/// (`noun` is the singular; the plural adds "s").
pub fn count(n: impl Into<u64>, noun: &str) -> String {
    let n = n.into();
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// The relative change from `base` to `value` in percent; None when `base` is 0 (no relative
/// change exists) or either is not finite.
pub fn percent_change(base: f64, value: f64) -> Option<f64> {
    (base != 0.0 && base.is_finite() && value.is_finite()).then(|| 100.0 * (value - base) / base.abs())
}

/// A percentage from [`percent_change`] as text for people: "+16 %", "-25 %", "+0.4 %", "0 %"
/// (whole percent from 10 % up, one decimal below).
pub fn signed_percent(p: f64) -> String {
    let r = if p.abs() >= 10.0 {
        p.round()
    } else {
        (p * 10.0).round() / 10.0
    };
    if r == 0.0 {
        return "0 %".to_string();
    }
    format!("{}{} %", if r > 0.0 { "+" } else { "" }, short_number(r))
}

#[cfg(test)]
mod short_number_tests {
    use super::short_number;

    #[test]
    fn numbers_read_like_people_write_them() {
        for (v, s) in [
            (0.0, "0"),
            (10.0, "10"),
            (0.2, "0.2"),
            (1.9674, "1.967"),
            (0.1667, "0.1667"),
            (5.24e-14, "< 1e-9"),
            (2.5e-5, "2.5e-5"),
            (67108864.0, "6.711e7"),
            (106.115, "106.1"),
            (-3.0, "-3"),
            (-0.0, "0"),
            (-5.24e-14, "> -1e-9"),
            (1e-9, "1e-9"),
            (0.00099996, "1e-3"),
            (0.001, "0.001"),
            (999_999.4, "999999"),
            (1e300, "1e300"),
            (-2.5e-5, "-2.5e-5"),
            (0.99996, "1"),
            (9.99951, "10"),
            (123_456.0, "123456"),
            (0.012346, "0.01235"),
        ] {
            assert_eq!(short_number(v), s, "{v}");
        }
    }

    #[test]
    fn no_number_reads_like_a_float_dump() {
        // Whatever the magnitude, no "e0", no "e-1x", no "e+", no run of zeros after the point.
        let mut x = 1e-300_f64;
        while x < 1e300 {
            for v in [x, -x, x * 1.5, x * 9.99951] {
                let s = short_number(v);
                assert!(
                    !s.contains("e0") && !s.contains("e-1") && !s.contains("e+") && !s.contains(".000"),
                    "{v} -> {s}"
                );
                assert!(s.len() <= 9, "{v} -> {s}");
            }
            x *= 10.0;
        }
    }

    #[test]
    fn counts_and_percentages_read_right() {
        use super::{count, percent_change, signed_percent};
        assert_eq!(count(1u64, "cascade"), "1 cascade");
        assert_eq!(count(0u64, "cascade"), "0 cascades");
        assert_eq!(count(4u32, "cascade"), "4 cascades");
        assert_eq!(percent_change(64.0, 48.0), Some(-25.0));
        assert_eq!(percent_change(0.0, 1.0), None);
        assert_eq!(signed_percent(percent_change(1.0, 1.1612).unwrap()), "+16 %");
        assert_eq!(signed_percent(-25.0), "-25 %");
        assert_eq!(signed_percent(0.04), "0 %");
        assert_eq!(signed_percent(0.44), "+0.4 %");
        assert_eq!(signed_percent(-9.96), "-10 %");
        assert_eq!(signed_percent(150.4), "+150 %");
    }
}
