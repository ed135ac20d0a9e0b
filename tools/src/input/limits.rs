//! Bounds on what the host tool reads from outside: every file has a size limit, a file that
//! must be read whole must be a regular file, and text quoted back in an error message is a short
//! escaped prefix. The table of limits is in docs/resource-limits.md.

use std::fmt;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};

/// Largest field file (a blob, optionally followed by its free-space section) the tool reads:
/// 128 MiB. A map within `field build`'s default `--max-cells` (16,777,216 cells) gives at most
/// 16 MiB of codes (raw encoding, one byte per cell; the tiled encoding is smaller) plus a
/// free-space section of at most 4 bytes per cell (8 bytes per run, at most one run per two
/// cells): 80 MiB and headers, so every file built with the default limit is read.
pub const MAX_FIELD_FILE_BYTES: u64 = 128 << 20;

/// Largest LiDAR capture `lidar decode` reads: 64 MiB. The Intel log's 910 scans encode to
/// 0.75–1.8 MB in the four protocols; 64 MiB holds about 33,000 XV-11 revolutions (the most bytes
/// per revolution, 1,980), close to two hours of a 5 Hz sensor. The capture is decoded in chunks
/// as it is read, never held whole.
pub const MAX_CAPTURE_BYTES: u64 = 64 << 20;

/// Largest number of scans `lidar decode` assembles from a capture: 100,000 (144 MB of ranges at
/// 360 beams). A real capture within [`MAX_CAPTURE_BYTES`] has at most about 80,000 revolutions
/// (YDLIDAR, 810 bytes each); a crafted one could close a revolution every few bytes.
pub const MAX_DECODED_SCANS: usize = 100_000;

/// Largest CARMEN log read: 256 MiB, about 150 times the Intel log (1.7 MB for 910 scans).
pub const MAX_LOG_BYTES: u64 = 256 << 20;

/// Largest small text file read whole (a sonar ring description): 1 MiB.
pub const MAX_TEXT_FILE_BYTES: u64 = 1 << 20;

/// Longest line of standard input `field query` reads: 64 KiB (a query line is a few dozen
/// bytes), as the CARMEN reader's [`crate::input::carmen::MAX_LINE_BYTES`].
pub const MAX_QUERY_LINE_BYTES: usize = crate::input::carmen::MAX_LINE_BYTES;

/// Characters of a bad input line (or token) quoted in an error message.
pub const QUOTE_CHARS: usize = 64;

/// Why a bounded file read failed.
#[derive(Debug)]
pub enum ReadError {
    /// The file could not be opened or read.
    Io(PathBuf, std::io::Error),
    /// The path names a device, a FIFO or a directory where a regular file is needed.
    NotAFile(PathBuf),
    /// The file is larger than the limit for its kind.
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit, bytes.
        limit: u64,
        /// What kind of file (for the message: "field file", "LiDAR capture", …).
        what: &'static str,
    },
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::NotAFile(p) => write!(f, "{} is not a regular file", p.display()),
            Self::TooLarge { path, limit, what } => write!(
                f,
                "{} is larger than {limit} bytes, the limit for a {what}",
                path.display()
            ),
        }
    }
}

impl std::error::Error for ReadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io(_, e) => Some(e),
            _ => None,
        }
    }
}

/// Reads a whole regular file of at most `limit` bytes. A device, FIFO or directory is refused
/// before it is opened; a file whose size is over the limit is refused before it is read, and one
/// that grows past the limit while being read is refused after `limit + 1` bytes.
///
/// # Errors
/// [`ReadError`].
pub fn read_regular_file(
    path: &Path,
    limit: u64,
    what: &'static str,
) -> Result<Vec<u8>, ReadError> {
    let io = |e| ReadError::Io(path.to_path_buf(), e);
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(ReadError::NotAFile(path.to_path_buf()));
    }
    let too_large = || ReadError::TooLarge {
        path: path.to_path_buf(),
        limit,
        what,
    };
    if meta.len() > limit {
        return Err(too_large());
    }
    let mut out = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(io)?;
    if out.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(out)
}

/// `s` as it may be quoted in a message: its first `max_chars` characters escaped
/// (`\u{1b}`, `\0`, `\"`, …), with `…` when something was cut. Never carries a control byte.
pub fn escaped_prefix(s: &str, max_chars: usize) -> String {
    let mut out: String = s.escape_default().take(max_chars).collect();
    if s.escape_default().nth(max_chars).is_some() {
        out.push('…');
    }
    out
}

/// One line read by [`read_bounded_line`].
#[derive(Debug, PartialEq, Eq)]
pub enum BoundedLine<'a> {
    /// Its text, without the line end (`\n` or `\r\n`).
    Text(&'a str),
    /// Longer than the limit. Nothing past the limit was read.
    TooLong,
    /// Not UTF-8.
    NotUtf8,
}

/// Reads the next line into `buf`, keeping at most `max` bytes of it; `None` at the end of the
/// input. A longer line is [`BoundedLine::TooLong`] and is left unread past `max + 1` bytes (the
/// caller decides whether to skip it or stop).
///
/// # Errors
/// I/O errors of `reader`.
pub fn read_bounded_line<'a, R: BufRead>(
    reader: &mut R,
    buf: &'a mut Vec<u8>,
    max: usize,
) -> std::io::Result<Option<BoundedLine<'a>>> {
    buf.clear();
    let n = reader
        .by_ref()
        .take(max as u64 + 1)
        .read_until(b'\n', buf)?;
    if n == 0 {
        return Ok(None);
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
    } else if buf.len() > max {
        return Ok(Some(BoundedLine::TooLong));
    }
    Ok(Some(match std::str::from_utf8(buf) {
        Ok(t) => BoundedLine::Text(t),
        Err(_) => BoundedLine::NotUtf8,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaped_prefix_cuts_and_escapes() {
        assert_eq!(escaped_prefix("1,2", 64), "1,2");
        assert_eq!(escaped_prefix("a\u{1b}b", 64), "a\\u{1b}b");
        assert_eq!(escaped_prefix(&"x".repeat(100), 5), "xxxxx…");
        assert_eq!(escaped_prefix("xxxxx", 5), "xxxxx");
    }

    #[test]
    fn bounded_lines() {
        let mut r = std::io::BufReader::new(&b"ab\r\ncdef\n\xff\nlast"[..]);
        let mut buf = Vec::new();
        assert_eq!(
            read_bounded_line(&mut r, &mut buf, 3).unwrap(),
            Some(BoundedLine::Text("ab"))
        );
        assert_eq!(
            read_bounded_line(&mut r, &mut buf, 3).unwrap(),
            Some(BoundedLine::TooLong)
        );
        let mut r = std::io::BufReader::new(&b"\xff\nlast"[..]);
        assert_eq!(
            read_bounded_line(&mut r, &mut buf, 3).unwrap(),
            Some(BoundedLine::NotUtf8)
        );
        assert_eq!(
            read_bounded_line(&mut r, &mut buf, 4).unwrap(),
            Some(BoundedLine::Text("last"))
        );
        assert_eq!(read_bounded_line(&mut r, &mut buf, 4).unwrap(), None);
    }
}
