//! `cargo qemu` on a machine whose toolchain lacks the Cortex-M4F target: stand-in `rustup` and
//! `cargo` programs record what the task asks of them.
#![cfg(unix)]

use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::PathBuf;
use std::process::{Command, Output};

/// A scratch folder with stand-in `rustup` and `cargo` scripts that append their arguments to
/// `rustup.log` and `cargo.log`. `rustup target list --installed` prints `installed`;
/// the stand-in cargo exits with `cargo_status`.
struct StandIns {
    dir: PathBuf,
}

impl StandIns {
    fn new(name: &str, installed: &[&str], cargo_status: i32) -> Self {
        let dir = std::env::temp_dir().join(format!("xtask-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let listed = installed.join("\n");
        let rustup = format!(
            "#!/bin/sh\necho \"$@\" >> '{log}'\n\
             if [ \"$1 $2 $3\" = 'target list --installed' ]; then printf '%s\\n' '{listed}'; fi\n",
            log = dir.join("rustup.log").display()
        );
        let cargo = format!(
            "#!/bin/sh\necho \"$@\" >> '{log}'\nexit {cargo_status}\n",
            log = dir.join("cargo.log").display()
        );
        for (file, text) in [("rustup", rustup), ("cargo", cargo)] {
            let path = dir.join(file);
            fs::write(&path, text).unwrap();
            fs::set_permissions(&path, fs::Permissions::from_mode(0o755)).unwrap();
        }
        Self { dir }
    }

    fn run(&self, args: &[&str]) -> Output {
        let path = std::env::var_os("PATH").unwrap_or_default();
        let mut paths = vec![self.dir.clone()];
        paths.extend(std::env::split_paths(&path));
        Command::new(env!("CARGO_BIN_EXE_xtask"))
            .args(args)
            .env("PATH", std::env::join_paths(paths).unwrap())
            .env("CARGO", self.dir.join("cargo"))
            .output()
            .unwrap()
    }

    fn log(&self, tool: &str) -> String {
        fs::read_to_string(self.dir.join(format!("{tool}.log"))).unwrap_or_default()
    }
}

impl Drop for StandIns {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.dir);
    }
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_missing_target_is_added_before_the_build() {
    let s = StandIns::new("missing", &["x86_64-unknown-linux-gnu"], 0);
    let out = s.run(&["qemu", "demo"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        s.log("rustup"),
        "target list --installed\ntarget add thumbv7em-none-eabihf\n"
    );
    assert_eq!(
        s.log("cargo"),
        "run --release --target thumbv7em-none-eabihf --example demo\n"
    );
    assert!(
        stderr(&out).contains("rustup target add thumbv7em-none-eabihf"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn an_installed_target_is_left_alone() {
    let s = StandIns::new(
        "installed",
        &["thumbv7em-none-eabihf", "x86_64-unknown-linux-gnu"],
        0,
    );
    let out = s.run(&["qemu", "parity", "--features", "x"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(s.log("rustup"), "target list --installed\n");
    assert_eq!(
        s.log("cargo"),
        "run --release --target thumbv7em-none-eabihf --example parity --features x\n"
    );
}

#[test]
fn the_firmware_exit_status_is_passed_on() {
    for status in [1, 124, 127] {
        let s = StandIns::new(
            &format!("status{status}"),
            &["thumbv7em-none-eabihf"],
            status,
        );
        let out = s.run(&["qemu", "selftest"]);
        assert_eq!(out.status.code(), Some(status), "{}", stderr(&out));
    }
}

#[test]
fn no_example_name_prints_the_usage() {
    let s = StandIns::new("usage", &[], 0);
    for args in [&["qemu"][..], &[], &["qemu", "--release"], &["build"]] {
        let out = s.run(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            stderr(&out).starts_with("usage: cargo qemu <example>"),
            "{args:?}"
        );
    }
    assert_eq!(s.log("cargo"), "", "nothing is built without an example");
}

#[test]
fn a_failing_target_add_stops_before_the_build() {
    let s = StandIns::new("addfails", &[], 0);
    // A rustup whose `target add` fails (offline, say).
    let rustup = s.dir.join("rustup");
    let text = fs::read_to_string(&rustup).unwrap() + "[ \"$2\" = add ] && exit 1\nexit 0\n";
    fs::write(&rustup, text).unwrap();
    let out = s.run(&["qemu", "demo"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("`rustup target add thumbv7em-none-eabihf` failed"));
    assert_eq!(s.log("cargo"), "");
}
