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

/// Writes `bytes` to `path` atomically: a one-file set ([`write_set`]) in the file's directory,
/// so the temporary is inside a marked staging directory of this run, under the directory's
/// lock.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .ok_or_else(|| Error::write(path, std::io::Error::other("not a file name")))?;
    write_set(&dir, &[(name, bytes.to_vec())], &[], None).map(|_| ())
}

/// Creates `dir` (and parents) with a message that names it.
pub(crate) fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))
}

/// Renders every exporter, then writes all files atomically into `dir`. Returns the paths.
pub(crate) fn export_all<T: ?Sized>(dir: &Path, data: &T, exporters: &[&dyn Exporter<T>]) -> Result<Vec<PathBuf>> {
    let rendered = exporters
        .iter()
        .map(|e| Ok((e.file_name(), e.render(data)?)))
        .collect::<Result<Vec<_>>>()?;
    write_files(dir, &rendered)
}

/// Rendered files: (file name, bytes).
pub(crate) type RenderedFiles = Vec<(String, Vec<u8>)>;

/// Writes already-rendered files into `dir` as one set (see [`write_set`]).
pub(crate) fn write_files<N: AsRef<str> + Sync>(dir: &Path, files: &[(N, Vec<u8>)]) -> Result<Vec<PathBuf>> {
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
/// `.csm-lab-staging-<run id>-XXXXXX`, the run id being 16 random hex digits ([`run_id`]).
pub(crate) const STAGING_PREFIX: &str = ".csm-lab-staging-";

/// The file a staging directory holds once every file of its set is written and synced: from
/// then on the set is moved into place, and an interrupted move is completed by the next run.
pub(crate) const STAGING_COMPLETE: &str = ".complete";

/// The marker a staging directory holds from its creation: `csm-lab staging <run id>` on the
/// first line, then the names of the set's files, one a line. Recovery touches a staging
/// directory only when its marker names the run id of the directory's own name, and then only
/// the files the marker lists.
pub(crate) const STAGING_MARKER: &str = ".csm-lab-run";

/// The lock file of an output directory, where the directory itself cannot be locked.
pub(crate) const LOCK_FILE: &str = ".csm-lab.lock";

static WAIT_FOR_LOCK: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(true);

/// Whether a run waits for another run that is writing the same output directory (the
/// default) or stops with an error (`--no-wait`).
pub(crate) fn set_wait_for_lock(wait: bool) {
    WAIT_FOR_LOCK.store(wait, std::sync::atomic::Ordering::Relaxed);
}

/// This process's run id: 16 hex digits from the operating system's random source (the
/// process id and time if that fails), the same for every set the process writes.
pub(crate) fn run_id() -> &'static str {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let x = getrandom::u64().unwrap_or_else(|_| {
            let t = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos() as u64);
            t ^ (u64::from(std::process::id()) << 32)
        });
        format!("{x:016x}")
    })
}

fn marker_text(id: &str, names: &[&str]) -> String {
    let mut t = format!("csm-lab staging {id}\n");
    for n in names {
        t.push_str(n);
        t.push('\n');
    }
    t
}

/// The run id in a staging directory's name, if it has the form csm-lab gives it.
fn staging_id(entry: &str) -> Option<&str> {
    let rest = entry.strip_prefix(STAGING_PREFIX)?;
    let (id, suffix) = rest.split_once('-')?;
    (id.len() == 16
        && id.bytes().all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase())
        && suffix.len() == 6
        && suffix.bytes().all(|b| b.is_ascii_alphanumeric()))
    .then_some(id)
}

/// The names a staging directory's marker lists, when the marker is valid: a regular file whose
/// first line names the run id of the directory's name. None for anything else.
fn marked_names(staging: &Path, id: &str) -> Option<Vec<String>> {
    let marker = staging.join(STAGING_MARKER);
    let meta = std::fs::symlink_metadata(&marker).ok()?;
    if !meta.is_file() || meta.len() > 1 << 20 {
        return None;
    }
    let text = std::fs::read_to_string(&marker).ok()?;
    let mut lines = text.lines();
    (lines.next()? == format!("csm-lab staging {id}")).then(|| {
        lines
            .filter(|n| !n.is_empty() && !n.contains('/') && !n.contains('\\') && *n != "." && *n != "..")
            .map(str::to_string)
            .collect()
    })
}

/// An output directory's advisory lock, held while a set is written into it (released when
/// dropped). Taken on the directory itself where the platform allows (no file is added), else
/// on [`LOCK_FILE`] inside it. An advisory lock (`flock`) is kept by the kernel for the open
/// file, so it holds across processes of other PID namespaces that share the file system, and
/// a killed run's lock is released with its last descriptor: no process id is ever judged.
pub struct DirLock {
    _file: std::fs::File,
}

impl DirLock {
    /// Takes `dir`'s lock: waits for another run that holds it (saying so once), or, after
    /// `--no-wait`, fails with "another csm-lab run is writing DIR".
    pub fn acquire(dir: &Path) -> Result<DirLock> {
        use fs4::FileExt;
        let file = Self::open(dir)?;
        match FileExt::try_lock(&file) {
            Ok(()) => return Ok(DirLock { _file: file }),
            Err(fs4::TryLockError::WouldBlock) => {}
            Err(fs4::TryLockError::Error(e)) => return Err(Error::write(dir, e)),
        }
        if !WAIT_FOR_LOCK.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(Error::write(
                dir,
                std::io::Error::other(
                    "another csm-lab run is writing this directory (drop --no-wait to wait for it, or choose another --out)",
                ),
            ));
        }
        eprintln!(
            "another csm-lab run is writing {}: waiting for it to finish",
            dir.display()
        );
        FileExt::lock(&file).map_err(|e| Error::write(dir, e))?;
        Ok(DirLock { _file: file })
    }

    fn open(dir: &Path) -> Result<std::fs::File> {
        #[cfg(unix)]
        if let Ok(f) = std::fs::File::open(dir) {
            use fs4::FileExt;
            // A file system that cannot lock a directory descriptor (some network file
            // systems) falls back to the lock file.
            match FileExt::try_lock_shared(&f) {
                Ok(()) => {
                    let _ = FileExt::unlock(&f);
                    return Ok(f);
                }
                Err(fs4::TryLockError::WouldBlock) => return Ok(f),
                Err(fs4::TryLockError::Error(_)) => {}
            }
        }
        std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(dir.join(LOCK_FILE))
            .map_err(|e| Error::write(&dir.join(LOCK_FILE), e))
    }
}

/// Writes a set of files into `dir`, all or nothing:
///
/// 0. Takes the directory's lock ([`DirLock`]) for the rest of the write: two runs into one
///    directory write their sets one after the other, never interleaved.
/// 1. Recovers what an interrupted run left ([`recover`]): its marked staging directories are
///    removed, and a staged set that was complete when the run stopped is moved into place
///    first.
/// 2. Writes the marker ([`STAGING_MARKER`]: this run's id and the set's names) into a new
///    staging directory inside `dir` (same file system), then every file, syncs each, then
///    marks the set complete ([`STAGING_COMPLETE`]) and syncs the directory.
/// 3. Renames each file over its name in `dir` (no data is written any more: renames only),
///    syncs `dir`, and removes the staging directory.
///
/// A failure in step 2 (a full disk, a bad value, a kill) leaves the previous files untouched
/// and no new file beside them. Only a kill within step 3 can leave a mix; the staging
/// directory is then marked complete, and the next run into `dir` completes the move before
/// anything else. Files in `dir` that are not of this set are never touched, whatever their
/// names.
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
    let _lock = DirLock::acquire(dir)?;
    let (completed, removed) = recover(dir);
    if completed > 0 {
        eprintln!(
            "completed the output set of an interrupted run in {} before writing this one",
            dir.display()
        );
    }
    if removed > 0 {
        eprintln!(
            "removed {removed} incomplete staging director{} (left by an interrupted run) from {}",
            if removed == 1 { "y" } else { "ies" },
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
        .prefix(&format!("{STAGING_PREFIX}{}-", run_id()))
        .tempdir_in(dir)
        .map_err(|e| Error::write(dir, e))?;
    write_synced(
        &staging.path().join(STAGING_MARKER),
        marker_text(run_id(), &names).as_bytes(),
    )
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
    // Only the markers are left; dropping the staging directory removes them.
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

/// Cleans up after interrupted runs in `dir`, with the directory's lock held (so no other run
/// is writing it), touching only staging directories csm-lab can prove it made: a directory
/// (not a link) named `.csm-lab-staging-<run id>-XXXXXX` holding a valid marker
/// ([`STAGING_MARKER`]). A complete one is first moved into place, file by file (the files its
/// marker lists); an incomplete one is removed. Only the files the marker lists and the two
/// markers are deleted; a staging directory that still holds anything else is left. Returns
/// (sets completed, staging directories removed). Best effort: what cannot be recovered is
/// left, and the write goes on. Files of the user are never touched, whatever their names.
pub(crate) fn recover(dir: &Path) -> (usize, usize) {
    let mut completed = 0;
    let mut removed = 0;
    let Ok(entries) = std::fs::read_dir(dir) else {
        return (completed, removed);
    };
    for e in entries.filter_map(|e| e.ok()) {
        let entry = e.file_name().to_string_lossy().into_owned();
        let Some(id) = staging_id(&entry) else {
            continue;
        };
        // file_type does not follow links: a link named like a staging directory is not one.
        if !e.file_type().is_ok_and(|t| t.is_dir()) {
            continue;
        }
        let staging = e.path();
        let Some(names) = marked_names(&staging, id) else {
            // A run killed between making its staging directory and finishing the marker's
            // first line leaves it empty or with a marker that is a strict prefix of
            // "csm-lab staging <its id>\n" (nothing else is written before the marker). Only
            // such a marker is removed, then the directory if empty: nothing of anyone's goes
            // (another id's marker, or any other file, keeps the directory).
            let partial = staging.join(STAGING_MARKER);
            let header = format!("csm-lab staging {id}\n");
            if std::fs::symlink_metadata(&partial).is_ok_and(|m| m.is_file())
                && std::fs::read(&partial).is_ok_and(|b| b.len() < header.len() && header.as_bytes().starts_with(&b))
            {
                let _ = std::fs::remove_file(&partial);
            }
            if std::fs::remove_dir(&staging).is_ok() {
                removed += 1;
            }
            continue;
        };
        let complete = std::fs::symlink_metadata(staging.join(STAGING_COMPLETE)).is_ok_and(|m| m.is_file());
        for name in &names {
            let staged = staging.join(name);
            if !std::fs::symlink_metadata(&staged).is_ok_and(|m| m.is_file()) {
                continue;
            }
            if complete {
                let _ = std::fs::rename(&staged, dir.join(name));
            } else {
                let _ = std::fs::remove_file(&staged);
            }
        }
        if complete {
            sync_dir(dir);
            completed += 1;
        }
        let _ = std::fs::remove_file(staging.join(STAGING_COMPLETE));
        let _ = std::fs::remove_file(staging.join(STAGING_MARKER));
        if std::fs::remove_dir(&staging).is_ok() && !complete {
            removed += 1;
        }
    }
    (completed, removed)
}

/// A finite number formatted for CSV/JSON: shortest round-trip representation.
pub(crate) fn num(what: &str, v: f64) -> Result<String> {
    Ok(format!("{}", ensure_finite(what, v)?))
}

pub(crate) fn encode_error(format: &'static str, e: impl std::fmt::Display) -> Error {
    IoError::Encode {
        format,
        message: e.to_string(),
    }
    .into()
}

/// CSV bytes from a header and rows of already formatted fields.
pub(crate) fn csv_bytes(header: &[&str], rows: &[Vec<String>]) -> Result<Vec<u8>> {
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
pub(crate) fn csv_bytes_from(header: &[&str], rows: impl Iterator<Item = Result<Vec<String>>>) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    csv_write_from(&mut out, header, rows)?;
    Ok(out)
}

/// [`csv_bytes_from`] written to `out` row by row (a streamed file holds no copy of itself).
pub(crate) fn csv_write_from(
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
pub(crate) fn json_bytes(what: &str, v: &serde_json::Value) -> Result<Vec<u8>> {
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
pub(crate) fn four_digits(v: f64, sci_below: f64) -> String {
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
pub(crate) fn count(n: impl Into<u64>, noun: &str) -> String {
    let n = n.into();
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// The relative change from `base` to `value` in percent; None when `base` is 0 (no relative
/// change exists) or either is not finite.
pub(crate) fn percent_change(base: f64, value: f64) -> Option<f64> {
    (base != 0.0 && base.is_finite() && value.is_finite()).then(|| 100.0 * (value - base) / base.abs())
}

/// A percentage from [`percent_change`] as text for people: "+16 %", "-25 %", "+0.4 %", "0 %"
/// (whole percent from 10 % up, one decimal below).
pub(crate) fn signed_percent(p: f64) -> String {
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

    /// A staging directory as a run with id `id` leaves it: the marker listing `names`, then
    /// the files `staged` (name, contents), then, when `complete`, the completion marker.
    fn staged(
        dir: &Path,
        id: &str,
        suffix: &str,
        names: &[&str],
        staged: &[(String, Vec<u8>)],
        complete: bool,
    ) -> PathBuf {
        let d = dir.join(format!("{STAGING_PREFIX}{id}-{suffix}"));
        std::fs::create_dir(&d).unwrap();
        std::fs::write(d.join(STAGING_MARKER), marker_text(id, names)).unwrap();
        for (n, b) in staged {
            std::fs::write(d.join(n), b).unwrap();
        }
        if complete {
            std::fs::write(d.join(STAGING_COMPLETE), names.join("\n")).unwrap();
        }
        d
    }

    /// A run killed while moving its staged set into place: the next run completes that set
    /// before it writes its own; a run killed while staging leaves a staging directory that
    /// the next run removes. Entries without a valid marker (a user's file, a directory of
    /// another tool's with a similar name, a marker naming another id, a user's temporaries)
    /// are left alone, whatever their names.
    #[test]
    fn the_next_run_completes_or_removes_what_an_interrupted_run_left() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("notes.txt"), "mine\n").unwrap();
        write_files(d, &set("old")).unwrap();
        let names = ["a.csv", "b.json", "c.svg"];
        // A complete staged set of a killed run, half moved.
        let complete = staged(d, "0123456789abcdef", "AbC123", &names, &set("killed"), true);
        std::fs::rename(complete.join("a.csv"), d.join("a.csv")).unwrap();
        // An incomplete one (one file written), and one killed before its marker (empty).
        staged(d, "fedcba9876543210", "XyZ789", &names, &set("partial")[..1], false);
        std::fs::create_dir(d.join(format!("{STAGING_PREFIX}00000000000000aa-Empty1"))).unwrap();
        // One killed while writing its marker's first line: a strict prefix of its own header.
        let half = d.join(format!("{STAGING_PREFIX}00000000000000bb-Half12"));
        std::fs::create_dir(&half).unwrap();
        std::fs::write(half.join(STAGING_MARKER), "csm-lab stag").unwrap();
        // Lookalikes that are not csm-lab's: no marker, a marker of another id, a user file in
        // a marked directory, a file named like a staging directory, user temporaries.
        let unmarked = d.join(format!("{STAGING_PREFIX}1111111111111111-mywork"));
        std::fs::create_dir(&unmarked).unwrap();
        std::fs::write(unmarked.join("notes"), "mine").unwrap();
        let forged = staged(d, "2222222222222222", "Forged", &names, &set("forged"), true);
        std::fs::write(forged.join(STAGING_MARKER), marker_text("3333333333333333", &names)).unwrap();
        let with_user_file = staged(d, "4444444444444444", "Mixed1", &["a.csv"], &set("mixed")[..1], false);
        std::fs::write(with_user_file.join("keep.txt"), "mine").unwrap();
        std::fs::write(d.join(format!("{STAGING_PREFIX}5555555555555555-File12")), "a file").unwrap();
        std::fs::write(d.join(".a.csv.Q1w2E3.tmp"), "mine").unwrap();
        std::fs::write(d.join(".a.csv.backup.tmp"), "mine").unwrap();
        assert_eq!(recover(d), (1, 3));
        let user = |mut want: Vec<(String, String)>| {
            want.push((format!("{STAGING_PREFIX}1111111111111111-mywork"), "<dir>".to_string()));
            want.push((format!("{STAGING_PREFIX}2222222222222222-Forged"), "<dir>".to_string()));
            want.push((format!("{STAGING_PREFIX}4444444444444444-Mixed1"), "<dir>".to_string()));
            want.push((format!("{STAGING_PREFIX}5555555555555555-File12"), "a file".to_string()));
            want.push((".a.csv.Q1w2E3.tmp".to_string(), "mine".to_string()));
            want.push((".a.csv.backup.tmp".to_string(), "mine".to_string()));
            want.sort();
            want
        };
        assert_eq!(listing(d), user(expected("killed", true)));
        assert_eq!(std::fs::read_to_string(unmarked.join("notes")).unwrap(), "mine");
        assert_eq!(listing(&forged).len(), 5, "a forged marker's directory was touched");
        assert_eq!(
            listing(&with_user_file),
            vec![("keep.txt".to_string(), "mine".to_string())],
            "only the marked set's files go"
        );
        write_files(d, &set("new")).unwrap();
        assert_eq!(listing(d), user(expected("new", true)));
    }

    #[test]
    fn a_staging_directory_of_a_run_holding_the_lock_is_left_alone() {
        // recover runs under the directory's lock; here the lock is held by "another run", so
        // a writer waits (or, with --no-wait, fails) instead of recovering.
        let dir = tempfile::tempdir().unwrap();
        let held = DirLock::acquire(dir.path()).unwrap();
        let live = staged(
            dir.path(),
            "0123456789abcdef",
            "Live12",
            &["a.csv"],
            &set("live")[..1],
            false,
        );
        set_wait_for_lock(false);
        let e = write_files(dir.path(), &set("new")).unwrap_err().to_string();
        set_wait_for_lock(true);
        assert!(e.contains("another csm-lab run is writing"), "{e}");
        assert!(live.join("a.csv").is_file());
        drop(held);
        write_files(dir.path(), &set("new")).unwrap();
        assert!(!live.exists());
    }

    #[test]
    fn a_directory_in_the_way_is_refused_before_anything_is_written() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("b.json")).unwrap();
        let e = write_files(dir.path(), &set("new")).unwrap_err().to_string();
        assert!(e.contains("b.json") && e.contains("directory"), "{e}");
        let mut l = listing(dir.path());
        l.retain(|(n, _)| n != LOCK_FILE);
        assert_eq!(l, vec![("b.json".to_string(), "<dir>".to_string())]);
    }
}
