//! Typed errors, one enum per domain. Every variant names what the user should change: the
//! config key (with its line and column when we can find it), the command-line flag, or the
//! file. All of them map to exit code 2 in the binary.

use std::path::{Path, PathBuf};

/// Everything that can go wrong, by domain.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Config(#[from] ConfigError),

    #[error(transparent)]
    Grid(#[from] GridError),

    #[error(transparent)]
    Preset(#[from] PresetError),

    #[error(transparent)]
    Baseline(#[from] BaselineError),

    #[error(transparent)]
    Plot(#[from] PlotError),

    #[error(transparent)]
    Shard(#[from] ShardError),

    #[error(transparent)]
    Io(#[from] IoError),

    /// A value that would have been written as NaN or infinity. This is a bug guard: it
    /// should never fire, and if it does no output file is touched.
    #[error("internal error: {what} is not finite ({value}); no file was written")]
    NonFinite { what: String, value: f64 },
}

/// A scene or thresholds file: TOML syntax, unknown keys, wrong types, values out of range.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The TOML text does not parse, or a key is unknown or has the wrong type.
    #[error("{path}:{line}:{column}: {message}{excerpt}")]
    Toml {
        path: String,
        line: usize,
        column: usize,
        message: String,
        /// The source line with a caret under the problem, as cargo shows it
        /// (`config::excerpt`), or empty.
        excerpt: String,
    },

    /// A value parsed but is not allowed.
    #[error("{location}`{key}` = {value} is not allowed: {allowed}{excerpt}")]
    Invalid {
        /// `file:line:column: ` or `file: ` or empty.
        location: String,
        key: String,
        value: String,
        allowed: String,
        /// The source line with a caret under the value, as cargo shows it
        /// (`config::excerpt`), or empty.
        excerpt: String,
    },
}

/// A command-line value (a sweep spec, a count, a flag that does not fit the command).
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// A flag's value does not parse or is out of range.
    #[error("{flag} {value:?}: {message}")]
    Flag {
        flag: String,
        value: String,
        message: String,
    },

    /// A sweep axis holds a value the engine preset does not accept.
    #[error("{source_key} = {spec}: {message}")]
    Axis {
        /// The flag or config key that gave the axis (`--cascades`, `sweep.cascades`).
        source_key: String,
        spec: String,
        message: String,
    },

    /// The sweep grid is larger than `sweep.max_configs`.
    #[error(
        "the sweep grid has {configs} configurations ({lambdas} λ × {counts} cascade counts × {resolutions} resolutions × {fits} fits{extra}), \
         more than sweep.max_configs = {max}; narrow an axis (--lambda, --cascades, --resolution, --fit{more_flags}) \
         or raise sweep.max_configs"
    )]
    TooLarge {
        configs: usize,
        lambdas: usize,
        counts: usize,
        resolutions: usize,
        fits: usize,
        /// " × N knob values × M distances" when those axes are swept, else empty.
        extra: String,
        /// ", --knob, --distance" for the swept ones, else empty.
        more_flags: String,
        max: usize,
    },

    /// The inputs parse but leave the command nothing to do.
    #[error("{context}: {message}")]
    Unusable { context: String, message: String },

    /// One point of a sweep that its config cannot hold.
    #[error("sweep point {point}: {source}")]
    Point { point: String, source: Box<Error> },
}

/// An engine preset that does not exist or cannot do what was asked.
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    /// A preset name that is not one of the engines.
    #[error("{key} {value:?}: {message}")]
    Unknown {
        /// The flag or config key that named it.
        key: String,
        value: String,
        message: String,
    },

    /// A sweep value outside the range of its axis.
    #[error("{axis} {value} is outside {range}")]
    OutOfRange {
        axis: &'static str,
        value: String,
        range: &'static str,
    },

    /// A cascade count outside csm-lab's own range.
    #[error("{count} cascades is outside 1..=16")]
    CascadeCount { count: usize },

    /// A λ sweep over a preset whose split rule has no λ.
    #[error("the {preset} preset has no λ to sweep ({split_rule}); remove the lambda axis")]
    NoLambda { preset: String, split_rule: String },

    /// A knob sweep over a preset without a split knob.
    #[error("the {preset} preset has no split knob to sweep; drop --knob / sweep.knob")]
    NoKnob { preset: String },

    /// A knob value outside the engine's range.
    #[error("{key} = {value} is outside the allowed range {range}")]
    KnobRange {
        key: &'static str,
        value: String,
        range: String,
    },

    /// A distance sweep over a preset that has no shadow distance.
    #[error("the {preset} preset has no shadow distance (it shadows to camera.far); drop --distance / sweep.distance")]
    NoDistance { preset: String },

    /// A cascade count the preset does not offer.
    #[error("the {preset} preset does not take {count} cascades (valid: {valid})")]
    Cascades {
        preset: String,
        count: usize,
        valid: String,
    },

    /// A map size the preset does not accept.
    #[error("the {preset} preset takes power-of-two map sizes only, not {size}")]
    MapSize { preset: String, size: u32 },

    /// An engine settings file (`recommendation.<engine>.txt`) that is not what csm-lab
    /// writes, or holds a value the engine does not take.
    #[error("{path}:{line}:{column}: {field}: {message}")]
    Settings {
        path: String,
        line: usize,
        column: usize,
        /// The field in the engine's own terms (and its config key), or "header".
        field: String,
        message: String,
    },
}

/// A baseline (`summary.json` or `sweep.csv`) that cannot be compared against.
#[derive(Debug, thiserror::Error)]
pub enum BaselineError {
    /// The baseline does not fit the current run.
    #[error("{}: {message}", path.display())]
    Mismatch { path: PathBuf, message: String },

    /// The baseline's content is not what a baseline of this kind holds.
    #[error("{label}: {message}")]
    Invalid { label: String, message: String },

    /// A sweep table with two rows for one configuration.
    #[error("the {which} sweep table has two rows for {key}; each configuration must appear once")]
    DuplicateRow { which: String, key: String },
}

/// Shards of a sweep that cannot be merged (`sweep --shard`, `merge`).
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// One shard directory: not a shard, unreadable, or not of the same sweep as the others.
    #[error("merge: {}: {message}", dir.display())]
    Dir { dir: PathBuf, message: String },

    /// The set of shards as a whole (missing shards, none given).
    #[error("merge: {0}")]
    Set(String),
}

impl ShardError {
    pub(crate) fn dir(dir: &Path, message: impl Into<String>) -> Self {
        ShardError::Dir {
            dir: dir.to_path_buf(),
            message: message.into(),
        }
    }
}

/// A figure that could not be drawn or rasterised.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The plotting backend failed while drawing.
    #[error("plot: {0}")]
    Draw(String),

    /// An SVG could not be rasterised.
    #[error("SVG to PNG: {0}")]
    Rasterise(String),

    /// The PNG encoder failed.
    #[error("PNG encoding: {0}")]
    Png(String),
}

/// Files and streams.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    #[error("cannot read {}: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },

    #[error("cannot write {}: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },

    /// A malformed row in a camera path file or another data file.
    #[error("{}:{line}: {message}", path.display())]
    DataFile {
        path: PathBuf,
        line: usize,
        message: String,
    },

    /// A file larger than what its kind may be: refused before it is read.
    #[error("{}: {size} bytes is too large for {what} (at most {max} bytes); nothing was read", path.display())]
    TooLarge {
        path: PathBuf,
        what: &'static str,
        size: u64,
        max: u64,
    },

    #[error("cannot write to standard output: {0}")]
    Stdout(std::io::Error),

    /// A CSV or JSON encoder failed.
    #[error("{format} encoding failed: {message}")]
    Encode { format: &'static str, message: String },
}

impl Error {
    /// The message without a config error's source excerpt: one line, for one-line reports
    /// (`stress.csv` and its table).
    pub(crate) fn without_excerpt(&self) -> String {
        let text = self.to_string();
        match self {
            Error::Config(ConfigError::Invalid { excerpt, .. } | ConfigError::Toml { excerpt, .. }) => text
                .strip_suffix(excerpt.as_str())
                .map_or_else(|| text.clone(), str::to_string),
            _ => text,
        }
    }

    pub fn read(path: &Path, source: std::io::Error) -> Self {
        IoError::Read {
            path: path.to_path_buf(),
            source,
        }
        .into()
    }

    pub(crate) fn write(path: &Path, source: std::io::Error) -> Self {
        IoError::Write {
            path: path.to_path_buf(),
            source,
        }
        .into()
    }

    pub(crate) fn flag(flag: &str, value: &str, message: impl Into<String>) -> Self {
        GridError::Flag {
            flag: flag.to_string(),
            value: value.to_string(),
            message: message.into(),
        }
        .into()
    }

    pub(crate) fn data_file(path: &Path, line: usize, message: impl Into<String>) -> Self {
        IoError::DataFile {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
        .into()
    }

    pub fn invalid(location: String, key: &str, value: impl std::fmt::Display, allowed: impl Into<String>) -> Self {
        ConfigError::Invalid {
            location,
            key: key.to_string(),
            value: value.to_string(),
            allowed: allowed.into(),
            excerpt: String::new(),
        }
        .into()
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Refuse to let a non-finite number reach an output file.
pub(crate) fn ensure_finite(what: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NonFinite {
            what: what.to_string(),
            value,
        })
    }
}
