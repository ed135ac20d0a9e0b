//! nav2's amcl parameters, read from a nav2 params file (`amcl: ros__parameters: …`): those
//! with a counterpart on the bridge or the device are applied, every other one is named with
//! the reason it is not (docs/nav2.md has the whole table).

use std::collections::BTreeMap;

use beamfield::link::{SetInitialPose, SetParameters};
use beamfield::Pose;
use serde::Serialize;
use serde_yaml::Value;

/// The bridge's settings that nav2_amcl's parameters name, with nav2's defaults.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Frames {
    /// `global_frame_id`.
    pub global: String,
    /// `odom_frame_id`.
    pub odom: String,
    /// `base_frame_id` (only reported: the device's poses are of its base).
    pub base: String,
    /// `transform_tolerance`, seconds the map → odom transform is post-dated by.
    pub transform_tolerance_s: f64,
    /// `tf_broadcast`.
    pub tf_broadcast: bool,
}

impl Default for Frames {
    fn default() -> Self {
        Self {
            global: "map".into(),
            odom: "odom".into(),
            base: "base_footprint".into(),
            transform_tolerance_s: 1.0,
            tf_broadcast: true,
        }
    }
}

/// What a params file says, sorted into what is applied and what is not.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Nav2Params {
    pub frames: Frames,
    /// To send to the device at start (particles and α), if any was given.
    #[serde(skip)]
    pub set_parameters: Option<SetParameters>,
    /// To send at start when `set_initial_pose` is true.
    #[serde(skip)]
    pub initial_pose: Option<SetInitialPose>,
    /// Applied: `name → what it became`.
    pub applied: BTreeMap<String, String>,
    /// Not applied: `name → why`.
    pub ignored: BTreeMap<String, String>,
}

/// Largest params file read, bytes: 1 MiB, as the host tool's limit for small text files
/// (`MAX_TEXT_FILE_BYTES`, `tools/src/input/limits.rs`).
pub const MAX_PARAMS_FILE_BYTES: u64 = 1 << 20;

/// A params file that could not be used.
#[derive(Debug)]
pub enum ParamsError {
    Read(std::path::PathBuf, std::io::Error),
    /// The path names a device, a FIFO or something else that is not a regular file.
    NotAFile(std::path::PathBuf),
    /// The file is larger than `limit` bytes: `bytes` is its size, or `limit + 1` for a file
    /// that grew past the limit while it was read.
    TooLarge {
        path: std::path::PathBuf,
        bytes: u64,
        limit: u64,
    },
    Yaml(serde_yaml::Error),
    /// No `amcl: ros__parameters:` mapping.
    NoAmclSection,
    /// A parameter with a counterpart but a value of the wrong type or range.
    Value {
        name: String,
        why: String,
    },
}

impl std::fmt::Display for ParamsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Read(p, e) => write!(f, "cannot read {}: {e}", p.display()),
            Self::NotAFile(p) => write!(f, "{} is not a regular file", p.display()),
            Self::TooLarge { path, bytes, limit } => write!(
                f,
                "{} is larger than {limit} bytes, the limit for a params file ({bytes} bytes seen)",
                path.display()
            ),
            Self::Yaml(e) => write!(f, "not a YAML params file: {e}"),
            Self::NoAmclSection => f.write_str(
                "no `amcl: ros__parameters:` section (the bridge reads nav2_amcl's parameters)",
            ),
            Self::Value { name, why } => write!(f, "parameter {name}: {why}"),
        }
    }
}

impl std::error::Error for ParamsError {}

/// Why each nav2_amcl parameter without a counterpart is not applied.
fn not_supported(name: &str) -> Option<&'static str> {
    Some(match name {
        "alpha5" => "omnidirectional motion model only; the device uses the differential one",
        "robot_model_type" => "the device's motion model is differential drive (beamfield::mcl::OdometryNoise)",
        "min_particles" => "the device keeps a fixed particle count (the library's KLD sampling, beamfield::mcl::Kld, is not on the link): max_particles is used",
        "laser_model_type" | "z_hit" | "z_short" | "z_max" | "z_rand" | "sigma_hit"
        | "lambda_short" | "laser_likelihood_max_dist" | "laser_max_range" | "laser_min_range"
        | "max_beams" => "the sensor model and its field are built into the firmware (beamfield field build, RobotConfig)",
        "do_beamskip" | "beam_skip_distance" | "beam_skip_threshold"
        | "beam_skip_error_threshold" => "no beam skipping on the device",
        "update_min_d" | "update_min_a" => "set in the firmware's RobotConfig (not on the link)",
        "resample_interval" => "the device resamples when the effective sample size falls below half",
        "recovery_alpha_slow" | "recovery_alpha_fast" => "the device's recovery is configured in the firmware",
        "pf_err" | "pf_z" => "no KLD sampling on the device",
        "scan_topic" => "the LiDAR is wired to the device: there is no scan topic",
        "map_topic" | "first_map_only" | "freespace_downsampling" => "the map is in the device's flash (beamfield field build)",
        "save_pose_rate" => "the device keeps its last estimate itself (Sink::save)",
        "always_reset_initial_pose" => "the device starts from its saved estimate or the initial pose sent",
        "use_sim_time" => "use --clock device for replays",
        "bond_heartbeat_period" | "bond_disable_heartbeat_timeout" => "no lifecycle bond",
        _ => return None,
    })
}

/// nav2's `alpha1..4` above this are sent with a warning in the report: measured on the Intel
/// log with the device's sensor model, α 0.2 (nav2's default) is lost in 4 to 10 runs of 10 where
/// α 0.005 is lost in none.
pub const ALPHA_WARN: f64 = 0.05;

fn number(name: &str, v: &Value) -> Result<f64, ParamsError> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| ParamsError::Value {
            name: name.into(),
            why: format!("{v:?} is not a finite number"),
        })
}

fn text(name: &str, v: &Value) -> Result<String, ParamsError> {
    v.as_str()
        .map(str::to_owned)
        .ok_or_else(|| ParamsError::Value {
            name: name.into(),
            why: format!("{v:?} is not a string"),
        })
}

impl Nav2Params {
    /// Reads a nav2 params file: a regular file of at most [`MAX_PARAMS_FILE_BYTES`] (a
    /// device or FIFO is refused before it is opened, a larger file before it is read or, if it
    /// grows while read, after `MAX_PARAMS_FILE_BYTES + 1` bytes).
    pub fn read(path: &std::path::Path) -> Result<Self, ParamsError> {
        use std::io::Read;
        let io = |e| ParamsError::Read(path.into(), e);
        let meta = std::fs::metadata(path).map_err(io)?;
        if !meta.is_file() {
            return Err(ParamsError::NotAFile(path.into()));
        }
        let too_large = |bytes| ParamsError::TooLarge {
            path: path.into(),
            bytes,
            limit: MAX_PARAMS_FILE_BYTES,
        };
        if meta.len() > MAX_PARAMS_FILE_BYTES {
            return Err(too_large(meta.len()));
        }
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .map_err(io)?
            .take(MAX_PARAMS_FILE_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        if bytes.len() as u64 > MAX_PARAMS_FILE_BYTES {
            return Err(too_large(bytes.len() as u64));
        }
        let text = String::from_utf8(bytes)
            .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
        Self::parse(&text)
    }

    /// Parses a nav2 params file's text.
    pub fn parse(yaml: &str) -> Result<Self, ParamsError> {
        let doc: Value = serde_yaml::from_str(yaml).map_err(ParamsError::Yaml)?;
        let params = doc
            .get("amcl")
            .and_then(|a| a.get("ros__parameters"))
            .and_then(Value::as_mapping)
            .ok_or(ParamsError::NoAmclSection)?;
        let mut out = Self::default();
        let mut sp = SetParameters::default();
        let mut any_sp = false;
        let mut set_initial = false;
        let mut initial = (0.0f64, 0.0f64, 0.0f64);
        for (k, v) in params {
            let Some(name) = k.as_str() else { continue };
            let applied = |out: &mut Self, what: String| {
                out.applied.insert(name.to_owned(), what);
            };
            match name {
                "global_frame_id" => {
                    out.frames.global = text(name, v)?;
                    let v = out.frames.global.clone();
                    applied(&mut out, v);
                }
                "odom_frame_id" => {
                    out.frames.odom = text(name, v)?;
                    let v = out.frames.odom.clone();
                    applied(&mut out, v);
                }
                "base_frame_id" => {
                    out.frames.base = text(name, v)?;
                    let v = out.frames.base.clone();
                    applied(&mut out, v);
                }
                "transform_tolerance" => {
                    let s = number(name, v)?;
                    if s < 0.0 {
                        return Err(ParamsError::Value {
                            name: name.into(),
                            why: "negative".into(),
                        });
                    }
                    out.frames.transform_tolerance_s = s;
                    applied(&mut out, format!("{s} s"));
                }
                "tf_broadcast" => {
                    out.frames.tf_broadcast = v.as_bool().ok_or_else(|| ParamsError::Value {
                        name: name.into(),
                        why: "not a boolean".into(),
                    })?;
                    let v = out.frames.tf_broadcast.to_string();
                    applied(&mut out, v);
                }
                "max_particles" => {
                    let n = v
                        .as_u64()
                        .filter(|n| (1..=65_535).contains(n))
                        .ok_or_else(|| ParamsError::Value {
                            name: name.into(),
                            why: format!("{v:?} is not a particle count in 1..=65535"),
                        })?;
                    sp.particles = Some(n as u16);
                    any_sp = true;
                    applied(&mut out, format!("SetParameters particles {n}"));
                }
                "alpha1" | "alpha2" | "alpha3" | "alpha4" => {
                    let a = number(name, v)?;
                    if a < 0.0 {
                        return Err(ParamsError::Value {
                            name: name.into(),
                            why: "negative".into(),
                        });
                    }
                    let i = usize::from(name.as_bytes()[5] - b'1');
                    sp.odom_alpha[i] = Some(a as f32);
                    any_sp = true;
                    // Sent as given, with a warning: nav2's values suit AMCL's broad sensor
                    // model, not the device's sharp one (docs/localization.md, "nav2's stock
                    // parameters").
                    let note = if a > ALPHA_WARN {
                        format!(
                            " (above {ALPHA_WARN}: with the device's sensor model (σ_hit 5 cm) \
                             the robot is lost more often than at 0.005-0.01, docs/localization.md)"
                        )
                    } else {
                        String::new()
                    };
                    applied(&mut out, format!("SetParameters α{} {a}{note}", i + 1));
                }
                "set_initial_pose" => {
                    set_initial = v.as_bool().unwrap_or(false);
                    applied(&mut out, set_initial.to_string());
                }
                "initial_pose" => {
                    let get = |k: &str| v.get(k).map(|x| number(k, x)).transpose();
                    initial = (
                        get("x")?.unwrap_or(0.0),
                        get("y")?.unwrap_or(0.0),
                        get("yaw")?.unwrap_or(0.0),
                    );
                    applied(
                        &mut out,
                        format!(
                            "x {} m, y {} m, yaw {} rad",
                            initial.0, initial.1, initial.2
                        ),
                    );
                }
                other => {
                    let why = not_supported(other)
                        .unwrap_or("not a nav2_amcl parameter the bridge knows");
                    out.ignored.insert(other.to_owned(), why.to_owned());
                }
            }
        }
        if any_sp {
            out.set_parameters = Some(sp);
        }
        if set_initial {
            let yaw = initial.2.sin().atan2(initial.2.cos());
            // nav2_amcl's default initial covariance: 0.5 m standard deviation, (π/12)² in yaw.
            let mut c = [[0.0f32; 3]; 3];
            c[0][0] = 0.25;
            c[1][1] = 0.25;
            c[2][2] = (core::f32::consts::PI / 12.0).powi(2);
            out.initial_pose = Some(SetInitialPose {
                timestamp_us: 0,
                pose: Pose::new(initial.0 as f32, initial.1 as f32, yaw as f32),
                covariance: c,
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAV2: &str = "
amcl:
  ros__parameters:
    alpha1: 0.2
    alpha2: 0.2
    alpha3: 0.2
    alpha4: 0.2
    alpha5: 0.2
    base_frame_id: base_link
    beam_skip_distance: 0.5
    do_beamskip: false
    global_frame_id: map
    laser_model_type: likelihood_field
    max_particles: 2000
    min_particles: 500
    odom_frame_id: odom
    robot_model_type: nav2_amcl::DifferentialMotionModel
    set_initial_pose: true
    initial_pose: {x: 1.5, y: -2.0, z: 0.0, yaw: 0.25}
    tf_broadcast: true
    transform_tolerance: 0.5
    scan_topic: scan
    z_hit: 0.5
bt_navigator:
  ros__parameters:
    global_frame: map
";

    #[test]
    fn nav2_defaults_file_sorts_into_applied_and_ignored() {
        let p = Nav2Params::parse(NAV2).unwrap();
        assert_eq!(p.frames.base, "base_link");
        assert_eq!(p.frames.transform_tolerance_s, 0.5);
        let sp = p.set_parameters.unwrap();
        assert_eq!(sp.particles, Some(2000));
        assert_eq!(sp.odom_alpha, [Some(0.2); 4]);
        let ip = p.initial_pose.unwrap();
        assert_eq!(
            (ip.pose.x_m, ip.pose.y_m, ip.pose.theta_rad),
            (1.5, -2.0, 0.25)
        );
        for k in [
            "alpha5",
            "min_particles",
            "scan_topic",
            "z_hit",
            "do_beamskip",
        ] {
            assert!(p.ignored.contains_key(k), "{k}");
        }
        assert!(p.applied.contains_key("max_particles"));
        assert_eq!(p.applied.len() + p.ignored.len(), 20);
        // nav2's α 0.2 is sent, and the report says why it is a poor value here.
        assert!(
            p.applied["alpha1"].contains("above 0.05"),
            "{:?}",
            p.applied
        );
        let low = Nav2Params::parse("amcl:\n  ros__parameters:\n    alpha1: 0.01\n").unwrap();
        assert_eq!(low.applied["alpha1"], "SetParameters α1 0.01");
    }

    #[test]
    fn only_a_regular_file_of_at_most_1_mib_is_read() {
        // A device would be read for ever; it is refused before it is opened.
        assert!(matches!(
            Nav2Params::read(std::path::Path::new("/dev/zero")),
            Err(ParamsError::NotAFile(_))
        ));
        let dir = std::env::temp_dir().join(format!("bf-params-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.yaml");
        let f = std::fs::File::create(&big).unwrap();
        f.set_len(MAX_PARAMS_FILE_BYTES + 1).unwrap();
        drop(f);
        let e = Nav2Params::read(&big).unwrap_err();
        assert!(
            matches!(e, ParamsError::TooLarge { bytes, limit, .. }
                if bytes == MAX_PARAMS_FILE_BYTES + 1 && limit == MAX_PARAMS_FILE_BYTES),
            "{e:?}"
        );
        let small = dir.join("nav2.yaml");
        std::fs::write(&small, NAV2).unwrap();
        assert_eq!(
            Nav2Params::read(&small).unwrap(),
            Nav2Params::parse(NAV2).unwrap()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_values_are_named() {
        let bad = "amcl:\n  ros__parameters:\n    max_particles: 0\n";
        let e = Nav2Params::parse(bad).unwrap_err();
        assert!(e.to_string().contains("max_particles"), "{e}");
        let nan = "amcl:\n  ros__parameters:\n    alpha1: .nan\n";
        assert!(Nav2Params::parse(nan)
            .unwrap_err()
            .to_string()
            .contains("alpha1"));
        assert!(matches!(
            Nav2Params::parse("controller_server: {}\n"),
            Err(ParamsError::NoAmclSection)
        ));
        assert!(matches!(
            Nav2Params::parse(":: ["),
            Err(ParamsError::Yaml(_))
        ));
    }
}
