//! The CSV reader of the `imu-ar` tool on arbitrary bytes: a column of finite numbers, or an
//! error naming the source and, for a bad row, its line; never a panic.
#![no_main]

use std::path::Path;

use imu_ar_cli::input::csv::parse_column;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let label = Path::new("fuzz.csv");
    match parse_column(label, data, "x") {
        Ok(x) => assert!(!x.is_empty() && x.iter().all(|v| v.is_finite())),
        Err(e) => assert!(e.to_string().starts_with("fuzz.csv")),
    }
});
