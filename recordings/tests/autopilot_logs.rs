//! The PX4 ULog and ArduPilot DataFlash readers on logs written here, by a small writer of
//! each format that follows the specifications (ULog: PX4 `docs/en/dev_log/ulog_file_format.md`;
//! DataFlash: ArduPilot `libraries/AP_Logger/LogStructure.h`), with the format strings real
//! logs carry: exact values and times back, FIFO unrolling, temperature interpolation, batch
//! reconstruction, selection, parameters, and hostile inputs (every prefix of a log, random
//! byte flips, flags, formats and batches that must be refused or dropped).
//!
//! With `IMU_AR_WRITE_FIXTURES=<folder>`, the fixtures and what the readers make of them are
//! written there (for a check by hand against pyulog and pymavlink).

mod writers;

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

use imu_ar_recordings::dataflash::{self, Corrected, Kind};
use imu_ar_recordings::ulog::{self, Select, Topic, Value, Which};
use writers::*;

/// A fixed generator for the random cases (xorshift64).
fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    }
}

/// A scratch file of its own for each call (tests run on several threads).
fn scratch(bytes: &[u8], extension: &str) -> PathBuf {
    static CALLS: AtomicU64 = AtomicU64::new(0);
    let call = CALLS.fetch_add(1, Ordering::Relaxed);
    let name = format!("imu-ar-autopilot-{}-{call}.{extension}", std::process::id());
    let path = std::env::temp_dir().join(name);
    std::fs::write(&path, bytes).expect("a scratch file");
    path
}

/// Writes `bytes` to `name` in the folder `IMU_AR_WRITE_FIXTURES` names, if it is set.
fn keep(name: &str, bytes: &[u8]) {
    if let Some(dir) = std::env::var_os("IMU_AR_WRITE_FIXTURES") {
        let dir = PathBuf::from(dir);
        std::fs::create_dir_all(&dir).expect("the fixture folder");
        std::fs::write(dir.join(name), bytes).expect("a fixture");
    }
}

/// The device_ids of the fixture's sensors.
const GYRO0: u32 = 2_752_545;
const GYRO1: u32 = 2_424_857;
const ACCEL0: u32 = 2_752_546;
/// A device with FIFO data and no sensor topic.
const LONELY: u32 = 3_000_001;

/// The FIFO messages' sample spacing (µs) and scale.
const DT: f32 = 124.87;
const SCALE: f32 = 0.000_532_6;
/// Samples per FIFO message.
const N: u8 = 20;

/// A message to write at a time: (time, order among messages of one time, writer).
type Timed = (u64, u8, Box<dyn Fn(&mut ULog)>);

/// What the ULog fixture holds, to check the readers against.
struct Expected {
    /// (instance, time, device, xyz, temperature) of the sensor_gyro messages.
    gyro: Vec<(u8, u64, u32, [f32; 3], f32)>,
    /// (timestamp_sample, xyz arrays) of the gyro FIFO messages.
    fifo: Vec<(u64, [[i16; 32]; 3])>,
    /// The data timestamp before the parameter change.
    change_us: u64,
}

/// A PX4 log: two gyros (instances 0 and 1), an accel, a gyro FIFO of gyro 0's device (from
/// before its first temperature to after its last), an accel FIFO of a device with no sensor
/// topic, a nested topic, info, parameters and their change, log strings, syncs, a dropout,
/// an unknown message type. `fifos` FIFO messages, 2.5 ms apart.
fn ulog_fixture(fifos: u64) -> (Vec<u8>, Expected) {
    let mut log = ULog::new(1_000);
    for f in [
        SENSOR_GYRO,
        SENSOR_ACCEL,
        GYRO_FIFO,
        ACCEL_FIFO,
        ESC_REPORT,
        ESC_STATUS,
    ] {
        log.format(f);
    }
    log.info("sys_name", "PX4");
    log.keyed(
        b'I',
        "uint32_t ver_sw_release",
        &0x010e_00ffu32.to_le_bytes(),
    );
    // A multi info message in two parts.
    for (continued, part) in [(0u8, "perf: 1 "), (1, "2 3")] {
        let key = "char[8] perf_counter_preflight";
        let mut p = vec![continued, key.len() as u8];
        p.extend_from_slice(key.as_bytes());
        p.extend_from_slice(part.as_bytes());
        log.msg(b'M', &p);
    }
    log.param_f32("TC_G0_TREF", 25.0);
    log.param_i32("TC_G0_ID", GYRO0 as i32);
    log.param_i32("TC_G_ENABLE", 0);
    log.subscribe(0, 0, "sensor_gyro");
    log.subscribe(1, 1, "sensor_gyro");
    log.subscribe(0, 2, "sensor_accel");
    log.subscribe(0, 3, "sensor_gyro_fifo");
    log.subscribe(0, 4, "esc_status");
    log.subscribe(0, 5, "sensor_accel_fifo");
    log.log_string(1_500, "[logger] started");

    // Messages by time: (time, order, writer).
    let mut events: Vec<Timed> = Vec::new();
    let mut gyro = Vec::new();
    let span_end = 60_000 + 2_500 * fifos;
    // Temperatures every 100 ms from 100 ms on, ending before the last FIFO samples.
    let last_temperature = (span_end.saturating_sub(50_000)).max(100_007);
    let mut k = 0u64;
    loop {
        let t = 100_007 + 100_000 * k;
        if t > last_temperature && k > 0 {
            break;
        }
        for (instance, device) in [(0u8, GYRO0), (1, GYRO1)] {
            let xyz = [
                0.01 * k as f32 + f32::from(instance),
                -0.002 * k as f32,
                1.0e-3 / (k as f32 + 3.0),
            ];
            let temperature = 31.25 + 0.37 * k as f32 + f32::from(instance);
            gyro.push((instance, t, device, xyz, temperature));
            let p = sensor(t + 120, t, device, xyz, temperature);
            events.push((
                t,
                1,
                Box::new(move |l: &mut ULog| l.data(u16::from(instance), &p)),
            ));
        }
        let p = sensor(t + 130, t + 3, ACCEL0, [0.1, 0.2, -9.81], 33.5);
        events.push((t + 3, 2, Box::new(move |l: &mut ULog| l.data(2, &p))));
        k += 1;
    }
    let mut fifo_messages = Vec::new();
    for m in 0..fifos {
        let sample = 60_000 + 2_500 * m;
        let mut xyz = [[0i16; 32]; 3];
        for (a, axis) in xyz.iter_mut().enumerate() {
            for (i, v) in axis.iter_mut().enumerate() {
                // Values past N are garbage the reader must not deliver.
                *v = if i < usize::from(N) {
                    (m as i16 * 37 + i as i16 * 11 - 300) * (a as i16 + 1)
                } else {
                    i16::MAX
                };
            }
        }
        fifo_messages.push((sample, xyz));
        let p = fifo(sample, GYRO0, DT, SCALE, N, &xyz);
        events.push((sample, 3, Box::new(move |l: &mut ULog| l.data(3, &p))));
        let p = fifo(sample + 7, LONELY, 250.0, 0.01, 10, &xyz);
        events.push((sample + 7, 4, Box::new(move |l: &mut ULog| l.data(5, &p))));
    }
    // esc_status: 8 + 2 + 1 + 5 + 8 * (8 + 4 + 4 + 1 + 7) bytes.
    for t in [150_000u64, 250_000] {
        let mut p = t.to_le_bytes().to_vec();
        p.extend_from_slice(&7u16.to_le_bytes());
        p.push(8);
        p.extend_from_slice(&[0; 5]);
        for e in 0..8u8 {
            p.extend_from_slice(&t.to_le_bytes());
            p.extend_from_slice(&1234.5f32.to_le_bytes());
            p.extend_from_slice(&15.8f32.to_le_bytes());
            p.push(e);
            p.extend_from_slice(&[0; 7]);
        }
        // The nested formats' padding is written: only the top level's trailing padding
        // may be left out (esc_status has none).
        events.push((t, 5, Box::new(move |l: &mut ULog| l.data(4, &p))));
    }
    events.sort_by_key(|&(t, order, _)| (t, order));
    // The parameter change (with an unknown message type, a sync and a dropout) goes before
    // the first message after 200 ms; its time is the newest data timestamp before it.
    let change_at = 200_000;
    let mut changed = false;
    for (t, _, write) in &events {
        if *t > change_at && !changed {
            log.param_i32("TC_G_ENABLE", 1);
            log.msg(b'Z', b"an unknown message type");
            log.sync();
            log.dropout(12);
            changed = true;
        }
        write(&mut log);
    }
    // Each message's `timestamp` by its time and kind (see above).
    let change_us = events
        .iter()
        .filter(|(t, _, _)| *t <= change_at)
        .map(|(t, order, _)| match order {
            1 => t + 120,
            2 => t + 127,
            3 | 4 => t + 40,
            _ => *t,
        })
        .max()
        .unwrap_or(1_000);
    (
        log.bytes,
        Expected {
            gyro,
            fifo: fifo_messages,
            change_us,
        },
    )
}

/// The samples `select` reads from the ULog `bytes`, and the report.
fn ulog_samples(bytes: &[u8], select: Select) -> (Vec<ulog::Sample>, ulog::Report) {
    let path = scratch(bytes, "ulg");
    let mut out = Vec::new();
    let report = ulog::read(&path, &select, &mut |s| out.push(s))
        .unwrap_or_else(|e| panic!("{select:?}: {e}"));
    let _ = std::fs::remove_file(&path);
    (out, report)
}

/// The survey of the ULog `bytes`, or the error's problem.
fn ulog_survey(bytes: &[u8]) -> Result<ulog::Survey, String> {
    let path = scratch(bytes, "ulg");
    let survey = ulog::survey(&path).map_err(|e| {
        assert_eq!(e.file, path);
        e.problem
    });
    let _ = std::fs::remove_file(&path);
    survey
}

/// The error problem of reading `select` from the ULog `bytes`.
fn ulog_error(bytes: &[u8], select: Select) -> String {
    let path = scratch(bytes, "ulg");
    let e = ulog::read(&path, &select, &mut |_| {}).expect_err("an error");
    let _ = std::fs::remove_file(&path);
    assert_eq!(e.file, path);
    e.problem
}

fn gyro(which: Which) -> Select {
    Select {
        topic: Topic::Gyro,
        which,
    }
}

#[test]
fn ulog_sensor_messages_come_back_exactly_by_instance_and_by_device() {
    let (bytes, expected) = ulog_fixture(200);
    keep("px4.ulg", &bytes);
    for (which, instance) in [
        (Which::Instance(0), 0u8),
        (Which::Instance(1), 1),
        (Which::DeviceId(GYRO1), 1),
    ] {
        let (samples, report) = ulog_samples(&bytes, gyro(which));
        let want: Vec<_> = expected.gyro.iter().filter(|g| g.0 == instance).collect();
        assert_eq!(samples.len(), want.len());
        for (s, &&(i, t, device, xyz, temperature)) in samples.iter().zip(&want) {
            assert_eq!(s.instance, i);
            assert_eq!(s.time_us, t as f64);
            assert_eq!(s.device_id, device);
            assert_eq!(s.xyz, xyz.map(f64::from));
            assert_eq!(s.temperature, Some(f64::from(temperature)));
        }
        assert_eq!(report.delivered, want.len() as u64);
        assert_eq!(report.temperature, Some(Topic::Gyro));
        assert_eq!((report.non_finite, report.truncated), (0, None));
    }
    let e = ulog_error(&bytes, gyro(Which::Only));
    assert!(e.contains("sensor_gyro has 2 instances"), "{e}");
    assert!(e.contains(&format!("instance 1 (device_id {GYRO1}")), "{e}");
    assert!(e.contains("choose one with --instance"), "{e}");
    let e = ulog_error(&bytes, gyro(Which::Instance(3)));
    assert!(e.contains("sensor_gyro has no instance 3"), "{e}");
    let e = ulog_error(&bytes, gyro(Which::DeviceId(5)));
    assert!(e.contains("no device_id 5"), "{e}");
    let (accel, _) = ulog_samples(
        &bytes,
        Select {
            topic: Topic::Accel,
            which: Which::Only,
        },
    );
    assert!(
        accel
            .iter()
            .all(|s| s.xyz == [0.1f32, 0.2, -9.81].map(f64::from))
    );
}

/// The temperature at `t` between the `points` (time, value), held outside them.
fn interpolated(points: &[(f64, f64)], t: f64) -> (f64, bool) {
    let k = points.partition_point(|&(pt, _)| pt <= t);
    match (k.checked_sub(1).map(|i| points[i]), points.get(k)) {
        (Some((t0, v0)), Some(&(t1, v1))) => (v0 + (v1 - v0) * ((t - t0) / (t1 - t0)), false),
        (Some((t0, v0)), None) => (v0, t != t0),
        (None, Some(&(_, v1))) => (v1, true),
        (None, None) => unreachable!(),
    }
}

#[test]
fn ulog_fifo_samples_are_unrolled_with_interpolated_temperatures() {
    let (bytes, expected) = ulog_fixture(200);
    let select = Select {
        topic: Topic::GyroFifo,
        which: Which::Only,
    };
    let (samples, report) = ulog_samples(&bytes, select);
    let points: Vec<(f64, f64)> = expected
        .gyro
        .iter()
        .filter(|g| g.2 == GYRO0)
        .map(|g| (g.1 as f64, f64::from(g.4)))
        .collect();
    let n = usize::from(N);
    assert_eq!(samples.len(), expected.fifo.len() * n);
    let mut held = 0;
    for (m, (sample, xyz)) in expected.fifo.iter().enumerate() {
        for i in 0..n {
            let s = &samples[m * n + i];
            // The first message's samples dt apart back from its stamp; the others' spread
            // evenly from the stamp before (2500 us for 20 samples: 125 us, the sensor's
            // period, where dt says 124.87).
            let step = match m {
                0 => f64::from(DT),
                _ => (*sample - expected.fifo[m - 1].0) as f64 / n as f64,
            };
            let t = *sample as f64 - (n - 1 - i) as f64 * step;
            assert_eq!(s.time_us, t, "message {m} sample {i}");
            let want = [0, 1, 2].map(|a| f64::from(xyz[a][i]) * f64::from(SCALE));
            assert_eq!(s.xyz, want);
            assert_eq!((s.device_id, s.instance), (GYRO0, 0));
            let (temperature, was_held) = interpolated(&points, t);
            let got = s.temperature.expect("a temperature");
            assert!(
                (got - temperature).abs() < 1e-12,
                "{got} {temperature} at {t}"
            );
            held += u64::from(was_held);
        }
    }
    // Samples before the first temperature (100 ms) and after the last are held.
    assert!(held > 2 * n as u64, "{held}");
    assert_eq!(report.held_temperature, held);
    assert_eq!(report.temperature, Some(Topic::Gyro));
    assert_eq!(report.without_temperature, 0);
    // dt is fractional: the samples are not on whole microseconds.
    assert!(samples.iter().any(|s| s.time_us.fract() != 0.0));

    // A device with no sensor topic: samples without a temperature, said so.
    let (samples, report) = ulog_samples(
        &bytes,
        Select {
            topic: Topic::AccelFifo,
            which: Which::DeviceId(LONELY),
        },
    );
    assert_eq!(samples.len(), expected.fifo.len() * 10);
    assert!(samples.iter().all(|s| s.temperature.is_none()));
    assert_eq!(report.temperature, None);
    assert_eq!(report.without_temperature, report.delivered);
    let survey = ulog_survey(&bytes).expect("a survey");
    let lonely = &survey.instances(Topic::AccelFifo)[0];
    assert_eq!((lonely.temperature, lonely.samples), (None, 10 * 200));
    let fifo = &survey.instances(Topic::GyroFifo)[0];
    assert_eq!(fifo.temperature, Some(Topic::Gyro));
}

#[test]
fn ulog_survey_lists_instances_parameters_and_changes() {
    let (bytes, expected) = ulog_fixture(200);
    let s = ulog_survey(&bytes).expect("a survey");
    assert_eq!((s.version, s.start_us, s.appended_data), (1, 1_000, false));
    assert_eq!(s.truncated, None);
    assert_eq!(s.dropouts, (1, 12));
    let gyros = s.instances(Topic::Gyro);
    assert_eq!(gyros.len(), 2);
    assert_eq!(gyros[0].device_ids, vec![GYRO0]);
    assert_eq!(gyros[1].device_ids, vec![GYRO1]);
    let n0 = expected.gyro.iter().filter(|g| g.0 == 0).count() as u64;
    assert_eq!((gyros[0].messages, gyros[0].samples), (n0, n0));
    assert_eq!(gyros[0].temperature, Some(Topic::Gyro));
    let first = expected.gyro[0].1 as f64;
    let last = expected.gyro.last().map(|g| g.1 as f64);
    assert_eq!(gyros[0].span_us, Some((first, last.unwrap_or(0.0))));
    let fifo = s.instances(Topic::GyroFifo);
    assert_eq!(fifo[0].samples, 200 * u64::from(N));
    let enable = s.parameter("TC_G_ENABLE").expect("TC_G_ENABLE");
    assert_eq!(enable.initial, Some(Value::Int(0)));
    assert_eq!(enable.value, Value::Int(1));
    assert_eq!(enable.changes, 1);
    assert_eq!(
        enable.first_changes,
        vec![(expected.change_us, Value::Int(1))]
    );
    let tref = s.parameter("TC_G0_TREF").expect("TC_G0_TREF");
    assert_eq!((tref.value, tref.changes), (Value::Float(25.0), 0));
    assert_eq!(
        s.parameter("TC_G0_ID").map(|p| p.value),
        Some(Value::Int(GYRO0 as i32))
    );
    assert!(s.info.contains(&("sys_name".into(), "PX4".into())));
    assert!(
        s.info
            .contains(&("ver_sw_release".into(), "17694975".into()))
    );
    assert!(
        s.info
            .contains(&("perf_counter_preflight".into(), "perf: 1 2 3".into()))
    );
}

#[test]
fn ulog_trailing_padding_may_be_written_or_not_and_nested_formats_place_fields() {
    // A sensor_gyro whose x comes after a nested array: its offset goes through the nesting.
    let mut log = ULog::new(0);
    log.format("pair:float[3] a;uint8_t b;");
    log.format("holder:pair[2] p;int16_t c;");
    log.format(concat!(
        "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;",
        "holder h;float x;float y;float z;float temperature;uint8_t[6] _padding0;"
    ));
    log.subscribe(0, 0, "sensor_gyro");
    let message = |t: u64, padding: bool| {
        let mut p = t.to_le_bytes().to_vec();
        p.extend_from_slice(&(t - 5).to_le_bytes());
        p.extend_from_slice(&77u32.to_le_bytes());
        p.extend_from_slice(&[0xee; 2 * 13 + 2]);
        for v in [1.5f32, -2.25, 3.125, 40.5] {
            p.extend_from_slice(&v.to_le_bytes());
        }
        if padding {
            p.extend_from_slice(&[0; 6]);
        }
        p
    };
    log.data(0, &message(100, false));
    log.data(0, &message(200, true));
    let (samples, _) = ulog_samples(&log.bytes, gyro(Which::Only));
    assert_eq!(samples.len(), 2);
    for (s, t) in samples.iter().zip([95.0, 195.0]) {
        assert_eq!((s.time_us, s.device_id), (t, 77));
        assert_eq!(s.xyz, [1.5, -2.25, 3.125]);
        assert_eq!(s.temperature, Some(40.5));
    }
    // One byte short of the unpadded length, or past the padded one: a corrupt file.
    for extra in [
        &message(300, false)[..63],
        &[message(300, true), vec![0]].concat(),
    ] {
        let mut bad = ULog {
            bytes: log.bytes.clone(),
        };
        let at = bad.bytes.len();
        bad.data(0, extra);
        let e = ulog_survey(&bad.bytes).expect_err("a corrupt length");
        assert!(e.contains(&format!("at byte {at}")), "{e}");
        assert!(e.contains("its format has 64 to 70"), "{e}");
    }
}

#[test]
fn ulog_refuses_incompatible_flags_recursive_and_deep_formats() {
    let mut log = ULog::bare(0);
    log.flags([0; 8], [0, 0, 0, 4, 0, 0, 0, 0], [0; 3]);
    let e = ulog_survey(&log.bytes).expect_err("an incompatible flag");
    assert!(e.contains("incompatible flag bit 2 of byte 3"), "{e}");
    let mut log = ULog::bare(0);
    log.flags([0; 8], [3, 0, 0, 0, 0, 0, 0, 0], [0; 3]);
    let e = ulog_survey(&log.bytes).expect_err("an incompatible flag");
    assert!(e.contains("incompatible flag bit 1 of byte 0"), "{e}");

    let mut log = ULog::new(0);
    log.format("a:uint64_t timestamp;b inner;");
    log.format("b:uint8_t x;a back;");
    log.subscribe(0, 0, "a");
    let e = ulog_survey(&log.bytes).expect_err("a recursive format");
    assert!(e.contains("format 'a' contains itself (a > b > a)"), "{e}");

    let mut log = ULog::new(0);
    log.format("f0:uint64_t timestamp;f1 n;");
    for k in 1..12 {
        log.format(&format!("f{k}:uint8_t x;f{} n;", k + 1));
    }
    log.format("f12:uint8_t x;");
    log.subscribe(0, 0, "f0");
    let e = ulog_survey(&log.bytes).expect_err("deep formats");
    assert!(e.contains("nested more than 8 deep"), "{e}");

    let mut log = ULog::new(0);
    log.format("huge:uint64_t timestamp;uint8_t[60000] a;uint8_t[60000] b;");
    log.subscribe(0, 0, "huge");
    let e = ulog_survey(&log.bytes).expect_err("a format too long");
    assert!(e.contains("longer than a data message can be"), "{e}");
}

#[test]
fn ulog_data_appended_resumes_at_the_offset() {
    let (bytes, expected) = ulog_fixture(4);
    // The flag bits at byte 16: set DATA_APPENDED and the offset where the appended data
    // (one more sensor_gyro message) begins, after a message cut short.
    let mut bytes = bytes;
    let offset = bytes.len() as u64 + 10;
    bytes[16 + 3 + 8] = 1;
    bytes[16 + 3 + 16..16 + 3 + 24].copy_from_slice(&offset.to_le_bytes());
    let mut tail = ULog { bytes: Vec::new() };
    tail.data(0, &sensor(900_120, 900_000, GYRO0, [7.0, 8.0, 9.0], 50.0));
    bytes.extend_from_slice(&tail.bytes[..tail.bytes.len() - 10]);
    assert_eq!(bytes.len() as u64, offset + tail.bytes.len() as u64 - 20);
    bytes.truncate(offset as usize);
    bytes.extend_from_slice(&tail.bytes);
    let s = ulog_survey(&bytes).expect("a survey");
    assert!(s.appended_data);
    assert_eq!((s.cut_before_appended, s.truncated), (1, None));
    let (samples, _) = ulog_samples(&bytes, gyro(Which::Instance(0)));
    let n0 = expected.gyro.iter().filter(|g| g.0 == 0).count();
    assert_eq!(samples.len(), n0 + 1);
    assert_eq!(samples[n0].xyz, [7.0, 8.0, 9.0]);
}

#[test]
fn ulog_counts_nan_samples_and_refuses_a_fifo_count_past_its_arrays() {
    let mut log = ULog::new(0);
    log.format(SENSOR_GYRO);
    log.format(GYRO_FIFO);
    log.subscribe(0, 0, "sensor_gyro");
    log.subscribe(0, 1, "sensor_gyro_fifo");
    log.data(0, &sensor(10, 10, 1, [f32::NAN, 0.0, 0.0], 20.0));
    log.data(0, &sensor(20, 20, 1, [0.0, f32::INFINITY, 0.0], 20.0));
    log.data(0, &sensor(30, 30, 1, [0.5, 0.5, 0.5], f32::NAN));
    let xyz = [[1i16; 32]; 3];
    log.data(1, &fifo(1000, 1, 100.0, f32::NAN, 4, &xyz));
    log.data(1, &fifo(2000, 1, 100.0, 0.5, 33, &xyz));
    log.data(1, &fifo(3000, 1, 100.0, 0.5, 2, &xyz));
    let (samples, report) = ulog_samples(&log.bytes, gyro(Which::Only));
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].temperature, None);
    assert_eq!((report.non_finite, report.without_temperature), (2, 1));
    let (samples, report) = ulog_samples(
        &log.bytes,
        Select {
            topic: Topic::GyroFifo,
            which: Which::Only,
        },
    );
    // The message of a NaN scale (no IMU's) is undecodable, as the one of 33 samples is.
    assert_eq!(samples.len(), 2);
    assert_eq!((report.non_finite, report.undecodable), (0, 2));
    assert_eq!(samples[0].time_us, 2900.0);
    // No finite sample at all: an error.
    let mut log = ULog::new(0);
    log.format(SENSOR_GYRO);
    log.subscribe(0, 0, "sensor_gyro");
    log.data(0, &sensor(10, 10, 1, [f32::NAN, 0.0, 0.0], 20.0));
    let e = ulog_error(&log.bytes, gyro(Which::Only));
    assert!(e.contains("no finite samples"), "{e}");
}

#[test]
fn ulog_corruption_midway_is_an_error_naming_its_byte_and_zeros_at_the_end_are_a_cut() {
    let (bytes, _) = ulog_fixture(4);
    // A message whose type byte is not a letter, after the last one.
    let mut bad = bytes.clone();
    let at = bad.len();
    bad.extend_from_slice(&[5, 0, 0x07, 1, 2, 3, 4, 5]);
    let mut more = ULog { bytes: bad };
    more.data(0, &sensor(1, 1, 1, [0.0; 3], 0.0));
    let e = ulog_survey(&more.bytes).expect_err("a corrupt type");
    assert!(e.starts_with("message "), "{e}");
    assert!(e.contains(&format!("at byte {at}: type 0x07")), "{e}");
    // Data of a msg_id never subscribed.
    let mut bad = ULog {
        bytes: bytes.clone(),
    };
    let at = bad.bytes.len();
    bad.data(42, &[0; 8]);
    let e = ulog_survey(&bad.bytes).expect_err("an unknown msg_id");
    assert!(
        e.contains(&format!("at byte {at}: data for msg_id 42")),
        "{e}"
    );
    // Zeros to the end (a log cut by a power loss): the log up to them, reported cut.
    let mut zeros = bytes.clone();
    let at = zeros.len() as u64;
    zeros.extend_from_slice(&[0; 5000]);
    let s = ulog_survey(&zeros).expect("a survey");
    assert_eq!(s.truncated, Some(at));
}

/// Survey and read every selection of the ULog `bytes`: Ok or a clean error, finite samples.
fn ulog_survive(bytes: &[u8]) -> (bool, Option<u64>) {
    let path = scratch(bytes, "ulg");
    let survey = ulog::survey(&path);
    let mut truncated = None;
    if let Ok(s) = &survey {
        truncated = s.truncated;
        for topic in Topic::ALL {
            for which in [Which::Only, Which::Instance(0), Which::DeviceId(GYRO0)] {
                let select = Select { topic, which };
                let r = ulog::read_surveyed(&path, s, &select, &mut |x| {
                    assert!(x.time_us.is_finite() && x.xyz.iter().all(|v| v.is_finite()));
                    assert!(x.temperature.is_none_or(f64::is_finite));
                });
                if let Err(e) = r {
                    assert_eq!(e.file, path);
                }
            }
        }
    }
    if let Err(e) = &survey {
        assert_eq!(e.file, path);
        assert!(!e.problem.contains('\n'));
    }
    let _ = std::fs::remove_file(&path);
    (survey.is_ok(), truncated)
}

#[test]
fn ulog_every_prefix_reads_or_fails_cleanly() {
    let (bytes, _) = ulog_fixture(3);
    keep("px4-small.ulg", &bytes);
    let mut cut = 0;
    for len in 0..=bytes.len() {
        let (ok, truncated) = ulog_survive(&bytes[..len]);
        if ok && truncated.is_some() {
            cut += 1;
        }
        if len < 16 {
            assert!(!ok, "a {len}-byte prefix");
        }
    }
    assert!(
        cut > bytes.len() / 2,
        "{cut} of {} prefixes reported cut",
        bytes.len()
    );
}

#[test]
fn ulog_random_byte_flips_never_panic() {
    let (bytes, _) = ulog_fixture(3);
    for seed in 1..=300u64 {
        let mut next = xorshift(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let mut b = bytes.clone();
        for _ in 0..1 + next() % 8 {
            let at = (next() % b.len() as u64) as usize;
            b[at] ^= 1 << (next() % 8);
        }
        ulog_survive(&b);
    }
}

/// The raw value of batch `n`, sample `j`, axis `a`.
fn raw(n: u16, j: usize, a: usize) -> i16 {
    ((j as i64 * 97 + i64::from(n) * 1000 + a as i64 * 31) % 20_000 - 10_000) as i16
}

/// A batch's blocks `seqnos` (of samples `raw`).
fn blocks(df: &mut Df, time: u64, n: u16, seqnos: &[u16]) {
    for &s in seqnos {
        let mut xyz = [[0i16; 32]; 3];
        for (a, axis) in xyz.iter_mut().enumerate() {
            for (i, v) in axis.iter_mut().enumerate() {
                *v = raw(n, usize::from(s) * 32 + i, a);
            }
        }
        df.isbd(time + u64::from(s), n, s, &xyz);
    }
}

/// The IMU samples of the DataFlash fixture: (time, instance, gyro, accel, temperature).
type ImuRow = (u64, u8, [f32; 3], [f32; 3], f32);

/// An ArduPilot log: parameters (one changed), two IMUs at 400 Hz, batches of both kinds
/// (one of 70 samples, one with a missing block, one with a repeated block), a format using
/// every format character, and garbage between messages when `garbage`.
fn df_fixture(imus: u64, garbage: bool) -> (Vec<u8>, Vec<ImuRow>, u64) {
    let mut df = Df::new();
    let mut skipped = 0u64;
    df.fmt(
        EVERY,
        "EVRY",
        "abBhHiIfdnNZcCeE",
        "a,b,B,h,H,i,I,f,d,n,N,Z,c,C,e,E",
    );
    df.fmt(EVERY + 1, "EVR2", "LMqQg", "L,M,q,Q,g");
    for (name, v) in [
        ("INS_TCAL1_ENABLE", 1.0),
        ("INS_TCAL2_ENABLE", 0.0),
        ("INS_TCAL3_ENABLE", 2.0),
        ("INS_LOG_BAT_OPT", 0.0),
        ("INS_GYRO_FILTER", 20.0),
    ] {
        df.parm(0, name, v);
    }
    let mut rows = Vec::new();
    let mut next = xorshift(7);
    for k in 0..imus {
        let t = 50_000 + 2_500 * k;
        for instance in 0..2u8 {
            let gyro = [0.001 * k as f32, -0.5 + f32::from(instance), 0.25];
            let accel = [0.1, -0.2 * f32::from(instance), -9.80665];
            let temperature = 35.0 + 0.01 * k as f32 + f32::from(instance);
            df.imu(t, instance, gyro, accel, temperature);
            rows.push((t, instance, gyro, accel, temperature));
        }
        if k == 3 {
            if garbage {
                df.bytes.extend_from_slice(&[0x11, 0x22, 0x33]);
                skipped += 3;
            }
            // EVRY and EVR2: every format character, of the lengths their FMTs give.
            let len = |f: &str| f.chars().map(df_size).sum::<usize>();
            df.msg(EVERY, &vec![0x5a; len("abBhHiIfdnNZcCeE")]);
            df.msg(EVERY + 1, &vec![0x3c; len("LMqQg")]);
        }
        if garbage && k % 7 == 5 {
            let len = 1 + next() % 40;
            for _ in 0..len {
                // Garbage without 0xA3: no message head inside it.
                df.bytes.push((next() % 0xa3) as u8);
            }
            skipped += len;
        }
        if k == 10 {
            df.parm(t, "INS_TCAL2_ENABLE", 1.0);
            // Batch 0: 70 accel samples of IMU 0 at 1344.5 Hz; 3 blocks, the last partial.
            df.isbh(t, 0, 0, 0, 208, 70, 60_000, 1344.5);
            blocks(&mut df, t, 0, &[0, 1, 2]);
            // Batch 1: 64 gyro samples of IMU 0.
            df.isbh(t + 10, 1, 1, 0, 938, 64, 61_000, 2000.0);
            blocks(&mut df, t + 10, 1, &[0, 1]);
        }
        if k == 20 {
            // Batch 2 misses block 1; batch 3 repeats block 0; batch 4 is whole.
            df.isbh(t, 2, 1, 0, 938, 96, 100_000, 2000.0);
            blocks(&mut df, t, 2, &[0, 2]);
            df.isbh(t + 10, 3, 1, 0, 938, 64, 140_000, 2000.0);
            blocks(&mut df, t + 10, 3, &[0, 0, 1]);
            df.isbh(t + 20, 4, 1, 0, 938, 32, 180_000, 2000.0);
            blocks(&mut df, t + 20, 4, &[0]);
        }
    }
    (df.bytes, rows, skipped)
}

/// The samples `select` reads from the DataFlash `bytes`, and the report.
fn df_samples(
    bytes: &[u8],
    select: dataflash::Select,
) -> (Vec<dataflash::Sample>, dataflash::Report) {
    let path = scratch(bytes, "bin");
    let mut out = Vec::new();
    let report = dataflash::read(&path, &select, &mut |s| out.push(s))
        .unwrap_or_else(|e| panic!("{select:?}: {e}"));
    let _ = std::fs::remove_file(&path);
    (out, report)
}

/// The survey of the DataFlash `bytes`, or the error's problem.
fn df_survey(bytes: &[u8]) -> Result<dataflash::Survey, String> {
    let path = scratch(bytes, "bin");
    let survey = dataflash::survey(&path).map_err(|e| {
        assert_eq!(e.file, path);
        e.problem
    });
    let _ = std::fs::remove_file(&path);
    survey
}

fn select(kind: Kind, instance: Option<u8>) -> dataflash::Select {
    dataflash::Select { kind, instance }
}

#[test]
fn dataflash_imu_messages_come_back_exactly_by_instance() {
    let (bytes, rows, _) = df_fixture(60, false);
    keep("ardupilot.bin", &bytes);
    for instance in 0..2u8 {
        let (samples, report) = df_samples(&bytes, select(Kind::Imu, Some(instance)));
        let want: Vec<&ImuRow> = rows.iter().filter(|r| r.1 == instance).collect();
        assert_eq!(samples.len(), want.len());
        for (s, &&(t, i, g, a, temperature)) in samples.iter().zip(&want) {
            assert_eq!((s.time_us, s.instance), (t as f64, i));
            assert_eq!(s.gyro, Some(g.map(f64::from)));
            assert_eq!(s.accel, Some(a.map(f64::from)));
            assert_eq!(s.temperature, Some(f64::from(temperature)));
        }
        assert_eq!((report.skipped_bytes, report.resyncs), (0, 0));
        assert_eq!(report.truncated, None);
    }
    let path = scratch(&bytes, "bin");
    let e = dataflash::read(&path, &select(Kind::Imu, None), &mut |_| {}).expect_err("two IMUs");
    assert!(e.problem.contains("IMU has 2 instances"), "{}", e.problem);
    assert!(
        e.problem.contains("choose one with --instance"),
        "{}",
        e.problem
    );
    let e = dataflash::read(&path, &select(Kind::Imu, Some(4)), &mut |_| {}).expect_err("no IMU 5");
    assert!(e.problem.contains("no instance 4"), "{}", e.problem);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn dataflash_batches_are_rebuilt_at_full_rate_and_holes_dropped() {
    let (bytes, rows, _) = df_fixture(60, false);
    let (accel, report) = df_samples(&bytes, select(Kind::BatchAccel, None));
    assert_eq!(accel.len(), 70);
    let points: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.1 == 0)
        .map(|r| (r.0 as f64, f64::from(r.4)))
        .collect();
    for (j, s) in accel.iter().enumerate() {
        assert_eq!(s.time_us, 60_000.0 + j as f64 * 1e6 / f64::from(1344.5f32));
        let want = [0, 1, 2].map(|a| f64::from(raw(0, j, a)) / 208.0);
        assert_eq!((s.accel, s.gyro), (Some(want), None));
        let (t, _) = interpolated(&points, s.time_us);
        assert!((s.temperature.expect("a temperature") - t).abs() < 1e-12);
    }
    // 60 000 µs is after the first IMU temperature (50 000): all interpolated.
    assert_eq!(report.held_temperature, 0);
    let (gyro, report) = df_samples(&bytes, select(Kind::BatchGyro, Some(0)));
    // Batches 1 (64 samples) and 4 (32); 2 and 3 dropped.
    assert_eq!(gyro.len(), 96);
    assert_eq!(report.dropped_batches, 2);
    assert_eq!(gyro[64].time_us, 180_000.0);
    assert_eq!(
        gyro[64].gyro,
        Some([0, 1, 2].map(|a| f64::from(raw(4, 0, a)) / 938.0))
    );
    assert_eq!(gyro[63].time_us, 61_000.0 + 63.0 * 1e6 / 2000.0);
    let survey = df_survey(&bytes).expect("a survey");
    let g = &survey.instances(Kind::BatchGyro)[0];
    assert_eq!((g.batches, g.dropped_batches, g.samples), (2, 2, 96));
    assert_eq!(
        (g.messages, g.rate_hz, g.temperature),
        (2 + 2 + 3 + 1, Some(2000.0), true)
    );
}

#[test]
fn dataflash_parameters_and_the_correction_helper() {
    let (bytes, _, _) = df_fixture(30, false);
    let s = df_survey(&bytes).expect("a survey");
    let p = s.parameter("INS_TCAL2_ENABLE").expect("INS_TCAL2_ENABLE");
    assert_eq!((p.first, p.value, p.changes), (0.0, 1.0, 1));
    assert_eq!(p.first_changes, vec![(50_000 + 2_500 * 10, 1.0)]);
    assert_eq!(p.default, Some(0.0));
    assert!(!s.parameter("INS_GYRO_FILTER").expect("a filter").changed());
    let c = |kind, instance| s.temperature_corrected(kind, instance);
    assert_eq!(c(Kind::Imu, 0).corrected, Corrected::Yes);
    assert!(c(Kind::Imu, 0).reason.contains("INS_TCAL1_ENABLE = 1"));
    assert_eq!(c(Kind::BatchGyro, 0).corrected, Corrected::Yes);
    assert_eq!(c(Kind::Imu, 1).corrected, Corrected::Mixed);
    assert_eq!(c(Kind::Imu, 2).corrected, Corrected::No);
    assert!(c(Kind::Imu, 2).reason.contains("learning"));
    assert_eq!(c(Kind::Imu, 3).corrected, Corrected::No);
    assert!(c(Kind::Imu, 3).reason.contains("INS4_TCAL_ENABLE"));
    assert_eq!(c(Kind::Imu, 9).corrected, Corrected::Unknown);
    // Sensor-rate batches are never corrected.
    let mut df = Df {
        bytes: bytes.clone(),
    };
    df.parm(1, "INS_LOG_BAT_OPT", 1.0);
    let mut first = Df::new();
    first.parm(0, "INS_LOG_BAT_OPT", 1.0);
    first.parm(0, "INS_TCAL1_ENABLE", 1.0);
    let s = df_survey(&first.bytes).expect("a survey");
    assert_eq!(
        s.temperature_corrected(Kind::BatchAccel, 0).corrected,
        Corrected::No
    );
    assert_eq!(
        s.temperature_corrected(Kind::Imu, 0).corrected,
        Corrected::Yes
    );
    let s = df_survey(&df.bytes).expect("a survey");
    assert_eq!(
        s.temperature_corrected(Kind::BatchAccel, 0).corrected,
        Corrected::Mixed
    );
    // An older log's PARM without its default ("QNf").
    let mut old = Df { bytes: Vec::new() };
    old.fmt(128, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
    old.fmt(PARM, "PARM", "QNf", "TimeUS,Name,Value");
    for (t, v) in [(5u64, 0.0f32), (9, 1.0)] {
        let mut p = t.to_le_bytes().to_vec();
        p.extend_from_slice(&fixed("INS_TCAL1_ENABLE", 16));
        p.extend_from_slice(&v.to_le_bytes());
        old.msg(PARM, &p);
    }
    let s = df_survey(&old.bytes).expect("a survey");
    let p = s.parameter("INS_TCAL1_ENABLE").expect("INS_TCAL1_ENABLE");
    assert_eq!(
        (p.first, p.value, p.default, p.changed()),
        (0.0, 1.0, None, true)
    );
    assert_eq!(p.first_changes, vec![(9, 1.0)]);
    assert_eq!(
        s.temperature_corrected(Kind::Imu, 0).corrected,
        Corrected::Mixed
    );
    let none = df_survey(&Df::new().bytes).expect("a survey");
    assert_eq!(
        none.temperature_corrected(Kind::Imu, 0).corrected,
        Corrected::Unknown
    );
}

#[test]
fn dataflash_garbage_is_skipped_counted_and_every_format_character_is_sized() {
    let (bytes, rows, skipped) = df_fixture(60, true);
    keep("ardupilot-garbage.bin", &bytes);
    let (samples, report) = df_samples(&bytes, select(Kind::Imu, Some(1)));
    assert_eq!(samples.len(), rows.len() / 2);
    assert_eq!(report.skipped_bytes, skipped);
    assert!(report.resyncs >= 8, "{}", report.resyncs);
    // Without the garbage, nothing is skipped: EVRY and EVR2 (every format character) have
    // the lengths their FMT gives.
    let (clean, _, zero) = df_fixture(60, false);
    assert_eq!(zero, 0);
    let s = df_survey(&clean).expect("a survey");
    assert_eq!((s.skipped_bytes, s.resyncs, s.truncated), (0, 0, None));
    // A truncated last message is reported, not an error.
    let cut = &clean[..clean.len() - 5];
    let s = df_survey(cut).expect("a survey");
    assert_eq!(s.truncated, Some(clean.len() as u64 - 54));
}

#[test]
fn dataflash_imu_units_are_checked_and_nan_samples_counted() {
    let mut df = Df::new();
    df.fmt(
        IMU + 1,
        "IMU",
        "QBffffffIIfBBHH",
        "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
    );
    df.fmtu(IMU + 1, "s#dddooo--O--zz", "F-000000-----00");
    let s = df_survey(&df.bytes).expect("a survey");
    assert!(
        s.unreadable
            .iter()
            .any(|u| u.contains("FMTU gives GyrX the unit 'd'")),
        "{:?}",
        s.unreadable
    );
    let mut df = Df::new();
    df.imu(10, 0, [f32::NAN, 0.0, 0.0], [0.0; 3], 20.0);
    df.imu(20, 0, [0.0; 3], [0.0, 0.0, f32::INFINITY], 20.0);
    df.imu(30, 0, [0.0; 3], [0.0; 3], f32::NAN);
    let (samples, report) = df_samples(&df.bytes, select(Kind::Imu, None));
    assert_eq!(samples.len(), 1);
    assert_eq!((report.non_finite, report.without_temperature), (2, 1));
    // Not a DataFlash log.
    let e = df_survey(b"hello, world").expect_err("no message");
    assert!(e.contains("not an ArduPilot DataFlash log"), "{e}");
    let e = df_survey(&ULog::new(0).bytes).expect_err("a ULog file");
    assert!(e.contains("PX4 ULog"), "{e}");
}

/// Survey and read every selection of the DataFlash `bytes`: Ok or a clean error, finite
/// samples.
fn df_survive(bytes: &[u8]) -> (bool, Option<u64>) {
    let path = scratch(bytes, "bin");
    let survey = dataflash::survey(&path);
    let mut truncated = None;
    if let Ok(s) = &survey {
        truncated = s.truncated;
        for kind in Kind::ALL {
            for instance in [None, Some(0), Some(1)] {
                let r = dataflash::read_surveyed(&path, s, &select(kind, instance), &mut |x| {
                    let values = x.gyro.iter().chain(&x.accel).flatten();
                    assert!(x.time_us.is_finite() && values.clone().all(|v| v.is_finite()));
                    assert!(x.temperature.is_none_or(f64::is_finite));
                });
                if let Err(e) = r {
                    assert_eq!(e.file, path);
                }
            }
        }
    }
    let _ = std::fs::remove_file(&path);
    (survey.is_ok(), truncated)
}

#[test]
fn dataflash_every_prefix_reads_or_fails_cleanly() {
    let (bytes, _, _) = df_fixture(22, false);
    keep("ardupilot-small.bin", &bytes);
    let mut cut = 0;
    for len in 0..=bytes.len() {
        let (ok, truncated) = df_survive(&bytes[..len]);
        cut += u64::from(ok && truncated.is_some());
    }
    assert!(cut as usize > bytes.len() / 2, "{cut} of {}", bytes.len());
}

#[test]
fn dataflash_random_byte_flips_never_panic() {
    let (bytes, _, _) = df_fixture(22, true);
    for seed in 1..=300u64 {
        let mut next = xorshift(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let mut b = bytes.clone();
        for _ in 0..1 + next() % 8 {
            let at = (next() % b.len() as u64) as usize;
            b[at] ^= 1 << (next() % 8);
        }
        df_survive(&b);
    }
}

/// Writes, when `IMU_AR_WRITE_FIXTURES` is set, what the readers make of the fixtures, for a
/// comparison by hand against pyulog and pymavlink (CSV: time, x, y, z, temperature).
#[test]
fn fixtures_and_their_samples_for_a_check_by_hand() {
    if std::env::var_os("IMU_AR_WRITE_FIXTURES").is_none() {
        return;
    }
    let (bytes, _) = ulog_fixture(200);
    keep("px4.ulg", &bytes);
    let csv = |rows: Vec<[f64; 5]>| {
        rows.iter()
            .map(|r| r.map(|v| format!("{v:?}")).join(","))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let nan = f64::NAN;
    for (name, topic, which) in [
        ("px4-gyro0.csv", Topic::Gyro, Which::Instance(0)),
        ("px4-gyro1.csv", Topic::Gyro, Which::Instance(1)),
        ("px4-gyro-fifo.csv", Topic::GyroFifo, Which::Only),
    ] {
        let (samples, _) = ulog_samples(&bytes, Select { topic, which });
        let rows = samples
            .iter()
            .map(|s| {
                [
                    s.time_us,
                    s.xyz[0],
                    s.xyz[1],
                    s.xyz[2],
                    s.temperature.unwrap_or(nan),
                ]
            })
            .collect();
        keep(name, csv(rows).as_bytes());
    }
    let (bytes, _, _) = df_fixture(60, false);
    keep("ardupilot.bin", &bytes);
    for (name, kind, instance) in [
        ("ap-imu0.csv", Kind::Imu, 0u8),
        ("ap-isb-accel0.csv", Kind::BatchAccel, 0),
        ("ap-isb-gyro0.csv", Kind::BatchGyro, 0),
    ] {
        let (samples, _) = df_samples(&bytes, select(kind, Some(instance)));
        let rows = samples
            .iter()
            .map(|s| {
                let v = s.gyro.or(s.accel).unwrap_or([nan; 3]);
                [s.time_us, v[0], v[1], v[2], s.temperature.unwrap_or(nan)]
            })
            .collect();
        keep(name, csv(rows).as_bytes());
    }
}
