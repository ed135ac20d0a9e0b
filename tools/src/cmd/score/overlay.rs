//! The `--overlay` picture of `beamfield score`: the scan's endpoints over the field at the
//! given pose and at the grid's best pose.

use super::grid::BestPose;
use super::ScoreArgs;
use crate::cmd::scored_log::{usage, Loaded, ScoreCmdError, MAX_BEAMS};
use beamfield::{Pose, Scan};
use std::path::Path;

/// The `--overlay` window's centre (metres), checking `--overlay-half` and `--overlay-center`.
pub(super) fn overlay_center(a: &ScoreArgs, pose: &Pose) -> Result<(f64, f64), ScoreCmdError> {
    if !(a.overlay_half.is_finite() && a.overlay_half > 0.0 && a.overlay_half <= 1000.0) {
        return Err(usage("--overlay-half must be in (0, 1000] metres"));
    }
    Ok(match &a.overlay_center {
        None => (f64::from(pose.x_m), f64::from(pose.y_m)),
        Some(t) => {
            let v: Vec<f64> = t
                .split(',')
                .map(|p| p.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| usage(format!("--overlay-center {t:?}: expected X,Y (numbers)")))?;
            match v.as_slice() {
                [x, y] if x.is_finite() && y.is_finite() => (*x, *y),
                _ => {
                    return Err(usage(format!(
                        "--overlay-center {t:?}: expected two finite numbers"
                    )))
                }
            }
        }
    })
}

pub(super) fn write_overlay(
    a: &ScoreArgs,
    l: &Loaded,
    scan: &Scan<MAX_BEAMS>,
    pose: &Pose,
    center: (f64, f64),
    best: &BestPose,
    path: &Path,
) -> Result<(), ScoreCmdError> {
    let bearings: Vec<f32> = l.layout.beams().iter().map(|b| b.bearing_rad).collect();
    let max_range = l.params.max_range_m();
    let at = |p: &Pose| (f64::from(p.x_m), f64::from(p.y_m), f64::from(p.theta_rad));
    let (dx, dy, dt) = best.offset;
    let title = format!(
        "scan {}: best grid pose {:.1} cm, {:.2}° from the given one",
        a.scan,
        (dx * dx + dy * dy).sqrt() * 100.0,
        dt.to_degrees()
    );
    let scans = vec![
        crate::draw::overlay::OverlayScan {
            name: "endpoints at the given pose".into(),
            color: plotters::style::RGBColor(20, 90, 230),
            pose: at(pose),
            points: crate::draw::overlay::endpoints(
                at(pose),
                &bearings,
                scan.ranges_m(),
                max_range,
            ),
        },
        crate::draw::overlay::OverlayScan {
            name: "endpoints at the grid's best pose".into(),
            color: plotters::style::RGBColor(0, 170, 60),
            pose: at(&best.pose),
            points: crate::draw::overlay::endpoints(
                at(&best.pose),
                &bearings,
                scan.ranges_m(),
                max_range,
            ),
        },
    ];
    let view = crate::input::field_file::parse_field_file(&l.blob).map_err(ScoreCmdError::Blob)?;
    crate::draw::overlay::draw_overlay(
        path,
        &view,
        &crate::draw::overlay::Overlay {
            title: &title,
            center,
            half_m: a.overlay_half,
            scans,
        },
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))
}
