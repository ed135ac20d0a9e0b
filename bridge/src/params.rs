//! nav2's amcl parameters, read from a nav2 params file: every section that applies to the
//! bridge's node as ROS 2 matches them (`amcl:`, `/amcl:`, a namespace nested or in the key,
//! the wildcards `/*` and `/**`), merged in file order. Each nav2_amcl parameter is applied,
//! adapted, or named with the reason it is not; an unknown one is named as unknown
//! (docs/nav2.md has the whole table).

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
    /// Applied as nav2_amcl applies them: `name → what it became`.
    pub applied: BTreeMap<String, String>,
    /// Applied in another form than nav2_amcl's: `name → what it became and how it differs`.
    pub adapted: BTreeMap<String, String>,
    /// Not applied: `name → why` (a nav2_amcl parameter without a counterpart, or an unknown
    /// name).
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
    /// No `ros__parameters:` section applies to the node (its fully qualified name); the
    /// sections the file has, by their node names.
    NoAmclSection {
        node: String,
        sections: Vec<String>,
    },
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
            Self::NoAmclSection { node, sections } => {
                write!(
                    f,
                    "no `ros__parameters:` section applies to the node {node} (the bridge reads \
                     nav2_amcl's parameters)"
                )?;
                if sections.is_empty() {
                    f.write_str("; the file has no sections")
                } else {
                    write!(f, "; the file has sections for {}", sections.join(", "))?;
                    if sections.iter().any(|s| s.ends_with("/amcl")) {
                        f.write_str(" (for a section /NS/amcl, run with --namespace NS)")?;
                    }
                    Ok(())
                }
            }
            Self::Value { name, why } => write!(f, "parameter {name}: {why}"),
        }
    }
}

impl std::error::Error for ParamsError {}

/// The fully qualified name of the bridge's node in namespace `/`: nav2_amcl's.
pub const NODE: &str = "/amcl";

/// Why each nav2_amcl parameter without a counterpart is not applied. The names are those
/// nav2_amcl declares (`AmclNode::initParameters` on navigation2's main branch, and
/// `random_seed`, `initialize_at_saved_pose`, `saved_pose_filepath` added after it), those its
/// base class `nav2::LifecycleNode`, its `declare_or_get_parameter` and its service servers
/// declare, and rclcpp's `use_sim_time` (docs/nav2.md, "nav2_amcl's parameters").
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
        "random_seed" => "the device's particle filter is seeded in the firmware (RobotConfig), not over the link",
        "scan_topic" => "the LiDAR is wired to the device: there is no scan topic",
        "map_topic" | "first_map_only" | "freespace_downsampling" => "the map is in the device's flash (beamfield field build)",
        "save_pose_rate" | "initialize_at_saved_pose" | "saved_pose_filepath" => {
            "the device keeps its last estimate itself (Sink::save) and starts from it: nothing is saved on the computer"
        }
        "always_reset_initial_pose" => "the device starts from its saved estimate or the initial pose sent",
        "initial_pose.z" => "the device is planar: z is not used (nav2_amcl's filter does not use it either)",
        "bond_heartbeat_period" | "bond_disable_heartbeat_timeout" => "no bond with nav2's lifecycle manager",
        "autostart_node" => "--lifecycle or not decides whether the node starts unconfigured or active",
        "introspection_mode" => "no service introspection: the bridge's services publish no service events",
        "warn_on_missing_params" | "strict_param_loading" => {
            "a parameter missing from the file keeps its default (the device's or nav2_amcl's): nothing is warned about or refused"
        }
        _ => return None,
    })
}

/// Every nav2_amcl parameter the bridge knows by name: applied, adapted or not supported.
pub fn is_known(name: &str) -> bool {
    not_supported(name).is_some()
        || matches!(
            name,
            "alpha1"
                | "alpha2"
                | "alpha3"
                | "alpha4"
                | "base_frame_id"
                | "global_frame_id"
                | "odom_frame_id"
                | "transform_tolerance"
                | "tf_broadcast"
                | "max_particles"
                | "set_initial_pose"
                | "initial_pose.x"
                | "initial_pose.y"
                | "initial_pose.yaw"
                | "use_sim_time"
        )
}

/// Whether a params file's node name (`/amcl`, `/**`, `/*/amcl`, `/robot1/amcl`, …) applies to
/// the node `fqn`: segment by segment, `*` is any one segment and `**` any number of them, as
/// rclcpp matches the names in a params file.
pub fn node_matches(pattern: &str, fqn: &str) -> bool {
    fn go(p: &[&str], n: &[&str]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some((&"**", rest)) => (0..=n.len()).any(|k| go(rest, &n[k..])),
            Some((&"*", rest)) => !n.is_empty() && go(rest, &n[1..]),
            Some((seg, rest)) => n.first() == Some(seg) && go(rest, &n[1..]),
        }
    }
    let p: Vec<&str> = pattern.split('/').filter(|x| !x.is_empty()).collect();
    let n: Vec<&str> = fqn.split('/').filter(|x| !x.is_empty()).collect();
    go(&p, &n)
}

/// The sections of a params file: `(node name, its ros__parameters mapping)` in file order. A
/// node name joins the keys leading to `ros__parameters` with `/`, with one leading `/`
/// (`robot1: amcl:` and `robot1/amcl:` are both `/robot1/amcl`).
fn sections(doc: &Value) -> Vec<(String, &serde_yaml::Mapping)> {
    fn walk<'a>(
        v: &'a Value,
        path: &mut Vec<String>,
        out: &mut Vec<(String, &'a serde_yaml::Mapping)>,
        depth: usize,
    ) {
        // A params file nests a few namespace levels; a deeper document is not walked further.
        const MAX_DEPTH: usize = 32;
        let Some(m) = v.as_mapping() else { return };
        if depth > MAX_DEPTH {
            return;
        }
        for (k, v) in m {
            let Some(k) = k.as_str() else { continue };
            if k == "ros__parameters" {
                if let Some(params) = v.as_mapping() {
                    let segs: Vec<&str> = path
                        .iter()
                        .flat_map(|p| p.split('/'))
                        .filter(|s| !s.is_empty())
                        .collect();
                    out.push((format!("/{}", segs.join("/")), params));
                }
                continue;
            }
            path.push(k.to_owned());
            walk(v, path, out, depth + 1);
            path.pop();
        }
    }
    let mut out = Vec::new();
    walk(doc, &mut Vec::new(), &mut out, 0);
    out
}

/// A section's parameters by their ROS names: a nested mapping is a dotted name
/// (`initial_pose: {x: 1}` is `initial_pose.x`), as ROS 2 reads a params file.
fn flatten(prefix: &str, m: &serde_yaml::Mapping, out: &mut BTreeMap<String, Value>, depth: usize) {
    const MAX_DEPTH: usize = 32;
    for (k, v) in m {
        let key = match k {
            Value::String(s) => s.clone(),
            Value::Number(n) => n.to_string(),
            Value::Bool(b) => b.to_string(),
            _ => continue,
        };
        let name = if prefix.is_empty() {
            key
        } else {
            format!("{prefix}.{key}")
        };
        match v.as_mapping() {
            Some(inner) if depth < MAX_DEPTH => flatten(&name, inner, out, depth + 1),
            Some(_) => {}
            None => {
                out.insert(name, v.clone());
            }
        }
    }
}

/// nav2's `alpha1..4` above this are sent with a warning in the report: with the device's sensor
/// model at its defaults (κ 64) α 0.2 (nav2's default) tracks a robot whose updates come at
/// 10 Hz, but the noise grows with the step between updates, and with steps of about 0.7 m
/// (updates gated by distance, or a slow scan rate) the robot is lost (docs/nav2.md, the
/// parameter table).
pub const ALPHA_WARN: f64 = 0.05;

fn number(name: &str, v: &Value) -> Result<f64, ParamsError> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| ParamsError::Value {
            name: name.into(),
            why: format!("{v:?} is not a finite number"),
        })
}

fn boolean(name: &str, v: &Value) -> Result<bool, ParamsError> {
    v.as_bool().ok_or_else(|| ParamsError::Value {
        name: name.into(),
        why: format!("{v:?} is not a boolean"),
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
        Self::read_for(path, NODE)
    }

    /// [`Nav2Params::read`] for the node whose fully qualified name is `node`
    /// ([`Nav2Params::parse_for`]).
    pub fn read_for(path: &std::path::Path, node: &str) -> Result<Self, ParamsError> {
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
        Self::parse_for(&text, node)
    }

    /// Parses a nav2 params file's text for the node [`NODE`] (`/amcl`).
    pub fn parse(yaml: &str) -> Result<Self, ParamsError> {
        Self::parse_for(yaml, NODE)
    }

    /// Parses a nav2 params file's text for the node whose fully qualified name is `node`
    /// (`/amcl`, `/robot1/amcl`): the parameters of every section that applies to it
    /// ([`node_matches`]), a later section's value replacing an earlier one's.
    pub fn parse_for(yaml: &str, node: &str) -> Result<Self, ParamsError> {
        let doc: Value = serde_yaml::from_str(yaml).map_err(ParamsError::Yaml)?;
        let all = sections(&doc);
        let mut params = BTreeMap::new();
        let mut any = false;
        for (pattern, m) in &all {
            if node_matches(pattern, node) {
                any = true;
                flatten("", m, &mut params, 0);
            }
        }
        if !any {
            return Err(ParamsError::NoAmclSection {
                node: node.to_owned(),
                sections: all.into_iter().map(|(p, _)| p).collect(),
            });
        }
        let mut out = Self::default();
        let mut sp = SetParameters::default();
        let mut any_sp = false;
        let mut set_initial = false;
        let mut initial = [0.0f64; 3];
        // nav2_amcl (Jazzy) strips one leading slash from its frame ids.
        let frame = |name: &str, v: &Value| -> Result<String, ParamsError> {
            let t = text(name, v)?;
            Ok(t.strip_prefix('/').unwrap_or(&t).to_owned())
        };
        for (name, v) in &params {
            let name = name.as_str();
            let mut applied = |what: String| {
                out.applied.insert(name.to_owned(), what);
            };
            match name {
                "global_frame_id" => {
                    let f = frame(name, v)?;
                    applied(f.clone());
                    out.frames.global = f;
                }
                "odom_frame_id" => {
                    let f = frame(name, v)?;
                    applied(f.clone());
                    out.frames.odom = f;
                }
                "transform_tolerance" => {
                    let s = number(name, v)?;
                    if s < 0.0 {
                        return Err(ParamsError::Value {
                            name: name.into(),
                            why: "negative".into(),
                        });
                    }
                    applied(format!("{s} s"));
                    out.frames.transform_tolerance_s = s;
                }
                "tf_broadcast" => {
                    let b = boolean(name, v)?;
                    applied(b.to_string());
                    out.frames.tf_broadcast = b;
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
                    // model; with the device's sharper one they hold only for short steps
                    // between updates (docs/nav2.md, the parameter table).
                    let note = if a > ALPHA_WARN {
                        format!(
                            " (above {ALPHA_WARN}: with the device's sensor model (σ_hit 5 cm) \
                             the robot is lost when updates are far apart (0.7 m), docs/nav2.md)"
                        )
                    } else {
                        String::new()
                    };
                    applied(format!("SetParameters α{} {a}{note}", i + 1));
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
                    out.adapted.insert(
                        name.to_owned(),
                        format!(
                            "SetParameters particles {n}: the device keeps this many at all \
                             times (nav2_amcl's KLD sampling varies the count up to it)"
                        ),
                    );
                }
                "set_initial_pose" => {
                    set_initial = boolean(name, v)?;
                    out.adapted.insert(
                        name.to_owned(),
                        format!(
                            "{set_initial}: sent to the device once at start (nav2_amcl: on \
                             each activation)"
                        ),
                    );
                }
                "initial_pose.x" | "initial_pose.y" | "initial_pose.yaw" => {
                    let i = match name {
                        "initial_pose.x" => 0,
                        "initial_pose.y" => 1,
                        _ => 2,
                    };
                    initial[i] = number(name, v)?;
                    let unit = if i == 2 { "rad" } else { "m" };
                    out.adapted.insert(
                        name.to_owned(),
                        format!(
                            "{} {unit}, with set_initial_pose: sent with a spread of 0.5 m and \
                             π/12 (nav2_amcl: zero, which the device would widen to its minimum)",
                            initial[i]
                        ),
                    );
                }
                "base_frame_id" => {
                    out.frames.base = frame(name, v)?;
                    out.ignored.insert(
                        name.to_owned(),
                        format!(
                            "{}: the device's poses are of its own base, whatever its name",
                            out.frames.base
                        ),
                    );
                }
                "use_sim_time" => {
                    out.ignored.insert(
                        name.to_owned(),
                        "the bridge's stamps follow --clock: use --clock device for replays".into(),
                    );
                }
                other => {
                    let why = not_supported(other)
                        .unwrap_or("unknown: not a nav2_amcl parameter the bridge knows");
                    out.ignored.insert(other.to_owned(), why.to_owned());
                }
            }
        }
        if any_sp {
            out.set_parameters = Some(sp);
        }
        if set_initial {
            let [x, y, yaw] = initial;
            let yaw = yaw.sin().atan2(yaw.cos());
            // RViz's "2D Pose Estimate" spread: 0.5 m standard deviation, (π/12)² in yaw.
            let mut c = [[0.0f32; 3]; 3];
            c[0][0] = 0.25;
            c[1][1] = 0.25;
            c[2][2] = (core::f32::consts::PI / 12.0).powi(2);
            out.initial_pose = Some(SetInitialPose {
                timestamp_us: 0,
                pose: Pose::new(x as f32, y as f32, yaw as f32),
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
        assert!(p.adapted.contains_key("max_particles"));
        // 19 keys, initial_pose counting as its 4 parameters x, y, z, yaw.
        assert_eq!(p.applied.len() + p.adapted.len() + p.ignored.len(), 23);
        assert!(p.ignored["initial_pose.z"].contains("planar"));
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
            Nav2Params::parse("controller_server: {ros__parameters: {a: 1}}\n"),
            Err(ParamsError::NoAmclSection { .. })
        ));
        assert!(matches!(
            Nav2Params::parse("amcl: {}\n"),
            Err(ParamsError::NoAmclSection { .. })
        ));
        let not_bool = "amcl:\n  ros__parameters:\n    tf_broadcast: 3\n";
        assert!(Nav2Params::parse(not_bool)
            .unwrap_err()
            .to_string()
            .contains("tf_broadcast"));
        assert!(matches!(
            Nav2Params::parse(":: ["),
            Err(ParamsError::Yaml(_))
        ));
    }

    /// The transform tolerance a file gives the node `node` (each form below sets a different
    /// one), or the error.
    fn tolerance(yaml: &str, node: &str) -> Result<f64, ParamsError> {
        Nav2Params::parse_for(yaml, node).map(|p| p.frames.transform_tolerance_s)
    }

    #[test]
    fn the_node_name_with_a_leading_slash_is_read() {
        let y = "/amcl:\n  ros__parameters:\n    transform_tolerance: 0.25\n";
        assert_eq!(tolerance(y, NODE).unwrap(), 0.25);
        assert_eq!(
            Nav2Params::parse(y).unwrap().frames.transform_tolerance_s,
            0.25
        );
    }

    #[test]
    fn a_namespaced_file_is_read_for_the_node_in_that_namespace() {
        let nested = "robot1:\n  amcl:\n    ros__parameters:\n      transform_tolerance: 0.3\n";
        let joined = "robot1/amcl:\n  ros__parameters:\n    transform_tolerance: 0.3\n";
        let absolute = "/robot1/amcl:\n  ros__parameters:\n    transform_tolerance: 0.3\n";
        for y in [nested, joined, absolute] {
            assert_eq!(tolerance(y, "/robot1/amcl").unwrap(), 0.3, "{y}");
            // Not the node of another namespace, nor the one at the root.
            for other in [NODE, "/robot2/amcl", "/robot1/x/amcl"] {
                let e = tolerance(y, other).unwrap_err();
                assert!(
                    matches!(&e, ParamsError::NoAmclSection { sections, .. }
                        if sections == &["/robot1/amcl".to_owned()]),
                    "{other}: {e:?}"
                );
                assert!(e.to_string().contains("--namespace"), "{e}");
            }
        }
    }

    #[test]
    fn wildcards_match_as_rclcpp_matches_them() {
        let all = "/**:\n  ros__parameters:\n    transform_tolerance: 0.4\n";
        let any_ns = "/**/amcl:\n  ros__parameters:\n    transform_tolerance: 0.4\n";
        let one_ns = "/*/amcl:\n  ros__parameters:\n    transform_tolerance: 0.4\n";
        for node in [NODE, "/robot1/amcl", "/a/b/amcl"] {
            assert_eq!(tolerance(all, node).unwrap(), 0.4, "{node}");
            assert_eq!(tolerance(any_ns, node).unwrap(), 0.4, "{node}");
        }
        assert!(tolerance(any_ns, "/robot1/amcl_x").is_err());
        // `*` is exactly one namespace level.
        assert_eq!(tolerance(one_ns, "/robot1/amcl").unwrap(), 0.4);
        assert!(tolerance(one_ns, NODE).is_err());
        assert!(tolerance(one_ns, "/a/b/amcl").is_err());
        let pairs = [
            ("/**", "/amcl", true),
            ("/**", "/", true),
            ("/*", "/amcl", true),
            ("/*", "/r/amcl", false),
            ("/**/amcl", "/amcl", true),
            ("/r/**/amcl", "/r/amcl", true),
            ("/r/**/amcl", "/r/s/t/amcl", true),
            ("/r/**/amcl", "/s/amcl", false),
            ("/amcl", "/amcl", true),
            ("/amcl", "/amcl2", false),
            ("/amcl/**", "/amcl", true),
        ];
        for (pattern, node, want) in pairs {
            assert_eq!(node_matches(pattern, node), want, "{pattern} {node}");
        }
    }

    #[test]
    fn matching_sections_merge_in_file_order() {
        let wildcard_first = "\
/**:
  ros__parameters:
    use_sim_time: true
    transform_tolerance: 0.3
    initial_pose: {x: 1.0, y: 2.0}
amcl:
  ros__parameters:
    transform_tolerance: 0.5
    initial_pose: {y: 7.0}
    set_initial_pose: true
bt_navigator:
  ros__parameters:
    transform_tolerance: 9.0
";
        let p = Nav2Params::parse(wildcard_first).unwrap();
        assert_eq!(p.frames.transform_tolerance_s, 0.5);
        assert!(p.ignored.contains_key("use_sim_time"));
        let ip = p.initial_pose.unwrap();
        // x from the wildcard, y from amcl's section.
        assert_eq!((ip.pose.x_m, ip.pose.y_m), (1.0, 7.0));
        let amcl_first = "\
amcl:
  ros__parameters:
    transform_tolerance: 0.5
/**:
  ros__parameters:
    transform_tolerance: 0.3
";
        assert_eq!(tolerance(amcl_first, NODE).unwrap(), 0.3);
    }

    /// nav2_amcl's parameters as declared on navigation2's main branch (`initParameters`),
    /// those added after it (`random_seed`, pose persistence), its base class's and
    /// rclcpp's: facts from the sources named in docs/nav2.md.
    const NAV2_AMCL_PARAMETERS: [&str; 56] = [
        "alpha1",
        "alpha2",
        "alpha3",
        "alpha4",
        "alpha5",
        "base_frame_id",
        "beam_skip_distance",
        "beam_skip_error_threshold",
        "beam_skip_threshold",
        "do_beamskip",
        "global_frame_id",
        "lambda_short",
        "laser_likelihood_max_dist",
        "laser_max_range",
        "laser_min_range",
        "laser_model_type",
        "set_initial_pose",
        "initial_pose.x",
        "initial_pose.y",
        "initial_pose.z",
        "initial_pose.yaw",
        "max_beams",
        "max_particles",
        "min_particles",
        "odom_frame_id",
        "pf_err",
        "pf_z",
        "recovery_alpha_fast",
        "recovery_alpha_slow",
        "resample_interval",
        "robot_model_type",
        "save_pose_rate",
        "sigma_hit",
        "tf_broadcast",
        "transform_tolerance",
        "update_min_a",
        "update_min_d",
        "z_hit",
        "z_max",
        "z_rand",
        "z_short",
        "first_map_only",
        "always_reset_initial_pose",
        "scan_topic",
        "map_topic",
        "freespace_downsampling",
        "random_seed",
        "initialize_at_saved_pose",
        "saved_pose_filepath",
        "bond_heartbeat_period",
        "bond_disable_heartbeat_timeout",
        "autostart_node",
        "introspection_mode",
        "warn_on_missing_params",
        "strict_param_loading",
        "use_sim_time",
    ];

    /// A value of the type nav2_amcl declares for `name`, in range.
    fn value_for(name: &str) -> &'static str {
        match name {
            "base_frame_id"
            | "global_frame_id"
            | "odom_frame_id"
            | "laser_model_type"
            | "robot_model_type"
            | "scan_topic"
            | "map_topic"
            | "saved_pose_filepath" => "x",
            "do_beamskip"
            | "set_initial_pose"
            | "tf_broadcast"
            | "first_map_only"
            | "always_reset_initial_pose"
            | "freespace_downsampling"
            | "initialize_at_saved_pose"
            | "bond_disable_heartbeat_timeout"
            | "autostart_node"
            | "warn_on_missing_params"
            | "strict_param_loading"
            | "use_sim_time" => "true",
            "introspection_mode" => "disabled",
            "max_particles" | "min_particles" | "max_beams" | "resample_interval"
            | "random_seed" => "42",
            _ => "0.5",
        }
    }

    #[test]
    fn every_nav2_amcl_parameter_is_known_by_name() {
        let mut yaml = String::from("amcl:\n  ros__parameters:\n");
        for name in NAV2_AMCL_PARAMETERS {
            // A dotted name is a nested key in a params file.
            match name.split_once('.') {
                Some((outer, inner)) => {
                    yaml += &format!("    {outer}:\n      {inner}: {}\n", value_for(name))
                }
                None => yaml += &format!("    {name}: {}\n", value_for(name)),
            }
        }
        // initial_pose's four keys must be one mapping: merge them.
        let yaml = yaml
            .replace("    initial_pose:\n      y:", "      y:")
            .replace("    initial_pose:\n      z:", "      z:")
            .replace("    initial_pose:\n      yaw:", "      yaw:");
        let p = Nav2Params::parse(&yaml).unwrap_or_else(|e| panic!("{e}\n{yaml}"));
        for name in NAV2_AMCL_PARAMETERS {
            assert!(is_known(name), "{name}");
            let said = p
                .applied
                .get(name)
                .or(p.adapted.get(name))
                .or(p.ignored.get(name))
                .unwrap_or_else(|| panic!("{name} is not in the report"));
            assert!(!said.contains("unknown"), "{name}: {said}");
        }
        assert_eq!(
            p.applied.len() + p.adapted.len() + p.ignored.len(),
            56,
            "{p:#?}"
        );
        // A name nav2_amcl does not have.
        let made_up = Nav2Params::parse("amcl:\n  ros__parameters:\n    alpha6: 1.0\n").unwrap();
        assert!(made_up.ignored["alpha6"].contains("unknown"));
        assert!(!is_known("alpha6"));
    }
}
