//! Runs on recordings: a ROS 2 bag's scans, odometry and reference pose
//! ([`load_bag`]), and recorded odometry for a CARMEN log from a text file
//! ([`read_odometry_file`]).

use super::{usage, TrackError, TrackInput};
use crate::cmd::scored_log::MAX_BEAMS;
use crate::input::bag::{interpolate, Bag, LaserScan, Pose2, Topics};
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
    /// Scans binned onto a fixed layout (scans whose angles change, or `--scan-layout`).
    pub rebinned: usize,
    /// Beams per scan, first angle and step (radians), maximum range (metres).
    pub beams: usize,
    pub angle_min_rad: f32,
    pub angle_increment_rad: f32,
    pub range_max_m: f32,
}

/// A fixed beam layout scans are binned onto: the first beam's bearing and the step (radians,
/// counter-clockwise in the laser's frame) and the number of beams.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ScanLayout {
    pub angle_min_rad: f64,
    pub increment_rad: f64,
    pub beams: usize,
}

impl ScanLayout {
    /// The layout for scans whose angles change from one to the next (an LD06 driver's
    /// revolutions): the median first bearing, the largest step (so that each beam of a
    /// contiguous scan's span receives a reading), and the beams from the median first to the
    /// median last bearing, at most [`MAX_BEAMS`] and at most one turn. `None` when no scan has
    /// finite angles and a positive step.
    pub fn covering(scans: &[&LaserScan]) -> Option<Self> {
        let ok: Vec<&&LaserScan> = scans
            .iter()
            .filter(|v| {
                v.angle_min.is_finite()
                    && v.angle_increment.is_finite()
                    && v.angle_increment > 0.0
                    && !v.ranges.is_empty()
            })
            .collect();
        let median = |mut x: Vec<f64>| {
            x.sort_by(f64::total_cmp);
            x.get(x.len() / 2).copied()
        };
        let first = median(ok.iter().map(|v| f64::from(v.angle_min)).collect())?;
        let last = median(
            ok.iter()
                .map(|v| {
                    f64::from(v.angle_min)
                        + (v.ranges.len() - 1) as f64 * f64::from(v.angle_increment)
                })
                .collect(),
        )?;
        let step = ok
            .iter()
            .map(|v| f64::from(v.angle_increment))
            .fold(0.0, f64::max);
        let per_turn = (std::f64::consts::TAU / step).floor().max(1.0) as usize;
        let beams = (((last - first) / step + 0.5).floor().max(0.0) as usize + 1)
            .min(per_turn)
            .min(MAX_BEAMS);
        Some(Self {
            angle_min_rad: first,
            increment_rad: step,
            beams,
        })
    }

    /// `v` binned onto this layout as the device's scan assembler bins a revolution's points
    /// (`beamfield::lidar`): each reading (finite, within the scan's `[range_min, range_max]`
    /// and at most `range_max`) goes to the beam whose bearing is nearest to its own, if one is
    /// within half a step (bearings compared around the turn); when several land on one beam,
    /// the one nearest to the beam's bearing stays (the first of equals). A beam with none
    /// reads `range_max` (no reading), as elsewhere in a bag's scans.
    pub fn bin(&self, v: &LaserScan, range_max: f32) -> Vec<f32> {
        let mut out = vec![range_max; self.beams];
        let mut off = vec![f64::INFINITY; self.beams];
        let per_turn = std::f64::consts::TAU / self.increment_rad;
        for (i, &r) in v.ranges.iter().enumerate() {
            if !(r.is_finite() && r >= v.range_min && r <= v.range_max && r <= range_max) {
                continue;
            }
            let bearing = f64::from(v.angle_min) + i as f64 * f64::from(v.angle_increment);
            let mut k = ((bearing - self.angle_min_rad) / self.increment_rad).rem_euclid(per_turn);
            // Within half a step below the first beam: measured from it, negatively.
            if k >= per_turn - 0.5 {
                k -= per_turn;
            }
            let idx = (k + 0.5).floor();
            if !(idx >= 0.0 && idx < self.beams as f64) {
                continue;
            }
            let (idx, d) = (idx as usize, (k - idx).abs());
            if let (Some(o), Some(slot)) = (off.get_mut(idx), out.get_mut(idx)) {
                if d < *o {
                    *o = d;
                    *slot = r;
                }
            }
        }
        out
    }
}

fn pose(p: Pose2) -> Pose {
    Pose::new(p.x as f32, p.y as f32, p.theta as f32)
}

/// Loads a bag for a run: the scans of `topics.scan` mapped onto one [`BeamLayout`] (the
/// first scan's angles when every scan has them; otherwise, or with `scan_layout`, each scan
/// binned onto a fixed layout, [`ScanLayout::bin`], the layout [`ScanLayout::covering`] the
/// scans unless `scan_layout` gives it), the laser's mount from
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
    scan_layout: Option<ScanLayout>,
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
    // One layout for every scan: the first scan's when all share it; otherwise (or when
    // --scan-layout gives one) every scan is binned onto a fixed layout.
    let same_as_first = |v: &LaserScan| {
        v.ranges.len() == s0.ranges.len()
            && v.angle_min == s0.angle_min
            && v.angle_increment == s0.angle_increment
    };
    let fixed = match scan_layout {
        Some(l) => Some(l),
        None if bag.scans.iter().all(|s| same_as_first(&s.value)) => None,
        None => Some(
            ScanLayout::covering(&bag.scans.iter().map(|s| &s.value).collect::<Vec<_>>())
                .ok_or_else(|| {
                    usage("--bag: no scan has finite angles and a positive step".to_owned())
                })?,
        ),
    };
    let (n, angle_min, angle_increment) = match fixed {
        Some(l) => (l.beams, l.angle_min_rad as f32, l.increment_rad as f32),
        None => (s0.ranges.len(), s0.angle_min, s0.angle_increment),
    };
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
    let layout = BeamLayout::<MAX_BEAMS>::uniform(angle_min, angle_increment, n, range_max, mount)
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
        angle_min_rad: angle_min,
        angle_increment_rad: angle_increment,
        range_max_m: range_max,
        ..BagSummary::default()
    };
    let mut skip = |why: &str| *summary.skipped.entry(why.to_owned()).or_default() += 1;
    let (mut scans, mut logged, mut odometry) = (Vec::new(), Vec::new(), Vec::new());
    let mut rebinned = 0;
    for s in &bag.scans {
        let v = &s.value;
        if fixed.is_none()
            && (v.ranges.len() != n
                || v.angle_min != s0.angle_min
                || v.angle_increment != s0.angle_increment
                || v.range_max != range_max)
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
        let ranges = match &fixed {
            Some(l) => {
                rebinned += 1;
                l.bin(v, range_max)
            }
            None => v
                .ranges
                .iter()
                .map(|&r| {
                    if r.is_finite() && r >= v.range_min && r <= range_max {
                        r
                    } else {
                        range_max
                    }
                })
                .collect(),
        };
        scans.push(ranges);
        odometry.push(pose(odom));
        logged.push(pose(truth));
    }
    summary.scans_used = scans.len();
    summary.rebinned = rebinned;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(angle_min_deg: f32, step_deg: f32, ranges: &[f32]) -> LaserScan {
        LaserScan {
            frame_id: "laser".into(),
            angle_min: angle_min_deg.to_radians(),
            angle_max: (angle_min_deg + step_deg * (ranges.len() as f32 - 1.0)).to_radians(),
            angle_increment: step_deg.to_radians(),
            range_min: 0.1,
            range_max: 10.0,
            ranges: ranges.to_vec(),
        }
    }

    #[test]
    fn binning_keeps_the_reading_nearest_to_each_beam() {
        // Four beams of 90° from 0°: at 0, 90, 180, 270.
        let l = ScanLayout {
            angle_min_rad: 0.0,
            increment_rad: 90f64.to_radians(),
            beams: 4,
        };
        // Readings every 30° from −30°: −30 (→ 0, 30° off), 0 (→ 0, exact), 30 (→ 0, 30°
        // off: the exact one stays), 60 (→ 90, 30° off), 90 (→ 90, exact), 120 (→ 90),
        // 150 (→ 180, 30° off), 180 is NaN (no reading), 210 (→ 180, 30° off: the first of
        // equals stays), 240 below range_min, 270 above range_max: 270° gets none.
        let v = scan(
            -30.0,
            30.0,
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, f32::NAN, 9.0, 0.05, 11.0],
        );
        assert_eq!(l.bin(&v, 10.0), vec![2.0, 5.0, 7.0, 10.0]);
        // Bearings wrap around the turn: 350° and −10° are both 10° below beam 0.
        let v = scan(350.0, 5.0, &[1.0, 2.0, 3.0]);
        assert_eq!(l.bin(&v, 10.0), vec![3.0, 10.0, 10.0, 10.0]);
        // Beyond half a step of every beam of a partial layout: dropped.
        let half = ScanLayout { beams: 2, ..l };
        let v = scan(180.0, 1.0, &[1.0]);
        assert_eq!(half.bin(&v, 10.0), vec![10.0, 10.0]);
    }

    #[test]
    fn the_covering_layout_takes_medians_and_the_largest_step() {
        let a = scan(-10.0, 1.0, &[1.0; 21]);
        let b = scan(-11.0, 2.0, &[1.0; 11]);
        let c = scan(-9.0, 0.5, &[1.0; 38]);
        let l = ScanLayout::covering(&[&a, &b, &c]).unwrap();
        // First bearings −11, −10, −9: median −10. Last: 10, 9, 9.5: median 9.5. Step 2°.
        // Beams: (9.5 − (−10)) / 2 = 9.75 → 10 steps, 11 beams.
        assert!((l.angle_min_rad - (-10f64).to_radians()).abs() < 1e-6);
        assert!((l.increment_rad - 2f64.to_radians()).abs() < 1e-6);
        assert_eq!(l.beams, 11);
    }
}
