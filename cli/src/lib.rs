//! The `imu-ar` command-line tool's reading of CSV sensor logs.

pub mod data;
