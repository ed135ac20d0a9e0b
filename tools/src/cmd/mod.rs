//! The `beamfield` subcommands, one module per subcommand as the user types it. Each parses its
//! arguments, runs the library and returns one report that is both `Serialize` (`--json`) and
//! `Display` (text); `main` prints it.
pub mod calibrate;
pub mod field;
pub mod fit;
pub mod info;
pub mod lidar;
pub mod likelihood;
pub mod log;
pub mod map;
pub mod score;
pub mod scored_log;
pub mod sonar;
pub mod track;
