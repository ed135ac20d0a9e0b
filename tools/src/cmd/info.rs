//! `beamfield info`: the tool's version and the build configuration of the library it links.

use beamfield::BUILD_INFO;
use serde::Serialize;
use std::fmt;

/// The report of `beamfield info`.
#[derive(Debug, Serialize)]
pub struct InfoReport {
    /// The tool's version.
    pub tool_version: &'static str,
    /// The library's version.
    pub library_version: &'static str,
    /// The library's features that are on.
    pub library_features: Vec<&'static str>,
    /// The trigonometry backend.
    pub trigonometry: &'static str,
    /// The blob format version.
    pub blob_format_version: u16,
    /// `debug` or `release`.
    pub profile: &'static str,
    /// Architecture and operating system.
    pub target: String,
}

/// The build configuration of this binary.
pub fn run() -> InfoReport {
    let b = BUILD_INFO;
    let library_features = [
        ("micromath", b.micromath),
        ("fixed", b.fixed),
        ("defmt", b.defmt),
        ("hal", b.hal),
    ]
    .into_iter()
    .filter_map(|(name, on)| on.then_some(name))
    .collect();
    InfoReport {
        tool_version: env!("CARGO_PKG_VERSION"),
        library_version: b.version,
        library_features,
        trigonometry: if b.micromath {
            "micromath sin/cos/atan2"
        } else {
            "the crate's own sin_cos, libm atan2"
        },
        blob_format_version: b.blob_format_version,
        profile: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        target: format!("{}-{}", std::env::consts::ARCH, std::env::consts::OS),
    }
}

impl fmt::Display for InfoReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let features = if self.library_features.is_empty() {
            "none".to_string()
        } else {
            self.library_features.join(", ")
        };
        write!(
            f,
            "beamfield (tool) {}\nlibrary: beamfield {}, features: {features}\ntrigonometry: {}\n\
             blob format version: {}\nbuild: {}, {}",
            self.tool_version,
            self.library_version,
            self.trigonometry,
            self.blob_format_version,
            self.profile,
            self.target
        )
    }
}
