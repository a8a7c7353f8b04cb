//! Where in a scene file a refusal belongs: the line of the key an error names, and parse errors said
//! in the format's own words.
//!
//! A [`SceneError`] found after parsing names a dotted key path (`section[1].material.
//! youngs_modulus_pa`, `tendon[0].end_m`, `output.s_m[3]`). [`locate`] finds that key's line in the
//! text, or, for a key left at its default, the line of the nearest table that is written (the
//! `[[tendon]]` header of `tendon[0].end_m`). The TOML parser's own messages about the scene's tables
//! (`duplicate key` for `[cable]` written twice, `invalid type: map, expected a sequence` for a
//! single `[cable]`, `missing field` pointed at line 1) are rewritten by [`explain_parse`] to say
//! which brackets the table takes.

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use super::SceneError;

/// The tables a scene may repeat: `[[name]]`, each one item.
const ARRAY_TABLES: [&str; 4] = ["section", "cable", "tendon", "load"];

/// The tables a scene has at most once: `[name]`.
const SINGLE_TABLES: [&str; 10] = [
    "base",
    "guides",
    "actuation",
    "tip",
    "output",
    "solver",
    "estimate",
    "estimate.tendons",
    "drive",
    "controller",
];

/// The line (from 1) of byte `offset` in `text`, and that line trimmed.
fn line_at(text: &str, offset: usize) -> (usize, &str) {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    (line, text.lines().nth(line - 1).unwrap_or("").trim())
}

/// `origin, line N (`content`)`.
pub(super) fn place(text: &str, origin: &str, offset: usize) -> String {
    let (line, content) = line_at(text, offset);
    format!("{origin}, line {line} (`{content}`)")
}

/// One step of a key path: a key, and an index into its array if the path gives one.
fn steps(path: &str) -> Vec<(&str, Option<usize>)> {
    path.split('.')
        .map(|part| match part.split_once('[') {
            Some((key, rest)) => (key, rest.trim_end_matches(']').parse().ok()),
            None => (part, None),
        })
        .collect()
}

/// The byte offset of the deepest part of `path` written in the file: the key itself, else the
/// table (or array item) that would hold it. `None` when not even its first key is written, when
/// the path names an array of tables without an item, or the text does not parse.
fn offset_of(text: &str, path: &str) -> Option<usize> {
    let root = DeTable::parse(text).ok()?;
    let mut table: &DeTable<'_> = root.get_ref();
    let mut found = None;
    for (key, index) in steps(path) {
        let Some((k, value)) = table.iter().find(|(k, _)| k.get_ref().as_ref() == key) else {
            return found;
        };
        // The key's own position (`[[tendon]]` items carry no key: the header's span is the value's).
        found = Some(k.span().start);
        let mut value: &Spanned<DeValue<'_>> = value;
        match (value.get_ref(), index) {
            (DeValue::Array(items), Some(i)) => {
                let Some(item) = items.get(i) else {
                    return found;
                };
                found = Some(item.span().start);
                value = item;
            }
            // A path into an array of tables without an index (`cable.end_m`) names no item: its
            // first table's line would blame the wrong one, so the error keeps no place.
            (DeValue::Array(_), None) if ARRAY_TABLES.contains(&key) => return None,
            _ => {}
        }
        match value.get_ref() {
            DeValue::Table(inner) => table = inner,
            _ => return found,
        }
    }
    found
}

/// `error` with its place in `text` (the file `origin`) when its field is a key path the file has:
/// `origin, line N (`content`): field: reason`. Any other error (a command-line option, a parse
/// error that already has its place) comes back as it was.
pub fn locate(error: SceneError, text: &str, origin: &str) -> SceneError {
    // A key path: lower-case keys, dots and indices (a file name or an option has other characters).
    let is_key = error.field.starts_with(|c: char| c.is_ascii_lowercase())
        && error
            .field
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || "_.[]".contains(c));
    match offset_of(text, &error.field).filter(|_| is_key) {
        Some(offset) => SceneError::new(
            format!("{}: {}", place(text, origin, offset), error.field),
            error.reason,
        ),
        None => error,
    }
}

/// The parser's message for the table at `line` (its trimmed text) said in the scene's words, if it
/// is one of the bracket mix-ups: `[cable]` for `[[cable]]`, `[[tip]]` for `[tip]`.
fn explain_brackets(line: &str, message: &str) -> Option<String> {
    let single = line
        .strip_prefix('[')
        .and_then(|l| l.strip_suffix(']'))
        .filter(|l| !l.starts_with('['));
    let double = line.strip_prefix("[[").and_then(|l| l.strip_suffix("]]"));
    if let Some(name) = single.map(str::trim)
        && ARRAY_TABLES.contains(&name)
        && (message.contains("duplicate key") || message.contains("expected a sequence"))
    {
        return Some(format!(
            "`[{name}]` is a single table, but a scene lists each {name} in its own `[[{name}]]` \
             table (double brackets), even when there is one"
        ));
    }
    if let Some(name) = double.map(str::trim)
        && SINGLE_TABLES.contains(&name)
    {
        return Some(format!(
            "`[[{name}]]` makes a list of tables, but a scene has one `[{name}]` table (single \
             brackets)"
        ));
    }
    None
}

/// A TOML parse or type error as a [`SceneError`]: at its line, and in the scene's words where the
/// parser's are about brackets or a missing table.
pub(super) fn explain_parse(error: &toml::de::Error, text: &str, origin: &str) -> SceneError {
    let message = error.message().trim_end();
    if let Some(field) = message
        .strip_prefix("missing field `")
        .and_then(|m| m.strip_suffix('`'))
        && ARRAY_TABLES.contains(&field)
        && error.span().is_none_or(|s| s.start == 0)
    {
        // Serde points a missing top-level table at the whole file, which reads as line 1.
        return SceneError::new(
            origin,
            format!(
                "no `[[{field}]]` table: a scene needs at least one (the rod from base to tip, \
                 one table per section; host-sim/SCENES.md)"
            ),
        );
    }
    match error.span() {
        Some(span) => {
            let (_, line) = line_at(text, span.start);
            let reason = explain_brackets(line, message).unwrap_or_else(|| message.to_string());
            SceneError::new(place(text, origin, span.start), reason)
        }
        None => SceneError::new(origin, message),
    }
}
