//! `imu-ar parity`: the checksums of the f32 and fixed-point lattices on the seeded parity
//! sequence and of the identified noise model on the seeded Allan stream, to compare with `cargo qemu parity` (bit-identical results on host and target).

use serde::Serialize;

use crate::error::Fail;
use crate::output::Output;

/// The parity run shared with the `parity` firmware (the same file, compiled for the host).
#[path = "../../examples/common/parity.rs"]
mod shared;

/// The two checksums of the parity run.
#[derive(Serialize)]
pub struct Checksums {
    /// Of the f32 lattice.
    pub f32: u64,
    /// Of the fixed-point lattice.
    pub fixed: u64,
    /// Of the identified noise model and its intervals.
    pub noise: u64,
}

impl Output for Checksums {
    /// The line the firmware prints.
    fn text(&self) -> String {
        format!(
            "parity f32 {:016x} fixed {:016x} noise {:016x}\n",
            self.f32, self.fixed, self.noise
        )
    }
}

/// The lattices' input sequence of the parity run (`SAMPLES` samples, every 997th NaN), for
/// replaying it through the estimators elsewhere (the Python package's tests).
pub fn input() -> Result<Vec<f32>, Fail> {
    shared::input()
        .map(Iterator::collect)
        .ok_or_else(|| Fail("parity run refused".into()))
}

/// Runs the parity sequence through both lattices.
pub fn run() -> Result<Checksums, Fail> {
    let (f32, fixed) = shared::checksums().ok_or_else(|| Fail("parity run refused".into()))?;
    let noise = shared::noise_checksum().ok_or_else(|| Fail("parity noise fit failed".into()))?;
    Ok(Checksums { f32, fixed, noise })
}
