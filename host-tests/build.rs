//! Finds the real IMU records (`../shared/data/imu` beside the repository, or the folder named
//! by `IMU_AR_DATA`, relative to the repository root) and, when they are there, sets
//! `cfg(imu_ar_data)` and `IMU_AR_DATA_DIR` for the tests. Without them the tests that read
//! the records are ignored, so `cargo test` reports them as ignored rather than passed.
//!
//! The build script of `imu-ar-host` and of `imu-ar-cli` (whose manifest names this file): both
//! sit one folder below the repository root.

use std::path::{Path, PathBuf};

fn main() {
    println!("cargo::rustc-check-cfg=cfg(imu_ar_data)");
    println!("cargo::rerun-if-env-changed=IMU_AR_DATA");
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let root = manifest.parent().unwrap_or(&manifest).to_path_buf();
    let dir = match std::env::var_os("IMU_AR_DATA") {
        Some(d) => root.join(d),
        None => root.join("../shared/data/imu"),
    };
    // Watch the folder, or its nearest existing ancestor so that its creation is noticed.
    let watched: &Path = dir
        .ancestors()
        .find(|p| p.is_dir())
        .unwrap_or(root.as_path());
    println!("cargo::rerun-if-changed={}", watched.display());
    if dir.is_dir() {
        let dir = dir.canonicalize().unwrap_or(dir);
        println!("cargo::rustc-cfg=imu_ar_data");
        println!("cargo::rustc-env=IMU_AR_DATA_DIR={}", dir.display());
    }
}
