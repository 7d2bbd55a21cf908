//! The rosbag2 `metadata.yaml` reader of the `imu-ar` tool on arbitrary text: a storage and a
//! list of files, or an error; never a panic.
#![no_main]

use imu_ar_cli::input::rosbag2::Metadata;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(meta) = Metadata::parse(text) {
        assert!(!meta.storage.is_empty());
    }
});
