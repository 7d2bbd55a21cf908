//! One reader over every kind of recording: CSV files, ROS 1 bags, MCAP files and rosbag2
//! folders or databases, streamed row by row (message by message) with their timestamps
//! checked on the way. Each input is opened once for its data (a pipe is read once).

use std::cell::Cell;
use std::io::Read as _;
use std::path::{Path, PathBuf};

use crate::csv::{self, DataError, position, split_unit};
use crate::error::{Fail, escaped, with_file};
use crate::frame::{Frame, Select, Skipped};
use crate::timing::{Call, Order, Step, TimeUnit, Timing};
use crate::units::Unit;
use crate::{bag, dataflash, mcap, rosbag2, ulog};

/// The kinds of recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// CSV with a header row.
    Csv,
    /// A ROS 1 bag (`#ROSBAG V`; format 2.0 is read).
    Bag,
    /// An MCAP file (ROS 2).
    Mcap,
    /// A rosbag2 folder (`metadata.yaml` and its storage files).
    Rosbag2,
    /// An SQLite database: a rosbag2 `.db3` storage file.
    Db3,
    /// A PX4 ULog file (`.ulg`).
    Ulog,
    /// An ArduPilot DataFlash log (`.bin`): a stream of messages, its formats first.
    DataFlash,
    /// A file none of the readers takes, with what it is.
    Other(&'static str),
    /// A file that cannot be opened.
    Unreadable,
}

impl Kind {
    /// The kind of `path`: a folder holding `metadata.yaml` (or that file) is a rosbag2 folder;
    /// a file is known by its first bytes (standard input, a pipe and a short text file are
    /// CSV).
    pub fn of(path: &Path) -> Kind {
        if rosbag2::folder(path) != path {
            return Kind::Rosbag2;
        }
        if path.is_dir() {
            return if path.join(rosbag2::METADATA).is_file() {
                Kind::Rosbag2
            } else {
                Kind::Other("a folder without metadata.yaml (not a rosbag2 folder)")
            };
        }
        let mut head = [0u8; 16];
        let head: &[u8] = match csv::read_once(path) {
            Some(Ok(bytes)) => &bytes[..bytes.len().min(16)],
            Some(Err(_)) => return Kind::Csv,
            None => match std::fs::File::open(path).and_then(|mut f| f.read(&mut head)) {
                Ok(n) => &head[..n],
                Err(_) => return Kind::Unreadable,
            },
        };
        Kind::of_head(head, path)
    }

    /// The kind of a file that starts with `head` (at most 16 bytes) and is named `path`.
    fn of_head(head: &[u8], path: &Path) -> Kind {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match head {
            h if h.starts_with(b"#ROSBAG V") => Kind::Bag,
            h if h.starts_with(b"\x89MCAP") => Kind::Mcap,
            // A cut MCAP file: its magic's first bytes.
            h if !h.is_empty() && b"\x89MCAP".starts_with(h) => Kind::Mcap,
            h if h.starts_with(rosbag2::SQLITE_MAGIC) => Kind::Db3,
            h if h.starts_with(&crate::ulog::MAGIC) => Kind::Ulog,
            // A DataFlash log starts with its FMT messages (the FMT of FMT first).
            [0xa3, 0x95, crate::dataflash::FMT_TYPE, ..] => Kind::DataFlash,
            [0x28, 0xb5, 0x2f, 0xfd, ..] => Kind::Other(
                "a zstd-compressed file (a rosbag2 folder compressed file by file: \
                 `ros2 bag decompress` writes one that can be read)",
            ),
            [0x04, 0x22, 0x4d, 0x18, ..] => Kind::Other("an lz4-compressed file"),
            [0x1f, 0x8b, ..] => Kind::Other("a gzip-compressed file"),
            [b'B', b'Z', b'h', ..] => Kind::Other("a bzip2-compressed file"),
            [0xfd, b'7', b'z', b'X', b'Z', 0, ..] => Kind::Other("an xz-compressed file"),
            [b'P', b'K', 3, 4, ..] => Kind::Other("a zip archive"),
            [0x89, b'H', b'D', b'F', ..] => Kind::Other("an HDF5 file"),
            [] => match extension.as_deref() {
                Some("bag") => Kind::Other("an empty file, not a ROS 1 bag"),
                Some("mcap") => Kind::Other("an empty file, not an MCAP file"),
                Some("db3") => Kind::Other("an empty file, not a rosbag2 database"),
                Some("ulg") => Kind::Other("an empty file, not a PX4 ULog file"),
                Some("bin") => Kind::Other("an empty file, not an ArduPilot DataFlash log"),
                _ => Kind::Csv,
            },
            // A DataFlash log cut inside its first message's head.
            h if h.len() < 3 && [0xa3, 0x95, crate::dataflash::FMT_TYPE].starts_with(h) => {
                Kind::DataFlash
            }
            // A ULog file cut inside its magic.
            h if h.len() < crate::ulog::MAGIC.len() && crate::ulog::MAGIC.starts_with(h) => {
                Kind::Ulog
            }
            // Text has no NUL and few control bytes: a file that starts otherwise is binary.
            h if h
                .iter()
                .any(|&b| b == 0 || (b < 0x09) || (0x0e..0x1b).contains(&b)) =>
            {
                Kind::Other("a binary file of no kind read here (not text, not a known magic)")
            }
            _ => match extension.as_deref() {
                Some("bag") => Kind::Other("not a ROS 1 bag (it does not start with '#ROSBAG V')"),
                Some("mcap") => {
                    Kind::Other("not an MCAP file (it does not start with the MCAP magic)")
                }
                Some("db3") => Kind::Other("not a rosbag2 database (not an SQLite file)"),
                Some("ulg") => Kind::Other("not a PX4 ULog file (it does not start with 'ULog')"),
                _ => Kind::Csv,
            },
        }
    }

    /// What the kind is called in messages.
    fn name(self) -> &'static str {
        match self {
            Kind::Csv => "a CSV file",
            Kind::Bag => "a ROS 1 bag",
            Kind::Mcap => "an MCAP file",
            Kind::Rosbag2 => "a rosbag2 folder",
            Kind::Db3 => "a rosbag2 database",
            Kind::Ulog => "a PX4 ULog file",
            Kind::DataFlash => "an ArduPilot DataFlash log",
            Kind::Other(what) => what,
            Kind::Unreadable => "a file that cannot be read",
        }
    }
}

/// The six axes of a `sensor_msgs/Imu` message, as `--column` names them.
pub const AXES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// The index in [`AXES`] of a column name: `gx` or `angular_velocity.x` .. `az` or
/// `linear_acceleration.z`.
pub fn axis(name: &str) -> Option<usize> {
    const LONG: [&str; 6] = [
        "angular_velocity.x",
        "angular_velocity.y",
        "angular_velocity.z",
        "linear_acceleration.x",
        "linear_acceleration.y",
        "linear_acceleration.z",
    ];
    AXES.iter()
        .position(|a| *a == name)
        .or_else(|| LONG.iter().position(|a| *a == name))
}

/// What to read.
pub struct Request<'a> {
    /// The columns (CSV names or indices; for a bag or an MCAP file, names of [`axis`]).
    pub columns: &'a [String],
    /// The `sensor_msgs/Imu` topic of a bag or an MCAP file.
    pub topic: Option<&'a str>,
    /// The header frame_id of the IMU to read, when the topic carries several.
    pub frame_id: Option<&'a str>,
    /// The CSV time column, when the user named one.
    pub time_column: Option<&'a str>,
    /// Whether the timestamps are wanted (they are read and checked only then, or when
    /// `time_column` names one; a bag's and an MCAP file's always are).
    pub want_time: bool,
    /// Drop (and count) samples whose stamp is not after the last one, instead of refusing them.
    pub drop_backward: bool,
    /// The IMU of an autopilot log (ULog multi_id, DataFlash `I`), when it holds several.
    pub instance: Option<u8>,
}

/// What a read gave besides the samples.
pub struct Read {
    /// The unit of each column, where its header bracket (or the message's SI units) says it.
    pub units: Vec<Option<Unit>>,
    /// A header bracket that names no unit known here, per column.
    pub unknown: Vec<Option<String>>,
    /// The timestamps, when read: their statistics and unit.
    pub timing: Option<(Timing, TimeUnit)>,
    /// Messages skipped (undecodable or not finite), counted.
    pub skipped: Skipped,
    /// Where a log's samples came from when it is not the one its six axes are read from
    /// (a DataFlash log's batch sampler's batches, not its `IMU` messages).
    pub source: Option<String>,
    /// What the stamps cannot check of the rate they give, to be warned of where no rate is
    /// given (batches parted by pauses, each stamped at its header's rate).
    pub caveat: Option<String>,
}

/// Reads `request` from `files` (one kind, joined in order), passing the values of each row
/// (message) whose stamp moves forward to `each`, in the order of `request.columns`.
pub fn stream(
    files: &[PathBuf],
    request: &Request,
    each: &mut dyn FnMut(&[f64]),
) -> Result<Read, Fail> {
    stream_stamped(files, request, &mut |_, values| each(values))
}

/// [`stream`], passing each row's timestamp (ns) too: `None` where the row has none that was
/// read (no time column, a stamp that is not a number with the rate given, a message stamped 0).
pub fn stream_stamped(
    files: &[PathBuf],
    request: &Request,
    each: &mut dyn FnMut(Option<i64>, &[f64]),
) -> Result<Read, Fail> {
    // Each file's kind, found once (each is opened for it).
    let kinds: Vec<Kind> = files.iter().map(|f| Kind::of(f)).collect();
    let kind = kinds[0];
    if let Kind::Other(what) = kind {
        return Err(with_file(
            &files[..1],
            format!("{what}: not a recording read here"),
        ));
    }
    if let Some((file, _)) = files
        .iter()
        .zip(&kinds)
        .find(|(_, k)| **k == Kind::Unreadable)
    {
        let problem = match std::fs::File::open(file) {
            Err(e) => format!("cannot open: {e}"),
            Ok(mut f) => match f.read(&mut [0u8; 1]) {
                Err(e) => format!("cannot read: {e}"),
                Ok(_) => "cannot read: it changed while being read".into(),
            },
        };
        return Err(with_file(std::slice::from_ref(file), problem));
    }
    for (file, &other) in files.iter().zip(&kinds).skip(1) {
        if other != kind {
            return Err(with_file(
                files,
                format!(
                    "{} is {} and {} is {}: one record is one kind of file",
                    files[0].display(),
                    kind.name(),
                    file.display(),
                    other.name()
                ),
            ));
        }
    }
    if kind != Kind::Csv
        && let Some(piped) = files.iter().find(|f| csv::read_once(f).is_some())
    {
        return Err(with_file(
            files,
            format!(
                "{} is {} read from a pipe: it is read from a file (or folder) on disk",
                piped.display(),
                kind.name()
            ),
        ));
    }
    if let (Kind::Csv, Some(f)) = (kind, request.frame_id) {
        return Err(with_file(
            files,
            format!(
                "--frame-id {}: the file is CSV; --frame-id picks an IMU of a bag's or an MCAP \
                 file's topic",
                escaped(f)
            ),
        ));
    }
    if matches!(kind, Kind::Ulog | Kind::DataFlash) {
        return autopilot_stream(files, kind, request, each);
    }
    if let Some(i) = request.instance {
        return Err(with_file(
            files,
            format!(
                "--instance {i}: the file is {}; --instance picks an IMU of a PX4 ULog file or \
                 an ArduPilot DataFlash log",
                kind.name()
            ),
        ));
    }
    match (kind, request.topic) {
        (Kind::Csv, None) => csv_stream(files, request, each),
        (Kind::Csv, Some(t)) => Err(with_file(
            files,
            format!(
                "--topic {}: the file is {}; --topic is for ROS 1 bags, MCAP files and rosbag2 \
                 folders or databases",
                escaped(t),
                if std::fs::metadata(&files[0]).is_ok_and(|m| m.is_file() && m.len() == 0) {
                    "empty"
                } else {
                    "CSV (its first bytes are text)"
                }
            ),
        )),
        (kind, topic) => messages(files, kind, topic, request, each),
    }
}

/// The instance to read of an autopilot log's IMUs `instances` (as `(instance, what)`, `what`
/// naming it in messages): the requested one, the only one, or an error that lists them.
fn choose(
    files: &[PathBuf],
    request: &Request,
    what: &str,
    instances: &[(u8, String)],
    cut_at: Option<u64>,
) -> Result<u8, Fail> {
    match (request.instance, instances) {
        (Some(i), _) if instances.iter().any(|(j, _)| *j == i) => Ok(i),
        (Some(i), _) => Err(with_file(
            files,
            format!("--instance {i}: the log has no {what} of that instance"),
        )),
        (None, [(i, _)]) => Ok(*i),
        (None, []) => Err(with_file(
            files,
            match cut_at {
                Some(at) => format!(
                    "the log has no {what}: it ends inside a message at byte {at} (cut short, \
                     as when the power goes) before any"
                ),
                None => format!("the log has no {what}"),
            },
        )),
        (None, many) => {
            let list: Vec<&str> = many.iter().map(|(_, w)| w.as_str()).collect();
            Err(with_file(
                files,
                format!(
                    "{} instances of {what}: {}; choose one with --instance",
                    many.len(),
                    list.join(", ")
                ),
            ))
        }
    }
}

/// A PX4 ULog file's or an ArduPilot DataFlash log's IMU samples: a DataFlash log's `IMU`
/// messages (gyro and accelerometer together) or its batches at the sensor's rate (one sensor's
/// axes, [`fuller_dataflash`]); a ULog file's `sensor_gyro` or `sensor_accel`
/// (their FIFO topics when the log has no sensor topic), one of them: the two are separate
/// topics, published at times of their own.
fn autopilot_stream(
    files: &[PathBuf],
    kind: Kind,
    request: &Request,
    each: &mut dyn FnMut(Option<i64>, &[f64]),
) -> Result<Read, Fail> {
    if files.len() > 1 {
        return Err(with_file(
            files,
            format!("{}: one log at a time", kind.name()),
        ));
    }
    if let Some(t) = request.topic {
        return Err(with_file(
            files,
            format!(
                "--topic {}: the file is {}, whose IMUs --instance picks",
                escaped(t),
                kind.name()
            ),
        ));
    }
    let picks = picks(
        files,
        request,
        "an autopilot log's IMU has gx, gy, gz (rad/s) and ax, ay, az (m/s^2)",
    )?;
    let path = &files[0];
    let mut timing = Timing::new();
    let mut backward: Option<(u64, i64, i64)> = None;
    let mut from = None;
    let mut count = 0u64;
    let mut values = vec![0.0; picks.len()];
    let mut take = |time_us: f64, axes: [f64; 6]| {
        count += 1;
        // Microseconds since boot, to nanoseconds.
        let stamp = (time_us * 1e3).round() as i64;
        if !take_stamp(&mut timing, stamp, request.drop_backward) {
            backward.get_or_insert((count, stamp, timing.last()));
            return;
        }
        for (v, &i) in values.iter_mut().zip(&picks) {
            *v = axes[i];
        }
        each(Some(stamp), &values);
    };
    let mut skipped = Skipped::default();
    let mut caveat = None;
    if kind == Kind::DataFlash {
        let survey = dataflash::survey(path).map_err(|e| Fail(e.to_string()))?;
        // The instances of the IMU messages and of the batches of the picked sensor; of the two,
        // the one with more samples of the instance chosen.
        let batch = batch_kind(&picks);
        // Each with its messages, so that a stray one shows as such.
        let mut counts: Vec<(u8, u64)> = Vec::new();
        for s in survey
            .instances(dataflash::Kind::Imu)
            .into_iter()
            .chain(batch.map(|b| survey.instances(b)).unwrap_or_default())
        {
            match counts.iter_mut().find(|(i, _)| *i == s.instance) {
                Some((_, n)) => *n += s.messages,
                None => counts.push((s.instance, s.messages)),
            }
        }
        counts.sort_by_key(|(i, _)| *i);
        let found: Vec<(u8, String)> = counts
            .into_iter()
            .map(|(i, n)| (i, format!("{i} ({n} messages)")))
            .collect();
        if found.is_empty() && survey.undecodable_batches > 0 {
            return Err(with_file(
                files,
                format!(
                    "its {} ISB batch headers cannot be rebuilt (no samples, a multiplier of 0, \
                     a sample rate that is not a positive number, or sample times no clock \
                     reaches), and it has no IMU messages to read instead",
                    survey.undecodable_batches
                ),
            ));
        }
        if found.is_empty() && !survey.unreadable.is_empty() {
            return Err(with_file(
                files,
                format!(
                    "its IMU samples cannot be read: {}",
                    survey.unreadable.join("; ")
                ),
            ));
        }
        let what = match batch {
            None => "IMU messages",
            Some(dataflash::Kind::BatchGyro) => "IMU messages or ISB gyro batches",
            Some(_) => "IMU messages or ISB accel batches",
        };
        let instance = choose(files, request, what, &found, survey.truncated)?;
        let source = fuller_dataflash(&survey, batch, instance);
        if source != dataflash::Kind::Imu {
            from = Some(format!(
                "read from the log's {} of IMU {instance} (the sensor's rate), which hold more of \
                 its samples than its IMU messages (the loop's rate, filtered); six axes are read \
                 from the IMU messages",
                match source {
                    dataflash::Kind::BatchGyro => "ISB gyro batches",
                    _ => "ISB accel batches",
                }
            ));
        }
        let select = dataflash::Select {
            kind: source,
            instance: Some(instance),
        };
        let report = dataflash::read_surveyed(path, &survey, &select, &mut |s| {
            // A batch holds one sensor: the other's three axes are never picked.
            let g = s.gyro.unwrap_or([f64::NAN; 3]);
            let a = s.accel.unwrap_or([f64::NAN; 3]);
            take(s.time_us, [g[0], g[1], g[2], a[0], a[1], a[2]]);
        })
        .map_err(|e| Fail(e.to_string()))?;
        // ArduPilot writes each batch's smp_rate from the rate it keeps estimating
        // (`AP_InertialSensor_Backend::_update_sensor_rate`): headers a little apart are one
        // sensor's, read at their mean; more than half a percent apart, two rates.
        if let Some((least, most, mean)) = report.batch_rates {
            if most > 1.005 * least {
                return Err(with_file(
                    files,
                    format!(
                        "its ISB batches' headers give sample rates from {least} to {most} Hz, \
                         more than half a percent apart: each batch's samples are placed at \
                         its own, and one record is read at one rate"
                    ),
                ));
            }
            timing.placed_at(mean);
            caveat = Some(batches_unchecked(mean, most > least));
        }
        skipped.non_finite = report.non_finite;
        // Corrupt IMU messages (a TimeUS or an instance no IMU has) are undecodable ones.
        skipped.undecodable = report.dropped_batches + report.undecodable_batches + report.corrupt;
        skipped.cut_short = u64::from(survey.truncated.is_some());
    } else {
        let rate;
        (skipped, rate) = ulog_stream(files, request, &picks, &mut take)?;
        if let Some((rate, warning)) = rate {
            timing.placed_at(rate);
            caveat = warning;
        }
    }
    let read = stamped(files, request, &picks, (timing, backward), skipped)?;
    Ok(Read {
        source: from,
        caveat,
        ..read
    })
}

/// The warning for the samples of a DataFlash log's batch sampler, whose headers give
/// `rate` (Hz): each batch's samples are placed at it from the batch's first sample, the only
/// time taken, and between two batches of a sensor the sampler turns to the other sensor and
/// the other IMUs (`AP_InertialSensor::BatchSampler::rotate_to_next_sensor`) for a time no
/// stamp counts in samples; so the rate read is the header's, which nothing checks (a sensor
/// 0.05 % faster, a sample skipped between batches, stamps the batches as one 0.05 % slower
/// does back to back).
fn batches_unchecked(rate: f64, spread: bool) -> String {
    let rate = if spread {
        format!("their mean {}", crate::timing::short(rate))
    } else {
        rate.to_string()
    };
    format!(
        "its samples are ISB batches, each placed at its header's smp_rate, {rate} Hz, from \
         its first sample, the only one timed: between batches the sampler turns to the other \
         sensors for a time no stamp counts in samples, so the rate read is that smp_rate, \
         which nothing checks (a sensor 0.2 % off its nominal rate reads as it, moving N by \
         0.1 %); --rate sets the sensor's own"
    )
}

/// The batches that could hold a DataFlash log's axes `picks`: those of the one sensor they
/// are all of; none for axes of both sensors, which batches take at times of their own.
fn batch_kind(picks: &[usize]) -> Option<dataflash::Kind> {
    if picks.iter().all(|&i| i < 3) {
        Some(dataflash::Kind::BatchGyro)
    } else if picks.iter().all(|&i| i >= 3) {
        Some(dataflash::Kind::BatchAccel)
    } else {
        None
    }
}

/// What a DataFlash log's IMU `instance` is read from: its batches of the `batch` kind
/// (`ISBH`, `ISBD`), when those hold more of its samples than its `IMU` messages (the batches
/// at the sensor's rate, the `IMU` messages at the loop's); its `IMU` messages otherwise. A
/// dropped or undecodable batch counts as undecodable.
fn fuller_dataflash(
    survey: &dataflash::Survey,
    batch: Option<dataflash::Kind>,
    instance: u8,
) -> dataflash::Kind {
    // The samples and the batches dropped of a kind's sources of `instance`.
    let of = |k| -> (u64, u64) {
        survey
            .instances(k)
            .iter()
            .filter(|s| s.instance == instance)
            .fold((0, 0), |(n, d), s| (n + s.samples, d + s.dropped_batches))
    };
    // (Batches none of which is whole are named for it where no `IMU` message is there
    // either.)
    let imu = of(dataflash::Kind::Imu).0;
    match batch.map(|b| (b, of(b))) {
        Some((b, (samples, _))) if samples > imu => b,
        Some((b, (_, dropped))) if imu == 0 && dropped > 0 => b,
        _ => dataflash::Kind::Imu,
    }
}

/// Of a ULog file's sensor topic and its FIFO topic, the one with more samples (of `instance`,
/// or of all instances): the FIFO topic at the sensor's full rate where the logger wrote it
/// (SDLOG_PROFILE's raw FIFO bits, which PX4 may log for some IMUs only), the sensor topic
/// otherwise.
pub fn fuller(
    survey: &ulog::Survey,
    sensor: ulog::Topic,
    fifo: ulog::Topic,
    instance: Option<u8>,
) -> ulog::Topic {
    // The samples and the messages of a topic's instances.
    let of = |t| -> (u64, u64) {
        survey
            .instances(t)
            .iter()
            .filter(|i| instance.is_none_or(|n| i.instance == n))
            .fold((0, 0), |(n, m), i| (n + i.samples, m + i.messages))
    };
    // (A FIFO topic none of whose messages decode is named for them where the sensor topic
    // has no sample either.)
    let ((fifo_samples, fifo_messages), (sensor_samples, _)) = (of(fifo), of(sensor));
    if fifo_samples > sensor_samples || sensor_samples == 0 && fifo_messages > 0 {
        fifo
    } else {
        sensor
    }
}

/// A FIFO topic's rate its messages' counts give, Hz, and the warning it is read with.
type FifoRate = Option<(f64, Option<String>)>;

/// The samples of a ULog file's gyro or accelerometer, or both (`picks`), to `take` (time in
/// microseconds, the six axes): of the sensor topic and its FIFO topic, the [`fuller`]. Gyro and accelerometer are separate topics: read together (on two threads), they are
/// paired by equal sample times, as PX4's drivers publish the two halves of one FIFO read;
/// samples without a partner are counted, and more than 1 % of them refused, naming why
/// ([`Pairing`]): one topic's lost messages, or times of their own. With the messages
/// skipped, the FIFO topic's rate its messages' counts give ([`ulog::Report::fifo_rate`]; of
/// both topics read, the gyro's), where it is read, and its warning.
fn ulog_stream(
    files: &[PathBuf],
    request: &Request,
    picks: &[usize],
    take: &mut dyn FnMut(f64, [f64; 6]),
) -> Result<(Skipped, FifoRate), Fail> {
    let path = &files[0];
    let survey = ulog::survey(path).map_err(|e| Fail(e.to_string()))?;
    let mut selects = Vec::with_capacity(2);
    for (wanted, sensor, fifo) in [
        (
            picks.iter().any(|&i| i < 3),
            ulog::Topic::Gyro,
            ulog::Topic::GyroFifo,
        ),
        (
            picks.iter().any(|&i| i >= 3),
            ulog::Topic::Accel,
            ulog::Topic::AccelFifo,
        ),
    ] {
        if !wanted {
            continue;
        }
        // The instances of either topic; of the two, the one with more samples of the
        // instance chosen.
        let mut found: Vec<(u8, String)> = Vec::new();
        for t in survey
            .instances(sensor)
            .into_iter()
            .chain(survey.instances(fifo))
        {
            if found.iter().all(|(i, _)| *i != t.instance) {
                let ids: Vec<String> = t.device_ids.iter().map(u32::to_string).collect();
                found.push((
                    t.instance,
                    format!("{} (device_id {})", t.instance, ids.join(", ")),
                ));
            }
        }
        found.sort_by_key(|(i, _)| *i);
        let instance = choose(
            files,
            request,
            &format!("{} or {} messages", sensor.name(), fifo.name()),
            &found,
            survey.truncated,
        )?;
        let topic = fuller(&survey, sensor, fifo, Some(instance));
        selects.push(ulog::Select {
            topic,
            which: ulog::Which::Instance(instance),
        });
    }
    let mut skipped = Skipped {
        cut_short: u64::from(survey.truncated.is_some()),
        ..Skipped::default()
    };
    let fail = |e: DataError| Fail(e.to_string());
    let [a, b] = selects[..] else {
        let gyro =
            selects[0].topic == ulog::Topic::Gyro || selects[0].topic == ulog::Topic::GyroFifo;
        let report = ulog::read_surveyed(path, &survey, &selects[0], &mut |s| {
            let [x, y, z] = s.xyz;
            take(
                s.time_us,
                if gyro {
                    [x, y, z, 0.0, 0.0, 0.0]
                } else {
                    [0.0, 0.0, 0.0, x, y, z]
                },
            );
        })
        .map_err(fail)?;
        if let Some(e) = report.fifo_overlap {
            return Err(Fail(e));
        }
        skipped.undecodable = report.undecodable;
        skipped.non_finite = report.non_finite;
        return Ok((skipped, report.fifo_rate.map(|r| (r, report.fifo_caveat))));
    };
    type Batch = Vec<(f64, [f64; 3])>;
    let dropouts = survey.dropouts;
    let survey = &survey;
    let (reports, pairing) = std::thread::scope(|scope| {
        let reader = |select: ulog::Select, send: std::sync::mpsc::SyncSender<Batch>| {
            move || {
                let mut batch = Vec::with_capacity(4096);
                let report = ulog::read_surveyed(path, survey, &select, &mut |s| {
                    batch.push((s.time_us, s.xyz));
                    if batch.len() == 4096 {
                        // A closed channel: the pairing stopped, its error says why.
                        let _ = send.send(std::mem::replace(&mut batch, Vec::with_capacity(4096)));
                    }
                });
                if !batch.is_empty() {
                    let _ = send.send(batch);
                }
                report
            }
        };
        let (gyro_send, gyro) = std::sync::mpsc::sync_channel::<Batch>(4);
        let (accel_send, accel) = std::sync::mpsc::sync_channel::<Batch>(4);
        let g = scope.spawn(reader(a, gyro_send));
        let x = scope.spawn(reader(b, accel_send));
        let (mut gyro, mut accel) = (gyro.iter().flatten(), accel.iter().flatten());
        let (mut next_gyro, mut next_accel) = (gyro.next(), accel.next());
        let mut pairing = Pairing::default();
        while let (Some((tg, wg)), Some((ta, wa))) = (next_gyro, next_accel) {
            // Equal sample times, to the microsecond's rounding.
            if (tg - ta).abs() < 0.5 {
                take(tg, [wg[0], wg[1], wg[2], wa[0], wa[1], wa[2]]);
                pairing.pair();
                pairing.spans.seen(tg, ta);
                (next_gyro, next_accel) = (gyro.next(), accel.next());
            } else if tg < ta {
                pairing.alone(Sensor::Gyro, 1);
                pairing.spans.gyro.seen(tg);
                next_gyro = gyro.next();
            } else {
                pairing.alone(Sensor::Accel, 1);
                pairing.spans.accel.seen(ta);
                next_accel = accel.next();
            }
        }
        // The samples after the other sensor's last.
        for (sensor, rest) in [
            (Sensor::Gyro, next_gyro.into_iter().chain(gyro)),
            (Sensor::Accel, next_accel.into_iter().chain(accel)),
        ] {
            let span = match sensor {
                Sensor::Gyro => &mut pairing.spans.gyro,
                Sensor::Accel => &mut pairing.spans.accel,
            };
            let mut n = 0;
            for (t, _) in rest {
                span.seen(t);
                n += 1;
            }
            pairing.alone(sensor, n);
        }
        pairing.finish();
        let join = |h: std::thread::ScopedJoinHandle<'_, Result<ulog::Report, DataError>>| {
            h.join().unwrap_or_else(|_| {
                Err(DataError {
                    file: path.clone(),
                    line: None,
                    problem: "the reader stopped".into(),
                })
            })
        };
        ((join(g), join(x)), pairing)
    });
    let (g, x) = (reports.0.map_err(fail)?, reports.1.map_err(fail)?);
    if let Some(e) = [&g, &x].into_iter().find_map(|r| r.fifo_overlap.clone()) {
        return Err(Fail(e));
    }
    // A sample that is not finite is not delivered, and leaves its partner without one: the
    // row is counted once, as not finite, as a CSV row with a NaN is.
    let non_finite = g.non_finite + x.non_finite;
    let paired = pairing.paired;
    let unpaired = (pairing.gyro.samples + pairing.accel.samples).saturating_sub(non_finite);
    if unpaired.saturating_mul(100) > paired.saturating_add(unpaired) {
        let (gyro, accel) = (a.topic.name(), b.topic.name());
        let Some(lost) = pairing.lost(
            [
                pairing.gyro.samples.saturating_sub(x.non_finite),
                pairing.accel.samples.saturating_sub(g.non_finite),
            ],
            [gyro, accel],
        ) else {
            if let Some(apart) = pairing.spans.rates_apart([gyro, accel]) {
                return Err(with_file(files, apart));
            }
            return Err(with_file(
                files,
                format!(
                    "{gyro} and {accel} share {paired} sample times; {unpaired} samples of one or \
                     the other have no partner (more than 1 %): the two are published at times \
                     of their own here, so read the gyro axes and the accelerometer axes apart"
                ),
            ));
        };
        let logger = match dropouts {
            (0, _) => String::new(),
            (n, ms) => format!(" (the log records {n} dropouts of the logger, {ms} ms in all)"),
        };
        let again = if pairing.gyro.gaps + pairing.accel.gaps > 0 {
            ", or record again with a logger that keeps up (a faster SD card, fewer topics \
             logged)"
        } else {
            ""
        };
        return Err(with_file(
            files,
            format!(
                "{gyro} and {accel} share {paired} sample times, but {lost}{logger}; the \
                 {unpaired} samples without a partner are more than 1 %: read the gyro axes and \
                 the accelerometer axes apart (each is then read with its gaps counted){again}"
            ),
        ));
    }
    skipped.undecodable = g.undecodable + x.undecodable;
    skipped.non_finite = non_finite;
    skipped.unpaired = unpaired;
    // (Paired by equal sample times, the samples are the gyro's.)
    let rate = g.fifo_rate.filter(|_| x.fifo_rate.is_some());
    Ok((skipped, rate.map(|r| (r, g.fifo_caveat))))
}

/// The sensor of a sample the pairing of gyro and accelerometer met.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sensor {
    /// The gyro.
    Gyro,
    /// The accelerometer.
    Accel,
}

/// The samples of one sensor without a partner of the same time in the other sensor's topic,
/// by where they lie in that topic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Alone {
    /// All of them.
    samples: u64,
    /// Runs of them between two paired samples, with no sample of the other sensor alone among
    /// them: each a gap of the other topic (messages it lost).
    gaps: u64,
    /// Those before the first paired sample: the other topic starts after them.
    before: u64,
    /// Those after the last paired sample: the other topic ends before them.
    after: u64,
}

/// The tally of gyro and accelerometer samples paired by their times, met in time order: how
/// many pair, and where those without a partner lie.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Pairing {
    /// Samples paired.
    paired: u64,
    /// The gyro samples alone.
    gyro: Alone,
    /// The accelerometer samples alone.
    accel: Alone,
    /// Samples alone between two paired samples that hold some of both sensors: scattered,
    /// as two clocks leave them.
    mixed: u64,
    /// The gyro and accelerometer samples alone since the last paired sample.
    open: (u64, u64),
    /// The times each sensor's samples span.
    spans: Spans,
}

/// The times of one sensor's samples met, microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Span {
    /// Samples met.
    samples: u64,
    /// The first one's time.
    first: f64,
    /// The last one's time.
    last: f64,
}

impl Span {
    /// A sample at `t`.
    fn seen(&mut self, t: f64) {
        if self.samples == 0 {
            self.first = t;
        }
        self.last = t;
        self.samples += 1;
    }

    /// The samples' mean rate over their span, Hz; `None` for fewer than two or no span.
    fn rate(&self) -> Option<f64> {
        let span = (self.last - self.first) * 1e-6;
        (self.samples > 1 && span > 0.0).then(|| (self.samples - 1) as f64 / span)
    }
}

/// The times each sensor's samples span.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Spans {
    /// The gyro's.
    gyro: Span,
    /// The accelerometer's.
    accel: Span,
}

impl Spans {
    /// A gyro sample at `tg` paired with an accelerometer sample at `ta`.
    fn seen(&mut self, tg: f64, ta: f64) {
        self.gyro.seen(tg);
        self.accel.seen(ta);
    }

    /// Where the two sensors' mean rates differ by more than a tenth: each topic's (`topics`,
    /// gyro then accelerometer) rate, and what a topic logged under
    /// [`ulog::LEAST_SENSOR_RATE`] holds.
    fn rates_apart(&self, topics: [&str; 2]) -> Option<String> {
        let (g, a) = (self.gyro.rate()?, self.accel.rate()?);
        if (g - a).abs() <= 0.1 * g.max(a) {
            return None;
        }
        let slow = if g < a { topics[0] } else { topics[1] };
        let subsample = if g.min(a) < ulog::LEAST_SENSOR_RATE {
            format!(
                "; {slow} under {} Hz is the logger's subsample of the sensor's stream (PX4's \
                 default profile writes sensor topics once a second, the thermal calibration \
                 profile ten times): single readings, whose noise is the sensor's at its own \
                 rate, fit for a thermal calibration but not a noise model",
                ulog::LEAST_SENSOR_RATE
            )
        } else {
            String::new()
        };
        Some(format!(
            "{} is logged at {} Hz and {} at {} Hz, so few of their samples share a time: read \
             the gyro axes and the accelerometer axes apart{subsample}",
            topics[0],
            crate::timing::short(g),
            topics[1],
            crate::timing::short(a),
        ))
    }
}

impl Pairing {
    /// A paired sample: closes the run of samples alone before it.
    fn pair(&mut self) {
        self.close(false);
        self.paired += 1;
    }

    /// Closes the run of samples alone since the last paired sample: before the first, a gap
    /// (or samples of both sensors, mixed) between two, or after the `last`.
    fn close(&mut self, last: bool) {
        let (g, a) = std::mem::take(&mut self.open);
        if self.paired == 0 {
            self.gyro.before += g;
            self.accel.before += a;
        } else if last {
            self.gyro.after += g;
            self.accel.after += a;
        } else {
            match (g, a) {
                (0, 0) => {}
                (_, 0) => self.gyro.gaps += 1,
                (0, _) => self.accel.gaps += 1,
                (g, a) => self.mixed += g + a,
            }
        }
    }

    /// `n` samples of `sensor` without a partner.
    fn alone(&mut self, sensor: Sensor, n: u64) {
        match sensor {
            Sensor::Gyro => {
                self.gyro.samples += n;
                self.open.0 += n;
            }
            Sensor::Accel => {
                self.accel.samples += n;
                self.open.1 += n;
            }
        }
    }

    /// The samples alone after the last paired sample.
    fn finish(&mut self) {
        self.close(true);
    }

    /// Why the samples without a partner have none, when a topic lost messages or spans less
    /// time than the other: for each sensor with `alone` (gyro, accelerometer) samples, where
    /// they lie in the other's topic (`topics`, gyro then accelerometer). `None` when they lie
    /// otherwise: scattered among both sensors' (two clocks), or one in most of the other
    /// topic's steps (two rates), the times of their own of each topic.
    fn lost(&self, alone: [u64; 2], topics: [&str; 2]) -> Option<String> {
        let total = self.paired + self.gyro.samples + self.accel.samples;
        // A topic's usual step is the other's when most of the steps between paired samples
        // hold no sample alone: the few that do are its gaps. Samples alone of both sensors
        // between the same two pairs are no gap; a few (1 %) are borne.
        let gaps = self.gyro.gaps + self.accel.gaps;
        if self.paired == 0 || gaps.saturating_mul(2) > self.paired || self.mixed * 100 > total {
            return None;
        }
        let sensors = [("gyro", &self.gyro), ("accelerometer", &self.accel)];
        let mut causes = Vec::new();
        for (k, n) in alone.into_iter().enumerate() {
            let (what, side) = sensors[k];
            let (other, _) = sensors[1 - k];
            let (mine, theirs) = (topics[k], topics[1 - k]);
            let mut how = Vec::new();
            if side.gaps > 0 {
                how.push(format!("lost messages ({} gaps)", side.gaps));
            }
            if side.before > 0 {
                how.push(format!("starts {} samples after {mine}", side.before));
            }
            if side.after > 0 {
                how.push(format!("ends {} samples before {mine}", side.after));
            }
            if n == 0 || how.is_empty() {
                continue;
            }
            causes.push(format!(
                "{n} {what} samples ({mine}) have no {other} sample at their times: {theirs} {}",
                how.join(" and ")
            ));
        }
        (!causes.is_empty()).then(|| causes.join("; "))
    }
}

/// The axes (of [`AXES`]) that `request.columns` name; an error naming the column that is none,
/// and saying what `has` the message.
fn picks(files: &[PathBuf], request: &Request, has: &str) -> Result<Vec<usize>, Fail> {
    request
        .columns
        .iter()
        .map(|c| axis(c).ok_or_else(|| with_file(files, format!("--column {}: {has}", escaped(c)))))
        .collect()
}

/// What a read of messages gave: the axes `picks` in SI units, and their stamps' statistics;
/// an error for the first stamp that went backwards (`backward`: message, stamp, the stamp
/// before), unless `request` drops such messages.
fn stamped(
    files: &[PathBuf],
    request: &Request,
    picks: &[usize],
    (timing, backward): (Timing, Option<(u64, i64, i64)>),
    skipped: Skipped,
) -> Result<Read, Fail> {
    if let Some((at, stamp, last)) = backward
        && !request.drop_backward
    {
        return Err(with_file(files, backward_text(&timing, at, stamp, last)));
    }
    Ok(Read {
        unknown: vec![None; picks.len()],
        units: picks.iter().map(|&i| si_unit(i)).collect(),
        timing: Some((timing, TimeUnit::HeaderStamps)),
        skipped,
        source: None,
        caveat: None,
    })
}

/// A bag's or an MCAP file's messages.
fn messages(
    files: &[PathBuf],
    kind: Kind,
    topic: Option<&str>,
    request: &Request,
    each: &mut dyn FnMut(Option<i64>, &[f64]),
) -> Result<Read, Fail> {
    let read = match kind {
        Kind::Mcap => mcap::read_selected,
        Kind::Rosbag2 => rosbag2::read_folder,
        Kind::Db3 => rosbag2::read_db3,
        _ => bag::read_selected,
    };
    let Some(topic) = topic else {
        // The reader's error for no topic lists the file's IMU topics.
        // (A damaged file gives its own error, before any topic is looked for.)
        let topics = match read(&files[0], &Select::topic(""), &mut |_| {}) {
            Err(e) if e.problem.starts_with("no ") && e.problem.contains(" messages on topic ") => {
                e.problem
                    .split_once(" (")
                    .map_or(String::new(), |(_, t)| format!(" ({t}"))
            }
            Err(e) => return Err(Fail(e.to_string())),
            Ok(_) => String::new(),
        };
        return Err(with_file(
            files,
            format!("{} needs --topic{topics}", kind.name()),
        ));
    };
    let picks = picks(
        files,
        request,
        "a sensor_msgs/Imu message has gx, gy, gz (angular_velocity, rad/s) and ax, ay, az \
         (linear_acceleration, m/s^2)",
    )?;
    let mut timing = Timing::new();
    let mut skipped = Skipped::default();
    let mut backward: Option<(u64, i64, i64)> = None;
    let mut count = 0u64;
    // Messages stamped 0: a driver that does not stamp. With --rate they are read in file
    // order, and the stamps give no rate.
    let mut unstamped = 0u64;
    let mut values = vec![0.0; picks.len()];
    let select = Select {
        topic,
        frame_id: request.frame_id,
        non_finite: true,
    };
    // The sensors read: a message that marks one of them as not provided, or holds a NaN or
    // an infinity in an axis read, is skipped, its stamp read with the others' (the clock's:
    // evenly spaced holes would read as a slower clock's beat with a coarse quantum).
    let gyro = picks.iter().any(|&i| i < 3);
    let accel = picks.iter().any(|&i| i >= 3);
    let (mut disregarded, mut non_finite) = (0u64, 0u64);
    // The first and last stamps of the file before, and this file's first.
    let mut before: Option<(i64, i64)> = None;
    for file in files {
        let mut first: Option<i64> = None;
        let s = read(file, &select, &mut |frame: Frame| {
            count += 1;
            if frame.stamp_ns != 0 && first.is_none() {
                first = Some(frame.stamp_ns);
            }
            if frame.stamp_ns == 0 {
                unstamped += 1;
            } else if !take_stamp(&mut timing, frame.stamp_ns, request.drop_backward) {
                backward.get_or_insert((count, frame.stamp_ns, timing.last()));
                return;
            }
            if (gyro && frame.not_provided.gyro) || (accel && frame.not_provided.accel) {
                disregarded += 1;
                return;
            }
            if picks.iter().any(|&i| !frame.axes[i].is_finite()) {
                non_finite += 1;
                return;
            }
            for (v, &i) in values.iter_mut().zip(&picks) {
                *v = frame.axes[i];
            }
            each((frame.stamp_ns != 0).then_some(frame.stamp_ns), &values);
        })
        .map_err(|e| Fail(e.to_string()))?;
        if let (Some(t), Some(before)) = (first, before)
            && misordered(t, before, request.drop_backward)
        {
            return Err(with_file(std::slice::from_ref(file), file_order(t, before)));
        }
        if let Some(t) = first {
            before = Some((t, timing.last().max(t)));
        }
        skipped.undecodable += s.undecodable;
        skipped.other_frame_id += s.other_frame_id;
        skipped.gyro_not_provided += s.gyro_not_provided;
        skipped.accel_not_provided += s.accel_not_provided;
    }
    // Skipped messages leave holes the stamps show only as gaps; uniform ones (every other
    // message) would pass for a lower rate. More than 1 % of the record is refused. A sensor
    // the messages mark as not provided (sensor_msgs/Imu: its covariance's first element -1)
    // holds no measurement there: more than 1 % of them is refused naming the mark (all of
    // them: a gyro-only IMU's zeros), fewer are skipped and counted.
    let total = count.saturating_add(skipped.undecodable);
    skipped.disregarded = disregarded;
    skipped.non_finite = non_finite;
    if disregarded.saturating_mul(100) > total
        && let Some(refusal) = skipped.not_provided(gyro, accel, total)
    {
        return Err(with_file(files, refusal));
    }
    let lost = skipped
        .undecodable
        .saturating_add(skipped.non_finite)
        .saturating_add(disregarded);
    if lost.saturating_mul(100) > total {
        return Err(with_file(
            files,
            format!(
                "{lost} of the {total} messages on '{}' were skipped ({} undecodable, {} with \
                 a NaN or infinite axis, {disregarded} marking a sensor read as not provided): \
                 more than 1 % of the record is missing",
                escaped(topic),
                skipped.undecodable,
                skipped.non_finite
            ),
        ));
    }
    if unstamped > 0 {
        if request.want_time {
            return Err(with_file(
                files,
                format!(
                    "the header stamps of {unstamped} of {count} messages on '{}' are zero (a \
                     driver that does not stamp its messages): give --rate to read them in \
                     file order",
                    escaped(topic)
                ),
            ));
        }
        return Ok(Read {
            unknown: vec![None; picks.len()],
            units: picks.iter().map(|&i| si_unit(i)).collect(),
            timing: None,
            skipped,
            source: None,
            caveat: None,
        });
    }
    stamped(files, request, &picks, (timing, backward), skipped)
}

/// Whether a file whose first stamp is `t` follows the file `before` (its first and last
/// stamps) out of order: not after its last, or with `drop_backward` (which drops the
/// stamps of a stretch two files share), not after its first (files out of order, or one
/// given twice, whose samples it would drop whole).
fn misordered(t: i64, (first, last): (i64, i64), drop_backward: bool) -> bool {
    if drop_backward { t <= first } else { t <= last }
}

/// The refusal of a file whose first stamp `t` is not after the last of the file before it
/// (`before`: that file's first and last stamps): files out of order (or a clock restarted
/// between them) where it lies before that file's first, files that overlap (one given twice)
/// where it lies within it.
fn file_order(t: i64, (first, last): (i64, i64)) -> String {
    if t < first {
        format!(
            "the file's first timestamp, {t} ns, is before the first of the file before \
             ({first} ns): the files are out of order (give them in time order; a shell's glob \
             puts rec_10 before rec_2), or the clock restarted between them (give each as a \
             record of its own)"
        )
    } else {
        format!(
            "the file's first timestamp, {t} ns, lies within the file before ({first} to \
             {last} ns): the files overlap (a file given twice, or pieces that share a \
             stretch); give each stretch once"
        )
    }
}

/// The unit of a message's axis `i` (of [`AXES`]).
fn si_unit(i: usize) -> Option<Unit> {
    Unit::parse(if i < 3 { "rad/s" } else { "m/s^2" })
}

/// Takes a message's stamp `t` into `timing`: whether the message is kept. A stamp equal to
/// the one before is kept (the summary tells a clock coarser than its messages, or a host's
/// late messages caught up on within its clock's step, from messages repeated), or dropped
/// and counted with `drop_backward`; one before it is dropped and counted.
fn take_stamp(timing: &mut Timing, t: i64, drop_backward: bool) -> bool {
    match timing.push(t) {
        Step::Forward => true,
        Step::Repeat if !drop_backward => {
            timing.keep_repeat();
            true
        }
        Step::Repeat => {
            timing.drop_repeat();
            false
        }
        Step::Backward { .. } => {
            timing.drop_one();
            false
        }
    }
}

/// The stamp before a sample's stamp `t` that did not move `step` forward.
fn not_after(step: Step, t: i64) -> Option<i64> {
    match step {
        Step::Forward => None,
        Step::Backward { last } => Some(last),
        Step::Repeat => Some(t),
    }
}

/// The refusal of stamps that go backwards.
fn backward_text(timing: &Timing, at: u64, stamp: i64, last: i64) -> String {
    format!(
        "{} timestamps are not after the one before (the first: message {at}, {stamp} ns after \
         {last} ns); --drop-backward drops such samples and counts them",
        timing.dropped()
    )
}

/// Parses `cells` (named by `request.columns`) into `values` and passes them on.
fn row_values(
    values: &mut [f64],
    cells: &[&str],
    request: &Request,
    stamp: Option<i64>,
    each: &mut dyn FnMut(Option<i64>, &[f64]),
) -> Result<(), String> {
    for ((v, cell), name) in values.iter_mut().zip(cells).zip(request.columns) {
        *v = csv::finite(name)(cell)?;
    }
    each(stamp, values);
    Ok(())
}

/// Whether a CSV column's name is one a time column goes by (`t`, `time`, `timestamp`,
/// `stamp`, `sec`, `seconds`, or `t_`, `time_`, `timestamp_`, `stamp_` and a time unit; with or
/// without a unit bracket or a leading `#`).
pub fn is_time(name: &str) -> bool {
    let bare = split_unit(name).0.to_ascii_lowercase();
    let bare = bare.trim_start_matches('#');
    matches!(
        bare,
        "t" | "time" | "timestamp" | "stamp" | "sec" | "seconds"
    ) || ["t_", "time_", "timestamp_", "stamp_"].iter().any(|p| {
        bare.strip_prefix(p)
            .is_some_and(|u| matches!(TimeUnit::of(u, Some(u)), Ok(Some(_))))
    })
}

/// CSV files.
fn csv_stream(
    files: &[PathBuf],
    request: &Request,
    each: &mut dyn FnMut(Option<i64>, &[f64]),
) -> Result<Read, Fail> {
    let mut units: Option<Vec<Option<Unit>>> = None;
    let mut unknown: Vec<Option<String>> = Vec::new();
    // The time column's index and unit (when the column does not say: by its first value).
    let time: Cell<Option<(usize, Option<TimeUnit>)>> = Cell::new(None);
    let strict = request.want_time;
    // The stamps' statistics are kept on a thread of their own, beside the parsing: each
    // sample's step (forward, repeated, backward) is told here at once from the stamps'
    // order, and the calls on the statistics sent over in batches.
    let (send, receive) = std::sync::mpsc::sync_channel::<Vec<Call>>(16);
    let mut timing = Beside {
        order: Order::default(),
        calls: Vec::with_capacity(CALLS),
        send,
    };
    let mut values = vec![0.0; request.columns.len()];
    // The files begun, and whether the one being read has passed a row yet.
    let begun = std::cell::Cell::new((0usize, false));
    // The first stamps of the file before and of the one being read, and that one's number.
    let mut firsts: (Option<i64>, Option<i64>, usize) = (None, None, 0);
    // Samples kept, at a given rate, whose stamp is not after the one before.
    let mut backward_kept = 0u64;
    let mut wraps = Wraps::default();
    let mut select = |header: &[String]| -> Result<Vec<usize>, String> {
        begun.set((begun.get().0 + 1, true));
        let mut picks = request
            .columns
            .iter()
            .map(|c| position(header, c))
            .collect::<Result<Vec<usize>, String>>()?;
        if let Some(k) = (1..picks.len()).find(|&k| picks[..k].contains(&picks[k])) {
            return Err(format!(
                "column '{}' is named twice",
                escaped(&header[picks[k]])
            ));
        }
        let here: Vec<Option<Unit>> = picks
            .iter()
            .map(|&i| split_unit(&header[i]).1.and_then(Unit::parse))
            .collect();
        if let Some(first) = &units
            && *first != here
        {
            return Err(
                "the columns' unit brackets differ from the first file's: one record is in \
                 one unit"
                    .into(),
            );
        }
        units.get_or_insert(here);
        unknown = picks
            .iter()
            .map(|&i| {
                let bracket = split_unit(&header[i]).1?;
                Unit::parse(bracket).is_none().then(|| bracket.to_string())
            })
            .collect();
        let t = match request.time_column {
            Some(name) => Some(position(header, name)?),
            None => (0..header.len()).find(|&i| is_time(&header[i])),
        };
        let t = match t.map(|i| (i, split_unit(&header[i]))) {
            Some((i, (name, bracket))) => match TimeUnit::of(name, bracket) {
                Ok(unit) => Some((i, unit)),
                Err(e) if strict => return Err(e),
                Err(_) => None,
            },
            None => None,
        };
        time.set(t);
        if let Some((i, _)) = t {
            picks.push(i);
        }
        Ok(picks)
    };
    let mut row = |cells: &[&str]| -> Result<(), String> {
        let (files, first_row) = begun.get();
        if first_row {
            begun.set((files, false));
        }
        let (cells, stamp) = match time.get() {
            Some((i, unit)) => {
                let (last, cells) = cells.split_last().ok_or("no cells")?;
                // Asked only while the unit is not known yet.
                let first = || last.parse::<f64>().ok().filter(|v| v.is_finite());
                let unit = match unit.or_else(|| TimeUnit::by_magnitude(first()?)) {
                    Some(u) => u,
                    // A first stamp that is no number says nothing of the unit: its sample is
                    // kept (with --rate) and the next stamp is asked, or it is refused as such.
                    None if first().is_none() && !strict => {
                        return row_values(&mut values, cells, request, None, &mut *each);
                    }
                    None if first().is_none() => {
                        return Err(format!("timestamp '{}' is not a number", csv::shown(last)));
                    }
                    None if strict => {
                        return Err(format!(
                            "the time column does not say its unit ([s], [ms], [us] or [ns] \
                             in its header, or a suffix such as _ns) and its first value '{}' \
                             is no epoch time; name the unit, or give --rate",
                            csv::shown(last)
                        ));
                    }
                    None => {
                        // The rate is given: stamps of unknown unit are not read.
                        time.set(None);
                        return row_values(&mut values, cells, request, None, &mut *each);
                    }
                };
                time.set(Some((i, Some(unit))));
                match unit.nanoseconds(last) {
                    Ok(t) => (cells, Some(t)),
                    Err(e) if strict => return Err(e),
                    Err(_) => {
                        // The rate is given: the sample stays, its stamp (not a number) is
                        // left out of the stamps' statistics, which still check the rate.
                        return row_values(&mut values, cells, request, None, &mut *each);
                    }
                }
            }
            None => (cells, None),
        };
        let stamp = stamp.map(|t| wraps.unwrapped(t, time.get().and_then(|(_, u)| u)));
        if let Some(t) = stamp
            && firsts.2 != files
        {
            firsts = (firsts.1, Some(t), files);
        }
        let step = stamp.map(|t| (t, timing.push(t)));
        if let Some((_, Step::Repeat)) = step
            && !request.drop_backward
        {
            // Kept: the summary tells a clock coarser than its samples from samples repeated.
            timing.keep_repeat();
        } else if let Some((t, step)) = step
            && let Some(last) = not_after(step, t)
        {
            // Files out of order, or overlapping, are refused whatever the rate.
            let before = (firsts.0.unwrap_or(last), last);
            if first_row && files > 1 && misordered(t, before, request.drop_backward) {
                return Err(file_order(t, before));
            }
            if !strict && !request.drop_backward {
                // The rate is given: the sample stays, counted, its stamp left out of the
                // stamps' statistics, which still check the rate given.
                backward_kept += 1;
                return row_values(&mut values, cells, request, Some(t), &mut *each);
            }
            if step == Step::Repeat {
                timing.drop_repeat();
            } else {
                timing.drop_one();
            }
            if !request.drop_backward {
                return Err(format!(
                    "timestamp {t} ns is not after the one before ({last} ns); \
                     --drop-backward drops such samples and counts them"
                ));
            }
            return Ok(());
        }
        row_values(&mut values, cells, request, stamp, &mut *each)
    };
    let keeper = std::thread::spawn(move || {
        let mut timing = Timing::new();
        for calls in receive {
            timing.replay(&calls);
        }
        timing
    });
    let read = csv::read_rows(files, &mut select, &mut row);
    timing.finish();
    let timing = keeper
        .join()
        .map_err(|_| Fail("the timestamps' thread stopped".into()))?;
    read.map_err(|e: DataError| Fail(e.to_string()))?;
    Ok(Read {
        unknown,
        units: units.unwrap_or_default(),
        timing: time
            .get()
            .map(|(_, u)| (timing, u.unwrap_or(TimeUnit::Seconds))),
        skipped: Skipped {
            backward_kept,
            ..Skipped::default()
        },
        source: None,
        caveat: wraps.caveat(),
    })
}

/// A time column that counts whole units on 32 bits (a microcontroller's `micros()` wraps
/// every 71.6 minutes, its `millis()` every 49.7 days), read on past each wrap: a stamp
/// before the last, both within the counter's range, where the counter's modulus puts it
/// after the last by no more than four intervals (the one before).
#[derive(Default)]
struct Wraps {
    /// The last stamp as read and the interval that reached it, ns.
    last: Option<(i64, i64)>,
    /// The time added for the wraps passed, ns, how many, and the unit's name.
    offset: i64,
    count: u32,
    unit: &'static str,
}

impl Wraps {
    /// The stamp `t` (ns, as read in `unit`) read on past the wraps passed.
    fn unwrapped(&mut self, t: i64, unit: Option<TimeUnit>) -> i64 {
        let (scale, name) = match unit {
            Some(TimeUnit::Milliseconds) => (1_000_000, "ms"),
            Some(TimeUnit::Microseconds) => (1_000, "us"),
            Some(TimeUnit::Nanoseconds) => (1, "ns"),
            _ => (0, ""),
        };
        let modulus = scale << 32;
        let interval = match self.last {
            Some((last, interval))
                if scale > 0
                    && t < last
                    && (0..modulus).contains(&t)
                    && last < modulus
                    && t % scale == 0
                    && last % scale == 0
                    && interval > 0
                    && t + modulus - last <= interval.saturating_mul(4) =>
            {
                self.offset = self.offset.saturating_add(modulus);
                (self.count, self.unit) = (self.count + 1, name);
                t + modulus - last
            }
            Some((last, _)) => t.saturating_sub(last),
            None => 0,
        };
        self.last = Some((t, interval));
        t.saturating_add(self.offset)
    }

    /// The warning that the stamps wrapped, where they did.
    fn caveat(&self) -> Option<String> {
        (self.count > 0).then(|| {
            format!(
                "the time column counts whole {} on 32 bits and wrapped {} time{} (at 2^32 {0}): \
                 read on past each wrap",
                self.unit,
                self.count,
                if self.count == 1 { "" } else { "s" }
            )
        })
    }
}

/// The calls on a [`Timing`] sent at once.
const CALLS: usize = 8192;

/// A [`Timing`] kept on another thread: the steps told here, the calls sent there.
struct Beside {
    order: Order,
    calls: Vec<Call>,
    send: std::sync::mpsc::SyncSender<Vec<Call>>,
}

impl Beside {
    /// [`Timing::push`].
    fn push(&mut self, t: i64) -> Step {
        self.call(Call::Push(t));
        self.order.step(t)
    }

    fn keep_repeat(&mut self) {
        self.call(Call::KeepRepeat);
    }

    fn drop_repeat(&mut self) {
        self.call(Call::DropRepeat);
    }

    fn drop_one(&mut self) {
        self.call(Call::DropOne);
    }

    fn call(&mut self, call: Call) {
        self.calls.push(call);
        if self.calls.len() == CALLS {
            // A closed channel means the thread is gone; its join says why.
            let _ = self.send.send(std::mem::replace(
                &mut self.calls,
                Vec::with_capacity(CALLS),
            ));
        }
    }

    /// Sends the calls left; the thread then ends.
    fn finish(self) {
        if !self.calls.is_empty() {
            let _ = self.send.send(self.calls);
        }
    }
}

/// The read of the `columns` of the file `bytes` (its extension `ext`), its stamps read, or
/// its refusal.
#[cfg(test)]
pub(crate) fn read_bytes(bytes: &[u8], ext: &str, columns: &[&str]) -> Result<Read, String> {
    let file = crate::Scratch::new(bytes, ext);
    let columns: Vec<String> = columns.iter().map(|c| c.to_string()).collect();
    let request = Request {
        columns: &columns,
        topic: None,
        frame_id: None,
        time_column: None,
        want_time: true,
        drop_backward: false,
        instance: None,
    };
    stream(std::slice::from_ref(&file.0), &request, &mut |_| {}).map_err(|e| e.0)
}

/// The refusal of the `columns` of the file `bytes` (its extension `ext`), its stamps read.
#[cfg(test)]
pub(crate) fn refusal(bytes: &[u8], ext: &str, columns: &[&str]) -> String {
    match read_bytes(bytes, ext, columns) {
        Ok(_) => panic!("read"),
        Err(e) => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The format PX4 writes for `sensor_gyro_fifo` and `sensor_accel_fifo` (after `name:`).
    const FIFO: &str = concat!(
        "uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;",
        "float scale;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;",
        "uint8_t[3] _padding0;",
    );

    /// A message of type `ty` and `payload`, as ULog frames it.
    fn message(bytes: &mut Vec<u8>, ty: u8, payload: &[u8]) {
        bytes.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        bytes.push(ty);
        bytes.extend_from_slice(payload);
    }

    /// A PX4 ULog file of one IMU's `sensor_gyro_fifo` and `sensor_accel_fifo`, 10 samples a
    /// message: for each, the times (µs) of its messages' last samples and its samples'
    /// spacing (µs).
    fn fifo_log(gyro: (&[u64], u64), accel: (&[u64], u64)) -> Vec<u8> {
        fifo_log_scaled(gyro, accel, 1e-3)
    }

    /// [`fifo_log`] with the messages' `scale` field.
    fn fifo_log_scaled(gyro: (&[u64], u64), accel: (&[u64], u64), scale: f32) -> Vec<u8> {
        let tens = |t: &[u64]| -> Vec<(u64, u8)> { t.iter().map(|&t| (t, 10)).collect() };
        fifo_log_counted((&tens(gyro.0), gyro.1), (&tens(accel.0), accel.1), scale)
    }

    /// [`fifo_log_scaled`] of messages each its stamp and its samples.
    fn fifo_log_counted(
        gyro: (&[(u64, u8)], u64),
        accel: (&[(u64, u8)], u64),
        scale: f32,
    ) -> Vec<u8> {
        let mut bytes = crate::ulog::MAGIC.to_vec();
        bytes.push(1);
        bytes.extend_from_slice(&0u64.to_le_bytes());
        message(&mut bytes, b'B', &[0; 40]);
        for (id, topic) in [(0u16, "sensor_gyro_fifo"), (1, "sensor_accel_fifo")] {
            message(&mut bytes, b'F', format!("{topic}:{FIFO}").as_bytes());
            let mut p = vec![0];
            p.extend_from_slice(&id.to_le_bytes());
            p.extend_from_slice(topic.as_bytes());
            message(&mut bytes, b'A', &p);
        }
        let mut data: Vec<(u64, u16, u64, u8)> =
            gyro.0.iter().map(|&(t, n)| (t, 0, gyro.1, n)).collect();
        data.extend(accel.0.iter().map(|&(t, n)| (t, 1, accel.1, n)));
        data.sort_unstable();
        for (t, id, dt, n) in data {
            let mut p = id.to_le_bytes().to_vec();
            p.extend_from_slice(&(t + 40).to_le_bytes());
            p.extend_from_slice(&t.to_le_bytes());
            p.extend_from_slice(&(7 + u32::from(id)).to_le_bytes());
            p.extend_from_slice(&(dt as f32).to_le_bytes());
            p.extend_from_slice(&scale.to_le_bytes());
            for axis in 0..3u64 {
                for i in 0..32u64 {
                    // Noise-like values, different for each sample and axis.
                    let v = ((t / 50 + i) * 7_919 + axis * 104_729) % 201;
                    p.extend_from_slice(&(v as i16 - 100).to_le_bytes());
                }
            }
            p.push(n);
            message(&mut bytes, b'D', &p);
        }
        bytes
    }

    /// The refusal of the six axes of the ULog file `bytes`.
    fn six_axis_refusal(bytes: &[u8]) -> String {
        let columns: Vec<&str> = AXES.to_vec();
        refusal(bytes, "ulg", &columns)
    }

    /// The times of the last samples of `n` messages of 10 samples `dt` µs apart from 1 s
    /// on, but those `k` for which `lost(k)`.
    fn messages(n: u64, dt: u64, lost: impl Fn(u64) -> bool) -> Vec<u64> {
        (0..n)
            .filter(|&k| !lost(k))
            .map(|k| 1_000_000 + 9 * dt + 10 * dt * k)
            .collect()
    }

    #[test]
    fn a_topic_that_lost_messages_is_named_with_its_gaps_not_called_a_clock_of_its_own() {
        // 2 kHz. The logger lost every 50th gyro message (2 % of the gyro, the last message
        // one of them); the accelerometer is whole. 98 % of the samples pair exactly.
        let e = six_axis_refusal(&fifo_log(
            (&messages(1_000, 500, |k| k % 50 == 49), 500),
            (&messages(1_000, 500, |_| false), 500),
        ));
        assert!(
            e.contains(
                "200 accelerometer samples (sensor_accel_fifo) have no gyro sample at their \
                 times: sensor_gyro_fifo lost messages (19 gaps) and ends 10 samples before \
                 sensor_accel_fifo"
            ),
            "{e}"
        );
        assert!(e.contains("share 9800 sample times"), "{e}");
        assert!(!e.contains("times of their own"), "{e}");
        // Both lost messages, and the accelerometer's first three: each topic is named.
        let e = six_axis_refusal(&fifo_log(
            (&messages(1_000, 500, |k| k % 50 == 20), 500),
            (&messages(1_000, 500, |k| k % 40 == 7 || k < 3), 500),
        ));
        assert!(
            e.contains(
                "280 gyro samples (sensor_gyro_fifo) have no accelerometer sample at their \
                 times: sensor_accel_fifo lost messages (25 gaps) and starts 30 samples after \
                 sensor_gyro_fifo; 200 accelerometer samples (sensor_accel_fifo) have no gyro \
                 sample at their times: sensor_gyro_fifo lost messages (20 gaps)"
            ),
            "{e}"
        );
        assert!(!e.contains("times of their own"), "{e}");
    }

    /// The rate the timestamps of a ULog FIFO log give, whether they are refused as runs,
    /// and the warning they are read with.
    fn fifo_rate(bytes: &[u8]) -> Result<(f64, bool, Option<String>), String> {
        let read = read_bytes(bytes, "ulg", &AXES)?;
        let (timing, unit) = read.timing.ok_or("no stamps")?;
        let s = timing.summary(unit)?;
        Ok((s.rate_hz, s.batch_refusal().is_some(), read.caveat))
    }

    #[test]
    fn two_samples_a_message_read_by_a_timer_are_read_at_their_counts_rate() {
        // A timer reading a sensor a little slower than its dt twice a dt: two samples a
        // message, one now and then; each stamped at the read. Read as a clock, the
        // samples placed dt apart read dt's rate (pass 48 F1: 1990 Hz read at 1 kHz, 2000.00013
        // Hz; 1595.2 Hz read at 800 Hz, 1600.0002 Hz); the messages' counts give the rate.
        for (rate, reads, dt) in [(1990.0, 1000.0, 500), (1595.2, 800.0, 625)] {
            let messages: Vec<(u64, u8)> = crate::timer_reads(rate, reads, 6_000)
                .into_iter()
                .map(|(t, n)| (t.round() as u64, n as u8))
                .collect();
            assert!(messages.iter().any(|m| m.1 == 1));
            let (read, _, _) =
                fifo_rate(&fifo_log_counted((&messages, dt), (&messages, dt), 1e-3)).unwrap();
            assert!((read / rate - 1.0).abs() < 5e-5, "{rate} Hz: {read} Hz");
        }
    }

    #[test]
    fn fifo_messages_whose_stamps_jitter_are_read_at_the_rate_their_counts_give() {
        // 10 samples a message, each message's timestamp_sample jittered alone by up to
        // `jitter` us (a driver's read scheduled late), messages lost now and then. Each
        // message's samples stamped back at dt from its stamp part runs by intervals off
        // the grid: 8000 Hz at 20 us was refused as a FIFO's reads stamped back at a set
        // spacing (pass 39 F4), and a sensor 0.125 % slower than its dt the same way.
        let mut next = crate::xorshift(11);
        let mut jitter =
            move |most: f64| ((next() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * most;
        for (rate, dt, most, lost) in [
            (8000.0, 125, 20.0, 0),
            (8000.0, 125, 40.0, 97),
            (7990.0, 125, 20.0, 0),
            (7990.0, 125, 30.0, 61),
            (2000.0, 500, 60.0, 0),
            (1999.0, 500, 100.0, 53),
            // Stamps jittered by up to a quarter of a message's time: a third of the
            // messages begin before the one before ends where their samples are placed dt
            // apart back from their stamp, and were refused as a sensor faster than its dt;
            // read, with a warning that a message lost is not told from a late stamp (runs
            // parted at stamps late by half a message's samples and fitted to their ends
            // read 8 kHz, 8 samples a message, stamps jittered by 170 us RMS, 8001.75 Hz).
            (8000.0, 125, 300.0, 0),
            (7996.0, 125, 600.0, 0),
        ] {
            let stamps: Vec<u64> = (0..4_000u64)
                .filter(|&k| lost == 0 || k % lost != lost / 2)
                .map(|k| (1e6 + (10 * k + 9) as f64 * 1e6 / rate + jitter(most)).round() as u64)
                .collect();
            let (read, runs, warned) = fifo_rate(&fifo_log((&stamps, dt), (&stamps, dt))).unwrap();
            assert!(
                (read / rate - 1.0).abs() < 5e-5 && !runs,
                "{rate} Hz, {most} us: {read} Hz{}",
                if runs { " (runs)" } else { "" }
            );
            assert_eq!(
                warned.is_some_and(|w| w.contains("a message lost is not told from a late")),
                most >= 300.0,
                "{rate} Hz, {most} us"
            );
        }
    }

    #[test]
    fn a_fifo_faster_than_its_dt_is_refused_naming_it() {
        // 10 samples a message every 1 ms, dt 125 us (a sensor at 10 kHz, dt saying 8 kHz):
        // each message's first sample before the last one's last, refused as stamps "not
        // after" with the --drop-backward hint, before.
        let every = messages(1_000, 100, |_| false);
        let log = fifo_log((&every, 125), (&every, 125));
        let e = six_axis_refusal(&log);
        assert!(
            e.contains("999 of the 1000 sensor_gyro_fifo messages begin before the one before")
                && e.contains("faster than its dt field says, 8000 Hz")
                && e.contains("about 10000 Hz"),
            "{e}"
        );
    }

    #[test]
    fn fifo_messages_of_no_imus_scale_are_not_read() {
        // A scale of 1e30, 0, -1e-3 or NaN per LSB: 1e30 read as it is (values of 1e32), the
        // others said to leave the log without sensor_gyro messages, before.
        let every = messages(1_000, 500, |_| false);
        for scale in [1e30, 0.0, -1e-3, f32::NAN] {
            let e = six_axis_refusal(&fifo_log_scaled((&every, 500), (&every, 500), scale));
            assert!(
                e.contains("no finite samples of sensor_gyro_fifo")
                    && e.contains("1000 messages undecodable (a samples field"),
                "{scale}: {e}"
            );
        }
    }

    #[test]
    fn samples_of_two_clocks_are_called_times_of_their_own_and_two_rates_named() {
        // The accelerometer's samples half a step after the gyro's: none pairs.
        let gyro = messages(1_000, 500, |_| false);
        let late: Vec<u64> = gyro.iter().map(|t| t + 250).collect();
        let e = six_axis_refusal(&fifo_log((&gyro, 500), (&late, 500)));
        assert!(e.contains("published at times of their own"), "{e}");
        // The accelerometer at half the gyro's rate: every other gyro sample has no partner,
        // one in each of the accelerometer's steps, which are no gaps: the two rates named.
        let e = six_axis_refusal(&fifo_log(
            (&gyro, 500),
            (&messages(500, 1_000, |_| false), 1_000),
        ));
        assert!(
            e.contains("sensor_gyro_fifo is logged at 2000 Hz and sensor_accel_fifo at 1000 Hz")
                && !e.contains("subsample")
                && !e.contains("times of their own"),
            "{e}"
        );
    }
}
