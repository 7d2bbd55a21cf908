//! Flash of the fixed-point lattice: `update` and `model` of a `FixedLattice<8>`
//! (`tools/bench-report.sh` subtracts `size_base`).
//!
//! ```text
//! cargo qemu size_lattice_fixed
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
    use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};

    let Ok(config) = Config::new(0.999f32, 0.01) else {
        common::exit(false)
    };
    let (Ok(fixed), Ok(channel)) = (
        FixedConfig::new(&config),
        Channel::new(0.1).and_then(|c| FixedChannel::new(&c, 4.0)),
    ) else {
        common::exit(false)
    };
    size::run(
        FixedLattice::<8>::new(&fixed, &channel),
        |lattice, x| {
            lattice.update(&fixed, x);
        },
        |lattice| lattice.model(&fixed).map_or(f32::NAN, |m| m.a()[0]),
    )
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "size_lattice_fixed is firmware for the Cortex-M4F: run it with `cargo qemu size_lattice_fixed`"
    );
}
