//! The fuzz target `decimal_number`: [`checks::decimal_number`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::decimal_number(data));
