//! Runs on recordings: a ROS 2 bag's scans, odometry and reference pose
//! ([`load_bag`]), and recorded odometry for a CARMEN log from a text file
//! ([`read_odometry_file`]).

use super::{usage, TrackError, TrackInput};
use crate::cmd::scored_log::MAX_BEAMS;
use crate::input::bag::{interpolate, Bag, Pose2, Topics};
use beamfield::field::LikelihoodParams;
use beamfield::{BeamLayout, Pose, SensorMount};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// What a bag gave a run, for the report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BagSummary {
    /// Scans used: each with odometry and a reference pose at its stamp.
    pub scans_used: usize,
    /// Scans and messages not used, by cause.
    pub skipped: BTreeMap<String, u64>,
    /// The laser's mount on the base frame: x, y (metres), yaw (radians), composed from
    /// `/tf_static` (the identity when the scans are in the base frame).
    pub mount: [f32; 3],
    /// Whether the odometry came from `/tf` (odom frame → base frame) because the bag has no
    /// odometry topic.
    pub odometry_from_tf: bool,
    /// Whether the mount came from `/tf_static` (false: the scans are in the base frame).
    pub mount_from_tf: bool,
    /// The scans' frame and the base frame the mount joins.
    pub scan_frame: String,
    pub base_frame: String,
    /// Beams per scan, first angle and step (radians), maximum range (metres).
    pub beams: usize,
    pub angle_min_rad: f32,
    pub angle_increment_rad: f32,
    pub range_max_m: f32,
}

fn pose(p: Pose2) -> Pose {
    Pose::new(p.x as f32, p.y as f32, p.theta as f32)
}

/// Loads a bag for a run: the scans of `topics.scan` mapped onto one [`BeamLayout`] (the
/// first scan's angles; a scan with other angles is skipped), the laser's mount from
/// `/tf_static` (`base_frame` → the scans' frame, through any chain of transforms,
/// [`Bag::frame_pose`]; the identity when the scans are in `base_frame`), `topics.odom` and the reference topic
/// interpolated at each scan's stamp (a scan outside either is skipped). Ranges that are not
/// finite or outside `[range_min, range_max]` become `range_max` (no reading).
///
/// # Errors
/// [`TrackError::Usage`] for a bag that cannot be read, a missing or mistyped topic, no
/// reference topic, scans no layout can hold, or scans whose frame `/tf_static` does not
/// connect to `base_frame`.
pub fn load_bag(
    field_bytes: Vec<u8>,
    bag_path: &Path,
    topics: &Topics,
    base_frame: &str,
    likelihood: (f32, f32, f32),
) -> Result<(TrackInput, BagSummary), TrackError> {
    if topics.reference.is_none() {
        return Err(usage(
            "track --bag needs --reference-topic: the errors are measured against it and the filter starts at its first pose",
        ));
    }
    let bag = Bag::read(bag_path, topics).map_err(|e| usage(format!("--bag: {e}")))?;
    let first = bag
        .scans
        .first()
        .ok_or_else(|| usage(format!("--bag: no usable message on {}", topics.scan)))?;
    let s0 = &first.value;
    let n = s0.ranges.len();
    if n > MAX_BEAMS {
        return Err(usage(format!(
            "--bag: scans of {n} beams; at most {MAX_BEAMS} fit a layout"
        )));
    }
    let (base, frame) = (
        base_frame.trim_start_matches('/'),
        s0.frame_id.trim_start_matches('/'),
    );
    let m = bag.frame_pose(base, frame).ok_or_else(|| {
        let mut known: Vec<String> = bag
            .mounts
            .iter()
            .map(|m| format!("{} → {}", m.parent, m.child))
            .collect();
        known.dedup();
        usage(format!(
            "--bag: the scans' frame {frame:?} is not connected to the base frame {base:?} by /tf_static ({}); \
             give --base-frame the robot's frame, or --base-frame {frame} to take the laser as the robot's centre",
            if known.is_empty() {
                "it has no transform".to_owned()
            } else {
                format!("its transforms: {}", known.join(", "))
            }
        ))
    })?;
    let mount = SensorMount {
        x_m: m.x as f32,
        y_m: m.y as f32,
        yaw_rad: m.theta as f32,
    };
    let mount_from_tf = base != frame;
    let range_max = s0.range_max;
    let layout =
        BeamLayout::<MAX_BEAMS>::uniform(s0.angle_min, s0.angle_increment, n, range_max, mount)
            .map_err(|e| usage(format!("--bag: the scans' angles fit no beam layout: {e}")))?;
    let (z_hit, z_rand, sigma_hit) = likelihood;
    let params = LikelihoodParams::new(z_hit, z_rand, sigma_hit, range_max)
        .map_err(|e| usage(format!("likelihood field parameters: {e}")))?;
    let mut summary = BagSummary {
        skipped: bag.skipped.clone(),
        mount: [mount.x_m, mount.y_m, mount.yaw_rad],
        mount_from_tf,
        odometry_from_tf: bag.odometry_from_tf,
        scan_frame: frame.to_owned(),
        base_frame: base.to_owned(),
        beams: n,
        angle_min_rad: s0.angle_min,
        angle_increment_rad: s0.angle_increment,
        range_max_m: range_max,
        ..BagSummary::default()
    };
    let mut skip = |why: &str| *summary.skipped.entry(why.to_owned()).or_default() += 1;
    let (mut scans, mut logged, mut odometry) = (Vec::new(), Vec::new(), Vec::new());
    for s in &bag.scans {
        let v = &s.value;
        if v.ranges.len() != n
            || v.angle_min != s0.angle_min
            || v.angle_increment != s0.angle_increment
            || v.range_max != range_max
        {
            skip("scan: angles or range limits differ from the first scan's");
            continue;
        }
        let (Some(odom), Some(truth)) = (
            interpolate(&bag.odometry, s.stamp_ns),
            interpolate(&bag.reference, s.stamp_ns),
        ) else {
            skip("scan: outside the odometry's or the reference's time span");
            continue;
        };
        let ranges = v
            .ranges
            .iter()
            .map(|&r| {
                if r.is_finite() && r >= v.range_min && r <= range_max {
                    r
                } else {
                    range_max
                }
            })
            .collect();
        scans.push(ranges);
        odometry.push(pose(odom));
        logged.push(pose(truth));
    }
    summary.scans_used = scans.len();
    if scans.len() < 2 {
        return Err(usage(format!(
            "--bag: {} scans have odometry and a reference pose at their stamp; at least 2 are needed",
            scans.len()
        )));
    }
    let input = TrackInput {
        bytes: field_bytes,
        params,
        layout,
        scans,
        logged,
        odometry: Some(odometry),
        reference: None,
    };
    input.views()?;
    Ok((input, summary))
}

/// Reads recorded odometry for a log: lines `index x y θ` (metres, metres, radians, in the
/// odometry frame; index 0 is the log's first scan), `#` starts a comment. Every scan from 0
/// to `scans − 1` (the scans the run uses) needs exactly one line; lines for later scans are
/// refused.
///
/// # Errors
/// [`TrackError::Usage`] naming the line of a malformed, duplicated or out-of-range entry, or
/// the first scan with none.
pub fn read_odometry_file(path: &Path, scans: usize) -> Result<Vec<Pose>, TrackError> {
    let text = crate::input::limits::read_regular_file(
        path,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "odometry file",
    )
    .map_err(TrackError::Read)?;
    let text = String::from_utf8(text)
        .map_err(|_| usage(format!("--odometry {}: not UTF-8 text", path.display())))?;
    let mut poses: Vec<Option<Pose>> = vec![None; scans];
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |why: &str| {
            usage(format!(
                "--odometry {} line {}: {why}",
                path.display(),
                i + 1
            ))
        };
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() != 4 {
            return Err(bad("want `index x y θ`"));
        }
        let k: usize = f[0]
            .parse()
            .map_err(|_| bad("the index is not a scan number"))?;
        let v: Vec<f32> = f[1..]
            .iter()
            .map(|t| t.parse::<f32>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| bad("x, y and θ must be finite numbers"))?;
        let slot = poses
            .get_mut(k)
            .ok_or_else(|| bad(&format!("scan {k} is past the log's {scans} scans")))?;
        if slot.is_some() {
            return Err(bad(&format!("scan {k} has a pose already")));
        }
        *slot = Some(Pose::new(v[0], v[1], v[2]));
    }
    poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            p.ok_or_else(|| {
                usage(format!(
                    "--odometry {}: no pose for scan {k}",
                    path.display()
                ))
            })
        })
        .collect()
}

/// Reads reference poses for a log (`--reference`): one line per reference scan, whitespace-
/// or tab-separated, `#` starts a comment. Either a header line naming the columns — the scan
/// `index` (0-based FLASER index), and `ref_x ref_y ref_theta` or `x y theta` (metres, metres,
/// radians, in the map's frame); other columns are ignored, as in the raw-odometry log's
/// `anchors.tsv` — or no header and `index x y θ` on every line. Returns one entry per scan of
/// the log (`scans` of them), `None` where there is no reference pose.
///
/// # Errors
/// [`TrackError::Usage`] naming the line of a malformed, duplicated or out-of-range entry, a
/// header without the columns, or a file with no reference pose at all.
pub fn read_reference_file(path: &Path, scans: usize) -> Result<Vec<Option<Pose>>, TrackError> {
    let text = crate::input::limits::read_regular_file(
        path,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "reference file",
    )
    .map_err(TrackError::Read)?;
    let text = String::from_utf8(text)
        .map_err(|_| usage(format!("--reference {}: not UTF-8 text", path.display())))?;
    let mut poses: Vec<Option<Pose>> = vec![None; scans];
    // Column positions of index, x, y, θ: from the header, or 0..4 without one.
    let mut columns: Option<[usize; 4]> = None;
    let mut found = 0usize;
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |why: &str| {
            usage(format!(
                "--reference {} line {}: {why}",
                path.display(),
                i + 1
            ))
        };
        let f: Vec<&str> = line.split_whitespace().collect();
        let cols = match columns {
            Some(c) => c,
            None if f[0].parse::<f64>().is_err() => {
                let find = |names: &[&str]| f.iter().position(|t| names.contains(t));
                let c = [
                    find(&["index", "scan"]),
                    find(&["ref_x", "x"]),
                    find(&["ref_y", "y"]),
                    find(&["ref_theta", "theta"]),
                ];
                let [Some(a), Some(b), Some(c), Some(d)] = c else {
                    return Err(bad(
                        "a header needs the columns index, ref_x (or x), ref_y (or y) and ref_theta (or theta)",
                    ));
                };
                columns = Some([a, b, c, d]);
                continue;
            }
            None => {
                columns = Some([0, 1, 2, 3]);
                [0, 1, 2, 3]
            }
        };
        let field = |c: usize| f.get(c).copied().ok_or_else(|| bad("too few columns"));
        let k: usize = field(cols[0])?
            .parse()
            .map_err(|_| bad("the index is not a scan number"))?;
        let mut v = [0f32; 3];
        for (slot, &c) in v.iter_mut().zip(&cols[1..]) {
            *slot = field(c)?
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad("x, y and θ must be finite numbers"))?;
        }
        let slot = poses
            .get_mut(k)
            .ok_or_else(|| bad(&format!("scan {k} is past the log's {scans} scans")))?;
        if slot.is_some() {
            return Err(bad(&format!("scan {k} has a pose already")));
        }
        *slot = Some(Pose::new(v[0], v[1], v[2]));
        found += 1;
    }
    if found == 0 {
        return Err(usage(format!(
            "--reference {}: no reference pose in it",
            path.display()
        )));
    }
    Ok(poses)
}
