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
