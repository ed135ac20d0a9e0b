//! Parsing one FLASER line.

use super::error::{Field, LineError, LineErrorKind};
use super::{printable, LaserScan, PoseF64, FLASER_TRAILER_TOKENS};
use beamfield::Pose;

pub(super) fn parse_finite<T>(token: &str, field: Field, line: usize) -> Result<T, LineError>
where
    T: std::str::FromStr + Into<f64> + Copy,
{
    match token.parse::<T>() {
        Ok(v) if v.into().is_finite() => Ok(v),
        _ => Err(LineError {
            line,
            kind: LineErrorKind::BadNumber {
                field,
                token: printable(token),
            },
        }),
    }
}

pub(super) fn parse_flaser<'a>(
    mut tokens: impl Iterator<Item = &'a str>,
    line: usize,
    first_n: Option<usize>,
) -> Result<LaserScan, LineError> {
    let err = |kind| LineError { line, kind };
    let n_token = tokens.next().unwrap_or("");
    let n = match n_token.parse::<usize>() {
        Ok(n) if n > 0 => n,
        _ => {
            return Err(err(LineErrorKind::BadBeamCount {
                token: printable(n_token),
            }))
        }
    };
    let rest: Vec<&str> = tokens.collect();
    let expected = n.saturating_add(FLASER_TRAILER_TOKENS);
    if rest.len() != expected {
        return Err(err(LineErrorKind::WrongTokenCount {
            beams: n,
            expected,
            found: rest.len(),
        }));
    }
    if let Some(first) = first_n {
        if first != n {
            return Err(err(LineErrorKind::BeamCountMismatch { first, found: n }));
        }
    }
    let (range_tokens, trailer) = rest.split_at(n);
    let mut ranges_m = Vec::with_capacity(n);
    for (i, t) in range_tokens.iter().enumerate() {
        // Ranges may be anything numeric (inf, nan): the reading policy classifies them later.
        let v = t.parse::<f32>().map_err(|_| {
            err(LineErrorKind::BadNumber {
                field: Field::Range(i),
                token: printable(t),
            })
        })?;
        ranges_m.push(v);
    }
    let fields = [
        Field::X,
        Field::Y,
        Field::Theta,
        Field::OdomX,
        Field::OdomY,
        Field::OdomTheta,
    ];
    // In f64: a pose far from the origin keeps its sub-millimetre digits (an f32 at 1e9 m is
    // 64 m apart from the next one); the f32 poses are rounded from these.
    let mut pose = [0.0f64; 6];
    for ((slot, field), token) in pose.iter_mut().zip(fields).zip(trailer) {
        *slot = parse_finite::<f64>(token, field.clone(), line)?;
        if !(*slot as f32).is_finite() {
            return Err(err(LineErrorKind::BadNumber {
                field,
                token: printable(token),
            }));
        }
    }
    let [x, y, th, ox, oy, oth] = pose;
    let (ipc, logger) = match trailer {
        [.., ipc, _host, logger] => (
            parse_finite::<f64>(ipc, Field::IpcTimestamp, line)?,
            parse_finite::<f64>(logger, Field::LoggerTimestamp, line)?,
        ),
        // Unreachable: the token count was checked above; report it as a count error anyway.
        _ => {
            return Err(err(LineErrorKind::WrongTokenCount {
                beams: n,
                expected,
                found: rest.len(),
            }))
        }
    };
    Ok(LaserScan {
        ranges_m,
        pose: Pose::new(x as f32, y as f32, th as f32),
        odom_pose: Pose::new(ox as f32, oy as f32, oth as f32),
        pose_f64: PoseF64 {
            x_m: x,
            y_m: y,
            theta_rad: th,
        },
        timestamp_s: ipc,
        logger_timestamp_s: logger,
        line,
    })
}
