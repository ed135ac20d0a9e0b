//! sqlite3 bags: the `.db3` files rosbag2 writes with its `sqlite3` storage (the default up to
//! Humble), read with SQLite itself (the `rusqlite` crate, SQLite compiled in).
//!
//! What is read is what every rosbag2 sqlite3 schema since Foxy has: the table `topics` with
//! the columns `id`, `name`, `type` and `serialization_format`, and the table `messages` with
//! `topic_id`, `timestamp` and `data` (the CDR bytes). Other tables and columns (metadata,
//! message definitions, type hashes, QoS profiles) are not read.
//!
//! Nothing in the file is trusted: the file must be a regular file of at most
//! [`crate::MAX_BAG_FILE_BYTES`] that starts with SQLite's 16-byte header; it is opened
//! read-only and immutable (SQLite writes nothing beside it and takes no lock; a journal or WAL
//! left by an interrupted recording is not applied); `topics` and `messages` must be tables,
//! not views; no value longer than [`MAX_DB3_MESSAGE_BYTES`] is read (SQLite refuses it before
//! it allocates it, `SQLITE_LIMIT_LENGTH`); SQLite checks each page's cells as it reads them
//! (`cell_size_check`) and reports a damaged file as corrupt, which is refused with its
//! message. Only the messages of the topics asked for are fetched, in the order rosbag2's own
//! reader plays them (by receive timestamp, then by row id).

use std::collections::BTreeMap;
use std::path::Path;

use rusqlite::{ffi::ErrorCode, Connection, OpenFlags};

use crate::{check_regular_file, Bag, BagError, Role, MAX_BAG_FILE_BYTES};

/// The first 16 bytes of every SQLite 3 database file.
pub const SQLITE_HEADER: &[u8; 16] = b"SQLite format 3\0";

/// Largest value read from a `.db3` file, bytes: 64 MiB (a message's CDR bytes; a 1,081-beam
/// LaserScan takes about 9 KB). A longer one is refused ([`BagError::Db3TooLong`]).
pub const MAX_DB3_MESSAGE_BYTES: u32 = 64 << 20;

/// Percent-encodes a path for an SQLite `file:` URI (every byte but unreserved ones and `/`).
fn uri(path: &Path) -> Result<String, BagError> {
    let abs = std::path::absolute(path).map_err(|e| BagError::Io(path.into(), e))?;
    let text = abs.to_str().ok_or_else(|| {
        BagError::Io(
            path.into(),
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path is not UTF-8"),
        )
    })?;
    let mut out = String::from("file:");
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out.push_str("?immutable=1");
    Ok(out)
}

/// An SQLite error as the bag's: a corrupt or non-database file, a value over the limit, or
/// any other failure with SQLite's message.
fn db_error(file: &Path, limit: u32) -> impl Fn(rusqlite::Error) -> BagError + '_ {
    move |e| match e.sqlite_error_code() {
        Some(ErrorCode::DatabaseCorrupt | ErrorCode::NotADatabase) => {
            BagError::Db3Damaged(file.into(), e.to_string())
        }
        Some(ErrorCode::TooBig) => BagError::Db3TooLong {
            path: file.into(),
            limit,
        },
        _ => BagError::Db3(file.into(), e.to_string()),
    }
}

/// Opens a `.db3` file read-only and immutable, with the limits of the module docs.
fn open(file: &Path, limit: u32) -> Result<Connection, BagError> {
    check_regular_file(file, MAX_BAG_FILE_BYTES)?;
    let mut head = [0u8; 16];
    {
        use std::io::Read;
        let mut f = std::fs::File::open(file).map_err(|e| BagError::Io(file.into(), e))?;
        match f.read_exact(&mut head) {
            Ok(()) if &head == SQLITE_HEADER => {}
            Ok(()) => return Err(BagError::NotSqlite(file.into())),
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                return Err(BagError::NotSqlite(file.into()))
            }
            Err(e) => return Err(BagError::Io(file.into(), e)),
        }
    }
    let err = db_error(file, limit);
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY
        | OpenFlags::SQLITE_OPEN_URI
        | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let db = Connection::open_with_flags(uri(file)?, flags).map_err(&err)?;
    db.set_limit(
        rusqlite::limits::Limit::SQLITE_LIMIT_LENGTH,
        i32::try_from(limit).unwrap_or(i32::MAX),
    )
    .map_err(&err)?;
    db.execute_batch(
        "PRAGMA trusted_schema = OFF; PRAGMA cell_size_check = ON; PRAGMA mmap_size = 0;",
    )
    .map_err(&err)?;
    Ok(db)
}

/// A topic of the bag: its name, type and serialization format.
struct Topic {
    name: String,
    ty: String,
    format: String,
}

impl Bag {
    /// Adds the messages of one `.db3` file to the bag: every topic's type and count, and the
    /// messages of the topics of `roles` decoded as [`Bag::read`] says. `last` holds each
    /// topic's last stamp across the files of a bag.
    pub(crate) fn add_db3<'t>(
        &mut self,
        file: &Path,
        roles: &[(&'t str, Role)],
        last: &mut BTreeMap<&'t str, u64>,
        limit: u32,
    ) -> Result<(), BagError> {
        let db = open(file, limit)?;
        let err = db_error(file, limit);
        for table in ["topics", "messages"] {
            let found: i64 = db
                .query_row(
                    "SELECT count(*) FROM sqlite_schema WHERE type = 'table' AND name = ?1",
                    [table],
                    |r| r.get(0),
                )
                .map_err(&err)?;
            if found == 0 {
                return Err(BagError::Db3Schema {
                    path: file.into(),
                    what: format!("no table {table}"),
                });
            }
        }
        let schema = |e: rusqlite::Error| match e.sqlite_error_code() {
            Some(ErrorCode::Unknown) | None => BagError::Db3Schema {
                path: file.into(),
                what: e.to_string(),
            },
            _ => err(e),
        };
        let mut topics: BTreeMap<i64, Topic> = BTreeMap::new();
        {
            let mut q = db
                .prepare("SELECT id, name, type, serialization_format FROM topics")
                .map_err(schema)?;
            let mut rows = q.query([]).map_err(&err)?;
            while let Some(r) = rows.next().map_err(&err)? {
                let text = |i: usize| -> Result<String, BagError> {
                    let v = r.get_ref(i).map_err(&err)?;
                    match v.as_str() {
                        Ok(s) => Ok(s.to_owned()),
                        Err(_) => Err(BagError::Db3Schema {
                            path: file.into(),
                            what: format!("a topic's column {i} is not text"),
                        }),
                    }
                };
                let id: i64 = r.get(0).map_err(|_| BagError::Db3Schema {
                    path: file.into(),
                    what: "a topic's id is not an integer".into(),
                })?;
                topics.insert(
                    id,
                    Topic {
                        name: text(1)?,
                        ty: text(2)?,
                        format: text(3)?,
                    },
                );
            }
        }
        // Every topic's message count (as the MCAP reader counts the messages it meets).
        let mut read_ids: Vec<(i64, &'t str, Role)> = Vec::new();
        {
            let mut q = db
                .prepare("SELECT topic_id, count(*) FROM messages GROUP BY topic_id")
                .map_err(schema)?;
            let mut rows = q.query([]).map_err(&err)?;
            while let Some(r) = rows.next().map_err(&err)? {
                let (id, n): (Option<i64>, i64) =
                    (r.get(0).unwrap_or(None), r.get(1).map_err(&err)?);
                let n = u64::try_from(n).unwrap_or(0);
                let Some(t) = id.and_then(|id| topics.get(&id)) else {
                    *self
                        .skipped
                        .entry("a message of no recorded topic".into())
                        .or_default() += n;
                    continue;
                };
                self.topics
                    .entry(t.name.clone())
                    .or_insert_with(|| (t.ty.clone(), 0))
                    .1 += n;
                let Some(&(name, role)) = roles.iter().find(|(r, _)| *r == t.name) else {
                    continue;
                };
                if !role.accepts(&t.ty) {
                    return Err(BagError::WrongType {
                        topic: t.name.clone(),
                        got: t.ty.clone(),
                        want: role.want(),
                    });
                }
                if t.format != "cdr" {
                    return Err(BagError::Encoding {
                        topic: t.name.clone(),
                        encoding: t.format.clone(),
                    });
                }
                if let Some(id) = id {
                    read_ids.push((id, name, role));
                }
            }
        }
        if read_ids.is_empty() {
            return Ok(());
        }
        // The ids are integers from the file, written as such: nothing of the file's text
        // reaches the statement.
        let list = read_ids
            .iter()
            .map(|(id, _, _)| id.to_string())
            .collect::<Vec<_>>()
            .join(",");
        let mut q = db
            .prepare(&format!(
                "SELECT topic_id, data FROM messages WHERE topic_id IN ({list}) \
                 ORDER BY timestamp, id"
            ))
            .map_err(schema)?;
        let mut rows = q.query([]).map_err(&err)?;
        while let Some(r) = rows.next().map_err(&err)? {
            let id: Option<i64> = r.get(0).unwrap_or(None);
            let Some(&(_, name, role)) = read_ids.iter().find(|(i, _, _)| Some(*i) == id) else {
                continue;
            };
            match r.get_ref(1).map_err(&err)?.as_bytes() {
                Ok(data) => self.take(name, role, data, last),
                Err(_) => self.skip(format!("{name}: malformed (its data is not a blob)")),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_over_the_limit_is_refused_before_it_is_read() {
        let file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tools/tests/data/intel-bag-db3/intel-bag-db3.db3");
        let topics = crate::Topics {
            reference: Some("/ground_truth".into()),
            ..crate::Topics::default()
        };
        let roles = crate::roles(&topics);
        let read = |limit| Bag::default().add_db3(&file, &roles, &mut BTreeMap::new(), limit);
        assert!(read(MAX_DB3_MESSAGE_BYTES).is_ok());
        // A 180-beam scan's CDR is about 800 bytes.
        match read(400) {
            Err(BagError::Db3TooLong { limit: 400, .. }) => {}
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn uri_escapes_everything_sqlite_reads_in_a_uri() {
        let u = uri(Path::new("/a b/c?d#e%f.db3")).unwrap();
        assert_eq!(u, "file:/a%20b/c%3Fd%23e%25f.db3?immutable=1");
    }
}
