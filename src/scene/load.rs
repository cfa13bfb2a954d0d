//! Scene text -> format structs, with every error placed at its file, line and field.
//!
//! serde reports the byte span of a bad value; validation reports a field path such as
//! `shapes[2].radius`, which [`SpanIndex`] maps back to its line with toml's spanned parser.
//! `--set key=value` overrides are applied to the parsed table, and errors in values they set
//! say so instead of pointing into the file.

use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};

use super::format::SceneFile;
use crate::error::{Error, Location, Result};

/// A parsed scene file, still unvalidated, with what is needed to place later errors.
pub struct ParsedScene {
    pub file: SceneFile,
    pub path: PathBuf,
    pub spans: SpanIndex,
    /// Field paths set by `--set` (normalised to `a[0].b` form).
    pub overridden: Vec<String>,
}

impl ParsedScene {
    /// An error about `field` (a path like `shapes[2].radius`).
    pub fn error(&self, field: &str, message: impl Into<String>) -> Error {
        let (line, column) = if self.overridden.iter().any(|o| is_within(field, o)) {
            (0, 0)
        } else {
            self.spans.line_col(field)
        };
        Error::Scene {
            location: Location {
                file: self.path.clone(),
                line,
                column,
                field: field.to_string(),
            },
            message: message.into(),
        }
    }
}

pub fn parse_scene_file(path: &Path, overrides: &[String]) -> Result<ParsedScene> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = std::str::from_utf8(&bytes).map_err(|e| invalid_utf8(path, &bytes, e))?;
    parse_scene_text(path, text, overrides)
}

/// The scene file at `path` with `overrides` applied, as TOML text (its comments and layout are
/// not kept: the text is the merged table written out).
pub fn merged_scene_text(path: &Path, overrides: &[String]) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = std::str::from_utf8(&bytes).map_err(|e| invalid_utf8(path, &bytes, e))?;
    // Parsing first places a syntax error in the file at its line.
    let parsed = parse_scene_text(path, text, &[])?;
    let mut table: toml::Table =
        toml::from_str(text).map_err(|e| parsed.error("", e.message().trim()))?;
    apply_overrides(&mut table, overrides)?;
    toml::to_string(&table).map_err(|e| Error::Override {
        key: overrides.join(" "),
        message: e.to_string(),
    })
}

/// The line and column (in bytes) of the first byte that is not UTF-8.
fn invalid_utf8(path: &Path, bytes: &[u8], e: std::str::Utf8Error) -> Error {
    let offset = e.valid_up_to();
    let before = &bytes[..offset];
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    Error::Scene {
        location: Location {
            file: path.to_path_buf(),
            line: 1 + before.iter().filter(|&&b| b == b'\n').count(),
            column: offset - line_start + 1,
            field: String::new(),
        },
        message: format!(
            "byte 0x{:02x} is not valid UTF-8: a scene file is UTF-8 text",
            bytes[offset]
        ),
    }
}

pub fn parse_scene_text(path: &Path, text: &str, overrides: &[String]) -> Result<ParsedScene> {
    let spans = SpanIndex::new(text);
    let syntax_error = |e: toml::de::Error| {
        let offset = e.span().map_or(0, |s| s.start);
        let (line, column) = spans.offset_to_line_col(offset);
        Error::Scene {
            location: Location {
                file: path.to_path_buf(),
                line,
                column,
                field: spans.field_at(offset, e.message()),
            },
            message: e.message().trim().to_string(),
        }
    };
    // The file alone first, so that its own errors keep their positions.
    let file: SceneFile = toml::from_str(text).map_err(syntax_error)?;
    if overrides.is_empty() {
        return Ok(ParsedScene {
            file,
            path: path.to_path_buf(),
            spans,
            overridden: Vec::new(),
        });
    }
    let mut table: toml::Table = toml::from_str(text).map_err(syntax_error)?;
    let overridden = apply_overrides(&mut table, overrides)?;
    let mut parsed = ParsedScene {
        file,
        path: path.to_path_buf(),
        spans,
        overridden,
    };
    parsed.file = parse_with_overrides(&parsed, &table)?;
    Ok(parsed)
}

/// Sets each `key=value` of `overrides` in `table`; returns the keys, normalised.
fn apply_overrides(table: &mut toml::Table, overrides: &[String]) -> Result<Vec<String>> {
    let mut keys = Vec::with_capacity(overrides.len());
    for item in overrides {
        let (key, value) = parse_override(item)?;
        set_path(table, &key, value).map_err(|message| Error::Override {
            key: key.clone(),
            message,
        })?;
        keys.push(normalise_path(&key));
    }
    Ok(keys)
}

/// The scene with its overrides applied, read back from TOML text so that an error in an
/// overridden value is placed at its field like an error in the file (serde reports a span in
/// text, but nothing for a value built in memory).
fn parse_with_overrides(parsed: &ParsedScene, table: &toml::Table) -> Result<SceneFile> {
    let merged = toml::to_string(table).map_err(|e| Error::Override {
        key: parsed.overridden.join(" "),
        message: e.to_string(),
    })?;
    toml::from_str(&merged).map_err(|e| {
        let merged_spans = SpanIndex::new(&merged);
        let offset = e.span().map_or(0, |s| s.start);
        let field = merged_spans.field_at(offset, e.message());
        parsed.error(&field, e.message().trim())
    })
}

/// Whether `field` is the path `outer` or lies inside it (`render.spp` is not inside `render.sp`).
fn is_within(field: &str, outer: &str) -> bool {
    field
        .strip_prefix(outer)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
}

/// Split `key=value`; the value is read as a TOML value (`16`, `2.8`, `[0, 1, 0]`, `"x"`), and
/// as a bare string when it is not one (`pixel_sampler=random`).
pub fn parse_override(item: &str) -> Result<(String, toml::Value)> {
    let Some((key, raw)) = item.split_once('=') else {
        return Err(Error::Override {
            key: item.to_string(),
            message: "expected key=value, e.g. render.spp=64".into(),
        });
    };
    let key = key.trim().to_string();
    let raw = raw.trim();
    let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()));
    Ok((key, value))
}

/// `shapes.0.radius` and `shapes[0].radius` both become `shapes[0].radius`.
fn normalise_path(key: &str) -> String {
    let mut out = String::new();
    for segment in path_segments(key) {
        match segment {
            Segment::Key(k) => {
                if !out.is_empty() {
                    out.push('.');
                }
                out += &k;
            }
            Segment::Index(i) => out += &format!("[{i}]"),
        }
    }
    out
}

enum Segment {
    Key(String),
    Index(usize),
}

fn path_segments(path: &str) -> Vec<Segment> {
    let mut segments = Vec::new();
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let mut rest = part;
        if let Some(open) = rest.find('[') {
            segments.push(Segment::Key(rest[..open].to_string()));
            rest = &rest[open..];
            while let Some(close) = rest.find(']') {
                if let Ok(i) = rest[1..close].parse() {
                    segments.push(Segment::Index(i));
                }
                rest = &rest[close + 1..];
            }
        } else if let Ok(i) = rest.parse() {
            segments.push(Segment::Index(i));
        } else {
            segments.push(Segment::Key(rest.to_string()));
        }
    }
    segments
}

fn set_path(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let segments = path_segments(key);
    let Some((Segment::Key(section), rest)) = segments.split_first() else {
        return Err("a key starts with a section name, e.g. render.spp".into());
    };
    if rest.is_empty() {
        table.insert(section.clone(), value);
        return Ok(());
    }
    let slot = table
        .entry(section.clone())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    set_in_value(slot, rest, value)
}

fn set_in_value(
    target: &mut toml::Value,
    segments: &[Segment],
    value: toml::Value,
) -> Result<(), String> {
    let Some((first, rest)) = segments.split_first() else {
        return Err("empty key".into());
    };
    let slot = match (first, target) {
        (Segment::Key(k), toml::Value::Table(t)) => {
            if rest.is_empty() {
                t.insert(k.clone(), value);
                return Ok(());
            }
            t.entry(k.clone())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        }
        (Segment::Index(i), toml::Value::Array(a)) if *i < a.len() => {
            if rest.is_empty() {
                a[*i] = value;
                return Ok(());
            }
            &mut a[*i]
        }
        (Segment::Key(k), _) => return Err(format!("`{k}` is not inside a table")),
        (Segment::Index(i), _) => return Err(format!("index {i} is out of range")),
    };
    set_in_value(slot, rest, value)
}

/// Byte spans of every key and value of the scene text, to map field paths to lines.
pub struct SpanIndex {
    line_starts: Vec<usize>,
    /// (field path, byte offset of its value)
    fields: Vec<(String, std::ops::Range<usize>)>,
}

impl SpanIndex {
    pub fn new(text: &str) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        let mut fields = Vec::new();
        if let Ok(root) = DeTable::parse(text) {
            collect_spans(root.get_ref(), "", &mut fields);
        }
        SpanIndex {
            line_starts,
            fields,
        }
    }

    pub fn offset_to_line_col(&self, offset: usize) -> (usize, usize) {
        let line = self.line_starts.partition_point(|&s| s <= offset);
        (line, offset - self.line_starts[line - 1] + 1)
    }

    /// Line and column of a field, or of its closest enclosing field when it is absent.
    pub fn line_col(&self, field: &str) -> (usize, usize) {
        let mut path = field.to_string();
        loop {
            if let Some((_, span)) = self.fields.iter().find(|(p, _)| *p == path) {
                return self.offset_to_line_col(span.start);
            }
            match path.rfind(['.', '[']) {
                Some(cut) => path.truncate(cut),
                None => return (1, 1),
            }
        }
    }

    /// The field a serde error is about: the unknown field it names, else the innermost field
    /// whose value contains the error offset.
    pub fn field_at(&self, offset: usize, message: &str) -> String {
        let innermost = self
            .fields
            .iter()
            .filter(|(_, span)| span.contains(&offset))
            .min_by_key(|(_, span)| span.len())
            .map(|(p, _)| p.clone())
            .unwrap_or_default();
        if let Some(rest) = message.strip_prefix("unknown field `")
            && let Some(name) = rest.split('`').next()
        {
            // The unknown key has a span of its own, which may be the innermost one already.
            if innermost.is_empty() {
                return name.to_string();
            }
            if innermost == name || innermost.ends_with(&format!(".{name}")) {
                return innermost;
            }
            return format!("{innermost}.{name}");
        }
        innermost
    }
}

fn collect_spans(
    table: &DeTable<'_>,
    prefix: &str,
    out: &mut Vec<(String, std::ops::Range<usize>)>,
) {
    for (key, value) in table.iter() {
        let path = if prefix.is_empty() {
            key.get_ref().to_string()
        } else {
            format!("{prefix}.{}", key.get_ref())
        };
        // Point at the key: that is the line a reader looks for.
        let span = key.span().start..value.span().end.max(key.span().end);
        out.push((path.clone(), span));
        collect_value_spans(value.get_ref(), &path, out);
    }
}

fn collect_value_spans(
    value: &DeValue<'_>,
    path: &str,
    out: &mut Vec<(String, std::ops::Range<usize>)>,
) {
    match value {
        DeValue::Table(t) => collect_spans(t, path, out),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let item_path = format!("{path}[{i}]");
                out.push((item_path.clone(), item.span()));
                collect_value_spans(item.get_ref(), &item_path, out);
            }
        }
        _ => {}
    }
}
