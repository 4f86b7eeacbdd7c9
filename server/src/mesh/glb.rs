//! The binary glTF container (glTF 2.0 §4.4): a 12-byte header, a JSON
//! chunk, then an optional BIN chunk holding buffer 0.

pub struct Glb<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

pub const MAGIC: &[u8; 4] = b"glTF";
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
pub const CHUNK_BIN: u32 = 0x004E_4942;

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
}

pub fn parse(bytes: &[u8]) -> Result<Glb<'_>, String> {
    let (Some(version), Some(length)) = (u32_at(bytes, 4), u32_at(bytes, 8)) else {
        return Err(format!("binary glTF is {} bytes, shorter than its 12-byte header", bytes.len()));
    };
    if version != 2 {
        return Err(format!("binary glTF version {version} is not supported: only version 2 is"));
    }
    if length as usize != bytes.len() {
        return Err(format!("binary glTF header says the file is {length} bytes, but it is {} bytes", bytes.len()));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < bytes.len() {
        let (Some(len), Some(kind)) = (u32_at(bytes, at), u32_at(bytes, at + 4)) else {
            return Err(format!("chunk header at byte {at} is cut off by the end of the file"));
        };
        let data = bytes
            .get(at + 8..)
            .and_then(|rest| rest.get(..len as usize))
            .ok_or_else(|| format!("chunk at byte {at} says it holds {len} bytes, past the end of the file"))?;
        chunks.push((kind, data));
        at += 8 + data.len();
    }
    let json = match chunks.first() {
        Some(&(CHUNK_JSON, json)) => json,
        _ => return Err("binary glTF does not start with a JSON chunk".into()),
    };
    // Writers pad the JSON chunk to 4 bytes with spaces, some with NULs.
    let json = &json[..json.iter().rposition(|&b| b != 0).map_or(0, |p| p + 1)];
    // Chunks of unknown types are to be ignored (§4.4.3.1).
    let bin = chunks.get(1).filter(|(kind, _)| *kind == CHUNK_BIN).map(|&(_, data)| data);
    Ok(Glb { json, bin })
}

/// A binary glTF file of `chunks` (type, data), as given: tests build
/// both good and broken files with it.
#[cfg(test)]
pub fn write(chunks: &[(u32, &[u8])]) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(0u32.to_le_bytes());
    for (kind, data) in chunks {
        out.extend((data.len() as u32).to_le_bytes());
        out.extend(kind.to_le_bytes());
        out.extend(*data);
    }
    let len = out.len() as u32;
    out[8..12].copy_from_slice(&len.to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_chunks() {
        let bytes = write(&[(CHUNK_JSON, b"{}  "), (CHUNK_BIN, &[1, 2, 3, 4])]);
        let g = parse(&bytes).unwrap();
        assert_eq!((g.json, g.bin), (&b"{}  "[..], Some(&[1u8, 2, 3, 4][..])));
        let bytes = write(&[(CHUNK_JSON, b"{}\0\0"), (0x1234, &[9; 4])]);
        let g = parse(&bytes).unwrap();
        assert_eq!((g.json, g.bin), (&b"{}"[..], None));
    }

    #[test]
    fn refuses_broken_containers() {
        let good = write(&[(CHUNK_JSON, b"{}  "), (CHUNK_BIN, &[0; 8])]);
        let msg = |bytes: &[u8]| parse(bytes).err().unwrap();
        assert!(msg(&good[..7]).contains("shorter than its 12-byte header"));
        assert!(msg(&good[..good.len() - 4]).contains("says the file is"));
        let mut v1 = good.clone();
        v1[4] = 1;
        assert!(msg(&v1).contains("version 1"));
        let mut long_chunk = good.clone();
        long_chunk[12] = 200;
        assert!(msg(&long_chunk).contains("past the end of the file"), "{}", msg(&long_chunk));
        assert!(msg(&write(&[(CHUNK_BIN, &[0; 4])])).contains("JSON chunk"));
        let mut cut = write(&[(CHUNK_JSON, b"{}  ")]);
        cut.extend([0, 0, 0]);
        let len = cut.len() as u32;
        cut[8..12].copy_from_slice(&len.to_le_bytes());
        assert!(msg(&cut).contains("cut off"));
    }
}
