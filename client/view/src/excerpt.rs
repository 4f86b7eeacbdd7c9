//! The source lines a problem points at, with a caret under its column.

/// Lines `line - 1 ..= line` of `text` (1-based), numbered, and a caret
/// under `column` (1-based, in characters); `None` when the file has no
/// such line (it changed since the diagnostic was made).
pub fn excerpt(text: &str, line: u32, column: u32) -> Option<String> {
    let index = usize::try_from(line).ok()?.checked_sub(1)?;
    let lines: Vec<&str> = text.lines().collect();
    let target = lines.get(index)?;
    let width = (index + 1).to_string().len();
    let mut out = String::new();
    if let Some(before) = index.checked_sub(1).and_then(|i| lines.get(i)) {
        out.push_str(&format!("{:>width$} | {before}\n", index));
    }
    out.push_str(&format!("{:>width$} | {target}\n", index + 1));
    let pad: String = target.chars().take(column.saturating_sub(1) as usize).map(|c| if c == '\t' { '\t' } else { ' ' }).collect();
    out.push_str(&format!("{:>width$} | {pad}^", ""));
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::excerpt;

    #[test]
    fn the_caret_sits_under_the_column() {
        let text = "fn a() {\n\tlet x = 1\n}\n";
        assert_eq!(excerpt(text, 2, 11).unwrap(), "1 | fn a() {\n2 | \tlet x = 1\n  | \t         ^");
        assert_eq!(excerpt(text, 1, 1).unwrap(), "1 | fn a() {\n  | ^");
        assert_eq!(excerpt(text, 9, 1), None);
        assert_eq!(excerpt(text, 0, 1), None);
    }
}
