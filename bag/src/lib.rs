//! ROS 2 bags in for beamfield's host tools (`beamfield track --bag`, `cargo xtask robot --bag`): the scans, odometry, a reference pose and the laser's mount from an MCAP file
//! (what `ros2 bag record` writes since Iron) or an sqlite3 `.db3` file (its default up to
//! Humble, [`sqlite`]), by topic, with each message's CDR decoded here
//! ([`cdr`]): `sensor_msgs/msg/LaserScan`, `nav_msgs/msg/Odometry`,
//! `geometry_msgs/msg/PoseWithCovarianceStamped` or `PoseStamped`, `tf2_msgs/msg/TFMessage`.
//!
//! A message that cannot be used is skipped and counted by cause (malformed, stamped before
//! the previous one on its topic, a scan with no ranges …); a missing topic or one of another
//! type is an error that names what the bag does have.
//!
//! Nothing in a file is trusted before it is checked: a bag file must be a regular file of at
//! most [`MAX_BAG_FILE_BYTES`] ([`read_bounded`]), and every record, chunk and CRC of it is
//! checked by [`guard::check`] before the `mcap` crate parses it; a `.db3` file is opened
//! read-only with the limits [`sqlite`] lists.

pub mod cdr;
pub mod guard;
pub mod sqlite;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cdr::{Cdr, CdrError};

/// A pose in the plane: metres, metres, radians (counter-clockwise).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

/// A value and its header stamp, ns since the epoch of the bag's clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stamped<T> {
    pub stamp_ns: u64,
    pub value: T,
}

/// A `sensor_msgs/LaserScan` (angles in radians, ranges in metres; beams outside
/// `[range_min, range_max]` or not finite are not readings, as in ROS).
#[derive(Clone, Debug, PartialEq)]
pub struct LaserScan {
    pub frame_id: String,
    pub angle_min: f32,
    pub angle_max: f32,
    pub angle_increment: f32,
    pub range_min: f32,
    pub range_max: f32,
    pub ranges: Vec<f32>,
}

/// A transform from `/tf_static`: `child`'s pose in `parent`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mount {
    pub parent: String,
    pub child: String,
    pub pose: Pose2,
}

/// Odometry from the transforms of a `tf2_msgs/TFMessage` topic (`/tf`): the pose of
/// `base_frame` in `odom_frame`, at each transform's header stamp, as a robot's odometry node
/// broadcasts it when it publishes no `nav_msgs/Odometry`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OdomFromTf {
    pub topic: String,
    pub odom_frame: String,
    pub base_frame: String,
}

/// Which topics to read.
#[derive(Clone, Debug)]
pub struct Topics {
    pub scan: String,
    pub odom: String,
    /// A reference pose to compare with (a recorded `amcl_pose`, ground truth), if any.
    pub reference: Option<String>,
    pub tf_static: String,
    /// Where the odometry comes from when the bag has no `odom` topic (none: the topic must
    /// be there).
    pub odom_from_tf: Option<OdomFromTf>,
}

impl Default for Topics {
    fn default() -> Self {
        Self {
            scan: "/scan".into(),
            odom: "/odom".into(),
            reference: None,
            tf_static: "/tf_static".into(),
            odom_from_tf: None,
        }
    }
}

/// What a bag holds for localization.
#[derive(Clone, Debug, Default)]
pub struct Bag {
    pub scans: Vec<Stamped<LaserScan>>,
    pub odometry: Vec<Stamped<Pose2>>,
    pub reference: Vec<Stamped<Pose2>>,
    pub mounts: Vec<Mount>,
    /// Whether [`Bag::odometry`] came from `/tf` ([`Topics::odom_from_tf`]) because the bag
    /// has no odometry topic.
    pub odometry_from_tf: bool,
    /// The odometry found on `/tf` while the bag is read; moved into `odometry` at the end
    /// when the odometry topic is missing.
    tf_odometry: Vec<Stamped<Pose2>>,
    /// Where odometry on `/tf` is looked for.
    odom_tf: Option<OdomFromTf>,
    /// Parent → child of every transform seen on `/tf` (for [`BagError::NoOdometry`]; at most
    /// [`MAX_TF_PAIRS_LISTED`]).
    tf_pairs: std::collections::BTreeSet<String>,
    /// Messages not used, by cause.
    pub skipped: BTreeMap<String, u64>,
    /// Every topic of the bag: its type and message count.
    pub topics: BTreeMap<String, (String, u64)>,
}

/// Most distinct parent → child pairs of `/tf` kept to name in [`BagError::NoOdometry`].
pub const MAX_TF_PAIRS_LISTED: usize = 64;

/// Largest MCAP file read, bytes: 2 GiB. rosbag2 splits a recording into files of a size the
/// user chooses; a file is read whole into memory.
pub const MAX_BAG_FILE_BYTES: u64 = 2 << 30;

/// A bag that could not be read.
#[derive(Debug)]
pub enum BagError {
    Io(PathBuf, std::io::Error),
    /// The path names a device, a FIFO or something else that is not a regular file.
    NotAFile(PathBuf),
    /// The file is larger than `limit` bytes: `bytes` is its size, or `limit + 1` for a file
    /// that grew past the limit while it was read.
    TooLarge {
        path: PathBuf,
        bytes: u64,
        limit: u64,
    },
    /// The file's records, chunks or CRCs are damaged ([`guard::check`]).
    Corrupt(PathBuf, guard::Corrupt),
    /// A directory with no `.mcap` and no `.db3` file.
    NoBagFile(PathBuf),
    /// A directory with both `.mcap` and `.db3` files: two recordings, or one converted beside
    /// the other.
    MixedStorage(PathBuf),
    Mcap(PathBuf, String),
    /// A `.db3` file that does not start with SQLite's header ([`sqlite::SQLITE_HEADER`]).
    NotSqlite(PathBuf),
    /// An SQLite database that is not a rosbag2 bag: a table or column missing (`what`).
    Db3Schema {
        path: PathBuf,
        what: String,
    },
    /// An SQLite database that SQLite finds damaged (SQLite's message).
    Db3Damaged(PathBuf, String),
    /// A value in a `.db3` file longer than `limit` bytes ([`sqlite::MAX_DB3_MESSAGE_BYTES`]).
    Db3TooLong {
        path: PathBuf,
        limit: u32,
    },
    /// Any other failure of SQLite on a `.db3` file (SQLite's message).
    Db3(PathBuf, String),
    /// A topic asked for that the bag does not have.
    MissingTopic {
        topic: String,
        available: Vec<String>,
    },
    /// No odometry topic, and no transform of the odometry frame to the base frame on `/tf`.
    NoOdometry {
        topic: String,
        /// Where the odometry was looked for on `/tf` (boxed: it keeps the error small).
        tf: Box<OdomFromTf>,
        /// Parent → child of every transform seen on the tf topic.
        tf_pairs: Vec<String>,
        available: Vec<String>,
    },
    /// A topic of a type the reader cannot use for it.
    WrongType {
        topic: String,
        got: String,
        want: &'static str,
    },
    /// A topic that is not CDR-encoded.
    Encoding {
        topic: String,
        encoding: String,
    },
}

impl std::fmt::Display for BagError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "cannot read {}: {e}", p.display()),
            Self::NotAFile(p) => write!(f, "{} is not a regular file", p.display()),
            Self::TooLarge { path, bytes, limit } => write!(
                f,
                "{} is larger than {limit} bytes, the limit for a bag file ({bytes} bytes seen)",
                path.display()
            ),
            Self::Corrupt(p, e) => write!(f, "{} is damaged: {e}", p.display()),
            Self::NoBagFile(p) => write!(f, "{} holds no .mcap and no .db3 file", p.display()),
            Self::MixedStorage(p) => write!(
                f,
                "{} holds both .mcap and .db3 files; give the file to read",
                p.display()
            ),
            Self::Mcap(p, e) => write!(f, "{} is not a readable MCAP file: {e}", p.display()),
            Self::NotSqlite(p) => write!(
                f,
                "{} is not an SQLite database (no SQLite header), so not a .db3 bag",
                p.display()
            ),
            Self::Db3Schema { path, what } => write!(
                f,
                "{} is an SQLite database but not a rosbag2 bag: {what}",
                path.display()
            ),
            Self::Db3Damaged(p, e) => write!(f, "{} is damaged: {e}", p.display()),
            Self::Db3TooLong { path, limit } => write!(
                f,
                "{} holds a value longer than {limit} bytes, the limit for a message",
                path.display()
            ),
            Self::Db3(p, e) => write!(f, "{} is not a readable .db3 bag: {e}", p.display()),
            Self::MissingTopic { topic, available } => write!(
                f,
                "the bag has no topic {topic}; it has {}",
                if available.is_empty() {
                    "none".into()
                } else {
                    available.join(", ")
                }
            ),
            Self::NoOdometry {
                topic,
                tf,
                tf_pairs,
                available,
            } => write!(
                f,
                "the bag has no odometry: no topic {topic}, and no transform {} → {} on {} ({}); it has {}",
                tf.odom_frame,
                tf.base_frame,
                tf.topic,
                if tf_pairs.is_empty() {
                    "none there".to_owned()
                } else {
                    format!("there: {}", tf_pairs.join(", "))
                },
                if available.is_empty() {
                    "no topic".into()
                } else {
                    available.join(", ")
                }
            ),
            Self::WrongType { topic, got, want } => {
                write!(f, "topic {topic} is {got}, not {want}")
            }
            Self::Encoding { topic, encoding } => {
                write!(f, "topic {topic} is encoded as {encoding:?}, not cdr")
            }
        }
    }
}

impl std::error::Error for BagError {}

/// Checks that `path` is a regular file of at most `limit` bytes, before it is opened.
///
/// # Errors
/// [`BagError::Io`], [`BagError::NotAFile`], [`BagError::TooLarge`].
pub fn check_regular_file(path: &Path, limit: u64) -> Result<(), BagError> {
    let meta = std::fs::metadata(path).map_err(|e| BagError::Io(path.to_path_buf(), e))?;
    if !meta.is_file() {
        return Err(BagError::NotAFile(path.to_path_buf()));
    }
    if meta.len() > limit {
        return Err(BagError::TooLarge {
            path: path.to_path_buf(),
            bytes: meta.len(),
            limit,
        });
    }
    Ok(())
}

/// Reads a whole regular file of at most `limit` bytes. A device, FIFO or directory is refused
/// before it is opened ([`BagError::NotAFile`]); a file whose size is over the limit is refused
/// before it is read, and one that grows past the limit while being read is refused after
/// `limit + 1` bytes ([`BagError::TooLarge`]).
///
/// # Errors
/// [`BagError::Io`], [`BagError::NotAFile`], [`BagError::TooLarge`].
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, BagError> {
    use std::io::Read;
    let io = |e| BagError::Io(path.to_path_buf(), e);
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(BagError::NotAFile(path.to_path_buf()));
    }
    let too_large = |bytes| BagError::TooLarge {
        path: path.to_path_buf(),
        bytes,
        limit,
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let mut out = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(io)?;
    if out.len() as u64 > limit {
        return Err(too_large(out.len() as u64));
    }
    Ok(out)
}

/// How a bag file is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Storage {
    Mcap,
    Sqlite3,
}

/// A file's storage: sqlite3 when it starts with SQLite's header or is named `.db3`
/// (refused later if it is not SQLite), MCAP otherwise. Only a regular file is opened to look
/// (a FIFO or device is refused later by the reader of either storage, before it is opened).
fn storage_of(path: &Path) -> Storage {
    let mut head = [0u8; 16];
    let is_sqlite = std::fs::metadata(path).is_ok_and(|m| m.is_file())
        && std::fs::File::open(path)
            .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
            .is_ok()
        && &head == sqlite::SQLITE_HEADER;
    if is_sqlite || path.extension().is_some_and(|x| x == "db3") {
        Storage::Sqlite3
    } else {
        Storage::Mcap
    }
}

/// The sort key of a split bag's file: its name with a trailing number compared as a number
/// (rosbag2 names the files of a split recording `NAME_0`, `NAME_1`, … `NAME_10`).
fn split_order(p: &Path) -> (String, u64, String) {
    let stem = p
        .file_stem()
        .map_or(String::new(), |s| s.to_string_lossy().into());
    let digits = stem.len() - stem.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    let (head, num) = stem.split_at(stem.len() - digits);
    (head.to_owned(), num.parse().unwrap_or(0), stem.clone())
}

/// The files of a bag and their storage: the file itself, or the `.mcap` or `.db3` files of a
/// rosbag2 directory, in the order of a split recording's numbers.
fn bag_files(path: &Path) -> Result<Vec<(PathBuf, Storage)>, BagError> {
    if !path.is_dir() {
        return Ok(vec![(path.to_path_buf(), storage_of(path))]);
    }
    let mut files: Vec<(PathBuf, Storage)> = std::fs::read_dir(path)
        .map_err(|e| BagError::Io(path.into(), e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| match p.extension().and_then(|x| x.to_str()) {
            Some("mcap") => Some((p, Storage::Mcap)),
            Some("db3") => Some((p, Storage::Sqlite3)),
            _ => None,
        })
        .collect();
    files.sort_by_cached_key(|(p, _)| split_order(p));
    match (
        files.iter().any(|(_, s)| *s == Storage::Mcap),
        files.iter().any(|(_, s)| *s == Storage::Sqlite3),
    ) {
        (false, false) => Err(BagError::NoBagFile(path.into())),
        (true, true) => Err(BagError::MixedStorage(path.into())),
        _ => Ok(files),
    }
}

fn yaw(x: f64, y: f64, z: f64, w: f64) -> Option<f64> {
    let n2 = x * x + y * y + z * z + w * w;
    (n2.is_finite() && n2 > 1e-12)
        .then(|| (2.0 * (w * z + x * y)).atan2(n2 - 2.0 * (y * y + z * z)))
}

fn stamp(c: &mut Cdr) -> Result<u64, CdrError> {
    let sec = c.i32()?;
    let nanosec = c.u32()?;
    Ok(u64::try_from(sec).unwrap_or(0) * 1_000_000_000 + u64::from(nanosec))
}

/// A `geometry_msgs/Pose` in the plane; `None` for a non-finite or zero-length one.
fn pose(c: &mut Cdr) -> Result<Option<Pose2>, CdrError> {
    let (x, y, _z) = (c.f64()?, c.f64()?, c.f64()?);
    let (qx, qy, qz, qw) = (c.f64()?, c.f64()?, c.f64()?, c.f64()?);
    Ok(yaw(qx, qy, qz, qw)
        .filter(|_| x.is_finite() && y.is_finite())
        .map(|theta| Pose2 { x, y, theta }))
}

/// Decodes a `sensor_msgs/msg/LaserScan`: its header stamp (ns) and the scan.
///
/// # Errors
/// [`CdrError`] for a message that is not one.
pub fn decode_scan(data: &[u8]) -> Result<(u64, LaserScan), CdrError> {
    let mut c = Cdr::new(data)?;
    let t = stamp(&mut c)?;
    let frame_id = c.string()?;
    let angle_min = c.f32()?;
    let angle_max = c.f32()?;
    let angle_increment = c.f32()?;
    let _time_increment = c.f32()?;
    let _scan_time = c.f32()?;
    let range_min = c.f32()?;
    let range_max = c.f32()?;
    let ranges = c.f32_seq()?;
    Ok((
        t,
        LaserScan {
            frame_id,
            angle_min,
            angle_max,
            angle_increment,
            range_min,
            range_max,
            ranges,
        },
    ))
}

/// Decodes a `nav_msgs/msg/Odometry`: header, child_frame_id, the pose (the twist is not read);
/// `None` for a pose that is not finite.
///
/// # Errors
/// [`CdrError`] for a message that is not one.
pub fn decode_odometry(data: &[u8]) -> Result<(u64, Option<Pose2>), CdrError> {
    let mut c = Cdr::new(data)?;
    let t = stamp(&mut c)?;
    let _frame = c.string()?;
    let _child = c.string()?;
    Ok((t, pose(&mut c)?))
}

/// Decodes a `PoseWithCovarianceStamped` or `PoseStamped`: the header, then the pose; `None`
/// for a pose that is not finite.
///
/// # Errors
/// [`CdrError`] for a message that is not one.
pub fn decode_stamped_pose(data: &[u8]) -> Result<(u64, Option<Pose2>), CdrError> {
    let mut c = Cdr::new(data)?;
    let t = stamp(&mut c)?;
    let _frame = c.string()?;
    Ok((t, pose(&mut c)?))
}

/// Decodes a `tf2_msgs/msg/TFMessage` into its planar transforms (those with a finite pose).
///
/// # Errors
/// [`CdrError`] for a message that is not one.
pub fn decode_tf(data: &[u8]) -> Result<Vec<Mount>, CdrError> {
    Ok(decode_tf_stamped(data)?
        .into_iter()
        .map(|m| m.value)
        .collect())
}

/// Decodes a `tf2_msgs/msg/TFMessage` into its planar transforms (those with a finite pose),
/// each with its header stamp (ns).
///
/// # Errors
/// [`CdrError`] for a message that is not one.
pub fn decode_tf_stamped(data: &[u8]) -> Result<Vec<Stamped<Mount>>, CdrError> {
    let mut c = Cdr::new(data)?;
    // A TransformStamped is at least a stamp, two strings and seven f64.
    let n = c.count(8 + 8 + 56)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let t = stamp(&mut c)?;
        let parent = c.string()?;
        let child = c.string()?;
        let (x, y, _z) = (c.f64()?, c.f64()?, c.f64()?);
        let (qx, qy, qz, qw) = (c.f64()?, c.f64()?, c.f64()?, c.f64()?);
        if let Some(theta) = yaw(qx, qy, qz, qw).filter(|_| x.is_finite() && y.is_finite()) {
            out.push(Stamped {
                stamp_ns: t,
                value: Mount {
                    parent: parent.trim_start_matches('/').to_owned(),
                    child: child.trim_start_matches('/').to_owned(),
                    pose: Pose2 { x, y, theta },
                },
            });
        }
    }
    Ok(out)
}

/// Which reader a topic gets, and the types it accepts.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Scan,
    Odom,
    Reference,
    Tf,
    /// `/tf`, for odometry when the odometry topic is missing.
    TfOdom,
}

impl Role {
    fn accepts(self, schema: &str) -> bool {
        match self {
            Self::Scan => schema == "sensor_msgs/msg/LaserScan",
            Self::Odom => schema == "nav_msgs/msg/Odometry",
            Self::Reference => matches!(
                schema,
                "geometry_msgs/msg/PoseWithCovarianceStamped" | "geometry_msgs/msg/PoseStamped"
            ),
            Self::Tf | Self::TfOdom => schema == "tf2_msgs/msg/TFMessage",
        }
    }

    fn want(self) -> &'static str {
        match self {
            Self::Scan => "sensor_msgs/msg/LaserScan",
            Self::Odom => "nav_msgs/msg/Odometry",
            Self::Reference => "geometry_msgs/msg/PoseWithCovarianceStamped or PoseStamped",
            Self::Tf | Self::TfOdom => "tf2_msgs/msg/TFMessage",
        }
    }
}

/// The topics to read and the reader of each.
fn roles(topics: &Topics) -> Vec<(&str, Role)> {
    let mut roles: Vec<(&str, Role)> = vec![
        (topics.scan.as_str(), Role::Scan),
        (topics.odom.as_str(), Role::Odom),
        (topics.tf_static.as_str(), Role::Tf),
    ];
    if let Some(r) = &topics.reference {
        roles.push((r.as_str(), Role::Reference));
    }
    if let Some(t) = &topics.odom_from_tf {
        roles.push((t.topic.as_str(), Role::TfOdom));
    }
    roles
}

impl Bag {
    /// Reads the topics of `topics` from a bag: an `.mcap` file, a `.db3` file (an SQLite
    /// file is known by its header, whatever its name), or a rosbag2 directory of either
    /// (its files in the order of their split numbers; `metadata.yaml` is not needed).
    /// `/tf_static` is optional; the scan topic and a reference topic asked for must be there,
    /// and the odometry topic unless [`Topics::odom_from_tf`] finds odometry on `/tf` (then
    /// [`Bag::odometry_from_tf`]). Messages are taken per topic in the order the storage plays them (an
    /// MCAP file's order; a `.db3`'s receive timestamps), so the same recording in either
    /// storage gives the same bag.
    ///
    /// # Errors
    /// [`BagError`]: a file that cannot be read, is not a bag or is damaged; a topic missing,
    /// of the wrong type or not CDR; no odometry ([`BagError::NoOdometry`]).
    pub fn read(path: &Path, topics: &Topics) -> Result<Self, BagError> {
        let mut bag = Bag {
            odom_tf: topics.odom_from_tf.clone(),
            ..Bag::default()
        };
        let roles = roles(topics);
        let mut last: BTreeMap<&str, u64> = BTreeMap::new();
        for (file, storage) in bag_files(path)? {
            match storage {
                Storage::Mcap => {
                    let bytes = read_bounded(&file, MAX_BAG_FILE_BYTES)?;
                    bag.add_mcap(&file, &bytes, &roles, &mut last)?;
                }
                Storage::Sqlite3 => {
                    bag.add_db3(&file, &roles, &mut last, sqlite::MAX_DB3_MESSAGE_BYTES)?;
                }
            }
        }
        bag.finish(&roles)?;
        Ok(bag)
    }

    /// Reads the topics of `topics` from the bytes of one MCAP file (`name` for errors).
    ///
    /// # Errors
    /// As [`Bag::read`], but for a missing file.
    pub fn from_mcap(name: &Path, bytes: &[u8], topics: &Topics) -> Result<Self, BagError> {
        let mut bag = Bag {
            odom_tf: topics.odom_from_tf.clone(),
            ..Bag::default()
        };
        let roles = roles(topics);
        bag.add_mcap(name, bytes, &roles, &mut BTreeMap::new())?;
        bag.finish(&roles)?;
        Ok(bag)
    }

    fn add_mcap<'t>(
        &mut self,
        file: &Path,
        bytes: &[u8],
        roles: &[(&'t str, Role)],
        last: &mut BTreeMap<&'t str, u64>,
    ) -> Result<(), BagError> {
        let bag = self;
        guard::check(bytes).map_err(|e| BagError::Corrupt(file.into(), e))?;
        {
            let stream = mcap::MessageStream::new(bytes)
                .map_err(|e| BagError::Mcap(file.into(), e.to_string()))?;
            for m in stream {
                let m = m.map_err(|e| BagError::Mcap(file.into(), e.to_string()))?;
                let topic = m.channel.topic.as_str();
                let schema = m.channel.schema.as_ref().map_or("", |s| s.name.as_str());
                let entry = bag
                    .topics
                    .entry(topic.to_owned())
                    .or_insert_with(|| (schema.to_owned(), 0));
                entry.1 += 1;
                let Some(&(name, role)) = roles.iter().find(|(t, _)| *t == topic) else {
                    continue;
                };
                if !role.accepts(schema) {
                    return Err(BagError::WrongType {
                        topic: topic.into(),
                        got: schema.into(),
                        want: role.want(),
                    });
                }
                if m.channel.message_encoding != "cdr" {
                    return Err(BagError::Encoding {
                        topic: topic.into(),
                        encoding: m.channel.message_encoding.clone(),
                    });
                }
                bag.take(name, role, &m.data, last);
            }
        }
        Ok(())
    }

    /// Checks that the topics asked for are there, taking the odometry from `/tf` when the
    /// odometry topic is missing and [`Topics::odom_from_tf`] allows it.
    fn finish(&mut self, roles: &[(&str, Role)]) -> Result<(), BagError> {
        let available = |bag: &Self| {
            bag.topics
                .iter()
                .map(|(t, (ty, _))| format!("{t} ({ty})"))
                .collect()
        };
        for (topic, role) in roles {
            if matches!(role, Role::Tf | Role::TfOdom) || self.topics.contains_key(*topic) {
                continue;
            }
            if *role == Role::Odom {
                if let Some(tf) = &self.odom_tf {
                    if self.tf_odometry.is_empty() {
                        return Err(BagError::NoOdometry {
                            topic: (*topic).into(),
                            tf: Box::new(tf.clone()),
                            tf_pairs: self.tf_pairs.iter().cloned().collect(),
                            available: available(self),
                        });
                    }
                    self.odometry = std::mem::take(&mut self.tf_odometry);
                    self.odometry_from_tf = true;
                    continue;
                }
            }
            return Err(BagError::MissingTopic {
                topic: (*topic).into(),
                available: available(self),
            });
        }
        self.tf_odometry = Vec::new();
        self.tf_pairs.clear();
        Ok(())
    }

    fn skip(&mut self, why: String) {
        *self.skipped.entry(why).or_default() += 1;
    }

    /// Decodes one message of `topic` into its place, or counts why not.
    fn take<'t>(
        &mut self,
        topic: &'t str,
        role: Role,
        data: &[u8],
        last: &mut BTreeMap<&'t str, u64>,
    ) {
        let mut in_order = |t: u64, this: &mut Self| {
            let prev = last.get(topic).copied();
            if prev.is_some_and(|p| t <= p) {
                this.skip(format!(
                    "{topic}: stamped at or before the previous message"
                ));
                return false;
            }
            last.insert(topic, t);
            true
        };
        match role {
            Role::Scan => match decode_scan(data) {
                Ok((_, s)) if s.ranges.is_empty() => self.skip(format!("{topic}: no ranges")),
                Ok((t, s)) => {
                    if in_order(t, self) {
                        self.scans.push(Stamped {
                            stamp_ns: t,
                            value: s,
                        });
                    }
                }
                Err(e) => self.skip(format!("{topic}: malformed ({e})")),
            },
            Role::Odom | Role::Reference => {
                let r = if role == Role::Odom {
                    decode_odometry(data)
                } else {
                    decode_stamped_pose(data)
                };
                match r {
                    Ok((_, None)) => self.skip(format!("{topic}: a pose that is not finite")),
                    Ok((t, Some(p))) => {
                        if in_order(t, self) {
                            let v = Stamped {
                                stamp_ns: t,
                                value: p,
                            };
                            if role == Role::Odom {
                                self.odometry.push(v);
                            } else {
                                self.reference.push(v);
                            }
                        }
                    }
                    Err(e) => self.skip(format!("{topic}: malformed ({e})")),
                }
            }
            Role::TfOdom => match decode_tf_stamped(data) {
                Ok(transforms) => {
                    let Some(tf) = self.odom_tf.clone() else {
                        return;
                    };
                    let (odom, base) = (
                        tf.odom_frame.trim_start_matches('/'),
                        tf.base_frame.trim_start_matches('/'),
                    );
                    for m in transforms {
                        let v = &m.value;
                        if v.parent != odom || v.child != base {
                            if self.tf_pairs.len() < MAX_TF_PAIRS_LISTED {
                                self.tf_pairs.insert(format!("{} → {}", v.parent, v.child));
                            }
                            continue;
                        }
                        if in_order(m.stamp_ns, self) {
                            self.tf_odometry.push(Stamped {
                                stamp_ns: m.stamp_ns,
                                value: v.pose,
                            });
                        }
                    }
                }
                Err(e) => self.skip(format!("{topic}: malformed ({e})")),
            },
            Role::Tf => match decode_tf(data) {
                Ok(m) => self.mounts.extend(m),
                Err(e) => self.skip(format!("{topic}: malformed ({e})")),
            },
        }
    }

    /// `child`'s pose in `parent` through any chain of `/tf_static` transforms, as tf2 finds
    /// it: each frame has the parent of its last transform, and the pose is composed up from
    /// `child` and from `parent` to their nearest common ancestor (a transform may be walked
    /// backwards, inverted). The identity when the two frames are the same; `None` when they are
    /// not connected (a loop in the transforms ends the walk). Metres and radians, in the plane.
    pub fn frame_pose(&self, parent: &str, child: &str) -> Option<Pose2> {
        let (p, c) = (
            parent.trim_start_matches('/'),
            child.trim_start_matches('/'),
        );
        // Each frame's parent and its pose there: the last transform wins, as in tf2.
        let mut up: BTreeMap<&str, (&str, Pose2)> = BTreeMap::new();
        for m in &self.mounts {
            up.insert(m.child.as_str(), (m.parent.as_str(), m.pose));
        }
        // A frame's ancestors, with the frame's pose in each: [(frame, I), (its parent, …), …].
        let chain = |f: &'_ str| {
            let mut out = vec![(f.to_owned(), Pose2::default())];
            let mut cur = f.to_owned();
            let mut acc = Pose2::default();
            while let Some(&(parent, pose)) = up.get(cur.as_str()) {
                if out.iter().any(|(g, _)| g == parent) || out.len() > up.len() {
                    break;
                }
                acc = compose(pose, acc);
                out.push((parent.to_owned(), acc));
                cur = parent.to_owned();
            }
            out
        };
        let (cp, cc) = (chain(p), chain(c));
        cc.iter().find_map(|(a, a_child)| {
            let (_, a_parent) = cp.iter().find(|(g, _)| g == a)?;
            Some(if a == p {
                *a_child
            } else {
                compose(inverse(*a_parent), *a_child)
            })
        })
    }

    /// `child`'s pose in `parent` from `/tf_static`, if recorded directly (one transform;
    /// [`Bag::frame_pose`] follows chains).
    pub fn mount(&self, parent: &str, child: &str) -> Option<Pose2> {
        let (p, c) = (
            parent.trim_start_matches('/'),
            child.trim_start_matches('/'),
        );
        self.mounts
            .iter()
            .rev()
            .find(|m| m.parent == p && m.child == c)
            .map(|m| m.pose)
    }
}

/// `b` (a pose in `a`'s frame) in the frame `a` is given in: `a ∘ b`. The heading is wrapped
/// to (−π, π] only when the sum leaves it, so a composition with no rotation adds exactly.
pub fn compose(a: Pose2, b: Pose2) -> Pose2 {
    let (s, c) = a.theta.sin_cos();
    let mut theta = a.theta + b.theta;
    if !(-std::f64::consts::PI..=std::f64::consts::PI).contains(&theta) {
        theta = theta.sin().atan2(theta.cos());
    }
    Pose2 {
        x: a.x + c * b.x - s * b.y,
        y: a.y + s * b.x + c * b.y,
        theta,
    }
}

/// The inverse of a pose: `compose(inverse(a), a)` is the identity (to rounding).
pub fn inverse(a: Pose2) -> Pose2 {
    let (s, c) = a.theta.sin_cos();
    Pose2 {
        x: -(c * a.x + s * a.y),
        y: -(-s * a.x + c * a.y),
        theta: -a.theta,
    }
}

/// The pose of a stamped series at `t_ns`, linear in between (heading along the shorter arc);
/// `None` outside the series.
pub fn interpolate(series: &[Stamped<Pose2>], t_ns: u64) -> Option<Pose2> {
    let i = series.partition_point(|s| s.stamp_ns < t_ns);
    let b = series.get(i)?;
    if b.stamp_ns == t_ns {
        return Some(b.value);
    }
    let a = series.get(i.checked_sub(1)?)?;
    let f = (t_ns - a.stamp_ns) as f64 / (b.stamp_ns - a.stamp_ns) as f64;
    let d = (b.value.theta - a.value.theta)
        .sin()
        .atan2((b.value.theta - a.value.theta).cos());
    let theta = a.value.theta + f * d;
    Some(Pose2 {
        x: a.value.x + f * (b.value.x - a.value.x),
        y: a.value.y + f * (b.value.y - a.value.y),
        theta: theta.sin().atan2(theta.cos()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_between_and_outside() {
        let s = [
            Stamped {
                stamp_ns: 10,
                value: Pose2 {
                    x: 0.0,
                    y: 0.0,
                    theta: 3.0,
                },
            },
            Stamped {
                stamp_ns: 20,
                value: Pose2 {
                    x: 1.0,
                    y: 2.0,
                    theta: -3.0,
                },
            },
        ];
        let m = interpolate(&s, 15).unwrap();
        assert!((m.x - 0.5).abs() < 1e-12 && (m.y - 1.0).abs() < 1e-12);
        // The shorter arc: through ±π, not through 0.
        assert!(m.theta.abs() > 3.1, "{}", m.theta);
        assert_eq!(interpolate(&s, 20).unwrap(), s[1].value);
        assert_eq!(interpolate(&s, 5), None);
        assert_eq!(interpolate(&s, 25), None);
    }

    fn mount(parent: &str, child: &str, x: f64, y: f64, deg: f64) -> Mount {
        Mount {
            parent: parent.into(),
            child: child.into(),
            pose: Pose2 {
                x,
                y,
                theta: deg.to_radians(),
            },
        }
    }

    fn close(a: Pose2, b: Pose2) -> bool {
        (a.x - b.x).abs() < 1e-12 && (a.y - b.y).abs() < 1e-12 && (a.theta - b.theta).abs() < 1e-12
    }

    #[test]
    fn frame_pose_follows_a_chain_in_any_order_and_direction() {
        // base_footprint -> base_link: 1 m ahead, turned 90°; base_link -> laser: 0.5 m ahead
        // of base_link, turned 90° more. By hand: the laser is 0.5 m along base_link's x, which
        // is base_footprint's y, so at (1, 0.5) and turned 180°.
        let bag = Bag {
            mounts: vec![
                mount("base_link", "laser", 0.5, 0.0, 90.0),
                mount("base_link", "imu", 0.0, -2.0, 0.0),
                mount("base_footprint", "base_link", 1.0, 0.0, 90.0),
                mount("odom_x", "other", 1.0, 1.0, 0.0),
            ],
            ..Bag::default()
        };
        let want = Pose2 {
            x: 1.0,
            y: 0.5,
            theta: std::f64::consts::PI,
        };
        let got = bag.frame_pose("base_footprint", "/laser").unwrap();
        assert!(close(got, want), "{got:?}");
        // Backwards: base_footprint in the laser's frame. By hand: from the laser at (1, 0.5)
        // the origin is (−1, −0.5) away; the laser faces −x, so that is (1, 0.5) ahead-left.
        let back = bag.frame_pose("laser", "base_footprint").unwrap();
        assert!(close(compose(got, back), Pose2::default()), "{back:?}");
        assert!(
            (back.x - 1.0).abs() < 1e-12 && (back.y - 0.5).abs() < 1e-12,
            "{back:?}"
        );
        // Through the common ancestor base_link: the imu is 2 m to base_link's right; the
        // laser at (0.5, 0) turned 90°: the imu is at (−2, 0.5) in the laser's frame.
        let imu = bag.frame_pose("laser", "imu").unwrap();
        assert!(
            (imu.x + 2.0).abs() < 1e-12 && (imu.y - 0.5).abs() < 1e-12,
            "{imu:?}"
        );
        assert_eq!(bag.frame_pose("laser", "laser"), Some(Pose2::default()));
        assert_eq!(bag.frame_pose("base_link", "other"), None);
        assert_eq!(bag.frame_pose("base_link", "nowhere"), None);
    }

    #[test]
    fn frame_pose_ends_at_a_loop() {
        let bag = Bag {
            mounts: vec![
                mount("a", "b", 1.0, 0.0, 0.0),
                mount("b", "a", 1.0, 0.0, 0.0),
            ],
            ..Bag::default()
        };
        assert_eq!(bag.frame_pose("a", "c"), None);
        assert!(bag.frame_pose("a", "b").is_some());
    }
}
