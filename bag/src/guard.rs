//! A check of an MCAP file's length fields before the `mcap` crate parses it.
//!
//! The crate (0.26) reserves memory for a string, a byte array or a map from the length written
//! in the file before it reads the bytes. A malformed file can therefore make it allocate 4 GiB
//! for a record a few bytes long; fuzzing found this (`fuzz/fuzz_targets/bag_decode.rs`). This
//! check walks every record and refuses the file when any length field points past the end of
//! its record. It walks the records inside uncompressed chunks, and bounds a compressed chunk's
//! declared uncompressed size by [`MAX_CHUNK_BYTES`]. The records inside a compressed chunk are
//! the crate's to parse.

/// Largest uncompressed chunk accepted, bytes (rosbag2 writes chunks of about 4 MiB).
pub const MAX_CHUNK_BYTES: u64 = 256 << 20;

const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Where a file's length fields went wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadLength {
    /// Byte offset of the record in the file (or in its chunk's records).
    pub at: usize,
    pub what: &'static str,
}

impl std::fmt::Display for BadLength {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} at byte {} points past its record",
            self.what, self.at
        )
    }
}

/// A cursor over one record's body.
struct Body<'a> {
    b: &'a [u8],
    at: usize,
}

impl Body<'_> {
    fn skip(&mut self, n: usize) -> Option<()> {
        self.at = self.at.checked_add(n).filter(|&e| e <= self.b.len())?;
        Some(())
    }
    fn u32(&mut self) -> Option<usize> {
        let v = self.b.get(self.at..self.at + 4)?;
        self.at += 4;
        Some(u32::from_le_bytes([v[0], v[1], v[2], v[3]]) as usize)
    }
    fn u64(&mut self) -> Option<u64> {
        let v = self.b.get(self.at..self.at + 8)?;
        self.at += 8;
        let mut a = [0u8; 8];
        a.copy_from_slice(v);
        Some(u64::from_le_bytes(a))
    }
    /// A u32-length-prefixed string or byte array.
    fn sized(&mut self) -> Option<()> {
        let n = self.u32()?;
        self.skip(n)
    }
    /// A u32 byte length, then `inner` over exactly those bytes.
    fn map(&mut self, inner: impl Fn(&mut Body) -> Option<()>) -> Option<()> {
        let n = self.u32()?;
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

/// Checks one record body of type `op`; `None` when a length field points past it.
fn record(op: u8, b: &[u8], depth: u8) -> Option<()> {
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
        // Chunk: start, end, uncompressed size, CRC, compression, records.
        0x06 => {
            r.skip(16)?;
            let uncompressed = r.u64()?;
            r.skip(4)?;
            let n = r.u32()?;
            let compression = b.get(r.at..r.at.checked_add(n)?)?;
            r.skip(n)?;
            let len = usize::try_from(r.u64()?).ok()?;
            let records = b.get(r.at..r.at.checked_add(len)?)?;
            if compression.is_empty() {
                if uncompressed != len as u64 || depth > 0 {
                    return None;
                }
                records_of(records, depth + 1).ok()
            } else {
                (uncompressed <= MAX_CHUNK_BYTES).then_some(())
            }
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
        // Attachment: two times, name, media type, data.
        0x09 => {
            r.skip(16)?;
            r.sized()?;
            r.sized()?;
            let n = usize::try_from(r.u64()?).ok()?;
            r.skip(n)
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
        // Messages (fixed header, data to the end), footers, data end, summary offsets:
        // nothing sized inside.
        _ => Some(()),
    }
}

fn what(op: u8) -> &'static str {
    match op {
        0x01 => "a header's string",
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
        _ => "a record's length",
    }
}

/// Walks a sequence of records (`opcode u8, length u64, body`).
fn records_of(mut b: &[u8], depth: u8) -> Result<(), BadLength> {
    let start = b.len();
    while !b.is_empty() {
        let at = start - b.len();
        let bad = |op| BadLength { at, what: what(op) };
        let (&op, rest) = b.split_first().ok_or(bad(0))?;
        let len = rest
            .get(..8)
            .map(|l| u64::from_le_bytes(l.try_into().unwrap_or([0xff; 8])))
            .and_then(|l| usize::try_from(l).ok())
            .ok_or(bad(0))?;
        let body = rest
            .get(8..8usize.checked_add(len).ok_or(bad(0))?)
            .ok_or(bad(0))?;
        record(op, body, depth).ok_or(bad(op))?;
        b = &rest[8 + len..];
        // The footer ends the file (the closing magic follows, already taken off); it has no
        // place inside a chunk, and nothing may follow it.
        if op == 0x02 {
            if depth > 0 || !b.is_empty() {
                return Err(BadLength {
                    at,
                    what: "a footer before the end",
                });
            }
            break;
        }
    }
    Ok(())
}

/// Checks a whole file: the magic, then every record up to the footer. A file that is not an
/// MCAP file at all passes (the `mcap` crate says what is wrong with it).
///
/// # Errors
/// [`BadLength`] for the first length field that points past its record.
pub fn check(file: &[u8]) -> Result<(), BadLength> {
    let Some(body) = file.strip_prefix(MAGIC) else {
        return Ok(());
    };
    let body = body.strip_suffix(MAGIC).unwrap_or(body);
    records_of(body, 0).map_err(|e| BadLength {
        at: e.at + MAGIC.len(),
        ..e
    })
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
            Err(BadLength {
                at: 8,
                what: "a header's string"
            })
        );
        // A record longer than the file.
        let mut cut = MAGIC.to_vec();
        cut.push(0x01);
        cut.extend(1000u64.to_le_bytes());
        assert!(check(&cut).is_err());
    }
}
