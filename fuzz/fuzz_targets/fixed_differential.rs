//! The fixed-point lattice against the f64 lattice on arbitrary in-range records, with the
//! acceptance of the differential property test (`imu_ar_host::differential`): within the
//! fixed-point tolerance, or a counted restart with the last good model held.
//!
//! The first byte picks the forgetting factor (1 included) and whether the mean is removed;
//! every further 2 bytes are an `i16` sample `v`, taken as `v / 2048` internal units (the
//! `i16` range less its bottom value, strictly inside the format's +-16).
#![no_main]

use imu_ar_host::differential::differential;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, data)) = data.split_first() else {
        return;
    };
    let lambda = [0.9f32, 0.95, 0.99, 0.995, 0.999, 0.9999, 1.0, 1.0][usize::from(head & 7)];
    let demean = head & 8 != 0;
    let x: Vec<f64> = data
        .chunks_exact(2)
        .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]]).max(-i16::MAX)) / 2048.0)
        .collect();
    if let Err(why) = differential::<3>(&x, lambda, demean) {
        panic!("lambda {lambda} demean {demean}: {why}");
    }
});
