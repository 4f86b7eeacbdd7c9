//! PROTOCOL.md's "Every key" table, read from the document itself so that
//! the document and the tests cannot drift: which keys each message's
//! objects must have, and a check of a message against them.

use serde_json::Value;

/// One row: a message (`GET /api/passes`, ``event `frame` ``), a path into
/// it (`[].writes[]`, empty for the message itself) and its keys.
#[derive(Debug, Clone)]
pub struct Row {
    pub message: String,
    pub at: String,
    pub keys: Vec<String>,
}

/// The rows of PROTOCOL.md's "Every key" table.
pub fn documented() -> Vec<Row> {
    let text = std::fs::read_to_string(crate::repo().join("PROTOCOL.md")).expect("PROTOCOL.md is readable");
    let section = text.split("\n## Every key\n").nth(1).expect("PROTOCOL.md has an `## Every key` section");
    let section = section.split("\n## ").next().unwrap_or(section);
    let rows: Vec<Row> = section
        .lines()
        .filter_map(|line| {
            let cells: Vec<&str> = line.strip_prefix('|')?.strip_suffix('|')?.split('|').map(str::trim).collect();
            let [message, at, keys] = cells[..] else { return None };
            if message == "message" || message.starts_with("---") {
                return None;
            }
            let ticked = |s: &str| s.split('`').skip(1).step_by(2).map(str::to_owned).collect::<Vec<_>>();
            Some(Row { message: message.replace('`', ""), at: ticked(at).concat(), keys: ticked(keys) })
        })
        .collect();
    assert!(rows.len() > 20, "the key table was not found in PROTOCOL.md: {} rows", rows.len());
    rows
}

/// Every object at `at` in `message` (`[]`: each element, `.key`: that
/// key's value); `null`s and keys that are not there have nothing to give.
pub fn objects_at<'a>(message: &'a Value, at: &str) -> Vec<&'a Value> {
    let mut found = vec![message];
    let mut rest = at;
    while !rest.is_empty() {
        if let Some(tail) = rest.strip_prefix("[]") {
            found = found.into_iter().filter_map(Value::as_array).flatten().collect();
            rest = tail;
        } else if let Some(tail) = rest.strip_prefix('.') {
            let end = tail.find(['.', '[']).unwrap_or(tail.len());
            found = found.into_iter().filter_map(|v| v.get(&tail[..end])).collect();
            rest = &tail[end..];
        } else {
            panic!("PROTOCOL.md's key table: cannot read the path `{at}`");
        }
    }
    found.into_iter().filter(|v| !v.is_null()).collect()
}

/// The documented keys `message` lacks, for every row about `name`, each
/// said with where and in what.
pub fn missing_keys(rows: &[Row], name: &str, message: &Value) -> Vec<String> {
    let mut out = Vec::new();
    for row in rows.iter().filter(|r| r.message == name) {
        for object in objects_at(message, &row.at) {
            for key in row.keys.iter().filter(|k| object.get(k.as_str()).is_none()) {
                out.push(format!("{name} at `{}` has no `{key}`: {object}", row.at));
            }
        }
    }
    out
}

/// The keys `message` has that no row about `name` documents at that place,
/// each said with where and in what: the table must name what is sent, not
/// only a subset of it.
pub fn undocumented_keys(rows: &[Row], name: &str, message: &Value) -> Vec<String> {
    let mut out = Vec::new();
    for row in rows.iter().filter(|r| r.message == name) {
        // The keys of every row about this place (a place may take rows).
        let named: Vec<&String> = rows.iter().filter(|r| r.message == name && r.at == row.at).flat_map(|r| &r.keys).collect();
        for object in objects_at(message, &row.at) {
            let Some(map) = object.as_object() else { continue };
            for key in map.keys().filter(|k| !named.contains(k)) {
                out.push(format!("{name} at `{}` sends `{key}`, which the table does not name", row.at));
            }
        }
    }
    out
}
