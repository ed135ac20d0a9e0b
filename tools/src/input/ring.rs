//! Reading ring files (TOML, docs/examples/ring24.toml): an ultrasonic ring's transducers and
//! its crosstalk law, validated into a [`beamfield::sonar::Ring`].

use beamfield::sonar::{CrosstalkModel, Ring, Transducer};
use serde::Deserialize;
use std::path::Path;

/// Largest ring the tool handles.
pub const MAX_TRANSDUCERS: usize = 64;

/// The crosstalk law of a ring file.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct CrosstalkSpec {
    /// `"constant"` or `"gaussian"`.
    pub model: String,
    /// `q` (constant) or `q0` (Gaussian peak), in [0, 1].
    pub q0: f32,
    /// Gaussian lobe width, degrees.
    pub width_deg: Option<f32>,
}

/// A ring file (TOML).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RingSpec {
    /// Explicit bearings, degrees counter-clockwise; or use `count`/`first_bearing_deg`/`step_deg`.
    pub bearings_deg: Option<Vec<f32>>,
    /// Number of evenly spaced transducers.
    pub count: Option<usize>,
    /// Bearing of transducer 0, degrees.
    pub first_bearing_deg: Option<f32>,
    /// Step between transducers, degrees (negative for clockwise numbering).
    pub step_deg: Option<f32>,
    /// Mounting radius, metres.
    #[serde(default)]
    pub radius_m: f32,
    /// Cone half-angle, degrees.
    pub cone_half_angle_deg: f32,
    /// Max range, metres.
    pub max_range_m: f32,
    /// Speed of sound, m/s (default 343).
    pub speed_of_sound_m_per_s: Option<f32>,
    /// Base z_rand (fired alone), default 0.05.
    pub z_rand0: Option<f32>,
    /// Crosstalk law.
    pub crosstalk: CrosstalkSpec,
}

/// A loaded, validated ring with its crosstalk law.
#[derive(Debug)]
pub struct LoadedRing {
    /// The ring.
    pub ring: Ring<MAX_TRANSDUCERS>,
    /// Speed of sound, m/s.
    pub speed_of_sound_m_per_s: f32,
    /// Base z_rand.
    pub z_rand0: f32,
    /// The crosstalk law.
    pub model: CrosstalkModel,
}

/// Reads and validates a ring file.
///
/// # Errors
/// A message naming the file and the problem.
pub fn load_ring(path: &Path) -> Result<LoadedRing, String> {
    let bytes = crate::input::limits::read_regular_file(
        path,
        crate::input::limits::MAX_TEXT_FILE_BYTES,
        "ring description",
    )
    .map_err(|e| e.to_string())?;
    let text =
        String::from_utf8(bytes).map_err(|_| format!("{}: not UTF-8 text", path.display()))?;
    let spec: RingSpec = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    ring_from_spec(&spec).map_err(|e| format!("{}: {e}", path.display()))
}

/// Builds the ring of a parsed spec.
///
/// # Errors
/// A message for an inconsistent or invalid spec.
pub fn ring_from_spec(spec: &RingSpec) -> Result<LoadedRing, String> {
    let cone = spec.cone_half_angle_deg.to_radians();
    let ring = match (&spec.bearings_deg, spec.count) {
        (Some(b), None) => {
            let ts: Vec<Transducer> = b
                .iter()
                .map(|&d| {
                    let r = d.to_radians();
                    Transducer {
                        bearing_rad: r,
                        x_m: spec.radius_m * r.cos(),
                        y_m: spec.radius_m * r.sin(),
                    }
                })
                .collect();
            Ring::new(&ts, cone, spec.max_range_m)
        }
        (None, Some(n)) => Ring::uniform(
            n,
            spec.first_bearing_deg.unwrap_or(0.0).to_radians(),
            spec.step_deg
                .ok_or("`step_deg` is required with `count`")?
                .to_radians(),
            spec.radius_m,
            cone,
            spec.max_range_m,
        ),
        _ => {
            return Err("give either `bearings_deg` or `count` (with `step_deg`), not both".into())
        }
    }
    .map_err(|e| format!("ring: {e}"))?;
    let model = match spec.crosstalk.model.as_str() {
        "constant" => CrosstalkModel::constant(spec.crosstalk.q0),
        "gaussian" => CrosstalkModel::gaussian(
            spec.crosstalk.q0,
            spec.crosstalk
                .width_deg
                .ok_or("crosstalk: `width_deg` is required for the gaussian model")?
                .to_radians(),
        ),
        other => {
            return Err(format!(
                "crosstalk: unknown model `{other}` (constant, gaussian)"
            ))
        }
    }
    .map_err(|e| format!("crosstalk: {e}"))?;
    let c = spec.speed_of_sound_m_per_s.unwrap_or(343.0);
    if !(c.is_finite() && c > 0.0) {
        return Err("speed_of_sound_m_per_s must be finite and > 0".into());
    }
    let z0 = spec.z_rand0.unwrap_or(0.05);
    if !(0.0..=1.0).contains(&z0) {
        return Err("z_rand0 must be in [0, 1]".into());
    }
    Ok(LoadedRing {
        ring,
        speed_of_sound_m_per_s: c,
        z_rand0: z0,
        model,
    })
}
