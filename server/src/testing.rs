//! Helpers the unit tests share.

/// The 1-based line and column (in characters) of byte `k` of the first
/// `needle` in `text`: where a diagnostic about it must point, worked out
/// from the text rather than by the code under test.
pub fn line_col(text: &str, needle: &str, k: usize) -> (u32, u32) {
    let at = text.find(needle).unwrap_or_else(|| panic!("{needle:?} is not in {text:?}")) + k;
    let line = text[..at].matches('\n').count() + 1;
    let column = text[..at].rsplit('\n').next().unwrap().chars().count() + 1;
    (line as u32, column as u32)
}
