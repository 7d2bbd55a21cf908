//! Bit-exact parity of host and target: the f32 and the fixed-point lattice on a seeded input
//! sequence, and the identified noise model with its intervals on a seeded Allan stream
//! (documented in `examples/common/parity.rs`), hashed to one checksum each.
//!
//! ```text
//! cargo qemu parity
//! cargo run -p imu-ar-cli --bin imu-ar -- parity
//! ```
//!
//! Both print `parity f32 <hex> fixed <hex> noise <hex>`; `.ci/run` fails when the two lines differ.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/mod.rs"]
mod common;

#[cfg(target_os = "none")]
#[path = "common/parity.rs"]
mod parity;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    match parity::checksums().zip(parity::noise_checksum()) {
        Some(((f, q), n)) => {
            defmt::info!(
                "parity f32 {=u64:016x} fixed {=u64:016x} noise {=u64:016x}",
                f,
                q,
                n
            );
            common::exit(true)
        }
        None => {
            defmt::error!("parity: a configuration or the noise fit was refused");
            common::exit(false)
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("parity is firmware for the Cortex-M4F: run it with `cargo qemu parity`");
}
