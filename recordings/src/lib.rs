//! Recorded IMU logs as `imu-ar` reads them: CSV files ([`csv`]), ROS 1 bags ([`bag`]), MCAP
//! files ([`mcap`]) and rosbag2 folders and databases ([`rosbag2`]), each IMU message as a
//! [`frame::Frame`], all streamed through [`source`] with their timestamps ([`timing`]) and
//! units ([`units`]) checked. An error names the file, and the line or message where one is
//! to blame ([`error`]). Autopilot logs have readers of their own, which survey a log (its IMU
//! instances and parameters) and stream its IMU samples with their temperatures: PX4 ULog files
//! ([`ulog`]) and ArduPilot DataFlash logs ([`dataflash`]).
//!
//! The readers have a crate of their own so that what needs only them (the fuzz targets in
//! `fuzz/recordings/`, bindings) builds without the tool's plotting and estimators.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod bag;
pub mod csv;
pub mod dataflash;
mod decimal;
pub mod error;
pub mod frame;
pub mod mcap;
pub mod rosbag2;
pub mod source;
pub mod timing;
pub mod ulog;
pub mod units;

/// `bytes` in a scratch file of the unit tests' own (they run on several threads), named
/// with `extension`, removed when dropped.
#[cfg(test)]
pub(crate) struct Scratch(pub std::path::PathBuf);

#[cfg(test)]
impl Scratch {
    /// `bytes` in a new scratch file.
    pub(crate) fn new(bytes: &[u8], extension: &str) -> Self {
        use std::sync::atomic::{AtomicU64, Ordering};
        static CALLS: AtomicU64 = AtomicU64::new(0);
        let call = CALLS.fetch_add(1, Ordering::Relaxed);
        let name = format!(
            "imu-ar-recordings-{}-{call}.{extension}",
            std::process::id()
        );
        let path = std::env::temp_dir().join(name);
        std::fs::write(&path, bytes).expect("a scratch file");
        Scratch(path)
    }
}

#[cfg(test)]
impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// A timer's `count` reads, `reads` Hz from 1 s, of a sensor at `rate` Hz: each read's time
/// (µs) and the samples it finds (reads that find none left out).
#[cfg(test)]
pub(crate) fn timer_reads(rate: f64, reads: f64, count: u64) -> Vec<(f64, usize)> {
    let mut held = 0u64;
    (1..=count)
        .filter_map(|k| {
            let read = 1e6 + k as f64 * 1e6 / reads;
            let all = ((read - 1e6) * rate / 1e6).floor() as u64;
            let n = (all - held) as usize;
            held = all;
            (n > 0).then_some((read, n))
        })
        .collect()
}

/// A fixed generator for the unit tests' random inputs (xorshift64).
#[cfg(test)]
pub(crate) fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    }
}
