//! The pose grids of `beamfield score`: the x–y surface and θ profile around the pose (`--grid`:
//! a CSV and two PNGs) and the best pose of the x–y–θ grid (`--overlay`).

use super::ScoreArgs;
use crate::cmd::scored_log::{usage, ScoreCmdError, MAX_BEAMS};
use crate::draw::plot::{line_chart, LineChart, Series};
use crate::pose_grid::{argmax, score_grid, GridSpec};
use beamfield::{BeamLayout, Pose, Scan, SensorModel};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub(super) fn check_grid(a: &ScoreArgs) -> Result<(), ScoreCmdError> {
    if !(a.grid_step > 0.0 && a.grid_half >= a.grid_step && a.grid_half / a.grid_step <= 500.0) {
        return Err(usage(
            "--grid-step must be > 0 and at most --grid-half, with ≤ 500 steps per side",
        ));
    }
    if !(a.grid_half_deg > 0.0 && a.grid_half_deg <= 180.0) {
        return Err(usage("--grid-half-deg must be in (0, 180]"));
    }
    Ok(())
}

/// The best pose of the x–y–θ grid around the given pose (`--overlay`).
pub(super) struct BestPose {
    pub pose: Pose,
    pub offset: (f64, f64, f64),
    pub log_likelihood: f64,
    pub poses: usize,
}

pub(super) fn best_grid_pose<M: SensorModel<MAX_BEAMS>>(
    a: &ScoreArgs,
    model: &M,
    layout: &BeamLayout<MAX_BEAMS>,
    scan: &Scan<MAX_BEAMS>,
    pose: &Pose,
) -> Result<BestPose, ScoreCmdError> {
    check_grid(a)?;
    let spec = GridSpec {
        half_xy_m: a.grid_half,
        step_xy_m: a.grid_step,
        half_theta_rad: a.grid_half_deg.to_radians(),
        step_theta_rad: 0.25f64.to_radians(),
    };
    if spec.len() > 20_000_000 {
        return Err(usage(format!(
            "--overlay: the x–y–θ grid has {} poses (at most 20 million): use a coarser --grid-step or a smaller --grid-half or --grid-half-deg",
            spec.len()
        )));
    }
    crate::progress::note(&format!(
        "score: searching {} poses for the overlay's best pose",
        spec.len()
    ));
    let g = score_grid(model, layout, scan, pose, &spec);
    let i = argmax(&g.log_likelihood).ok_or_else(|| usage("the pose grid is empty"))?;
    Ok(BestPose {
        pose: spec.pose(pose, i),
        offset: spec.offset(i),
        log_likelihood: g.log_likelihood.get(i).copied().unwrap_or(f64::NAN),
        poses: spec.len(),
    })
}

/// The x–y surface at θ and the θ profile at (x, y): a CSV (`dx_m,dy_m,dtheta_rad,log_likelihood`)
/// and two PNGs.
pub(super) fn write_grid<M: SensorModel<MAX_BEAMS>>(
    a: &ScoreArgs,
    model: &M,
    layout: &BeamLayout<MAX_BEAMS>,
    scan: &Scan<MAX_BEAMS>,
    pose: &Pose,
    prefix: &Path,
) -> Result<Vec<String>, ScoreCmdError> {
    check_grid(a)?;
    let xy = GridSpec {
        half_xy_m: a.grid_half,
        step_xy_m: a.grid_step,
        half_theta_rad: 0.0,
        step_theta_rad: 1.0,
    };
    let th = GridSpec {
        half_xy_m: 0.0,
        step_xy_m: 1.0,
        half_theta_rad: a.grid_half_deg.to_radians(),
        step_theta_rad: 0.25f64.to_radians(),
    };
    let gxy = score_grid(model, layout, scan, pose, &xy);
    let gth = score_grid(model, layout, scan, pose, &th);
    let mut csv = String::from("dx_m,dy_m,dtheta_rad,log_likelihood\n");
    for (spec, g) in [(&xy, &gxy), (&th, &gth)] {
        for (i, l) in g.log_likelihood.iter().enumerate() {
            let (dx, dy, dt) = spec.offset(i);
            let _ = writeln!(csv, "{dx:.4},{dy:.4},{dt:.5},{l:.4}");
        }
    }
    let name = |suffix: &str| {
        let mut s = prefix.as_os_str().to_owned();
        s.push(suffix);
        PathBuf::from(s)
    };
    let csv_path = name(".csv");
    std::fs::write(&csv_path, csv).map_err(|e| ScoreCmdError::Io(csv_path.clone(), e))?;
    let png_xy = name("-xy.png");
    crate::draw::heat_map::heat_map(
        &png_xy,
        &format!(
            "log-likelihood around ({:.2}, {:.2}) m at θ = {:.3} rad",
            pose.x_m, pose.y_m, pose.theta_rad
        ),
        xy.dims().0,
        a.grid_half,
        &gxy.log_likelihood,
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))?;
    let png_th = name("-theta.png");
    let pts = gth
        .log_likelihood
        .iter()
        .enumerate()
        .map(|(i, l)| (th.offset(i).2.to_degrees(), *l))
        .collect();
    line_chart(
        &png_th,
        &LineChart {
            title: "log-likelihood against heading offset",
            x_label: "θ offset (degrees)",
            y_label: "log-likelihood (nats)",
            x_log: false,
            h_lines: vec![],
            v_lines: vec![(0.0, "given θ".into())],
            series: vec![Series {
                name: "scan".into(),
                points: pts,
            }],
        },
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))?;
    Ok([csv_path, png_xy, png_th]
        .iter()
        .map(|p| p.display().to_string())
        .collect())
}
