//! glTF buffer URIs: `data:` URIs with base64 payloads, and paths relative
//! to the .gltf (percent-encoded, as URIs are). Other schemes (`http:`,
//! `file:`) are refused: a scene must not reach outside its files.

/// What a buffer's `uri` names.
#[derive(Debug, PartialEq, Eq)]
pub enum Uri {
    Data(Vec<u8>),
    Relative(String),
}

/// Why a URI is unusable, and the byte offset in it of the culprit when there
/// is one, so the diagnostic can point at that character.
#[derive(Debug, PartialEq, Eq)]
pub struct UriError {
    pub message: String,
    pub offset: Option<usize>,
}

impl UriError {
    fn new(message: impl Into<String>, offset: Option<usize>) -> Self {
        UriError { message: message.into(), offset }
    }
}

pub fn parse(uri: &str) -> Result<Uri, UriError> {
    match scheme(uri) {
        Some("data") => data(uri),
        Some(other) => Err(UriError::new(
            format!("URI scheme `{other}:` is not supported: use a path relative to the .gltf file or a data: URI"),
            Some(0),
        )),
        None => percent_decode(uri).map(Uri::Relative),
    }
}

/// RFC 3986: a scheme is a letter then letters, digits, `+`, `-` or `.`,
/// ended by `:`. A colon after a `/` belongs to a relative path.
fn scheme(uri: &str) -> Option<&str> {
    let (scheme, _) = uri.split_once(':')?;
    let mut chars = scheme.chars();
    let first = chars.next()?;
    (first.is_ascii_alphabetic() && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))).then_some(scheme)
}

/// `data:[<media type>][;base64],<payload>`
fn data(uri: &str) -> Result<Uri, UriError> {
    let Some(comma) = uri.find(',') else {
        return Err(UriError::new("data URI has no `,` before its payload", None));
    };
    if !uri[..comma].ends_with(";base64") {
        return Err(UriError::new("data URI is not base64-encoded (`;base64,` is missing)", None));
    }
    let start = comma + 1;
    base64(&uri[start..]).map(Uri::Data).map_err(|e| UriError { offset: e.offset.map(|o| o + start), ..e })
}

/// Standard base64 (RFC 4648 §4), padding optional.
fn base64(s: &str) -> Result<Vec<u8>, UriError> {
    let body = s.trim_end_matches('=');
    if s.len() - body.len() > 2 {
        return Err(UriError::new("base64 payload has more than two `=` of padding", Some(body.len() + 2)));
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in body.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                let shown = s[i..].chars().next().unwrap_or('?');
                return Err(UriError::new(format!("`{shown}` is not a base64 character"), Some(i)));
            }
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    // One character left over carries 6 bits: not even one byte.
    if body.len() % 4 == 1 {
        return Err(UriError::new("base64 payload is truncated", Some(body.len() - 1)));
    }
    Ok(out)
}

fn percent_decode(uri: &str) -> Result<String, UriError> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
            match hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                Some(byte) => out.push(byte),
                None => return Err(UriError::new("`%` must be followed by two hex digits", Some(i))),
            }
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| UriError::new("percent-encoded path is not UTF-8", None))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_data_uris() {
        assert_eq!(parse("data:application/octet-stream;base64,AAECAw==").unwrap(), Uri::Data(vec![0, 1, 2, 3]));
        assert_eq!(parse("data:application/gltf-buffer;base64,/+8").unwrap(), Uri::Data(vec![0xff, 0xef]));
        assert_eq!(parse("data:;base64,").unwrap(), Uri::Data(vec![]));
    }

    #[test]
    fn points_at_bad_characters() {
        let e = parse("data:application/octet-stream;base64,AA*A").unwrap_err();
        assert_eq!((e.message.as_str(), e.offset), ("`*` is not a base64 character", Some(39)));
        assert_eq!(parse("data:;base64,AAAAA").unwrap_err().offset, Some(17));
        assert!(parse("data:text/plain,hello").unwrap_err().message.contains("not base64"));
        assert_eq!(parse("a%2").unwrap_err().offset, Some(1));
        assert!(parse("%FF.bin").unwrap_err().message.contains("UTF-8"));
    }

    #[test]
    fn paths_and_schemes() {
        assert_eq!(parse("my%20mesh.bin").unwrap(), Uri::Relative("my mesh.bin".into()));
        assert_eq!(parse("dir/a:b.bin").unwrap(), Uri::Relative("dir/a:b.bin".into()));
        assert!(parse("https://example.com/x.bin").unwrap_err().message.contains("`https:`"));
        assert!(parse("file:///etc/passwd").is_err());
    }
}
