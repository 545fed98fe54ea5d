//! Sharded sweeps: `sweep --shard K/N` runs the K-th of N disjoint slices of a grid, and
//! `merge` joins the slices back into the rows of the unsharded sweep.
//!
//! A slice is round-robin over the grid order: row `i` (0-based, in [`Grid::settings`] order)
//! belongs to shard `i mod N + 1`, so every shard gets a share of every axis (cheap and costly
//! settings alike) and the N slices together are the grid, each row exactly once.
//!
//! A shard keeps its rows in [`ROWS_FILE`] in a lossless text form (JSON lines: a header with
//! the format's version, then one object per row as serde writes [`Row`], each `f64` exact)
//! and describes itself in [`MANIFEST_FILE`]: the csm-lab version,
//! K and N, the grid size, the command of the unsharded sweep and a hash of everything that
//! decides the rows. Merging rebuilds the exact rows, so the merged files are byte for byte
//! those of the unsharded sweep. Nothing here reads or writes a file: [`crate::app`] does.
//!
//! Merge trusts nothing it reads: each row ends in a digest of the row's text keyed by the
//! shard's `config_hash` and K/N, and the manifest carries a digest of its own fields
//! (`manifest_digest`). An edited row is an error naming the shard and the line; an edited
//! manifest (a `config_hash` pasted from another run, say) is an error naming the shard, and
//! so are its rows, whose digests were made with the hash the shard really ran. The digests
//! (64-bit FNV-1a) catch edits and mix-ups, not forgery: they are not signatures.

use crate::commands::sweep::grid::{Grid, GridFlags};
use crate::commands::sweep::run::Row;
use crate::config::Config;
use crate::error::{Error, Result, ShardError};

/// The shard's description, beside its other files.
pub(crate) const MANIFEST_FILE: &str = "shard.json";
/// The shard's rows, lossless.
pub(crate) const ROWS_FILE: &str = "shard-rows.jsonl";
/// The format named by the first line of [`ROWS_FILE`], and its version.
const ROWS_FORMAT: &str = "csm-lab shard rows";
const ROWS_VERSION: u32 = 5;
/// Most shards a grid may be split into.
pub(crate) const MAX_SHARDS: usize = 100_000;

/// `--shard K/N`: the K-th (1-based) of N slices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub k: usize,
    pub n: usize,
}

impl Shard {
    /// Parses `K/N` (`1 <= K <= N <= 100000`), naming `--shard` in every error.
    pub fn parse(spec: &str) -> Result<Shard> {
        let err = |m: String| Error::flag("--shard", spec, m);
        let (k, n) = spec
            .split_once('/')
            .ok_or_else(|| err("use K/N: the K-th of N shards, K from 1 to N (e.g. 2/4)".into()))?;
        let whole = |s: &str, what: &str| {
            s.trim().parse::<usize>().map_err(|_| {
                err(format!(
                    "{what} {s:?} is not a whole number; use K/N with 1 <= K <= N (e.g. 2/4)"
                ))
            })
        };
        let (k, n) = (whole(k, "K")?, whole(n, "N")?);
        if n == 0 || n > MAX_SHARDS {
            return Err(err(format!("N = {n} shards is outside 1..={MAX_SHARDS}")));
        }
        if k == 0 || k > n {
            return Err(err(format!(
                "K = {k} is outside 1..={n}: shards are numbered from 1 to N (a 0-based index such as \
                 $JOB_COMPLETION_INDEX needs +1)"
            )));
        }
        Ok(Shard { k, n })
    }

    /// Whether row `index` of the grid is in this shard.
    pub(crate) fn contains(self, index: usize) -> bool {
        index % self.n == self.k - 1
    }

    /// The grid indices of this shard, ascending.
    pub(crate) fn indices(self, grid_len: usize) -> impl Iterator<Item = usize> {
        (self.k - 1..grid_len).step_by(self.n)
    }

    /// How many rows of a grid of `grid_len` rows this shard holds.
    pub(crate) fn len_of(self, grid_len: usize) -> usize {
        (grid_len + self.n - self.k) / self.n
    }

    /// Refuses more shards than the grid has configurations (a shard would be empty).
    pub(crate) fn check_grid(self, grid_len: usize) -> Result<()> {
        if self.n > grid_len {
            return Err(Error::flag(
                "--shard",
                &format!("{}/{}", self.k, self.n),
                format!(
                    "{} shards for a grid of {grid_len} configurations: at most {grid_len} (no shard may be empty)",
                    self.n
                ),
            ));
        }
        Ok(())
    }
}

/// What a shard says about itself ([`MANIFEST_FILE`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Manifest {
    /// `csm-lab <version>` that ran the shard.
    pub tool: String,
    pub shard: Shard,
    /// Configurations in the whole grid.
    pub grid_configurations: usize,
    /// The config file as given to `sweep` (merge loads it again from there).
    pub config: String,
    /// The grid flags as given.
    pub flags: GridFlags,
    /// The command of the unsharded sweep (it appears in the merged files).
    pub command: String,
    /// [`config_hash`] of the loaded config, grid and command.
    pub config_hash: String,
}

/// The csm-lab that is running, as written in manifests and reports.
pub(crate) fn tool() -> String {
    format!("csm-lab {}", env!("CARGO_PKG_VERSION"))
}

/// [`MANIFEST_FILE`] as serde writes and reads it; the grid flags given (one key per
/// [`GridFlags::KEYS`] entry that was given) sit beside the named fields.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
struct ManifestFile {
    tool: String,
    shard: usize,
    shards: usize,
    grid_configurations: usize,
    rows: usize,
    rows_file: String,
    config: String,
    command: String,
    config_hash: String,
    manifest_digest: String,
    #[serde(flatten)]
    flags: std::collections::BTreeMap<String, String>,
}

impl Manifest {
    /// The digest of every field of the manifest ([`MANIFEST_FILE`]'s `manifest_digest`).
    pub(crate) fn digest(&self) -> String {
        let mut h = Fnv::default();
        for field in [
            self.tool.as_str(),
            &self.shard.k.to_string(),
            &self.shard.n.to_string(),
            &self.grid_configurations.to_string(),
            &self.config,
            &self.command,
            &self.config_hash,
        ] {
            h.eat(field.as_bytes());
        }
        for (key, value) in GridFlags::KEYS.iter().zip(self.flags.values()) {
            h.eat(key.as_bytes());
            h.eat(value.as_deref().unwrap_or("\u{0}").as_bytes());
        }
        h.hex()
    }

    pub(crate) fn to_json(&self) -> serde_json::Value {
        let file = ManifestFile {
            tool: self.tool.clone(),
            shard: self.shard.k,
            shards: self.shard.n,
            grid_configurations: self.grid_configurations,
            rows: self.shard.len_of(self.grid_configurations),
            rows_file: ROWS_FILE.to_string(),
            config: self.config.clone(),
            command: self.command.clone(),
            config_hash: self.config_hash.clone(),
            manifest_digest: self.digest(),
            flags: GridFlags::KEYS
                .iter()
                .zip(self.flags.values())
                .filter_map(|(k, v)| v.clone().map(|v| (k.to_string(), v)))
                .collect(),
        };
        // Through a Value: its map orders the keys, as the manifest always has.
        serde_json::to_value(file).unwrap_or_default()
    }

    /// Reads a manifest back; `dir` names the shard in errors. A manifest of this csm-lab
    /// version must carry the digest of its own fields (one of another version is left to
    /// [`check_set`], which names the version).
    pub(crate) fn from_json(dir: &std::path::Path, text: &str) -> Result<Manifest> {
        let bad = |m: String| Error::from(ShardError::dir(dir, format!("{MANIFEST_FILE}: {m}")));
        let file: ManifestFile =
            serde_json::from_str(text).map_err(|e| bad(format!("not a csm-lab shard manifest ({e})")))?;
        let (k, n) = (file.shard, file.shards);
        if n == 0 || n > MAX_SHARDS || k == 0 || k > n {
            return Err(bad(format!("shard {k} of {n} is not a valid K/N")));
        }
        let manifest = Manifest {
            tool: file.tool,
            shard: Shard { k, n },
            grid_configurations: file.grid_configurations,
            config: file.config,
            flags: GridFlags::from_keys(|key| file.flags.get(key).cloned()),
            command: file.command,
            config_hash: file.config_hash,
        };
        if manifest.tool == tool() && manifest.digest() != file.manifest_digest {
            return Err(bad(format!(
                "its fields do not match its manifest_digest {}: the file was edited after the shard ran \
                 (a config_hash pasted from another run, say); run the shard again",
                file.manifest_digest
            )));
        }
        Ok(manifest)
    }
}

/// FNV-1a (64 bits) over byte strings, each followed by its length so that boundaries count.
#[derive(Debug, Clone)]
pub(crate) struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub(crate) fn eat(&mut self, bytes: &[u8]) {
        for b in bytes.iter().chain(&(bytes.len() as u64).to_le_bytes()) {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    pub(crate) fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}

/// The hash two shards must share to be merged: the csm-lab version, the config file's bytes
/// (and its glTF's, if any), the loaded config (every value as used, the motion file's poses),
/// the resolved grid and the command of the unsharded sweep. 16 hex digits.
pub(crate) fn config_hash(
    file_bytes: &[u8],
    gltf_bytes: Option<&[u8]>,
    config: &Config,
    grid: &Grid,
    command: &str,
) -> String {
    let mut h = Fnv::default();
    h.eat(tool().as_bytes());
    h.eat(file_bytes);
    h.eat(gltf_bytes.unwrap_or_default());
    h.eat(config.echo().to_string().as_bytes());
    h.eat(config.scene_hash().as_bytes());
    h.eat(format!("{:?}", config.sweep).as_bytes());
    h.eat(format!("{:?}", config.shadow.preset.as_ref().map(|p| p.name)).as_bytes());
    h.eat(
        format!(
            "{:?}",
            (
                &grid.lambda,
                &grid.cascades,
                &grid.resolution,
                &grid.fit,
                &grid.split_range
            )
        )
        .as_bytes(),
    );
    // Only when swept: the hashes of sweeps without these axes stay as they were.
    if grid.knob.is_some() || grid.distance.is_some() {
        h.eat(format!("{:?}", (&grid.knob, &grid.distance)).as_bytes());
    }
    if let Some(sun) = &grid.sun {
        h.eat(format!("{sun:?}").as_bytes());
    }
    if let Some(u) = &grid.light_update {
        h.eat(format!("{u:?}").as_bytes());
    }
    if let Some(u) = &grid.update_every {
        h.eat(format!("{u:?}").as_bytes());
    }
    h.eat(command.as_bytes());
    h.hex()
}

// ---------------------------------------------------------------------------------------------
// Rows, lossless
// ---------------------------------------------------------------------------------------------

/// The digest that ends a row: its text before the digest, keyed by the shard's
/// `config_hash` and K/N (a row of another shard or run does not match).
fn row_digest(m: &Manifest, text: &str) -> String {
    let mut h = Fnv::default();
    h.eat(m.config_hash.as_bytes());
    h.eat(format!("{}/{}", m.shard.k, m.shard.n).as_bytes());
    h.eat(text.as_bytes());
    h.hex()
}

/// One line of [`ROWS_FILE`]: the row's grid index, the row as serde writes it, and its
/// digest. `serde_json` (with `float_roundtrip`) writes every `f64` in its shortest exact form
/// and reads it back bit for bit, so the merged rows equal the unsharded ones; a new field of
/// [`Row`] is carried without touching this file. Ground truth is not part of a sweep row (only
/// `analyze` runs it): serde skips it.
#[derive(serde::Deserialize)]
struct StoredRow {
    index: usize,
    row: Row,
    digest: String,
}

/// What a row's digest is made of (its index and row, as serde writes them).
#[derive(serde::Serialize)]
struct Digested<'a> {
    index: usize,
    row: &'a Row,
}

impl Digested<'_> {
    fn digest(&self, m: &Manifest) -> String {
        row_digest(
            m,
            &serde_json::to_string(self).expect("a row holds finite plain values"),
        )
    }
}

/// The first line of [`ROWS_FILE`]: the format and its version.
fn rows_header() -> String {
    serde_json::json!({"format": ROWS_FORMAT, "version": ROWS_VERSION}).to_string()
}

/// [`ROWS_FILE`]'s text for rows `(grid index, row)` of the shard `m` describes: JSON lines, a
/// header and then one object per row.
pub(crate) fn rows_text<'a>(m: &Manifest, rows: impl IntoIterator<Item = (usize, &'a Row)>) -> String {
    let mut out = rows_header();
    out.push('\n');
    for (index, row) in rows {
        let digest = Digested { index, row }.digest(m);
        let line = serde_json::json!({"index": index, "row": row, "digest": digest});
        out.push_str(&line.to_string());
        out.push('\n');
    }
    out
}

/// Reads [`rows_text`] back: (grid index, row) per line, each checked against its digest for
/// the shard `m` describes. `file` names the file in errors.
pub(crate) fn parse_rows(file: &std::path::Path, text: &str, m: &Manifest) -> Result<Vec<(usize, Row)>> {
    let mut lines = text.lines().enumerate();
    let bad = |line: usize, m: String| Error::data_file(file, line, m);
    let header = rows_header();
    match lines.next() {
        Some((_, first)) if first == header => {}
        _ => {
            return Err(bad(
                1,
                format!("not a shard rows file of this csm-lab (the first line is not {header})"),
            ))
        }
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let n = i + 1;
        let stored: StoredRow =
            serde_json::from_str(line).map_err(|e| bad(n, format!("not a row of this csm-lab: {e}")))?;
        // The digest is of the values read, written again: an edited value changes it, while
        // whitespace or key order, which change no value, do not.
        let expected = Digested {
            index: stored.index,
            row: &stored.row,
        }
        .digest(m);
        if expected != stored.digest {
            return Err(bad(
                n,
                format!(
                    "the row does not match its digest {:?}: it was edited after shard {} of {} ran, or the \
                     shard's {MANIFEST_FILE} is not the one it ran with; run the shard again",
                    stored.digest, m.shard.k, m.shard.n
                ),
            ));
        }
        rows.push((stored.index, stored.row));
    }
    Ok(rows)
}

/// One shard as read from its directory.
#[derive(Debug, Clone)]
pub(crate) struct ShardInput {
    pub dir: std::path::PathBuf,
    pub manifest: Manifest,
    /// (grid index, row), as stored.
    pub rows: Vec<(usize, Row)>,
}

/// Checks that `shards` are the N slices of one sweep, each once, and returns the manifest they
/// share. Errors name the problem and the directory: a shard given twice, shards of other
/// csm-lab versions or of different sweeps, missing shards (by K).
pub(crate) fn check_set(shards: &[ShardInput]) -> Result<&Manifest> {
    let first = shards
        .first()
        .ok_or_else(|| ShardError::Set("no shard directories were given".into()))?;
    let m0 = &first.manifest;
    for s in shards {
        let m = &s.manifest;
        if m.tool != tool() {
            return Err(ShardError::dir(
                &s.dir,
                format!(
                    "this shard was made by {}, and this is {}: run every shard and the merge with one csm-lab version",
                    m.tool,
                    tool()
                ),
            )
            .into());
        }
        if m.shard.n != m0.shard.n {
            return Err(ShardError::dir(
                &s.dir,
                format!(
                    "this shard is {} of {} shards, but {} is {} of {}: every shard must come from one split",
                    m.shard.k,
                    m.shard.n,
                    first.dir.display(),
                    m0.shard.k,
                    m0.shard.n
                ),
            )
            .into());
        }
        if m.config_hash != m0.config_hash || m.command != m0.command {
            return Err(ShardError::dir(
                &s.dir,
                format!(
                    "this shard is of another config or sweep than {} (config_hash {} running `{}`; \
                     {} running `{}`)",
                    first.dir.display(),
                    m.config_hash,
                    m.command,
                    m0.config_hash,
                    m0.command
                ),
            )
            .into());
        }
    }
    let n = m0.shard.n;
    let mut seen: Vec<Option<&std::path::Path>> = vec![None; n];
    for s in shards {
        let k = s.manifest.shard.k;
        if let Some(other) = seen[k - 1] {
            return Err(ShardError::dir(
                &s.dir,
                format!(
                    "shard {k} of {n} was given twice (also as {}); give each shard once",
                    other.display()
                ),
            )
            .into());
        }
        seen[k - 1] = Some(&s.dir);
    }
    let missing: Vec<String> = (1..=n)
        .filter(|k| seen[k - 1].is_none())
        .map(|k| k.to_string())
        .collect();
    if !missing.is_empty() {
        let shown = if missing.len() > 20 {
            format!("{}, ... ({} in all)", missing[..20].join(", "), missing.len())
        } else {
            missing.join(", ")
        };
        return Err(ShardError::Set(format!(
            "missing shard{} {shown} of {n}: merge needs all {n} shards of the sweep",
            if missing.len() == 1 { "" } else { "s" }
        ))
        .into());
    }
    Ok(m0)
}

/// The grid's rows, in grid order, from a complete set of shards ([`check_set`]); every row must
/// sit in its own shard and carry the setting of its place in `grid`.
pub(crate) fn join(shards: Vec<ShardInput>, grid: &Grid) -> Result<Vec<Row>> {
    let settings = grid.settings();
    let mut slots: Vec<Option<Row>> = vec![None; settings.len()];
    for s in shards {
        let shard = s.manifest.shard;
        let expected = shard.len_of(settings.len());
        if s.rows.len() != expected {
            return Err(ShardError::dir(
                &s.dir,
                format!(
                    "{ROWS_FILE} has {} rows; shard {} of {} of this grid has {expected}",
                    s.rows.len(),
                    shard.k,
                    shard.n
                ),
            )
            .into());
        }
        for (index, row) in s.rows {
            let place = settings.get(index).filter(|_| shard.contains(index));
            let same = place.is_some_and(|p| {
                p.lambda.to_bits() == row.setting.lambda.to_bits()
                    && p.cascades == row.setting.cascades
                    && p.resolution == row.setting.resolution
                    && p.fit == row.setting.fit
                    && p.split_range == row.setting.split_range
                    && p.knob.map(f64::to_bits) == row.setting.knob.map(f64::to_bits)
                    && p.distance.map(f64::to_bits) == row.setting.distance.map(f64::to_bits)
                    && p.sun.map(|s| (s.azimuth_deg.to_bits(), s.elevation_deg.to_bits()))
                        == row
                            .setting
                            .sun
                            .map(|s| (s.azimuth_deg.to_bits(), s.elevation_deg.to_bits()))
                    && p.light_update == row.setting.light_update
                    && p.update_every == row.setting.update_every
            });
            if !same || slots[index].is_some() {
                return Err(ShardError::dir(
                    &s.dir,
                    format!(
                        "{ROWS_FILE}: row {index} ({}) is not a row of shard {} of {} of this grid",
                        row.setting.label(),
                        shard.k,
                        shard.n
                    ),
                )
                .into());
            }
            slots[index] = Some(row);
        }
    }
    // Every slot is filled: each shard had exactly its count of distinct, in-shard indices.
    Ok(slots.into_iter().map(|r| r.expect("all shards present")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_specs_parse_and_bad_ones_name_the_flag() {
        assert_eq!(Shard::parse("1/1").unwrap(), Shard { k: 1, n: 1 });
        assert_eq!(Shard::parse(" 3 / 7 ").unwrap(), Shard { k: 3, n: 7 });
        for bad in ["", "1", "0/4", "5/4", "1/0", "a/4", "1/b", "-1/4", "1/100001", "1/2/3"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("--shard"), "{bad}: {e}");
        }
    }

    #[test]
    fn shards_are_disjoint_and_cover_the_grid() {
        for len in [1usize, 2, 7, 10, 672] {
            for n in 1..=len.min(9) {
                let mut count = vec![0; len];
                for k in 1..=n {
                    let s = Shard { k, n };
                    let idx: Vec<usize> = s.indices(len).collect();
                    assert_eq!(idx.len(), s.len_of(len));
                    for &i in &idx {
                        assert!(s.contains(i));
                        count[i] += 1;
                    }
                }
                assert!(count.iter().all(|&c| c == 1), "len {len}, n {n}");
            }
        }
    }
}
