//! The base controller's localization loop: the LiDAR's bytes and the computer's link bytes in,
//! estimates, heartbeats and typed errors out. `no_std`, no allocation, no panic on any input;
//! the firmware program `firmware/src/bin/robot.rs` runs it behind three USARTs and
//! `cargo xtask robot` replays the same bytes through it on the host, bit for bit
//! (`docs/robot.md`).
//!
//! [`Robot::poll`] does a bounded amount of work per call and pulls bytes from two
//! [`ByteSource`]s:
//!
//! 1. **Link** (odometry and commands, the protocol of [`crate::link`]): frames are decoded as
//!    long as the odometry window ([`window::WINDOW`] samples) and the command queue
//!    ([`COMMANDS`]) have room — a sender that runs ahead of the LiDAR is held back. While the
//!    LiDAR is silent ([`Robot::tick`] or [`Robot::set_lidar_silent`], from the device's timer)
//!    the link is read all the same, so that it never backs up: the
//!    oldest odometry is dropped to make room (counted in [`RobotCounters::odometry_dropped`]
//!    and the heartbeats' drops) and a command that finds the queue full is refused.
//!    Odometry ([`link::WheelOdometry`], or [`link::WheelTicks`] through the crate's
//!    [`DiffDrive`] model) must come with strictly increasing timestamps, at most
//!    [`RobotConfig::max_odometry_lead_us`] ahead of the device clock, and steps a robot can
//!    make ([`RobotConfig::max_speed_m_per_s`], [`RobotConfig::max_turn_rad_per_s`]); anything
//!    else is refused with an [`link::ErrorReport`] and leaves the state unchanged — except a
//!    step no robot makes after a silence of [`RobotConfig::odometry_restart_gap_us`], which is
//!    a restart of the odometry: a new odometry frame, no motion applied across it, the
//!    estimates across it flagged [`EstimateFlags::ODOMETRY_STALE`]. A timestamp of 0 means
//!    "on arrival": the device clock when the frame is decoded. Commands are
//!    checked when they arrive (and refused then: a `SetInitialPose` whose covariance spreads
//!    wider than [`RobotConfig::max_init_sigma_xy_m`] too) and carried out at their place in the
//!    stream: before the first revolution that ends after the last odometry sample received
//!    before them.
//! 2. **LiDAR** (LD06 frames): decoded and assembled into revolutions on the layout. The
//!    revolution's time is the middle of its first and last frames' timestamps, on the sensor's
//!    clock unwrapped into µs ([`ScanClock`], advanced at every frame; a frame whose stamp
//!    jumps further than [`clock::MAX_STEP_MS`] is held until the next frame confirms the jump,
//!    and its points are dropped — a single wrong stamp never moves the clock). **The sensor's
//!    clock is the device's clock**: odometry timestamps must be on it (a sender learns it from
//!    the heartbeats' timestamps).
//! 3. **Update**: a revolution is processed once the odometry reaches its time (the pose is
//!    interpolated there, [`OdometryWindow::at`]) — or, when the next revolution is complete
//!    first, with the odometry it has, flagged [`EstimateFlags::ODOMETRY_STALE`] and counted as
//!    late. The filter predicts with the odometry step since the last update and updates with the
//!    tempered likelihood field; an [`link::Estimate`] goes out for every update that succeeded,
//!    stamped with the revolution's time, so a pose is never sent twice or late under a new time.
//! 4. **Time**: the device hands [`Robot::tick`] its own monotonic clock (a timer, not the
//!    LiDAR). A heartbeat goes out every [`RobotConfig::heartbeat_period_us`] of it, whatever
//!    the LiDAR sends, and once no valid LiDAR frame has come for
//!    [`RobotConfig::lidar_silence_us`] (noise, a wrong baud rate, a silent line) the LiDAR is
//!    taken as silent and the link is read whatever the odometry window holds.
//!
//! Nothing depends on how the bytes are split between calls, as long as the odometry that
//! reaches a revolution's time arrives before the next revolution is complete, is stamped
//! (not 0, "on arrival") and the LiDAR is not declared silent: the device's estimates and
//! error reports are then a function of the two byte streams alone, which is what lets the
//! host recompute them. The heartbeats are not: they follow the device's clock.

pub mod clock;
mod io;
#[cfg(test)]
mod tests;
pub mod window;

pub use clock::ScanClock;
pub use io::{ByteSource, Seed, Sink, SliceSource};
pub use window::{OdometryWindow, Sample};

use crate::field::{FieldView, FreeSpace, LikelihoodField, LikelihoodParams};
use crate::lidar::ld06::{Ld06Decoder, TIMESTAMP_WRAP_MS};
use crate::lidar::{AssemblerConfig, AssemblerStats, DecoderStats, Deskewer, ScanAssembler, Sweep};
use crate::link::{
    self, ErrorCode, ErrorReport, EstimateFlags, Frame, Heartbeat, LinkError, LinkStats, Message,
    MessageType, Quality, SetParameters, MAX_WIRE_LEN,
};
use crate::math;
use crate::mcl::odometry::{DiffDrive, DiffDriveGeometry};
use crate::mcl::{Mcl, MclConfig, OdometryNoise, OdometryStep, Particles, SplitMix64};
use crate::pose::{wrap_angle, Pose};
use crate::scan::{BeamLayout, Scan};
use crate::tempered::Tempered;
use crate::Error;
use heapless::Deque;

/// Commands queued until their place in the stream is reached.
pub const COMMANDS: usize = 8;

/// The largest standard deviation of heading a cloud is drawn with, rad (a wider one is clamped
/// to it: at 2π the heading is as good as uniform, and a wider one would be drawn at angles too
/// large to wrap exactly in `f32`).
pub const MAX_INIT_SIGMA_THETA_RAD: f32 = core::f32::consts::TAU;

/// What the application is set up with. Units: metres, radians, seconds, microseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RobotConfig {
    /// Particles in use (at most the storage's capacity `N`).
    pub particles: usize,
    /// Likelihood field: weight of the Gaussian hit component.
    pub z_hit: f32,
    /// Likelihood field: weight of the uniform random component.
    pub z_rand: f32,
    /// Likelihood field: standard deviation of a hit, m.
    pub sigma_hit_m: f32,
    /// The sensor's largest range, m (readings at or beyond it are not scored).
    pub max_range_m: f32,
    /// Tempering κ: the summed log-likelihood of a scan is divided by it.
    pub kappa: f32,
    /// The motion model's odometry noise (AMCL's α1 … α4).
    pub odom_noise: OdometryNoise,
    /// Resample when the effective sample size falls below this fraction of the particles.
    pub resample_ess_fraction: f32,
    /// The smallest standard deviation used when the cloud is drawn around a pose, m and rad
    /// (an `initialpose` with a smaller covariance is widened to it).
    pub min_init_sigma_xy_m: f32,
    /// See [`RobotConfig::min_init_sigma_xy_m`], rad.
    pub min_init_sigma_theta_rad: f32,
    /// The largest standard deviation in position an initial pose (or a seed) may carry, m: a
    /// `SetInitialPose` whose covariance gives a wider one (`√((c_xx + c_yy) / 2)`, not finite
    /// included) is refused with an [`link::ErrorReport`] of [`ErrorCode::Refused`] and changes
    /// nothing. The heading's standard deviation is clamped to [`MAX_INIT_SIGMA_THETA_RAD`].
    pub max_init_sigma_xy_m: f32,
    /// Wheel geometry for [`link::WheelTicks`]; without it tick messages are refused.
    pub wheels: Option<DiffDriveGeometry>,
    /// Odometry faster than this between two samples is refused, m/s.
    pub max_speed_m_per_s: f32,
    /// Odometry turning faster than this between two samples is refused, rad/s.
    pub max_turn_rad_per_s: f32,
    /// Interpolating across a longer gap between two odometry samples flags the estimate
    /// [`EstimateFlags::ODOMETRY_STALE`], µs.
    pub max_odometry_gap_us: u64,
    /// An odometry sample stamped further than this ahead of the device clock (before the clock
    /// has started: of the newest sample) is refused ([`ErrorCode::ValueOutOfRange`] at the
    /// timestamp's offset), µs.
    pub max_odometry_lead_us: u64,
    /// After a silence of the odometry at least this long, a sample that no robot could have
    /// reached within the speed limits is taken as a restart of the odometry (a new odometry
    /// frame, counted in [`RobotCounters::odometry_restarts`]): no motion is applied across it
    /// and the next estimate is flagged [`EstimateFlags::ODOMETRY_STALE`]. Within shorter
    /// gaps such a sample is refused, µs.
    pub odometry_restart_gap_us: u64,
    /// Skip the update until the odometry has moved this far since the last one (AMCL's
    /// `update_min_d`), m; 0 updates at every revolution.
    pub update_min_d_m: f32,
    /// See [`RobotConfig::update_min_d_m`]: AMCL's `update_min_a`, rad.
    pub update_min_a_rad: f32,
    /// A heartbeat whenever this much time has passed since the last one on the board's own
    /// monotonic clock (the time handed to [`Robot::tick`], not the LiDAR's), µs: heartbeats
    /// go out whatever the LiDAR sends (good data, noise, nothing). 0: none from
    /// [`Robot::tick`].
    pub heartbeat_period_us: u64,
    /// The LiDAR is taken as silent once no valid LiDAR frame has come for this long
    /// on the board's clock (the time handed to [`Robot::tick`]), µs: noise and silence alike.
    /// While it is, the link is read whatever the odometry window holds
    /// ([`Robot::set_lidar_silent`]). 0: [`Robot::tick`] leaves it to the caller.
    pub lidar_silence_us: u64,
    /// Seed of the filter's random generator.
    pub seed: u64,
    /// De-skew every revolution for the motion during it before the update
    /// ([`crate::lidar::deskew`]; docs/robot.md, "De-skew"): each beam's endpoint is moved into
    /// the robot frame at the revolution's time, with the odometry interpolated at the
    /// revolution's first and last stamps. A revolution is then processed once the odometry
    /// reaches its last stamp (not only its middle). Off by default.
    pub deskew: bool,
}

impl RobotConfig {
    /// The defaults of a small indoor robot with an LD06: 500 particles, the likelihood field of
    /// the Intel lab demo (z_hit 0.95, z_rand 0.05, σ_hit 5 cm) tempered by κ 64 (chosen for a
    /// filter that applies every scan: docs/localization.md, "Tempering over time"), odometry
    /// noise α 0.02 (variance coefficients, AMCL's convention),
    /// resampling below half the particles, at most 2 m/s and 4 rad/s, 100 ms gaps, initial
    /// poses up to σ 100 m, odometry up to 10 s ahead of the device clock, a restart of the
    /// odometry recognised after 1 s of silence, an update at every revolution, a heartbeat
    /// every second of the board's clock and the LiDAR taken as silent after 1 s without a
    /// valid frame.
    ///
    /// # Errors
    /// [`Error::Motion`] if `max_range_m` is not finite (it checks nothing else: the checks are
    /// in [`Robot::new`]).
    pub fn new(max_range_m: f32) -> Result<Self, Error> {
        Ok(Self {
            particles: 500,
            z_hit: 0.95,
            z_rand: 0.05,
            sigma_hit_m: 0.05,
            max_range_m,
            kappa: 64.0,
            odom_noise: OdometryNoise::uniform(0.02)?,
            resample_ess_fraction: 0.5,
            min_init_sigma_xy_m: 0.01,
            min_init_sigma_theta_rad: 0.005,
            max_init_sigma_xy_m: 100.0,
            wheels: None,
            max_speed_m_per_s: 2.0,
            max_turn_rad_per_s: 4.0,
            max_odometry_gap_us: 100_000,
            max_odometry_lead_us: 10_000_000,
            odometry_restart_gap_us: 1_000_000,
            update_min_d_m: 0.0,
            update_min_a_rad: 0.0,
            heartbeat_period_us: 1_000_000,
            lidar_silence_us: 1_000_000,
            seed: 1,
            deskew: false,
        })
    }
}

/// What the application counted since it started (all wrap at 2³²).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RobotCounters {
    /// Revolutions assembled.
    pub revolutions: u32,
    /// Filter updates that succeeded (one estimate each).
    pub updates: u32,
    /// Revolutions not used for an update: filter not initialized, too little motion, no
    /// valid beam, every particle impossible.
    pub skipped: u32,
    /// Revolutions processed before the odometry reached their time.
    pub late_odometry: u32,
    /// Estimates flagged [`EstimateFlags::ODOMETRY_STALE`] (late, gap, or no odometry).
    pub stale_odometry: u32,
    /// Odometry messages accepted.
    pub odometry: u32,
    /// Commands carried out.
    pub commands: u32,
    /// Frames refused after their CRC passed (an error report went out for each).
    pub refused: u32,
    /// Bytes or messages dropped outside the application (a full receive ring), as reported by
    /// [`Robot::add_drops`].
    pub drops: u32,
    /// Frames sent.
    pub frames_sent: u32,
    /// Estimates or heartbeats that could not be encoded (never sent).
    pub encode_failures: u32,
    /// Revolutions de-skewed before their update ([`RobotConfig::deskew`]).
    pub deskewed: u32,
    /// Revolutions updated without de-skew although it is on: no timestamps, no odometry at
    /// the revolution's start or end (or only a stale one), or a pose that is not finite.
    pub deskew_skipped: u32,
    /// Odometry samples dropped, oldest first, to keep reading the link while the LiDAR is
    /// silent (the window full, no revolution to use them), or dropped because they lay
    /// further ahead of the device clock than [`RobotConfig::max_odometry_lead_us`].
    pub odometry_dropped: u32,
    /// Odometry restarts: a sample after a silence of at least
    /// [`RobotConfig::odometry_restart_gap_us`] that no robot could have reached from the last
    /// one, taken as the start of a new odometry frame rather than as motion.
    pub odometry_restarts: u32,
}

/// The stages of [`Robot::poll_probed`], for a caller that measures them (instruction counts
/// on the device: `firmware/src/bin/robot.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Decoding link bytes (odometry and commands), from the first byte taken to the last.
    Link,
    /// Decoding and assembling LiDAR bytes, from the first byte taken to the last.
    Lidar,
    /// The motion model's sample of every particle.
    Predict,
    /// De-skewing the scan when [`RobotConfig::deskew`] is on, preparing it and updating the
    /// filter (scoring, weights, estimate, resampling).
    Update,
    /// Encoding a frame and handing it to the sink.
    Send,
}

/// Told when each [`Stage`] starts and ends. Every method does nothing by default.
pub trait Probe {
    /// `stage` starts.
    fn enter(&mut self, stage: Stage) {
        let _ = stage;
    }
    /// `stage` ends.
    fn leave(&mut self, stage: Stage) {
        let _ = stage;
    }
}

/// The probe that measures nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProbe;

impl Probe for NoProbe {}

/// What one [`Robot::poll`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Progress {
    /// Link bytes taken.
    pub link_bytes: u32,
    /// LiDAR bytes taken.
    pub lidar_bytes: u32,
    /// Whether a revolution was processed.
    pub processed: bool,
}

impl Progress {
    /// Whether nothing happened (nothing to read, nothing ready).
    pub fn is_idle(&self) -> bool {
        self.link_bytes == 0 && self.lidar_bytes == 0 && !self.processed
    }
}

#[derive(Clone, Copy, Debug)]
enum Command {
    Initial(link::SetInitialPose),
    Global,
    NoMotion,
    Parameters(SetParameters),
}

#[derive(Clone, Copy, Debug)]
struct Queued {
    /// Carried out before the first revolution whose time is at or after this, µs.
    at_us: u64,
    command: Command,
}

#[derive(Clone, Debug)]
struct Revolution<const S: usize> {
    scan: Scan<S>,
    t_us: u64,
    /// The timing anchors, for de-skew: device times of the first and last stamps, µs, and the
    /// rotor positions they belong to, degrees clockwise.
    sweep: Option<SweepTimes>,
}

#[derive(Clone, Copy, Debug)]
struct SweepTimes {
    start_us: u64,
    end_us: u64,
    start_deg: f32,
    end_deg: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OdometrySource {
    Poses,
    Ticks,
}

/// The application: decoder, assembler, odometry window, filter and link in one value, for `N`
/// particles of capacity and scans of `S` beams. See the [module docs](self).
pub struct Robot<'a, const N: usize, const S: usize> {
    config: RobotConfig,
    layout: BeamLayout<S>,
    model: Tempered<LikelihoodField<'a>>,
    free: Option<FreeSpace<'a>>,
    mcl: Mcl<'a, N>,
    rng: SplitMix64,
    lidar: Ld06Decoder,
    assembler: ScanAssembler<S>,
    clock: ScanClock,
    link: link::Decoder,
    encoder: link::Encoder,
    wheels: Option<DiffDrive>,
    source: Option<OdometrySource>,
    window: OdometryWindow,
    stream_time_us: u64,
    commands: Deque<Queued, COMMANDS>,
    pending: Option<Revolution<S>>,
    next: Option<Revolution<S>>,
    /// The odometry pose of the last update (or initialization), and its frame
    /// ([`window::Interpolated::frame`]).
    last_odom: Option<(Pose, u32)>,
    initialized: bool,
    global: bool,
    force_update: bool,
    processed_us: u64,
    counters: RobotCounters,
    /// The caller says the LiDAR is silent ([`Robot::set_lidar_silent`]): the link is read
    /// whatever the window holds.
    lidar_silent: bool,
    /// The board's time at the last [`Robot::tick`], µs.
    board_us: Option<u64>,
    /// When the next heartbeat is due on the board's clock, µs.
    heartbeat_due_us: Option<u64>,
    /// Points decoded from valid LiDAR frames (wrapping).
    lidar_points: u32,
    /// The board's time at the last tick that saw a new LiDAR point (or the first), µs, and
    /// `lidar_points` then.
    lidar_seen_us: u64,
    lidar_points_seen: u32,
    /// The LD06 stamp of the last point decoded, and whether the clock took it.
    last_stamp_ms: Option<u16>,
    stamp_taken: bool,
    deskewer: Option<Deskewer>,
    deskewed: Scan<S>,
}

impl<'a, const N: usize, const S: usize> Robot<'a, N, S> {
    /// Sets up the application over the distance field `view` (and its free space, needed for
    /// global localization), the sensor's `layout` and `config`. With a `seed` (the estimate
    /// saved at the last run, [`Sink::save`]) the filter starts around it; without (or with a
    /// seed whose position lies beyond [`link::MAX_POSITION_M`] or whose covariance an initial
    /// pose could not carry), it waits for a `SetInitialPose` or `StartGlobalLocalization`.
    ///
    /// # Errors
    /// The first parameter refused: [`Error::Likelihood`], [`Error::Temper`], [`Error::Mcl`]
    /// (particles 0 or above `N`, resampling fraction), [`Error::Motion`] (wheel geometry),
    /// [`Error::Assembler`].
    pub fn new(
        store: &'a mut Particles<N>,
        view: FieldView<'a>,
        free: Option<FreeSpace<'a>>,
        layout: BeamLayout<S>,
        config: RobotConfig,
        seed: Option<Seed>,
    ) -> Result<Self, Error> {
        let params = LikelihoodParams::new(
            config.z_hit,
            config.z_rand,
            config.sigma_hit_m,
            config.max_range_m,
        )?;
        let model = Tempered::new(LikelihoodField::new(view, params), config.kappa, 1)?;
        if config.particles == 0 || config.particles > N {
            return Err(Error::Mcl(crate::mcl::MclError::TooManyParticles));
        }
        let mcl_config = MclConfig::new(config.odom_noise, config.resample_ess_fraction, 0.0, 0.0)?;
        let mcl = Mcl::new(store, mcl_config)?;
        let wheels = match config.wheels {
            Some(g) => Some(DiffDrive::new(g)?),
            None => None,
        };
        let mut assembler_config = AssemblerConfig::for_layout(&layout);
        assembler_config.max_range_m = config.max_range_m;
        let assembler = ScanAssembler::new(&layout, assembler_config)?;
        let deskewer = if config.deskew {
            Some(Deskewer::new(&layout).map_err(|e| match e {
                crate::lidar::DeskewError::Layout(a) => Error::Assembler(a),
                _ => Error::Assembler(crate::lidar::AssemblerError::NotUniform(0)),
            })?)
        } else {
            None
        };
        let mut robot = Self {
            config,
            layout,
            model,
            free,
            mcl,
            rng: SplitMix64::new(config.seed),
            lidar: Ld06Decoder::new(),
            assembler,
            clock: ScanClock::new(TIMESTAMP_WRAP_MS),
            link: link::Decoder::new(),
            encoder: link::Encoder::new(),
            wheels,
            source: None,
            window: OdometryWindow::new(),
            stream_time_us: 0,
            commands: Deque::new(),
            pending: None,
            next: None,
            last_odom: None,
            initialized: false,
            global: false,
            force_update: false,
            processed_us: 0,
            counters: RobotCounters::default(),
            lidar_silent: false,
            board_us: None,
            heartbeat_due_us: None,
            lidar_points: 0,
            lidar_seen_us: 0,
            lidar_points_seen: 0,
            last_stamp_ms: None,
            stamp_taken: true,
            deskewer,
            deskewed: Scan::default(),
        };
        if let Some(s) = seed {
            // A seed the link could carry (a corrupted store holds anything): a position within
            // link::MAX_POSITION_M, a covariance the filter can use.
            let on_map = |v: f32| v.abs() <= link::MAX_POSITION_M;
            if s.pose.is_finite()
                && on_map(s.pose.x_m)
                && on_map(s.pose.y_m)
                && robot.check_covariance(&s.covariance).is_ok()
            {
                robot.init_around(&s.pose, &s.covariance);
            }
        }
        Ok(robot)
    }

    /// Takes what is waiting on both sources, processes at most one revolution and sends what
    /// it produced to `sink`. Call it whenever bytes may have arrived; it returns at once when
    /// nothing is waiting.
    pub fn poll(
        &mut self,
        lidar: &mut impl ByteSource,
        link: &mut impl ByteSource,
        sink: &mut impl Sink,
    ) -> Progress {
        self.poll_probed(lidar, link, sink, &mut NoProbe)
    }

    /// [`Robot::poll`], telling `probe` when each [`Stage`] starts and ends.
    pub fn poll_probed(
        &mut self,
        lidar: &mut impl ByteSource,
        link: &mut impl ByteSource,
        sink: &mut impl Sink,
        probe: &mut impl Probe,
    ) -> Progress {
        let mut progress = Progress::default();
        // While the LiDAR is silent, no revolution takes odometry out of the window or commands
        // out of the queue: the link is read all the same (the oldest odometry dropped, further
        // commands refused), so that it never backs up into the receive ring.
        let silent = self.lidar_silent;
        while silent || (self.window.has_room() && !self.commands.is_full()) {
            let Some(b) = link.next_byte() else { break };
            if progress.link_bytes == 0 {
                probe.enter(Stage::Link);
            }
            progress.link_bytes += 1;
            if let Some(frame) = self.link.push(b) {
                self.on_frame(frame, sink);
            }
        }
        if progress.link_bytes > 0 {
            probe.leave(Stage::Link);
        }
        while self.next.is_none() {
            if self
                .pending
                .as_ref()
                .is_some_and(|p| self.window.covers(self.ready_us(p)))
            {
                break;
            }
            let Some(b) = lidar.next_byte() else { break };
            if progress.lidar_bytes == 0 {
                probe.enter(Stage::Lidar);
            }
            progress.lidar_bytes += 1;
            self.push_lidar_byte(b);
        }
        if progress.lidar_bytes > 0 {
            probe.leave(Stage::Lidar);
        }
        let ready = match &self.pending {
            Some(p) => self.window.covers(self.ready_us(p)) || self.next.is_some(),
            None => false,
        };
        if ready {
            if let Some(rev) = self.pending.take() {
                let late = !self.window.covers(rev.t_us);
                self.process(&rev, late, sink, probe);
                progress.processed = true;
            }
            self.pending = self.next.take();
        }
        progress
    }

    /// Tells the application the time on the board's own monotonic clock, `now_us` µs since
    /// the device started (a timer: not the LiDAR's stamps; a time before the last one is taken
    /// as the last one). Call it at every turn of the main loop, before or after
    /// [`Robot::poll`]; it does a bounded amount of work.
    ///
    /// - Sends a heartbeat ([`Robot::heartbeat`]) when [`RobotConfig::heartbeat_period_us`] has
    ///   passed since the last one (the first one period after the first tick), whatever the
    ///   LiDAR sends; returns whether it did. A caller that ticks late gets one heartbeat, not
    ///   a burst.
    /// - Takes the LiDAR as silent ([`Robot::set_lidar_silent`]) once no valid LiDAR frame (one
    ///   whose points the decoder emitted) has come for [`RobotConfig::lidar_silence_us`], and
    ///   as back at the next one (with 0 it leaves that to the caller).
    ///
    /// Without ticks the application sends no heartbeat of its own and the LiDAR is silent
    /// only when the caller says so: a host that replays recorded bytes leaves it out.
    pub fn tick(&mut self, now_us: u64, sink: &mut impl Sink) -> bool {
        let now = self.board_us.map_or(now_us, |b| b.max(now_us));
        let first = self.board_us.is_none();
        self.board_us = Some(now);
        // The application's own wrapping count (the decoder's counters saturate).
        if first || self.lidar_points != self.lidar_points_seen {
            self.lidar_seen_us = now;
            self.lidar_points_seen = self.lidar_points;
        }
        let quiet = self.config.lidar_silence_us;
        if quiet > 0 {
            self.lidar_silent = now - self.lidar_seen_us >= quiet;
        }
        let period = self.config.heartbeat_period_us;
        if period == 0 {
            return false;
        }
        let due = *self
            .heartbeat_due_us
            .get_or_insert(now.saturating_add(period));
        if now < due {
            return false;
        }
        // Next one a period after this one was due; from now on if the caller fell further
        // behind than a period.
        let next = due.saturating_add(period);
        self.heartbeat_due_us = Some(if next > now {
            next
        } else {
            now.saturating_add(period)
        });
        self.send_heartbeat(sink);
        true
    }

    /// The heartbeat [`Robot::send_heartbeat`] would send now.
    ///
    /// Its timestamp is the time of the last revolution processed on the device clock (the
    /// LiDAR's, which odometry is stamped on; it stands still while the LiDAR sends nothing
    /// usable), and its scans and updates count up to that revolution: those follow from the
    /// byte streams alone. The link counters (bytes, frames, odometry, errors, refused) count
    /// what was read so far, which depends on how far ahead the sender is; the LiDAR's skipped
    /// bytes what was decoded so far; the uptime is the last [`Robot::tick`]'s time in ms
    /// (wrapping; 0 before the first tick).
    pub fn heartbeat(&self) -> Heartbeat {
        let d = self.lidar.stats();
        let l = self.link.stats();
        Heartbeat {
            timestamp_us: self.processed_us,
            bytes: l.bytes,
            frames: l.frames,
            checksum_failures: l.bad_crc,
            scans: self.counters.revolutions,
            updates: self.counters.updates,
            odometry: self.counters.odometry,
            drops: self
                .counters
                .drops
                .wrapping_add(self.counters.late_odometry)
                .wrapping_add(self.counters.odometry_dropped)
                .wrapping_add(d.bad_checksum),
            link_errors: l.errors().wrapping_add(self.counters.refused),
            lidar_skipped: d.skipped_bytes,
            encode_failures: self.counters.encode_failures,
            refused: self.counters.refused,
            // Wraps at 2^32 ms, as the protocol says.
            uptime_ms: (self.board_us.unwrap_or(0) / 1000) as u32,
        }
    }

    /// Sends [`Robot::heartbeat`] now ([`Robot::tick`] sends one every
    /// [`RobotConfig::heartbeat_period_us`]; this one does not move its schedule).
    pub fn send_heartbeat(&mut self, sink: &mut impl Sink) {
        let heartbeat = self.heartbeat();
        self.send(&Message::Heartbeat(heartbeat), sink);
    }

    /// Tells the application whether the LiDAR is silent ([`Robot::tick`] does, from the
    /// board's clock and [`RobotConfig::lidar_silence_us`]; the next tick overrides this). While
    /// it is, [`Robot::poll`] reads the link whatever the odometry window and
    /// the command queue hold, dropping the oldest odometry (counted in
    /// [`RobotCounters::odometry_dropped`]) and refusing commands beyond the queue, so that the
    /// link never backs up into the receive ring. Off at the start.
    pub fn set_lidar_silent(&mut self, silent: bool) {
        self.lidar_silent = silent;
    }

    /// Whether the LiDAR is taken as silent ([`Robot::tick`], [`Robot::set_lidar_silent`]).
    pub fn is_lidar_silent(&self) -> bool {
        self.lidar_silent
    }

    /// Counts `n` bytes or messages lost before they reached the application (a receive ring
    /// that was full, a UART overrun); they are reported in the heartbeats' drops.
    pub fn add_drops(&mut self, n: u32) {
        self.counters.drops = self.counters.drops.wrapping_add(n);
    }

    /// The counters.
    pub fn counters(&self) -> RobotCounters {
        self.counters
    }

    /// The LiDAR decoder's counters.
    pub fn lidar_stats(&self) -> DecoderStats {
        self.lidar.stats()
    }

    /// The scan assembler's counters.
    pub fn assembler_stats(&self) -> AssemblerStats {
        self.assembler.stats()
    }

    /// The link decoder's counters.
    pub fn link_stats(&self) -> LinkStats {
        self.link.stats()
    }

    /// The filter (its particles, estimate and configuration).
    pub fn filter(&self) -> &Mcl<'a, N> {
        &self.mcl
    }

    /// The configuration in force (after any `SetParameters`).
    pub fn config(&self) -> &RobotConfig {
        &self.config
    }

    /// Whether the filter has particles (from a seed, an initial pose or a global start).
    pub fn is_initialized(&self) -> bool {
        self.initialized
    }

    /// The device clock: the last LiDAR timestamp, unwrapped, µs.
    pub fn now_us(&self) -> u64 {
        self.clock.now_us()
    }

    /// LiDAR timestamps the device clock dropped as wrong ([`ScanClock::outliers`]).
    pub fn clock_outliers(&self) -> u32 {
        self.clock.outliers()
    }

    /// The odometry time a revolution waits for: its time, or with de-skew on its last stamp.
    fn ready_us(&self, rev: &Revolution<S>) -> u64 {
        match (&self.deskewer, rev.sweep) {
            (Some(_), Some(w)) => w.end_us.max(rev.t_us),
            _ => rev.t_us,
        }
    }

    fn push_lidar_byte(&mut self, byte: u8) {
        let (assembler, clock, last_stamp, stamp_taken, points) = (
            &mut self.assembler,
            &mut self.clock,
            &mut self.last_stamp_ms,
            &mut self.stamp_taken,
            &mut self.lidar_points,
        );
        let mut done: Option<Revolution<S>> = None;
        self.lidar.push_byte(byte, &mut |point| {
            // Every point comes from a frame that passed its checks: the LiDAR is not silent.
            *points = points.wrapping_add(1);
            // The clock moves once per frame (its points share the stamp). The points of a frame
            // whose stamp it did not take (a wrong stamp, or the first frame after a silence)
            // are dropped: the assembler would read the stamp as turns gone by.
            if let Some(ts) = point.timestamp_ms {
                if *last_stamp != Some(ts) {
                    *last_stamp = Some(ts);
                    clock.advance(ts);
                    *stamp_taken = clock.time_of(ts).is_some();
                }
                if !*stamp_taken {
                    return;
                }
            }
            if assembler.push(point).is_some() {
                let r = assembler.revolution();
                // A stamp the clock did not take (a wrong one) gives no time: the revolution
                // is timed by its other stamp, or by the clock.
                let at = |ts: Option<u16>| ts.and_then(|ts| clock.time_of(ts));
                let (t_us, stamps) = match (at(r.start_timestamp_ms), at(r.end_timestamp_ms)) {
                    (Some(t0), Some(t1)) if t1 >= t0 => (t0 + (t1 - t0) / 2, Some((t0, t1))),
                    (Some(t), None) | (None, Some(t)) => (t, None),
                    _ => (clock.now_us(), None),
                };
                // The assembler's anchors are the same first and last stamps.
                let sweep = match (stamps, assembler.timing()) {
                    (Some((start_us, end_us)), Some(t)) => Some(SweepTimes {
                        start_us,
                        end_us,
                        start_deg: t.start_deg,
                        end_deg: t.end_deg,
                    }),
                    _ => None,
                };
                done = Some(Revolution {
                    scan: assembler.scan().clone(),
                    t_us,
                    sweep,
                });
            }
        });
        if let Some(rev) = done {
            self.counters.revolutions = self.counters.revolutions.wrapping_add(1);
            if self.pending.is_none() {
                self.pending = Some(rev);
            } else {
                self.next = Some(rev);
            }
        }
    }

    fn on_frame(&mut self, frame: Result<Frame, LinkError>, sink: &mut impl Sink) {
        let frame = match frame {
            Ok(f) => f,
            Err(e) => {
                if let Some(report) = ErrorReport::for_link_error(&e) {
                    self.send(&Message::Error(report), sink);
                }
                return;
            }
        };
        let t = frame.message.message_type();
        let refusal = match frame.message {
            Message::WheelOdometry(o) => {
                let t_us = self.arrival(o.timestamp_us);
                self.on_odometry_pose(t_us, o.pose)
            }
            Message::WheelTicks(k) => self.on_ticks(&k),
            Message::SetInitialPose(p) => self
                .check_covariance(&p.covariance)
                .and_then(|()| self.queue(Command::Initial(p))),
            Message::StartGlobalLocalization => {
                if self.free.is_none() {
                    Err((ErrorCode::Refused, 0))
                } else {
                    self.queue(Command::Global)
                }
            }
            Message::RequestNoMotionUpdate => {
                let coming = self
                    .commands
                    .iter()
                    .any(|q| matches!(q.command, Command::Initial(_) | Command::Global));
                if self.initialized || coming {
                    self.queue(Command::NoMotion)
                } else {
                    Err((ErrorCode::NotInitialized, 0))
                }
            }
            Message::SetParameters(p) => self
                .check_parameters(&p)
                .and_then(|()| self.queue(Command::Parameters(p))),
            // Messages of the device itself, sent back: not for the device.
            _ => Err((ErrorCode::Refused, 0)),
        };
        if let Err((code, detail)) = refusal {
            self.counters.refused = self.counters.refused.wrapping_add(1);
            let report = ErrorReport {
                code,
                msg_type: t as u8,
                seq: frame.seq,
                detail,
            };
            self.send(&Message::Error(report), sink);
        }
    }

    fn queue(&mut self, command: Command) -> Result<(), (ErrorCode, u8)> {
        let at_us = self.stream_time_us;
        self.commands
            .push_back(Queued { at_us, command })
            .map_err(|_| (ErrorCode::Refused, 0))
    }

    fn check_parameters(&self, p: &SetParameters) -> Result<(), (ErrorCode, u8)> {
        if let Some(n) = p.particles {
            if n == 0 || usize::from(n) > N {
                return Err((ErrorCode::Refused, 0));
            }
        }
        if let Some(k) = p.kappa {
            if !(k.is_finite() && k > 0.0) {
                return Err((ErrorCode::Refused, 0));
            }
        }
        let alphas = self.merged_alphas(p);
        OdometryNoise::new(alphas[0], alphas[1], alphas[2], alphas[3])
            .map(|_| ())
            .map_err(|_| (ErrorCode::Refused, 0))
    }

    fn merged_alphas(&self, p: &SetParameters) -> [f32; 4] {
        let mut alphas = self.config.odom_noise.alphas();
        for (a, new) in alphas.iter_mut().zip(p.odom_alpha) {
            if let Some(v) = new {
                *a = v;
            }
        }
        alphas
    }

    /// The standard deviations a cloud is drawn with around a pose of `covariance`, m and rad:
    /// widened to the configured floors, the heading's clamped to [`MAX_INIT_SIGMA_THETA_RAD`].
    fn init_sigmas(&self, covariance: &[[f32; 3]; 3]) -> (f32, f32) {
        let [vx, vy, vt] = crate::mcl::diagonal_variances(covariance);
        // Halved before the sum: two variances near f32::MAX do not overflow.
        let sigma_xy = math::sqrt(0.5 * vx + 0.5 * vy).max(self.config.min_init_sigma_xy_m);
        let sigma_theta = math::sqrt(vt)
            .max(self.config.min_init_sigma_theta_rad)
            .min(MAX_INIT_SIGMA_THETA_RAD);
        (sigma_xy, sigma_theta)
    }

    /// Refuses a covariance whose position spread the filter cannot use
    /// ([`RobotConfig::max_init_sigma_xy_m`]).
    fn check_covariance(&self, covariance: &[[f32; 3]; 3]) -> Result<(), (ErrorCode, u8)> {
        let (sigma_xy, sigma_theta) = self.init_sigmas(covariance);
        if sigma_xy.is_finite()
            && sigma_xy <= self.config.max_init_sigma_xy_m
            && sigma_theta.is_finite()
        {
            Ok(())
        } else {
            Err((ErrorCode::Refused, 0))
        }
    }

    /// A message's timestamp on the device clock: 0 means "when the frame arrives", the time of
    /// the last LiDAR frame decoded (0 before the first).
    fn arrival(&self, timestamp_us: u64) -> u64 {
        if timestamp_us == 0 {
            self.clock.now_us()
        } else {
            timestamp_us
        }
    }

    /// Refuses an odometry time that is not after the newest sample's, or lies further ahead
    /// than [`RobotConfig::max_odometry_lead_us`]. Samples taken before the device clock started
    /// that lie that far ahead of it once it has are dropped first (counted).
    fn check_time(&mut self, t_us: u64) -> Result<(), (ErrorCode, u8)> {
        let lead = self.config.max_odometry_lead_us;
        let far = (ErrorCode::ValueOutOfRange, 0);
        if self.clock.started() {
            let limit = self.clock.now_us().saturating_add(lead);
            if self.window.newest().is_some_and(|n| n.t_us > limit) {
                let n = self.window.len() as u32;
                self.window.clear();
                self.counters.odometry_dropped = self.counters.odometry_dropped.wrapping_add(n);
            }
            if t_us > limit {
                return Err(far);
            }
        }
        if let Some(n) = self.window.newest() {
            if t_us <= n.t_us {
                return Err((ErrorCode::OutOfOrder, 0));
            }
            if t_us - n.t_us > lead {
                return Err(far);
            }
        }
        Ok(())
    }

    fn on_odometry_pose(&mut self, t_us: u64, pose: Pose) -> Result<(), (ErrorCode, u8)> {
        self.check_time(t_us)?;
        self.switch_source(OdometrySource::Poses);
        self.accept_sample(t_us, pose)
    }

    fn on_ticks(&mut self, k: &link::WheelTicks) -> Result<(), (ErrorCode, u8)> {
        if self.wheels.is_none() {
            return Err((ErrorCode::Refused, 0));
        }
        let t_us = self.arrival(k.timestamp_us);
        self.check_time(t_us)?;
        self.switch_source(OdometrySource::Ticks);
        let Some(wheels) = self.wheels.as_mut() else {
            return Err((ErrorCode::Refused, 0));
        };
        // A refused step (an encoder reset, a corrupted count) leaves the wheel model as it was:
        // the next reading is measured from the last good one. Ticks are cumulative: a message
        // refused later (its speed) still moved the integrated pose, as the wheels did.
        let before = wheels.clone();
        if wheels.step(k.left_ticks, k.right_ticks).is_err() {
            *wheels = before;
            return Err((
                ErrorCode::ValueOutOfRange,
                link::layout::wheel_ticks::LEFT_TICKS.start as u8,
            ));
        }
        let pose = wheels.pose();
        self.accept_sample(t_us, pose)
    }

    fn switch_source(&mut self, to: OdometrySource) {
        if self.source != Some(to) {
            // Poses of another source are in another frame: start over without a motion step.
            if self.source.is_some() {
                self.window.clear();
                self.last_odom = None;
            }
            self.source = Some(to);
        }
    }

    fn accept_sample(&mut self, t_us: u64, pose: Pose) -> Result<(), (ErrorCode, u8)> {
        let x_offset = link::layout::wheel_odometry::X_M.start as u8;
        if let Some(n) = self.window.newest() {
            if t_us <= n.t_us {
                return Err((ErrorCode::OutOfOrder, 0));
            }
            let gap_us = t_us - n.t_us;
            let dt_s = gap_us as f32 * 1e-6;
            let (dx, dy) = (pose.x_m - n.pose.x_m, pose.y_m - n.pose.y_m);
            let d = math::sqrt(dx * dx + dy * dy);
            let a = wrap_angle(pose.theta_rad - n.pose.theta_rad).abs();
            if !(d.is_finite()) {
                return Err((ErrorCode::ValueOutOfRange, x_offset));
            }
            let too_fast = d > self.config.max_speed_m_per_s * dt_s
                || a > self.config.max_turn_rad_per_s * dt_s;
            if too_fast {
                if gap_us < self.config.odometry_restart_gap_us {
                    return Err((ErrorCode::ValueOutOfRange, x_offset));
                }
                // After a long silence, a step no robot makes: the odometry restarted (or the
                // robot was carried). A new odometry frame, no motion across the gap.
                self.window.restart();
                self.counters.odometry_restarts = self.counters.odometry_restarts.wrapping_add(1);
            }
        }
        if !self.window.has_room() {
            // Only while the LiDAR is silent (the link is read then whatever the window holds).
            self.window.pop_oldest();
            self.counters.odometry_dropped = self.counters.odometry_dropped.wrapping_add(1);
        }
        if !self.window.push(Sample { t_us, pose }) {
            return Err((ErrorCode::Refused, 0));
        }
        self.stream_time_us = t_us;
        self.counters.odometry = self.counters.odometry.wrapping_add(1);
        Ok(())
    }

    fn odom_at(&self, t_us: u64) -> Option<window::Interpolated> {
        self.window.at(t_us, self.config.max_odometry_gap_us)
    }

    fn init_around(&mut self, pose: &Pose, covariance: &[[f32; 3]; 3]) -> bool {
        let (sigma_xy, sigma_theta) = self.init_sigmas(covariance);
        let ok = self
            .mcl
            .init_gaussian(
                self.config.particles,
                pose,
                sigma_xy,
                sigma_theta,
                &mut self.rng,
            )
            .is_ok();
        if ok {
            self.initialized = true;
            self.global = false;
        }
        ok
    }

    fn apply(&mut self, q: Queued) {
        self.counters.commands = self.counters.commands.wrapping_add(1);
        let odom_then = self.odom_at(q.at_us).map(|i| (i.pose, i.frame));
        match q.command {
            Command::Initial(p) => {
                if self.init_around(&p.pose, &p.covariance) {
                    self.last_odom = odom_then;
                }
            }
            Command::Global => {
                if let Some(free) = self.free {
                    if self
                        .mcl
                        .init_uniform(self.config.particles, &free, &mut self.rng)
                        .is_ok()
                    {
                        self.initialized = true;
                        self.global = true;
                        self.last_odom = odom_then;
                    }
                }
            }
            Command::NoMotion => self.force_update = true,
            Command::Parameters(p) => {
                let alphas = self.merged_alphas(&p);
                if let Ok(noise) = OdometryNoise::new(alphas[0], alphas[1], alphas[2], alphas[3]) {
                    if let Ok(c) =
                        MclConfig::new(noise, self.config.resample_ess_fraction, 0.0, 0.0)
                    {
                        self.mcl.set_config(c);
                        self.config.odom_noise = noise;
                    }
                }
                if let Some(k) = p.kappa {
                    if let Ok(m) = Tempered::new(self.model.inner().clone(), k, 1) {
                        self.model = m;
                        self.config.kappa = k;
                    }
                }
                if let Some(n) = p.particles {
                    self.config.particles = usize::from(n);
                    if self.initialized && self.mcl.len() != usize::from(n) {
                        // Redraw the cloud at the new size around the current estimate.
                        let e = *self.mcl.estimate();
                        let global = self.global;
                        self.init_around(&e.pose, &e.covariance);
                        self.global = global;
                    }
                }
            }
        }
    }

    fn process(
        &mut self,
        rev: &Revolution<S>,
        late: bool,
        sink: &mut impl Sink,
        probe: &mut impl Probe,
    ) {
        while self.commands.front().is_some_and(|q| q.at_us <= rev.t_us) {
            if let Some(q) = self.commands.pop_front() {
                self.apply(q);
            }
        }
        self.processed_us = rev.t_us;
        if late {
            self.counters.late_odometry = self.counters.late_odometry.wrapping_add(1);
        }
        if let Some(estimate) = self.update(rev, late, probe) {
            probe.enter(Stage::Send);
            let sent = self.send(&Message::Estimate(estimate), sink);
            probe.leave(Stage::Send);
            if sent && !self.global {
                sink.save(&Seed {
                    pose: estimate.pose,
                    covariance: estimate.covariance,
                });
            }
        }
        self.window.forget_before(rev.t_us);
    }

    /// Predicts and updates with `rev`; the estimate to send, `None` when the revolution was
    /// not used.
    fn update(
        &mut self,
        rev: &Revolution<S>,
        late: bool,
        probe: &mut impl Probe,
    ) -> Option<link::Estimate> {
        if !self.initialized {
            self.skip();
            return None;
        }
        let odom = self.odom_at(rev.t_us);
        let mut stale = late;
        let step = match (odom, self.last_odom) {
            (Some(now), Some((before, frame))) if frame == now.frame => {
                stale |= now.stale;
                OdometryStep::between(&before, &now.pose).ok()
            }
            // No odometry before, or before a restart of the odometry: no motion known.
            (Some(now), last) => {
                stale |= now.stale || last.is_some();
                Some(OdometryStep::STILL)
            }
            (None, _) => {
                stale = true;
                Some(OdometryStep::STILL)
            }
        };
        let Some(step) = step else {
            self.skip();
            return None;
        };
        let moved = step.trans_m() >= self.config.update_min_d_m
            || wrap_angle(step.rot1_rad() + step.rot2_rad()).abs() >= self.config.update_min_a_rad;
        let forced = self.force_update;
        if !(moved || forced) {
            self.skip();
            return None;
        }
        self.force_update = false;
        if let Some(now) = odom {
            self.last_odom = Some((now.pose, now.frame));
        }
        probe.enter(Stage::Predict);
        self.mcl.predict(&step, &mut self.rng);
        probe.leave(Stage::Predict);
        probe.enter(Stage::Update);
        let deskewed = self.deskewer.is_some() && self.deskew(rev, odom.map(|o| o.pose));
        let scan = if deskewed { &self.deskewed } else { &rev.scan };
        let prepared = self.model.prepare(&self.layout, scan);
        let update = self.mcl.update_prepared(&prepared, None, &mut self.rng);
        probe.leave(Stage::Update);
        let Ok(update) = update else {
            self.skip();
            return None;
        };
        self.counters.updates = self.counters.updates.wrapping_add(1);
        let mut flags = EstimateFlags::INITIALIZED;
        if update.resampled {
            flags = flags | EstimateFlags::RESAMPLED;
        }
        if self.global {
            flags = flags | EstimateFlags::GLOBAL_LOCALIZATION;
        }
        if forced && !moved {
            flags = flags | EstimateFlags::NO_MOTION_UPDATE;
        }
        if stale {
            flags = flags | EstimateFlags::ODOMETRY_STALE;
            self.counters.stale_odometry = self.counters.stale_odometry.wrapping_add(1);
        }
        // The reported covariance (the particles' inflated, growing while not tracking), not
        // the particles' own: consumers weigh the pose by it.
        let e = crate::mcl::Estimate {
            covariance: update.covariance,
            ..*self.mcl.estimate()
        };
        if self.global && settled(&self.mcl, &e.pose) {
            self.global = false;
        }
        // The odometry the prediction reached: this revolution's, or the last one used when
        // none reached the device (then the robot is taken to have stood still).
        let odometry = odom
            .map(|o| o.pose)
            .or(self.last_odom.map(|(p, _)| p))
            .unwrap_or_default();
        Some(link::Estimate::from_mcl(
            &e,
            rev.t_us,
            flags,
            Quality::from(&update.quality),
            odometry,
        ))
    }

    fn skip(&mut self) {
        self.counters.skipped = self.counters.skipped.wrapping_add(1);
    }

    /// De-skews `rev` into `self.deskewed` for the odometry pose `reference` at its time;
    /// `false` (counted) when it cannot: no timing, no fresh odometry at the start or end.
    fn deskew(&mut self, rev: &Revolution<S>, reference: Option<Pose>) -> bool {
        let gap = self.config.max_odometry_gap_us;
        let fresh = |t: u64| self.window.at(t, gap).filter(|i| !i.stale).map(|i| i.pose);
        let sweep = match (rev.sweep, reference) {
            (Some(w), Some(reference)) => match (fresh(w.start_us), fresh(w.end_us)) {
                (Some(start), Some(end)) => Some(Sweep {
                    start_deg: w.start_deg,
                    end_deg: w.end_deg,
                    start,
                    end,
                    reference,
                }),
                _ => None,
            },
            _ => None,
        };
        let ok = match (sweep, &self.deskewer) {
            (Some(sweep), Some(d)) => d
                .apply(&self.layout, &rev.scan, &sweep, &mut self.deskewed)
                .is_ok(),
            _ => false,
        };
        if ok {
            self.counters.deskewed = self.counters.deskewed.wrapping_add(1);
        } else {
            self.counters.deskew_skipped = self.counters.deskew_skipped.wrapping_add(1);
        }
        ok
    }

    /// Encodes and sends `message`; `false` when it could not be encoded (never sent).
    fn send(&mut self, message: &Message, sink: &mut impl Sink) -> bool {
        let mut wire = [0u8; MAX_WIRE_LEN];
        match self.encoder.encode(message, &mut wire) {
            Ok(n) => {
                sink.send(message, wire.get(..n).unwrap_or(&[]));
                self.counters.frames_sent = self.counters.frames_sent.wrapping_add(1);
                true
            }
            Err(_) => {
                self.counters.encode_failures = self.counters.encode_failures.wrapping_add(1);
                false
            }
        }
    }
}

/// Whether a global localization has narrowed to one place: 90 % of the particles' weight within
/// 0.5 m and 0.3 rad of the estimate.
fn settled<const N: usize>(mcl: &Mcl<'_, N>, at: &Pose) -> bool {
    let (mut near, mut total) = (0.0f32, 0.0f32);
    for (p, &w) in mcl.poses().iter().zip(mcl.weights()) {
        total += w;
        let (dx, dy) = (p.x_m - at.x_m, p.y_m - at.y_m);
        if dx * dx + dy * dy < 0.25 && wrap_angle(p.theta_rad - at.theta_rad).abs() < 0.3 {
            near += w;
        }
    }
    total > 0.0 && near >= 0.9 * total
}

/// The message types a device running [`Robot`] accepts.
pub const ACCEPTED: [MessageType; 6] = [
    MessageType::WheelOdometry,
    MessageType::WheelTicks,
    MessageType::SetInitialPose,
    MessageType::StartGlobalLocalization,
    MessageType::RequestNoMotionUpdate,
    MessageType::SetParameters,
];
