//! Tokens of a material file, each with its byte span. Comments are kept
//! apart (a comment right above a `param` is its documentation).

use std::ops::Range;

#[derive(Debug, Clone, PartialEq)]
pub enum Tok {
    Ident(String),
    /// A number literal; `None` when it does not fit a finite `f32`.
    Number(Option<f32>),
    Str(String),
    Punct(char),
    /// `->`
    Arrow,
    Eof,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    pub tok: Tok,
    pub span: Range<usize>,
}

/// A `//` comment: its text without the slashes, and its span.
#[derive(Debug, Clone, PartialEq)]
pub struct Comment {
    pub text: String,
    pub span: Range<usize>,
}

/// A character no token starts with, or an unterminated string.
#[derive(Debug, Clone, PartialEq)]
pub struct LexError {
    pub message: String,
    pub span: Range<usize>,
}

pub struct Lexed {
    pub tokens: Vec<Token>,
    pub comments: Vec<Comment>,
    pub errors: Vec<LexError>,
}

const PUNCT: &str = "(){}[],:;=.+-*/";

pub fn lex(text: &str) -> Lexed {
    let mut out = Lexed { tokens: Vec::new(), comments: Vec::new(), errors: Vec::new() };
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < text.len() {
        let c = text[i..].chars().next().expect("i is a char boundary");
        let start = i;
        if c.is_whitespace() {
            i += c.len_utf8();
        } else if text[i..].starts_with("//") {
            let end = text[i..].find('\n').map_or(text.len(), |n| i + n);
            out.comments.push(Comment { text: text[i + 2..end].trim().to_owned(), span: i..end });
            i = end;
        } else if c.is_ascii_alphabetic() || c == '_' {
            while i < text.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            out.tokens.push(Token { tok: Tok::Ident(text[start..i].to_owned()), span: start..i });
        } else if c.is_ascii_digit() || (c == '.' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            i = number_end(bytes, i);
            let value = text[start..i].parse::<f32>().ok().filter(|v| v.is_finite());
            out.tokens.push(Token { tok: Tok::Number(value), span: start..i });
        } else if c == '"' {
            match text[i + 1..].find(['"', '\n']) {
                Some(n) if bytes[i + 1 + n] == b'"' => {
                    i += n + 2;
                    out.tokens.push(Token { tok: Tok::Str(text[start + 1..i - 1].to_owned()), span: start..i });
                }
                _ => {
                    i = text[i..].find('\n').map_or(text.len(), |n| i + n);
                    out.errors.push(LexError { message: "unterminated string".into(), span: start..i });
                }
            }
        } else if text[i..].starts_with("->") {
            i += 2;
            out.tokens.push(Token { tok: Tok::Arrow, span: start..i });
        } else if PUNCT.contains(c) {
            i += 1;
            out.tokens.push(Token { tok: Tok::Punct(c), span: start..i });
        } else {
            i += c.len_utf8();
            out.errors.push(LexError { message: format!("unexpected character `{c}`"), span: start..i });
        }
    }
    out.tokens.push(Token { tok: Tok::Eof, span: text.len()..text.len() });
    out
}

/// The end of a number starting at `i`: digits, a fraction, an exponent.
fn number_end(bytes: &[u8], mut i: usize) -> usize {
    let digits = |mut i: usize| {
        while bytes.get(i).is_some_and(u8::is_ascii_digit) {
            i += 1;
        }
        i
    };
    i = digits(i);
    if bytes.get(i) == Some(&b'.') {
        i = digits(i + 1);
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(bytes.get(i + 1), Some(b'+' | b'-')));
        if bytes.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
            i = digits(i + 1 + sign);
        }
    }
    i
}
