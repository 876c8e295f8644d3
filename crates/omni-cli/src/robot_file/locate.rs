//! Finding fields in a robot file's TOML text: the field at an error's byte offset, and the bytes of a field
//! path.

use std::ops::Range;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// The path (`wheels[1].radius_m`) of the innermost key or array element that starts at or before
/// `span.start` (the last one before it in the text). Tables of an array (`[[wheels]]`) have spans
/// that do not cover their keys, so containment cannot be used.
pub fn path_at(text: &str, span: &Range<usize>) -> Option<String> {
    let root = DeTable::parse(text).ok()?;
    let mut path = String::new();
    walk_to(root.get_ref(), span.start, &mut path);
    (!path.is_empty()).then_some(path)
}

fn walk_to(table: &DeTable<'_>, at: usize, path: &mut String) {
    let last = table
        .iter()
        .map(|(k, v)| (k.span().start.min(v.span().start), k, v))
        .filter(|(start, _, _)| *start <= at)
        .max_by_key(|(start, _, _)| *start);
    if let Some((_, k, v)) = last {
        if !path.is_empty() {
            path.push('.');
        }
        path.push_str(k.get_ref());
        descend(v, at, path);
    }
}

fn descend(v: &Spanned<DeValue<'_>>, at: usize, path: &mut String) {
    match v.get_ref() {
        DeValue::Table(t) => walk_to(t, at, path),
        DeValue::Array(a) => {
            let last = a.iter().enumerate().filter(|(_, e)| e.span().start <= at).max_by_key(|(_, e)| e.span().start);
            if let Some((i, e)) = last {
                path.push_str(&format!("[{i}]"));
                descend(e, at, path);
            }
        }
        _ => {}
    }
}

/// The bytes of the field named by `path` (`wheels[2].radius_m`), or of the innermost part of it that
/// exists (the wheel's table when the key is missing).
pub fn span_of(text: &str, path: &str) -> Option<Range<usize>> {
    let root = DeTable::parse(text).ok()?;
    let mut table: &DeTable<'_> = root.get_ref();
    let mut found: Option<Range<usize>> = None;
    for part in path.split('.') {
        let (key, index) = match part.split_once('[') {
            Some((k, rest)) => (k, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        let Some((k, v)) = table.iter().find(|(k, _)| k.get_ref().as_ref() == key) else {
            return found;
        };
        found = Some(k.span());
        let value = match (index, v.get_ref()) {
            (Some(i), DeValue::Array(a)) => match a.get(i) {
                Some(e) => {
                    found = Some(e.span());
                    e
                }
                None => return found,
            },
            _ => v,
        };
        match value.get_ref() {
            DeValue::Table(t) => table = t,
            _ => return found,
        }
    }
    found
}
