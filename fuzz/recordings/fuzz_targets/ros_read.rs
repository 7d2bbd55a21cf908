//! The fuzz target `ros_read`: [`checks::ros_read`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::ros_read(data));
