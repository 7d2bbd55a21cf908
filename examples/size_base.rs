//! Flash baseline for `size_*`: the driver with a running sum in place of an estimator.
//!
//! ```text
//! cargo qemu size_base
//! ```
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/mod.rs"]
mod common;
#[cfg(target_os = "none")]
#[path = "common/size.rs"]
mod size;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    size::run(0.0f32, |sum, x| *sum += x, |sum| sum / 10_000.0)
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("size_base is firmware for the Cortex-M4F: run it with `cargo qemu size_base`");
}
