//! The scene file as a spanned TOML document. Owns the byte-offset bookkeeping: it parses the
//! text once, indexes every key and value by its field path (`objects[2].radius`), and turns
//! either a path or a TOML error span into a [`SceneError`] with file, line and field. It knows
//! nothing about what the fields mean (that is `format` and `validate`) and must not read other
//! files.

use super::SceneError;
use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;
use toml::de::{DeTable, DeValue, ValueDeserializer};

/// A TOML value with its byte span in the scene text.
pub(crate) type Value<'t> = Spanned<DeValue<'t>>;

/// One key or array element of the document, found by its field path.
struct Node {
    path: String,
    key_span: Option<Range<usize>>,
    value_span: Range<usize>,
    is_table: bool,
}

pub(crate) struct Document<'t> {
    file: PathBuf,
    text: &'t str,
    root: DeTable<'t>,
    nodes: Vec<Node>,
}

fn is_bare_key(word: &str) -> bool {
    !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// `` `a`, `b`, `c` ``
pub(crate) fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `parent.key`, quoting keys that are not bare TOML keys.
pub(crate) fn child_path(parent: &str, key: &str) -> String {
    let key = if is_bare_key(key) {
        key.to_string()
    } else {
        format!("{key:?}")
    };
    if parent.is_empty() {
        key
    } else {
        format!("{parent}.{key}")
    }
}

impl<'t> Document<'t> {
    /// Parses `text` (the contents of `file`); a syntax error names the line it is on.
    pub(crate) fn parse(file: &Path, text: &'t str) -> Result<Self, SceneError> {
        // The recovering parser keeps what it could read, so a syntax error can still be
        // attributed to the key it sits in.
        let (root, errors) = DeTable::parse_recoverable(text);
        let mut doc = Document {
            file: file.to_path_buf(),
            text,
            root: root.into_inner(),
            nodes: Vec::new(),
        };
        doc.index();
        match errors
            .iter()
            .min_by_key(|e| e.span().map_or(0, |s| s.start))
        {
            Some(first) => Err(doc.syntax_error(first)),
            None => Ok(doc),
        }
    }

    pub(crate) fn root(&self) -> &DeTable<'t> {
        &self.root
    }

    fn index(&mut self) {
        let mut nodes = vec![Node {
            path: String::new(),
            key_span: None,
            value_span: 0..0,
            is_table: true,
        }];
        for (key, value) in self.root.iter() {
            index_value(
                &mut nodes,
                child_path("", key.get_ref()),
                Some(key.span()),
                value,
            );
        }
        self.nodes = nodes;
    }

    /// 1-based line holding byte `offset`.
    /// `file:line` of the field at `path`, for reports.
    pub(crate) fn place(&self, path: &str) -> String {
        format!(
            "{}:{}",
            self.file.display(),
            self.line_of(self.offset_of(path))
        )
    }

    pub(crate) fn line_of(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    }

    /// An error about the field at `path`. When the field is absent (a missing field) the line
    /// is that of its nearest enclosing table or array element.
    pub(crate) fn error(&self, path: &str, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.clone(),
            line: Some(self.line_of(self.offset_of(path))),
            column: None,
            field: path.to_string(),
            message: message.into(),
        }
    }

    fn offset_of(&self, path: &str) -> usize {
        let mut probe = path;
        loop {
            if let Some(node) = self.nodes.iter().find(|n| n.path == probe) {
                return node.value_span.start;
            }
            match parent_path(probe) {
                Some(parent) => probe = parent,
                None => return 0,
            }
        }
    }

    /// Converts a TOML deserialization error (unknown field, missing field, wrong type) into a
    /// [`SceneError`] on the field its span points at.
    pub(crate) fn toml_error(&self, err: &toml::de::Error) -> SceneError {
        let span = err.span().unwrap_or(0..0);
        let mut path = self.path_at(&span);
        let mut message = err.message().to_string();
        // serde reports a missing field on the table that lacks it; name the field itself.
        if let Some(missing) = message
            .strip_prefix("missing field `")
            .and_then(|rest| rest.strip_suffix('`'))
        {
            path = child_path(&path, missing);
            message = "missing field".to_string();
        }
        SceneError {
            file: self.file.clone(),
            line: Some(self.line_of(span.start)),
            column: None,
            field: display_path(&path),
            message,
        }
    }

    fn syntax_error(&self, err: &toml::de::Error) -> SceneError {
        let span = err.span().unwrap_or(0..0);
        // Name the deepest key enclosing the error; failing that (the parser dropped the
        // broken entry), the table it is in, plus the key it stumbled on.
        let path = self
            .deepest(|n| n.key_span.is_some() && spans_contain(n, span.start))
            .unwrap_or_else(|| {
                let table = self.table_before(span.start);
                match self.text.get(span.clone()).map(str::trim) {
                    Some(word) if is_bare_key(word) => child_path(table, word),
                    _ => table.to_string(),
                }
            });
        SceneError {
            file: self.file.clone(),
            line: Some(self.line_of(span.start)),
            column: None,
            field: display_path(&path),
            message: format!("TOML syntax error: {}", err.message()),
        }
    }

    /// The path of the table whose header (or inline start) most closely precedes `offset`.
    fn table_before(&self, offset: usize) -> &str {
        self.nodes
            .iter()
            .filter(|n| n.is_table && !n.path.is_empty() && n.value_span.start <= offset)
            .max_by_key(|n| (n.value_span.start, n.path.len()))
            .map_or("", |n| n.path.as_str())
    }

    /// The path of the deepest node whose key or value span is exactly `span`, else of the
    /// deepest node enclosing its start.
    fn path_at(&self, span: &Range<usize>) -> String {
        self.deepest(|n| n.value_span == *span || n.key_span.as_ref() == Some(span))
            .or_else(|| self.deepest(|n| spans_contain(n, span.start)))
            .unwrap_or_default()
    }

    fn deepest(&self, wanted: impl Fn(&Node) -> bool) -> Option<String> {
        // Paths of nested nodes extend their parents' paths, so the longest is the deepest.
        self.nodes
            .iter()
            .filter(|n| !n.path.is_empty() && wanted(n))
            .max_by_key(|n| n.path.len())
            .map(|n| n.path.clone())
    }

    /// Deserializes one value into a format struct, mapping serde errors onto field paths.
    pub(crate) fn deserialize<T: Deserialize<'t>>(
        &self,
        value: &Value<'t>,
    ) -> Result<T, SceneError> {
        T::deserialize(ValueDeserializer::from(value.clone())).map_err(|e| self.toml_error(&e))
    }

    /// Splits a `type = "..."`-tagged table at `path` into its kind (one of `kinds`) and the
    /// table without the tag, ready for [`Document::deserialize`].
    pub(crate) fn tagged(
        &self,
        path: &str,
        value: &Value<'t>,
        kinds: &[&'static str],
    ) -> Result<(&'static str, Value<'t>), SceneError> {
        let expected = quoted_list(kinds);
        let DeValue::Table(table) = value.get_ref() else {
            return Err(self.error(
                path,
                format!("expected a table, found {}", value.get_ref().type_str()),
            ));
        };
        let type_path = child_path(path, "type");
        let Some(tag) = table.get("type") else {
            return Err(self.error(&type_path, format!("missing field (one of {expected})")));
        };
        let Some(name) = tag.get_ref().as_str() else {
            return Err(self.error(&type_path, format!("expected a string (one of {expected})")));
        };
        let Some(kind) = kinds.iter().find(|k| **k == name) else {
            return Err(self.error(
                &type_path,
                format!("unknown type `{name}`, expected one of {expected}"),
            ));
        };
        let mut rest = table.clone();
        rest.remove("type");
        Ok((kind, Spanned::new(value.span(), DeValue::Table(rest))))
    }
}

fn index_value(nodes: &mut Vec<Node>, path: String, key_span: Option<Range<usize>>, value: &Value) {
    nodes.push(Node {
        path: path.clone(),
        key_span,
        value_span: value.span(),
        is_table: matches!(value.get_ref(), DeValue::Table(_)),
    });
    match value.get_ref() {
        DeValue::Table(table) => {
            for (key, child) in table.iter() {
                index_value(
                    nodes,
                    child_path(&path, key.get_ref()),
                    Some(key.span()),
                    child,
                );
            }
        }
        DeValue::Array(array) => {
            for (i, child) in array.iter().enumerate() {
                index_value(nodes, format!("{path}[{i}]"), None, child);
            }
        }
        _ => {}
    }
}

fn spans_contain(node: &Node, offset: usize) -> bool {
    let contains = |s: &Range<usize>| s.start <= offset && offset < s.end;
    contains(&node.value_span) || node.key_span.as_ref().is_some_and(contains)
}

/// `a.b[2]` → `a.b`, `a.b` → `a`, `a` → the root (""), the root → none.
fn parent_path(path: &str) -> Option<&str> {
    if path.is_empty() {
        return None;
    }
    if path.ends_with(']') {
        return path.rfind('[').map(|open| &path[..open]);
    }
    // A quoted key may contain dots; skip back over it.
    let search_end = match path.strip_suffix('"') {
        Some(quoted) => quoted.rfind('"').unwrap_or(0),
        None => path.len(),
    };
    Some(path[..search_end].rfind('.').map_or("", |dot| &path[..dot]))
}

fn display_path(path: &str) -> String {
    if path.is_empty() {
        "(document)".to_string()
    } else {
        path.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parent_paths_step_out_one_level() {
        assert_eq!(
            parent_path("objects[2].center[1]"),
            Some("objects[2].center")
        );
        assert_eq!(parent_path("objects[2].center"), Some("objects[2]"));
        assert_eq!(parent_path("objects[2]"), Some("objects"));
        assert_eq!(parent_path("objects"), Some(""));
        assert_eq!(parent_path(""), None);
        assert_eq!(parent_path("materials.\"a.b\""), Some("materials"));
    }

    #[test]
    fn unknown_field_names_its_key_and_line() {
        #[derive(Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Probe {
            radius: f32,
        }
        let text = "[[objects]]\nradius = 1\n\n[[objects]]\nradius = 2\nradiuss = 3\n";
        let doc = Document::parse(Path::new("probe.toml"), text).unwrap();
        let DeValue::Array(objects) = doc.root().get("objects").unwrap().get_ref() else {
            panic!("objects is an array");
        };
        let err = doc.deserialize::<Probe>(&objects[1]).unwrap_err();
        assert_eq!(err.field, "objects[1].radiuss");
        assert_eq!(err.line, Some(6));
    }

    #[test]
    fn syntax_error_names_its_line() {
        let err = Document::parse(Path::new("s.toml"), "[camera]\nfov_y = 4 0\n")
            .err()
            .unwrap();
        assert_eq!(err.line, Some(2));
        assert!(err.message.contains("syntax"), "{}", err.message);
    }
}
