//! `cargo xtask budgets`: flash, RAM, stack and instruction budgets of the scoring core, as a
//! table against the demo's targets.

use crate::budget_run::run_budget;
use crate::cross::build_firmware;
use crate::elf::{gsec, region_length, sections, symbols, LAYOUT};
use crate::error::{Error, Result};
use crate::process::{capture, repo_root};
use crate::qemu::ensure_qemu;
use crate::toolchain::{llvm_tool, FIRMWARE_TARGET};
use std::fs;
use std::process::Command;

/// Target: text of the scoring core, bytes.
const TARGET_TEXT: u64 = 8 * 1024;
/// Target: RAM of the scoring core with its stack, bytes (360 beams).
const TARGET_RAM: u64 = 2 * 1024;
/// Target: instructions per beam of the likelihood field.
const TARGET_LF_PER_BEAM: f64 = 20.0;
/// Symbols that only a program with a heap contains.
const ALLOC_SYMBOLS: [&str; 4] = [
    "__rust_alloc",
    "__rg_alloc",
    "__rdl_alloc",
    "__rust_alloc_error_handler",
];

/// One row of the table.
struct Row {
    what: String,
    value: String,
    target: String,
    status: &'static str,
}

fn row(what: impl Into<String>, value: impl Into<String>) -> Row {
    Row {
        what: what.into(),
        value: value.into(),
        target: "-".into(),
        status: "info",
    }
}

fn check(what: impl Into<String>, value: impl Into<String>, target: String, ok: bool) -> Row {
    Row {
        what: what.into(),
        value: value.into(),
        target,
        status: if ok { "PASS" } else { "OVER" },
    }
}

fn hard(what: impl Into<String>, value: impl Into<String>, target: String, ok: bool) -> Row {
    Row {
        what: what.into(),
        value: value.into(),
        target,
        status: if ok { "PASS (hard)" } else { "FAIL (hard)" },
    }
}

/// `cargo xtask budgets`: the table on QEMU's `machine`, the firmware built with `features`.
pub fn budgets(machine: &str, features: Option<&str>) -> Result {
    ensure_qemu()?;
    let size = llvm_tool("llvm-size")?;
    let nm = llvm_tool("llvm-nm")?;
    let elves = build_firmware(true, features)?;
    let elf = |n: &str| {
        elves
            .get(n)
            .ok_or_else(|| Error::Output(format!("the firmware has no `{n}` program")))
    };
    let (core_elf, lf_elf, skel_elf, budget_elf) = (
        elf("size_core")?,
        elf("size_lf")?,
        elf("size_skeleton")?,
        elf("budget")?,
    );
    let core = sections(&size, core_elf)?;
    let lf = sections(&size, lf_elf)?;
    let skel = sections(&size, skel_elf)?;
    let diff = |names: &[&str]| gsec(&core, names).saturating_sub(gsec(&skel, names));
    let signed = |names: &[&str]| gsec(&core, names) as i64 - gsec(&skel, names) as i64;
    let lf_diff = |names: &[&str]| gsec(&lf, names).saturating_sub(gsec(&skel, names));

    // Heap: no allocator symbol in any firmware program (they link without a
    // #[global_allocator], which already proves the crate graph never allocates).
    let mut with_heap = Vec::new();
    for (name, path) in &elves {
        let syms = capture(Command::new(&nm).arg(path))?;
        if syms
            .lines()
            .any(|l| ALLOC_SYMBOLS.iter().any(|a| l.ends_with(&format!(" {a}"))))
        {
            with_heap.push(name.clone());
        }
    }

    let run = run_budget(budget_elf, machine)?;
    let stack = |n: &str| run.stack.get(n).copied();
    let state = |n: &str| run.state.get(n).copied();
    let region = |n: &str| run.region(n);

    let mut rows = Vec::new();
    let lf_text = lf_diff(&[".text"]);
    rows.push(check(
        "likelihood-field core .text (size_lf - size_skeleton)",
        format!("{lf_text} B"),
        format!("<= {TARGET_TEXT} B"),
        lf_text <= TARGET_TEXT,
    ));
    rows.push(row(
        "likelihood-field core .rodata (size_lf - size_skeleton)",
        format!(
            "{} B",
            gsec(&lf, &[".rodata"]) as i64 - gsec(&skel, &[".rodata"]) as i64
        ),
    ));
    let text = diff(&[".text"]);
    rows.push(check(
        "full core .text, both models (size_core - size_skeleton)",
        format!("{text} B"),
        format!("<= {TARGET_TEXT} B"),
        text <= TARGET_TEXT,
    ));
    rows.push(row(
        "full core .rodata (size_core - size_skeleton)",
        format!("{} B", signed(&[".rodata"])),
    ));
    let static_ram = diff(&[".data", ".bss", ".uninit"]);
    rows.push(row(
        "full core .data + .bss (size_core - size_skeleton)",
        format!("{static_ram} B"),
    ));
    for (key, what) in [
        ("lf", "stack, one likelihood-field score (360 beams)"),
        ("tempered", "stack, one tempered likelihood-field score"),
        ("normalize", "stack, normalize_log_weights"),
        ("beam", "stack, one beam-model score with ray casting"),
    ] {
        rows.push(row(
            what,
            stack(key).map_or("not measured".into(), |b| format!("{b} B")),
        ));
    }
    for (model, state_key, stack_keys, what) in [
        (
            "tempered likelihood field",
            "tempered",
            &["tempered", "normalize"][..],
            "core RAM, tempered LF: .data+.bss + model value + deepest stack",
        ),
        (
            "beam model",
            "beam",
            &["beam"][..],
            "core RAM, beam model: .data+.bss + model value + stack",
        ),
    ] {
        let deepest = stack_keys.iter().filter_map(|k| stack(k)).max();
        match (state(state_key), deepest) {
            (Some(v), Some(s)) => {
                let total = static_ram + v + s;
                rows.push(check(
                    what,
                    format!("{total} B ({static_ram} + {v} + {s})"),
                    format!("<= {TARGET_RAM} B"),
                    total <= TARGET_RAM,
                ));
            }
            _ => rows.push(row(what, format!("not measured ({model})"))),
        }
    }
    if let (Some(l), Some(s)) = (state("layout"), state("scan")) {
        rows.push(row(
            "caller's buffers, 360 beams: BeamLayout + Scan (not in the core)",
            format!("{} B ({l} + {s})", l + s),
        ));
    }
    if let Some(p) = state("prepared") {
        rows.push(row(
            "caller's PreparedScan, 360 beams (8 B per kept beam + header; not in the core)",
            format!("{p} B"),
        ));
    }
    rows.push(hard(
        "heap (allocator symbols in the firmware programs)",
        if with_heap.is_empty() {
            "none".to_string()
        } else {
            with_heap.join(", ")
        },
        "none".into(),
        with_heap.is_empty(),
    ));
    let layout_path = repo_root().join(LAYOUT);
    let layout_text = fs::read_to_string(&layout_path).map_err(|e| Error::io(&layout_path, e))?;
    let (flash_max, ram_max) = (
        region_length(&layout_text, "FLASH")?,
        region_length(&layout_text, "RAM")?,
    );
    let flash = gsec(&core, &[".vector_table", ".text", ".rodata", ".data"]);
    let deepest = run.stack.values().copied().max().unwrap_or(0);
    let ram = gsec(&core, &[".data", ".bss", ".uninit"]) + deepest;
    rows.push(hard(
        "size_core image, Intel blob included: flash",
        format!("{flash} B"),
        format!("<= {flash_max} B ({LAYOUT})"),
        flash <= flash_max,
    ));
    rows.push(hard(
        "size_core RAM: .data+.bss + deepest scoring stack",
        format!("{ram} B"),
        format!("<= {ram_max} B ({LAYOUT})"),
        ram <= ram_max,
    ));
    let mut counted = true;
    for (full, half, label, target) in [
        (
            "lf",
            "lf-half",
            "likelihood field",
            Some(TARGET_LF_PER_BEAM),
        ),
        ("beam", "beam-half", "beam model + ray casting", None),
        (
            "lf-prepared",
            "lf-prepared-half",
            "likelihood field, prepared scan",
            Some(TARGET_LF_PER_BEAM),
        ),
    ] {
        let (Some(f), Some(h)) = (region(full), region(half)) else {
            rows.push(row(format!("{label}: instructions"), "not measured"));
            counted = false;
            continue;
        };
        let per_pose = f.insns as f64 / f.poses as f64;
        let per_beam = per_pose / f.beams as f64;
        rows.push(row(
            format!("{label}: instructions per pose ({} beams)", f.beams),
            format!("{per_pose:.1}"),
        ));
        let what = format!("{label}: instructions per beam (per pose / {})", f.beams);
        rows.push(match target {
            Some(t) => check(
                what,
                format!("{per_beam:.1}"),
                format!("<= {t}"),
                per_beam <= t,
            ),
            None => row(what, format!("{per_beam:.1}")),
        });
        let extra_beams = (f.beams * f.poses).saturating_sub(h.beams * h.poses);
        if extra_beams > 0 {
            let marginal = f.insns.saturating_sub(h.insns) as f64 / extra_beams as f64;
            rows.push(row(
                format!("{label}: marginal per beam (stride 1 vs 2)"),
                format!("{marginal:.1}"),
            ));
        }
    }
    if let Some(t) = region("tempered") {
        rows.push(row(
            "tempered likelihood field: instructions per pose",
            format!("{:.1}", t.insns as f64 / t.poses as f64),
        ));
    }
    if let Some(n) = region("normalize") {
        rows.push(row(
            format!(
                "normalize_log_weights: instructions per weight ({} weights)",
                n.poses
            ),
            format!("{:.1}", n.insns as f64 / n.poses as f64),
        ));
    }

    // The largest symbols each core adds (present in it, absent from the skeleton).
    let skel_syms = symbols(&nm, skel_elf)?;
    for (program, elf) in [("size_lf", lf_elf), ("size_core", core_elf)] {
        let mut added: Vec<(u64, String)> = symbols(&nm, elf)?
            .into_iter()
            .filter(|(name, _)| !skel_syms.contains_key(name))
            .map(|(name, bytes)| (bytes, name))
            .collect();
        added.sort_by(|a, b| b.cmp(a));
        println!("\nbudgets: largest symbols of {program} that size_skeleton does not have:");
        for (bytes, name) in added.iter().take(12) {
            println!("budgets:   {bytes:>6} B  {name}");
        }
    }

    // firmware/Cargo.toml sets "s"; Cargo lets the environment override it.
    let opt_level = std::env::var("CARGO_PROFILE_RELEASE_OPT_LEVEL")
        .map(|v| format!("{v} (from CARGO_PROFILE_RELEASE_OPT_LEVEL)"))
        .unwrap_or_else(|_| "\"s\"".to_string());
    println!(
        "\nbudgets: scoring core on {FIRMWARE_TARGET} (release: LTO, 1 codegen unit, opt-level \
         {opt_level}; firmware features: {}), instructions on QEMU {machine}",
        features.unwrap_or("none")
    );
    println!("budgets: {}", run.scan);
    let w = rows.iter().map(|r| r.what.len()).max().unwrap_or(0);
    let wv = rows.iter().map(|r| r.value.len()).max().unwrap_or(0);
    let wt = rows.iter().map(|r| r.target.len()).max().unwrap_or(0);
    println!(
        "| {:<w$} | {:>wv$} | {:<wt$} | status |",
        "budget", "measured", "target"
    );
    println!(
        "|{}|{}|{}|--------|",
        "-".repeat(w + 2),
        "-".repeat(wv + 2),
        "-".repeat(wt + 2)
    );
    for r in &rows {
        println!(
            "| {:<w$} | {:>wv$} | {:<wt$} | {} |",
            r.what, r.value, r.target, r.status
        );
    }
    let failed: Vec<&str> = rows
        .iter()
        .filter(|r| r.status.starts_with("FAIL"))
        .map(|r| r.what.as_str())
        .collect();
    let over = rows.iter().filter(|r| r.status == "OVER").count();
    println!(
        "budgets: {} hard failures, {over} targets not met (OVER is reported, not fatal)",
        failed.len()
    );
    if !failed.is_empty() {
        return Err(Error::Requirement(format!(
            "hard budget failed: {}",
            failed.join("; ")
        )));
    }
    if !counted || run.stack.len() < 4 {
        return Err(Error::Output(
            "the budget program did not report every measurement".into(),
        ));
    }
    Ok(())
}
