//! Locating what is wrong in a TOML file: the project file's text and
//! spans, shared by `[check]` (project) and `[[images]]` (images::config).

use std::ops::Range;

use toml_edit::{Item, Value};

use crate::diag::{Code, Diagnostic, LineIndex, Location};

/// The project file's text, for locating what is wrong in it.
pub struct Source<'a> {
    display: &'a str,
    text: &'a str,
    lines: LineIndex,
}

impl<'a> Source<'a> {
    pub fn new(display: &'a str, text: &'a str) -> Self {
        Source { display, text, lines: LineIndex::new(text) }
    }

    pub fn location(&self, span: Option<Range<usize>>) -> Location {
        match span {
            Some(s) => self.lines.location(self.display, self.text, s),
            None => Location::file_start(self.display),
        }
    }

    /// A `project-file` error at `span`.
    pub fn error(&self, span: Option<Range<usize>>, message: String) -> Diagnostic {
        let d = Diagnostic::error(Code::ProjectFile, message);
        match span {
            Some(_) => d.with_label(self.location(span), "here", true),
            None => d.at(self.location(None)),
        }
    }
}

/// An array of strings with each one's span; `None` for anything else.
pub fn strings(value: &Value) -> Option<Vec<(String, Option<Range<usize>>)>> {
    value.as_array()?.iter().map(|v| v.as_str().map(|s| (s.to_owned(), v.span()))).collect()
}

pub fn span_of(item: &Item) -> Option<Range<usize>> {
    match item {
        Item::Value(v) => v.span(),
        Item::Table(t) => t.span(),
        Item::ArrayOfTables(a) => a.span(),
        Item::None => None,
    }
}
