//! `beamfield info`: the tool's version and the build configuration of the library it links.

use beamfield::BUILD_INFO;

/// The report of `beamfield info`, as text or (with `json`) as one JSON object.
pub fn render(json: bool) -> String {
    let b = BUILD_INFO;
    let features: Vec<&str> = [
        ("micromath", b.micromath),
        ("fixed", b.fixed),
        ("defmt", b.defmt),
        ("hal", b.hal),
    ]
    .into_iter()
    .filter_map(|(name, on)| on.then_some(name))
    .collect();
    let trig = if b.micromath {
        "micromath sin/cos/atan2"
    } else {
        "the crate's own sin_cos, libm atan2"
    };
    let profile = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    let target = format!("{}-{}", std::env::consts::ARCH, std::env::consts::OS);
    if json {
        return serde_json::json!({
            "tool_version": env!("CARGO_PKG_VERSION"),
            "library_version": b.version,
            "library_features": features,
            "trigonometry": trig,
            "blob_format_version": b.blob_format_version,
            "profile": profile,
            "target": target,
        })
        .to_string();
    }
    let features = if features.is_empty() {
        "none".to_string()
    } else {
        features.join(", ")
    };
    format!(
        "beamfield (tool) {}\nlibrary: beamfield {}, features: {features}\ntrigonometry: {trig}\n\
         blob format version: {}\nbuild: {profile}, {target}",
        env!("CARGO_PKG_VERSION"),
        b.version,
        b.blob_format_version
    )
}
