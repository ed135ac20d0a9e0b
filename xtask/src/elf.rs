//! What an ELF holds: its loaded sections (`llvm-size -A`), its symbols' sizes (`llvm-nm`), and
//! the lengths of a memory layout's regions.

use crate::error::{Error, Result};
use crate::process::capture;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// The real MCU layout the image must fit (a hard requirement of `cargo xtask budgets`).
pub const LAYOUT: &str = "memory-stm32f405.x";

/// Allocated sections of an ELF and their sizes, bytes (`llvm-size -A`).
pub fn sections(size: &Path, elf: &Path) -> Result<BTreeMap<String, u64>> {
    let out = capture(Command::new(size).arg("-A").arg(elf))?;
    let mut map = BTreeMap::new();
    for line in out.lines() {
        let mut f = line.split_whitespace();
        if let (Some(name), Some(bytes), Some(addr), None) =
            (f.next(), f.next(), f.next(), f.next())
        {
            // Debug sections sit at address 0 and are not loaded; keep the loaded ones.
            let loaded = addr != "0" || name == ".vector_table";
            if let (true, true, Ok(n)) = (name.starts_with('.'), loaded, bytes.parse::<u64>()) {
                map.insert(name.to_string(), n);
            }
        }
    }
    Ok(map)
}

/// `LENGTH = …` of a region of the memory layout [`LAYOUT`] (its text `layout`), bytes.
pub fn region_length(layout: &str, region: &str) -> Result<u64> {
    let line = layout
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with(region) && l.contains("LENGTH"))
        .ok_or_else(|| Error::Output(format!("{LAYOUT}: no {region} region")))?;
    let v = line
        .split("LENGTH")
        .nth(1)
        .and_then(|s| s.split('=').nth(1))
        .map(|s| s.trim().trim_end_matches([',', ';']).trim())
        .ok_or_else(|| Error::Output(format!("{LAYOUT}: cannot read `{line}`")))?;
    let (digits, mult) = match v.strip_suffix('K') {
        Some(d) => (d, 1024),
        None => match v.strip_suffix('M') {
            Some(d) => (d, 1024 * 1024),
            None => (v, 1),
        },
    };
    let n: u64 = if let Some(hex) = digits.strip_prefix("0x") {
        u64::from_str_radix(hex, 16).map_err(|e| Error::Output(format!("{LAYOUT}: `{v}`: {e}")))?
    } else {
        digits
            .parse()
            .map_err(|e| Error::Output(format!("{LAYOUT}: `{v}`: {e}")))?
    };
    Ok(n * mult)
}

/// The sizes of the sections `names` of `m`, added up.
pub fn gsec(m: &BTreeMap<String, u64>, names: &[&str]) -> u64 {
    names.iter().filter_map(|n| m.get(*n)).sum()
}

/// Code and data symbols of an ELF (`llvm-nm -S -C`), name (without the hash) → bytes.
pub fn symbols(nm: &Path, elf: &Path) -> Result<BTreeMap<String, u64>> {
    let out = capture(Command::new(nm).args(["-S", "-C", "--size-sort"]).arg(elf))?;
    let mut map = BTreeMap::new();
    for line in out.lines() {
        let mut f = line.splitn(4, ' ');
        let (Some(_), Some(size), Some(kind), Some(name)) =
            (f.next(), f.next(), f.next(), f.next())
        else {
            continue;
        };
        // t/T: code, r/R: constants, d/D/b/B: static RAM.
        if !matches!(kind, "t" | "T" | "r" | "R" | "d" | "D" | "b" | "B") {
            continue;
        }
        let Ok(bytes) = u64::from_str_radix(size, 16) else {
            continue;
        };
        let name = match name.rsplit_once("::h") {
            Some((base, hash)) if hash.len() == 16 => base,
            _ => name,
        };
        // The two programs' own items differ only by their crate name; legacy-mangled trait
        // impls keep `$LT$`-style escapes after demangling.
        let name = name
            .replace("size_core::", "<program>::")
            .replace("size_lf::", "<program>::")
            .replace("size_skeleton::", "<program>::")
            .replace("$LT$", "<")
            .replace("$GT$", ">")
            .replace("$u20$", " ")
            .replace("..", "::");
        let name = name.trim_start_matches('_');
        *map.entry(name.to_string()).or_insert(0) += bytes;
    }
    Ok(map)
}
