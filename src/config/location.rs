//! Where in the file a problem is: line and column of a byte offset, of a `table.key` or a
//! `[table]` header, and the [`Validator`] that builds "value not allowed" errors from them.

use glam::DVec3;
use toml::Spanned;

use crate::error::{ConfigError, Error, Result};

use super::MAX_WORLD;

/// Byte offset to 1-based (line, column), counting columns in characters.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = text[line_start..offset].chars().count() + 1;
    (line, column)
}

/// Turn a `toml` deserialisation error into one with the file's line and column.
/// A value of the wrong type or length (`position = [0, 10]`) is reported with its key
/// (`` `camera.position`: invalid length 2, ... ``); errors about a key itself name it already.
pub fn toml_error(path: &str, text: &str, err: &toml::de::Error) -> Error {
    let (line, column) = err.span().map(|span| line_column(text, span.start)).unwrap_or((1, 1));
    let message = err.message().trim();
    let message = match err.span().and_then(|span| key_of_value_at(text, span.start)) {
        Some(key) => format!("`{key}`: {message}"),
        None => message.to_string(),
    };
    Error::from(ConfigError::Toml {
        path: path.to_string(),
        line,
        column,
        message,
    })
}

/// The dotted key (`table.key`) whose value starts the line holding byte `offset`, when
/// `offset` lies in that value (after the `=`): None for a position in a key, a header or a
/// continuation line of a multi-line array.
pub fn key_of_value_at(text: &str, offset: usize) -> Option<String> {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next().unwrap_or("");
    let eq = line.find('=')?;
    if line_start + eq >= offset {
        return None;
    }
    let key = line[..eq].trim();
    let bare = |s: &str| {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '"' | '\'' | ' '))
    };
    if !bare(key) {
        return None;
    }
    let table = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']').trim());
    Some(match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key.to_string(),
    })
}

/// Finds where `table.key = ...` is written, for error messages about values that parsed
/// but are out of range. Returns 1-based (line, column) of the key, if found.
pub fn locate_key(text: &str, dotted: &str) -> Option<(usize, usize)> {
    let (table, key) = match dotted.rsplit_once('.') {
        Some((t, k)) => (t, k),
        None => ("", dotted),
    };
    let mut current = String::new();
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix('[') {
            let rest = rest.trim_start_matches('[');
            if let Some(end) = rest.find(']') {
                current = rest[..end].trim().to_string();
            }
            continue;
        }
        if current != table {
            continue;
        }
        if let Some(after) = trimmed.strip_prefix(key) {
            if after.trim_start().starts_with('=') {
                let column = line.len() - trimmed.len() + 1;
                return Some((i + 1, column));
            }
        }
    }
    None
}

/// 1-based line and column of a `[name]` table header.
pub fn locate_table(text: &str, name: &str) -> Option<(usize, usize)> {
    text.lines().enumerate().find_map(|(i, line)| {
        let t = line.trim_start();
        let rest = t.strip_prefix('[')?;
        let end = rest.find(']')?;
        (rest[..end].trim() == name).then(|| (i + 1, line.len() - t.len() + 1))
    })
}

/// Builds "value not allowed" errors that point at the key in the file.
pub struct Validator<'a> {
    pub path: &'a str,
    pub text: &'a str,
}

impl Validator<'_> {
    pub fn invalid(&self, key: &str, value: impl std::fmt::Display, allowed: &str) -> Error {
        let location = match (self.path.is_empty(), locate_key(self.text, key)) {
            (_, Some((line, column))) if !self.path.is_empty() => {
                format!("{}:{line}:{column}: ", self.path)
            }
            (_, Some((line, column))) => format!("line {line}, column {column}: "),
            (false, None) => format!("{}: ", self.path),
            (true, None) => String::new(),
        };
        Error::from(ConfigError::Invalid {
            location,
            key: key.to_string(),
            value: value.to_string(),
            allowed: allowed.to_string(),
        })
    }

    pub fn finite(&self, key: &str, v: f64) -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(key, v, "a finite number"))
        }
    }

    pub fn vec3(&self, key: &str, v: [f64; 3]) -> Result<DVec3> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(DVec3::from_array(v))
        } else {
            Err(self.invalid(key, format!("{v:?}"), "three finite numbers"))
        }
    }

    /// Three finite numbers, none beyond [`MAX_WORLD`] in magnitude.
    pub fn point(&self, key: &str, v: [f64; 3]) -> Result<DVec3> {
        let p = self.vec3(key, v)?;
        if p.abs().max_element() <= MAX_WORLD {
            Ok(p)
        } else {
            Err(self.invalid(key, format!("{v:?}"), "three numbers within ±1e9 world units"))
        }
    }

    /// The value of an enum-valued key: one of `names`, or an error at the value naming the key
    /// and every allowed name.
    pub fn one_of<T: Copy>(&self, key: &str, value: &Spanned<String>, names: &[(&str, T)]) -> Result<T> {
        if let Some((_, t)) = names.iter().find(|(n, _)| *n == value.get_ref().as_str()) {
            return Ok(*t);
        }
        let list: Vec<String> = names.iter().map(|(n, _)| format!("{n:?}")).collect();
        Err(self.invalid_at(
            key,
            value.span().start,
            format!("{:?}", value.get_ref()),
            &format!("one of {}", list.join(", ")),
        ))
    }

    /// Like [`Validator::invalid`], located at a byte offset of the text.
    pub fn invalid_at(&self, key: &str, offset: usize, value: impl std::fmt::Display, allowed: &str) -> Error {
        let (line, column) = line_column(self.text, offset);
        let location = if self.path.is_empty() {
            format!("line {line}, column {column}: ")
        } else {
            format!("{}:{line}:{column}: ", self.path)
        };
        Error::from(ConfigError::Invalid {
            location,
            key: key.to_string(),
            value: value.to_string(),
            allowed: allowed.to_string(),
        })
    }

    pub fn int_range(&self, key: &str, v: i64, lo: i64, hi: i64) -> Result<i64> {
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.invalid(key, v, &format!("an integer in {lo}..={hi}")))
        }
    }
}
