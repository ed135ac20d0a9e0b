//! Exact guest-instruction counts under QEMU: the repository's counting plugin
//! (`xtask/insncount/insncount.c`), built with gcc on first use into `target/insncount/`, the
//! QEMU arguments that count between the firmware's `bench_mark_start` and `bench_mark_end`
//! markers (firmware/src/lib.rs), and the counts paired with the names of the regions.
//!
//! The plugin prints `insncount: region K: N instructions` for every region and
//! `insncount: total N` at exit, on QEMU's log (stderr with `-d plugin`). The firmware prints
//! `region: NAME` (`beamfield_fixtures::regions::NAME_LINE`) right before measuring each region,
//! so the K-th name printed names the K-th count ([`Regions`]).

use crate::error::{Error, Result};
use crate::process::{capture, repo_root, show, Finished};
use crate::qemu::{ensure_qemu, run_elf};
use crate::toolchain::{gcc, llvm_tool};
use beamfield_fixtures::regions::{Region, NAME_LINE};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The plugin's source, relative to the repository.
const SOURCE: &str = "xtask/insncount/insncount.c";

/// The built plugin: `target/insncount/libinsncount-CRC.so`, named after the CRC-32 of the
/// source so an edited plugin is always rebuilt. `hint` ends the message when gcc is missing
/// (e.g. ", or run with --no-count").
pub fn plugin(hint: &str) -> Result<PathBuf> {
    let src = repo_root().join(SOURCE);
    let text = fs::read(&src).map_err(|e| Error::io(&src, e))?;
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&text);
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo_root().join("target"))
        .join("insncount");
    let so = dir.join(format!("libinsncount-{crc:08x}.so"));
    if so.is_file() {
        return Ok(so);
    }
    fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    // Built under a private name, then renamed: a concurrent task never loads half a file.
    let partial = dir.join(format!("libinsncount-{crc:08x}.{}.tmp", std::process::id()));
    let mut gcc = gcc(hint, SOURCE)?;
    gcc.args(["-O2", "-Wall", "-shared", "-fPIC", "-o"])
        .arg(&partial)
        .arg(&src);
    eprintln!("+ {}", show(&gcc));
    let out = gcc
        .output()
        .map_err(|e| crate::process::spawn_error(&gcc, e))?;
    if !out.status.success() {
        return Err(Error::Host(format!(
            "gcc could not build {SOURCE}:\n{}",
            String::from_utf8_lossy(&out.stderr)
        )));
    }
    fs::rename(&partial, &so).map_err(|e| Error::io(&so, e))?;
    Ok(so)
}

/// QEMU's arguments to count between the markers of `elf` with the plugin.
pub fn qemu_args(elf: &Path, hint: &str) -> Result<Vec<String>> {
    let nm = llvm_tool("llvm-nm")?;
    let so = plugin(hint)?;
    let syms = capture(Command::new(nm).arg(elf))?;
    let addr = |name: &str| {
        syms.lines()
            .find_map(|l| {
                let mut w = l.split_whitespace();
                let a = w.next()?;
                (w.nth(1)? == name).then(|| format!("0x{a}"))
            })
            .ok_or_else(|| Error::Output(format!("no symbol {name} in {}", elf.display())))
    };
    Ok(vec![
        "-plugin".into(),
        format!(
            "{},start={},end={}",
            so.display(),
            addr("bench_mark_start")?,
            addr("bench_mark_end")?
        ),
        "-d".into(),
        "plugin".into(),
    ])
}

/// Runs `elf` on QEMU's `machine` under the counting plugin, its output captured in files
/// named after `name`. The plugin's lines are on stderr.
pub fn run_counted(elf: &Path, machine: &str, name: &str) -> Result<Finished> {
    let args = qemu_args(elf, "")?;
    run_elf(elf, machine, &args, name)
}

/// Instructions per region, in the order the plugin reported them.
pub fn region_counts(text: &str) -> Vec<u64> {
    text.lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("insncount: region ")?;
            let (_, n) = rest.split_once(": ")?;
            n.strip_suffix(" instructions")?.parse().ok()
        })
        .collect()
}

/// The counted regions of one run, each with the name the firmware printed before it.
#[derive(Debug)]
pub struct Regions(Vec<(String, u64)>);

impl Regions {
    /// Pairs the names in the program's output `stdout` with the plugin's counts in its log
    /// `stderr`, in order.
    ///
    /// # Errors
    /// When there are more names than counts or the other way round.
    pub fn read(stdout: &str, stderr: &str) -> Result<Self> {
        let names: Vec<&str> = stdout
            .lines()
            .filter_map(|l| l.strip_prefix(NAME_LINE))
            .map(str::trim)
            .collect();
        let counts = region_counts(stderr);
        if names.len() != counts.len() {
            return Err(Error::Regions(format!(
                "the firmware named {} regions, the plugin counted {}",
                names.len(),
                counts.len()
            )));
        }
        Ok(Regions(
            names.into_iter().map(String::from).zip(counts).collect(),
        ))
    }

    /// Checks that every region is one of `expected` and that each of `expected` was counted.
    ///
    /// # Errors
    /// The first name not expected, or the first expected name missing.
    pub fn expect(&self, expected: &[Region]) -> Result {
        if let Some((extra, _)) = self
            .0
            .iter()
            .find(|(n, _)| !expected.iter().any(|r| r.name == n))
        {
            return Err(Error::Regions(format!(
                "the firmware measured a region `{extra}` that is not expected (expected: {})",
                names(expected)
            )));
        }
        if let Some(missing) = expected
            .iter()
            .find(|r| !self.0.iter().any(|(n, _)| n == r.name))
        {
            return Err(Error::Regions(format!(
                "the firmware measured no region `{}` (expected: {})",
                missing.name,
                names(expected)
            )));
        }
        Ok(())
    }

    /// The count of the region `name`, which must have been measured exactly once.
    ///
    /// # Errors
    /// When it was measured never or more than once.
    pub fn once(&self, name: &str) -> Result<u64> {
        let (total, times) = self.sum(name);
        if times == 1 {
            Ok(total)
        } else {
            Err(Error::Regions(format!(
                "the region `{name}` was measured {times} times, not once"
            )))
        }
    }

    /// The counts of every measurement of the region `name`, added up, and how many there were.
    pub fn sum(&self, name: &str) -> (u64, usize) {
        self.0
            .iter()
            .filter(|(n, _)| n == name)
            .fold((0, 0), |(t, k), (_, c)| (t + c, k + 1))
    }

    /// The largest count of the region `name` (0 when it was never measured).
    pub fn max(&self, name: &str) -> u64 {
        self.0
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, c)| *c)
            .max()
            .unwrap_or(0)
    }

    /// How many regions were counted.
    pub fn len(&self) -> usize {
        self.0.len()
    }
}

/// A program's output `out` without the lines naming its regions (the counting run pairs them
/// with the counts; a reader of the report does not need them).
pub fn without_names(out: &str) -> String {
    out.lines()
        .filter(|l| !l.starts_with(NAME_LINE))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// The names of `regions`, for messages.
fn names(regions: &[Region]) -> String {
    regions
        .iter()
        .map(|r| r.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// `cargo xtask count ELF`: runs a firmware image under the counting plugin, prints what it
/// printed and the plugin's lines, and fails with the program's exit status.
pub fn count(elf: &Path, machine: &str) -> Result {
    ensure_qemu()?;
    let run = run_counted(elf, machine, "count")?;
    print!("{}", run.stdout);
    eprint!("{}", run.stderr);
    if region_counts(&run.stderr).is_empty() {
        return Err(Error::Regions(format!(
            "{} reported no region: does it call bench_mark_start and bench_mark_end?",
            elf.display()
        )));
    }
    match run.code {
        0 => Ok(()),
        c => Err(Error::Qemu(format!(
            "{} exited {c} under QEMU ({machine})",
            elf.display()
        ))),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn region_lines_are_read_in_order_and_others_ignored() {
        let log = "insncount: region 0: 12 instructions\nnoise\n\
                   insncount: region 1: 7 instructions\ninsncount: total 99\n";
        assert_eq!(super::region_counts(log), vec![12, 7]);
    }

    #[test]
    fn counts_are_taken_by_the_names_printed_before_them() {
        use super::Regions;
        use beamfield_fixtures::regions::{insns, lidar};
        let out = "region: ln\nother line\nregion: exp\n";
        let log = "insncount: region 0: 12 instructions\ninsncount: region 1: 7 instructions\n";
        let r = Regions::read(out, log).expect("paired");
        assert_eq!(r.once(insns::LN.name).ok(), Some(12));
        assert_eq!(r.once(insns::EXP.name).ok(), Some(7));
        assert!(r.once(insns::EMPTY_LOOP.name).is_err());
        assert!(r.expect(&[insns::LN, insns::EXP]).is_ok());
        // A region missing or one not expected is an error, and so is a count without a name.
        assert!(r
            .expect(&[insns::LN, insns::EXP, insns::EMPTY_LOOP])
            .is_err());
        assert!(r.expect(&[insns::LN]).is_err());
        assert!(Regions::read("region: ln\n", log).is_err());
        let out = "region: crc\nregion: crc\n";
        let r = Regions::read(out, log).expect("paired");
        assert_eq!(r.sum(lidar::CRC.name), (19, 2));
        assert!(r.once(lidar::CRC.name).is_err());
    }
}
