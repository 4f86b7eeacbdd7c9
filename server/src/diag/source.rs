//! Original source text, kept so diagnostics can show excerpts and byte
//! offsets can become line:column.

use std::collections::BTreeMap;
use std::sync::Arc;

use super::Location;

/// Byte offset → (line, column) for one text. Columns count characters.
#[derive(Debug, Clone)]
pub struct LineIndex {
    /// Byte offset of the start of every line.
    starts: Vec<usize>,
}

impl LineIndex {
    pub fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { starts }
    }

    /// 1-based line and character column of a byte offset, clamped to the
    /// text (spans past the end point at the end).
    pub fn line_col(&self, text: &str, offset: usize) -> (u32, u32) {
        let offset = offset.min(text.len());
        let line = self.starts.partition_point(|&s| s <= offset) - 1;
        let start = self.starts[line];
        let mut end = offset;
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        let col = text[start..end].chars().count();
        (line as u32 + 1, col as u32 + 1)
    }

    pub fn location(&self, file: &str, text: &str, range: std::ops::Range<usize>) -> Location {
        let (line, column) = self.line_col(text, range.start);
        let (end_line, end_column) = self.line_col(text, range.end.max(range.start));
        Location { file: file.to_owned(), line, column, end_line, end_column }
    }

    pub fn line_count(&self) -> usize {
        self.starts.len()
    }
}

/// The texts of the files diagnostics point into, by display path.
#[derive(Debug, Clone, Default)]
pub struct SourceFiles {
    files: BTreeMap<String, Arc<str>>,
}

impl SourceFiles {
    pub fn insert(&mut self, path: impl Into<String>, text: Arc<str>) {
        self.files.insert(path.into(), text);
    }

    pub fn get(&self, path: &str) -> Option<&str> {
        self.files.get(path).map(|t| &**t)
    }

    /// The text of `line` (1-based) of `path`, without its newline.
    pub fn line(&self, path: &str, line: u32) -> Option<&str> {
        self.get(path)?.lines().nth(line.checked_sub(1)? as usize)
    }
}
