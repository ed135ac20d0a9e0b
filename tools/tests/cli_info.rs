//! `beamfield info`: the build configuration it prints agrees with the repository's own
//! description of the library (its Cargo.toml and the blob format document), in text and JSON.

use std::path::PathBuf;

mod common;
use common::{bin, run_json};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn info_reports_the_library_build() {
    let manifest: toml::Table = std::fs::read_to_string(repo().join("Cargo.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let version = manifest["package"]["version"].as_str().unwrap();
    let declared: Vec<&str> = manifest["features"]
        .as_table()
        .unwrap()
        .keys()
        .map(String::as_str)
        .filter(|f| *f != "default")
        .collect();
    // "# Distance-field blob, format version 1 (encodings 1 and 2)"
    let format_doc = std::fs::read_to_string(repo().join("docs/blob-format.md")).unwrap();
    let title = format_doc.lines().next().unwrap();
    let after = title.split("format version ").nth(1).unwrap();
    let doc_version: u64 = after.split(' ').next().unwrap().parse().unwrap();

    let v = run_json(bin().args(["--json", "info"]));
    assert_eq!(v["library_version"], version);
    assert_eq!(v["blob_format_version"].as_u64(), Some(doc_version));
    let features: Vec<&str> = v["library_features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    for f in &features {
        assert!(declared.contains(f), "{f} is not a feature of the library");
    }
    let micromath = features.contains(&"micromath");
    assert_eq!(
        v["trigonometry"].as_str().unwrap().contains("micromath"),
        micromath
    );

    let out = bin().arg("info").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains(&format!("library: beamfield {version}")),
        "{text}"
    );
    assert!(
        text.contains(&format!("blob format version: {doc_version}")),
        "{text}"
    );
    let listed = if features.is_empty() {
        "none".to_string()
    } else {
        features.join(", ")
    };
    assert!(text.contains(&format!("features: {listed}\n")), "{text}");
}
