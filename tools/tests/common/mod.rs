//! Shared by the command-line tests (`mod common;`): the binary under test, and a run that must
//! succeed and print JSON. Not every test file uses both.
#![allow(dead_code)]

use std::process::Command;

/// The `beamfield` binary cargo built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beamfield"))
}

/// Runs `cmd`, which must exit with status 0 (the assertion shows its stderr otherwise), and
/// parses its standard output as JSON.
pub fn run_json(cmd: &mut Command) -> serde_json::Value {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Address space the bounded runs get (`ulimit -v`, KiB): 1 GiB. The tool needs a few MiB for
/// hostile inputs; before the limits, such inputs allocated 2–4 GiB and aborted.
pub const MEMORY_LIMIT_KIB: u64 = 1 << 20;

/// Kill timeout of the bounded runs. Not a timing assertion: a run that has not ended by then
/// is taken as a hang (reading a FIFO or `/dev/zero` forever) and fails the test.
pub const KILL_AFTER: std::time::Duration = std::time::Duration::from_secs(300);

/// Runs the `beamfield` binary with `args` under [`MEMORY_LIMIT_KIB`] of address space, with
/// standard input from `stdin` (a path; none: empty), killed after [`KILL_AFTER`].
pub fn run_bounded<S: AsRef<std::ffi::OsStr>>(
    args: &[S],
    stdin: Option<&std::path::Path>,
) -> std::process::Output {
    use std::io::Read;
    use std::process::Stdio;
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg("ulimit -v \"$1\" && shift && exec \"$@\"")
        .arg("sh")
        .arg(MEMORY_LIMIT_KIB.to_string())
        .arg(env!("CARGO_BIN_EXE_beamfield"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    match stdin {
        Some(p) => cmd.stdin(std::fs::File::open(p).unwrap()),
        None => cmd.stdin(Stdio::null()),
    };
    let mut child = cmd.spawn().unwrap();
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut v = Vec::new();
            let _ = r.read_to_end(&mut v);
            v
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > KILL_AFTER {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "beamfield {:?} still running after {KILL_AFTER:?}: a hang",
                args.iter()
                    .map(|a| a.as_ref().to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    std::process::Output {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    }
}

/// The one line of standard error of a failed run (the assertion shows it otherwise): exactly
/// one line, ending in a newline, without a control byte.
pub fn one_line_error(out: &std::process::Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(err.matches('\n').count(), 1, "not one line: {err:?}");
    assert!(err.ends_with('\n'), "{err:?}");
    assert!(
        !err.trim_end().chars().any(char::is_control),
        "control character in {err:?}"
    );
    err.trim_end().to_string()
}
