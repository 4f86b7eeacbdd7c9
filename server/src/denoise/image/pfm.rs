//! Portable float map: a text header `PF` (RGB) or `Pf` (grey), width,
//! height and a scale whose sign gives the byte order (negative: little
//! endian), one whitespace character, then f32 pixels, rows bottom first.
//! As OIDN reads it (`apps/utils/image_io.cpp`), values are multiplied by
//! the scale's magnitude; unlike OIDN, big-endian files are read too.

use super::{Image, MAX_SIDE};

/// What is wrong with a PFM file, and the byte where it was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("at byte {at}: {message}")]
pub struct PfmError {
    pub at: usize,
    pub message: String,
}

fn error<T>(at: usize, message: impl Into<String>) -> Result<T, PfmError> {
    Err(PfmError { at, message: message.into() })
}

/// The header's next whitespace-separated token and where it starts.
fn token(bytes: &[u8], at: &mut usize, what: &str) -> Result<(usize, String), PfmError> {
    while bytes.get(*at).is_some_and(u8::is_ascii_whitespace) {
        *at += 1;
    }
    let start = *at;
    while bytes.get(*at).is_some_and(|b| !b.is_ascii_whitespace()) && *at - start < 32 {
        *at += 1;
    }
    if start == *at {
        return error(start, format!("expected {what} in the PFM header, found the end of the file"));
    }
    Ok((start, String::from_utf8_lossy(&bytes[start..*at]).into_owned()))
}

pub fn parse(bytes: &[u8]) -> Result<Image, PfmError> {
    let mut at = 0;
    let channels = match token(bytes, &mut at, "`PF` or `Pf`")?.1.as_str() {
        "PF" => 3,
        "Pf" => 1,
        other => return error(0, format!("expected `PF` (RGB) or `Pf` (grey), found `{}`: not a PFM file", other.escape_default())),
    };
    let mut side = |what: &str| -> Result<usize, PfmError> {
        let (start, text) = token(bytes, &mut at, what)?;
        match text.parse::<usize>() {
            Ok(n) if (1..=MAX_SIDE).contains(&n) => Ok(n),
            Ok(n) => error(start, format!("the {what} is {n}: expected 1..={MAX_SIDE}")),
            Err(_) => error(start, format!("expected the {what}, a whole number, found `{}`", text.escape_default())),
        }
    };
    let (width, height) = (side("width")?, side("height")?);
    let (start, text) = token(bytes, &mut at, "the scale")?;
    let scale = match text.parse::<f32>() {
        Ok(s) if s.is_finite() && s != 0.0 => s,
        _ => {
            return error(
                start,
                format!("expected the scale, a non-zero number (negative: little-endian), found `{}`", text.escape_default()),
            );
        }
    };
    if !bytes.get(at).is_some_and(u8::is_ascii_whitespace) {
        return error(at, "expected one whitespace character after the scale, then the pixels");
    }
    let data_at = at + 1;
    let need = width * height * channels * 4;
    let have = bytes.len() - data_at;
    if have != need {
        let found = if have < need { "the file ends" } else { "bytes follow" };
        return error(data_at, format!("{width}×{height} pixels of {channels} f32 take {need} bytes, but {found} after {have}"));
    }
    let little = scale < 0.0;
    let values: Vec<f32> = bytes[data_at..]
        .chunks_exact(4)
        .map(|b| {
            let b = [b[0], b[1], b[2], b[3]];
            scale.abs() * if little { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) }
        })
        .collect();
    let mut data = Vec::with_capacity(width * height * 3);
    for row in values.chunks_exact(width * channels).rev() {
        for px in row.chunks_exact(channels) {
            data.extend(if channels == 3 { [px[0], px[1], px[2]] } else { [px[0]; 3] });
        }
    }
    Ok(Image { width, height, data })
}

/// RGB, little-endian, scale 1.
pub fn encode(image: &Image) -> Vec<u8> {
    let mut out = format!("PF\n{} {}\n-1.0\n", image.width, image.height).into_bytes();
    for row in image.data.chunks_exact(image.width * 3).rev() {
        out.extend(row.iter().flat_map(|v| v.to_le_bytes()));
    }
    out
}
