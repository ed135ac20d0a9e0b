//! What a file is, from its first bytes: for telling a user that the file they passed is of
//! another kind than the one expected (an image where the map's YAML goes, a YAML where a blob
//! goes), instead of quoting a parser's message about its bytes.

use std::fmt;

/// A kind of file a user may pass in the wrong place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A picture: PNG, netpbm (PGM, PPM, PBM, PAM), JPEG, GIF, TIFF or BMP.
    Image,
    /// A distance-field blob (`field build`'s output; magic `BFDF`).
    FieldBlob,
    /// A ROS 2 bag: a SQLite 3 database (`.db3`) or an MCAP file.
    Bag,
}

impl fmt::Display for FileKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Image => "an image",
            Self::FieldBlob => "a distance-field blob",
            Self::Bag => "a ROS 2 bag",
        })
    }
}

/// The kind `head` (a file's first bytes; 16 are enough) shows, if it is one of
/// [`FileKind`]'s. Text files (YAML, CARMEN logs, TOML) are none of them.
pub fn file_kind(head: &[u8]) -> Option<FileKind> {
    let starts = |magic: &[u8]| head.starts_with(magic);
    let netpbm = matches!(
        head,
        [b'P', b'1'..=b'7', b' ' | b'\t' | b'\n' | b'\r' | b'#', ..]
    );
    if starts(b"\x89PNG\r\n\x1a\n")
        || netpbm
        || starts(b"\xff\xd8\xff")
        || starts(b"GIF87a")
        || starts(b"GIF89a")
        || starts(b"II*\0")
        || starts(b"MM\0*")
        || (starts(b"BM") && head.len() >= 14 && head.get(6..10) == Some(&[0, 0, 0, 0]))
    {
        Some(FileKind::Image)
    } else if starts(&beamfield::field::BLOB_MAGIC) {
        Some(FileKind::FieldBlob)
    } else if starts(b"SQLite format 3\0") || starts(b"\x89MCAP") {
        Some(FileKind::Bag)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_blobs_and_bags_are_told_from_text() {
        assert_eq!(file_kind(b"P5\n# CREATOR\n"), Some(FileKind::Image));
        assert_eq!(file_kind(b"P2 10 10 255"), Some(FileKind::Image));
        assert_eq!(
            file_kind(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"),
            Some(FileKind::Image)
        );
        assert_eq!(file_kind(b"BFDF\x01\0"), Some(FileKind::FieldBlob));
        assert_eq!(file_kind(b"SQLite format 3\0"), Some(FileKind::Bag));
        // map_server YAML, CARMEN logs, and text that merely starts like a magic number.
        assert_eq!(file_kind(b"image: intel.pgm\nresolution: 0.05\n"), None);
        assert_eq!(file_kind(b"# CARMEN Logfile\nFLASER 180 "), None);
        assert_eq!(file_kind(b"P5"), None);
        assert_eq!(file_kind(b"Pose: 1 2 3"), None);
        assert_eq!(file_kind(b"BM: not a bitmap at all"), None);
        assert_eq!(file_kind(b""), None);
    }
}
