//! Exact guest-instruction counts under QEMU: the repository's counting plugin
//! (`xtask/insncount/insncount.c`), built with gcc on first use into `target/insncount/`, and
//! the QEMU arguments that count between the firmware's `bench_mark_start` and
//! `bench_mark_end` markers (firmware/src/lib.rs).
//!
//! The plugin prints `insncount: region K: N instructions` for every region and
//! `insncount: total N` at exit, on QEMU's log (stderr with `-d plugin`).

use super::{capture, ensure_llvm_nm, llvm_nm, repo_root, run_to_files, Result, QEMU_TIMEOUT_S};
use std::fs;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The plugin's source, relative to the repository.
const SOURCE: &str = "xtask/insncount/insncount.c";

/// The one-line advice when the plugin cannot be built for want of a C compiler.
fn no_compiler(hint: &str) -> String {
    format!(
        "counting instructions needs gcc to build the QEMU plugin {SOURCE} \
         (Debian: apt-get install -y gcc){hint}"
    )
}

/// The built plugin: `target/insncount/libinsncount-CRC.so`, named after the CRC-32 of the
/// source so an edited plugin is always rebuilt. The compiler is `$CC`, else `gcc`. `hint` ends
/// the message when it is missing (e.g. ", or run with --no-count").
pub fn plugin(hint: &str) -> Result<PathBuf> {
    let src = repo_root().join(SOURCE);
    let text = fs::read(&src).map_err(|e| format!("{}: {e}", src.display()))?;
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&text);
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo_root().join("target"))
        .join("insncount");
    let so = dir.join(format!("libinsncount-{crc:08x}.so"));
    if so.is_file() {
        return Ok(so);
    }
    fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    // Built under a private name, then renamed: a concurrent task never loads half a file.
    let partial = dir.join(format!("libinsncount-{crc:08x}.{}.tmp", std::process::id()));
    let compiler = std::env::var_os("CC").unwrap_or_else(|| "gcc".into());
    compile(Command::new(compiler), &src, &partial, hint)?;
    fs::rename(&partial, &so).map_err(|e| format!("{}: {e}", so.display()))?;
    Ok(so)
}

/// Compiles the plugin's source `src` into the shared object `so` with `cc`.
fn compile(mut cc: Command, src: &Path, so: &Path, hint: &str) -> Result {
    cc.args(["-O2", "-Wall", "-shared", "-fPIC", "-o"])
        .arg(so)
        .arg(src);
    eprintln!("+ {}", super::show(&cc));
    let out = match cc.output() {
        Ok(out) => out,
        Err(e) if e.kind() == ErrorKind::NotFound => return Err(no_compiler(hint)),
        Err(e) => return Err(format!("cannot start the C compiler: {e}")),
    };
    if !out.status.success() {
        return Err(format!(
            "the C compiler could not build {SOURCE}:\n{}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(())
}

/// QEMU's arguments to count between the markers of `elf` with the plugin.
pub fn qemu_args(elf: &Path, hint: &str) -> Result<Vec<String>> {
    ensure_llvm_nm()?;
    let so = plugin(hint)?;
    let syms = capture(Command::new(llvm_nm()).arg(elf))?;
    let addr = |name: &str| {
        syms.lines()
            .find_map(|l| {
                let mut w = l.split_whitespace();
                let a = w.next()?;
                (w.nth(1)? == name).then(|| format!("0x{a}"))
            })
            .ok_or_else(|| format!("no symbol {name} in {}", elf.display()))
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
/// named after `name`: (exit code, stdout, stderr). The plugin's lines are on stderr.
pub fn run_counted(elf: &Path, machine: &str, name: &str) -> Result<(i32, String, String)> {
    let args = qemu_args(elf, "")?;
    run_to_files(
        Command::new("timeout")
            .args([QEMU_TIMEOUT_S, "qemu-system-arm", "-machine", machine])
            .args([
                "-nographic",
                "-semihosting-config",
                "enable=on,target=native",
                "-icount",
                "shift=0",
            ])
            .args(&args)
            .arg("-kernel")
            .arg(elf),
        name,
    )
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

/// `cargo xtask count ELF`: runs a firmware image under the counting plugin, prints what it
/// printed and the plugin's lines, and fails with the program's exit status.
pub fn count(elf: &Path, machine: &str) -> Result {
    super::ensure_qemu()?;
    let (code, out, err) = run_counted(elf, machine, "count")?;
    print!("{out}");
    eprint!("{err}");
    if region_counts(&err).is_empty() {
        return Err(format!(
            "{} reported no region: does it call bench_mark_start and bench_mark_end?",
            elf.display()
        ));
    }
    match code {
        0 => Ok(()),
        c => Err(format!(
            "{} exited {c} under QEMU ({machine})",
            elf.display()
        )),
    }
}

#[cfg(test)]
mod tests {
    use std::process::Command;

    #[test]
    fn a_missing_compiler_is_one_line_naming_the_package_and_the_way_out() {
        let dir = std::env::temp_dir();
        let err = super::compile(
            Command::new("/nonexistent/gcc"),
            &super::repo_root().join(super::SOURCE),
            &dir.join("never-built.so"),
            ", or run with --no-count",
        )
        .unwrap_err();
        assert!(!err.contains('\n'), "{err}");
        assert!(err.contains("apt-get install -y gcc"), "{err}");
        assert!(err.ends_with("--no-count"), "{err}");
    }

    #[test]
    fn the_plugin_source_compiles_without_warnings() {
        let so = std::env::temp_dir().join(format!("insncount-test-{}.so", std::process::id()));
        let mut cc = Command::new("gcc");
        cc.arg("-Werror");
        let built = super::compile(cc, &super::repo_root().join(super::SOURCE), &so, "");
        let _ = std::fs::remove_file(&so);
        built.unwrap();
    }

    #[test]
    fn region_lines_are_read_in_order_and_others_ignored() {
        let log = "insncount: region 0: 12 instructions\nnoise\n\
                   insncount: region 1: 7 instructions\ninsncount: total 99\n";
        assert_eq!(super::region_counts(log), vec![12, 7]);
    }
}
