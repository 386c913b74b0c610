//! [`SceneError`], and how a byte span of the scene text becomes a line, a column and the
//! dotted path of the field (e.g. `body["rodB"].joint.angle`).

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};

use crate::math::Shown;
use crate::model::ModelError;

/// A scene that cannot be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file cannot be read.
    #[error("{path}: cannot read the scene: {error}", path = path.display())]
    Io {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// A syntax error, a type error, an unknown or missing field, or a value that fails
    /// validation, located in the file.
    #[error("{path}:{line}:{column}: {field}: {message}", path = path.display())]
    At {
        /// The scene file.
        path: PathBuf,
        /// Line, from 1.
        line: usize,
        /// Column (in characters), from 1.
        column: usize,
        /// Dotted path of the field, e.g. `body["rodB"].joint.angle` (`(file)` if the error
        /// is not inside a field).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The model builder rejected the scene (a check the scene loader does not repeat).
    /// No longer produced: such errors are located at the body or obstacle they name
    /// ([`SceneError::At`]); kept for the callers that match on it.
    #[error("{path}: {error}", path = path.display())]
    Model {
        /// The scene file.
        path: PathBuf,
        /// The model error.
        error: ModelError,
    },
}

impl SceneError {
    /// The line of a located error.
    pub fn line(&self) -> Option<usize> {
        match self {
            SceneError::At { line, .. } => Some(*line),
            _ => None,
        }
    }

    /// The field path of a located error.
    pub fn field(&self) -> Option<&str> {
        match self {
            SceneError::At { field, .. } => Some(field),
            _ => None,
        }
    }
}

/// Turns spans of one scene text into located errors.
pub(super) struct Locator<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

impl Locator<'_> {
    /// A located error at `span` saying `message`.
    pub fn at(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        let start = span.start.min(self.text.len());
        let before = &self.text[..start];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = self.text[line_start..start].chars().count() + 1;
        let field = field_path(self.text, start);
        SceneError::At {
            path: self.path.to_owned(),
            line,
            column,
            field: if field.is_empty() {
                "(file)".into()
            } else {
                field
            },
            message: message.into(),
        }
    }

    /// A located error from a TOML parse or deserialization error.
    pub fn toml(&self, err: &toml::de::Error) -> SceneError {
        self.at(
            err.span().unwrap_or(0..0),
            shown_floats(err.message().trim_end()),
        )
    }
}

/// `message` with the numbers that serde quotes as ``floating point `…` `` shown as
/// [`Shown`] does: serde writes every digit (`1e308` as 309 of them), while the file said
/// `1e308`.
fn shown_floats(message: &str) -> String {
    const QUOTE: &str = "floating point `";
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(i) = rest.find(QUOTE) {
        let (head, tail) = rest.split_at(i + QUOTE.len());
        out.push_str(head);
        let end = tail.find('`').unwrap_or(tail.len());
        match tail[..end].parse::<f64>() {
            Ok(x) => out.push_str(&Shown(x).to_string()),
            Err(_) => out.push_str(&tail[..end]),
        }
        rest = &tail[end..];
    }
    out.push_str(rest);
    out
}

/// The dotted path of the innermost key or value of `text` that contains the byte
/// `offset`, e.g. `body["rodB"].joint.angle` or `contact.pair[0].between[1]`. Elements of
/// arrays of tables are named by their `name` field when they have one.
fn field_path(text: &str, offset: usize) -> String {
    let (root, _) = DeTable::parse_recoverable(text);
    let mut path = String::new();
    search_table(root.get_ref(), offset, &mut path);
    path
}

fn search_table(table: &DeTable<'_>, offset: usize, path: &mut String) -> bool {
    for (key, value) in table.iter() {
        let len = path.len();
        if !path.is_empty() {
            path.push('.');
        }
        path.push_str(key.get_ref());
        if key.span().contains(&offset) || search_value(value, offset, path) {
            return true;
        }
        path.truncate(len);
    }
    false
}

fn search_value(value: &toml::Spanned<DeValue<'_>>, offset: usize, path: &mut String) -> bool {
    match value.get_ref() {
        DeValue::Table(t) => search_table(t, offset, path) || value.span().contains(&offset),
        DeValue::Array(a) => {
            for (i, elem) in a.iter().enumerate() {
                let len = path.len();
                match elem
                    .get_ref()
                    .as_table()
                    .and_then(|t| t.get("name"))
                    .and_then(|n| n.get_ref().as_str())
                {
                    Some(name) => path.push_str(&format!("[{name:?}]")),
                    None => path.push_str(&format!("[{i}]")),
                }
                if search_value(elem, offset, path) {
                    return true;
                }
                path.truncate(len);
            }
            value.span().contains(&offset)
        }
        _ => value.span().contains(&offset),
    }
}
