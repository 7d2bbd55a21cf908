//! The fuzz target `timing_summary`: [`checks::timing_summary`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::timing_summary(data));
