//! The fuzz target `dataflash_read`: [`checks::dataflash_read`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::dataflash_read(data));
