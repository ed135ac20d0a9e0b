//! The synthesized odometry a run is fed: the logged poses' steps perturbed by the motion
//! model's noise, with Box–Muller normals from [`SplitMix64`].

use super::{usage, TrackError, ODOMETRY_SEED_XOR};
use beamfield::gaussian::standard_normal_pair;
use beamfield::mcl::{OdometryNoise, OdometryStep, SplitMix64};
use beamfield::{math, wrap_angle, Pose};

/// The synthesized odometry of run seed `seed`: starting at the first logged pose, each step
/// between consecutive logged poses is perturbed by `noise` (the variances of
/// [`OdometryNoise::sigmas`], drawn by [`odometry_sample`] from [`SplitMix64`] seeded
/// `seed ^ ODOMETRY_SEED_XOR`) and chained. One pose per logged pose
/// (none for none). The filter sees the steps between consecutive odometry poses; the firmware's
/// track asset (`fixtures/assets/track.rs`) is written from the same function.
///
/// # Errors
/// [`TrackError::Usage`] for a logged pose that is not finite.
pub fn synthesize_odometry(
    noise: &OdometryNoise,
    logged: &[Pose],
    seed: u64,
) -> Result<Vec<Pose>, TrackError> {
    let mut odom_rng = SplitMix64::new(seed ^ ODOMETRY_SEED_XOR);
    let mut out: Vec<Pose> = Vec::with_capacity(logged.len());
    for (k, truth) in logged.iter().enumerate() {
        let next = match (k.checked_sub(1).and_then(|j| logged.get(j)), out.last()) {
            (Some(prev), Some(odom)) => {
                let step = OdometryStep::between(prev, truth)
                    .map_err(|e| usage(format!("logged pose {k}: {e}")))?;
                odometry_sample(noise, odom, &step, &mut odom_rng)
            }
            _ => *truth,
        };
        out.push(next);
    }
    Ok(out)
}

/// One draw of the odometry model for the synthesized odometry: the model of
/// [`OdometryNoise::sample`], with its normals from the Box–Muller transform
/// ([`standard_normal_pair`], four `next_u32`: δrot1 and δtrans from the first pair, δrot2 from
/// the first value of the second) rather than the filter's ziggurat, so that the data the
/// filter is measured on does not come from the filter's own sampler. (The filter used
/// Box–Muller until it moved to the ziggurat for speed; this keeps the synthesized odometry,
/// and the firmware's track asset, as they were.)
pub fn odometry_sample(
    noise: &OdometryNoise,
    pose: &Pose,
    step: &OdometryStep,
    rng: &mut SplitMix64,
) -> Pose {
    let (s_rot1, s_trans, s_rot2) = noise.sigmas(step);
    let (n1, n2) = standard_normal_pair(rng);
    let (n3, _) = standard_normal_pair(rng);
    let rot1 = step.rot1_rad() - s_rot1 * n1;
    let trans = step.trans_m() - s_trans * n2;
    let rot2 = step.rot2_rad() - s_rot2 * n3;
    let (s, c) = math::sin_cos(pose.theta_rad + rot1);
    Pose {
        x_m: pose.x_m + trans * c,
        y_m: pose.y_m + trans * s,
        theta_rad: wrap_angle(pose.theta_rad + rot1 + rot2),
    }
}
