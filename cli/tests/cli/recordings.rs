//! Recordings as users have them: two IMUs on one topic, drivers that do not stamp, chunks
//! stored out of order, ROS 2 folders and databases, files that are none of these, pipes,
//! units the tool does not know, and time units mistaken by 1000. The fixtures are
//! cli/tests/fixtures/ros/ (write_ros.py, `publisher_fixtures`).

use crate::common;
use crate::ros;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use common::{assert_one_line_failure, imu_ar, json, stderr};
use imu_ar_cli::input::frame::{Frame, Select};
use imu_ar_cli::input::{bag, mcap, rosbag2};
use ros::{assert_bits, fixture, fixture_dir, noise, noise_frames, temp_dir};

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The readers by extension, with a chosen frame_id.
fn read(file: &Path, frame_id: Option<&str>) -> (Vec<Frame>, Result<u64, String>) {
    let select = Select {
        frame_id,
        ..Select::topic("/imu0")
    };
    let mut got = Vec::new();
    let each = &mut |f| got.push(f);
    let result = match file.extension().and_then(|e| e.to_str()) {
        Some("bag") => bag::read_selected(file, &select, each),
        Some("mcap") => mcap::read_selected(file, &select, each),
        Some("db3") => rosbag2::read_db3(file, &select, each),
        _ => rosbag2::read_folder(file, &select, each),
    };
    (got, result.map(|s| s.other_frame_id).map_err(|e| e.problem))
}

/// A CSV `t_ns,gx,..,az` of `frames`.
fn csv_of(dir: &Path, name: &str, frames: &[Frame]) -> PathBuf {
    let mut s = "t_ns,gx,gy,gz,ax,ay,az\n".to_string();
    for f in frames {
        write!(s, "{}", f.stamp_ns).unwrap();
        for v in f.axes {
            write!(s, ",{v:?}").unwrap();
        }
        s.push('\n');
    }
    let file = dir.join(name);
    std::fs::write(&file, s).unwrap();
    file
}

#[test]
fn two_imus_on_one_topic_are_refused_by_name_and_either_can_be_read() {
    let a = noise(400, 2);
    let b: Vec<Frame> = noise(400, 3)
        .into_iter()
        .map(|f| Frame {
            stamp_ns: f.stamp_ns + 5_000_000,
            ..f
        })
        .collect();
    for name in ["two-imus.bag", "two-imus.mcap", "two-imus.db3"] {
        let file = fixture(name);
        let (_, result) = read(&file, None);
        let e = result.expect_err(name);
        assert!(
            e.contains("2 IMUs publish on '/imu0'")
                && e.contains("'imu_a' (400 messages)")
                && e.contains("'imu_b' (400 messages)")
                && e.contains("--frame-id"),
            "{name}: {e}"
        );
        for (id, want) in [("imu_a", &a), ("imu_b", &b)] {
            let (got, result) = read(&file, Some(id));
            assert_eq!(
                result,
                Ok(400),
                "{name} {id}: the other IMU's messages are counted"
            );
            assert_bits(&got, want, name);
        }
        let (_, result) = read(&file, Some("imu_c"));
        let e = result.expect_err(name);
        assert!(
            e.contains("--frame-id imu_c: no message on '/imu0' has it"),
            "{e}"
        );
        // The tool: refused with exit 2 (not a 200 Hz IMU of half the noise), then read.
        let out = imu_ar(&["noise", path(&file), "--topic", "/imu0", "--column", "gz"]);
        assert_one_line_failure(&out);
        assert!(stderr(&out).contains("imu_a"), "{}", stderr(&out));
        let dir = temp_dir(&format!("two-imus-{name}"));
        let csv = csv_of(&dir, "a.csv", &a);
        let one = json(&imu_ar(&[
            "noise",
            path(&file),
            "--topic",
            "/imu0",
            "--frame-id",
            "imu_a",
            "--column",
            "gz",
            "--json",
        ]));
        let from_csv = json(&imu_ar(&[
            "noise",
            path(&csv),
            "--column",
            "gz",
            "--unit",
            "rad/s",
            "--json",
        ]));
        assert_eq!(one["white_noise"], from_csv["white_noise"], "{name}");
        assert_eq!(one["rate_hz"], from_csv["rate_hz"], "{name}");
    }
}

#[test]
fn publishers_of_one_frame_id_are_one_imu_only_one_after_the_other() {
    // Interleaved: two sensors that cannot be told apart.
    let (_, result) = read(&fixture("same-frame.bag"), None);
    let e = result.expect_err("interleaved publishers");
    assert!(
        e.contains("two publishers on '/imu0'")
            && e.contains("callerid '/imu_driver'")
            && e.contains("callerid '/imu_driver_2'"),
        "{e}"
    );
    // A driver that restarted: its second connection follows the first, and is read.
    let (got, result) = read(&fixture("restart.bag"), None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise(400, 2), "restart.bag");
}

#[test]
fn unstamped_messages_need_the_rate_and_are_then_read_in_file_order() {
    let dir = temp_dir("unstamped");
    let frames = noise(400, 2);
    let csv = csv_of(&dir, "frames.csv", &frames);
    let from_csv = json(&imu_ar(&[
        "noise",
        path(&csv),
        "--column",
        "gx",
        "--unit",
        "rad/s",
        "--rate",
        "100",
        "--json",
    ]));
    for name in ["unstamped.bag", "unstamped.mcap", "unstamped.db3"] {
        let file = fixture(name);
        let out = imu_ar(&["noise", path(&file), "--topic", "/imu0", "--column", "gx"]);
        assert_one_line_failure(&out);
        assert!(
            stderr(&out).contains("the header stamps of 400 of 400 messages on '/imu0' are zero")
                && stderr(&out).contains("give --rate"),
            "{name}: {}",
            stderr(&out)
        );
        let got = json(&imu_ar(&[
            "noise",
            path(&file),
            "--topic",
            "/imu0",
            "--column",
            "gx",
            "--rate",
            "100",
            "--json",
        ]));
        assert_eq!(got["white_noise"], from_csv["white_noise"], "{name}");
        assert_eq!(got["allan"], from_csv["allan"], "{name}");
    }
}

#[test]
fn chunks_stored_out_of_time_order_are_read_in_time_order() {
    // The second half of the record written first, in chunks of 8 KiB.
    let bytes = std::fs::read(fixture("out-of-order.bag")).unwrap();
    let (got, result) = read(&fixture("out-of-order.bag"), None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise(400, 2), "out-of-order.bag");
    assert!(bytes.len() > 4 * 8 * 1024, "several chunks");
    // The tool reads it with no --drop-backward and no sample lost.
    let one = json(&imu_ar(&[
        "noise",
        path(&fixture("out-of-order.bag")),
        "--topic",
        "/imu0",
        "--column",
        "gx",
        "--json",
    ]));
    assert_eq!(one["n"], 400);
}

#[test]
fn files_that_are_no_recording_are_named_for_what_they_are() {
    let dir = temp_dir("kinds");
    let mcap_bytes = std::fs::read(fixture("one.mcap")).unwrap();
    let cases: [(&str, Vec<u8>, &str); 7] = [
        ("empty.bag", Vec::new(), "an empty file, not a ROS 1 bag"),
        (
            "old.bag",
            b"#ROSBAG V1.3\n\0\0\0\0".to_vec(),
            "a ROS bag of format 1.3: only format 2.0 is read",
        ),
        (
            "cut.mcap",
            mcap_bytes[..5].to_vec(),
            "truncated or corrupt MCAP file",
        ),
        (
            "bag.mcap.zstd",
            vec![0x28, 0xb5, 0x2f, 0xfd, 0, 0, 0, 0],
            "a zstd-compressed file",
        ),
        (
            "text.db3",
            b"hello,world\n1,2\n".to_vec(),
            "not a rosbag2 database",
        ),
        ("notes.bag", b"gx,gy\n1,2\n".to_vec(), "not a ROS 1 bag"),
        (
            "plain.db3",
            b"SQLite format 3\0 but nothing after".to_vec(),
            "not a readable rosbag2 database",
        ),
    ];
    for (name, bytes, want) in cases {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let out = imu_ar(&["noise", path(&file), "--topic", "/imu0", "--column", "gx"]);
        assert_one_line_failure(&out);
        assert!(stderr(&out).contains(want), "{name}: {}", stderr(&out));
        assert!(!stderr(&out).contains("the file is CSV"), "{name}");
    }
    // A file that is not there is not there (not an empty bag).
    let missing = dir.join("missing.bag");
    let out = imu_ar(&[
        "noise",
        path(&missing),
        "--topic",
        "/imu0",
        "--column",
        "gx",
    ]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("missing.bag: cannot open: "),
        "{}",
        stderr(&out)
    );
    // A folder without metadata.yaml, and a rosbag2 folder whose metadata names a missing file.
    let bare = dir.join("folder");
    std::fs::create_dir_all(&bare).unwrap();
    let out = imu_ar(&["noise", path(&bare), "--topic", "/imu0", "--column", "gx"]);
    assert!(
        stderr(&out).contains("a folder without metadata.yaml"),
        "{}",
        stderr(&out)
    );
    let broken = dir.join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    std::fs::write(
        broken.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths:\n  - broken_0.db3\n",
    )
    .unwrap();
    let out = imu_ar(&["noise", path(&broken), "--topic", "/imu0", "--column", "gx"]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("storage file 'broken_0.db3' is missing from the folder"),
        "{}",
        stderr(&out)
    );
    std::fs::write(
        broken.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths:\n  - ../x.db3\n",
    )
    .unwrap();
    let out = imu_ar(&["noise", path(&broken), "--topic", "/imu0", "--column", "gx"]);
    assert!(
        stderr(&out).contains("is not inside the folder"),
        "{}",
        stderr(&out)
    );
    // A topic of a bare database that is not there lists the IMU topics.
    let out = imu_ar(&[
        "noise",
        path(&fixture("noise.db3")),
        "--topic",
        "/imu9",
        "--column",
        "gx",
    ]);
    assert!(
        stderr(&out)
            .contains("no sensor_msgs/msg/Imu messages on topic '/imu9' (IMU topics: /imu0)"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_named_pipe_is_read_once() {
    let dir = temp_dir("pipe");
    let frames = noise(1200, 2);
    let csv = csv_of(&dir, "frames.csv", &frames);
    let fifo = dir.join("p");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("no mkfifo here: the pipe is not tested");
        return;
    }
    let from_file = json(&imu_ar(&["noise", path(&csv), "--column", "gy", "--json"]));
    // The writer opens the pipe once and writes the file once, as `cat f > p &` does.
    let (source, target) = (csv.clone(), fifo.clone());
    let writer = std::thread::spawn(move || {
        let bytes = std::fs::read(source).unwrap();
        std::fs::write(target, bytes).unwrap();
    });
    let mut child = common::command()
        .args(["noise", path(&fifo), "--column", "gy", "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > std::time::Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("the tool hangs on a named pipe");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(got["white_noise"], from_file["white_noise"]);
    assert_eq!(got["n"], from_file["n"]);
}

/// A CSV of `header` and `gx` at stamps `first + i * step` (one a frame) in `file`: refused,
/// the message holding each of `named`, and read at `rate` where `--rate` confirms it.
fn refused_until_confirmed(
    file: &Path,
    (header, first, step): (&str, u64, u64),
    rate: f64,
    named: &[&str],
) {
    let mut s = format!("{header},gx\n");
    for (i, f) in noise(1200, 2).iter().enumerate() {
        writeln!(s, "{},{:?}", first + i as u64 * step, f.axes[0]).unwrap();
    }
    std::fs::write(file, s).unwrap();
    let out = imu_ar(&["noise", path(file), "--column", "gx"]);
    assert_one_line_failure(&out);
    let e = stderr(&out);
    assert!(named.iter().all(|n| e.contains(n)), "{header}: {e}");
    let rate_text = rate.to_string();
    let got = json(&imu_ar(&[
        "noise",
        path(file),
        "--column",
        "gx",
        "--rate",
        &rate_text,
        "--json",
    ]));
    assert_eq!(got["rate_hz"], rate);
}

#[test]
fn a_rate_above_10_khz_from_stamps_needs_the_rate_to_confirm_it() {
    let dir = temp_dir("us-as-ns");
    // 400 Hz stamps written in microseconds under a [ns] header: 400 kHz read as is.
    // Confirmed, it is read at that rate.
    let file = dir.join("us.csv");
    refused_until_confirmed(
        &file,
        ("t [ns]", 1_000_000, 2_500),
        400_000.0,
        &["give 400000 Hz", "microseconds under [ns]", "--rate 400000"],
    );
    // 10 kHz is still taken from the stamps.
    let mut s = "t [ns],gx\n".to_string();
    for (i, f) in noise(1200, 2).iter().enumerate() {
        writeln!(s, "{},{:?}", 1_000_000 + i as u64 * 100_000, f.axes[0]).unwrap();
    }
    std::fs::write(&file, s).unwrap();
    let got = json(&imu_ar(&["noise", path(&file), "--column", "gx", "--json"]));
    assert_eq!(got["rate_hz"], 10_000.0);
}

#[test]
fn a_rate_below_5_hz_from_stamps_needs_the_rate_to_confirm_it() {
    // 1000 Hz stamps in ms under a [s] header, and 1000 Hz in us since boot, 20 days up, under
    // a column that names no unit (1.728e12: an epoch time in ms by its size): 1 Hz, exit 0,
    // before. Confirmed, each is read at that rate.
    let dir = temp_dir("ms-as-s");
    for stamps in [("t [s]", 1_000, 1), ("timestamp", 1_728_000_000_000, 1_000)] {
        refused_until_confirmed(
            &dir.join("slow.csv"),
            stamps,
            1.0,
            &["give 1 Hz", "milliseconds under [s]", "--rate 1 "],
        );
    }
}

#[test]
fn an_unknown_unit_bracket_is_named_with_the_known_ones() {
    let dir = temp_dir("unit-g");
    let frames = noise(1200, 2);
    let mut s = "t [s],gx [rad/s],gy [rad/s],gz [rad/s],ax [G],ay [G],az [G]\n".to_string();
    for (i, f) in frames.iter().enumerate() {
        write!(s, "{}", i as f64 * 0.01).unwrap();
        for v in f.axes {
            write!(s, ",{v:?}").unwrap();
        }
        s.push('\n');
    }
    let file = dir.join("g.csv");
    std::fs::write(&file, s).unwrap();
    let out = imu_ar(&[
        "characterise",
        path(&file),
        "--columns",
        "gx,gy,gz,ax,ay,az",
        "--out",
        path(&dir.join("out")),
    ]);
    assert_one_line_failure(&out);
    let e = stderr(&out);
    assert!(
        e.contains("its unit [G] is not one known here")
            && e.contains("m/s^2, g, mg")
            && e.contains("--accel-unit"),
        "{e}"
    );
    // A failed run leaves no --out folder behind, nor the parents it made; and the file is
    // named.
    assert!(!dir.join("out").exists());
    assert!(
        e.starts_with(&format!("imu-ar: {}: column 'ax'", file.display())),
        "{e}"
    );
    let nested = dir.join("nest/a/b");
    let out = imu_ar(&[
        "characterise",
        path(&file),
        "--columns",
        "gx,gy,gz,ax,ay,az",
        "--out",
        path(&nested),
    ]);
    assert_one_line_failure(&out);
    assert!(!dir.join("nest").exists());
}

#[test]
fn a_plot_that_cannot_be_written_leaves_no_parameter_file() {
    let dir = temp_dir("all-or-nothing");
    let frames = noise(1200, 2);
    let csv = csv_of(&dir, "frames.csv", &frames);
    let out_dir = dir.join("out");
    std::fs::create_dir_all(out_dir.join("gyro.png")).unwrap();
    let out = imu_ar(&[
        "characterise",
        path(&csv),
        "--gyro-unit",
        "rad/s",
        "--accel-unit",
        "m/s^2",
        "--out",
        path(&out_dir),
    ]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("gyro.png: is a directory"),
        "{}",
        stderr(&out)
    );
    let left: Vec<_> = std::fs::read_dir(&out_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("gyro.png")], "{left:?}");
}

#[test]
fn rosbag2_metadata_is_read_in_its_block_and_flow_forms() {
    let meta = rosbag2::Metadata::parse(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  \
         relative_file_paths:\n    - 'run_0.db3'\n    - run_1.db3\n  duration:\n    \
         nanoseconds: 1\n  files:\n  - path: run_0.db3\n  compression_format: \"\"\n  \
         compression_mode: \"\"\n",
    )
    .unwrap();
    assert_eq!(meta.storage, "sqlite3");
    assert_eq!(meta.files, ["run_0.db3", "run_1.db3"]);
    let meta = rosbag2::Metadata::parse(
        "storage_identifier: mcap\nrelative_file_paths: [a.mcap, \"b.mcap\"]\ncompression_mode: FILE\n",
    )
    .unwrap();
    assert_eq!(meta.files, ["a.mcap", "b.mcap"]);
    assert_eq!(meta.compression_mode, "FILE");
    assert!(rosbag2::Metadata::parse("relative_file_paths: []\n").is_err());
    assert!(rosbag2::Metadata::parse("storage_identifier: mcap\n").is_err());
    // Comments after values, outside quotes (pass 49 F1, F2: the file was looked for as
    // 'b_0.db3  # first file', and a count with a comment went unchecked).
    let meta = rosbag2::Metadata::parse(
        "storage_identifier: sqlite3  # the default\nrelative_file_paths:\n  - b_0.db3  # first\n  \
         - 'b#1.db3' # second\ntopics_with_message_count:\n  - topic_metadata:\n      name: \
         /imu # the IMU\n    message_count: 40001 # all\n",
    )
    .unwrap();
    assert_eq!(meta.storage, "sqlite3");
    assert_eq!(meta.files, ["b_0.db3", "b#1.db3"]);
    assert_eq!(meta.topic_counts, [("/imu".to_string(), 40_001)]);
    // Quotes escaped within quoted names, quoted keys, keys of a map within (custom_data),
    // a second document (pass 51 F1, F2, F4, F6: 'it''s #0.db3' was cut at its '#', a
    // quoted "message_count" went unchecked, custom_data's keys were taken for the bag's,
    // the second document's files were read too).
    let meta = rosbag2::Metadata::parse(
        "rosbag2_bagfile_information:\n  custom_data:\n    storage_identifier: nope\n    \
         relative_file_paths:\n    - ghost.db3\n  \"storage_identifier\": sqlite3\n  \
         relative_file_paths:\n  - 'it''s #0.db3' # first\n  - \"b \\\" #1.db3\"\n  \
         topics_with_message_count:\n  - \"message_count\": 7\n    topic_metadata:\n      \
         name: /imu\n---\nrelative_file_paths:\n- other.db3\n",
    )
    .unwrap();
    assert_eq!(meta.storage, "sqlite3");
    assert_eq!(meta.files, ["it's #0.db3", "b \" #1.db3"]);
    assert_eq!(meta.topic_counts, [("/imu".to_string(), 7)]);
    // A count that is none: refused, not passed over (2^64 and 1e30 went unchecked).
    for count in ["18446744073709551616", "1e30", "-1", "many"] {
        let e = rosbag2::Metadata::parse(&format!(
            "storage_identifier: mcap\nrelative_file_paths: [a.mcap]\n\
             topics_with_message_count:\n- message_count: {count}\n  topic_metadata:\n    \
             name: /imu\n"
        ))
        .unwrap_err();
        assert!(
            e.contains(&format!("message_count '{count}' is not a count")),
            "{e}"
        );
    }
}

/// `imu-ar noise FILE --topic /imu0 --column gx EXTRA..`.
fn noise_of(file: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["noise", path(file), "--topic", "/imu0", "--column", "gx"];
    args.extend_from_slice(extra);
    imu_ar(&args)
}

#[test]
fn more_than_one_percent_of_skipped_messages_is_refused() {
    let dir = temp_dir("skipped-share");
    let base = std::fs::read(fixture("noise.bag")).unwrap();
    let ids = ros::frame_ids(&base);
    // A frame_id given another length: the message no longer decodes. Every 50th message of
    // 1200 (24, 2 %) is refused; every 400th (3, 0.25 %) is read, the holes shown as gaps.
    for (every, refused) in [(50, true), (400, false)] {
        let mut bytes = base.clone();
        for &id in ids.iter().step_by(every) {
            bytes[id - 4..id].copy_from_slice(&1000u32.to_le_bytes());
        }
        let file = dir.join(format!("every-{every}.bag"));
        std::fs::write(&file, bytes).unwrap();
        let out = noise_of(&file, &[]);
        if refused {
            assert_one_line_failure(&out);
            assert!(
                stderr(&out)
                    .contains("24 of the 1200 messages on '/imu0' were skipped (24 undecodable")
                    && stderr(&out).contains("more than 1 %"),
                "{}",
                stderr(&out)
            );
        } else {
            assert!(out.status.success(), "{}", stderr(&out));
            assert_eq!(json(&noise_of(&file, &["--json"]))["n"], 1197);
        }
    }
}

#[test]
fn a_chunk_that_reads_short_is_a_damaged_file() {
    let dir = temp_dir("short-chunk");
    // ROS 1, bz2: the first chunk's header says its data decompress to 0 bytes.
    let mut bytes = std::fs::read(fixture("noise-bz2.bag")).unwrap();
    let at = ros::find_all(&bytes, b"size=")[0] + 5;
    bytes[at..at + 4].copy_from_slice(&0u32.to_le_bytes());
    let bag = dir.join("zero.bag");
    std::fs::write(&bag, bytes).unwrap();
    let out = noise_of(&bag, &[]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("a chunk is damaged"),
        "{}",
        stderr(&out)
    );
    // MCAP, zstd: the same in a chunk record (opcode 0x06: start and end times, then the
    // uncompressed size and CRC, zeroed so that no CRC check tells).
    let mut bytes = std::fs::read(fixture("noise-zstd.mcap")).unwrap();
    let mut at = 8;
    while bytes[at] != 0x06 {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        at += 9 + len;
    }
    let body = at + 9;
    bytes[body + 16..body + 28].fill(0);
    let mcap = dir.join("zero.mcap");
    std::fs::write(&mcap, bytes).unwrap();
    let out = noise_of(&mcap, &[]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("a chunk is damaged"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn refusals_name_the_file_and_what_it_is() {
    let dir = temp_dir("messages");
    // The rate's refusals name the file; for a bag they speak of its header stamps.
    let bag = fixture("noise.bag");
    let out = noise_of(&bag, &["--rate", "103"]);
    assert!(
        stderr(&out).starts_with(&format!("imu-ar: {}: --rate 103", bag.display())),
        "{}",
        stderr(&out)
    );
    let mut bytes = std::fs::read(&bag).unwrap();
    for (i, &id) in ros::frame_ids(&bytes.clone()).iter().enumerate() {
        ros::set_stamp(
            &mut bytes,
            id,
            1_600_000_000_000_000_000 + i as i64 * 50_000,
        );
    }
    let fast = dir.join("fast.bag");
    std::fs::write(&fast, bytes).unwrap();
    let out = noise_of(&fast, &[]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).starts_with(&format!(
            "imu-ar: {}: the messages' header stamps give 20000 Hz",
            fast.display()
        )) && !stderr(&out).contains("time column"),
        "{}",
        stderr(&out)
    );
    // A damaged bag without --topic says it is damaged.
    let cut = dir.join("cut.bag");
    let whole = std::fs::read(&bag).unwrap();
    std::fs::write(&cut, &whole[..whole.len() - 100]).unwrap();
    let out = imu_ar(&["noise", path(&cut), "--column", "gx"]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("truncated or corrupt bag"),
        "{}",
        stderr(&out)
    );
    // Empty, binary and compressed files under --topic.
    let cases: [(&str, &[u8], &str); 4] = [
        ("empty.dat", b"", "the file is empty"),
        ("x.h5", b"\x89HDF\r\n\x1a\n\0\0\0\0", "an HDF5 file"),
        ("blob", b"\x01\x02\x03\x04abc", "a binary file"),
        ("a.csv.xz", b"\xfd7zXZ\0\0\x04", "an xz-compressed file"),
    ];
    for (name, bytes, want) in cases {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let out = noise_of(&file, &[]);
        assert_one_line_failure(&out);
        assert!(stderr(&out).contains(want), "{name}: {}", stderr(&out));
    }
    // A storage file that is a folder is not a missing one.
    let folder = dir.join("rb2");
    std::fs::create_dir_all(folder.join("bag_0.db3")).unwrap();
    std::fs::write(
        folder.join("metadata.yaml"),
        "storage_identifier: sqlite3\nrelative_file_paths:\n- bag_0.db3\n",
    )
    .unwrap();
    let out = noise_of(&folder, &[]);
    assert!(
        stderr(&out).contains("'bag_0.db3' is not a regular file"),
        "{}",
        stderr(&out)
    );
    // PX4's vehicle id is 1 to 255 in one message.
    let out = imu_ar(&[
        "characterise",
        path(&bag),
        "--topic",
        "/imu0",
        "--sysid",
        "0",
        "--out",
        path(&dir.join("o")),
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("1..=255"), "{}", stderr(&out));
}

#[test]
fn a_frame_id_that_is_not_utf8_is_shown_escaped_and_can_be_chosen() {
    let dir = temp_dir("non-utf8");
    let mut bytes = std::fs::read(fixture("noise.bag")).unwrap();
    let ids = ros::frame_ids(&bytes);
    // Every other message from frame_id "\xffmu_link".
    for &id in ids.iter().step_by(2) {
        bytes[id] = 0xff;
    }
    let file = dir.join("bytes.bag");
    std::fs::write(&file, bytes).unwrap();
    let out = noise_of(&file, &[]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("'\\xffmu_link' (600 messages)")
            && stderr(&out).contains("'imu_link' (600 messages)"),
        "{}",
        stderr(&out)
    );
    let (got, result) = read(&file, Some("\\xffmu_link"));
    assert_eq!(result, Ok(600));
    let want: Vec<Frame> = ros::noise_frames().into_iter().step_by(2).collect();
    assert_bits(&got, &want, "\\xffmu_link");
}

#[test]
fn a_database_with_a_timestamp_that_is_not_an_integer_is_refused() {
    let dir = temp_dir("db3-types");
    let file = dir.join("text.db3");
    std::fs::copy(fixture("noise.db3"), &file).unwrap();
    let db = rusqlite::Connection::open(&file).unwrap();
    db.execute("UPDATE messages SET timestamp = 'abc' WHERE id = 5", [])
        .unwrap();
    drop(db);
    let out = noise_of(&file, &[]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out)
            .contains("1 messages on '/imu0' have a receive timestamp that is not an integer"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_database_topic_of_two_types_names_both() {
    let dir = temp_dir("db3-two-types");
    for (name, first) in [("imu-first.db3", false), ("string-first.db3", true)] {
        let file = dir.join(name);
        std::fs::copy(fixture("noise.db3"), &file).unwrap();
        let db = rusqlite::Connection::open(&file).unwrap();
        if first {
            // The string row before the IMU's: the IMU's moved to id 3.
            db.execute("UPDATE topics SET id = 3 WHERE id = 1", [])
                .unwrap();
            db.execute("UPDATE messages SET topic_id = 3", []).unwrap();
        }
        db.execute(
            "INSERT INTO topics VALUES (2, '/imu0', 'std_msgs/msg/String', 'cdr', '', '')",
            [],
        )
        .unwrap();
        drop(db);
        let (got, result) = read(&file, None);
        let imu = if first { 3 } else { 1 };
        assert_eq!(
            result,
            Err(format!(
                "topic '/imu0' carries sensor_msgs/msg/Imu (topic row {imu}) and \
                 std_msgs/msg/String (topic row 2): one topic, one type of message; in a copy \
                 of the file, delete the others' messages (sqlite3: DELETE FROM messages WHERE \
                 topic_id IN (2)) and read the copy"
            )),
            "{name}"
        );
        assert!(got.is_empty());
    }
}

#[test]
fn an_mcap_record_that_overruns_its_chunk_is_a_damaged_file() {
    // Found by the `ros_read` fuzz target: an uncompressed chunk whose last record claims more
    // bytes than the chunk holds (the mcap crate's reader overflowed its count on it).
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fuzz/chunk-overrun.mcap");
    for topic in ["/imu0", "/imu"] {
        let select = Select::topic(topic);
        let result = mcap::read_selected(&file, &select, &mut |_| {});
        let e = result.expect_err("a damaged file");
        assert!(
            e.problem.starts_with("truncated or corrupt MCAP file"),
            "{e}"
        );
    }
}

#[test]
fn messages_stored_out_of_order_inside_a_chunk_are_read_in_time_order() {
    let dir = temp_dir("swapped");
    let mut bytes = std::fs::read(fixture("noise.bag")).unwrap();
    let ids = ros::frame_ids(&bytes);
    // Two neighbouring message records of one chunk (equal strides: no chunk boundary
    // between them), swapped whole: header (with its receive time) and data.
    let i = (40..ids.len() - 2)
        .find(|&i| ids[i + 1] - ids[i] == ids[i + 2] - ids[i + 1])
        .unwrap();
    let stride = ids[i + 1] - ids[i];
    let data_len = u32::from_le_bytes(bytes[ids[i] - 20..ids[i] - 16].try_into().unwrap());
    let next = ids[i] - 16 + data_len as usize;
    let start = next - stride;
    let first = bytes[start..next].to_vec();
    bytes.copy_within(next..next + stride, start);
    bytes[start + stride..start + 2 * stride].copy_from_slice(&first);
    let file = dir.join("swapped.bag");
    std::fs::write(&file, bytes).unwrap();
    let (got, result) = read(&file, None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &ros::noise_frames(), "swapped.bag");
}

/// `frames`' gx under `header`, the stamp of row `row` written as `bad`.
fn stamped_csv(dir: &Path, name: &str, header: &str, row: usize, bad: &str) -> PathBuf {
    let mut s = format!("{header},gx\n");
    for (i, f) in noise(1000, 2).iter().enumerate() {
        let stamp = if i == row {
            bad.to_string()
        } else {
            f.stamp_ns.to_string()
        };
        writeln!(s, "{stamp},{:?}", f.axes[0]).unwrap();
    }
    let file = dir.join(format!("{name}.csv"));
    std::fs::write(&file, s).unwrap();
    file
}

/// `--rate 200` on a 100 Hz record is refused, naming what the stamps give.
fn refuses_rate_200(file: &Path) {
    let out = imu_ar(&["noise", path(file), "--column", "gx", "--rate", "200"]);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    let last = e.lines().last().unwrap_or_default();
    assert!(last.contains("--rate 200: the timestamps give 100"), "{e}");
    // Before it, at most the warning of a stamp kept out of time order.
    for line in e.lines().rev().skip(1) {
        assert!(
            line.contains("1 samples stamped before the one before kept in file order"),
            "{e}"
        );
    }
}

#[test]
fn a_bad_stamp_does_not_switch_off_the_check_of_a_given_rate() {
    let dir = temp_dir("backward-rate");
    // 1000 rows at 100 Hz; row 10 stamped as row 8, not a number, or empty.
    let back = noise(1000, 2)[8].stamp_ns.to_string();
    for (name, bad) in [("back", back.as_str()), ("abc", "abc"), ("empty", "")] {
        let file = stamped_csv(&dir, name, "t_ns", 10, bad);
        refuses_rate_200(&file);
        // The rate the stamps give is taken, the sample kept (a backward stamp's counted).
        let got = json(&imu_ar(&[
            "noise",
            path(&file),
            "--column",
            "gx",
            "--rate",
            "100",
            "--json",
        ]));
        assert_eq!(got["n"], 1000, "{name}");
    }
    // A time column without a unit: an empty first stamp leaves the unit to the next one.
    let file = stamped_csv(&dir, "first-empty", "timestamp", 0, "");
    refuses_rate_200(&file);
    let out = imu_ar(&["noise", path(&file), "--column", "gx"]);
    assert_one_line_failure(&out);
    let e = stderr(&out);
    assert!(e.contains(":2: timestamp '' is not a number"), "{e}");
}

#[test]
fn allan_deviations_that_overflow_are_refused() {
    let dir = temp_dir("adev-huge");
    let mut s = "gx\n".to_string();
    for i in 0..1000 {
        writeln!(s, "{}", if i == 500 { 1e300 } else { 0.001 * i as f64 }).unwrap();
    }
    let file = dir.join("huge.csv");
    std::fs::write(&file, s).unwrap();
    let out = imu_ar(&["adev", path(&file), "--column", "gx", "--rate", "100"]);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("overflows"), "{}", stderr(&out));
}

/// An MCAP record: opcode, length, body.
fn record(out: &mut Vec<u8>, opcode: u8, body: &[u8]) {
    out.push(opcode);
    out.extend((body.len() as u64).to_le_bytes());
    out.extend(body);
}

/// An MCAP string: length, bytes.
fn string(out: &mut Vec<u8>, s: &str) {
    out.extend((s.len() as u32).to_le_bytes());
    out.extend(s.as_bytes());
}

/// A CDR `sensor_msgs/msg/Imu` of `frame`, frame_id `imu_link`.
fn cdr(frame: &Frame) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0];
    b.extend((frame.stamp_ns.div_euclid(1_000_000_000) as i32).to_le_bytes());
    b.extend((frame.stamp_ns.rem_euclid(1_000_000_000) as u32).to_le_bytes());
    b.extend(9u32.to_le_bytes());
    b.extend(b"imu_link\0");
    while (b.len() - 4) % 8 != 0 {
        b.push(0);
    }
    let mut values = [0.0; 37];
    values[13..16].copy_from_slice(&frame.axes[..3]);
    values[25..28].copy_from_slice(&frame.axes[3..]);
    values.iter().for_each(|v| b.extend(v.to_le_bytes()));
    b
}

/// An unchunked MCAP file: the IMU schema, `channels` (id, topic), and one message per frame
/// on `channel_of(i)`.
fn hand_mcap(
    channels: &[(u16, &str)],
    frames: &[Frame],
    channel_of: impl Fn(usize) -> u16,
) -> Vec<u8> {
    let messages = MessagesOf {
        schema: ("sensor_msgs/msg/Imu", "ros2msg"),
        encoding: "cdr",
        data: |f: &Frame, _| cdr(f),
    };
    hand_mcap_of(&messages, channels, frames, channel_of)
}

/// How an MCAP file's IMU messages are written: the schema (name, encoding), the channels'
/// message encoding, and each frame's data (the frame, its number).
struct MessagesOf<'a, D: Fn(&Frame, usize) -> Vec<u8>> {
    schema: (&'a str, &'a str),
    encoding: &'a str,
    data: D,
}

/// An MCAP file's magic and header, and the record of schema 1 (`name`, `encoding`).
fn mcap_start((name, encoding): (&str, &str)) -> (Vec<u8>, Vec<u8>) {
    let mut out = b"\x89MCAP0\r\n".to_vec();
    let mut body = Vec::new();
    string(&mut body, "ros2");
    string(&mut body, "hand");
    record(&mut out, 0x01, &body);
    let mut schema = 1u16.to_le_bytes().to_vec();
    string(&mut schema, name);
    string(&mut schema, encoding);
    schema.extend(0u32.to_le_bytes());
    (out, schema)
}

/// The record of channel `id` of schema 1 on `topic`, in message `encoding`.
fn mcap_channel(id: u16, topic: &str, encoding: &str) -> Vec<u8> {
    let mut c = id.to_le_bytes().to_vec();
    c.extend(1u16.to_le_bytes());
    string(&mut c, topic);
    string(&mut c, encoding);
    c.extend(0u32.to_le_bytes());
    c
}

/// The data end, the footer (with the summary at `summary_start`, or none at 0) and the
/// closing magic.
fn mcap_end(out: &mut Vec<u8>, summary_start: u64) {
    let mut footer = summary_start.to_le_bytes().to_vec();
    footer.extend(0u64.to_le_bytes());
    footer.extend(0u32.to_le_bytes());
    record(out, 0x02, &footer);
    out.extend(b"\x89MCAP0\r\n");
}

/// [`hand_mcap`] of `messages`.
fn hand_mcap_of<D: Fn(&Frame, usize) -> Vec<u8>>(
    messages: &MessagesOf<'_, D>,
    channels: &[(u16, &str)],
    frames: &[Frame],
    channel_of: impl Fn(usize) -> u16,
) -> Vec<u8> {
    let (mut out, schema) = mcap_start(messages.schema);
    record(&mut out, 0x03, &schema);
    for &(id, topic) in channels {
        record(&mut out, 0x04, &mcap_channel(id, topic, messages.encoding));
    }
    for (i, f) in frames.iter().enumerate() {
        let mut m = channel_of(i).to_le_bytes().to_vec();
        m.extend((i as u32).to_le_bytes());
        m.extend((f.stamp_ns as u64).to_le_bytes());
        m.extend((f.stamp_ns as u64).to_le_bytes());
        m.extend((messages.data)(f, i));
        record(&mut out, 0x05, &m);
    }
    record(&mut out, 0x0f, &0u32.to_le_bytes());
    mcap_end(&mut out, 0);
    out
}

#[test]
fn an_mcap_file_whose_structure_is_damaged_is_refused() {
    let dir = temp_dir("mcap-structure");
    let frames = noise(200, 2);
    let cases: [(&str, Vec<u8>, Option<&str>); 3] = [
        (
            "good.mcap",
            hand_mcap(&[(1, "/imu0")], &frames, |_| 1),
            None,
        ),
        (
            "undefined.mcap",
            hand_mcap(&[(1, "/imu0")], &frames, |i| if i % 4 == 3 { 7 } else { 1 }),
            Some("a message on channel 7, which the file does not define"),
        ),
        (
            "redefined.mcap",
            hand_mcap(&[(1, "/imu0"), (1, "/imuX")], &frames, |_| 1),
            Some("channel 1 is defined twice, differently"),
        ),
    ];
    for (name, bytes, refused) in cases {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let (got, result) = read(&file, None);
        match refused {
            None => {
                assert_eq!(result, Ok(0), "{name}");
                assert_bits(&got, &frames, name);
            }
            Some(want) => {
                let e = result.expect_err(name);
                assert!(e.contains(want), "{name}: {e}");
            }
        }
    }
}

/// `noise --json` of the column gx of `file`, with `extra` arguments.
fn noise_json(file: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["noise", path(file), "--column", "gx", "--json"];
    args.extend_from_slice(extra);
    json(&imu_ar(&args))
}

#[test]
fn stamps_rounded_to_a_coarse_clock_give_the_clocks_rate() {
    let dir = temp_dir("coarse-stamps");
    let frames = noise(24_000, 5);
    // The same samples with no time column: the model at the rate given.
    let mut plain = "gx\n".to_string();
    for f in &frames {
        writeln!(plain, "{:e}", f.axes[0]).unwrap();
    }
    let plain_file = dir.join("plain.csv");
    std::fs::write(&plain_file, plain).unwrap();
    // 325 Hz to whole ms (intervals of 3 and 4 ms), 340 Hz to whole ms (2 and 3 ms), 950 Hz
    // (1 and 2 ms), 480 Hz (2 and 3 ms), and 200 Hz to 10 ms, in seconds (every other stamp
    // repeats).
    for (rate, header, stamp) in [
        (
            325.0,
            "t [ms]",
            &(|t: f64| format!("{}", (t * 1e3).floor())) as &dyn Fn(f64) -> String,
        ),
        (340.0, "t [ms]", &|t: f64| format!("{}", (t * 1e3).floor())),
        // Just over one and two quanta: 950 and 480 Hz to the nearest ms.
        (950.0, "t [ms]", &|t: f64| format!("{}", (t * 1e3).round())),
        (480.0, "t [ms]", &|t: f64| format!("{}", (t * 1e3).round())),
        (200.0, "t [s]", &|t: f64| {
            format!("{:.2}", (t * 100.0).floor() / 100.0)
        }),
    ] {
        let mut text = format!("{header},gx\n");
        for (i, f) in frames.iter().enumerate() {
            let t = 1_700_000_000.0 + (i as f64 + 0.5) / rate;
            writeln!(text, "{},{:e}", stamp(t), f.axes[0]).unwrap();
        }
        let file = dir.join(format!("{rate}.csv"));
        std::fs::write(&file, text).unwrap();
        let got = noise_json(&file, &[]);
        let timing = &got["timing"];
        let stamped = timing["rate_hz"].as_f64().unwrap();
        assert!((stamped / rate - 1.0).abs() < 1e-4, "{rate} Hz: {timing}");
        assert_eq!(timing["gaps"], 0, "{rate} Hz: {timing}");
        assert_eq!(timing["short_intervals"], 0, "{rate} Hz: {timing}");
        // The model is the plain samples' at the rate the stamps give.
        let r = format!("{stamped}");
        let expected = noise_json(&plain_file, &["--rate", &r]);
        assert_eq!(got["white_noise"], expected["white_noise"], "{rate} Hz");
        // The clock's rate, given, agrees with the stamps.
        let r = format!("{rate}");
        let given = noise_json(&file, &["--rate", &r]);
        assert_eq!(
            given["white_noise"],
            noise_json(&plain_file, &["--rate", &r])["white_noise"],
            "{rate} Hz"
        );
    }
}

#[test]
fn a_stretch_at_another_rate_under_whole_milliseconds_is_mixed_rates() {
    // 800 Hz, the last tenth at 600 Hz, to the nearest ms: both show intervals of 1 and 2 ms;
    // the stretch at 600 Hz is named, and --rate reads the record as given.
    let dir = temp_dir("stretch-rate");
    let frames = noise(5_000, 4);
    let mut text = "t [ms],gx\n".to_string();
    let mut t = 0.0;
    for (i, f) in frames.iter().enumerate() {
        writeln!(text, "{},{:e}", (t * 1e3_f64).round(), f.axes[0]).unwrap();
        t += if i < 4_500 { 1.0 / 800.0 } else { 1.0 / 600.0 };
    }
    let file = dir.join("mixed.csv");
    std::fs::write(&file, text).unwrap();
    let out = imu_ar(&["noise", path(&file), "--column", "gx"]);
    assert_one_line_failure(&out);
    let e = stderr(&out);
    assert!(e.contains("mixed rates: samples 4"), "{e}");
    assert!(e.contains("run at 60"), "{e}");
    let given = noise_json(&file, &["--rate", "800"]);
    assert_eq!(given["n"], 5_000);
}

#[test]
fn a_repeated_stamp_of_a_fine_clock_is_refused_after_the_file_is_read() {
    let dir = temp_dir("repeated-stamp");
    let frames = noise(2_000, 3);
    let mut text = "t_ns,gx\n".to_string();
    for (i, f) in frames.iter().enumerate() {
        let t = if i == 700 {
            frames[699].stamp_ns
        } else {
            f.stamp_ns
        };
        writeln!(text, "{t},{:e}", f.axes[0]).unwrap();
    }
    let file = dir.join("repeat.csv");
    std::fs::write(&file, text).unwrap();
    let out = imu_ar(&["noise", path(&file), "--column", "gx"]);
    assert_one_line_failure(&out);
    let e = stderr(&out);
    assert!(
        e.contains(&format!(
            "1 timestamps equal the one before (the first: sample 701, {} ns)",
            frames[699].stamp_ns
        )),
        "{e}"
    );
    // Dropped on request, and counted.
    let dropped = noise_json(&file, &["--drop-backward"]);
    assert_eq!(dropped["timing"]["dropped_backward"], 1);
    assert_eq!(dropped["n"], 1_999);
    // With --rate the sample stays and the other stamps still check the rate.
    let kept = noise_json(&file, &["--rate", "100"]);
    assert_eq!(
        (kept["n"].clone(), kept["timing"]["repeated"].clone()),
        (2_000.into(), 1.into())
    );
    let out = imu_ar(&["noise", path(&file), "--column", "gx", "--rate", "200"]);
    assert!(
        stderr(&out).contains("--rate 200: the timestamps give 99.99"),
        "{}",
        stderr(&out)
    );
}

/// A copy of the committed rosbag2 folder `name` in `dir` as `to`, its metadata edited by
/// `edit`.
fn copied_folder(dir: &Path, name: &str, to: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let from = fixture_dir(name);
    let folder = dir.join(to);
    std::fs::create_dir_all(&folder).unwrap();
    for entry in std::fs::read_dir(&from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), folder.join(entry.file_name())).unwrap();
    }
    let meta = folder.join("metadata.yaml");
    let text = std::fs::read_to_string(&meta).unwrap();
    std::fs::write(&meta, edit(text)).unwrap();
    folder
}

#[test]
fn old_rosbag2_folders_name_their_files_from_the_folders_parent() {
    // Up to metadata version 3 (Dashing, Eloquent), each path starts with the folder's name:
    // as recorded, and after the folder was renamed.
    let dir = temp_dir("rosbag2-v3");
    for (to, prefix) in [("old_bag", "old_bag"), ("renamed", "rosbag2_2019_11_05")] {
        let folder = copied_folder(&dir, "rosbag2-sqlite3", to, |t| {
            t.replace("version: 9", "version: 3").replace(
                "  - rosbag2-sqlite3.db3",
                &format!("  - {prefix}/rosbag2-sqlite3.db3"),
            )
        });
        let (got, result) = read(&folder, None);
        assert_eq!(result, Ok(0), "{to}");
        assert_bits(&got, &noise_frames(), to);
    }
    // From version 4 on, the path is the folder's own: a prefix is a file missing.
    let folder = copied_folder(&dir, "rosbag2-sqlite3", "v4", |t| {
        t.replace("version: 9", "version: 4")
            .replace("  - rosbag2-sqlite3.db3", "  - v4/rosbag2-sqlite3.db3")
    });
    let (_, result) = read(&folder, None);
    assert!(
        result
            .unwrap_err()
            .contains("'v4/rosbag2-sqlite3.db3' is missing"),
        "v4"
    );
}

#[test]
fn a_rosbag2_folder_compressed_message_by_message_is_read() {
    // `ros2 bag record --compression-mode message --compression-format zstd`: each message's
    // data one zstd frame, the metadata saying so.
    let dir = temp_dir("rosbag2-message-zstd");
    let folder = copied_folder(&dir, "rosbag2-sqlite3", "zstd", |t| {
        t.replace("compression_format: ''", "compression_format: zstd")
            .replace("compression_mode: ''", "compression_mode: MESSAGE")
    });
    let db = rusqlite::Connection::open(folder.join("rosbag2-sqlite3.db3")).unwrap();
    let rows: Vec<(i64, Vec<u8>)> = db
        .prepare("SELECT id, data FROM messages")
        .unwrap()
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(rows.len(), 1200);
    for (id, data) in rows {
        let packed = zstd::bulk::compress(&data, 3).unwrap();
        db.execute(
            "UPDATE messages SET data = ?1 WHERE id = ?2",
            rusqlite::params![packed, id],
        )
        .unwrap();
    }
    drop(db);
    let (got, result) = read(&folder, None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise_frames(), "zstd messages");
    // Its storage file alone: the compression is named ("no decodable messages" before).
    let e = read(&folder.join("rosbag2-sqlite3.db3"), None)
        .1
        .unwrap_err();
    assert!(
        e.contains("1200 undecodable): each is a zstd frame")
            && e.contains("read through the bag's folder"),
        "{e}"
    );
    // A folder whose metadata does not say so: what it must say.
    let silent = copied_folder(&dir, "rosbag2-sqlite3", "silent", |t| t);
    std::fs::copy(
        folder.join("rosbag2-sqlite3.db3"),
        silent.join("rosbag2-sqlite3.db3"),
    )
    .unwrap();
    let e = read(&silent, None).1.unwrap_err();
    assert!(
        e.contains("whose metadata.yaml says compression_mode: MESSAGE"),
        "{e}"
    );
    // Another format is named, not counted undecodable.
    let lz4 = copied_folder(&dir, "rosbag2-sqlite3", "lz4", |t| {
        t.replace("compression_format: ''", "compression_format: lz4")
            .replace("compression_mode: ''", "compression_mode: MESSAGE")
    });
    let e = read(&lz4, None).1.unwrap_err();
    assert!(
        e.contains("compressed one by one in 'lz4', which is not read (zstd is)"),
        "{e}"
    );
}

#[test]
fn a_rosbag2_folders_metadata_file_reads_its_folder() {
    let folder = fixture_dir("rosbag2-mcap");
    let meta = folder.join("metadata.yaml");
    let (got, result) = read(&meta, None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise_frames(), "metadata.yaml");
    let of_folder = json(&imu_ar(&[
        "noise",
        path(&folder),
        "--topic",
        "/imu0",
        "--column",
        "gx",
        "--json",
    ]));
    let of_meta = json(&imu_ar(&[
        "noise",
        path(&meta),
        "--topic",
        "/imu0",
        "--column",
        "gx",
        "--json",
    ]));
    assert_eq!(of_meta["white_noise"], of_folder["white_noise"]);
    assert_eq!(of_meta["n"], 1200);
}

/// A ROS 1 `sensor_msgs/Imu` of `frame` (seq, stamp, frame_id `imu_link`, 37 float64), as a
/// bag holds it.
fn ros1(frame: &Frame, seq: u32) -> Vec<u8> {
    let mut b = seq.to_le_bytes().to_vec();
    b.extend((frame.stamp_ns.div_euclid(1_000_000_000) as u32).to_le_bytes());
    b.extend((frame.stamp_ns.rem_euclid(1_000_000_000) as u32).to_le_bytes());
    b.extend(8u32.to_le_bytes());
    b.extend(b"imu_link");
    let mut values = [0.0; 37];
    values[13..16].copy_from_slice(&frame.axes[..3]);
    values[25..28].copy_from_slice(&frame.axes[3..]);
    values.iter().for_each(|v| b.extend(v.to_le_bytes()));
    b
}

#[test]
fn an_mcap_file_of_ros1_messages_is_read_as_a_bag_is() {
    // What `mcap convert x.bag x.mcap` writes: schema sensor_msgs/Imu in ros1msg, message
    // encoding ros1, each message's data the bag's.
    let dir = temp_dir("mcap-ros1");
    let frames = noise(300, 2);
    let file = |schema: (&str, &str), encoding: &str| {
        let messages = MessagesOf {
            schema,
            encoding,
            data: |f: &Frame, i| ros1(f, i as u32),
        };
        hand_mcap_of(&messages, &[(1, "/imu0")], &frames, |_| 1)
    };
    let good = dir.join("ros1.mcap");
    std::fs::write(&good, file(("sensor_msgs/Imu", "ros1msg"), "ros1")).unwrap();
    let (got, result) = read(&good, None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &frames, "ros1.mcap");
    // The ROS 1 type in another encoding is named with its encodings.
    let cdr = dir.join("ros1-cdr.mcap");
    std::fs::write(&cdr, file(("sensor_msgs/Imu", "ros1msg"), "cdr")).unwrap();
    let e = read(&cdr, None).1.unwrap_err();
    assert!(
        e.contains("has the ROS 1 type sensor_msgs/Imu in schema encoding 'ros1msg' and message encoding 'cdr'"),
        "{e}"
    );
}

#[test]
fn values_separated_by_tabs_or_semicolons_are_named_for_it() {
    let dir = temp_dir("separators");
    let frames = noise(400, 2);
    for (name, sep, comment) in [
        ("tabs", '\t', ""),
        ("semicolons", ';', ""),
        ("tabs", '\t', "#"),
    ] {
        let mut text =
            format!("{comment}timestamp [ns]{sep}gx [rad/s]{sep}gy [rad/s]{sep}gz [rad/s]\n");
        for f in &frames {
            writeln!(
                text,
                "{}{sep}{:?}{sep}{:?}{sep}{:?}",
                f.stamp_ns, f.axes[0], f.axes[1], f.axes[2]
            )
            .unwrap();
        }
        let file = dir.join(format!("{name}{comment}.txt"));
        std::fs::write(&file, text).unwrap();
        for args in [
            vec!["noise", path(&file), "--column", "gx"],
            vec!["characterise", path(&file), "--out", path(&dir)],
        ] {
            let out = imu_ar(&args);
            assert_one_line_failure(&out);
            assert!(
                stderr(&out).contains(&format!("the values are separated by {name}, not commas")),
                "{name}{comment} {}: {}",
                args[0],
                stderr(&out)
            );
        }
    }
}

/// The files beside the database `file` whose names start with its name (`-wal`, `-shm`,
/// `-journal`).
fn beside(file: &Path) -> Vec<String> {
    let name = file.file_name().unwrap().to_str().unwrap();
    let mut found: Vec<String> = std::fs::read_dir(file.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(name) && n != name)
        .collect();
    found.sort();
    found
}

#[test]
fn a_database_in_wal_mode_is_read_without_writing_beside_it() {
    // rosbag2's `resilient` storage preset records in WAL mode, which the file keeps; the
    // database closed cleanly. The folder's name holds characters a URI escapes.
    use std::os::unix::fs::PermissionsExt as _;
    let dir = temp_dir("db3-wal").join("a b?c#d%e");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bag.db3");
    std::fs::copy(fixture("noise.db3"), &file).unwrap();
    let db = rusqlite::Connection::open(&file).unwrap();
    let mode: String = db
        .query_row("PRAGMA journal_mode=WAL", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
    db.close().unwrap();
    assert_eq!(beside(&file), Vec::<String>::new(), "closed cleanly");
    let (got, result) = read(&file, None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise_frames(), "WAL mode");
    assert_eq!(beside(&file), Vec::<String>::new(), "after the read");
    let out = noise_of(&file, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(beside(&file), Vec::<String>::new(), "after the tool");
    // The file and its folder read-only (as a shared dataset is; root may write anyway).
    std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o444)).unwrap();
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    let (got, result) = read(&file, None);
    let left = beside(&file);
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o644)).unwrap();
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise_frames(), "read-only WAL mode");
    assert_eq!(left, Vec::<String>::new(), "after the read-only read");
    // A write-ahead log that holds changes (a recording still open, or not closed): they are
    // read from it.
    let db = rusqlite::Connection::open(&file).unwrap();
    db.execute_batch("PRAGMA wal_autocheckpoint=0; DELETE FROM messages WHERE id > 600")
        .unwrap();
    assert!(beside(&file).contains(&"bag.db3-wal".to_string()));
    let (got, result) = read(&file, None);
    drop(db);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise_frames()[..600], "changes in the log");
}

#[test]
fn messages_that_mark_a_sensor_as_not_provided_are_counted_for_its_refusal() {
    // sensor_msgs/Imu: -1 in the first element of a covariance means "not provided". A
    // gyro-only IMU marks its accelerometer so, its linear_acceleration zeros or placeholders.
    let dir = temp_dir("not-provided");
    let mut bytes = ros::fixture_bytes("noise.bag");
    for id in ros::frame_ids(&bytes) {
        // linear_acceleration_covariance[0]: after `imu_link`, 28 float64.
        bytes[id + 232..id + 240].copy_from_slice(&(-1.0f64).to_le_bytes());
    }
    let bag_file = dir.join("gyro-only.bag");
    std::fs::write(&bag_file, bytes).unwrap();
    let frames = noise(300, 2);
    // A CDR (ROS 2) message marking the gyro, and a ROS 1 one marking the accelerometer.
    let marked = |data: Vec<u8>, at: usize| {
        let mut data = data;
        data[at..at + 8].copy_from_slice(&(-1.0f64).to_le_bytes());
        data
    };
    let cdr_marked = MessagesOf {
        schema: ("sensor_msgs/msg/Imu", "ros2msg"),
        encoding: "cdr",
        // 4 bytes of encapsulation, 24 of header with `imu_link\0` aligned to 8, 16 float64.
        data: |f: &Frame, _| marked(cdr(f), 4 + 24 + 16 * 8),
    };
    let ros1_marked = MessagesOf {
        schema: ("sensor_msgs/Imu", "ros1msg"),
        encoding: "ros1",
        data: |f: &Frame, i| marked(ros1(f, i as u32), 24 + 28 * 8),
    };
    let cdr_file = dir.join("accel-only.mcap");
    std::fs::write(
        &cdr_file,
        hand_mcap_of(&cdr_marked, &[(1, "/imu0")], &frames, |_| 1),
    )
    .unwrap();
    let ros1_file = dir.join("gyro-only-ros1.mcap");
    std::fs::write(
        &ros1_file,
        hand_mcap_of(&ros1_marked, &[(1, "/imu0")], &frames, |_| 1),
    )
    .unwrap();
    let select = Select::topic("/imu0");
    let bag_frames = noise_frames();
    let cases: [(&Path, u64, u64, &[Frame]); 3] = [
        (&bag_file, 0, bag_frames.len() as u64, &bag_frames),
        (&cdr_file, 300, 0, &frames),
        (&ros1_file, 0, 300, &frames),
    ];
    for (file, gyro, accel, want) in cases {
        let name = file.display().to_string();
        let mut got = Vec::new();
        let each = &mut |f| got.push(f);
        let skipped = if file.extension().unwrap() == "bag" {
            bag::read_selected(file, &select, each)
        } else {
            mcap::read_selected(file, &select, each)
        }
        .unwrap();
        assert_bits(&got, want, &name);
        assert_eq!(
            (skipped.gyro_not_provided, skipped.accel_not_provided),
            (gyro, accel),
            "{name}"
        );
        let (sensor, field, other) = if gyro > 0 {
            ("gyro", "angular_velocity", (false, true))
        } else {
            ("accelerometer", "linear_acceleration", (true, false))
        };
        let total = want.len() as u64;
        let refusal = skipped.not_provided(true, true, total).expect(&name);
        assert_eq!(
            refusal,
            format!(
                "the messages mark the {sensor} as not provided: {field}_covariance[0] = -1 in \
                 {} of the {total} (sensor_msgs/Imu: disregard its values); the {} axes can be \
                 read alone",
                gyro + accel,
                if gyro > 0 {
                    "accelerometer's (ax, ay, az)"
                } else {
                    "gyro's (gx, gy, gz)"
                }
            ),
            "{name}"
        );
        assert_eq!(
            skipped.not_provided(other.0, other.1, total),
            None,
            "{name}"
        );
    }
    // Through the tool: characterise (all six axes) is refused naming the flag (a gyro-only
    // bag read as "ax: constant (a stuck sensor?)", its placeholders modelled, before); the
    // sensor provided is read alone.
    let out = dir.join("out");
    let refused = imu_ar(&[
        "characterise",
        path(&bag_file),
        "--topic",
        "/imu0",
        "--out",
        path(&out),
    ]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(
        stderr(&refused).contains("the messages mark the accelerometer as not provided"),
        "{}",
        stderr(&refused)
    );
    assert!(!out.exists());
    let column = |c: &str| imu_ar(&["noise", path(&bag_file), "--topic", "/imu0", "--column", c]);
    let gyro = column("gx");
    assert_eq!(gyro.status.code(), Some(0), "{}", stderr(&gyro));
    let accel = column("ax");
    assert!(
        stderr(&accel).contains("linear_acceleration_covariance[0] = -1"),
        "{}",
        stderr(&accel)
    );
    // A few messages marked among a record that provides the sensor (a driver's placeholder
    // while the sensor restarts; the whole sensor refused before): 6 of 1200 are skipped and
    // counted, read as the record without them is; 24 (2 %) are refused giving the total.
    let marked_bag = |every: usize| {
        let mut bytes = ros::fixture_bytes("noise.bag");
        for id in ros::frame_ids(&bytes).into_iter().step_by(every) {
            bytes[id + 232..id + 240].copy_from_slice(&(-1.0f64).to_le_bytes());
        }
        let file = dir.join(format!("every-{every}.bag"));
        std::fs::write(&file, bytes).unwrap();
        file
    };
    let few = marked_bag(200);
    let read = imu_ar(&[
        "noise",
        path(&few),
        "--topic",
        "/imu0",
        "--column",
        "ax",
        "--json",
    ]);
    assert_eq!(read.status.code(), Some(0), "{}", stderr(&read));
    assert!(
        stderr(&read).contains("messages skipped: 6 marking a sensor read as not provided"),
        "{}",
        stderr(&read)
    );
    let read = json(&read);
    assert_eq!(read["n"], 1_194, "{read}");
    // characterise counts them and warns as noise does (left out silently before).
    let out = dir.join("few-out");
    let all = imu_ar(&[
        "characterise",
        path(&few),
        "--topic",
        "/imu0",
        "--out",
        path(&out),
        "--json",
    ]);
    assert!(
        stderr(&all).contains("messages skipped: 6 marking a sensor read as not provided"),
        "{}",
        stderr(&all)
    );
    let all = json(&all);
    assert_eq!(
        (&all["n"], &all["skipped"]["not_provided"]),
        (&1_194.into(), &6.into()),
        "{all}"
    );
    let gyro_read = json(&imu_ar(&[
        "noise",
        path(&few),
        "--topic",
        "/imu0",
        "--column",
        "gx",
        "--json",
    ]));
    assert_eq!(gyro_read["n"], 1_200, "{gyro_read}");
    let many = marked_bag(50);
    let refused = imu_ar(&["noise", path(&many), "--topic", "/imu0", "--column", "az"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(
        stderr(&refused).contains("linear_acceleration_covariance[0] = -1 in 24 of the 1200"),
        "{}",
        stderr(&refused)
    );
}

/// A chunked MCAP file of the IMU messages `frames` on `/imu0` (channel 1), in the order
/// given, `per_chunk` of them to an uncompressed chunk, and, when `indexed`, a summary with
/// each chunk's index.
fn chunked_mcap(frames: &[Frame], per_chunk: usize, indexed: bool) -> Vec<u8> {
    let (mut out, schema) = mcap_start(("sensor_msgs/msg/Imu", "ros2msg"));
    record(&mut out, 0x03, &schema);
    let channel = mcap_channel(1, "/imu0", "cdr");
    record(&mut out, 0x04, &channel);
    let mut indexes = Vec::new();
    for (k, group) in frames.chunks(per_chunk).enumerate() {
        let mut records = Vec::new();
        for (i, f) in group.iter().enumerate() {
            let mut m = 1u16.to_le_bytes().to_vec();
            m.extend(((k * per_chunk + i) as u32).to_le_bytes());
            m.extend((f.stamp_ns as u64).to_le_bytes());
            m.extend((f.stamp_ns as u64).to_le_bytes());
            m.extend(cdr(f));
            record(&mut records, 0x05, &m);
        }
        let start = group.iter().map(|f| f.stamp_ns as u64).min().unwrap();
        let end = group.iter().map(|f| f.stamp_ns as u64).max().unwrap();
        let mut chunk = start.to_le_bytes().to_vec();
        chunk.extend(end.to_le_bytes());
        chunk.extend((records.len() as u64).to_le_bytes());
        chunk.extend(0u32.to_le_bytes());
        string(&mut chunk, "");
        chunk.extend((records.len() as u64).to_le_bytes());
        chunk.extend(&records);
        let offset = out.len() as u64;
        record(&mut out, 0x06, &chunk);
        let mut index = start.to_le_bytes().to_vec();
        index.extend(end.to_le_bytes());
        index.extend(offset.to_le_bytes());
        index.extend((out.len() as u64 - offset).to_le_bytes());
        index.extend(0u32.to_le_bytes());
        index.extend(0u64.to_le_bytes());
        string(&mut index, "");
        index.extend((records.len() as u64).to_le_bytes());
        index.extend((records.len() as u64).to_le_bytes());
        indexes.push(index);
    }
    record(&mut out, 0x0f, &0u32.to_le_bytes());
    let summary_start = if indexed { out.len() as u64 } else { 0 };
    if indexed {
        record(&mut out, 0x03, &schema);
        record(&mut out, 0x04, &channel);
        for index in &indexes {
            record(&mut out, 0x08, index);
        }
    }
    mcap_end(&mut out, summary_start);
    out
}

#[test]
fn an_mcap_file_out_of_log_time_order_is_read_in_it_by_its_chunk_index() {
    let dir = temp_dir("mcap-log-time");
    let frames = noise(400, 2);
    // The second half written first; chunks of 50 that follow each other in time otherwise.
    let swapped: Vec<Frame> = frames[200..]
        .iter()
        .chain(&frames[..200])
        .copied()
        .collect();
    // Chunks whose times overlap: each pair of chunks shares a stretch of 100 frames.
    let interleaved: Vec<Frame> = frames
        .chunks(100)
        .flat_map(|c| c.iter().step_by(2).chain(c.iter().skip(1).step_by(2)))
        .copied()
        .collect();
    for (name, order) in [
        ("in-order", &frames),
        ("swapped", &swapped),
        ("overlapping", &interleaved),
    ] {
        let file = dir.join(format!("{name}.mcap"));
        std::fs::write(&file, chunked_mcap(order, 50, true)).unwrap();
        let (got, result) = read(&file, None);
        assert_eq!(result, Ok(0), "{name}");
        assert_bits(&got, &frames, name);
        let out = noise_json(&file, &["--topic", "/imu0"]);
        assert_eq!(out["n"], 400, "{name}");
    }
    // Without a chunk index (unchunked, or chunked with no summary) the order cannot be
    // known before the end: the file's order is named, not the stamps.
    for (name, bytes) in [
        ("unchunked", hand_mcap(&[(1, "/imu0")], &swapped, |_| 1)),
        ("no-summary", chunked_mcap(&swapped, 50, false)),
    ] {
        let file = dir.join(format!("{name}.mcap"));
        std::fs::write(&file, bytes).unwrap();
        let e = read(&file, None).1.unwrap_err();
        assert!(
            e.starts_with("the file's messages are out of log-time order")
                && e.ends_with("and the file has no chunk index to read them in order by"),
            "{name}: {e}"
        );
        let out = noise_of(&file, &[]);
        assert_one_line_failure(&out);
        assert!(
            stderr(&out).contains("out of log-time order")
                && !stderr(&out).contains("--drop-backward"),
            "{name}: {}",
            stderr(&out)
        );
    }
}

#[test]
fn an_mcap_channel_of_another_schema_encoding_lists_the_ones_read() {
    let dir = temp_dir("mcap-json");
    let messages = MessagesOf {
        schema: ("sensor_msgs/msg/Imu", "jsonschema"),
        encoding: "json",
        data: |f: &Frame, _| cdr(f),
    };
    let file = dir.join("json.mcap");
    std::fs::write(
        &file,
        hand_mcap_of(&messages, &[(1, "/imu0")], &noise(10, 2), |_| 1),
    )
    .unwrap();
    assert_eq!(
        read(&file, None).1,
        Err(
            "unknown schema encoding 'jsonschema' on topic '/imu0' (supported: ros2msg, \
             ros2idl, or ros1msg for the ROS 1 type sensor_msgs/Imu)"
                .to_string()
        )
    );
}

#[test]
fn messages_skipped_evenly_keep_the_clocks_rate() {
    // 100 Hz on an exact 10 ms grid, every 250th message with a NaN in ax, or marking the
    // accelerometer as not provided: the holes the reader made, evenly spaced, read as a
    // 99.6 Hz clock's beat with the 10 ms quantum (the rate 0.4 % low, exit 0, before). The
    // skipped messages' stamps are the clock's: 100 Hz, the samples counted.
    let dir = temp_dir("even-holes");
    let mut frames = noise(60_000, 9);
    for (k, f) in frames.iter_mut().enumerate() {
        f.stamp_ns = 1_700_000_000_000_000_000 + 10_000_000 * k as i64;
    }
    let mut nan = frames.clone();
    nan.iter_mut()
        .step_by(250)
        .for_each(|f| f.axes[3] = f64::NAN);
    let file = dir.join("nan.mcap");
    std::fs::write(&file, hand_mcap(&[(1, "/imu0")], &nan, |_| 1)).unwrap();
    let marked = MessagesOf {
        schema: ("sensor_msgs/msg/Imu", "ros2msg"),
        encoding: "cdr",
        // linear_acceleration_covariance[0]: 4 bytes of encapsulation, 24 of header, 28
        // float64.
        data: |f: &Frame, i| {
            let mut data = cdr(f);
            if i % 250 == 0 {
                data[4 + 24 + 28 * 8..4 + 24 + 29 * 8].copy_from_slice(&(-1.0f64).to_le_bytes());
            }
            data
        },
    };
    let flagged = dir.join("flagged.mcap");
    std::fs::write(
        &flagged,
        hand_mcap_of(&marked, &[(1, "/imu0")], &frames, |_| 1),
    )
    .unwrap();
    for (file, skipped) in [
        (&file, "240 not finite"),
        (&flagged, "240 marking a sensor read"),
    ] {
        let out = imu_ar(&[
            "noise",
            path(file),
            "--topic",
            "/imu0",
            "--column",
            "ax",
            "--json",
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        assert!(stderr(&out).contains(skipped), "{}", stderr(&out));
        let got = json(&out);
        assert_eq!(got["n"], 59_760, "{got}");
        assert_eq!(got["timing"]["rate_hz"], 100.0, "{}", got["timing"]);
        // The gyro's axes, finite and provided in every message, are all read.
        let gyro = json(&imu_ar(&[
            "noise",
            path(file),
            "--topic",
            "/imu0",
            "--column",
            "gx",
            "--json",
        ]));
        assert_eq!(gyro["n"], 60_000, "{gyro}");
    }
}

#[test]
fn stamps_put_on_a_fifos_reads_at_another_period_need_the_rate() {
    // A 100 Hz clock read 16 samples at a time, stamped 9.52 ms apart back from the read (a
    // driver's nominal 105 Hz): read at 106.25 Hz with a sample "missing" in every 16, exit
    // 0, before, and the right --rate refused. Now named, and read at the rate given where
    // the stamps' span gives it, as the same samples stamped at their own period are.
    let dir = temp_dir("fifo-reads");
    let frames = noise(16 * 1_250, 7);
    let at_reads: Vec<Frame> = frames
        .iter()
        .enumerate()
        .map(|(k, f)| Frame {
            stamp_ns: frames[0].stamp_ns + (k / 16 + 1) as i64 * 160_000_000
                - (15 - k % 16) as i64 * 9_520_000,
            ..*f
        })
        .collect();
    let on_clock: Vec<Frame> = frames
        .iter()
        .enumerate()
        .map(|(k, f)| Frame {
            stamp_ns: frames[0].stamp_ns + k as i64 * 10_000_000,
            ..*f
        })
        .collect();
    let reads = csv_of(&dir, "reads.csv", &at_reads);
    let clock = csv_of(&dir, "clock.csv", &on_clock);
    for args in [
        vec!["noise", path(&reads), "--column", "gx"],
        vec!["adev", path(&reads), "--column", "gx"],
        vec!["characterise", path(&reads), "--out", path(&dir)],
    ] {
        let run = imu_ar(&args);
        assert_one_line_failure(&run);
        let e = stderr(&run);
        assert!(
            e.contains("runs of 16 samples 0.00952 s apart")
                && e.contains("their span less its pauses gives 100.0")
                && e.ends_with("give --rate\n"),
            "{args:?}: {e}"
        );
    }
    let run = imu_ar(&[
        "noise",
        path(&reads),
        "--column",
        "gx",
        "--rate",
        "100",
        "--json",
    ]);
    assert!(stderr(&run).contains("warning") && stderr(&run).contains("runs of 16"));
    let (given, own) = (json(&run), noise_json(&clock, &[]));
    assert_eq!(given["white_noise"], own["white_noise"], "{given}\n{own}");
    assert_eq!(given["random_walk"], own["random_walk"]);
    let run = imu_ar(&["noise", path(&reads), "--column", "gx", "--rate", "106.25"]);
    assert_one_line_failure(&run);
    assert!(
        stderr(&run).contains("the timestamps give 100.0"),
        "{}",
        stderr(&run)
    );
    // Samples lost within the runs leave no mark: a rate up to 5 % above the span's is
    // taken, with the warning (2 % lost: the right --rate refused, before); one below it is
    // not.
    let run = imu_ar(&["noise", path(&reads), "--column", "gx", "--rate", "102"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("a --rate up to 5 % above it is taken"));
    for rate in ["98", "105.5"] {
        let run = imu_ar(&["noise", path(&reads), "--column", "gx", "--rate", rate]);
        assert_one_line_failure(&run);
    }
}

#[test]
fn a_rosbag2_folder_is_checked_against_its_metadatas_counts_and_files_order() {
    // Its one file split in two by time, x_0.db3 and x_1.db3, with the metadata listing them.
    let dir = temp_dir("rosbag2-split");
    let split = |to: &str, list: &[&str], count: u64| {
        let folder = copied_folder(&dir, "rosbag2-sqlite3", to, |t| {
            let files: String = list.iter().map(|f| format!("  - {f}\n")).collect();
            t.replace("  - rosbag2-sqlite3.db3\n", &files).replace(
                "  - message_count: 1200\n",
                &format!("  - message_count: {count}\n"),
            )
        });
        let whole = folder.join("rosbag2-sqlite3.db3");
        for (k, keep) in ["<=", ">"].into_iter().enumerate() {
            let part = folder.join(format!("x_{k}.db3"));
            std::fs::copy(&whole, &part).unwrap();
            let db = rusqlite::Connection::open(&part).unwrap();
            let cut = "(SELECT timestamp FROM messages ORDER BY timestamp LIMIT 1 OFFSET 599)";
            let kept = db
                .execute(
                    &format!("DELETE FROM messages WHERE NOT timestamp {keep} {cut}"),
                    [],
                )
                .unwrap();
            assert_eq!(kept, 600);
        }
        std::fs::remove_file(whole).unwrap();
        folder
    };
    // In order: the record, as the one file reads it.
    let (got, result) = read(&split("ordered", &["x_0.db3", "x_1.db3"], 1200), None);
    assert_eq!(result, Ok(0));
    assert_bits(&got, &noise_frames(), "split in order");
    // Listed out of order: named as such (refused as 600 stamps "not after the one before",
    // with a --drop-backward hint, which then read half the record, before).
    let e = read(&split("reversed", &["x_1.db3", "x_0.db3"], 1200), None)
        .1
        .unwrap_err();
    assert!(
        e.contains("'x_0.db3' begins at") && e.contains("lists the files out of order"),
        "{e}"
    );
    // One file left off the list, the metadata counting both: refused naming it (half the
    // record read with no warning, before).
    let e = read(&split("one-listed", &["x_0.db3"], 1200), None)
        .1
        .unwrap_err();
    assert!(
        e.contains("it counts 1200 messages on '/imu0' and its storage files hold 600")
            && e.contains("the folder holds 'x_1.db3', which relative_file_paths does not list"),
        "{e}"
    );
    // One file listed twice (read as "not after the one before", pass 51 F7): named.
    let e = read(&split("twice", &["x_0.db3", "x_0.db3"], 1200), None)
        .1
        .unwrap_err();
    assert!(
        e.contains("relative_file_paths lists 'x_0.db3' twice"),
        "{e}"
    );
    // Both listed, the metadata counting more: a file is damaged.
    let e = read(&split("more-counted", &["x_0.db3", "x_1.db3"], 1300), None)
        .1
        .unwrap_err();
    assert!(e.contains("a storage file is damaged or cut short"), "{e}");
    let meta = rosbag2::Metadata::parse(
        &std::fs::read_to_string(fixture_dir("rosbag2-mcap").join("metadata.yaml")).unwrap(),
    )
    .unwrap();
    assert_eq!(meta.topic_counts, [("/imu0".to_string(), 1200)]);
}

#[test]
fn a_bag_whose_index_holds_fewer_connections_than_its_header_declares_is_named_damaged() {
    // The header's conn_count past the connection records in the index: refused as "no
    // topics" where the index lost the IMU's connection, before (pass 47 F4).
    let dir = temp_dir("bag-conn-count");
    let mut bytes = std::fs::read(fixture("noise.bag")).unwrap();
    let at = bytes.windows(11).position(|w| w == b"conn_count=").unwrap() + 11;
    let held = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    bytes[at..at + 4].copy_from_slice(&(held + 1).to_le_bytes());
    let file = dir.join("conn-count.bag");
    std::fs::write(&file, bytes).unwrap();
    let e = read(&file, None).1.unwrap_err();
    assert!(
        e.contains(&format!(
            "its header declares {} connections and its index holds {held}",
            held + 1
        )) && e.contains("`rosbag reindex` rebuilds it"),
        "{e}"
    );
}
