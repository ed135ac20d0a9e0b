//! `beamfield bridge`: the computer's side of a beamfield base controller. It reads the device's
//! link (docs/link-protocol.md) from a serial port or a TCP socket and speaks ROS 2 the way
//! nav2_amcl does (docs/nav2.md): the estimates on `amcl_pose`, the map → odom transform on
//! `/tf`, `initialpose` and nav2_amcl's two services to the device.
//!
//! - [`msg`]: the ROS 2 messages, laid out as CDR has them;
//! - [`clock`]: the device's clock on the computer's (`--clock host`) or continued on its own
//!   (`--clock device`);
//! - [`lifecycle`]: the managed-node state machine nav2's lifecycle manager drives;
//! - [`convert`]: link messages to ROS messages and back;
//! - [`outbox`]: the newest message of a topic while the DDS writer's window is full;
//! - [`queue`]: the bounded queue between the link's reader and the bridge's loop;
//! - [`repeat`]: the last map → odom transform re-sent while no estimate comes;
//! - [`params`]: a nav2 params file's amcl section;
//! - [`port`]: the link's bytes;
//! - [`ros`]: the ROS 2 node;
//! - [`stop`]: SIGINT and SIGTERM, a requested stop.

pub mod clock;
pub mod convert;
pub mod lifecycle;
pub mod msg;
pub mod outbox;
pub mod params;
pub mod port;
pub mod queue;
pub mod repeat;
pub mod ros;
mod run;
pub mod stop;

pub use run::{
    parse_seconds, run, run_until, BridgeArgs, BridgeError, BridgeReport, ClockArg, Rmw,
    EXIT_CANNOT_START, EXIT_LINK_LOST, EXIT_STOPPED, EXIT_USAGE, REFUSED_EXAMPLES,
};
