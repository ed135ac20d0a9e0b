//! `cargo xtask track` and `cargo xtask track-assets`: the localizer on the device
//! (`firmware/src/bin/track.rs`) under QEMU, recomputed on the host with the same library code
//! and the same plan (`fixtures/src/track_plan.rs`, shared word for word), and required to match
//! bit for bit; and the regeneration of its input asset.

use crate::cross::build_program;
use crate::demo::build_and_run;
use crate::elf::sections;
use crate::error::{Error, Result};
use crate::insncount::{run_counted, Regions};
use crate::process::{cargo, repo_root, run, Finished};
use crate::qemu::{failure, Board};
use crate::report::{estimate_bits, readable, same_bits, unexpected_report, Items};
use crate::toolchain::llvm_tool;
use beamfield::link;
use beamfield::mcl::Particles;
use beamfield_fixtures::regions::track as regions;
use beamfield_fixtures::report::{track_estimate, Report, TrackStep, TrackSummary};
use beamfield_fixtures::track_plan::{self, Summary, PARTICLES};
use track_plan::asset::{MAX_RANGE_M, ODOM_ALPHA, SEED, TRACK};

/// Translation RMSE over the segment the run must stay under, metres. `beamfield track
/// --field firmware/assets/intel.bin --scans 90 --seeds 10` gives 4.00 / 4.91 / 6.79 cm
/// (min / median / max; seed 1, the device's, has 5.16): 8 cm leaves room for a change of the
/// library that moves the numbers a little, and fails a filter that loses the robot at a corner.
pub const MAX_RMSE_M: f64 = 0.08;
/// Heading RMSE bound, degrees (the same ten seeds: 0.39 / 0.46 / 1.12°).
pub const MAX_HEADING_RMSE_DEG: f64 = 2.0;
/// No estimate may be farther than this from the logged pose, metres (`beamfield track`'s
/// "lost"; the ten seeds' largest error: 0.097 / 0.144 / 0.289 m).
pub const LOST_M: f64 = 0.5;

/// What the host computes for one update: the estimate frame's message and the step report
/// the device must send.
struct HostStep {
    estimate: link::Estimate,
    step: Report,
}

/// The host's run of the plan: every update's estimate and report, and the summary.
fn host_run() -> Result<(Vec<HostStep>, Summary)> {
    let blob_path = repo_root().join("firmware/assets/intel.bin");
    let blob = std::fs::read(&blob_path).map_err(|e| Error::io(&blob_path, e))?;
    let mut store: Box<Particles<PARTICLES>> = Box::default();
    let mut steps = Vec::new();
    let sum = track_plan::run(
        &mut store,
        &blob,
        &TRACK,
        MAX_RANGE_M,
        ODOM_ALPHA,
        SEED,
        |_| {},
        |s| {
            let log_index = TRACK.get(s.k).map_or(0, |t| t.log_index);
            steps.push(HostStep {
                estimate: track_estimate(s),
                step: Report::TrackStep(TrackStep::of(s, log_index)),
            });
        },
    )
    .map_err(|e| Error::Host(format!("host run: {e}")))?;
    Ok((steps, sum))
}

/// Checks the device's data in its output `out` against the host's run: per update, its
/// `Estimate` frame (sequence number, pose, covariance, ESS, flags) and its `TrackStep` report
/// (scan, particle hash, skipped, errors), then the `TrackSummary` (RMSE, final and largest
/// error, resamplings), all bit for bit, and nothing more; then the tracking bounds. Returns
/// the summary lines.
///
/// # Errors
/// The first difference ([`Error::Mismatch`]), a data line that does not decode, one missing or
/// one more ([`Error::Report`]), or a bound not met.
pub fn check(out: &str) -> Result<Vec<String>> {
    let (host, sum) = host_run()?;
    let mut items = Items::new(out)?;
    for (k, h) in host.iter().enumerate() {
        let what = format!("the Estimate frame of update {k}");
        let (seq, e) = items.estimate(&what)?;
        if usize::from(seq) != k || estimate_bits(&e) != estimate_bits(&h.estimate) {
            return Err(Error::Mismatch(format!(
                "update {k}: the device's estimate differs from the host's (bit patterns: \
                 timestamp, x, y, θ, covariance, ESS, flags, quality state and score):\n  \
                 device: seq {seq} {:08x?}\n  host:   seq {k} {:08x?}",
                estimate_bits(&e),
                estimate_bits(&h.estimate)
            )));
        }
        let what = format!("the TrackStep report of update {k}");
        let r = items.report(&what)?;
        if !matches!(r, Report::TrackStep(_)) {
            return Err(unexpected_report(&what, &r));
        }
        if !same_bits(&r, &h.step) {
            return Err(Error::Mismatch(format!(
                "update {k}: the device and the host differ:\n  device: {r:?}\n  host:   {:?}",
                h.step
            )));
        }
    }
    let what = "the TrackSummary report";
    let r = items.report(what)?;
    let want = Report::TrackSummary(TrackSummary::of(&sum));
    if !matches!(r, Report::TrackSummary(_)) {
        return Err(unexpected_report(what, &r));
    }
    if !same_bits(&r, &want) {
        return Err(Error::Mismatch(format!(
            "the summaries differ:\n  device: {r:?}\n  host:   {want:?}"
        )));
    }
    items.end()?;
    let mut report = vec![format!(
        "host reference: {} updates recomputed on the host are bit-identical to the device's \
         reports, decoded from its data (each Estimate frame's x, y, θ, covariance and ESS, a \
         hash of all {PARTICLES} particles' poses and weights, the errors, and the summary's \
         RMSE, final and largest errors)",
        host.len()
    )];
    let rmse_cm = sum.trans_rmse_m * 100.0;
    if !(sum.trans_rmse_m <= MAX_RMSE_M
        && sum.heading_rmse_deg <= MAX_HEADING_RMSE_DEG
        && sum.max_trans_m <= LOST_M)
    {
        return Err(Error::Requirement(format!(
            "tracking: RMSE {rmse_cm:.2} cm, {:.3}°, largest error {:.3} m: over the bounds \
             ({:.0} cm, {MAX_HEADING_RMSE_DEG}°, {LOST_M} m)",
            sum.heading_rmse_deg,
            sum.max_trans_m,
            MAX_RMSE_M * 100.0
        )));
    }
    report.push(format!(
        "tracking: RMSE {rmse_cm:.2} cm and {:.3}° over the segment (bounds {:.0} cm, \
         {MAX_HEADING_RMSE_DEG}°), largest error {:.3} m (lost above {LOST_M} m), final error \
         {:.2} cm {:.2}°",
        sum.heading_rmse_deg,
        MAX_RMSE_M * 100.0,
        sum.max_trans_m,
        sum.final_err.0 * 100.0,
        sum.final_err.1
    ));
    Ok(report)
}

/// Runs the track firmware under QEMU on `board`, prints its report, and checks it against the
/// host's recomputation.
pub fn track(board: Board) -> Result {
    crate::qemu::ensure_qemu()?;
    let machine = board.machine();
    let Finished {
        code,
        stdout: out,
        stderr: err,
    } = build_and_run(board, "track", &[])?;
    print!("{}", readable(&out));
    eprint!("{err}");
    match code {
        0 => {
            for line in check(&out)? {
                println!("{line}");
            }
            Ok(())
        }
        c => Err(failure(c, "the track", machine, "its input was rejected")),
    }
}

/// Instructions per particle per update from the counting plugin's regions of the track
/// program, by name: per scan the prediction (none for the first), the scoring alone, the whole
/// update. Returns `(motion, scoring alone, update with scoring)` averaged over the scans, per
/// particle.
fn per_particle(counted: &Regions) -> Result<(f64, f64, f64)> {
    let scans = TRACK.len();
    counted.expect(&regions::ALL)?;
    let (motion, predictions) = counted.sum(regions::PREDICT.name);
    let (score, scorings) = counted.sum(regions::SCORING.name);
    let (update, updates) = counted.sum(regions::UPDATE.name);
    if (predictions, scorings, updates) != (scans - 1, scans, scans) {
        return Err(Error::Regions(format!(
            "expected {} predictions and {scans} scorings and updates for {scans} scans, the \
             firmware measured {predictions}, {scorings} and {updates}",
            scans - 1
        )));
    }
    let p = PARTICLES as f64;
    Ok((
        motion as f64 / ((scans - 1) as f64 * p),
        score as f64 / (scans as f64 * p),
        update as f64 / (scans as f64 * p),
    ))
}

/// Runs the track program under QEMU's counting plugin on `board`, checks its output against
/// the host as [`track`] does, and prints the instructions per particle per update (scoring
/// included and excluded) and the program's RAM (`.data`, `.bss`, `.uninit` by `llvm-size`).
pub fn track_insns(board: Board) -> Result {
    crate::qemu::ensure_qemu()?;
    let elf = build_program(board, "track", &[])?;
    let run = run_counted(&elf, board.machine(), "track-insns")?;
    if run.code != 0 {
        print!("{}", run.stdout);
        eprint!("{}", run.stderr);
        return Err(failure(
            run.code,
            "the counting run",
            board.machine(),
            "see its output",
        ));
    }
    for line in check(&run.stdout)? {
        println!("{line}");
    }
    let (motion, score, update) = per_particle(&Regions::read(&run.stdout, &run.stderr)?)?;
    let beams = track_plan::BEAMS as f64;
    println!(
        "instructions per particle per update ({} scans, {PARTICLES} particles, {}):",
        TRACK.len(),
        board.machine()
    );
    let row = |what: &str, n: f64, note: &str| println!("  {what:<50} {n:8.1}{note}");
    row("motion model sample (predict)", motion, "");
    row(
        &format!("scoring alone (prepare + {beams} beams)"),
        score,
        &format!("  ({:.2} per beam slot)", score / beams),
    );
    row(
        "update (scoring, weights, estimate, resampling)",
        update,
        "",
    );
    row(
        "filter overhead (predict + update - scoring)",
        motion + update - score,
        "",
    );
    row("everything (predict + update)", motion + update, "");
    let size = llvm_tool("llvm-size")?;
    let secs = sections(&size, &elf)?;
    let get = |n: &str| secs.get(n).copied().unwrap_or(0);
    let particles = core::mem::size_of::<Particles<PARTICLES>>();
    println!(
        "RAM: .data {} + .bss {} + .uninit {} bytes (Particles<{PARTICLES}> is {particles} bytes, {} per particle); flash: .text {} + .rodata {} bytes",
        get(".data"),
        get(".bss"),
        get(".uninit"),
        particles / PARTICLES,
        get(".text"),
        get(".rodata"),
    );
    Ok(())
}

/// Regenerates `fixtures/assets/track.rs` from the Intel lab log beside the repository.
pub fn track_assets() -> Result {
    let root = repo_root();
    run(cargo().current_dir(&root).args([
        "run",
        "--release",
        "-p",
        "beamfield-tools",
        "--example",
        "track_assets",
        "--",
        "data/laser_intel_lab/intel-corrected.log",
        "fixtures/assets/track.rs",
    ]))
}

#[cfg(test)]
mod tests {
    use super::{check, host_run, Report, TrackSummary};
    use crate::error::{Error, ReportFault};
    use crate::report::{frame_line, report_line};
    use beamfield::link::Message;
    use beamfield_fixtures::report::TrackStep;

    #[test]
    fn a_changed_bit_or_a_missing_or_extra_report_fails_the_check() {
        let (host, sum) = host_run().expect("host run");
        let summary = Report::TrackSummary(TrackSummary::of(&sum));
        let lines = |steps: &[(Message, Report)], last: &Report| -> String {
            let mut out: Vec<String> = Vec::new();
            for (k, (m, r)) in steps.iter().enumerate() {
                out.push(frame_line(k as u16, m));
                out.push(report_line(r));
                out.push(format!("update {k}: words for a person"));
            }
            out.push(report_line(last));
            out.join("\n")
        };
        let steps: Vec<(Message, Report)> = host
            .iter()
            .map(|h| (Message::Estimate(h.estimate), h.step))
            .collect();
        assert!(check(&lines(&steps, &summary)).is_ok());
        // One bit of one particle hash.
        let mut flipped = steps.clone();
        if let Report::TrackStep(s) = &mut flipped[40].1 {
            s.particles_hash ^= 1;
        }
        assert!(matches!(
            check(&lines(&flipped, &summary)),
            Err(Error::Mismatch(_))
        ));
        // One bit of one covariance entry (kept symmetric, so that it encodes).
        let mut cov = steps.clone();
        if let Message::Estimate(e) = &mut cov[7].0 {
            let v = f32::from_bits(e.covariance[0][0].to_bits() ^ 1);
            e.covariance[0][0] = v;
        }
        assert!(matches!(
            check(&lines(&cov, &summary)),
            Err(Error::Mismatch(_))
        ));
        // One RMSE bit.
        let mut last = summary;
        if let Report::TrackSummary(s) = &mut last {
            s.trans_rmse_m = f64::from_bits(s.trans_rmse_m.to_bits() ^ 1);
        }
        assert!(matches!(
            check(&lines(&steps, &last)),
            Err(Error::Mismatch(_))
        ));
        // An update's data missing (the sequence numbers then have no gap, but one is short).
        assert!(matches!(
            check(&lines(&steps[..89], &summary)),
            Err(Error::Report(ReportFault::Unexpected { .. }))
        ));
        // The summary missing, one report more, a report of the wrong kind.
        let all = lines(&steps, &summary);
        let without_summary = all.rsplit_once('\n').map(|(a, _)| a).unwrap();
        assert!(matches!(
            check(without_summary),
            Err(Error::Report(ReportFault::Missing { .. }))
        ));
        assert!(matches!(
            check(&format!("{all}\n{}", report_line(&summary))),
            Err(Error::Report(ReportFault::Unexpected { .. }))
        ));
        let wrong_kind = Report::TrackStep(TrackStep {
            update: 90,
            log_index: 0,
            particles_hash: 0,
            skipped: false,
            trans_err_m: 0.0,
            heading_err_deg: 0.0,
        });
        assert!(matches!(
            check(&lines(&steps, &wrong_kind)),
            Err(Error::Report(ReportFault::Unexpected { .. }))
        ));
    }
}
