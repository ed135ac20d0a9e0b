//! The nearest-beam lookup of a uniform layout, and its inverse (a revolution sampled from a
//! scan).

use super::config::AssemblerError;
use crate::scan::{BeamLayout, Scan};

/// The geometry of a uniform layout, in degrees, for nearest-beam lookups.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bins {
    pub(crate) beams: usize,
    /// Layout start, degrees counter-clockwise, in `[0, 360)`.
    first_deg: f32,
    /// Beams per degree.
    inv_step: f32,
    /// Beam steps in a full turn.
    steps_per_turn: f32,
}

impl Bins {
    pub(crate) fn new<const N: usize>(layout: &BeamLayout<N>) -> Result<Self, AssemblerError> {
        let beams = layout.beams();
        let first_rad = beams.first().map_or(0.0, |b| b.bearing_rad);
        let step_rad = match beams {
            [a, b, ..] => b.bearing_rad - a.bearing_rad,
            // One beam: a full-turn bin.
            _ => core::f32::consts::TAU,
        };
        if step_rad.is_nan() || step_rad <= 0.0 {
            return Err(AssemblerError::NotUniform(1));
        }
        for (i, b) in beams.iter().enumerate() {
            let want = first_rad + step_rad * i as f32;
            if (b.bearing_rad - want).abs() > 1e-4 {
                return Err(AssemblerError::NotUniform(i));
            }
        }
        let step_deg = step_rad.to_degrees();
        if step_deg * beams.len() as f32 > 360.0 + 1e-3 {
            return Err(AssemblerError::MoreThanOneTurn);
        }
        let mut first_deg = first_rad.to_degrees() % 360.0;
        if first_deg < 0.0 {
            first_deg += 360.0;
        }
        if first_deg >= 360.0 {
            first_deg = 0.0;
        }
        Ok(Self {
            beams: beams.len(),
            first_deg,
            inv_step: 1.0 / step_deg,
            steps_per_turn: 360.0 / step_deg,
        })
    }

    /// The beam nearest to the clockwise angle `a` (degrees, `[0, 360)`) and the distance to
    /// it in beam steps (≤ 0.5), or `None` when no beam is within half a step.
    #[inline(always)]
    pub(crate) fn nearest(&self, a: f32) -> Option<(usize, f32)> {
        // Bearing −a relative to the layout's first beam, brought into [0, 360].
        let mut rel = -a - self.first_deg; // in (−720, 0]
        rel += if rel < -360.0 { 720.0 } else { 360.0 };
        let mut k = rel * self.inv_step;
        // Within half a step below the first beam: measure from it, negatively.
        if k >= self.steps_per_turn - 0.5 {
            k -= self.steps_per_turn;
        }
        // k ≥ −0.5 here, so truncation is rounding to nearest.
        let idx = (k + 0.5) as usize;
        (idx < self.beams).then(|| (idx, (k - idx as f32).abs()))
    }
}

/// The inverse of assembly, for encoders and tests: the range a sensor turning clockwise would
/// report at each of `out.len()` evenly spaced angles (`out[k]` at `k · 360° / out.len()`
/// clockwise from the sensor's zero direction), read from `scan` on `layout`.
///
/// `out[k]` is the reading of the beam nearest to that angle when one lies within half a beam
/// step (the assembler's binning rule), NaN otherwise (the sensor sees nothing the scan covers).
/// A scan shorter than the layout reads NaN for its missing beams.
///
/// # Errors
/// As [`ScanAssembler::new`](super::ScanAssembler::new) for the layout.
pub fn sample_revolution<const N: usize>(
    layout: &BeamLayout<N>,
    scan: &Scan<N>,
    out: &mut [f32],
) -> Result<(), AssemblerError> {
    let bins = Bins::new(layout)?;
    let step_deg = 360.0 / out.len().max(1) as f32;
    for (k, o) in out.iter_mut().enumerate() {
        let a = k as f32 * step_deg;
        *o = bins
            .nearest(if a < 360.0 { a } else { 0.0 })
            .and_then(|(i, _)| scan.ranges_m().get(i).copied())
            .unwrap_or(f32::NAN);
    }
    Ok(())
}

/// The layout the LD06 family reports natively: 360 beams 1° apart, counter-clockwise from the
/// sensor's zero direction, for a sensor at `mount` (a convenience; any uniform layout works).
///
/// # Errors
/// As [`BeamLayout::uniform`].
pub fn full_turn_layout<const N: usize>(
    beams: usize,
    max_range_m: f32,
    mount: crate::pose::SensorMount,
) -> Result<BeamLayout<N>, crate::scan::ScanError> {
    let step = core::f32::consts::TAU / beams.max(1) as f32;
    BeamLayout::uniform(0.0, step, beams, max_range_m, mount)
}
