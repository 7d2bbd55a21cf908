//! `cargo qemu` edge cases: a build ended by a signal, help, odd rustup listings, no rustup.
#![cfg(unix)]

use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

struct Dir(PathBuf);

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

fn scratch(name: &str) -> Dir {
    let dir = std::env::temp_dir().join(format!("xtask-red-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    Dir(dir)
}

fn script(dir: &Path, name: &str, body: &str) {
    let path = dir.join(name);
    fs::write(
        &path,
        format!(
            "#!/bin/sh\necho \"$@\" >> '{}'\n{body}",
            dir.join(format!("{name}.log")).display()
        ),
    )
    .unwrap();
    fs::set_permissions(&path, fs::Permissions::from_mode(0o755)).unwrap();
}

fn run(dir: &Path, args: &[&str], path_only_dir: bool, cargo_env: bool) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_xtask"));
    cmd.args(args);
    if path_only_dir {
        cmd.env("PATH", dir);
    } else {
        let mut paths = vec![dir.to_path_buf()];
        paths.extend(std::env::split_paths(
            &std::env::var_os("PATH").unwrap_or_default(),
        ));
        cmd.env("PATH", std::env::join_paths(paths).unwrap());
    }
    if cargo_env {
        cmd.env("CARGO", dir.join("cargo"));
    } else {
        cmd.env_remove("CARGO");
    }
    cmd.output().unwrap()
}

fn log(dir: &Path, tool: &str) -> String {
    fs::read_to_string(dir.join(format!("{tool}.log"))).unwrap_or_default()
}

const LISTED: &str =
    "if [ \"$1 $2 $3\" = 'target list --installed' ]; then printf 'thumbv7em-none-eabihf\\n'; fi\n";

/// A build (or QEMU under the runner) killed by a signal: the shell convention is status
/// 128 + signal (143 for SIGTERM, 130 for Ctrl-C), so a script can tell it from a firmware
/// that returned 1.
#[test]
fn a_build_killed_by_a_signal_exits_128_plus_the_signal() {
    let d = scratch("signal");
    script(&d.0, "rustup", LISTED);
    script(&d.0, "cargo", "kill -TERM $$\n");
    let out = run(&d.0, &["qemu", "demo"], false, true);
    assert_eq!(
        out.status.code(),
        Some(128 + 15),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `cargo qemu --help` / `-h` asks for the usage: it is printed and the status is 0.
#[test]
fn help_is_not_an_error() {
    let d = scratch("help");
    script(&d.0, "rustup", LISTED);
    script(&d.0, "cargo", "exit 0\n");
    for args in [&["qemu", "--help"][..], &["qemu", "-h"], &["--help"]] {
        let out = run(&d.0, args, false, true);
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        let all = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(all.contains("usage: cargo qemu <example>"), "{args:?}");
    }
    assert_eq!(log(&d.0, "cargo"), "");
}

/// A listing with trailing blanks or CR line ends still counts as installed.
#[test]
fn an_installed_target_with_odd_whitespace_is_left_alone() {
    let d = scratch("ws");
    script(
        &d.0,
        "rustup",
        "if [ \"$1 $2 $3\" = 'target list --installed' ]; then printf '  x86_64-unknown-linux-gnu\\r\\n\\tthumbv7em-none-eabihf  \\r\\n'; fi\n",
    );
    script(&d.0, "cargo", "exit 0\n");
    let out = run(&d.0, &["qemu", "demo"], false, true);
    assert!(out.status.success());
    assert_eq!(log(&d.0, "rustup"), "target list --installed\n");
}

/// Without rustup (a distribution's Rust) the build goes ahead; without `$CARGO` the
/// `cargo` on PATH is used.
#[test]
fn no_rustup_and_no_cargo_env() {
    let d = scratch("norustup");
    script(&d.0, "cargo", "exit 3\n");
    let out = run(&d.0, &["qemu", "demo", "--", "arg with space"], true, false);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        log(&d.0, "cargo"),
        "run --release --target thumbv7em-none-eabihf --example demo -- arg with space\n"
    );
}

/// No cargo at all: one line naming it, status 1.
#[test]
fn no_cargo_at_all() {
    let d = scratch("nocargo");
    let out = run(&d.0, &["qemu", "demo"], true, false);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.starts_with("cargo qemu: cannot run cargo"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}
