//! Running commands: echoed, checked, captured, or with their output sent to files.

use crate::error::{Error, Result};
use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The repository's root (the parent of `xtask/`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// The cargo that runs this task (`$CARGO`), else `cargo`.
pub fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

/// The command line of `cmd`, for messages.
pub fn show(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

/// The error for `cmd` that could not be started.
pub fn spawn_error(cmd: &Command, source: std::io::Error) -> Error {
    Error::Spawn {
        command: show(cmd),
        source,
    }
}

/// Runs a command, echoing it, and fails unless it exits 0.
pub fn run(cmd: &mut Command) -> Result {
    eprintln!("+ {}", show(cmd));
    let status = cmd.status().map_err(|e| spawn_error(cmd, e))?;
    if status.success() {
        Ok(())
    } else {
        Err(Error::Command {
            command: show(cmd),
            status,
        })
    }
}

/// Runs a command and returns its stdout (stderr passes through).
pub fn capture(cmd: &mut Command) -> Result<String> {
    let out = cmd
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| spawn_error(cmd, e))?;
    if !out.status.success() {
        return Err(Error::Command {
            command: show(cmd),
            status: out.status,
        });
    }
    String::from_utf8(out.stdout)
        .map_err(|e| Error::Output(format!("`{}` printed no UTF-8: {e}", show(cmd))))
}

/// Whether `program --version` runs and exits 0 (a tool that is there and works).
pub fn answers(program: &Path) -> bool {
    Command::new(program)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// A scratch directory for QEMU's output files (never a pipe: docs/firmware.md).
pub fn scratch() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("beamfield-xtask-{}", std::process::id()));
    fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    Ok(dir)
}

/// What a program run with its output in files printed.
pub struct Finished {
    /// Its exit code (a signal reads as 128 + 9, like a shell reports a kill).
    pub code: i32,
    /// Its stdout.
    pub stdout: String,
    /// Its stderr.
    pub stderr: String,
}

/// Runs `cmd` with stdout and stderr sent to files named after `name`.
pub fn run_to_files(cmd: &mut Command, name: &str) -> Result<Finished> {
    let dir = scratch()?;
    let (out_p, err_p) = (
        dir.join(format!("{name}.stdout")),
        dir.join(format!("{name}.stderr")),
    );
    let file = |p: &Path| File::create(p).map_err(|e| Error::io(p, e));
    cmd.stdin(Stdio::null())
        .stdout(file(&out_p)?)
        .stderr(file(&err_p)?);
    eprintln!("+ {} >{} 2>{}", show(cmd), out_p.display(), err_p.display());
    let status = cmd.status().map_err(|e| spawn_error(cmd, e))?;
    let read = |p: &Path| fs::read_to_string(p).unwrap_or_default();
    let (stdout, stderr) = (read(&out_p), read(&err_p));
    let _ = fs::remove_dir_all(&dir);
    Ok(Finished {
        code: status.code().unwrap_or(137),
        stdout,
        stderr,
    })
}

#[cfg(test)]
mod tests {
    use super::repo_root;

    /// A cold `cargo xtask …` compiles xtask and its dependencies before the task runs; with
    /// `--quiet` in the alias that took minutes without a line of output.
    #[test]
    fn the_xtask_alias_lets_cargo_say_what_it_builds() {
        let path = repo_root().join(".cargo/config.toml");
        let config = std::fs::read_to_string(&path).unwrap();
        let alias = config
            .lines()
            .find(|l| l.trim_start().starts_with("xtask ="))
            .unwrap_or_else(|| panic!("no xtask alias in {}", path.display()));
        assert!(alias.contains("--package xtask"), "{alias}");
        assert!(
            !alias.contains("--quiet") && !alias.contains(" -q"),
            "the alias silences cargo: {alias}"
        );
    }
}
