//! Reading input files safely: regular files only, bounded in size, and
//! excerpts of bad content short enough to quote in an error message.
//! Point sets, scenes and the renderer's OBJ frames read through it.

use std::io::Read;
use std::path::Path;

/// Longest excerpt of a file's content quoted in an error message, in
/// characters; a longer token is cut and ends with `...`.
pub const EXCERPT_CHARS: usize = 80;

/// `text` as quoted in an error message: at most [`EXCERPT_CHARS`]
/// characters, the cut marked by `...`.
pub fn excerpt(text: &str) -> String {
    if text.chars().count() <= EXCERPT_CHARS {
        return text.to_string();
    }
    let head: String = text.chars().take(EXCERPT_CHARS - 3).collect();
    format!("{head}...")
}

/// Why an input file was not read by [`read_regular_file`].
#[derive(Debug)]
pub enum InputFileError {
    /// The system could not open or read it.
    Io(std::io::Error),
    /// It is not a regular file; what it is instead.
    NotRegular(&'static str),
    /// It holds more than the limit; its size in bytes (at least).
    TooLarge(u64),
}

impl InputFileError {
    /// The message for a problem other than [`InputFileError::Io`].
    pub fn message(&self, limit: u64) -> String {
        match self {
            InputFileError::Io(e) => e.to_string(),
            InputFileError::NotRegular(what) => {
                format!("not a regular file ({what}): give a file")
            }
            InputFileError::TooLarge(size) => format!(
                "{size} bytes or more, larger than the limit of {limit} bytes ({} MiB)",
                limit >> 20
            ),
        }
    }
}

/// What a non-regular file is, for messages.
fn file_kind(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a named pipe";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

/// The bytes of the regular file at `path` (symlinks followed), at most
/// `limit` of them. The type and size are checked before the file is
/// opened (so a pipe or device is never read), and the read stops after
/// `limit + 1` bytes in case the file grew meanwhile.
pub fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, InputFileError> {
    let meta = std::fs::metadata(path).map_err(InputFileError::Io)?;
    if !meta.is_file() {
        return Err(InputFileError::NotRegular(file_kind(meta.file_type())));
    }
    if meta.len() > limit {
        return Err(InputFileError::TooLarge(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(InputFileError::Io)?;
    let opened = file.metadata().map_err(InputFileError::Io)?;
    if !opened.is_file() {
        return Err(InputFileError::NotRegular(file_kind(opened.file_type())));
    }
    let mut bytes = Vec::with_capacity(opened.len().min(limit) as usize);
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(InputFileError::Io)?;
    if bytes.len() as u64 > limit {
        return Err(InputFileError::TooLarge(bytes.len() as u64));
    }
    Ok(bytes)
}

/// `bytes` without a leading UTF-8 byte-order mark.
pub fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}
