//! Answers in each engine's own terms: a setting (the engine's knobs, cascade count, map size
//! and shadow distance) written in the engine's own configuration language, and read back.
//!
//! Each engine declares one [`Terms`] template: lines of its language with `{{field}}`
//! placeholders. [`Engine::terms`] fills the placeholders from the knobs; [`read`] matches a
//! text line by line against the same template (comment and blank lines skipped), so the
//! parser takes exactly what the writer writes, and [`Engine::from_terms`] turns the fields
//! back into knobs through the engine's own validation. Numbers are written in the shortest
//! form that reads back as the same f64. The formats, field by field: `docs/presets.md`,
//! "Engine settings files".

use std::cell::RefCell;

use crate::config::{Config, Validator};
use crate::error::{ConfigError, Error, PresetError, Result};

use super::*;

/// How an engine writes a setting in its own configuration language.
pub struct Terms {
    /// The language's line comment marker (`//`, `#`, `;`).
    pub comment: &'static str,
    /// The language and what the text sets, for the header line.
    pub language: &'static str,
    /// The lines, with `{{field}}` placeholders, in the order they are written and read.
    pub template: &'static str,
}

/// The cascade count, map size per cascade and shadow distance of a setting (None when the
/// engine has no shadow distance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dims {
    pub cascades: usize,
    pub resolution: u32,
    pub max_distance: Option<f64>,
}

impl Dims {
    /// The count, map size and (for an engine with one) shadow distance of a loaded config.
    pub(crate) fn of(config: &Config) -> Dims {
        let s = &config.shadow;
        let has_distance = s.preset.as_ref().is_none_or(|p| p.knobs.engine().has_distance());
        Dims {
            cascades: s.cascades,
            resolution: s.resolution,
            max_distance: has_distance.then_some(s.max_distance),
        }
    }
}

/// A number as written in every engine file: the shortest decimal that reads back as the same
/// f64, always with a `.` or an exponent (so that it is a float literal in Rust, C#, C++ too).
pub fn number(x: f64) -> String {
    format!("{x:?}")
}

/// The placeholders' values of a template, as text.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Values(pub Vec<(&'static str, String)>);

impl Values {
    pub(crate) fn new() -> Self {
        Values::default()
    }

    pub(crate) fn num(mut self, field: &'static str, x: f64) -> Self {
        self.0.push((field, number(x)));
        self
    }

    pub(crate) fn int(mut self, field: &'static str, n: impl std::fmt::Display) -> Self {
        self.0.push((field, n.to_string()));
        self
    }

    pub(crate) fn bool(mut self, field: &'static str, b: bool) -> Self {
        self.0.push((field, b.to_string()));
        self
    }

    pub(crate) fn word(mut self, field: &'static str, w: &str) -> Self {
        self.0.push((field, w.to_string()));
        self
    }

    /// Numbers separated by `, ` (a TOML array's or an argument list's inside).
    pub(crate) fn nums(mut self, field: &'static str, xs: &[f64]) -> Self {
        self.0
            .push((field, xs.iter().map(|x| number(*x)).collect::<Vec<_>>().join(", ")));
        self
    }

    fn get(&self, field: &str) -> Option<&str> {
        self.0.iter().find(|(f, _)| *f == field).map(|(_, v)| v.as_str())
    }
}

/// One part of a template line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Part<'t> {
    Text(&'t str),
    Slot(&'t str),
}

fn parts(line: &str) -> Vec<Part<'_>> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(i) = rest.find("{{") {
        let Some(j) = rest[i..].find("}}") else { break };
        if i > 0 {
            out.push(Part::Text(&rest[..i]));
        }
        out.push(Part::Slot(&rest[i + 2..i + j]));
        rest = &rest[i + j + 2..];
    }
    if !rest.is_empty() {
        out.push(Part::Text(rest));
    }
    out
}

/// The first line of every engine settings file.
const HEADER: &str = "csm-lab engine settings for ";

/// Writes a setting: the header, `comments` as comment lines, then the template filled in.
pub fn render(engine: &'static dyn DynEngine, values: &Values, comments: &[String]) -> String {
    let t = engine.terms();
    let mut out = format!("{} {HEADER}{} ({})\n", t.comment, engine.name(), t.language);
    for c in comments {
        out.push_str(&format!("{} {c}\n", t.comment));
    }
    for line in t.template.lines() {
        for p in parts(line) {
            match p {
                Part::Text(s) => out.push_str(s),
                Part::Slot(f) => out.push_str(
                    values
                        .get(f)
                        .unwrap_or_else(|| panic!("{}: no value for {f}", engine.name())),
                ),
            }
        }
        out.push('\n');
    }
    out
}

fn settings_error(
    path: &str,
    line: usize,
    column: usize,
    field: impl Into<String>,
    message: impl Into<String>,
) -> Error {
    Error::from(PresetError::Settings {
        path: path.to_string(),
        line,
        column,
        field: field.into(),
        message: message.into(),
    })
}

const COMMENTS: [&str; 3] = ["//", "#", ";"];

/// The engine an engine settings file is for, from its header line.
pub(crate) fn engine_of(text: &str, label: &str) -> Result<PresetName> {
    let Some((i, first)) = text.lines().enumerate().find(|(_, l)| !l.trim().is_empty()) else {
        return Err(settings_error(
            label,
            1,
            1,
            "header",
            "the file is empty; expected the engine settings csm-lab writes",
        ));
    };
    let trimmed = first.trim();
    let body = COMMENTS
        .iter()
        .find_map(|c| trimmed.strip_prefix(c))
        .map(str::trim_start);
    let Some(name) = body.and_then(|b| b.strip_prefix(HEADER)) else {
        return Err(settings_error(
            label,
            i + 1,
            1,
            "header",
            format!("expected the first line `// {HEADER}<engine> (...)` (with the engine's own comment marker) that csm-lab writes, found {trimmed:?}"),
        ));
    };
    let name = name.split_whitespace().next().unwrap_or("");
    PresetName::parse(name).ok_or_else(|| {
        settings_error(
            label,
            i + 1,
            1,
            "header",
            format!("unknown engine {name:?}; {}", unknown_name_message(name)),
        )
    })
}

/// One placeholder's text as read, and where.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Field {
    pub name: &'static str,
    pub raw: String,
    pub line: usize,
    pub column: usize,
}

/// The fields of an engine settings file, read against the engine's template; typed getters
/// with errors naming the file, line, column and field.
pub struct Fields<'a> {
    label: &'a str,
    fields: Vec<Field>,
    /// Config keys read from each field (for values the engine's validation refuses).
    keys: RefCell<Vec<(String, usize)>>,
}

impl Fields<'_> {
    fn at(&self, name: &str, key: &str) -> Result<&Field> {
        let i =
            self.fields.iter().position(|f| f.name == name).ok_or_else(|| {
                settings_error(self.label, 1, 1, name, "not in the engine's template (internal error)")
            })?;
        self.keys.borrow_mut().push((key.to_string(), i));
        Ok(&self.fields[i])
    }

    /// An error at a field.
    pub(crate) fn error(&self, f: &Field, message: impl Into<String>) -> Error {
        settings_error(self.label, f.line, f.column, format!("`{}`", f.name), message)
    }

    /// A finite number; `key` is the config key it becomes (for range errors).
    pub(crate) fn num(&self, name: &str, key: &str) -> Result<f64> {
        let f = self.at(name, key)?;
        parse_number(&f.raw).ok_or_else(|| self.error(f, format!("expected a number, found {:?}", f.raw)))
    }

    /// A whole number >= 0.
    pub(crate) fn int(&self, name: &str, key: &str) -> Result<u64> {
        let f = self.at(name, key)?;
        f.raw
            .parse::<u64>()
            .map_err(|_| self.error(f, format!("expected a whole number, found {:?}", f.raw)))
    }

    /// `true` or `false`.
    pub(crate) fn bool(&self, name: &str, key: &str) -> Result<bool> {
        let f = self.at(name, key)?;
        match f.raw.as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(self.error(f, format!("expected true or false, found {:?}", f.raw))),
        }
    }

    /// One of `words`, mapped to its value.
    pub(crate) fn word<T: Copy>(&self, name: &str, key: &str, words: &[(&str, T)]) -> Result<T> {
        let f = self.at(name, key)?;
        words.iter().find(|(w, _)| *w == f.raw).map(|(_, t)| *t).ok_or_else(|| {
            let list: Vec<String> = words.iter().map(|(w, _)| format!("{w:?}")).collect();
            self.error(f, format!("expected one of {}, found {:?}", list.join(", "), f.raw))
        })
    }

    /// Numbers separated by commas.
    pub(crate) fn nums(&self, name: &str, key: &str) -> Result<Vec<f64>> {
        let f = self.at(name, key)?;
        f.raw
            .split(',')
            .map(|s| parse_number(s.trim()))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| self.error(f, format!("expected numbers separated by commas, found {:?}", f.raw)))
    }

    /// A cascade count.
    pub(crate) fn count(&self, name: &str, key: &str) -> Result<usize> {
        Ok(usize::try_from(self.int(name, key)?).unwrap_or(usize::MAX))
    }

    /// A map size (texels); values beyond u32 are kept out of range for the range check.
    pub(crate) fn size(&self, name: &str, key: &str) -> Result<u32> {
        Ok(u32::try_from(self.int(name, key)?).unwrap_or(u32::MAX))
    }

    /// A map size that is `per` tiles of the cascade's map across (an atlas of 2 × 2 tiles:
    /// `per` = 2): the size of one tile, or an error when the atlas does not divide.
    pub(crate) fn tile(&self, name: &str, key: &str, per: u32) -> Result<u32> {
        let atlas = self.size(name, key)?;
        if atlas % per != 0 {
            let f = &self.fields[self.fields.iter().position(|f| f.name == name).unwrap_or(0)];
            return Err(self.error(
                f,
                format!("{atlas} does not hold {per} × {per} equal tiles; expected a multiple of {per}"),
            ));
        }
        Ok(atlas / per)
    }

    /// Three numbers separated by commas.
    pub(crate) fn vec3(&self, name: &str, key: &str) -> Result<[f64; 3]> {
        let v = self.nums(name, key)?;
        <[f64; 3]>::try_from(v.as_slice()).map_err(|_| {
            let f = &self.fields[self.fields.iter().position(|f| f.name == name).unwrap_or(0)];
            self.error(f, format!("expected three numbers, found {}", v.len()))
        })
    }

    /// A value the engine's validation refused (a `ConfigError::Invalid` naming a config key
    /// read from a field) re-pointed at that field's line; other errors pass unchanged.
    pub(crate) fn relocate(&self, e: Error) -> Error {
        let Error::Config(ConfigError::Invalid {
            key, value, allowed, ..
        }) = &e
        else {
            return e;
        };
        let keys = self.keys.borrow();
        let Some(&(_, i)) = keys.iter().find(|(k, _)| k == key) else {
            return e;
        };
        let f = &self.fields[i];
        settings_error(
            self.label,
            f.line,
            f.column,
            format!("`{}` ({key})", f.name),
            format!("{value} is not allowed: {allowed}"),
        )
    }
}

/// A finite number as the files write it (a trailing C#/C++ `f` is part of the template).
fn parse_number(s: &str) -> Option<f64> {
    let ok = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E'));
    s.parse::<f64>().ok().filter(|x| ok && x.is_finite())
}

/// Matches `text` line by line against `engine`'s template: comment and blank lines are
/// skipped, every other line must be the next template line with its placeholders filled.
pub fn read<'a>(engine: &'static dyn DynEngine, text: &str, label: &'a str) -> Result<Fields<'a>> {
    let t = engine.terms();
    let mut content = text.lines().enumerate().map(|(i, l)| (i + 1, l)).filter(|(_, l)| {
        let l = l.trim();
        !l.is_empty() && !l.starts_with(t.comment)
    });
    let mut fields = Vec::new();
    let last_line = text.lines().count();
    for tl in t.template.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let ps = parts(tl);
        let slots: Vec<&str> = ps
            .iter()
            .filter_map(|p| match p {
                Part::Slot(s) => Some(*s),
                Part::Text(_) => None,
            })
            .collect();
        let what = if slots.is_empty() {
            "line".to_string()
        } else {
            slots.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ")
        };
        let shown = tl.replace("{{", "<").replace("}}", ">");
        let Some((n, line)) = content.next() else {
            return Err(settings_error(
                label,
                last_line + 1,
                1,
                what,
                format!("expected `{shown}`, found the end of the file"),
            ));
        };
        let indent = line.len() - line.trim_start().len();
        let line = line.trim();
        let mismatch = |col: usize| {
            settings_error(
                label,
                n,
                indent + col + 1,
                what.clone(),
                format!(
                    "expected `{shown}` ({} writes this line so), found {line:?}",
                    engine.name()
                ),
            )
        };
        let mut pos = 0;
        for (k, p) in ps.iter().enumerate() {
            match p {
                Part::Text(s) => {
                    if !line[pos..].starts_with(s) {
                        return Err(mismatch(pos));
                    }
                    pos += s.len();
                }
                Part::Slot(name) => {
                    let end = match ps.get(k + 1) {
                        Some(Part::Text(next)) => match line[pos..].find(next) {
                            Some(i) => pos + i,
                            None => return Err(mismatch(pos)),
                        },
                        _ => line.len(),
                    };
                    let raw = line[pos..end].trim();
                    if raw.is_empty() {
                        return Err(mismatch(pos));
                    }
                    let name = engine_field(t, name);
                    fields.push(Field {
                        name,
                        raw: raw.to_string(),
                        line: n,
                        column: indent + pos + 1,
                    });
                    pos = end;
                }
            }
        }
        if pos != line.len() {
            return Err(mismatch(pos));
        }
    }
    if let Some((n, line)) = content.next() {
        return Err(settings_error(
            label,
            n,
            1,
            "line",
            format!(
                "unexpected {:?} after the last setting (only comments starting with `{}` may follow)",
                line.trim(),
                t.comment
            ),
        ));
    }
    Ok(Fields {
        label,
        fields,
        keys: RefCell::new(Vec::new()),
    })
}

/// The template's own `&'static str` for a placeholder name.
fn engine_field(t: &'static Terms, name: &str) -> &'static str {
    t.template
        .lines()
        .flat_map(parts)
        .find_map(|p| match p {
            Part::Slot(s) if s == name => Some(s),
            _ => None,
        })
        .unwrap_or("field")
}

/// Reads an engine settings file for `config`'s preset and puts its setting in place: the
/// knobs, cascade count, map size and shadow distance replace the config's `[<engine>]` table
/// and `[shadow]` values, through the engine's own validation. The file must be for the
/// config's preset.
pub fn apply_terms(config: &mut Config, text: &str, label: &str) -> Result<()> {
    let named = engine_of(text, label)?;
    let Some(preset) = &config.shadow.preset else {
        return Err(settings_error(
            label,
            1,
            1,
            "header",
            format!("the settings are for {named}, but no preset is applied"),
        ));
    };
    if preset.name != named {
        return Err(settings_error(
            label,
            1,
            1,
            "header",
            format!(
                "the settings are for {named}, but the preset is {}; use --preset {named}",
                preset.name
            ),
        ));
    }
    let engine = named.engine();
    let v = Validator { path: label, text: "" };
    let cx = KnobContext {
        v: &v,
        scene: &config.scene,
        light_direction: config.light_direction,
    };
    let fields = read(engine, text, label)?;
    let (knobs, dims) = engine.read_terms(&fields, &cx).map_err(|e| fields.relocate(e))?;
    let checked = (|| -> Result<()> {
        let counts = engine.counts(&knobs).list();
        if !counts.contains(&dims.cascades) {
            return Err(v.invalid(
                "shadow.cascades",
                dims.cascades,
                &format!("one of {} for {named}", join(&counts)),
            ));
        }
        if !(16..=16384).contains(&dims.resolution)
            || (engine.power_of_two_maps() && !dims.resolution.is_power_of_two())
        {
            let allowed = if engine.power_of_two_maps() {
                "a power of two in 16..=16384 (the engine requires powers of two)"
            } else {
                "a map size in 16..=16384"
            };
            return Err(v.invalid("shadow.resolution", dims.resolution, allowed));
        }
        if let Some(d) = dims.max_distance {
            if !(d > 0.0 && d <= crate::config::MAX_WORLD) {
                return Err(v.invalid("shadow.max_distance", d, "a distance in (0, 1e9]"));
            }
        }
        let max_distance = dims.max_distance.unwrap_or(config.shadow.max_distance);
        engine.check(&knobs, dims.cascades, max_distance, &v)?;
        let camera = &config.camera;
        let lay = engine.layout(&knobs, dims.cascades, max_distance, camera.near, camera.far);
        for (i, &(a, b)) in lay.fitted.iter().enumerate() {
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a) {
                return Err(v.invalid(
                    "shadow.cascades",
                    dims.cascades,
                    &format!("settings that give every cascade a slice with 0 <= near < far; cascade {i} would be [{a}, {b}]"),
                ));
            }
        }
        Ok(())
    })();
    checked.map_err(|e| fields.relocate(e))?;
    let shadow = &mut config.shadow;
    shadow.cascades = dims.cascades;
    shadow.resolution = dims.resolution;
    if let Some(d) = dims.max_distance {
        shadow.max_distance = d;
    }
    if let Some(l) = engine.lambda(&knobs) {
        shadow.lambda = l;
    }
    let p = shadow.preset.as_mut().expect("checked above");
    p.knobs = knobs;
    p.notes.push(format!(
        "engine settings read from {label}: they replace [{named}] and [shadow] cascades, resolution{}",
        if dims.max_distance.is_some() {
            ", max_distance"
        } else {
            ""
        }
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_so_they_read_back_exactly() {
        let mut rng = csm_core::rng::SplitMix64::new(3);
        for _ in 0..2000 {
            let x = rng.range(-1.0, 1.0) * 10f64.powi((rng.range(-12.0, 12.0)) as i32);
            let s = number(x);
            assert_eq!(parse_number(&s), Some(x), "{s}");
            assert!(s.contains('.') || s.contains('e'), "{s}");
        }
        assert_eq!(number(150.0), "150.0");
        assert_eq!(number(0.1), "0.1");
        assert_eq!(parse_number("inf"), None);
        assert_eq!(parse_number("NaN"), None);
        assert_eq!(parse_number("0x10"), None);
    }

    #[test]
    fn template_parts_split_placeholders_from_text() {
        assert_eq!(
            parts("a = new Vector3({{x}}f, {{y}}f);"),
            vec![
                Part::Text("a = new Vector3("),
                Part::Slot("x"),
                Part::Text("f, "),
                Part::Slot("y"),
                Part::Text("f);")
            ]
        );
        assert_eq!(parts("{{n}}"), vec![Part::Slot("n")]);
    }

    #[test]
    fn the_header_names_the_engine() {
        assert_eq!(
            engine_of("\n// csm-lab engine settings for bevy (Rust)\n", "f").unwrap(),
            PresetName::Bevy
        );
        assert_eq!(
            engine_of("; csm-lab engine settings for unreal", "f").unwrap(),
            PresetName::Unreal
        );
        let e = engine_of("# csm-lab engine settings for gdot (x)", "r.txt")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("r.txt:1:1: header: unknown engine \"gdot\"") && e.contains("\"godot\""),
            "{e}"
        );
        let e = engine_of("hello", "r.txt").unwrap_err().to_string();
        assert!(e.starts_with("r.txt:1:1: header:"), "{e}");
        assert!(engine_of("  \n", "r.txt").is_err());
    }
}
