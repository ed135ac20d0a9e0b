//! ROS 2 bags in for beamfield's host tools (`beamfield track --bag`, `cargo xtask robot --bag`): the scans, odometry, a reference pose and the laser's mount from an MCAP file
//! (what `ros2 bag record` writes since Iron), by topic, with each message's CDR decoded here
//! ([`cdr`]): `sensor_msgs/msg/LaserScan`, `nav_msgs/msg/Odometry`,
//! `geometry_msgs/msg/PoseWithCovarianceStamped` or `PoseStamped`, `tf2_msgs/msg/TFMessage`.
//!
//! A message that cannot be used is skipped and counted by cause (malformed, stamped before
//! the previous one on its topic, a scan with no ranges …); a missing topic or one of another
//! type is an error that names what the bag does have.
//!
//! Nothing in a file is trusted before it is checked: a bag file must be a regular file of at
//! most [`MAX_BAG_FILE_BYTES`] ([`read_bounded`]), and every record, chunk and CRC of it is
//! checked by [`guard::check`] before the `mcap` crate parses it.

pub mod cdr;
pub mod guard;

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

/// Which topics to read.
#[derive(Clone, Debug)]
pub struct Topics {
    pub scan: String,
    pub odom: String,
    /// A reference pose to compare with (a recorded `amcl_pose`, ground truth), if any.
    pub reference: Option<String>,
    pub tf_static: String,
}

impl Default for Topics {
    fn default() -> Self {
        Self {
            scan: "/scan".into(),
            odom: "/odom".into(),
            reference: None,
            tf_static: "/tf_static".into(),
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
    /// Messages not used, by cause.
    pub skipped: BTreeMap<String, u64>,
    /// Every topic of the bag: its type and message count.
    pub topics: BTreeMap<String, (String, u64)>,
}

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
    /// A directory with no `.mcap` file.
    NoMcap(PathBuf),
    Mcap(PathBuf, String),
    /// A topic asked for that the bag does not have.
    MissingTopic {
        topic: String,
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
                "{} is larger than {limit} bytes, the limit for an MCAP file ({bytes} bytes seen)",
                path.display()
            ),
            Self::Corrupt(p, e) => write!(f, "{} is damaged: {e}", p.display()),
            Self::NoMcap(p) => write!(f, "{} holds no .mcap file", p.display()),
            Self::Mcap(p, e) => write!(f, "{} is not a readable MCAP file: {e}", p.display()),
            Self::MissingTopic { topic, available } => write!(
                f,
                "the bag has no topic {topic}; it has {}",
                if available.is_empty() {
                    "none".into()
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

/// The `.mcap` files of a bag: the file itself, or those of a rosbag2 directory, sorted.
fn mcap_files(path: &Path) -> Result<Vec<PathBuf>, BagError> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| BagError::Io(path.into(), e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(BagError::NoMcap(path.into()));
    }
    Ok(files)
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
    let mut c = Cdr::new(data)?;
    // A TransformStamped is at least a stamp, two strings and seven f64.
    let n = c.count(8 + 8 + 56)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let _t = stamp(&mut c)?;
        let parent = c.string()?;
        let child = c.string()?;
        let (x, y, _z) = (c.f64()?, c.f64()?, c.f64()?);
        let (qx, qy, qz, qw) = (c.f64()?, c.f64()?, c.f64()?, c.f64()?);
        if let Some(theta) = yaw(qx, qy, qz, qw).filter(|_| x.is_finite() && y.is_finite()) {
            out.push(Mount {
                parent: parent.trim_start_matches('/').to_owned(),
                child: child.trim_start_matches('/').to_owned(),
                pose: Pose2 { x, y, theta },
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
            Self::Tf => schema == "tf2_msgs/msg/TFMessage",
        }
    }

    fn want(self) -> &'static str {
        match self {
            Self::Scan => "sensor_msgs/msg/LaserScan",
            Self::Odom => "nav_msgs/msg/Odometry",
            Self::Reference => "geometry_msgs/msg/PoseWithCovarianceStamped or PoseStamped",
            Self::Tf => "tf2_msgs/msg/TFMessage",
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
    roles
}

impl Bag {
    /// Reads the topics of `topics` from a bag (an `.mcap` file or a rosbag2 directory).
    /// `/tf_static` is optional; the scan and odometry topics and a reference topic asked for
    /// must be there.
    pub fn read(path: &Path, topics: &Topics) -> Result<Self, BagError> {
        let mut bag = Bag::default();
        let roles = roles(topics);
        let mut last: BTreeMap<&str, u64> = BTreeMap::new();
        for file in mcap_files(path)? {
            let bytes = read_bounded(&file, MAX_BAG_FILE_BYTES)?;
            bag.add_mcap(&file, &bytes, &roles, &mut last)?;
        }
        bag.check_topics(&roles)?;
        Ok(bag)
    }

    /// Reads the topics of `topics` from the bytes of one MCAP file (`name` for errors).
    ///
    /// # Errors
    /// As [`Bag::read`], but for a missing file.
    pub fn from_mcap(name: &Path, bytes: &[u8], topics: &Topics) -> Result<Self, BagError> {
        let mut bag = Bag::default();
        let roles = roles(topics);
        bag.add_mcap(name, bytes, &roles, &mut BTreeMap::new())?;
        bag.check_topics(&roles)?;
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

    fn check_topics(&self, roles: &[(&str, Role)]) -> Result<(), BagError> {
        let bag = self;
        for (topic, role) in roles {
            if *role != Role::Tf && !bag.topics.contains_key(*topic) {
                return Err(BagError::MissingTopic {
                    topic: (*topic).into(),
                    available: bag
                        .topics
                        .iter()
                        .map(|(t, (ty, _))| format!("{t} ({ty})"))
                        .collect(),
                });
            }
        }
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
            Role::Tf => match decode_tf(data) {
                Ok(m) => self.mounts.extend(m),
                Err(e) => self.skip(format!("{topic}: malformed ({e})")),
            },
        }
    }

    /// `child`'s pose in `parent` from `/tf_static`, if recorded directly.
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
}
