//! The fuzz target `csv_column`: [`checks::csv_column`] on libFuzzer's inputs.
#![no_main]

#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::csv_column(data));
