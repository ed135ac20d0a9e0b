//! [`BeamFieldModel`]: the beam model (Thrun Table 6.1) scored on the device, with each beam's
//! `z*` ray cast through the distance-field blob ([`crate::raycast`]).
//!
//! For a pose `x = (x, y, θ)` and the [`SensorMount`](crate::SensorMount) `(x_s, y_s, θ_s)`,
//! beam `k` (bearing `θ_k`) is cast from the sensor's position along `θ + θ_s + θ_k` up to the
//! intrinsics' `z_max`, and the reading is scored with [`BeamModel::beam_log_likelihood`]
//! against that range: the mixture of `p_hit`, `p_short`, `p_max`, `p_rand`, in nats. Max-range
//! readings are scored (the point mass `z_max`), NaN and negative readings are skipped and
//! counted. The sensor pose needs one `sin_cos` per pose; bearings' unit vectors come from the
//! [`BeamLayout`], so no trigonometry per beam.

use crate::beam::{saturating_u16, BeamModel};
use crate::math;
use crate::model::{SensorModel, Stride};
use crate::pose::Pose;
use crate::raycast::{CastTrace, RayCaster};
use crate::scan::{Beam, BeamLayout, Scan, ScanScore};

/// Beams cast together ([`RayCaster::cast_dirs`]) before they are scored in bearing order:
/// two stack buffers of this many directions and ranges (12 bytes per beam).
pub const CAST_BLOCK: usize = 16;

/// Whether [`BeamFieldModel`] casts its beams in interleaved blocks: on the host yes, on 32-bit
/// Arm no (docs/race.md: measured under QEMU, interleaving only adds instructions there).
const BATCH_CASTS: bool = !cfg!(target_arch = "arm");

/// The beam model over a blob: a [`BeamModel`] and a [`RayCaster`]. Immutable; one value scores
/// every pose hypothesis.
#[derive(Clone, Copy, Debug)]
pub struct BeamFieldModel<'a> {
    model: BeamModel,
    caster: RayCaster<'a>,
}

impl<'a> BeamFieldModel<'a> {
    /// Pairs a beam model with a ray caster (both validated already).
    pub fn new(model: BeamModel, caster: RayCaster<'a>) -> Self {
        Self { model, caster }
    }

    /// The beam mixture.
    pub fn model(&self) -> &BeamModel {
        &self.model
    }

    /// The ray caster.
    pub fn caster(&self) -> &RayCaster<'a> {
        &self.caster
    }

    /// Writes `z*` (metres, `≤ z_max`) of every `stride`-th beam of `layout` at `pose` into
    /// `z_star_m[k]` (entries of skipped beams and past the layout are left alone; a shorter
    /// slice receives what fits). The EM tools cast once per beam with this.
    pub fn cast_layout<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        pose: &Pose,
        stride: Stride,
        z_star_m: &mut [f32],
    ) {
        let beams = layout.beams().iter().take(z_star_m.len());
        let mut outs = z_star_m.iter_mut().step_by(stride.get());
        let items = beams.map(|b| (b, ())).step_by(stride.get());
        self.cast_in_order(layout, pose, items, |(), z_star| {
            if let Some(o) = outs.next() {
                *o = z_star;
            }
        });
    }

    /// Casts the beams of `items` (a beam of `layout` and anything `f` needs with it) at
    /// `pose` and hands each item's extra and `z*` (metres, `≤ z_max`) to `f`, in the
    /// iterator's order. On the host the rays are cast [`CAST_BLOCK`] at a time with
    /// [`RayCaster::cast_dirs`] (interleaved; the same results as one by one). On 32-bit Arm
    /// (the Cortex-M targets: no data cache to hide, and interleaving costs instructions) they
    /// are cast one by one.
    #[inline(always)]
    fn cast_in_order<'b, X: Copy, const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        pose: &Pose,
        items: impl Iterator<Item = (&'b Beam, X)>,
        mut f: impl FnMut(X, f32),
    ) {
        let sensor = layout.mount().sensor_pose(pose);
        let (s, c) = math::sin_cos(sensor.theta_rad);
        let max = self.model.intrinsics().max_range_m();
        let dir = |beam: &Beam| [c * beam.cos - s * beam.sin, s * beam.cos + c * beam.sin];
        if !BATCH_CASTS {
            for (beam, x) in items {
                let [ux, uy] = dir(beam);
                f(x, self.caster.cast_dir(sensor.x_m, sensor.y_m, ux, uy, max));
            }
            return;
        }
        let mut items = items;
        let mut dirs = [[0.0f32; 2]; CAST_BLOCK];
        let mut extras: [Option<X>; CAST_BLOCK] = [None; CAST_BLOCK];
        let mut z_star = [0.0f32; CAST_BLOCK];
        loop {
            let mut n = 0usize;
            for ((d, e), (beam, x)) in dirs.iter_mut().zip(extras.iter_mut()).zip(&mut items) {
                *d = dir(beam);
                *e = Some(x);
                n += 1;
            }
            let block = dirs.get(..n).unwrap_or_default();
            self.caster
                .cast_dirs(sensor.x_m, sensor.y_m, block, max, &mut z_star);
            for (e, &z) in extras.iter().zip(&z_star).take(n) {
                if let Some(x) = *e {
                    f(x, z);
                }
            }
            if n < CAST_BLOCK {
                return;
            }
        }
    }
}

impl BeamFieldModel<'_> {
    /// As [`BeamFieldModel::cast_layout`], also adding each cast's jumps and cell steps to
    /// `traces[k]` (profiling: where the ray casting's time goes).
    pub fn cast_layout_traced<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        pose: &Pose,
        z_star_m: &mut [f32],
        traces: &mut [CastTrace],
    ) {
        let sensor = layout.mount().sensor_pose(pose);
        let (s, c) = math::sin_cos(sensor.theta_rad);
        let max = self.model.intrinsics().max_range_m();
        for ((beam, out), trace) in layout
            .beams()
            .iter()
            .zip(z_star_m.iter_mut())
            .zip(traces.iter_mut())
        {
            let ux = c * beam.cos - s * beam.sin;
            let uy = s * beam.cos + c * beam.sin;
            *out = self
                .caster
                .cast_dir_traced(sensor.x_m, sensor.y_m, ux, uy, max, trace);
        }
    }
}

impl<const N: usize> SensorModel<N> for BeamFieldModel<'_> {
    /// Casts and scores beams `0, s, 2s, …`. Every valid reading, max-range ones included, is
    /// counted in `scored`; readings past the layout are `unpaired`.
    fn score_strided(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
    ) -> ScanScore {
        let ranges = scan.ranges_m();
        let mut score = ScanScore::default();
        let mut sum = 0.0f32;
        let items = layout.beams().iter().zip(ranges.iter().copied());
        self.cast_in_order(
            layout,
            pose,
            items.step_by(stride.get()),
            |z, z_star| match self.model.beam_log_likelihood(z, z_star) {
                Some(l) => {
                    sum += l;
                    score.scored = score.scored.saturating_add(1);
                }
                None => score.invalid = score.invalid.saturating_add(1),
            },
        );
        // A NaN or infinite pose is nowhere: no finite score for it.
        score.log_likelihood = if pose.is_finite() { sum } else { f32::NAN };
        score.unpaired = saturating_u16(ranges.len().saturating_sub(layout.len()));
        score
    }
}
