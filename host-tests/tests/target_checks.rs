//! Host-side checks of what runs on the target; none of them needs QEMU.
//!
//! - the checked-in `firmware/src/reference_cases.rs` is what the f64 reference gives today;
//! - the crate meets those cases' tolerances on the host too (the firmware repeats this on an
//!   emulated Cortex-M4F: `cargo xtask qemu`);
//! - the library uses no `alloc` and the firmware defines no global allocator;
//! - the instruction-count markers exist and cannot be merged by the linker.

use beamfield::{BeamIntrinsics, BeamModel};
use host_tests::firmware_cases::{cases, render, GENERATED_PATH};
use std::fs;
use std::path::{Path, PathBuf};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host-tests lives in the repository")
        .to_path_buf()
}

#[test]
fn reference_cases_file_is_fresh() {
    let path = repo_root().join(GENERATED_PATH);
    let on_disk = fs::read_to_string(&path).unwrap_or_default();
    let want = render();
    assert!(
        on_disk == want,
        "{} is stale or missing: run `cargo xtask refcases` and commit it",
        path.display()
    );
}

#[test]
fn crate_meets_the_reference_cases_on_the_host() {
    let table = cases();
    assert!(table.len() > 50, "table unexpectedly small");
    let mut worst = 0.0f64;
    for c in &table {
        let [zh, zs, zm, zr, s, l, r] = c.intrinsics;
        let model = BeamModel::new(BeamIntrinsics::new(zh, zs, zm, zr, s, l, r).unwrap());
        let got = model.beam_log_likelihood(c.range_m, c.z_star_m);
        match (got, c.expected) {
            (None, None) => {}
            (Some(g), Some(e)) => {
                let err = (f64::from(g) - e).abs();
                worst = worst.max(err / c.tolerance);
                assert!(
                    err <= c.tolerance,
                    "{}: z={} z*={}: got {g}, want {e} (|err| {err:e} > {:e})",
                    c.name,
                    c.range_m,
                    c.z_star_m,
                    c.tolerance
                );
            }
            (g, e) => panic!("{}: got {g:?}, reference {e:?}", c.name),
        }
    }
    println!("worst |err|/tolerance over the table: {worst:.3}");
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// Lines of Rust code with `//` comments removed (doc comments may mention `alloc`).
fn code_lines(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .filter(|l| !l.trim().is_empty())
}

#[test]
fn library_is_no_std_without_alloc() {
    let root = repo_root();
    let lib = fs::read_to_string(root.join("src/lib.rs")).unwrap();
    assert!(
        code_lines(&lib).any(|l| l.contains("no_std")),
        "src/lib.rs must declare no_std"
    );
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    assert!(files.len() >= 5, "found only {files:?}");
    for f in files {
        let text = fs::read_to_string(&f).unwrap();
        for line in code_lines(&text) {
            assert!(
                !line.contains("extern crate alloc")
                    && !line.contains("alloc::")
                    && !line.contains("extern crate std")
                    && !line.contains("global_allocator"),
                "{}: `{}` (the library must not allocate)",
                f.display(),
                line.trim()
            );
        }
    }
}

#[test]
fn firmware_has_no_allocator_and_distinct_markers() {
    let mut files = Vec::new();
    rust_files(&repo_root().join("firmware/src"), &mut files);
    let mut start = None;
    let mut end = None;
    for f in &files {
        let text = fs::read_to_string(f).unwrap();
        for line in code_lines(&text) {
            assert!(
                !line.contains("global_allocator") && !line.contains("extern crate alloc"),
                "{}: the firmware must link without an allocator",
                f.display()
            );
        }
        if let Some(i) = text.find("fn bench_mark_start") {
            start = Some(text[i..].split('}').next().unwrap().to_string());
        }
        if let Some(i) = text.find("fn bench_mark_end") {
            end = Some(text[i..].split('}').next().unwrap().to_string());
        }
    }
    let (start, end) = (
        start.expect("bench_mark_start"),
        end.expect("bench_mark_end"),
    );
    let body = |s: &str| s.split('{').nth(1).unwrap_or("").trim().to_string();
    assert_ne!(
        body(&start),
        body(&end),
        "identical marker bodies would be merged by the linker"
    );
}
