//! Writing results: a small exporter trait, CSV/JSON renderers, and atomic file writes.
//!
//! Every file is rendered to memory first; only when all of them rendered does anything touch
//! the disk. A command's files are one set: written into a staging directory inside the
//! output directory and moved into place only when all of them are on disk ([`write_files`]).
//! A crash, a full disk or a bad value therefore never leaves a half-written CSV where a CI
//! job will read it, nor new files beside the previous run's: the previous set stays whole.
//! A single file (`check`'s JUnit report, a baseline) is written with [`write_atomic`].

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

/// Writes already-rendered files into `dir` as one set (see [`write_set`]).
pub fn write_files<N: AsRef<str> + Sync>(dir: &Path, files: &[(N, Vec<u8>)]) -> Result<Vec<PathBuf>> {
    write_set(dir, files, &[], None)
}

/// A file too large to render in memory: it writes itself into the staged file as it is
/// produced (a long path's every frame, say). Its numbers pass the same finite guard.
pub trait StreamedFile: Sync {
    fn file_name(&self) -> &str;
    fn write_to(&self, out: &mut dyn Write) -> Result<()>;
}

/// [`write_files`] with some files streamed into the set instead of rendered first.
pub fn write_files_streamed<N: AsRef<str> + Sync>(
    dir: &Path,
    files: &[(N, Vec<u8>)],
    streamed: &[&dyn StreamedFile],
) -> Result<Vec<PathBuf>> {
    write_set(dir, files, streamed, None)
}

/// Name prefix of the staging directories [`write_files`] makes in an output directory:
/// `.csm-lab-staging-<pid>-XXXXXX`.
pub const STAGING_PREFIX: &str = ".csm-lab-staging-";

/// The file a staging directory holds once every file of its set is written and synced: from
/// then on the set is moved into place, and an interrupted move is completed by the next run.
pub const STAGING_COMPLETE: &str = ".complete";

/// Writes a set of files into `dir`, all or nothing:
///
/// 1. Recovers what an interrupted run left ([`recover`]): its stale temporaries and staging
///    directories are removed, and a staged set that was complete when the run stopped is
///    moved into place first.
/// 2. Writes every file into a new staging directory inside `dir` (same file system), syncs
///    each, then marks the set complete ([`STAGING_COMPLETE`]) and syncs the directory.
/// 3. Renames each file over its name in `dir` (no data is written any more: renames only),
///    syncs `dir`, and removes the staging directory.
///
/// A failure in step 2 (a full disk, a bad value, a kill) leaves the previous files untouched
/// and no new file beside them. Only a kill within step 3 can leave a mix; the staging
/// directory is then marked complete, and the next run into `dir` completes the move before
/// anything else. Files in `dir` that are not of this set are never touched.
fn write_set<N: AsRef<str> + Sync>(
    dir: &Path,
    files: &[(N, Vec<u8>)],
    streamed: &[&dyn StreamedFile],
    fail_at: Option<usize>,
) -> Result<Vec<PathBuf>> {
    ensure_dir(dir)?;
    let names: Vec<&str> = files
        .iter()
        .map(|(n, _)| n.as_ref())
        .chain(streamed.iter().map(|f| f.file_name()))
        .collect();
    let (completed, removed) = recover(dir, &names);
    if completed > 0 {
        eprintln!(
            "completed the output set of an interrupted run in {} before writing this one",
            dir.display()
        );
    }
    if removed > 0 {
        eprintln!(
            "removed {removed} stale temporary file{} (left by an interrupted run) from {}",
            if removed == 1 { "" } else { "s" },
            dir.display()
        );
    }
    // A name taken by a directory would fail in the middle of the swap: refuse it up front.
    for name in &names {
        let target = dir.join(name);
        if target.is_dir() {
            return Err(Error::write(
                &target,
                std::io::Error::other("a directory has this name; move it away or choose another --out"),
            ));
        }
    }
    let staging = tempfile::Builder::new()
        .prefix(&format!("{STAGING_PREFIX}{}-", std::process::id()))
        .tempdir_in(dir)
        .map_err(|e| Error::write(dir, e))?;
    // Each file is written and synced on its own; in parallel, the syncs overlap (they were
    // most of the wall time of a small sweep).
    use rayon::prelude::*;
    files.par_iter().enumerate().try_for_each(|(k, (name, bytes))| {
        let path = staging.path().join(name.as_ref());
        if fail_at == Some(k) {
            return Err(Error::write(
                &dir.join(name.as_ref()),
                std::io::Error::other("simulated failure"),
            ));
        }
        write_synced(&path, bytes).map_err(|e| Error::write(&dir.join(name.as_ref()), e))
    })?;
    for f in streamed {
        let target = dir.join(f.file_name());
        let file = std::fs::File::create(staging.path().join(f.file_name())).map_err(|e| Error::write(&target, e))?;
        let mut out = std::io::BufWriter::new(file);
        f.write_to(&mut out)?;
        let file = out.into_inner().map_err(|e| Error::write(&target, e.into_error()))?;
        finish_synced(&file).map_err(|e| Error::write(&target, e))?;
    }
    write_synced(&staging.path().join(STAGING_COMPLETE), names.join("\n").as_bytes())
        .map_err(|e| Error::write(dir, e))?;
    sync_dir(staging.path());
    let paths = names
        .iter()
        .map(|name| {
            let path = dir.join(name);
            std::fs::rename(staging.path().join(name), &path).map_err(|e| Error::write(&path, e))?;
            Ok(path)
        })
        .collect::<Result<Vec<_>>>()?;
    sync_dir(dir);
    // Only the marker is left; dropping the staging directory removes it.
    drop(staging);
    Ok(paths)
}

/// Creates `path` (a new file in a staging directory), writes `bytes`, sets it readable like
/// an ordinary file and syncs it.
fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(path)?;
    f.write_all(bytes)?;
    finish_synced(&f)
}

/// Sets a written staged file readable like an ordinary file and syncs it.
fn finish_synced(f: &std::fs::File) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        f.set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    f.sync_all()
}

/// Syncs a directory's entries (best effort: not every platform opens directories).
fn sync_dir(dir: &Path) {
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

/// The process id in a staging directory's name, if it is one.
fn staging_pid(entry: &str) -> Option<u32> {
    let rest = entry.strip_prefix(STAGING_PREFIX)?;
    let (pid, suffix) = rest.split_once('-')?;
    (suffix.len() == 6 && suffix.bytes().all(|b| b.is_ascii_alphanumeric()))
        .then(|| pid.parse().ok())
        .flatten()
}

/// Whether the process that made a staging directory may still be writing it.
fn still_running(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    #[cfg(target_os = "linux")]
    {
        Path::new(&format!("/proc/{pid}")).exists()
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}

/// Cleans up after interrupted runs in `dir`, touching only csm-lab's own entries: staging
/// directories of processes that are gone (a complete one is first moved into place, file by
/// file; an incomplete one is removed) and the temporaries of earlier versions for the files
/// `names` ([`remove_stale_temporaries`]). Returns (sets completed, entries removed). Best
/// effort: what cannot be recovered is left, and the write goes on.
pub fn recover(dir: &Path, names: &[&str]) -> (usize, usize) {
    let mut completed = 0;
    let mut removed = remove_stale_temporaries(dir, names);
    let Ok(entries) = std::fs::read_dir(dir) else {
        return (completed, removed);
    };
    for e in entries.filter_map(|e| e.ok()) {
        let entry = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = staging_pid(&entry) else {
            continue;
        };
        if !e.file_type().is_ok_and(|t| t.is_dir()) || still_running(pid) {
            continue;
        }
        let staging = e.path();
        if staging.join(STAGING_COMPLETE).is_file() {
            let Ok(staged) = std::fs::read_dir(&staging) else {
                continue;
            };
            for f in staged.filter_map(|f| f.ok()) {
                let name = f.file_name();
                if name != STAGING_COMPLETE && f.file_type().is_ok_and(|t| t.is_file()) {
                    let _ = std::fs::rename(f.path(), dir.join(&name));
                }
            }
            sync_dir(dir);
            completed += 1;
        } else {
            removed += 1;
        }
        let _ = std::fs::remove_dir_all(&staging);
    }
    (completed, removed)
}

/// A finite number formatted for CSV/JSON: shortest round-trip representation.
pub fn num(what: &str, v: f64) -> Result<String> {
    Ok(format!("{}", ensure_finite(what, v)?))
}

pub fn encode_error(format: &'static str, e: impl std::fmt::Display) -> Error {
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
    let mut out = Vec::new();
    csv_write_from(&mut out, header, rows)?;
    Ok(out)
}

/// [`csv_bytes_from`] written to `out` row by row (a streamed file holds no copy of itself).
pub fn csv_write_from(
    out: &mut dyn Write,
    header: &[&str],
    rows: impl Iterator<Item = Result<Vec<String>>>,
) -> Result<()> {
    let mut w = csv::Writer::from_writer(out);
    let wrap = |e: csv::Error| encode_error("CSV", e);
    w.write_record(header).map_err(wrap)?;
    for r in rows {
        w.write_record(&r?).map_err(wrap)?;
    }
    w.flush().map_err(|e| encode_error("CSV", e))
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
    four_digits(v, 1e-3)
}

/// At most four significant digits without trailing zeros ("10", "0.2", "1.967"), scientific
/// notation for magnitudes outside `[sci_below, 1e6)` ("2.5e-5", "6.711e7"). `v` is finite and
/// not zero. The one decimal formatter behind [`short_number`] and the figures' tick labels.
pub fn four_digits(v: f64, sci_below: f64) -> String {
    let a = v.abs();
    if !(sci_below..1e6).contains(&a) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
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

#[cfg(test)]
mod set_tests {
    use super::*;

    fn set(tag: &str) -> Vec<(String, Vec<u8>)> {
        ["a.csv", "b.json", "c.svg"]
            .iter()
            .map(|n| (n.to_string(), format!("{tag} {n}\n").into_bytes()))
            .collect()
    }

    /// Every entry of `dir` with its contents (directories as "<dir>").
    fn listing(dir: &Path) -> Vec<(String, String)> {
        let mut v: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let name = e.file_name().to_string_lossy().into_owned();
                let body = if e.path().is_dir() {
                    "<dir>".to_string()
                } else {
                    std::fs::read_to_string(e.path()).unwrap()
                };
                (name, body)
            })
            .collect();
        v.sort();
        v
    }

    fn expected(tag: &str, user: bool) -> Vec<(String, String)> {
        let mut v: Vec<_> = set(tag)
            .into_iter()
            .map(|(n, b)| (n, String::from_utf8(b).unwrap()))
            .collect();
        if user {
            v.push(("notes.txt".to_string(), "mine\n".to_string()));
        }
        v.sort();
        v
    }

    #[test]
    fn a_failure_while_writing_leaves_the_previous_set_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("notes.txt"), "mine\n").unwrap();
        write_files(dir.path(), &set("old")).unwrap();
        assert_eq!(listing(dir.path()), expected("old", true));
        for k in 0..3 {
            assert!(write_set(dir.path(), &set("new"), &[], Some(k)).is_err());
            assert_eq!(listing(dir.path()), expected("old", true), "failure at file {k}");
        }
        write_files(dir.path(), &set("new")).unwrap();
        assert_eq!(listing(dir.path()), expected("new", true));
    }

    /// A run killed while moving its staged set into place: the next run completes that set
    /// before it writes its own; a run killed while staging leaves a staging directory that
    /// the next run removes. Other entries (a user's file, a directory of another tool's
    /// with a similar name) are left alone.
    #[test]
    fn the_next_run_completes_or_removes_what_an_interrupted_run_left() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("notes.txt"), "mine\n").unwrap();
        write_files(d, &set("old")).unwrap();
        // A complete staged set of a dead process (pid 0 never names one), half moved.
        let staged = d.join(format!("{STAGING_PREFIX}0-AbC123"));
        std::fs::create_dir(&staged).unwrap();
        for (n, b) in set("killed") {
            std::fs::write(staged.join(&n), b).unwrap();
        }
        std::fs::write(staged.join(STAGING_COMPLETE), "a.csv\nb.json\nc.svg").unwrap();
        std::fs::rename(staged.join("a.csv"), d.join("a.csv")).unwrap();
        // An incomplete one, a stale temporary of an earlier version, and lookalikes that are
        // not csm-lab's (wrong suffix length; a file, not a directory).
        let partial = d.join(format!("{STAGING_PREFIX}0-XyZ789"));
        std::fs::create_dir(&partial).unwrap();
        std::fs::write(partial.join("a.csv"), "partial").unwrap();
        std::fs::write(d.join(".a.csv.Q1w2E3.tmp"), "stale").unwrap();
        std::fs::create_dir(d.join(format!("{STAGING_PREFIX}0-notours"))).unwrap();
        std::fs::write(d.join(format!("{STAGING_PREFIX}0-File12")), "a file").unwrap();
        assert_eq!(recover(d, &["a.csv", "b.json", "c.svg"]), (1, 2));
        let mut want = expected("killed", true);
        want.push((format!("{STAGING_PREFIX}0-File12"), "a file".to_string()));
        want.push((format!("{STAGING_PREFIX}0-notours"), "<dir>".to_string()));
        want.sort();
        assert_eq!(listing(d), want);
        write_files(d, &set("new")).unwrap();
        let mut want = expected("new", true);
        want.push((format!("{STAGING_PREFIX}0-File12"), "a file".to_string()));
        want.push((format!("{STAGING_PREFIX}0-notours"), "<dir>".to_string()));
        want.sort();
        assert_eq!(listing(d), want);
    }

    #[test]
    fn a_live_process_staging_directory_is_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let mine = dir
            .path()
            .join(format!("{STAGING_PREFIX}{}-AbC123", std::process::id()));
        std::fs::create_dir(&mine).unwrap();
        assert_eq!(recover(dir.path(), &["a.csv"]), (0, 0));
        assert!(mine.is_dir());
    }

    #[test]
    fn a_directory_in_the_way_is_refused_before_anything_is_written() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("b.json")).unwrap();
        let e = write_files(dir.path(), &set("new")).unwrap_err().to_string();
        assert!(e.contains("b.json") && e.contains("directory"), "{e}");
        assert_eq!(listing(dir.path()), vec![("b.json".to_string(), "<dir>".to_string())]);
    }
}
