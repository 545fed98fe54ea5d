//! Where in the file a problem is: line and column of a byte offset, of a `table.key` or a
//! `[table]` header, and the [`Validator`] that builds "value not allowed" errors from them.

use std::ops::Range;

use annotate_snippets::{Level, Renderer, Snippet};
use glam::DVec3;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::error::{ConfigError, Error, Result};

use super::MAX_WORLD;

/// Byte offset to 1-based (line, column), counting columns in characters.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
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
pub(crate) fn toml_error(path: &str, text: &str, err: &toml::de::Error) -> Error {
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
        excerpt: err.span().map(|span| excerpt(text, span)).unwrap_or_default(),
    })
}

/// The dotted key (`table.key`) whose value starts the line holding byte `offset`, when
/// `offset` lies in that value (after the `=`): None for a position in a key, a header or a
/// continuation line of a multi-line array.
pub(crate) fn key_of_value_at(text: &str, offset: usize) -> Option<String> {
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

/// Where a key is written, as the TOML parser read it: byte ranges of the key and of its value.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Place {
    pub key: Range<usize>,
    pub value: Range<usize>,
}

/// Finds where `table.key` (or the table `table`) is written, by the spans of the TOML parser
/// (`toml::de::DeTable`, the parser `toml::from_str` uses): None when the text does not parse
/// or holds no such key. Every line and column of a config error comes from such a span.
pub(crate) fn locate(text: &str, dotted: &str) -> Option<Place> {
    let doc = DeTable::parse(text).ok()?;
    let parts: Vec<&str> = dotted.split('.').collect();
    locate_in(doc.get_ref(), &parts)
}

/// [`locate`] below one table. A part `name[i]` is entry `i` of the array of tables `name`;
/// a plain name of an array of tables (`[[scene.box]]`) is its first entry holding the rest of
/// the path.
fn locate_in(table: &DeTable<'_>, parts: &[&str]) -> Option<Place> {
    let (first, rest) = parts.split_first()?;
    let (name, index) = match first.split_once('[') {
        Some((name, i)) => (name, Some(i.strip_suffix(']')?.parse::<usize>().ok()?)),
        None => (*first, None),
    };
    let (key, value) = table.get_key_value(name)?;
    if rest.is_empty() {
        return Some(Place {
            key: key.span(),
            value: value.span(),
        });
    }
    let in_entry = |item: &toml::Spanned<DeValue<'_>>| match item.get_ref() {
        DeValue::Table(t) => locate_in(t, rest),
        _ => None,
    };
    match (value.get_ref(), index) {
        (DeValue::Table(t), None) => locate_in(t, rest),
        (DeValue::Array(items), None) => items.iter().find_map(in_entry),
        (DeValue::Array(items), Some(i)) => items.get(i).and_then(in_entry),
        _ => None,
    }
}

/// Finds where `table.key = ...` is written, for error messages about values that parsed
/// but are out of range. Returns 1-based (line, column) of the key, if found.
pub(crate) fn locate_key(text: &str, dotted: &str) -> Option<(usize, usize)> {
    locate(text, dotted).map(|p| line_column(text, p.key.start))
}

/// 1-based line and column of a `[name]` table header (its opening bracket).
pub(crate) fn locate_table(text: &str, name: &str) -> Option<(usize, usize)> {
    let key = locate(text, name)?.key;
    let bracket = text[..key.start].rfind('[')?;
    let (line, column) = line_column(text, bracket);
    (line == line_column(text, key.start).0).then_some((line, column))
}

/// The source line holding `span`, with carets under the span (its first line when it runs
/// over several), rendered the way cargo shows it (annotate-snippets); empty for an empty text.
/// Printed after an error's first line.
pub(crate) fn excerpt(text: &str, span: Range<usize>) -> String {
    let start = span.start.min(text.len());
    if text.is_empty() || !text.is_char_boundary(start) {
        return String::new();
    }
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let line = text[line_start..line_end].trim_end_matches('\r');
    let end = span.end.clamp(start, line_start + line.len());
    let (number, _) = line_column(text, start);
    let message = Level::Error.title("").snippet(
        Snippet::source(line)
            .line_start(number)
            .annotation(Level::Error.span(start - line_start..end - line_start)),
    );
    let rendered = Renderer::plain().render(message).to_string();
    // Drop the title line: the error's own first line stands in its place.
    match rendered.split_once('\n') {
        Some((_, rest)) => format!("\n{}", rest.trim_end()),
        None => String::new(),
    }
}

/// Builds "value not allowed" errors that point at the key in the file.
pub struct Validator<'a> {
    pub path: &'a str,
    pub text: &'a str,
}

impl Validator<'_> {
    /// A value not allowed, located at its key, with the value underlined.
    pub(crate) fn invalid(&self, key: &str, value: impl std::fmt::Display, allowed: &str) -> Error {
        self.invalid_found(key, key, value, allowed)
    }

    /// [`Validator::invalid`] for a key found at another path than its name: an entry of an
    /// array of tables (`scene.box[6].max` for box 7's `scene.box.max`).
    pub(crate) fn invalid_found(&self, key: &str, path: &str, value: impl std::fmt::Display, allowed: &str) -> Error {
        let place = locate(self.text, path);
        let at = place.as_ref().map(|p| p.key.start);
        self.error(key, at, place.map(|p| p.value), value, allowed)
    }

    /// The "not allowed" error: `file:line:column: ` of byte `at` (of the file alone when
    /// unknown), and the excerpt with `underline` marked.
    fn error(
        &self,
        key: &str,
        at: Option<usize>,
        underline: Option<Range<usize>>,
        value: impl std::fmt::Display,
        allowed: &str,
    ) -> Error {
        let location = match at.map(|offset| line_column(self.text, offset)) {
            Some((line, column)) if !self.path.is_empty() => format!("{}:{line}:{column}: ", self.path),
            Some((line, column)) => format!("line {line}, column {column}: "),
            None if !self.path.is_empty() => format!("{}: ", self.path),
            None => String::new(),
        };
        Error::from(ConfigError::Invalid {
            location,
            key: key.to_string(),
            value: value.to_string(),
            allowed: allowed.to_string(),
            excerpt: underline.map(|span| excerpt(self.text, span)).unwrap_or_default(),
        })
    }

    pub(crate) fn finite(&self, key: &str, v: f64) -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(key, v, "a finite number"))
        }
    }

    pub(crate) fn vec3(&self, key: &str, v: [f64; 3]) -> Result<DVec3> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(DVec3::from_array(v))
        } else {
            Err(self.invalid(key, format!("{v:?}"), "three finite numbers"))
        }
    }

    /// Three finite numbers, none beyond [`MAX_WORLD`] in magnitude.
    pub(crate) fn point(&self, key: &str, v: [f64; 3]) -> Result<DVec3> {
        let p = self.vec3(key, v)?;
        if p.abs().max_element() <= MAX_WORLD {
            Ok(p)
        } else {
            Err(self.invalid(key, format!("{v:?}"), "three numbers within ±1e9 world units"))
        }
    }

    /// The value of an enum-valued key: one of `names`, or an error at the value naming the key
    /// and every allowed name.
    pub(crate) fn one_of<T: Copy>(&self, key: &str, value: &Spanned<String>, names: &[(&str, T)]) -> Result<T> {
        if let Some((_, t)) = names.iter().find(|(n, _)| *n == value.get_ref().as_str()) {
            return Ok(*t);
        }
        let list: Vec<String> = names.iter().map(|(n, _)| format!("{n:?}")).collect();
        Err(self.invalid_at(
            key,
            value.span(),
            format!("{:?}", value.get_ref()),
            &format!("one of {}", list.join(", ")),
        ))
    }

    /// Like [`Validator::invalid`], located at the value's span in the text.
    pub(crate) fn invalid_at(
        &self,
        key: &str,
        span: Range<usize>,
        value: impl std::fmt::Display,
        allowed: &str,
    ) -> Error {
        self.error(key, Some(span.start), Some(span), value, allowed)
    }

    pub(crate) fn int_range(&self, key: &str, v: i64, lo: i64, hi: i64) -> Result<i64> {
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.invalid(key, v, &format!("an integer in {lo}..={hi}")))
        }
    }
}
