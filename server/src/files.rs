//! Reading a user's file with a size cap: the length is checked before
//! anything is allocated, so a file that claims or is gigabytes costs
//! nothing; and only a regular file is opened, so a name that points at a
//! FIFO or a device (`/dev/stdin`) is an error, not a read that waits for
//! ever.

use std::io::Read;
use std::path::Path;

use crate::diag::{Code, Diagnostic};

/// Why a file could not be read.
pub enum ReadError {
    Io(std::io::Error),
    TooLarge(u64),
    NotAFile,
}

impl ReadError {
    /// `what` names the file in the message ("file", "buffer 2").
    pub fn diagnostic(self, what: &str, limit: u64) -> Diagnostic {
        match self {
            ReadError::Io(e) => Diagnostic::error(Code::Io, format!("cannot read {what}: {e}")),
            ReadError::TooLarge(len) => Diagnostic::error(Code::FileTooLarge, format!("{what} is {len} bytes; the limit is {limit} bytes")),
            ReadError::NotAFile => Diagnostic::error(Code::Io, format!("cannot read {what}: it is not a regular file")),
        }
    }
}

/// Reads at most `limit` bytes: the length is checked before reading, and
/// the read is capped in case the file grows meanwhile.
pub fn read_capped(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    if !std::fs::metadata(path).map_err(ReadError::Io)?.is_file() {
        return Err(ReadError::NotAFile);
    }
    let file = std::fs::File::open(path).map_err(ReadError::Io)?;
    let len = file.metadata().map_err(ReadError::Io)?.len();
    if len > limit {
        return Err(ReadError::TooLarge(len));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(ReadError::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge(bytes.len() as u64));
    }
    Ok(bytes)
}
