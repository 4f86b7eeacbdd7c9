//! OIDN's tensor archive (`.tza`), the weights file of its denoisers.
//!
//! Little-endian: u16 magic 0x41D7, u8 major version (2), u8 minor, u64
//! offset of the tensor table. The table: u32 count, then per tensor a u16
//! name length and the name, u8 ndims, u32 dims[ndims], a layout string of
//! ndims characters (`oihw` for weights, `x` for biases), a dtype character
//! (`h` fp16, `f` fp32) and the u64 offset of its data. Read as OIDN reads it
//! (`core/tza.cpp`), except that what OIDN throws one message for ("invalid or
//! corrupted weights blob") is here an error saying where and what; duplicate
//! names are refused (OIDN keeps the first silently); and data offsets need
//! not be 64-byte aligned (OIDN's writer aligns them, its reader does not ask).

use std::ops::Range;
use std::path::Path;

use crate::diag::Diagnostic;
use crate::files::read_capped;

pub const MAGIC: u16 = 0x41D7;

/// The largest weights file loupe reads. OIDN's largest (the `large`
/// networks) are about 20 MB.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// A convolution's weights: output channels, input channels, height, width.
    Oihw,
    /// A vector (biases).
    X,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DType {
    F16,
    F32,
}

impl DType {
    fn bytes(self) -> u64 {
        match self {
            DType::F16 => 2,
            DType::F32 => 4,
        }
    }
}

/// One tensor's table entry.
#[derive(Debug, Clone, PartialEq)]
pub struct TensorInfo {
    pub name: String,
    pub dims: Vec<u32>,
    pub layout: Layout,
    pub dtype: DType,
    /// The byte where its table entry starts: problems with the tensor
    /// found later (a shape that does not chain) are located here.
    pub entry_at: u64,
    data: Range<usize>,
}

/// A parsed archive: the file's bytes and its table, every entry checked
/// to lie inside the file.
#[derive(Debug)]
pub struct Archive {
    bytes: Vec<u8>,
    tensors: Vec<TensorInfo>,
    table_at: u64,
}

/// What is wrong with an archive, and the byte where it was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("at byte {at}: {kind}")]
pub struct TzaError {
    pub at: u64,
    pub kind: TzaErrorKind,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TzaErrorKind {
    #[error("expected {what} ({need} bytes), but the file ends at byte {len}")]
    Truncated { what: &'static str, need: u64, len: u64 },
    #[error("expected the .tza magic number 0x41D7, found {0:#06X}: this is not an OIDN weights file")]
    Magic(u16),
    #[error("format version {major}.{minor} is not supported: only major version 2 is")]
    Version { major: u8, minor: u8 },
    #[error("the tensor table is said to start at byte {offset}, past the end of the file ({len} bytes)")]
    TableOffset { offset: u64, len: u64 },
    #[error("a tensor name must be UTF-8")]
    NameEncoding,
    #[error("tensor `{name}` has layout `{layout}`: expected `oihw` (4 dimensions) or `x` (1)")]
    Layout { name: String, layout: String },
    #[error("tensor `{name}` has data type `{found}`: expected `h` (fp16) or `f` (fp32)")]
    DType { name: String, found: String },
    #[error("tensor `{name}` has dimensions {dims:?}, more elements than fit in memory")]
    Overflow { name: String, dims: Vec<u32> },
    #[error("tensor `{name}` claims {size} bytes at byte {offset}, past the end of the file ({len} bytes)")]
    DataPastEnd { name: String, offset: u64, size: u64, len: u64 },
    #[error("tensor `{name}` is in the table twice (first at byte {first})")]
    Duplicate { name: String, first: u64 },
}

impl TzaError {
    /// The diagnostic for `display`, the file as the user named it.
    pub fn diagnostic(&self, display: &str) -> Diagnostic {
        super::weights_error(display, self.at, self.kind.to_string())
    }
}

/// Reads and parses the archive at `path`.
pub fn read(path: &Path, display: &str) -> Result<Archive, Diagnostic> {
    let bytes = read_capped(path, MAX_FILE_BYTES)
        .map_err(|e| e.diagnostic("the weights file", MAX_FILE_BYTES).at(crate::diag::Location::file_start(display)))?;
    Archive::parse(bytes).map_err(|e| e.diagnostic(display))
}

impl Archive {
    pub fn parse(bytes: Vec<u8>) -> Result<Archive, TzaError> {
        let mut r = Reader { bytes: &bytes, at: 0 };
        let magic = r.u16("the magic number")?;
        if magic != MAGIC {
            return Err(TzaError { at: 0, kind: TzaErrorKind::Magic(magic) });
        }
        let (major, minor) = (r.u8("the major version")?, r.u8("the minor version")?);
        if major != 2 {
            return Err(TzaError { at: 2, kind: TzaErrorKind::Version { major, minor } });
        }
        let table_at = r.u64("the tensor table offset")?;
        let len = bytes.len() as u64;
        if table_at > len {
            return Err(TzaError { at: 4, kind: TzaErrorKind::TableOffset { offset: table_at, len } });
        }
        r.at = table_at as usize;
        let count = r.u32("the tensor count")?;
        // Not `with_capacity(count)`: the count is the file's claim, and
        // entries run out of file long before a bogus one is reached.
        let mut tensors: Vec<TensorInfo> = Vec::new();
        for _ in 0..count {
            let t = r.entry()?;
            if let Some(first) = tensors.iter().find(|o| o.name == t.name) {
                let kind = TzaErrorKind::Duplicate { name: t.name.clone(), first: first.entry_at };
                return Err(TzaError { at: t.entry_at, kind });
            }
            tensors.push(t);
        }
        Ok(Archive { bytes, tensors, table_at })
    }

    pub fn tensors(&self) -> &[TensorInfo] {
        &self.tensors
    }

    pub fn get(&self, name: &str) -> Option<&TensorInfo> {
        self.tensors.iter().find(|t| t.name == name)
    }

    /// Where the tensor table starts: problems with no tensor of their own
    /// (one is missing) are located here.
    pub fn table_at(&self) -> u64 {
        self.table_at
    }

    /// A tensor's elements as f32, in the file's order (row-major in its
    /// layout). fp16 converts exactly.
    pub fn values(&self, t: &TensorInfo) -> Vec<f32> {
        let data = &self.bytes[t.data.clone()];
        match t.dtype {
            DType::F16 => data.chunks_exact(2).map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32()).collect(),
            DType::F32 => data.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
        }
    }
}

/// A bounds-checked cursor over the file.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&[u8], TzaError> {
        let len = self.bytes.len() as u64;
        match self.bytes.get(self.at..).and_then(|rest| rest.get(..n)) {
            Some(b) => {
                self.at += n;
                Ok(b)
            }
            None => Err(TzaError { at: self.at as u64, kind: TzaErrorKind::Truncated { what, need: n as u64, len } }),
        }
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], TzaError> {
        Ok(self.take(N, what)?.try_into().expect("take returns N bytes"))
    }

    fn u8(&mut self, what: &'static str) -> Result<u8, TzaError> {
        Ok(self.array::<1>(what)?[0])
    }

    fn u16(&mut self, what: &'static str) -> Result<u16, TzaError> {
        Ok(u16::from_le_bytes(self.array(what)?))
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, TzaError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    fn u64(&mut self, what: &'static str) -> Result<u64, TzaError> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }

    /// One table entry, its data checked to lie inside the file.
    fn entry(&mut self) -> Result<TensorInfo, TzaError> {
        let entry_at = self.at as u64;
        let name_len = self.u16("a tensor name's length")?;
        let name_at = self.at as u64;
        let name = std::str::from_utf8(self.take(name_len.into(), "a tensor name")?)
            .map_err(|_| TzaError { at: name_at, kind: TzaErrorKind::NameEncoding })?
            .to_owned();
        let ndims = self.u8("a tensor's number of dimensions")?;
        let dims = (0..ndims).map(|_| self.u32("a tensor dimension")).collect::<Result<Vec<_>, _>>()?;
        let layout_at = self.at as u64;
        let layout = match self.take(ndims.into(), "a tensor's layout")? {
            b"oihw" => Layout::Oihw,
            b"x" => Layout::X,
            other => {
                let kind = TzaErrorKind::Layout { name, layout: String::from_utf8_lossy(other).into_owned() };
                return Err(TzaError { at: layout_at, kind });
            }
        };
        let dtype_at = self.at as u64;
        let dtype = match self.u8("a tensor's data type")? {
            b'h' => DType::F16,
            b'f' => DType::F32,
            other => {
                let kind = TzaErrorKind::DType { name, found: char::from(other).escape_default().to_string() };
                return Err(TzaError { at: dtype_at, kind });
            }
        };
        let offset_at = self.at as u64;
        let offset = self.u64("a tensor's data offset")?;
        let size = dims
            .iter()
            .try_fold(dtype.bytes(), |n, &d| n.checked_mul(u64::from(d)))
            .filter(|&n| usize::try_from(n).is_ok())
            .ok_or_else(|| TzaError { at: entry_at, kind: TzaErrorKind::Overflow { name: name.clone(), dims: dims.clone() } })?;
        let len = self.bytes.len() as u64;
        if offset.checked_add(size).is_none_or(|end| end > len) {
            let kind = TzaErrorKind::DataPastEnd { name, offset, size, len };
            return Err(TzaError { at: offset_at, kind });
        }
        let data = offset as usize..(offset + size) as usize;
        Ok(TensorInfo { name, dims, layout, dtype, entry_at, data })
    }
}

/// A tensor for `write`: name, dims, layout, dtype character, data.
#[cfg(test)]
pub type Entry<'a> = (&'a str, &'a [u32], &'a str, u8, &'a [u8]);

/// Writes an archive of entries,
/// data 64-byte aligned as OIDN's writer does: tests build good and broken
/// files with it.
#[cfg(test)]
pub fn write(tensors: &[Entry]) -> Vec<u8> {
    let mut out = vec![0u8; 12];
    out[..2].copy_from_slice(&MAGIC.to_le_bytes());
    out[2] = 2;
    let mut offsets = Vec::new();
    for (.., data) in tensors {
        out.resize(out.len().next_multiple_of(64), 0);
        offsets.push(out.len() as u64);
        out.extend_from_slice(data);
    }
    let table = out.len() as u64;
    out[4..12].copy_from_slice(&table.to_le_bytes());
    out.extend((tensors.len() as u32).to_le_bytes());
    for ((name, dims, layout, dtype, _), offset) in tensors.iter().zip(offsets) {
        out.extend((name.len() as u16).to_le_bytes());
        out.extend(name.as_bytes());
        out.push(dims.len() as u8);
        dims.iter().for_each(|d| out.extend(d.to_le_bytes()));
        out.extend(layout.as_bytes());
        out.push(*dtype);
        out.extend(offset.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests;
