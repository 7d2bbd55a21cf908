//! The fuzz target `rosbag2_metadata`: [`checks::rosbag2_metadata`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::rosbag2_metadata(data));
