//! A check of an MCAP file before the `mcap` crate parses it: its length fields, its chunks'
//! sizes and its CRCs.
//!
//! The crate (0.26) reserves memory for a string, a byte array or a map from the length written
//! in the file before it reads the bytes, and for a chunk from the uncompressed size the chunk
//! declares. A malformed file can therefore make it allocate 4 GiB for a record a few bytes long
//! (`fuzz/fuzz_targets/bag_decode.rs` found one). It does not check CRCs unless asked, so a
//! damaged chunk reads as data. This check walks every record and refuses the file when:
//!
//! - a length field points past the end of its record ([`BadLength`]), in the file or in the
//!   records of a chunk, compressed or not;
//! - a chunk declares more than [`MAX_CHUNK_BYTES`] uncompressed, or more than its compression
//!   can yield from its compressed bytes ([`MAX_ZSTD_RATIO`], [`MAX_LZ4_RATIO`]);
//! - a compressed chunk does not decompress to exactly its declared size (it is decompressed here
//!   into a buffer of that size, never more);
//! - a CRC written in the file does not match: a chunk's (over its uncompressed records), the
//!   data section's (in the Data End record) or the summary section's (in the Footer). A CRC of
//!   0 means "not written" (MCAP specification) and is not checked.
//!
//! A file that passes can be handed to the crate: every length it will allocate from has been
//! checked against the bytes that hold it.

use std::io::Read;

/// Largest uncompressed chunk accepted, bytes (rosbag2 writes chunks of about 4 MiB).
pub const MAX_CHUNK_BYTES: u64 = 256 << 20;

/// Most uncompressed bytes a zstd chunk may declare per compressed byte: 32,768. A zstd block
/// holds at most 128 KiB and the smallest block (an RLE block) takes 4 bytes, so no zstd frame
/// decompresses to more than 32,768 times its size.
pub const MAX_ZSTD_RATIO: u64 = 32_768;

/// Most uncompressed bytes an LZ4 chunk may declare per compressed byte: 255. An LZ4 sequence
/// lengthens its match by at most 255 bytes per byte it spends on the length, so no LZ4 frame
/// decompresses to more than 255 times its size.
pub const MAX_LZ4_RATIO: u64 = 255;

const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Where a file's length fields went wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadLength {
    /// Byte offset of the record: in the file, or in the uncompressed records of the chunk at
    /// [`BadLength::chunk`].
    pub at: usize,
    pub what: &'static str,
    /// Byte offset in the file of the compressed chunk whose records hold the record, if any.
    pub chunk: Option<usize>,
}

impl std::fmt::Display for BadLength {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.chunk {
            None => write!(
                f,
                "{} at byte {} points past its record",
                self.what, self.at
            ),
            Some(c) => write!(
                f,
                "{} at byte {} of the uncompressed records of the chunk at byte {c} points past \
                 its record",
                self.what, self.at
            ),
        }
    }
}

/// Whose CRC did not match.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CrcOf {
    /// A chunk's records (uncompressed); `at` is the chunk's byte offset in the file.
    Chunk { at: usize },
    /// The data section (from the file's start to the Data End record at byte `at`).
    DataSection { at: usize },
    /// The summary section and the Footer's first two fields (the Footer is at byte `at`).
    SummarySection { at: usize },
}

/// Why an MCAP file is refused before it is parsed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Corrupt {
    /// A length field points past its record.
    Length(BadLength),
    /// A CRC written in the file does not match the bytes.
    BadCrc {
        what: CrcOf,
        /// The CRC-32 written in the file.
        saved: u32,
        /// The CRC-32 of the bytes.
        calculated: u32,
    },
    /// A chunk declares more uncompressed bytes than are accepted (`limit`: the smaller of
    /// [`MAX_CHUNK_BYTES`] and what its compression can yield from `compressed` bytes).
    ChunkTooLarge {
        at: usize,
        declared: u64,
        compressed: u64,
        limit: u64,
    },
    /// A chunk compressed with something other than zstd or LZ4.
    Compression { at: usize, name: String },
    /// A chunk, data end or footer record where it cannot be: in a chunk, or a footer with
    /// records after it (`chunk`: the byte offset of the chunk whose records hold it).
    Misplaced {
        at: usize,
        what: &'static str,
        chunk: Option<usize>,
    },
    /// A compressed chunk that does not decompress to its declared size.
    Decompress {
        at: usize,
        compression: &'static str,
        why: String,
    },
}

impl std::fmt::Display for Corrupt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Length(e) => e.fmt(f),
            Self::BadCrc {
                what,
                saved,
                calculated,
            } => {
                match what {
                    CrcOf::Chunk { at } => write!(f, "the chunk at byte {at}")?,
                    CrcOf::DataSection { at } => {
                        write!(f, "the data section (Data End record at byte {at})")?
                    }
                    CrcOf::SummarySection { at } => {
                        write!(f, "the summary section (Footer at byte {at})")?
                    }
                }
                write!(
                    f,
                    " has CRC-32 {calculated:#010x}, but {saved:#010x} is written: the bytes are damaged"
                )
            }
            Self::ChunkTooLarge {
                at,
                declared,
                compressed,
                limit,
            } => write!(
                f,
                "the chunk at byte {at} declares {declared} uncompressed bytes from {compressed} \
                 compressed, more than the {limit} accepted"
            ),
            Self::Compression { at, name } => write!(
                f,
                "the chunk at byte {at} is compressed with {:?}, not zstd or lz4",
                name.escape_default().to_string()
            ),
            Self::Misplaced {
                at,
                what,
                chunk: None,
            } => write!(f, "{what} at byte {at}"),
            Self::Misplaced {
                at,
                what,
                chunk: Some(c),
            } => write!(
                f,
                "{what} at byte {at} of the uncompressed records of the chunk at byte {c}"
            ),
            Self::Decompress {
                at,
                compression,
                why,
            } => write!(f, "the {compression} chunk at byte {at}: {why}"),
        }
    }
}

impl std::error::Error for Corrupt {}

impl From<BadLength> for Corrupt {
    fn from(e: BadLength) -> Self {
        Self::Length(e)
    }
}

/// A cursor over one record's body.
struct Body<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Body<'a> {
    fn skip(&mut self, n: usize) -> Option<()> {
        self.at = self.at.checked_add(n).filter(|&e| e <= self.b.len())?;
        Some(())
    }
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let v = self.b.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(v)
    }
    fn u32(&mut self) -> Option<u32> {
        let v = self.take(4)?;
        Some(u32::from_le_bytes([v[0], v[1], v[2], v[3]]))
    }
    fn len32(&mut self) -> Option<usize> {
        usize::try_from(self.u32()?).ok()
    }
    fn u64(&mut self) -> Option<u64> {
        let mut a = [0u8; 8];
        a.copy_from_slice(self.take(8)?);
        Some(u64::from_le_bytes(a))
    }
    /// A u32-length-prefixed string or byte array.
    fn sized(&mut self) -> Option<()> {
        let n = self.len32()?;
        self.skip(n)
    }
    /// A u32 byte length, then `inner` over exactly those bytes.
    fn map(&mut self, inner: impl Fn(&mut Body) -> Option<()>) -> Option<()> {
        let n = self.len32()?;
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len())?;
        let mut m = Body {
            b: &self.b[..end],
            at: self.at,
        };
        while m.at < end {
            inner(&mut m)?;
        }
        self.at = end;
        Some(())
    }
}

/// Checks the length fields of one record body of type `op` (not a chunk, a data end or a
/// footer); `None` when one points past it.
fn fields(op: u8, b: &[u8]) -> Option<()> {
    let mut r = Body { b, at: 0 };
    match op {
        // Header: profile, library.
        0x01 => {
            r.sized()?;
            r.sized()
        }
        // Schema: id, name, encoding, data.
        0x03 => {
            r.skip(2)?;
            r.sized()?;
            r.sized()?;
            r.sized()
        }
        // Channel: id, schema id, topic, message encoding, metadata.
        0x04 => {
            r.skip(4)?;
            r.sized()?;
            r.sized()?;
            r.map(|m| {
                m.sized()?;
                m.sized()
            })
        }
        // Message index: channel, entries.
        0x07 => {
            r.skip(2)?;
            r.map(|m| m.skip(16))
        }
        // Chunk index: four u64, offsets map, index length, compression, two sizes.
        0x08 => {
            r.skip(32)?;
            r.map(|m| m.skip(10))?;
            r.skip(8)?;
            r.sized()?;
            r.skip(16)
        }
        // Attachment: two times, name, media type, data, CRC (the crate slices the data up to
        // the CRC and panicked on an attachment with no room for it).
        0x09 => {
            r.skip(16)?;
            r.sized()?;
            r.sized()?;
            let n = usize::try_from(r.u64()?).ok()?;
            r.skip(n)?;
            r.skip(4)
        }
        // Attachment index: five u64, name, media type.
        0x0A => {
            r.skip(40)?;
            r.sized()?;
            r.sized()
        }
        // Statistics: counts and times, then the per-channel counts.
        0x0B => {
            r.skip(8 + 2 + 4 * 4 + 16)?;
            r.map(|m| m.skip(10))
        }
        // Metadata: name, map.
        0x0C => {
            r.sized()?;
            r.map(|m| {
                m.sized()?;
                m.sized()
            })
        }
        // Metadata index: offset, length, name.
        0x0D => {
            r.skip(16)?;
            r.sized()
        }
        // Messages (fixed header, data to the end), summary offsets: nothing sized inside.
        _ => Some(()),
    }
}

fn what(op: u8) -> &'static str {
    match op {
        0x01 => "a header's string",
        0x02 => "the footer",
        0x03 => "a schema's field",
        0x04 => "a channel's field",
        0x06 => "a chunk's field",
        0x07 => "a message index",
        0x08 => "a chunk index",
        0x09 => "an attachment's field",
        0x0A => "an attachment index",
        0x0B => "the statistics",
        0x0C => "a metadata record",
        0x0D => "a metadata index",
        0x0F => "the data end record",
        _ => "a record's length",
    }
}

/// Decompresses a chunk's records into a buffer that never grows past `declared + 1` bytes.
fn decompress(at: usize, name: &[u8], data: &[u8], declared: u64) -> Result<Vec<u8>, Corrupt> {
    let (compression, ratio) = match name {
        b"zstd" => ("zstd", MAX_ZSTD_RATIO),
        b"lz4" => ("lz4", MAX_LZ4_RATIO),
        _ => {
            return Err(Corrupt::Compression {
                at,
                name: String::from_utf8_lossy(name).into_owned(),
            })
        }
    };
    let compressed = data.len() as u64;
    let limit = compressed.saturating_mul(ratio).min(MAX_CHUNK_BYTES);
    if declared > limit {
        return Err(Corrupt::ChunkTooLarge {
            at,
            declared,
            compressed,
            limit,
        });
    }
    let fail = |e: std::io::Error| Corrupt::Decompress {
        at,
        compression,
        why: e.to_string(),
    };
    let mut out = Vec::new();
    let cap = declared + 1;
    if compression == "zstd" {
        zstd::stream::read::Decoder::with_buffer(data)
            .map_err(fail)?
            .take(cap)
            .read_to_end(&mut out)
            .map_err(fail)?;
    } else {
        lz4::Decoder::new(data)
            .map_err(fail)?
            .take(cap)
            .read_to_end(&mut out)
            .map_err(fail)?;
    }
    if out.len() as u64 != declared {
        return Err(Corrupt::Decompress {
            at,
            compression,
            why: if out.len() as u64 > declared {
                format!("more than the {declared} uncompressed bytes it declares")
            } else {
                format!(
                    "{} uncompressed bytes, not the {declared} it declares",
                    out.len()
                )
            },
        });
    }
    Ok(out)
}

/// Checks a chunk at byte `at` of the file: its fields, its size, its CRC, then its records.
fn chunk(at: usize, body: &[u8]) -> Result<(), Corrupt> {
    let bad = || BadLength {
        at,
        what: what(0x06),
        chunk: None,
    };
    let mut r = Body { b: body, at: 0 };
    r.skip(16).ok_or_else(bad)?;
    let declared = r.u64().ok_or_else(bad)?;
    let crc = r.u32().ok_or_else(bad)?;
    let n = r.len32().ok_or_else(bad)?;
    let compression = r.take(n).ok_or_else(bad)?;
    let len = r
        .u64()
        .and_then(|l| usize::try_from(l).ok())
        .ok_or_else(bad)?;
    let data = r.take(len).ok_or_else(bad)?;
    let owned;
    let records = if compression.is_empty() {
        if declared != len as u64 {
            return Err(bad().into());
        }
        data
    } else {
        owned = decompress(at, compression, data, declared)?;
        &owned[..]
    };
    if crc != 0 {
        let calculated = crc32fast::hash(records);
        if calculated != crc {
            return Err(Corrupt::BadCrc {
                what: CrcOf::Chunk { at },
                saved: crc,
                calculated,
            });
        }
    }
    walk(&[], records, 0, Some(at))
}

/// Walks a sequence of records (`opcode u8, length u64, body`): those of the file (`file` is the
/// whole file, `records` starts at its byte `base`; `in_chunk` is `None`) or those of the chunk
/// at byte `in_chunk` (offsets are then in its records).
fn walk(file: &[u8], records: &[u8], base: usize, in_chunk: Option<usize>) -> Result<(), Corrupt> {
    let mut pos = 0;
    // Where the summary section starts: after the data end record.
    let mut summary_from = None;
    while pos < records.len() {
        let at = base + pos;
        let bad = |op| BadLength {
            at,
            what: what(op),
            chunk: in_chunk,
        };
        let op = records[pos];
        let len = records
            .get(pos + 1..pos + 9)
            .map(|l| {
                let mut a = [0u8; 8];
                a.copy_from_slice(l);
                u64::from_le_bytes(a)
            })
            .and_then(|l| usize::try_from(l).ok())
            .ok_or(bad(0))?;
        let end = (pos + 9)
            .checked_add(len)
            .filter(|&e| e <= records.len())
            .ok_or(bad(0))?;
        let body = &records[pos + 9..end];
        let misplaced = |what| {
            Err(Corrupt::Misplaced {
                at,
                what,
                chunk: in_chunk,
            })
        };
        match op {
            0x02 | 0x06 | 0x0F if in_chunk.is_some() => {
                return misplaced("a chunk, data end or footer record inside a chunk")
            }
            0x06 => chunk(at, body)?,
            // Data end: the data section's CRC, over every byte before this record.
            0x0F => {
                let saved = Body { b: body, at: 0 }.u32().ok_or(bad(op))?;
                if saved != 0 {
                    let calculated = crc32fast::hash(&file[..at]);
                    if calculated != saved {
                        return Err(Corrupt::BadCrc {
                            what: CrcOf::DataSection { at },
                            saved,
                            calculated,
                        });
                    }
                }
                summary_from = Some(base + end);
            }
            // Footer: summary start, summary offset start, then the CRC of the summary section
            // and of the footer up to the CRC.
            0x02 => {
                if end != records.len() {
                    return misplaced("a footer before the end");
                }
                let mut r = Body { b: body, at: 0 };
                let start = r.u64().ok_or(bad(op))?;
                r.skip(8).ok_or(bad(op))?;
                let saved = r.u32().ok_or(bad(op))?;
                if saved != 0 {
                    let from = summary_from.unwrap_or_else(|| {
                        usize::try_from(start)
                            .ok()
                            .filter(|&s| s > 0 && s <= at)
                            .unwrap_or(at)
                    });
                    let calculated = crc32fast::hash(&file[from..at + 9 + 16]);
                    if calculated != saved {
                        return Err(Corrupt::BadCrc {
                            what: CrcOf::SummarySection { at },
                            saved,
                            calculated,
                        });
                    }
                }
            }
            _ => fields(op, body).ok_or(bad(op))?,
        }
        pos = end;
    }
    Ok(())
}

/// Checks a whole file: the magic, then every record up to the footer, with the records of every
/// chunk. A file that is not an MCAP file at all passes (the `mcap` crate says what is wrong
/// with it).
///
/// # Errors
/// [`Corrupt`] for the first thing found wrong.
pub fn check(file: &[u8]) -> Result<(), Corrupt> {
    let Some(body) = file.strip_prefix(MAGIC) else {
        return Ok(());
    };
    let body = body.strip_suffix(MAGIC).unwrap_or(body);
    walk(file, body, MAGIC.len(), None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(op: u8, body: &[u8]) -> Vec<u8> {
        let mut v = vec![op];
        v.extend((body.len() as u64).to_le_bytes());
        v.extend(body);
        v
    }

    #[test]
    fn a_string_longer_than_its_record_is_refused() {
        let mut good = MAGIC.to_vec();
        let mut header = Vec::new();
        header.extend(4u32.to_le_bytes());
        header.extend(b"ros2");
        header.extend(0u32.to_le_bytes());
        good.extend(rec(0x01, &header));
        assert_eq!(check(&good), Ok(()));
        let mut bad = MAGIC.to_vec();
        let mut header = Vec::new();
        header.extend(0xffff_fff0u32.to_le_bytes());
        header.extend(b"ros2");
        bad.extend(rec(0x01, &header));
        assert_eq!(
            check(&bad),
            Err(Corrupt::Length(BadLength {
                at: 8,
                what: "a header's string",
                chunk: None,
            }))
        );
        // A record longer than the file.
        let mut cut = MAGIC.to_vec();
        cut.push(0x01);
        cut.extend(1000u64.to_le_bytes());
        assert!(check(&cut).is_err());
    }

    #[test]
    fn an_attachment_without_room_for_its_crc_is_refused() {
        let mut body = Vec::new();
        body.extend([0u8; 16]);
        body.extend(0u32.to_le_bytes());
        body.extend(0u32.to_le_bytes());
        body.extend(3u64.to_le_bytes());
        body.extend(b"abc");
        let mut file = MAGIC.to_vec();
        file.extend(rec(0x09, &body));
        assert_eq!(
            check(&file),
            Err(Corrupt::Length(BadLength {
                at: 8,
                what: "an attachment's field",
                chunk: None,
            }))
        );
        body.extend(0u32.to_le_bytes());
        let mut file = MAGIC.to_vec();
        file.extend(rec(0x09, &body));
        assert_eq!(check(&file), Ok(()));
    }

    #[test]
    fn a_chunk_declaring_more_than_its_compression_can_yield_is_refused() {
        // 10 compressed bytes of zstd may declare 327,680 uncompressed, not one more.
        let mut body = Vec::new();
        body.extend([0u8; 16]);
        body.extend((10 * MAX_ZSTD_RATIO + 1).to_le_bytes());
        body.extend(0u32.to_le_bytes());
        body.extend(4u32.to_le_bytes());
        body.extend(b"zstd");
        body.extend(10u64.to_le_bytes());
        body.extend([0u8; 10]);
        let mut file = MAGIC.to_vec();
        file.extend(rec(0x06, &body));
        assert_eq!(
            check(&file),
            Err(Corrupt::ChunkTooLarge {
                at: 8,
                declared: 327_681,
                compressed: 10,
                limit: 327_680,
            })
        );
    }
}
