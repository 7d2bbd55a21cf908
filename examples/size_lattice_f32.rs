//! Flash of the f32 lattice: `update` and `model` of a `Lattice<f32, 8>` (`tools/bench-report.sh`
//! subtracts `size_base`).
//!
//! ```text
//! cargo qemu size_lattice_f32
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
    use imu_ar::recursive::{Channel, Config, Estimator, Lattice};

    let (Ok(config), Ok(channel)) = (Config::new(0.999f32, 0.01), Channel::new(0.1)) else {
        common::exit(false)
    };
    size::run(
        Lattice::<f32, 8>::new(&config, &channel),
        |lattice, x| {
            lattice.update(&config, x);
        },
        |lattice| lattice.model(&config).map_or(f32::NAN, |m| m.a()[0]),
    )
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "size_lattice_f32 is firmware for the Cortex-M4F: run it with `cargo qemu size_lattice_f32`"
    );
}
