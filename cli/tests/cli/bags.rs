//! The ROS readers (`input::bag`, `input::mcap`) against files written by the Python package
//! `rosbags` (committed fixtures, `cli/tests/fixtures/write_ros.py`): every frame back bit for
//! bit, for every compression; each error's text; what is skipped; and no panic on truncated,
//! bit-flipped or random bytes, all derived in Rust from the committed files. The read speed
//! (it writes its files with the script): `cargo test --release -p imu-ar-cli --test cli -- bags::
//! --ignored --nocapture`.

use crate::ros;

use std::collections::BTreeMap;
use std::time::Instant;

use imu_ar_cli::input::frame::{Frame, Select, Skipped};
use imu_ar_cli::input::{bag, mcap as mcap_reader};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use ros::*;

#[test]
fn every_frame_back_bit_for_bit() {
    let want = round_trip_frames();
    for (format, compressions) in [
        ("ros1", ["none", "bz2", "lz4"]),
        ("mcap", ["none", "zstd", "lz4"]),
    ] {
        for compression in compressions {
            let path = fixture(&format!("frames-{compression}.{}", extension(format)));
            let (got, result) = collect(reader(format), &path, "/imu");
            assert_eq!(result, Ok(Skipped::default()), "{format} {compression}");
            assert_bits(&got, &want, &format!("{format} {compression}"));
        }
    }
    // Eight MCAP chunks, more than the reader reads at once.
    let path = fixture("chunks.mcap");
    assert!(std::fs::metadata(&path).unwrap().len() > 256 * 1024);
    let (got, result) = collect(mcap_reader::read, &path, "/imu");
    assert_eq!(result, Ok(Skipped::default()), "chunks.mcap");
    assert_bits(&got, &frames(800, 13), "chunks.mcap");
    // The static-IMU frames the commands' tests read (characterise.rs).
    for name in ["noise.bag", "noise-bz2.bag", "noise-zstd.mcap"] {
        let read = if name.ends_with(".bag") {
            bag::read
        } else {
            mcap_reader::read
        };
        let (got, result) = collect(read, &fixture(name), "/imu0");
        assert_eq!(result, Ok(Skipped::default()), "{name}");
        assert_bits(&got, &noise_frames(), name);
    }
}

#[test]
fn big_endian_cdr_and_every_frame_id_alignment() {
    // Hand-made CDR: frame_id lengths 0 to 9 move the float64s to each alignment case.
    let dir = temp_dir("cdr");
    let want = frames(20, 2);
    let path = dir.join("hand.mcap");
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&path).unwrap(),
    ))
    .unwrap();
    let schema = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", b"").unwrap();
    let channel = w
        .add_channel(schema, "/imu", "cdr", &BTreeMap::new())
        .unwrap();
    for (i, f) in want.iter().enumerate() {
        let big = i % 2 == 1;
        let u32b = |v: u32| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        };
        let mut b = vec![0, u8::from(!big), 0, 0];
        b.extend(u32b(f.stamp_ns.div_euclid(1_000_000_000) as u32));
        b.extend(u32b(f.stamp_ns.rem_euclid(1_000_000_000) as u32));
        let id_len = i % 10;
        b.extend(u32b(id_len as u32 + 1));
        b.extend(std::iter::repeat_n(b'f', id_len));
        b.push(0);
        while (b.len() - 4) % 8 != 0 {
            b.push(0xee);
        }
        let mut values = [0.5; 37];
        values[13..16].copy_from_slice(&f.axes[..3]);
        values[25..28].copy_from_slice(&f.axes[3..]);
        for v in values {
            b.extend(if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: i as u32,
            log_time: 0,
            publish_time: 0,
        };
        w.write_to_known_channel(&header, &b).unwrap();
    }
    w.finish().unwrap();
    drop(w);
    // Each frame_id length is one IMU of the topic: read one at a time.
    for id_len in 0..10 {
        let id = "f".repeat(id_len);
        let select = Select {
            frame_id: Some(&id),
            ..Select::topic("/imu")
        };
        let mut got = Vec::new();
        let result = mcap_reader::read_selected(&path, &select, &mut |f| got.push(f));
        assert_eq!(
            result,
            Ok(Skipped {
                other_frame_id: 18,
                ..Skipped::default()
            })
        );
        let mine: Vec<Frame> = want.iter().skip(id_len).step_by(10).copied().collect();
        assert_bits(&got, &mine, "hand-made CDR");
    }
}

#[test]
fn an_absent_topic_lists_the_imu_topics() {
    for (format, imu) in [("ros1", "sensor_msgs/Imu"), ("mcap", "sensor_msgs/msg/Imu")] {
        let ext = extension(format);
        let read = reader(format);
        // The IMU on /imu0, strings on /chatter.
        let path = fixture(&format!("chatter.{ext}"));
        assert_eq!(
            problem(&path, read(&path, "/imu", &mut |_| {})),
            format!("no {imu} messages on topic '/imu' (IMU topics: /imu0)")
        );
        assert_bits(&collect(read, &path, "/imu0").0, &frames(10, 3), "/imu0");
        // Strings on /a and /b only.
        let path = fixture(&format!("strings.{ext}"));
        assert_eq!(
            problem(&path, read(&path, "/imu", &mut |_| {})),
            format!("no {imu} messages on topic '/imu' (no IMU topics; topics: /a, /b)")
        );
    }
}

#[test]
fn a_topic_of_another_type_is_named() {
    for (format, want) in [
        (
            "ros1",
            "topic '/imu' has type std_msgs/String, not sensor_msgs/Imu",
        ),
        (
            "mcap",
            "topic '/imu' has type std_msgs/msg/String, not sensor_msgs/msg/Imu",
        ),
    ] {
        // A string on /imu, the IMU on /imu0.
        let path = fixture(&format!("string-on-imu.{}", extension(format)));
        let (got, result) = collect(reader(format), &path, "/imu");
        assert_eq!(problem(&path, result), want);
        assert!(got.is_empty());
        // The IMU topic of the same file reads.
        assert_bits(
            &collect(reader(format), &path, "/imu0").0,
            &frames(10, 4),
            format,
        );
    }
}

#[test]
fn a_topic_of_two_types_names_both() {
    // Three strings (connection 0) and ten IMU messages (connection 1) on /imu0.
    let path = fixture("string-and-imu.bag");
    let (got, result) = collect(reader("ros1"), &path, "/imu0");
    assert_eq!(
        problem(&path, result),
        "topic '/imu0' carries sensor_msgs/Imu (connection 1) and std_msgs/String (connection \
         0): one topic, one type of message; keep the IMU's connections (rosbag \
         filter) and read those"
    );
    assert!(got.is_empty());
    // In MCAP: an IMU channel and a string channel on one topic, in either order.
    for imu_first in [true, false] {
        let path = temp_dir("two-types").join(format!("two-types-{imu_first}.mcap"));
        let mut w = mcap::Writer::new(std::fs::File::create(&path).unwrap()).unwrap();
        let imu = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", b"").unwrap();
        let string = w.add_schema("std_msgs/msg/String", "ros2msg", b"").unwrap();
        let order = if imu_first {
            [imu, string]
        } else {
            [string, imu]
        };
        for schema in order {
            w.add_channel(schema, "/imu", "cdr", &BTreeMap::new())
                .unwrap();
        }
        w.finish().unwrap();
        drop(w);
        let (imu, string) = if imu_first { (1, 2) } else { (2, 1) };
        assert_eq!(
            problem(&path, mcap_reader::read(&path, "/imu", &mut |_| {})),
            format!(
                "topic '/imu' carries sensor_msgs/msg/Imu (channel {imu}) and \
                 std_msgs/msg/String (channel {string}): one topic, one type of message; copy \
                 the IMU's channel into a file of its own (the mcap library's reader and \
                 writer) and read that"
            )
        );
    }
}

#[test]
fn other_mcap_encodings_are_refused() {
    let dir = temp_dir("encoding");
    // The IMU channel declared as json (its bytes are CDR).
    let path = fixture("json.mcap");
    assert_eq!(
        problem(&path, mcap_reader::read(&path, "/imu", &mut |_| {})),
        "unknown encoding 'json' on topic '/imu' (supported: cdr)"
    );
    // A schema in another encoding, from the mcap crate's writer.
    let path = dir.join("jsonschema.mcap");
    let mut w = mcap::Writer::new(std::fs::File::create(&path).unwrap()).unwrap();
    let schema = w
        .add_schema("sensor_msgs/msg/Imu", "jsonschema", b"{}")
        .unwrap();
    w.add_channel(schema, "/imu", "cdr", &BTreeMap::new())
        .unwrap();
    w.finish().unwrap();
    drop(w);
    assert_eq!(
        problem(&path, mcap_reader::read(&path, "/imu", &mut |_| {})),
        "unknown schema encoding 'jsonschema' on topic '/imu' (supported: ros2msg, ros2idl, or \
         ros1msg for the ROS 1 type sensor_msgs/Imu)"
    );
}

#[test]
fn truncated_files_are_errors_even_after_frames() {
    let dir = temp_dir("truncated");
    let want = round_trip_frames();
    for (format, compression, start) in [
        ("ros1", "none", "truncated or corrupt bag: "),
        ("ros1", "lz4", "truncated or corrupt bag: "),
        ("mcap", "none", "truncated or corrupt MCAP file: "),
        ("mcap", "zstd", "truncated or corrupt MCAP file: "),
    ] {
        let bytes = fixture_bytes(&format!("frames-{compression}.{}", extension(format)));
        let cut = dir.join("cut");
        let n = bytes.len();
        for at in [
            0,
            5,
            12,
            13,
            20,
            100,
            4000,
            4200,
            n / 3,
            n / 2,
            n - 100,
            n - 1,
        ] {
            std::fs::write(&cut, &bytes[..at]).unwrap();
            let (got, result) = collect(reader(format), &cut, "/imu");
            let p = problem(&cut, result);
            assert!(
                p.starts_with(start),
                "{format} {compression} cut at {at}: {p}"
            );
            // The frames of the whole chunks before the cut may have come, then the error.
            assert_bits(&got, &want[..got.len()], "before the cut");
        }
    }
    // Streamed chunk by chunk: an MCAP file of eight chunks cut in the middle delivers the
    // frames of the chunks before the cut, then the error.
    let bytes = fixture_bytes("chunks.mcap");
    let cut = dir.join("cut-chunks.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let (got, result) = collect(mcap_reader::read, &cut, "/imu");
    assert!(problem(&cut, result).starts_with("truncated or corrupt MCAP file: "));
    assert!(
        got.len() >= 200 && got.len() % 100 == 0,
        "{} frames",
        got.len()
    );
    assert_bits(&got, &frames(800, 13)[..got.len()], "chunks before the cut");
    // Cut where a record ends (a recording killed between two chunks): said so, not "in the
    // middle of a record" (pass 49 F3); cut within the next, the byte its record began at.
    let mut ends = Vec::new();
    let mut at = 8;
    while at + 9 <= bytes.len() {
        at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        ends.push(at);
    }
    let boundary = ends[ends.len() / 2];
    std::fs::write(&cut, &bytes[..boundary]).unwrap();
    let p = problem(&cut, collect(mcap_reader::read, &cut, "/imu").1);
    assert!(
        p.contains("it ends after its last whole record, without its footer"),
        "{p}"
    );
    std::fs::write(&cut, &bytes[..boundary + 20]).unwrap();
    let p = problem(&cut, collect(mcap_reader::read, &cut, "/imu").1);
    assert!(
        p.contains(&format!(
            "in the middle of a record begun at byte {boundary}"
        )),
        "{p}"
    );
    // Cut within the closing magic, or just before it: its footer whole (said to end
    // "without its footer", or within a record begun at the magic, pass 51 F8).
    let n = bytes.len();
    for at in [n - 8, n - 3] {
        std::fs::write(&cut, &bytes[..at]).unwrap();
        let p = problem(&cut, collect(mcap_reader::read, &cut, "/imu").1);
        assert!(
            p.contains(&format!(
                "closing magic is cut short after its footer (at byte {}",
                n - 8
            )),
            "{at}: {p}"
        );
    }
    // A bag whose second chunk is damaged: the first chunk's frames, then the error.
    let mut bytes = fixture_bytes("frames-none.bag");
    let chunks: Vec<usize> = find_all(&bytes, b"compression=none");
    assert!(chunks.len() >= 2, "{} chunks", chunks.len());
    bytes[chunks[1] + 12..chunks[1] + 16].copy_from_slice(b"nope");
    let path = dir.join("damaged-chunk.bag");
    std::fs::write(&path, &bytes).unwrap();
    let (got, result) = collect(bag::read, &path, "/imu");
    let p = problem(&path, result);
    assert!(
        p.starts_with("truncated or corrupt bag: invalid header (in the chunk section, after "),
        "{p}"
    );
    assert!(
        !got.is_empty() && got.len() < want.len(),
        "{} frames",
        got.len()
    );
    assert_bits(&got, &want[..got.len()], "before the damaged chunk");
}

#[test]
fn other_files_are_named() {
    let dir = temp_dir("other");
    let mut noise = vec![0u8; 8192];
    ChaCha8Rng::seed_from_u64(7).fill_bytes(&mut noise);
    let path = dir.join("noise");
    std::fs::write(&path, &noise).unwrap();
    assert_eq!(
        problem(&path, bag::read(&path, "/imu", &mut |_| {})),
        "not a ROS 1 bag (it does not start with '#ROSBAG V2.0')"
    );
    assert_eq!(
        problem(&path, mcap_reader::read(&path, "/imu", &mut |_| {})),
        "not an MCAP file (it does not start with the MCAP magic)"
    );
    let bag_path = fixture("frames-none.bag");
    let mcap_path = fixture("frames-none.mcap");
    assert_eq!(
        problem(&bag_path, mcap_reader::read(&bag_path, "/imu", &mut |_| {})),
        "not an MCAP file: a ROS 1 bag (read it as a bag)"
    );
    assert_eq!(
        problem(&mcap_path, bag::read(&mcap_path, "/imu", &mut |_| {})),
        "not a ROS 1 bag: an MCAP file (read it as MCAP)"
    );
    let missing = dir.join("missing.bag");
    assert!(
        problem(&missing, bag::read(&missing, "/imu", &mut |_| {})).starts_with("cannot open: ")
    );
}

#[test]
fn non_finite_and_undecodable_messages_are_counted() {
    let dir = temp_dir("skipped");
    let mut want = frames(50, 9);
    want[3].axes[0] = f64::NAN;
    want[7].axes[5] = f64::INFINITY;
    want[8].axes[2] = f64::NEG_INFINITY;
    for format in ["ros1", "mcap"] {
        let name = format!("non-finite.{}", extension(format));
        let path = fixture(&name);
        let (got, result) = collect(reader(format), &path, "/imu");
        let skipped = Skipped {
            undecodable: 0,
            non_finite: 3,
            ..Skipped::default()
        };
        assert_eq!(result, Ok(skipped), "{format}");
        let finite: Vec<Frame> = want
            .iter()
            .copied()
            .filter(|f| f.axes.iter().all(|v| v.is_finite()))
            .collect();
        assert_bits(&got, &finite, format);

        // frame_id "imu_link" given another length: that message no longer decodes.
        let mut bytes = fixture_bytes(&name);
        let ids = frame_ids(&bytes);
        let len_at = ids[10] - 4;
        bytes[len_at..len_at + 4].copy_from_slice(&1000u32.to_le_bytes());
        let path = dir.join(&name);
        std::fs::write(&path, &bytes).unwrap();
        let (got, result) = collect(reader(format), &path, "/imu");
        assert_eq!(
            result,
            Ok(Skipped {
                undecodable: 1,
                non_finite: 3,
                ..Skipped::default()
            }),
            "{format}"
        );
        assert_eq!(got.len(), finite.len() - 1);
    }
}

#[test]
fn no_decodable_message_is_an_error() {
    let dir = temp_dir("none");
    for format in ["ros1", "mcap"] {
        let ext = extension(format);
        let empty = fixture(&format!("empty.{ext}"));
        assert_eq!(
            problem(&empty, reader(format)(&empty, "/imu", &mut |_| {})),
            "no decodable messages on '/imu' (0 undecodable)"
        );
        let one = fixture(&format!("one.{ext}"));
        assert_bits(
            &collect(reader(format), &one, "/imu").0,
            &frames(1, 10),
            "one",
        );
        let mut bytes = fixture_bytes(&format!("one.{ext}"));
        let at = frame_ids(&bytes)[0] - 4;
        bytes[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let path = dir.join(format!("one.{ext}"));
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(
            problem(&path, reader(format)(&path, "/imu", &mut |_| {})),
            "no decodable messages on '/imu' (1 undecodable)"
        );
        // Two frames, each with a NaN.
        let path = fixture(&format!("all-nan.{ext}"));
        assert_eq!(
            problem(&path, reader(format)(&path, "/imu", &mut |_| {})),
            "no finite messages on '/imu' (0 undecodable, 2 with a NaN or infinite axis)"
        );
    }
}

#[test]
fn damaged_bytes_never_panic() {
    let dir = temp_dir("fuzz");
    let seeds: Vec<Vec<u8>> = [
        "frames-none.bag",
        "frames-bz2.bag",
        "frames-lz4.bag",
        "frames-none.mcap",
        "frames-zstd.mcap",
        "frames-lz4.mcap",
    ]
    .map(fixture_bytes)
    .into();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let path = dir.join("mutant");
    let mut outcomes = [0usize; 2];
    for i in 0..2000 {
        let seed = &seeds[i % seeds.len()];
        let mut bytes = seed.clone();
        match rng.next_u32() % 5 {
            0 => bytes.truncate(rng.next_u32() as usize % bytes.len()),
            1 => {
                for _ in 0..1 + rng.next_u32() % 8 {
                    let at = rng.next_u32() as usize % bytes.len();
                    bytes[at] ^= 1 << (rng.next_u32() % 8);
                }
            }
            2 => {
                let at = rng.next_u32() as usize % bytes.len();
                let end = (at + 1 + rng.next_u32() as usize % 16).min(bytes.len());
                rng.fill_bytes(&mut bytes[at..end]);
            }
            3 => {
                // A length field set to an extreme.
                let at = rng.next_u32() as usize % (bytes.len() - 8);
                let v = [u32::MAX, 0x8000_0000, 0, 1][rng.next_u32() as usize % 4];
                bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            _ => {
                let mut noise = vec![0u8; rng.next_u32() as usize % 5000];
                rng.fill_bytes(&mut noise);
                let keep = rng.next_u32() as usize % 64;
                noise.splice(0..0, seed[..keep].iter().copied());
                bytes = noise;
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        for (k, read) in [bag::read as Reader, mcap_reader::read]
            .into_iter()
            .enumerate()
        {
            let outcome = std::panic::catch_unwind(|| read(&path, "/imu", &mut |_| {}));
            match outcome {
                Ok(result) => outcomes[k] += usize::from(result.is_ok()),
                Err(_) => {
                    let keep = dir.join(format!("panic-{i}-{k}"));
                    std::fs::copy(&path, &keep).unwrap();
                    panic!(
                        "reader {k} panicked on mutant {i}, kept as {}",
                        keep.display()
                    );
                }
            }
        }
    }
    println!(
        "mutants read without an error: bag {}, mcap {}",
        outcomes[0], outcomes[1]
    );
}

/// The file `speed-{compression}.{ext}` of `IMU_AR_SPEED_DIR`, which the fixture script wrote
/// from `frames(1_000_000, 14)` (the test starts no program):
/// `python3 cli/tests/fixtures/write_ros.py one DIR/speed-none.bag ros1 /imu none FRAMES.csv`.
fn speed_file(format: &str, compression: &str) -> std::path::PathBuf {
    let dir = std::env::var_os("IMU_AR_SPEED_DIR")
        .expect("IMU_AR_SPEED_DIR: the folder of the speed files");
    std::path::Path::new(&dir).join(format!("speed-{compression}.{}", extension(format)))
}

#[test]
#[ignore = "reads 1 M-message files from IMU_AR_SPEED_DIR (written beforehand by \
            tests/fixtures/write_ros.py one); run with --release --ignored --nocapture"]
fn read_speed() {
    let n = 1_000_000;
    let first = frames(1, 14)[0];
    for (format, compression) in [
        ("ros1", "none"),
        ("ros1", "lz4"),
        ("mcap", "none"),
        ("mcap", "zstd"),
    ] {
        let path = speed_file(format, compression);
        let size = std::fs::metadata(&path).unwrap().len();
        let before = rss_anon_kb();
        let mut peak = before;
        let mut count = 0usize;
        let mut check = 0u64;
        let start = Instant::now();
        let result = reader(format)(&path, "/imu", &mut |f| {
            count += 1;
            if count == 1 {
                assert_eq!(
                    f.stamp_ns, first.stamp_ns,
                    "the speed file holds frames(1_000_000, 14)"
                );
            }
            check ^= f.axes[0].to_bits();
            if count.is_multiple_of(100_000) {
                peak = peak.max(rss_anon_kb());
            }
        });
        let secs = start.elapsed().as_secs_f64();
        assert_eq!(result, Ok(Skipped::default()));
        assert_eq!(count, n);
        println!(
            "{format} {compression}: {n} messages, {:.0} MB, in {secs:.3} s: {:.2} M messages/s, \
             {:.2} s per million; heap grew by {} kB (check {check:x})",
            size as f64 / 1e6,
            n as f64 / secs / 1e6,
            secs / (n as f64 / 1e6),
            peak.saturating_sub(before)
        );
    }
}
