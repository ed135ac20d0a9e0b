//! What this build of the crate was compiled with, for tools and logs that report it.

/// The version and Cargo features of this build of `beamfield`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct BuildInfo {
    /// The crate's version.
    pub version: &'static str,
    /// Feature `micromath`: micromath's sin/cos/atan2 instead of the crate's own `sin_cos` and
    /// libm's `atan2`.
    pub micromath: bool,
    /// Feature `fixed`: the fixed-point likelihood field.
    pub fixed: bool,
    /// Feature `defmt`: `defmt::Format` on errors and reports.
    pub defmt: bool,
    /// Feature `hal`: the embedded-hal ultrasonic ring driver.
    pub hal: bool,
    /// Version of the distance-field blob format this build reads and writes.
    pub blob_format_version: u16,
}

/// The version and features of this build.
pub const BUILD_INFO: BuildInfo = BuildInfo {
    version: env!("CARGO_PKG_VERSION"),
    micromath: cfg!(feature = "micromath"),
    fixed: cfg!(feature = "fixed"),
    defmt: cfg!(feature = "defmt"),
    hal: cfg!(feature = "hal"),
    blob_format_version: crate::field::BLOB_VERSION,
};
