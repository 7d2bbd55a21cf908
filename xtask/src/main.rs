//! `cargo qemu <example> [cargo run options]`: builds a firmware example for the Cortex-M4F and
//! runs it on QEMU's emulated `mps2-an386` board (`.cargo/config.toml` makes `cargo qemu` run
//! this program).
//!
//! rustup installs the targets of `rust-toolchain.toml` only when it installs the toolchain, so
//! a machine that already had the pinned toolchain lacks `thumbv7em-none-eabihf` and the build
//! fails with "can't find crate for `core`". This program first adds the target where rustup
//! says it is missing, then runs
//! `cargo run --release --target thumbv7em-none-eabihf --example <example> [options]`, whose
//! runner `tools/qemu-run.sh` installs `qemu-system-arm` and `defmt-print` when they are
//! missing. The exit status is the firmware's (through the runner).
//!
//! `rustup` and `cargo` are found on `PATH` (`cargo` as `$CARGO` first, which cargo sets).

use std::env;
use std::ffi::OsString;
use std::process::{Command, ExitCode};

/// The Cortex-M4F/M7 target the firmware examples are built for.
const TARGET: &str = "thumbv7em-none-eabihf";

const USAGE: &str = "usage: cargo qemu <example> [cargo run options]
  builds examples/<example>.rs for thumbv7em-none-eabihf and runs it on QEMU (mps2-an386);
  examples: demo, bench, parity, nopanic, selftest";

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    match args.split_first() {
        Some((task, rest)) if task == "qemu" => match rest.split_first() {
            Some((help, _)) if help == "-h" || help == "--help" => help_text(),
            Some((example, options)) if !example.starts_with('-') => qemu(example, options),
            _ => usage(),
        },
        Some((help, _)) if help == "-h" || help == "--help" => help_text(),
        _ => usage(),
    }
}

/// Help asked for: the usage on stdout, status 0.
fn help_text() -> ExitCode {
    println!("{USAGE}");
    ExitCode::SUCCESS
}

fn usage() -> ExitCode {
    eprintln!("{USAGE}");
    ExitCode::from(2)
}

/// Adds the target if it is missing, then builds and runs `example`.
fn qemu(example: &str, options: &[String]) -> ExitCode {
    if let Err(e) = ensure_target() {
        eprintln!("cargo qemu: {e}");
        return ExitCode::from(1);
    }
    let cargo = env::var_os("CARGO").unwrap_or_else(|| OsString::from("cargo"));
    let status = Command::new(&cargo)
        .args(["run", "--release", "--target", TARGET, "--example", example])
        .args(options)
        .status();
    match status {
        Ok(s) => ExitCode::from(exit_code(s)),
        Err(e) => {
            eprintln!("cargo qemu: cannot run {}: {e}", cargo.to_string_lossy());
            ExitCode::from(1)
        }
    }
}

/// Installs the target with rustup when rustup lists it as missing. Without rustup (a
/// distribution's Rust), the build itself says whether the target's `core` is there.
fn ensure_target() -> Result<(), String> {
    let listed = match Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
    {
        Ok(out) if out.status.success() => out.stdout,
        Ok(out) => {
            return Err(format!(
                "`rustup target list --installed` failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        Err(_) => return Ok(()),
    };
    if String::from_utf8_lossy(&listed)
        .lines()
        .any(|l| l.trim() == TARGET)
    {
        return Ok(());
    }
    eprintln!(
        "cargo qemu: the {TARGET} target is missing; installing it: rustup target add {TARGET}"
    );
    let added = Command::new("rustup")
        .args(["target", "add", TARGET])
        .status()
        .map_err(|e| format!("cannot run rustup: {e}"))?;
    if added.success() {
        Ok(())
    } else {
        Err(format!("`rustup target add {TARGET}` failed ({added})"))
    }
}

/// The status to exit with: the child's, or `128 + n` for a child ended by signal `n` (the
/// shell's convention), with a line saying so.
fn exit_code(status: std::process::ExitStatus) -> u8 {
    if let Some(code) = status.code() {
        return u8::try_from(code).unwrap_or(1);
    }
    #[cfg(unix)]
    if let Some(signal) = std::os::unix::process::ExitStatusExt::signal(&status) {
        eprintln!("cargo qemu: the build or run was ended by signal {signal}");
        return u8::try_from(128 + signal).unwrap_or(1);
    }
    1
}
