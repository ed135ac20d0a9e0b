//! `beamfield sonar …`: host tools for an ultrasonic ring (docs/models.md#sonar).
//!
//! `beamfield sonar schedule --ring RING.toml --rate HZ` compares candidate firing schedules by
//! expected crosstalk and achievable scan rate, and recommends one ([`crate::sonar`]). See
//! `docs/sonar.md`.

use crate::input::ring::load_ring;
use crate::sonar::{compare_schedules, ScheduleReport};
use clap::{Args, Subcommand};
use std::path::PathBuf;

/// `beamfield sonar` subcommands.
#[derive(Subcommand, Debug)]
pub enum SonarCommand {
    /// Compare firing schedules for a ring by expected crosstalk and scan rate, and recommend one.
    ///
    /// Candidates: all at once, alternating halves, opposite pairs, one at a time, and groups of
    /// k spread evenly around the ring for every k dividing the ring size. Each group waits the
    /// echo lifetime 2·max_range/c before the next fires, so no echo lingers; a candidate too
    /// slow for the requested rate at that pace is also evaluated squeezed to the rate, with the
    /// lingering echoes of earlier groups counted as co-fired, its usable range shortened, and
    /// its groups fired in the order (stride) that keeps lingering echoes least harmful.
    /// Full-range schedules are preferred; a squeezed one is recommended only when none reaches
    /// the rate. Add `--json` for machine-readable output.
    Schedule(ScheduleArgs),
}

/// Arguments of `beamfield sonar schedule`.
#[derive(Args, Debug)]
pub struct ScheduleArgs {
    /// Ring description (TOML); see docs/examples/ring24.toml.
    #[arg(long)]
    pub ring: PathBuf,
    /// Required full-ring scan rate, Hz.
    #[arg(long)]
    pub rate: f64,
}

/// Runs a `sonar` subcommand.
///
/// # Errors
/// A message for bad input.
pub fn run(cmd: &SonarCommand) -> Result<ScheduleReport, String> {
    match cmd {
        SonarCommand::Schedule(a) => {
            let lr = load_ring(&a.ring)?;
            compare_schedules(&lr, a.rate)
        }
    }
}
