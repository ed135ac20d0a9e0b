//! What a run of the localizer needs, loaded once: the field and its free space, the log's
//! scans, layout and logged poses, and the likelihood field.

use super::{usage, TrackError};
use crate::cmd::scored_log::MAX_BEAMS;
use crate::input::carmen::{CarmenLog, ReadOptions};
use beamfield::field::{FieldView, FreeSpace, LikelihoodParams};
use beamfield::{BeamLayout, Pose, SensorMount};
use std::path::Path;

/// Everything a run needs, loaded once.
pub struct TrackInput {
    /// Blob bytes (and any free-space section after them).
    pub bytes: Vec<u8>,
    /// Likelihood-field parameters.
    pub params: LikelihoodParams,
    /// The log's beam layout (centred mount).
    pub layout: BeamLayout<MAX_BEAMS>,
    /// The scans' ranges (each made a [`Scan`](beamfield::Scan) when it is scored: a `Scan<MAX_BEAMS>` holds
    /// 4.3 KB whatever its beams, so a log of many short scans is not multiplied in memory).
    pub scans: Vec<Vec<f32>>,
    /// The log's laser poses, one per scan: the truth, unless [`TrackInput::reference`] is
    /// given (then they are what the log holds, e.g. integrated odometry, and not used as truth).
    pub logged: Vec<Pose>,
    /// Recorded odometry, one pose per scan in the odometry frame (a bag's `/odom`, an
    /// `--odometry` file); `None`: the run synthesizes it from the logged poses.
    pub odometry: Option<Vec<Pose>>,
    /// Reference poses at some scans (`--reference`, e.g. a raw-odometry log's anchors), one
    /// entry per scan, `None` where there is none: when given, the truth is known only there —
    /// a run starts at the first one and is scored at them alone. `None`: every logged pose is
    /// the truth.
    pub reference: Option<Vec<Option<Pose>>>,
}

impl TrackInput {
    /// The truth at scan `k`: the reference pose there when a reference is given (`None`
    /// between reference scans), else the logged pose.
    pub fn truth(&self, k: usize) -> Option<Pose> {
        match &self.reference {
            Some(r) => r.get(k).copied().flatten(),
            None => self.logged.get(k).copied(),
        }
    }

    /// The first scan with a truth (0 without a reference; `None` when the reference has none).
    pub fn first_truth(&self) -> Option<usize> {
        match &self.reference {
            Some(r) => r.iter().position(Option::is_some),
            None => (!self.logged.is_empty()).then_some(0),
        }
    }

    /// The field view and the free space after it, if any.
    ///
    /// # Errors
    /// [`TrackError::Blob`], [`TrackError::FreeSpace`] (also when its grid is not the blob's).
    pub fn views(&self) -> Result<(FieldView<'_>, Option<FreeSpace<'_>>), TrackError> {
        let (view, rest) = FieldView::parse_prefix(&self.bytes).map_err(TrackError::Blob)?;
        if rest.is_empty() {
            return Ok((view, None));
        }
        let free = FreeSpace::parse(rest).map_err(TrackError::FreeSpace)?;
        if !free.matches(&view) {
            return Err(usage("the free-space section's grid is not the blob's"));
        }
        Ok((view, Some(free)))
    }
}

/// The field a run scores against: a blob file (`beamfield field build`), or a nav2 /
/// map_server map YAML (`.yaml`, `.yml`), from which the blob and its free-space section are
/// built here as `beamfield field build MAP.yaml --free-space` would (default clamp distance).
///
/// # Errors
/// [`TrackError::Read`] for an unreadable file, [`TrackError::Usage`] for a map that cannot be
/// read or turned into a blob.
pub fn field_bytes(field: &Path) -> Result<Vec<u8>, TrackError> {
    let is_yaml = field
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"));
    if !is_yaml {
        return crate::input::limits::read_regular_file(
            field,
            crate::input::limits::MAX_FIELD_FILE_BYTES,
            "field file",
        )
        .map_err(TrackError::Read);
    }
    let bad = |e: &dyn std::fmt::Display| usage(format!("--field {}: {e}", field.display()));
    let map = crate::input::map::load_map(field).map_err(|e| bad(&e))?;
    let mut bytes =
        crate::blob::build_blob(&map, beamfield::field::DEFAULT_MAX_DIST_M).map_err(|e| bad(&e))?;
    bytes.extend(crate::blob::build_free_space(&map).map_err(|e| bad(&e))?);
    Ok(bytes)
}

/// Loads the field and the log (its max-range value detected).
///
/// # Errors
/// [`TrackError`] for unreadable or malformed inputs.
pub fn load(
    field: &Path,
    log: &Path,
    z_hit: f32,
    z_rand: f32,
    sigma_hit: f32,
) -> Result<TrackInput, TrackError> {
    load_with_max_range(field, log, (z_hit, z_rand, sigma_hit), None)
}

/// [`load`] with the log's max-range value given (metres; `None`: detected).
///
/// # Errors
/// [`TrackError`] for unreadable or malformed inputs.
pub fn load_with_max_range(
    field: &Path,
    log: &Path,
    (z_hit, z_rand, sigma_hit): (f32, f32, f32),
    max_range_m: Option<f32>,
) -> Result<TrackInput, TrackError> {
    let bytes = field_bytes(field)?;
    let options = ReadOptions {
        max_range_m,
        ..ReadOptions::default()
    };
    let log = CarmenLog::read_path(log, options).map_err(TrackError::Log)?;
    let max_range = log.max_range.value_m().ok_or_else(|| {
        usage("the log's max-range value could not be detected (give --max-range)")
    })?;
    let params = LikelihoodParams::new(z_hit, z_rand, sigma_hit, max_range)
        .map_err(|e| usage(format!("likelihood field parameters: {e}")))?;
    let layout = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(|e| usage(format!("beam layout of the log: {e}")))?;
    if let Some(s) = log.scans.first() {
        // Every scan has the first one's beams (the reader enforces it).
        s.to_scan::<MAX_BEAMS>()
            .map_err(|e| usage(format!("scan: {e}")))?;
    } else {
        return Err(usage("no FLASER scans in the log"));
    }
    let logged = log.scans.iter().map(|s| s.pose).collect();
    let scans = log.scans.into_iter().map(|s| s.ranges_m).collect();
    let input = TrackInput {
        bytes,
        params,
        layout,
        scans,
        logged,
        odometry: None,
        reference: None,
    };
    input.views()?;
    Ok(input)
}
