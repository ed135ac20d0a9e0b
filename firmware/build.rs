//! Puts the memory layout where the linker finds it and adds cortex-m-rt's linker script.
//!
//! The layout is the repository's top-level `memory.x` (or the file named by the environment
//! variable `BEAMFIELD_MEMORY_X`), copied into `OUT_DIR`, which is added to the linker's search
//! path. The linker looks in its working directory (this package's root) *before* the search
//! path, so a `firmware/memory.x` would silently shadow the copy: this script refuses to build
//! when one exists.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets this"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets this"));
    println!("cargo:rerun-if-env-changed=BEAMFIELD_MEMORY_X");
    let layout = match env::var_os("BEAMFIELD_MEMORY_X") {
        Some(p) => PathBuf::from(p),
        None => manifest.join("..").join("memory.x"),
    };
    let shadow = manifest.join("memory.x");
    if shadow.exists() {
        panic!(
            "{} would shadow {} (the linker searches its working directory first); remove it",
            shadow.display(),
            layout.display()
        );
    }
    println!("cargo:rerun-if-changed={}", layout.display());
    let text = fs::read(&layout)
        .unwrap_or_else(|e| panic!("cannot read memory layout {}: {e}", layout.display()));
    fs::write(out.join("memory.x"), text).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    // Only the firmware's binaries are linked with cortex-m-rt's script.
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    // defmt's interned strings need its linker script (feature `defmt`).
    if env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
}
