//! `cargo xtask insns`: instructions per beam, pose and byte of the scoring paths and the LiDAR
//! decoders (firmware/src/bin/insns.rs) under the QEMU counting plugin, by region name.

use crate::cross::build_firmware;
use crate::error::{Error, Result};
use crate::insncount::{run_counted, without_names, Regions};
use crate::qemu::ensure_qemu;
use crate::toolchain::FIRMWARE_TARGET;
use beamfield_fixtures::regions::insns::{self, *};
use beamfield_fixtures::regions::Region;
use std::collections::BTreeMap;

/// Beams per scan of the synthetic regions (the first four) in `firmware/src/bin/insns.rs`.
const INSNS_BEAMS: u64 = 360;

/// The divisor of each region, by name, from the program's `insns divisor: NAME N` lines.
fn divisors(out: &str) -> Result<BTreeMap<String, u64>> {
    let mut map = BTreeMap::new();
    for l in out.lines() {
        let Some(rest) = l.strip_prefix(insns::DIVISOR_LINE) else {
            continue;
        };
        let parsed = rest
            .split_once(' ')
            .and_then(|(n, d)| Some((n.to_string(), d.trim().parse::<u64>().ok()?)));
        match parsed {
            Some((name, d)) if d > 0 => {
                map.insert(name, d);
            }
            _ => return Err(Error::Output(format!("cannot read the divisor line `{l}`"))),
        }
    }
    Ok(map)
}

/// One region's count and divisor.
struct Measured {
    count: u64,
    divisor: u64,
}

impl Measured {
    fn ratio(&self) -> f64 {
        self.count as f64 / self.divisor as f64
    }
}

/// `cargo xtask insns` on QEMU's `machine`.
pub fn insns(machine: &str) -> Result {
    ensure_qemu()?;
    // The tiled regions read a tiled blob: one build with the tiled reader measures both
    // encodings.
    let elves = build_firmware(true, Some("tiled"))?;
    let elf = elves
        .get("insns")
        .ok_or_else(|| Error::Output("the firmware has no `insns` program".into()))?;
    let run = run_counted(elf, machine, "insns")?;
    print!("{}", without_names(&run.stdout));
    if run.code != 0 {
        eprint!("{}", run.stderr);
        return Err(Error::Qemu(format!("the counting run exited {}", run.code)));
    }
    let regions = Regions::read(&run.stdout, &run.stderr)?;
    regions.expect(&insns::ALL)?;
    let divisors = divisors(&run.stdout)?;
    let mut m = BTreeMap::new();
    for r in &insns::ALL {
        let divisor = *divisors.get(r.name).ok_or_else(|| {
            Error::Output(format!("the program printed no divisor for `{}`", r.name))
        })?;
        m.insert(
            r.name,
            Measured {
                count: regions.once(r.name)?,
                divisor,
            },
        );
    }
    let get = |r: &Region| &m[r.name];
    let per_beam = |n: u64| n as f64 / INSNS_BEAMS as f64;
    println!(
        "\ninstructions on {machine} ({FIRMWARE_TARGET}, release); regions 0-3: {INSNS_BEAMS} synthetic beams; 4-9: Intel map and real scans; 10-11: the same map tiled; 12-17: LiDAR streams of the real scans:"
    );
    println!(
        "{:<3} {:<34} {:>12} {:>10} {:>10} per",
        "#", "region", "total", "divisor", "ratio"
    );
    for (i, r) in insns::ALL.iter().enumerate() {
        let x = get(r);
        println!(
            "{i:<3} {:<34} {:>12} {:>10} {:>10.1} {}",
            r.what,
            x.count,
            x.divisor,
            x.ratio(),
            r.per
        );
    }
    let (prepared, no_beams) = (get(&LF_PREPARED), get(&LF_PREPARED_NO_BEAMS));
    let per_beam_prepared =
        (prepared.count as f64 - no_beams.count as f64) / prepared.divisor as f64;
    println!(
        "likelihood field, prepared: {:.1} instructions per beam ({:.1} with the per-pose work of {:.0} spread over {:.1} beams); per-pose path: {:.1} per beam ({:.1}x); empty loop over the endpoints: {:.1}",
        per_beam_prepared,
        prepared.ratio(),
        no_beams.ratio(),
        prepared.divisor as f64 / no_beams.divisor as f64,
        get(&LF_PER_POSE).ratio(),
        get(&LF_PER_POSE).count as f64 / prepared.count as f64,
        get(&EMPTY_PREPARED).ratio()
    );
    let (tiled, tiled_no_beams) = (get(&LF_PREPARED_TILED), get(&LF_PREPARED_NO_BEAMS_TILED));
    let tiled_per_beam = tiled.count as f64 - tiled_no_beams.count as f64;
    println!(
        "likelihood field, prepared, tiled blob (encoding 2, same codes): {:.1} instructions per beam ({:.1} with the per-pose work), {:.2}x the raw blob's {:.1}",
        tiled_per_beam / tiled.divisor as f64,
        tiled.ratio(),
        tiled_per_beam / (prepared.count as f64 - no_beams.count as f64),
        per_beam_prepared,
    );
    let (empty, ln, mixture) = (
        get(&EMPTY_LOOP).count,
        get(&LN).count,
        get(&BEAM_MIXTURE).count,
    );
    println!(
        "beam mixture: {:.1} instructions per beam ({:.1} above the empty loop; {:.2}x one ln per beam)",
        per_beam(mixture),
        per_beam(mixture.saturating_sub(empty)),
        mixture as f64 / ln as f64
    );
    println!(
        "beam model with on-device ray casting (real Intel map and scans): {:.1} instructions per beam (the mixture alone, given z*, on the synthetic scan: {:.1})",
        get(&BEAM_RAY_CAST).ratio(),
        per_beam(mixture)
    );
    println!(
        "LiDAR streams, instructions per received byte: LD06 decode {:.1}, LD06 decode + assembly {:.1} ({:.1}x the empty byte loop of {:.1}), RPLIDAR {:.1}, XV-11 {:.1}, YDLIDAR {:.1}",
        get(&LD06_DECODE).ratio(),
        get(&LD06_ASSEMBLE).ratio(),
        get(&LD06_ASSEMBLE).ratio() / get(&EMPTY_BYTES).ratio(),
        get(&EMPTY_BYTES).ratio(),
        get(&RPLIDAR_ASSEMBLE).ratio(),
        get(&XV11_ASSEMBLE).ratio(),
        get(&YDLIDAR_ASSEMBLE).ratio()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::divisors;

    #[test]
    fn divisors_are_read_by_name_and_a_zero_or_garbled_one_is_an_error() {
        let out = "insns divisor: ln 360\nnoise\ninsns divisor: lf-prepared 4096\n";
        let d = divisors(out).expect("read");
        assert_eq!(d.get("ln"), Some(&360));
        assert_eq!(d.get("lf-prepared"), Some(&4096));
        assert!(divisors("insns divisor: ln 0\n").is_err());
        assert!(divisors("insns divisor: ln x\n").is_err());
    }
}
