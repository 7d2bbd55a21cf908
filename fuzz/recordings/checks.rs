//! What the fuzz targets of the readers check, one function per target: the targets
//! (`fuzz_targets/*.rs`) call these on libFuzzer's inputs, and the readers' tests
//! (`recordings/tests/fuzz_corpora.rs`) replay every kept corpus file through them on the stable
//! toolchain, so the test command checks the corpora without a sanitised build.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use imu_ar_recordings::csv::{DataError, parse_column};
use imu_ar_recordings::dataflash::{self, Kind};
use imu_ar_recordings::frame::{Frame, Select, Skipped};
use imu_ar_recordings::rosbag2::Metadata;
use imu_ar_recordings::ulog::{self, Topic, Which};
use imu_ar_recordings::{bag, mcap, rosbag2};

/// The CSV reader on arbitrary bytes: a column of finite numbers, or an error naming the source
/// and, for a bad row, its line; never a panic.
pub fn csv_column(data: &[u8]) {
    let label = Path::new("fuzz.csv");
    match parse_column(label, data, "x") {
        Ok(x) => assert!(!x.is_empty() && x.iter().all(|v| v.is_finite())),
        Err(e) => assert!(e.to_string().starts_with("fuzz.csv")),
    }
}

/// The stamps' statistics on a clock shaped by the bytes: the first eight set its period (1 us
/// to 65 ms), the quantum its stamps are floored to (none, 1 us, 1 ms), the epoch (0 or past
/// 2001) and a drift; each further byte is one sample's fate (stamped on time, jittered by up
/// to a quarter period, lost, repeated, a gap of some periods, or caught up a few at once, as
/// hosts do), its stamps pushed as a reader pushes them (repeats kept, stopping at the first
/// stamp back, which a reader refuses). The summary is an error, or a rate and a span rate
/// that are finite and positive, samples missing no more than the span holds; never a panic.
pub fn timing_summary(data: &[u8]) {
    use imu_ar_recordings::timing::{Step, TimeUnit, Timing};
    let Some((head, fates)) = data.split_first_chunk::<8>() else {
        return;
    };
    let period = 1e3 + 1e3 * f64::from(u16::from_le_bytes([head[0], head[1]]));
    let quantum = [1i64, 1_000, 1_000_000, 1][usize::from(head[2] & 3)];
    let epoch = if head[2] & 4 == 0 {
        0
    } else {
        1_600_000_000_000_000_000
    };
    let drift = f64::from(i8::from_le_bytes([head[3]])) * 1e-5;
    let mut timing = Timing::new();
    let (mut place, mut late) = (1.0f64, 0.0f64);
    let mut last = None;
    for &fate in fates {
        let now = place * period * (1.0 + drift * place / (fates.len() as f64 + 1.0));
        let jitter = f64::from(fate & 0x3f) / 256.0 * period;
        let t = match fate >> 6 {
            0 => now + late,
            1 => now + late + jitter,
            2 if fate & 1 == 0 => {
                // A gap of 1 to 31 periods.
                place += f64::from((fate >> 1) & 31);
                continue;
            }
            2 => last.map_or(now, |l: f64| l),
            _ => {
                // A host's stall of up to 63 periods, caught up on by the samples after it.
                late = f64::from(fate & 0x3f) * period;
                now + late
            }
        };
        late = (late - 0.8 * period).max(0.0);
        place += 1.0;
        let stamp = epoch + (t as i64).div_euclid(quantum) * quantum;
        last = Some(t);
        match timing.push(stamp) {
            Step::Forward => {}
            Step::Repeat => timing.keep_repeat(),
            Step::Backward { .. } => break,
        }
    }
    // The same stamps said to be placed at a rate near the clock's (a batch sampler's,
    // a FIFO's messages counted): its summary holds the same.
    let mut placed = timing.clone();
    placed.placed_at(1e9 / period * (1.0 + f64::from(i8::from_le_bytes([head[4]])) * 1e-3));
    for s in [&timing, &placed].map(|t| t.summary(TimeUnit::Nanoseconds)) {
        let Ok(s) = s else { continue };
        assert!(s.rate_hz.is_finite() && s.rate_hz > 0.0, "{s:?}");
        assert!(s.span_rate_hz.is_finite() && s.span_rate_hz > 0.0, "{s:?}");
        assert!(s.span_s.is_finite() && s.span_s > 0.0, "{s:?}");
        assert!(
            (s.missing_samples as f64) <= s.span_s * s.rate_hz + 1.0,
            "{s:?}: {} missing over {} s at {} Hz",
            s.missing_samples,
            s.span_s,
            s.rate_hz
        );
        // The warnings the summary gives are one line each, with no NaN.
        for w in [s.loose_warning(), s.quantum_warning(), s.coarse_warning()]
            .into_iter()
            .flatten()
        {
            assert!(!w.contains('\n') && !w.contains("NaN"), "{w}");
        }
    }
}

/// A cell as the CSV reader reads it, against the standard library: every text that
/// `str::parse::<f64>` reads to a finite number is read to the same bits (the reader's own
/// parser of plain decimals, or fast-float2 for the rest); anything it reads is finite.
pub fn decimal_number(data: &[u8]) {
    // The bytes as a plain decimal too (a sign, digits, a point where the first byte says):
    // the reader's own parser's path, every length and digit.
    if let Some((&first, digits)) = data.split_first() {
        let mut text: String = digits.iter().map(|b| char::from(b'0' + b % 10)).collect();
        text.insert(usize::from(first >> 1) % (text.len() + 1), '.');
        if first & 1 == 1 {
            text.insert(0, '-');
        }
        same_as_std(&text);
    }
    if let Ok(text) = std::str::from_utf8(data) {
        same_as_std(text);
    }
}

/// [`decimal_number`]'s check of one text.
fn same_as_std(text: &str) {
    let ours = imu_ar_recordings::csv::finite("x")(text);
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => match ours {
            Ok(o) => assert_eq!(o.to_bits(), v.to_bits(), "{text:?}: {o} against {v}"),
            Err(e) => panic!("{text:?}: {e}, the standard library reads {v}"),
        },
        _ => {
            if let Ok(o) = ours {
                assert!(o.is_finite(), "{text:?}: {o}");
            }
        }
    }
}

/// A scratch file of its own for each call (the tests replay on several threads).
fn scratch(extension: &str) -> PathBuf {
    static CALLS: AtomicU64 = AtomicU64::new(0);
    let call = CALLS.fetch_add(1, Ordering::Relaxed);
    let name = format!("imu-ar-fuzz-{}-{call}.{extension}", std::process::id());
    std::env::temp_dir().join(name)
}

/// The ROS readers (ROS 1 bag, MCAP, rosbag2 SQLite database) on arbitrary bytes: the first
/// byte picks the reader (240 and up: a rosbag2 folder compressed message by message, of MCAP
/// or SQLite storage), the rest is the file, read with and without a frame_id. Every
/// delivered frame is finite, a success delivered at least one, an error names the file, and
/// nothing panics.
pub fn ros_read(data: &[u8]) {
    let Some((&which, bytes)) = data.split_first() else {
        return;
    };
    type Read = fn(&Path, &Select, &mut dyn FnMut(Frame)) -> Result<Skipped, DataError>;
    if which >= 240 {
        return compressed_folder(which % 2 == 0, bytes);
    }
    let (extension, read): (&str, Read) = match which % 3 {
        0 => ("bag", bag::read_selected),
        1 => ("mcap", mcap::read_selected),
        _ => ("db3", rosbag2::read_db3),
    };
    let path = scratch(extension);
    std::fs::write(&path, bytes).expect("a scratch file in the temporary folder");
    for select in [
        Select::topic("/imu0"),
        Select::topic("/imu"),
        Select {
            frame_id: Some("imu_a"),
            ..Select::topic("/imu0")
        },
        Select {
            non_finite: true,
            ..Select::topic("/imu0")
        },
    ] {
        let mut frames = 0u64;
        let result = read(&path, &select, &mut |f: Frame| {
            assert!(select.non_finite || f.axes.iter().all(|v| v.is_finite()));
            frames += 1;
        });
        match result {
            Ok(_) => assert!(frames > 0),
            Err(e) => assert_eq!(e.file, path),
        }
    }
    let _ = std::fs::remove_file(&path);
}

/// [`ros_read`]'s rosbag2 folder compressed message by message in zstd: `bytes` its one
/// storage file (MCAP or SQLite), each message's data decompressed before it is decoded.
fn compressed_folder(is_mcap: bool, bytes: &[u8]) {
    let folder = scratch("bag");
    std::fs::create_dir_all(&folder).expect("a scratch folder in the temporary folder");
    let file = if is_mcap { "a_0.mcap" } else { "a_0.db3" };
    // (Counting 0 to 3 messages on the topic: a file that holds fewer is refused.)
    let meta = format!(
        "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: {}\n  \
         relative_file_paths:\n  - {file}\n  compression_format: zstd\n  \
         compression_mode: MESSAGE\n  topics_with_message_count:\n  - message_count: {}\n    \
         topic_metadata:\n      name: /imu0\n",
        if is_mcap { "mcap" } else { "sqlite3" },
        bytes.first().map_or(0, |b| b % 4)
    );
    std::fs::write(folder.join(rosbag2::METADATA), meta).expect("the folder's metadata");
    std::fs::write(folder.join(file), bytes).expect("the folder's storage file");
    let mut frames = 0u64;
    match rosbag2::read_folder(&folder, &Select::topic("/imu0"), &mut |f: Frame| {
        assert!(f.axes.iter().all(|v| v.is_finite()));
        frames += 1;
    }) {
        Ok(_) => assert!(frames > 0),
        Err(e) => assert!(e.file.starts_with(&folder)),
    }
    let _ = std::fs::remove_dir_all(&folder);
}

/// The rosbag2 `metadata.yaml` reader on arbitrary text: a storage and a list of files, or an
/// error; never a panic.
pub fn rosbag2_metadata(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(meta) = Metadata::parse(text) {
        assert!(!meta.storage.is_empty());
        // Each topic counted is named in the text.
        assert!(
            meta.topic_counts
                .iter()
                .all(|(name, _)| text.contains(name.as_str()))
        );
    }
}

/// The PX4 ULog reader on arbitrary bytes, written to a scratch file, surveyed, then read for
/// every topic by instance and by device_id. Every delivered sample is finite, a success
/// delivered at least one, an error names the file and fits on one line, and nothing panics.
pub fn ulog_read(data: &[u8]) {
    let path = scratch("ulg");
    std::fs::write(&path, data).expect("a scratch file in the temporary folder");
    match ulog::survey(&path) {
        Ok(survey) => {
            for topic in Topic::ALL {
                let mut which = vec![Which::Only];
                for t in survey.instances(topic) {
                    which.push(Which::Instance(t.instance));
                    which.extend(t.device_ids.iter().map(|&d| Which::DeviceId(d)));
                }
                for which in which {
                    let mut samples = 0u64;
                    let result = ulog::read_surveyed(
                        &path,
                        &survey,
                        &ulog::Select { topic, which },
                        &mut |s| {
                            assert!(s.time_us.is_finite() && s.xyz.iter().all(|v| v.is_finite()));
                            assert!(s.temperature.is_none_or(f64::is_finite));
                            samples += 1;
                        },
                    );
                    match result {
                        Ok(report) => {
                            assert!(samples > 0 && report.delivered == samples);
                            // A FIFO topic's rate is a rate, its warning one line.
                            assert!(report.fifo_rate.is_none_or(|r| r.is_finite() && r > 0.0));
                            assert!(report.fifo_caveat.is_none_or(|c| !c.contains('\n')));
                        }
                        Err(e) => assert_one_line(&e, &path),
                    }
                }
            }
        }
        Err(e) => assert_one_line(&e, &path),
    }
    let _ = std::fs::remove_file(&path);
}

/// The ArduPilot DataFlash reader on arbitrary bytes, written to a scratch file, surveyed, then
/// read for every kind and instance, and asked whether each instance's samples were
/// temperature-corrected. Every delivered sample is finite, a success delivered at least one,
/// an error names the file and fits on one line, and nothing panics.
pub fn dataflash_read(data: &[u8]) {
    let path = scratch("bin");
    std::fs::write(&path, data).expect("a scratch file in the temporary folder");
    match dataflash::survey(&path) {
        Ok(survey) => {
            for kind in Kind::ALL {
                let mut instances = vec![None];
                instances.extend(survey.instances(kind).iter().map(|s| Some(s.instance)));
                for instance in instances {
                    if let Some(i) = instance {
                        let _ = survey.temperature_corrected(kind, i);
                    }
                    let mut samples = 0u64;
                    let select = dataflash::Select { kind, instance };
                    let result = dataflash::read_surveyed(&path, &survey, &select, &mut |s| {
                        let values = s.gyro.iter().chain(&s.accel).flatten();
                        assert!(s.time_us.is_finite() && values.clone().all(|v| v.is_finite()));
                        assert!(s.temperature.is_none_or(f64::is_finite));
                        samples += 1;
                    });
                    match result {
                        Ok(report) => {
                            assert!(samples > 0 && report.delivered == samples);
                            // The batches' rates are rates, the least first.
                            assert!(report.batch_rates.is_none_or(|(least, most, mean)| {
                                least.is_finite() && least > 0.0 && least <= mean && mean <= most
                            }));
                        }
                        Err(e) => assert_one_line(&e, &path),
                    }
                }
            }
        }
        Err(e) => assert_one_line(&e, &path),
    }
    let _ = std::fs::remove_file(&path);
}

/// An autopilot log reader's error: it names the file, on one line.
fn assert_one_line(e: &DataError, path: &Path) {
    assert_eq!(e.file, path);
    assert!(!e.problem.contains('\n'));
}
