//! The fuzz target `ulog_read`: [`checks::ulog_read`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::ulog_read(data));
