//! The ROS readers of the `imu-ar` tool (ROS 1 bag, MCAP, rosbag2 SQLite database) on arbitrary
//! bytes: the first byte picks the reader, the rest is the file. Every delivered frame is
//! finite, an error names the file, and nothing panics.
#![no_main]

use std::path::PathBuf;

use imu_ar_cli::input::frame::{Frame, Select};
use imu_ar_cli::input::{bag, mcap, rosbag2};
use libfuzzer_sys::fuzz_target;

/// This process's scratch file for one input.
fn scratch(extension: &str) -> PathBuf {
    std::env::temp_dir().join(format!("imu-ar-fuzz-{}.{extension}", std::process::id()))
}

fuzz_target!(|data: &[u8]| {
    let Some((&which, bytes)) = data.split_first() else {
        return;
    };
    let (extension, read): (&str, fn(&std::path::Path, &Select, &mut dyn FnMut(Frame)) -> _) =
        match which % 3 {
            0 => ("bag", bag::read_selected),
            1 => ("mcap", mcap::read_selected),
            _ => ("db3", rosbag2::read_db3),
        };
    let path = scratch(extension);
    std::fs::write(&path, bytes).unwrap();
    // With and without a frame_id, on the fixtures' topics.
    for select in [
        Select::topic("/imu0"),
        Select::topic("/imu"),
        Select {
            topic: "/imu0",
            frame_id: Some("imu_a"),
        },
    ] {
        let mut frames = 0u64;
        let result = read(&path, &select, &mut |f: Frame| {
            assert!(f.axes.iter().all(|v| v.is_finite()));
            frames += 1;
        });
        match result {
            Ok(_) => assert!(frames > 0),
            Err(e) => assert_eq!(e.file, path),
        }
    }
});
