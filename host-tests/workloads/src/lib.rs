//! The workloads that host-tests' benches, examples and tests share, so that a timing, an
//! instruction count and a test run exactly the same code on the same data:
//!
//! - [`intel_race`]: the race's data (the Intel map's blob, real scans, fitted parameters);
//! - [`race_passes`]: one pass of each variant the race times;
//! - [`amcl_beam`]: an AMCL-style beam model, the race's same-run baseline;
//! - [`em_data`]: the EM bench's data set.

pub mod amcl_beam;
pub mod em_data;
pub mod intel_race;
pub mod race_passes;
