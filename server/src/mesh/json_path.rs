//! Paths to elements of a glTF document (`meshes[0].primitives[1].mode`):
//! they name the element in messages, and `locate` finds where the element
//! is written in the .gltf text so a diagnostic can point at it. serde keeps
//! no spans, so the text is scanned again, only along the one path.

use std::fmt;
use std::ops::Range;

#[derive(Debug, Clone, PartialEq, Eq)]
enum Segment {
    /// A member of an object, written `.name`.
    Field(&'static str),
    /// A member of a map keyed by data (attribute semantics), written `["NAME"]`.
    Key(&'static str),
    Index(usize),
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct JsonPath(Vec<Segment>);

impl JsonPath {
    /// A top-level property: `JsonPath::top("scene")`.
    pub fn top(name: &'static str) -> Self {
        JsonPath(vec![Segment::Field(name)])
    }

    /// An element of a top-level array: `JsonPath::element("accessors", 3)`.
    pub fn element(array: &'static str, index: usize) -> Self {
        Self::top(array).index(index)
    }

    pub fn field(&self, name: &'static str) -> Self {
        self.with(Segment::Field(name))
    }

    pub fn key(&self, name: &'static str) -> Self {
        self.with(Segment::Key(name))
    }

    pub fn index(&self, index: usize) -> Self {
        self.with(Segment::Index(index))
    }

    fn with(&self, segment: Segment) -> Self {
        let mut path = self.clone();
        path.0.push(segment);
        path
    }

    /// The byte range of the value at this path in `text`, a JSON document
    /// serde has already accepted; where the path runs out (an optional
    /// property left out), the range of the deepest value that is there.
    pub fn locate(&self, text: &str) -> Range<usize> {
        let b = text.as_bytes();
        let mut start = skip_ws(b, 0);
        for segment in &self.0 {
            let found = match segment {
                Segment::Field(name) | Segment::Key(name) => member(b, start, name),
                Segment::Index(i) => element(b, start, *i),
            };
            match found {
                Some(s) => start = s,
                None => break,
            }
        }
        start..value_end(b, start)
    }
}

impl fmt::Display for JsonPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, segment) in self.0.iter().enumerate() {
            match segment {
                Segment::Field(name) if i == 0 => write!(f, "{name}")?,
                Segment::Field(name) => write!(f, ".{name}")?,
                Segment::Key(name) => write!(f, "[\"{name}\"]")?,
                Segment::Index(index) => write!(f, "[{index}]")?,
            }
        }
        Ok(())
    }
}

fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while b.get(i).is_some_and(|c| matches!(c, b' ' | b'\t' | b'\r' | b'\n')) {
        i += 1;
    }
    i
}

/// Just past the string starting at `b[i]` (a quote).
fn string_end(b: &[u8], mut i: usize) -> usize {
    i += 1;
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    b.len()
}

/// Just past the value starting at `b[i]`. Every step moves forward, so it
/// ends on any input, valid JSON or not.
fn value_end(b: &[u8], mut i: usize) -> usize {
    match b.get(i) {
        Some(b'"') => string_end(b, i),
        Some(b'{' | b'[') => {
            let mut depth = 0usize;
            while i < b.len() {
                match b[i] {
                    b'"' => {
                        i = string_end(b, i);
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return i + 1;
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
            b.len()
        }
        _ => {
            while b.get(i).is_some_and(|c| !matches!(c, b',' | b'}' | b']' | b' ' | b'\t' | b'\r' | b'\n')) {
                i += 1;
            }
            i
        }
    }
}

/// Where the value of member `name` of the object at `b[i]` starts. Keys are
/// compared as written: glTF's keys need no escapes.
fn member(b: &[u8], i: usize, name: &str) -> Option<usize> {
    if b.get(i) != Some(&b'{') {
        return None;
    }
    let mut i = skip_ws(b, i + 1);
    while b.get(i) == Some(&b'"') {
        let key_end = string_end(b, i);
        let key = &b[i + 1..key_end.saturating_sub(1).max(i + 1)];
        i = skip_ws(b, key_end);
        if b.get(i) != Some(&b':') {
            return None;
        }
        i = skip_ws(b, i + 1);
        if key == name.as_bytes() {
            return Some(i);
        }
        i = skip_ws(b, value_end(b, i));
        if b.get(i) != Some(&b',') {
            return None;
        }
        i = skip_ws(b, i + 1);
    }
    None
}

/// Where element `n` of the array at `b[i]` starts.
fn element(b: &[u8], i: usize, n: usize) -> Option<usize> {
    if b.get(i) != Some(&b'[') {
        return None;
    }
    let mut i = skip_ws(b, i + 1);
    for _ in 0..n {
        if matches!(b.get(i), None | Some(b']')) {
            return None;
        }
        i = skip_ws(b, value_end(b, i));
        if b.get(i) != Some(&b',') {
            return None;
        }
        i = skip_ws(b, i + 1);
    }
    if matches!(b.get(i), None | Some(b']')) { None } else { Some(i) }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = r#"{ "asset": {"version": "2.0"},
  "meshes": [ { "primitives": [ {"attributes": {"POSITION": 0}},
                                {"attributes": {"POSITION": 1, "NORMAL": 2}, "mode": 1 } ] } ],
  "buffers": [ { "uri": "a\"b.bin", "byteLength": 12 } ] }"#;

    fn text_at(path: &JsonPath) -> &'static str {
        &DOC[path.locate(DOC)]
    }

    #[test]
    fn finds_members_elements_and_keys() {
        let prim = JsonPath::element("meshes", 0).field("primitives").index(1);
        assert_eq!(text_at(&prim.field("mode")), "1");
        assert_eq!(text_at(&prim.field("attributes").key("NORMAL")), "2");
        assert_eq!(text_at(&JsonPath::element("buffers", 0).field("uri")), r#""a\"b.bin""#);
        assert_eq!(text_at(&JsonPath::element("buffers", 0).field("byteLength")), "12");
        assert_eq!(prim.field("attributes").key("NORMAL").to_string(), r#"meshes[0].primitives[1].attributes["NORMAL"]"#);
    }

    #[test]
    fn missing_parts_fall_back_to_the_deepest_existing_value() {
        let prim0 = JsonPath::element("meshes", 0).field("primitives").index(0);
        assert!(text_at(&prim0.field("mode")).starts_with(r#"{"attributes": {"POSITION": 0}}"#));
        assert!(text_at(&JsonPath::element("meshes", 0).field("primitives").index(7)).starts_with("[ {"));
        assert!(text_at(&JsonPath::top("nodes")).starts_with("{ \"asset\""));
    }

    #[test]
    fn ends_on_broken_text() {
        for text in ["", "{", "{\"a\"", "[1,", "{\"meshes\": [", "\"unterminated", "{\"meshes\":}"] {
            let range = JsonPath::element("meshes", 2).field("x").locate(text);
            assert!(range.start <= range.end && range.end <= text.len(), "{text:?}");
        }
    }
}
