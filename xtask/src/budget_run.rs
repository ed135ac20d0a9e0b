//! What one run of `firmware/src/bin/budget.rs` under the counting plugin reports: the
//! instructions of each named region with its poses and beams, the stack high-water marks and
//! the sizes of the state a caller keeps (`cargo xtask budgets` makes its table from it).

use crate::error::{Error, Result};
use crate::insncount::{run_counted, Regions};
use crate::qemu::failure;
use beamfield_fixtures::regions::budget;
use std::collections::BTreeMap;
use std::path::Path;

/// One measured region of `budget.rs`: name, poses, beams per pose, instructions.
pub struct Region {
    /// Its name (`beamfield_fixtures::regions::budget`).
    pub name: String,
    /// Poses scored.
    pub poses: u64,
    /// Beams per pose.
    pub beams: u64,
    /// Instructions counted.
    pub insns: u64,
}

/// What one run of `budget.rs` under the counting plugin reported.
pub struct Run {
    /// The program's description of its scan.
    pub scan: String,
    /// The regions, in the order the program described them.
    pub regions: Vec<Region>,
    /// Stack high-water marks by call, bytes.
    pub stack: BTreeMap<String, u64>,
    /// Sizes of the values a caller keeps, bytes.
    pub state: BTreeMap<String, u64>,
}

impl Run {
    /// The region `name`, if the program measured it.
    pub fn region(&self, name: &str) -> Option<&Region> {
        self.regions.iter().find(|r| r.name == name)
    }
}

/// Reads the program's `budget: …` lines in `out` and the counts of its named regions (names in
/// `out`, counts in the plugin's log `err`).
fn parse_run(out: &str, err: &str) -> Result<Run> {
    let counted = Regions::read(out, err)?;
    counted.expect(&budget::ALL)?;
    let mut regions = Vec::new();
    let mut scan = String::new();
    let (mut stack, mut state) = (BTreeMap::new(), BTreeMap::new());
    for l in out.lines() {
        let Some(rest) = l.strip_prefix("budget: ") else {
            continue;
        };
        let bad = || Error::Output(format!("cannot read `{l}`"));
        let f: Vec<&str> = rest.split_whitespace().collect();
        match f.as_slice() {
            ["region", name, "poses", p, "beams", b] => {
                regions.push(Region {
                    name: name.to_string(),
                    poses: p.parse().map_err(|_| bad())?,
                    beams: b.parse().map_err(|_| bad())?,
                    insns: counted.once(name)?,
                });
            }
            ["stack", name, n] => {
                stack.insert(name.to_string(), n.parse().map_err(|_| bad())?);
            }
            ["scan", ..] => scan = rest.to_string(),
            ["state", name, n] => {
                state.insert(name.to_string(), n.parse().map_err(|_| bad())?);
            }
            _ => {}
        }
    }
    if regions.len() != counted.len() {
        return Err(Error::Regions(format!(
            "budget.rs described {} regions, the plugin counted {}",
            regions.len(),
            counted.len()
        )));
    }
    Ok(Run {
        scan,
        regions,
        stack,
        state,
    })
}

/// Runs `budget` under the counting plugin on QEMU's `machine` (as `cargo xtask insns` does).
pub fn run_budget(elf: &Path, machine: &str) -> Result<Run> {
    let run = run_counted(elf, machine, "budget")?;
    if run.code != 0 {
        eprint!("{}{}", run.stdout, run.stderr);
        return Err(failure(
            run.code,
            "the budget program",
            machine,
            "see its output",
        ));
    }
    for l in run.stdout.lines().filter(|l| {
        !l.starts_with("budget: ") && !l.starts_with(beamfield_fixtures::regions::NAME_LINE)
    }) {
        eprintln!("{l}");
    }
    parse_run(&run.stdout, &run.stderr)
}

#[cfg(test)]
mod tests {
    use super::parse_run;

    #[test]
    fn regions_are_described_and_counted_by_name() {
        let names = [
            "lf",
            "lf-half",
            "tempered",
            "normalize",
            "beam",
            "beam-half",
            "lf-prepared",
            "lf-prepared-half",
        ];
        let mut out = String::new();
        let mut log = String::new();
        for (k, n) in names.iter().enumerate() {
            out.push_str(&format!("budget: region {n} poses 8 beams 360\n"));
            log.push_str(&format!(
                "insncount: region {k}: {} instructions\n",
                100 + k
            ));
        }
        for n in names {
            out.push_str(&format!("region: {n}\n"));
        }
        out.push_str("budget: stack lf 512\n");
        let run = parse_run(&out, &log).expect("parsed");
        assert_eq!(run.region("tempered").map(|r| r.insns), Some(102));
        assert_eq!(run.stack.get("lf"), Some(&512));
        // A count without a name, or a name the table does not know, is an error.
        assert!(parse_run(&out, &format!("{log}insncount: region 8: 1 instructions\n")).is_err());
        let renamed = out.replace("region: beam-half", "region: beam-third");
        assert!(parse_run(&renamed, &log).is_err());
    }
}
