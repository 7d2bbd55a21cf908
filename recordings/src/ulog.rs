//! Streaming IMU samples out of a PX4 ULog file (`.ulg`): the topics `sensor_gyro` and
//! `sensor_accel`, and `sensor_gyro_fifo` and `sensor_accel_fifo` unrolled into their samples.
//!
//! Format: the ULog specification (PX4 `docs/en/dev_log/ulog_file_format.md`,
//! <https://docs.px4.io/main/en/dev_log/ulog_file_format.html>), as its reference reader
//! `pyulog` (<https://github.com/PX4/pyulog>, `pyulog/core.py`) reads it: a 16-byte header
//! (magic `55 4C 6F 67 01 12 35`, version, start time in µs), then messages of `uint16 size`,
//! `uint8 type` and `size` bytes, little-endian and unaligned. The flag bits ('B') must come
//! first: a log with an incompatible flag other than DATA_APPENDED (bit 0 of byte 0) is
//! refused; with DATA_APPENDED, a message cut short where appended data begins is dropped and
//! reading goes on at the appended data, as pyulog does. Formats ('F') give every layout:
//! fields are looked up by name and type, nested formats flattened (at most
//! [`MAX_NESTING`] deep, never recursive), trailing `_padding*` fields may be missing from a
//! data message. Parameters ('P', `int32_t` or `float`) of the definitions section (before
//! the first 'A', 'L' or 'C') are the initial values; later ones are changes, timed by the
//! newest data timestamp before them (the header's start time before any).
//! Subscriptions ('A') name a format and its uORB instance (multi_id); data ('D') follows.
//! Info ('I', 'M') is kept as text. Log strings, syncs, dropouts (counted), default parameters
//! and unknown message types are skipped; an unsubscription ('R') frees its msg_id.
//!
//! Topics (PX4 `msg/SensorGyro.msg`, `SensorAccel.msg`, `SensorGyroFifo.msg`,
//! `SensorAccelFifo.msg`): a sample's time is `timestamp_sample` (`timestamp` when the format
//! has none) in µs since boot; `x`, `y`, `z` in rad/s or m/s^2 in the board frame, before any
//! calibration (no `CAL_*` offsets, no `TC_*` thermal correction, no `SENS_BOARD_ROT`);
//! `temperature` in °C. A FIFO message of N = `samples` samples is unrolled as
//! `value_i = x[i]*scale`, i = 0..N-1, at `t_i = timestamp_sample - (N-1-i)*s`: `s` is the
//! time from the last message's `timestamp_sample` over N where that is 1.5 `dt` or less
//! (the samples came at the sensor's rate between the two reads, and each read's stamp
//! jitters alone), else (the first message, one after messages lost) `dt` (µs); the
//! topic's rate is then the slope of the messages' stamps on their samples counted, fitted
//! by least squares over each run of messages that follow one another ([`Report::fifo_rate`]);
//! FIFO topics carry no temperature: it is interpolated linearly in time from the
//! `temperature` of the sensor topic of the same kind and device_id (`sensor_gyro` for gyro
//! FIFO, `sensor_accel` for accel FIFO; the other one when the device has no temperature
//! there), and held at the nearest value outside their span. A device that has no such
//! messages gives no temperature (`None`), and [`Report::temperature`] says so.
//!
//! The file is read front to back through a buffer of 256 KiB, one message at a time: memory
//! is bounded by the formats, subscriptions and parameters the log defines (each bounded),
//! whatever its length; [`read`] surveys the file first, then reads it again. A truncated
//! last message, or zeros to the end of the file (a log cut by a power loss), is reported,
//! not an error; a message whose
//! type is not a letter, a data message of a length its format does not allow, or data of a
//! subscription never made is a corrupt file: an error naming the message and its byte offset.

use std::collections::{HashMap, VecDeque};
use std::fmt;
use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::Path;

use crate::csv::DataError;
use crate::error::escaped;
use crate::frame::{bytes_at, data_error};

/// The first seven bytes of a ULog file.
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];

/// The deepest nesting of formats read (a format holding one holding one ... ).
pub const MAX_NESTING: usize = 8;

/// The least rate of a sensor topic read as the sensor's own samples, Hz: PX4's IMU drivers
/// publish `sensor_gyro` and `sensor_accel` at hundreds of Hz, and its logger's profiles write
/// them once a second (the default) or ten times (thermal calibration, sensor comparison), a
/// sample kept each interval.
pub const LEAST_SENSOR_RATE: f64 = 50.0;

/// The header's length: magic, version, start time.
const HEADER_LEN: usize = 16;
/// The longest data payload: a message's size is a u16, the msg_id takes two bytes.
const MAX_DATA: usize = u16::MAX as usize - 2;
/// The most format text kept, in bytes, all formats together.
const MAX_FORMAT_BYTES: usize = 16 << 20;
/// The most parameters kept.
const MAX_PARAMETERS: usize = 1 << 16;
/// The changes of a parameter kept with their time (all are counted).
const KEPT_CHANGES: usize = 16;
/// The most info ('I') entries kept, and the longest text kept of one.
const MAX_INFO: usize = 256;
const MAX_INFO_TEXT: usize = 256;
/// The most device_ids listed for one topic instance.
const MAX_DEVICE_IDS: usize = 8;

/// The IMU topics read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Topic {
    /// `sensor_gyro`: one averaged sample per message, rad/s, with temperature.
    Gyro,
    /// `sensor_accel`: one averaged sample per message, m/s^2, with temperature.
    Accel,
    /// `sensor_gyro_fifo`: up to 32 raw samples per message, rad/s, no temperature.
    GyroFifo,
    /// `sensor_accel_fifo`: up to 32 raw samples per message, m/s^2, no temperature.
    AccelFifo,
}

impl Topic {
    /// Every topic, in this order.
    pub const ALL: [Topic; 4] = [Topic::Gyro, Topic::Accel, Topic::GyroFifo, Topic::AccelFifo];

    /// The uORB topic name (`sensor_gyro`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Topic::Gyro => "sensor_gyro",
            Topic::Accel => "sensor_accel",
            Topic::GyroFifo => "sensor_gyro_fifo",
            Topic::AccelFifo => "sensor_accel_fifo",
        }
    }

    /// Whether messages of the topic hold a FIFO's worth of samples.
    pub fn is_fifo(self) -> bool {
        matches!(self, Topic::GyroFifo | Topic::AccelFifo)
    }

    /// The topic named `name`.
    fn of(name: &str) -> Option<Topic> {
        Topic::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The sensor topics a FIFO topic's temperature comes from, preferred first.
    fn temperature_sources(self) -> [Topic; 2] {
        match self {
            Topic::Gyro | Topic::GyroFifo => [Topic::Gyro, Topic::Accel],
            Topic::Accel | Topic::AccelFifo => [Topic::Accel, Topic::Gyro],
        }
    }
}

impl fmt::Display for Topic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which IMU of a topic to read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// The topic's one instance: an error when it has several.
    Only,
    /// The uORB instance (the subscription's multi_id).
    Instance(u8),
    /// The sensor's device_id, on whichever instance it is.
    DeviceId(u32),
}

/// Which samples to read: a topic, and which of its IMUs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Select {
    /// The topic.
    pub topic: Topic,
    /// Its instance or device.
    pub which: Which,
}

/// One IMU sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The sample time in µs since boot (fractional for unrolled FIFO samples).
    pub time_us: f64,
    /// x, y, z: rad/s (gyro) or m/s^2 (accel), board frame, uncalibrated.
    pub xyz: [f64; 3],
    /// The sensor's temperature in °C: the message's own, or interpolated for FIFO samples;
    /// `None` when the log gives none (or a NaN one).
    pub temperature: Option<f64>,
    /// The sensor's device_id.
    pub device_id: u32,
    /// The uORB instance (multi_id) of the message.
    pub instance: u8,
}

/// A parameter's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// An `int32_t` parameter.
    Int(i32),
    /// A `float` parameter.
    Float(f32),
}

impl Value {
    /// The value as an f64 (exact for both kinds).
    pub fn as_f64(self) -> f64 {
        match self {
            Value::Int(v) => f64::from(v),
            Value::Float(v) => f64::from(v),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Int(v) => write!(f, "{v}"),
            Value::Float(v) => write!(f, "{v}"),
        }
    }
}

/// A parameter of the log.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Its name (`TC_G0_ID`, ...).
    pub name: String,
    /// Its value in the definitions section; `None` when it first appears as a change.
    pub initial: Option<Value>,
    /// Its last value.
    pub value: Value,
    /// How many changes the data section holds.
    pub changes: u64,
    /// The first 16 changes: the newest data timestamp before each (µs), and the new value.
    pub first_changes: Vec<(u64, Value)>,
}

/// What the log holds of one topic instance.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicSurvey {
    /// The topic.
    pub topic: Topic,
    /// The uORB instance (multi_id).
    pub instance: u8,
    /// The device_ids of its messages, in the order first seen (at most 8 listed).
    pub device_ids: Vec<u32>,
    /// Its data messages.
    pub messages: u64,
    /// The samples they hold (unrolled, for a FIFO topic; messages that cannot be decoded
    /// not counted).
    pub samples: u64,
    /// The first and last sample time in µs.
    pub span_us: Option<(f64, f64)>,
    /// The topic whose `temperature` gives this one's: itself for a sensor topic with a finite
    /// temperature, a sensor topic of the same device_id (the first one's) for a FIFO topic;
    /// `None` when there is none.
    pub temperature: Option<Topic>,
    /// Why its messages cannot be read (a format without a needed field), if so.
    pub unreadable: Option<String>,
}

/// What a ULog file holds, without its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Survey {
    /// The header's format version.
    pub version: u8,
    /// The header's start time in µs.
    pub start_us: u64,
    /// Whether the DATA_APPENDED flag is set.
    pub appended_data: bool,
    /// Messages read (the header excluded).
    pub messages: u64,
    /// The IMU topic instances subscribed, by topic then instance.
    pub topics: Vec<TopicSurvey>,
    /// The parameters, by name.
    pub parameters: Vec<Parameter>,
    /// The info messages ('I', and 'M' with its continuations joined) as text, in the order
    /// first seen (at most 256; a text cut at 256 characters, a value of another type than a
    /// string or a number shown as its length).
    pub info: Vec<(String, String)>,
    /// Dropout messages ('O': the logger lost data) and their total duration in ms.
    pub dropouts: (u64, u64),
    /// Messages dropped because appended data begins inside them.
    pub cut_before_appended: u64,
    /// The byte offset of the last message when it is cut short by the end of the file.
    pub truncated: Option<u64>,
}

impl Survey {
    /// The parameter `name`.
    pub fn parameter(&self, name: &str) -> Option<&Parameter> {
        crate::frame::by_name(&self.parameters, name, |p| &p.name)
    }

    /// The instances of `topic` that hold messages.
    pub fn instances(&self, topic: Topic) -> Vec<&TopicSurvey> {
        self.topics
            .iter()
            .filter(|t| t.topic == topic && t.messages > 0)
            .collect()
    }

    /// The sensor topic whose `temperature` gives the samples of `topic` from `device_id`:
    /// `topic` itself for a sensor topic, for a FIFO topic its sensor topic (the other one when
    /// it has none), when a message of that device has a finite temperature.
    pub fn temperature_source(&self, topic: Topic, device_id: u32) -> Option<Topic> {
        let has = |t: Topic| {
            self.topics.iter().any(|s| {
                s.topic == t && s.temperature == Some(t) && s.device_ids.contains(&device_id)
            })
        };
        if !topic.is_fifo() {
            return has(topic).then_some(topic);
        }
        topic.temperature_sources().into_iter().find(|&t| has(t))
    }
}

/// What a read delivered and skipped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Samples delivered.
    pub delivered: u64,
    /// Messages of the selection that could not be decoded (a FIFO message claiming more
    /// samples than its arrays hold).
    pub undecodable: u64,
    /// Samples with a NaN or infinite value or time, not delivered.
    pub non_finite: u64,
    /// Samples delivered without a temperature.
    pub without_temperature: u64,
    /// FIFO samples outside the span of the temperatures (or too far from the next one),
    /// given the nearest temperature.
    pub held_temperature: u64,
    /// The topic the temperatures came from (for FIFO samples, the sensor topic of the same
    /// device_id); `None` when the samples have none.
    pub temperature: Option<Topic>,
    /// The byte offset of the last message when it is cut short by the end of the file.
    pub truncated: Option<u64>,
    /// Where one FIFO message in ten or more begins before the one before ends (the sensor
    /// faster than the `dt` field says), why its samples' times cannot be placed; or where
    /// the two halves of its messages give two rates ([`Report::fifo_rate`]), that: a caller
    /// refuses the file with it.
    pub fifo_overlap: Option<String>,
    /// A FIFO topic's rate, Hz, where every message gives the same `dt` and the messages
    /// hold two samples or more on average: the reciprocal of the slope of the messages'
    /// `timestamp_sample` on their samples counted, fitted by least squares over each run of
    /// messages that follow one another (each message counts its samples, and each read's
    /// stamp jitters alone: 8 kHz, 10 samples a message jittered by up to 40 us, one message
    /// in 97 lost, reads within 1e-6). Of the device with the most messages.
    pub fifo_rate: Option<f64>,
    /// Where the FIFO messages' stamps jitter so that a message lost is not told from a
    /// late stamp, the warning that says so.
    pub fifo_caveat: Option<String>,
}

/// What the log holds of IMU data, its parameters and info, read in one pass without
/// delivering samples. An error when the file is not a ULog file, sets an incompatible flag,
/// or is corrupt before its end (a truncated last message is reported in
/// [`Survey::truncated`]).
pub fn survey(path: &Path) -> Result<Survey, DataError> {
    let mut tally: Vec<TopicSurvey> = Vec::new();
    let mut visit = |sub: &Sub, imu: &Imu, payload: Option<&[u8]>| {
        let at = match tally
            .iter()
            .position(|t| t.topic == imu.topic && t.instance == sub.multi_id)
        {
            Some(at) => at,
            None => {
                tally.push(TopicSurvey {
                    topic: imu.topic,
                    instance: sub.multi_id,
                    device_ids: Vec::new(),
                    messages: 0,
                    samples: 0,
                    span_us: None,
                    temperature: None,
                    unreadable: None,
                });
                tally.len() - 1
            }
        };
        let Some(entry) = tally.get_mut(at) else {
            return;
        };
        let Some(payload) = payload else {
            // The subscription: a format that cannot be read is noted before any message.
            if let Err(why) = &imu.layout {
                entry.unreadable = Some(why.clone());
            }
            return;
        };
        entry.messages += 1;
        let Ok(layout) = &imu.layout else {
            return;
        };
        let mut span = |t: f64| {
            if t.is_finite() {
                entry.span_us = Some(entry.span_us.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
            }
        };
        let device = match layout {
            Layout::Sensor(s) => {
                let Some(m) = s.decode(payload) else {
                    return;
                };
                span(m.time_us);
                if m.temperature.is_some_and(f64::is_finite) {
                    entry.temperature = Some(imu.topic);
                }
                entry.samples += 1;
                m.device_id
            }
            Layout::Fifo(f) => {
                let Some(m) = f.decode(payload) else {
                    return;
                };
                if m.n > 0 {
                    span(m.time(0));
                    span(m.time(m.n - 1));
                }
                entry.samples += m.n as u64;
                m.device_id
            }
        };
        if !entry.device_ids.contains(&device) && entry.device_ids.len() < MAX_DEVICE_IDS {
            entry.device_ids.push(device);
        }
    };
    let log = scan(path, &mut visit)?;
    tally.sort_by_key(|t| (t.topic, t.instance));
    let mut survey = Survey {
        version: log.version,
        start_us: log.start_us,
        appended_data: log.appended,
        messages: log.messages,
        topics: tally,
        parameters: log.parameters,
        info: log.info,
        dropouts: log.dropouts,
        cut_before_appended: log.cut,
        truncated: log.truncated,
    };
    let sources: Vec<Option<Topic>> = survey
        .topics
        .iter()
        .map(|t| match (t.topic.is_fifo(), t.device_ids.first()) {
            (true, Some(&d)) => survey.temperature_source(t.topic, d),
            _ => t.temperature,
        })
        .collect();
    for (t, source) in survey.topics.iter_mut().zip(sources) {
        t.temperature = source;
    }
    Ok(survey)
}

/// Calls `each` with every finite sample that `select` asks for, in file order (FIFO samples
/// held back until the temperature after them is read, at most 2^18 of them), and returns what
/// was delivered and skipped. The file is surveyed first ([`survey`]), so that a selection
/// the log cannot satisfy is an error before any sample: a topic without messages, an instance
/// or device_id it does not have, [`Which::Only`] on a topic with several instances, a topic
/// whose format lacks a needed field; also an error when no sample is finite.
pub fn read(
    path: &Path,
    select: &Select,
    each: &mut dyn FnMut(Sample),
) -> Result<Report, DataError> {
    let survey = survey(path)?;
    read_surveyed(path, &survey, select, each)
}

/// [`read`] with the survey of the same file already made.
pub fn read_surveyed(
    path: &Path,
    survey: &Survey,
    select: &Select,
    each: &mut dyn FnMut(Sample),
) -> Result<Report, DataError> {
    let chosen = choose(survey, select).map_err(|e| data_error(path, e))?;
    let topic = select.topic;
    // The device_ids read, and each one's temperature source.
    let mut devices: Vec<(u32, Option<Topic>)> = Vec::new();
    for t in &chosen {
        for &d in &t.device_ids {
            if matches!(select.which, Which::DeviceId(w) if w != d) {
                continue;
            }
            if !devices.iter().any(|&(e, _)| e == d) {
                devices.push((d, survey.temperature_source(topic, d)));
            }
        }
    }
    let instances: Vec<u8> = chosen.iter().map(|t| t.instance).collect();
    let mut interps: Vec<(u32, Topic, Interp<Sample>)> = devices
        .iter()
        .filter_map(|&(d, s)| Some((d, s?, Interp::new())))
        .filter(|_| topic.is_fifo())
        .collect();
    let (mut delivered, mut without_temperature) = (0u64, 0u64);
    let (mut undecodable, mut non_finite) = (0u64, 0u64);
    // Each FIFO device's last sample time; the messages read, those whose first sample comes
    // before the last one's last, and the first such (its first, the last one's last, dt).
    let mut ends: Vec<(u32, f64)> = Vec::new();
    let (mut fifo_messages, mut overlaps) = (0u64, 0u64);
    let mut overlap: Option<(f64, f64, f64, usize)> = None;
    let mut first_last: Option<(f64, f64, u64)> = None;
    // Each FIFO device's messages: their stamps (µs) and samples; the least and the most dt.
    let mut stamped: Vec<(u32, Vec<(f64, usize)>)> = Vec::new();
    let mut dts: Option<(f64, f64)> = None;
    let mut deliver = |s: Sample, temperature: Option<f64>| {
        delivered += 1;
        if temperature.is_none() {
            without_temperature += 1;
        }
        each(Sample { temperature, ..s });
    };
    let mut visit = |sub: &Sub, imu: &Imu, payload: Option<&[u8]>| {
        let (Ok(layout), Some(payload)) = (&imu.layout, payload) else {
            return;
        };
        if imu.topic != topic {
            // A temperature source of a FIFO topic.
            let Layout::Sensor(s) = layout else {
                return;
            };
            if interps.is_empty() {
                return;
            }
            let Some(m) = s.decode(payload) else {
                return;
            };
            if let Some(t) = m.temperature.filter(|t| t.is_finite())
                && let Some((_, _, interp)) = interps
                    .iter_mut()
                    .find(|(d, src, _)| *d == m.device_id && *src == imu.topic)
            {
                interp.point(m.time_us, t, &mut deliver);
            }
            return;
        }
        if !instances.contains(&sub.multi_id) {
            return;
        }
        let wanted = |d: u32| devices.iter().any(|&(e, _)| e == d);
        match layout {
            Layout::Sensor(s) => {
                let Some(m) = s.decode(payload) else {
                    undecodable += 1;
                    return;
                };
                if !wanted(m.device_id) {
                    return;
                }
                if !m.xyz.iter().all(|v| v.is_finite()) {
                    non_finite += 1;
                    return;
                }
                let sample = Sample {
                    time_us: m.time_us,
                    xyz: m.xyz,
                    temperature: None,
                    device_id: m.device_id,
                    instance: sub.multi_id,
                };
                deliver(sample, m.temperature.filter(|t| t.is_finite()));
            }
            Layout::Fifo(f) => {
                let Some(m) = f.decode(payload) else {
                    undecodable += 1;
                    return;
                };
                if !wanted(m.device_id) {
                    return;
                }
                // The last message's last sample time, where this one's samples came after it.
                let mut after = None;
                if m.n > 0 {
                    fifo_messages += 1;
                    let (first, last) = (m.time(0), m.time(m.n - 1));
                    match ends.iter_mut().find(|(d, _)| *d == m.device_id) {
                        Some((_, end)) => {
                            if first <= *end {
                                overlaps += 1;
                                overlap.get_or_insert((first, *end, m.dt, m.n));
                            }
                            after = Some(*end);
                            *end = last;
                        }
                        None => ends.push((m.device_id, last)),
                    }
                    let span = first_last.get_or_insert((m.time_us, m.time_us, 0));
                    *span = (span.0, m.time_us, span.2 + m.n as u64);
                }
                let time = m.placed(after);
                if m.n > 0 {
                    let at = match stamped.iter().position(|(d, _)| *d == m.device_id) {
                        Some(at) => at,
                        None => {
                            stamped.push((m.device_id, Vec::new()));
                            stamped.len() - 1
                        }
                    };
                    stamped[at].1.push((m.time_us, m.n));
                }
                if m.n > 0 {
                    let (least, most) = dts.get_or_insert((m.dt, m.dt));
                    (*least, *most) = (least.min(m.dt), most.max(m.dt));
                }
                let mut interp = interps
                    .iter_mut()
                    .find(|(d, _, _)| *d == m.device_id)
                    .map(|(_, _, i)| i);
                for i in 0..m.n {
                    let sample = Sample {
                        time_us: time(i),
                        xyz: m.value(i),
                        temperature: None,
                        device_id: m.device_id,
                        instance: sub.multi_id,
                    };
                    if !sample.time_us.is_finite() || !sample.xyz.iter().all(|v| v.is_finite()) {
                        non_finite += 1;
                        continue;
                    }
                    match interp.as_deref_mut() {
                        Some(interp) => interp.sample(sample.time_us, sample, &mut deliver),
                        None => deliver(sample, None),
                    }
                }
            }
        }
    };
    let log = scan(path, &mut visit)?;
    // The FIFO's rate, its warning and whether its parts' rates are apart: of the device with
    // the most messages, a sample and a half a message or more (of one sample a message, each
    // sample's stamp is its own, and the clock's reading weighs each alone; of two, read by a
    // timer a sensor a little slower than its dt leaves one now and then, and its samples
    // placed dt apart read dt's rate: 1990 Hz read every 1 ms, 2000.00 Hz).
    let fitted = stamped
        .iter()
        .max_by_key(|(_, m)| m.len())
        .filter(|_| {
            dts.is_some_and(|(least, most)| least == most)
                && first_last.is_some_and(|(_, _, n)| 2 * n >= 3 * fifo_messages)
        })
        .and_then(|(_, m)| fifo_rate(m));
    // The rate the messages give: their samples over their spacing (and those two).
    let messages_rate = first_last
        .filter(|&(a, b, _)| b > a && fifo_messages > 1)
        .map(|(a, b, samples)| {
            let (per, spacing) = (
                samples as f64 / fifo_messages as f64,
                (b - a) / (fifo_messages - 1) as f64,
            );
            (per * 1e6 / spacing, per, spacing)
        });
    // A FIFO whose messages run one into the next, one in ten or more, and give a rate past
    // dt's by half a sample a message: the sensor faster than dt says (10 kHz at a dt of 125
    // us), each message's samples spread back too far (where a read's stamp jitters alone,
    // one now and then runs into the one before with no rate past dt's).
    let fifo_overlap = overlap
        .filter(|&(_, _, dt, _)| {
            10 * overlaps >= fifo_messages
                && messages_rate.is_none_or(|(rate, per, _)| rate * dt * 1e-6 > 1.0 + 0.5 / per)
        })
        .map(|(first, end, dt, n)| {
            let given = messages_rate
                .map(|(rate, per, spacing)| {
                    format!(
                        "; the messages give about {} Hz ({:.1} samples a message over {} us)",
                        crate::timing::short(rate),
                        per,
                        crate::timing::short(spacing)
                    )
                })
                .unwrap_or_default();
            data_error(
            path,
            format!(
                "{overlaps} of the {fifo_messages} {topic} messages begin before the one before \
                 ends (a message of {n} samples, dt {} us apart, begins at {} us, the one \
                 before ended at {} us): the sensor runs faster than its dt field says, {} \
                 Hz{given}, and the samples' times cannot be placed from the messages",
                crate::timing::short(dt),
                crate::timing::short(first),
                crate::timing::short(end),
                crate::timing::short(1e6 / dt)
            ),
        )
        .to_string()
        });
    let mut held = 0u64;
    for (_, _, interp) in interps {
        held += interp.finish(&mut deliver);
    }
    if delivered == 0 {
        return Err(data_error(
            path,
            format!(
                "no finite samples of {topic} {} ({undecodable} messages undecodable (a \
                 samples field over its arrays, a scale or dt no IMU's), {non_finite} samples \
                 with a NaN or infinite value)",
                which_text(select.which)
            ),
        ));
    }
    Ok(Report {
        delivered,
        undecodable,
        non_finite,
        without_temperature,
        held_temperature: held,
        temperature: devices.first().and_then(|&(_, s)| s),
        truncated: log.truncated,
        fifo_overlap: fifo_overlap.or_else(|| {
            let mixed = fitted.as_ref().and_then(|f| f.2.clone())?;
            Some(data_error(path, mixed).to_string())
        }),
        fifo_rate: fitted.as_ref().map(|f| f.0),
        fifo_caveat: fitted.and_then(|f| f.1),
    })
}

/// A FIFO topic's rate, Hz, from its `messages` (each one's stamp, µs, and samples), and
/// where a message lost could hide in the stamps' jitter, the warning that says so. The
/// period is the slope of the stamps on the samples counted up to each, fitted by least
/// squares over each run of messages that follow one another, on one slope (each run its
/// own offset): every stamp weighs, each read's jitter its own. A run is parted where the
/// time from one stamp to the next passes its samples' at the median period by more than
/// jitter can: the time from one stamp to the next, less its samples', is as often that
/// much short as long however the stamps jitter (it is the difference of two of them), and
/// only a lost message makes it long alone; so by more than the most it comes short, and a
/// fifth, and by half the fewest samples a message holds (or it goes back). Parted by less,
/// runs are chosen by their stamps' jitter: a run that starts on a late stamp and may not
/// meet another leans (8000 Hz read every 1 ms, a fifth of the stamps 550 us late: 8060
/// Hz). Where that jitter passes half the fewest samples' time, a message lost is not told
/// from a late stamp, and the warning says so. A run's first and last messages are left
/// out of the fit too. Where a tenth of the messages (a half, under 200) gives a rate apart
/// from the whole's by more than half a percent and four standard errors, the refusal that
/// says so (a sensor whose rate steps, its dt field unchanged: 1000.37 and 1050.39 Hz read
/// 1025.69 Hz; 5 % faster from 40 to 60 % of the log, 1015.23 Hz, where the halves agree).
fn fifo_rate(messages: &[(f64, usize)]) -> Option<(f64, Option<String>, Option<String>)> {
    if messages.len() < 4 {
        return None;
    }
    let mut steps: Vec<f64> = messages
        .windows(2)
        .map(|w| (w[1].0 - w[0].0) / w[1].1 as f64)
        .filter(|s| *s > 0.0 && s.is_finite())
        .collect();
    if steps.is_empty() {
        return None;
    }
    let mid = (steps.len() - 1) / 2;
    let period = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    // Reads on a timer: nine spacings in ten within a quarter of their median, however many
    // samples each message holds (a sensor a little slower than two samples a read leaves
    // one now and then, a read short of a sample, not a sample lost: parted there, runs read
    // the timer's rate, 1990 Hz read every 1 ms 2000 Hz). There a message is lost where the
    // time to it passes the spacing; else where it passes its samples' time.
    let mut spacings: Vec<f64> = messages.windows(2).map(|w| w[1].0 - w[0].0).collect();
    let mid = (spacings.len() - 1) / 2;
    let spacing = *spacings.select_nth_unstable_by(mid, f64::total_cmp).1;
    let even = spacings
        .iter()
        .filter(|&&d| (d - spacing).abs() <= 0.25 * spacing)
        .count();
    let timer = spacing > 0.0 && 10 * even >= 9 * spacings.len();
    let excess = move |w: &[(f64, usize)]| {
        w[1].0
            - w[0].0
            - if timer {
                spacing
            } else {
                w[1].1 as f64 * period
            }
    };
    // The most the time to a stamp comes short of it (a stamp going back too), and the
    // least time a message lost takes.
    let short = messages
        .windows(2)
        .map(|w| -excess(w))
        .fold(0.0f64, f64::max);
    let (fewest, most) = messages
        .iter()
        .fold((usize::MAX, 0), |(a, b), m| (a.min(m.1), b.max(m.1)));
    let fewest = fewest as f64;
    let least = if timer { spacing } else { fewest * period };
    let parted = (0.5 * least).max(1.2 * short);
    let fitted = |messages: &[(f64, usize)]| {
        let (mut fit, mut run) = (Line::default(), Line::default());
        let mut last: Option<(f64, usize)> = None;
        for &m in messages {
            if let Some(b) = last
                && (m.0 <= b.0 || excess(&[b, m]) > parted)
            {
                fit.pool(std::mem::take(&mut run));
            }
            run.point(m.1 as f64, m.0);
            last = Some(m);
        }
        fit.pool(run);
        fit
    };
    let whole = fitted(messages);
    let rate = whole.rate()?;
    // The most time a message lost may take unseen: a message's samples (a read's spacing)
    // within the time a run is parted at and the most a stamp comes short.
    let unseen = if timer {
        if spacing <= parted + short {
            spacing
        } else {
            0.0
        }
    } else {
        messages
            .iter()
            .map(|m| m.1 as f64 * period)
            .filter(|&t| t <= parted + short)
            .fold(0.0, f64::max)
    };
    // Where the messages hold more samples or fewer (a timer's reads of a sensor off its
    // rate), a read's stamp may lie up to a sample's time past its last sample; where each
    // holds as many, the reads keep one phase with the samples.
    let phase = if fewest < most as f64 { period } else { 0.0 };
    let mixed = apart(messages, &fitted, &excess, (rate, phase, parted, unseen));
    let caveat = (1.2 * short > 0.5 * least).then(|| {
        format!(
            "the FIFO messages' stamps come up to {} us short of {} from one to the next, as \
             much as half {}: a message lost is not told from a late stamp, and the rate read, \
             {} Hz, counts every message's samples over their time (the sensor's where none \
             was lost); --rate sets it",
            crate::timing::short(short),
            if timer {
                "the reads' spacing"
            } else {
                "their samples' time"
            },
            if timer {
                format!("that spacing ({} us)", crate::timing::short(spacing))
            } else {
                format!(
                    "the fewest samples a message holds ({}, {} us)",
                    crate::timing::short(fewest),
                    crate::timing::short(fewest * period)
                )
            },
            crate::timing::short(rate)
        )
    });
    // (A third of the rate's tolerance, 1e-4: few messages, heavily jittered.)
    let error = whole.relative_error();
    let loose = (3.0 * error > 1e-4).then(|| {
        format!(
            "the FIFO messages' stamps scatter about their line by {} us RMS, so over {} \
             messages the rate read, {} Hz, has a standard error of {:.1e} of it; --rate \
             sets it",
            crate::timing::short(whole.scatter()),
            messages.len(),
            crate::timing::short(rate),
            error
        )
    });
    let caveat = match (caveat, loose) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    };
    Some((rate, caveat, mixed))
}

/// Where stretches of the FIFO `messages` give rates apart (`fitted` as [`fifo_rate`] fits
/// them; the whole's rate `rate`, Hz; a message lost unseen takes up to `unseen` µs):
/// halves, tenths, fortieths and so on to 640 parts, down to 20 messages a part, each its
/// samples over its runs' time (from each run's first fitted stamp to its last), any two of
/// one cut more than half a percent apart, by more than five of their standard errors, the
/// messages lost unseen in each (as many as the stamps suggest, and three standard errors:
/// `unseen` µs each, runs parted past `parted` µs, the time to a message past what it
/// should take its `excess`) and `phase` µs a run (where the messages hold more samples or
/// fewer, a sample's time: a read's stamp is its own time, not its last sample's, and a timer
/// reading a sensor 0.03 % fast takes a sample more now and then, which moves a part of 20
/// messages of 4 by 1.25 %): the refusal that names them. A part's error is from the parts'
/// median scatter about their lines, not its own: a stretch at another rate bends its part's line and would widen its
/// own. Parts are compared with one another, not with the whole, which a step between
/// halves splits (0.8 % read 3212.8 Hz, between 3200 and 3225.6); a part's span counts the
/// time a short stretch takes in full, where its line's slope leans on it by where it lies
/// (5 % faster for 30 messages of 2,000 read 3203.4 Hz for 3200; 30 % slower for 50 of
/// 10,000, 3189.7).
fn apart(
    messages: &[(f64, usize)],
    fitted: &impl Fn(&[(f64, usize)]) -> Line,
    excess: &impl Fn(&[(f64, usize)]) -> f64,
    (rate, phase, parted, unseen): (f64, f64, f64, f64),
) -> Option<String> {
    // The time the messages a part may have lost unseen take: where the time from a stamp
    // to the next passes its samples' by half such a message more often than it comes as
    // short (jitter alone makes the two alike), the difference, and three standard errors
    // of it, and one.
    let lost = |part: &[(f64, usize)]| {
        if unseen <= 0.0 {
            return 0.0;
        }
        let (mut long, mut short) = (0.0, 0.0);
        for w in part.windows(2) {
            let d = excess(w);
            if w[1].0 > w[0].0 && d <= parted {
                long += f64::from(u8::from(d > 0.5 * unseen));
                short += f64::from(u8::from(d < -0.5 * unseen));
            }
        }
        unseen * ((long - short).max(0.0) + 3.0 * (long + short).sqrt() + 1.0)
    };
    let mut parts = 2;
    // (Up to 640 parts: every pair of them compared.)
    while messages.len() >= 20 * parts && parts <= 640 {
        let size = messages.len().div_ceil(parts);
        let chunks: Vec<&[(f64, usize)]> = messages.chunks(size).collect();
        let lines: Vec<Line> = chunks.iter().map(|c| fitted(c)).collect();
        let mut scatter: Vec<f64> = lines.iter().map(Line::variance).collect();
        let mid = (scatter.len() - 1) / 2;
        let sigma = scatter.select_nth_unstable_by(mid, f64::total_cmp).1.sqrt();
        // Each part's rate and what it may be off by, both relative.
        let each: Vec<Option<(f64, f64)>> = lines
            .iter()
            .zip(&chunks)
            .map(|(l, c)| {
                let (samples, time) = l.span;
                let r = 1e6 * samples / time;
                let off = (5.0 * sigma * (2.0 * l.runs).sqrt() + lost(c) + l.runs * phase) / time;
                (samples > 0.0 && time > 0.0 && r.is_finite()).then_some((r, off))
            })
            .collect();
        let found = (0..each.len())
            .flat_map(|i| (i + 1..each.len()).map(move |j| (i, j)))
            .filter_map(|(i, j)| {
                let ((a, ea), (b, eb)) = (each[i]?, each[j]?);
                let off = (a / b - 1.0).abs();
                (off > 0.005f64.max(ea + eb)).then_some((off, i, a, j, b))
            })
            .max_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((_, i, a, j, b)) = found {
            return Some(format!(
                "the FIFO messages' part {} of {parts} gives {} Hz and part {} gives {} Hz (the \
                 whole {} Hz), their samples over their stamps' time: mixed rates (one record \
                 must have one rate; give --rate)",
                i + 1,
                crate::timing::short(a),
                j + 1,
                crate::timing::short(b),
                crate::timing::short(rate)
            ));
        }
        parts = if parts == 2 { 10 } else { 4 * parts };
    }
    None
}

/// A straight line through the stamps of a run of FIFO messages that follow one another
/// (each at the count of samples up to its last), fitted by least squares as the points come
/// (Welford's updates), its first and last points left out; and, pooled, the runs' fits on
/// one slope, each run its own offset.
#[derive(Clone, Copy, Debug, Default)]
struct Line {
    /// The points fitted; the samples counted so far (the run's), and the run's first stamp.
    n: f64,
    count: f64,
    origin: Option<f64>,
    /// The last message's point, fitted when the next follows it, and whether it is the
    /// run's first.
    pending: Option<(f64, f64)>,
    first: bool,
    /// The means of the counts and the stamps (µs from the run's first), and the sums of
    /// squares and products about them.
    mean: (f64, f64),
    sxx: f64,
    sxy: f64,
    syy: f64,
    /// The run's first and last points fitted; pooled, the runs' samples and time (µs)
    /// between those, and how many runs gave them.
    from: Option<(f64, f64)>,
    to: (f64, f64),
    span: (f64, f64),
    runs: f64,
}

impl Line {
    /// The next message of the run: its `samples`, its stamp (µs).
    fn point(&mut self, samples: f64, stamp: f64) {
        let Some(origin) = self.origin else {
            (self.origin, self.pending, self.first) = (Some(stamp), Some((0.0, 0.0)), true);
            return;
        };
        self.count += samples;
        let before = self.pending.replace((self.count, stamp - origin));
        if let Some((x, y)) = before.filter(|_| !self.first) {
            self.n += 1.0;
            let (dx, dy) = (x - self.mean.0, y - self.mean.1);
            self.mean.0 += dx / self.n;
            self.mean.1 += dy / self.n;
            self.sxx += dx * (x - self.mean.0);
            self.sxy += dx * (y - self.mean.1);
            self.syy += dy * (y - self.mean.1);
            self.from.get_or_insert((x, y));
            self.to = (x, y);
        }
        self.first = false;
    }

    /// Pools the `run`'s fit into these (the sums about each run's own means; its last
    /// message left out).
    fn pool(&mut self, run: Line) {
        self.sxx += run.sxx;
        self.sxy += run.sxy;
        self.syy += run.syy;
        self.n += (run.n - 1.0).max(0.0);
        if let Some(from) = run.from.filter(|_| run.n >= 2.0) {
            self.span.0 += run.to.0 - from.0;
            self.span.1 += run.to.1 - from.1;
            self.runs += 1.0;
        }
    }

    /// The rate of the pooled slope, Hz, where it is one.
    fn rate(&self) -> Option<f64> {
        let rate = 1e6 * self.sxx / self.sxy;
        (self.sxx > 0.0 && self.sxy > 0.0 && rate.is_finite()).then_some(rate)
    }

    /// The standard error of the pooled slope relative to it (the residuals' spread about
    /// each run's line, over the points less the runs' offsets and the slope).
    fn relative_error(&self) -> f64 {
        (self.variance() / self.sxx).sqrt() * self.sxx / self.sxy
    }

    /// The residuals' variance about the runs' lines, µs² (over the points less the runs'
    /// offsets and the slope).
    fn variance(&self) -> f64 {
        let slope = self.sxy / self.sxx;
        (self.syy - slope * self.sxy).max(0.0) / (self.n - 1.0).max(1.0)
    }

    /// The residuals' RMS about the runs' lines, µs.
    fn scatter(&self) -> f64 {
        self.variance().sqrt()
    }
}

/// The selection `which` in words.
fn which_text(which: Which) -> String {
    match which {
        Which::Only => "(its one instance)".into(),
        Which::Instance(m) => format!("instance {m}"),
        Which::DeviceId(d) => format!("device_id {d}"),
    }
}

/// The topic instances `select` reads, or why none.
fn choose<'a>(survey: &'a Survey, select: &Select) -> Result<Vec<&'a TopicSurvey>, String> {
    let topic = select.topic;
    let present = survey.instances(topic);
    let listed = |list: &[&TopicSurvey]| {
        list.iter()
            .map(|t| {
                let ids: Vec<String> = t.device_ids.iter().map(u32::to_string).collect();
                format!(
                    "instance {} (device_id {}, {} messages)",
                    t.instance,
                    if ids.is_empty() {
                        "none".into()
                    } else {
                        ids.join(", ")
                    },
                    t.messages
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    if present.is_empty() {
        let others: Vec<String> = Topic::ALL
            .into_iter()
            .filter(|&t| !survey.instances(t).is_empty())
            .map(|t| format!("{t} ({} instances)", survey.instances(t).len()))
            .collect();
        return Err(format!(
            "no {topic} messages in the log (IMU topics: {})",
            if others.is_empty() {
                "none".into()
            } else {
                others.join(", ")
            }
        ));
    }
    let chosen: Vec<&TopicSurvey> = match select.which {
        Which::Only if present.len() > 1 => {
            return Err(format!(
                "{topic} has {} instances: {}; choose one with --instance or --device-id",
                present.len(),
                listed(&present)
            ));
        }
        Which::Only => present.clone(),
        Which::Instance(m) => present
            .iter()
            .copied()
            .filter(|t| t.instance == m)
            .collect(),
        Which::DeviceId(d) => present
            .iter()
            .copied()
            .filter(|t| t.device_ids.contains(&d))
            .collect(),
    };
    if chosen.is_empty() {
        let what = match select.which {
            Which::Instance(m) => format!("instance {m}"),
            Which::DeviceId(d) => format!("device_id {d}"),
            Which::Only => "instance".into(),
        };
        return Err(format!(
            "{topic} has no {what} with messages ({})",
            listed(&present)
        ));
    }
    if let Some(why) = chosen.iter().find_map(|t| t.unreadable.as_ref()) {
        return Err(why.clone());
    }
    Ok(chosen)
}

/// The base types of ULog fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Base {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Char,
}

impl Base {
    /// The type named `name` in a format (`uint8_t`, `float`, ...).
    fn of(name: &str) -> Option<Base> {
        Some(match name {
            "int8_t" => Base::I8,
            "uint8_t" => Base::U8,
            "int16_t" => Base::I16,
            "uint16_t" => Base::U16,
            "int32_t" => Base::I32,
            "uint32_t" => Base::U32,
            "int64_t" => Base::I64,
            "uint64_t" => Base::U64,
            "float" => Base::F32,
            "double" => Base::F64,
            "bool" => Base::Bool,
            "char" => Base::Char,
            _ => return None,
        })
    }

    /// Its name in a format.
    fn name(self) -> &'static str {
        match self {
            Base::I8 => "int8_t",
            Base::U8 => "uint8_t",
            Base::I16 => "int16_t",
            Base::U16 => "uint16_t",
            Base::I32 => "int32_t",
            Base::U32 => "uint32_t",
            Base::I64 => "int64_t",
            Base::U64 => "uint64_t",
            Base::F32 => "float",
            Base::F64 => "double",
            Base::Bool => "bool",
            Base::Char => "char",
        }
    }

    /// Its size in bytes.
    fn size(self) -> usize {
        match self {
            Base::I8 | Base::U8 | Base::Bool | Base::Char => 1,
            Base::I16 | Base::U16 => 2,
            Base::I32 | Base::U32 | Base::F32 => 4,
            Base::I64 | Base::U64 | Base::F64 => 8,
        }
    }
}

/// A field's type: a base type or another format.
#[derive(Clone, Debug, PartialEq)]
enum FieldType {
    Base(Base),
    Nested(String),
}

/// One field of a format: its type, array length (`None`: not an array) and name.
#[derive(Clone, Debug, PartialEq)]
struct FieldDef {
    ty: FieldType,
    count: Option<u16>,
    name: String,
}

impl FieldDef {
    /// Its type as a format writes it (`uint8_t[3]`).
    fn type_text(&self) -> String {
        let base = match &self.ty {
            FieldType::Base(b) => b.name(),
            FieldType::Nested(n) => n.as_str(),
        };
        match self.count {
            Some(n) => format!("{base}[{n}]"),
            None => base.to_string(),
        }
    }
}

/// The formats ('F') of a log, and the sizes of those resolved so far.
#[derive(Default)]
struct Formats {
    defs: HashMap<String, Vec<FieldDef>>,
    sizes: HashMap<String, usize>,
    bytes: usize,
}

impl Formats {
    /// Adds the format of an 'F' message: `name:type field;type[N] field;...`.
    fn add(&mut self, payload: &[u8]) -> Result<(), String> {
        let text = std::str::from_utf8(payload)
            .map_err(|_| "a format ('F') that is not text".to_string())?;
        let (name, body) = text.split_once(':').ok_or_else(|| {
            format!(
                "a format ('F') without ':' after its name: '{}'",
                short(text)
            )
        })?;
        if name.is_empty() {
            return Err(format!("a format ('F') without a name: '{}'", short(text)));
        }
        let mut fields = Vec::new();
        for segment in body.split(';').filter(|s| !s.is_empty()) {
            let bad = || {
                format!(
                    "format '{}': field '{}' is not 'type name'",
                    short(name),
                    short(segment)
                )
            };
            let (ty, field) = segment.split_once(' ').ok_or_else(bad)?;
            if field.is_empty() || ty.is_empty() {
                return Err(bad());
            }
            let (base, count) = match ty.split_once('[') {
                None => (ty, None),
                Some((base, rest)) => {
                    let n = rest
                        .strip_suffix(']')
                        .and_then(|n| n.parse::<u16>().ok())
                        .filter(|_| !base.is_empty())
                        .ok_or_else(bad)?;
                    (base, Some(n))
                }
            };
            let ty = match Base::of(base) {
                Some(b) => FieldType::Base(b),
                None => FieldType::Nested(base.to_string()),
            };
            fields.push(FieldDef {
                ty,
                count,
                name: field.to_string(),
            });
        }
        if let Some(old) = self.defs.get(name) {
            if *old == fields {
                return Ok(());
            }
            return Err(format!(
                "format '{}' is defined twice, differently",
                short(name)
            ));
        }
        self.bytes = self.bytes.saturating_add(payload.len());
        if self.bytes > MAX_FORMAT_BYTES {
            return Err(format!(
                "more than {} MiB of formats",
                MAX_FORMAT_BYTES >> 20
            ));
        }
        self.defs.insert(name.to_string(), fields);
        Ok(())
    }

    /// The size in bytes of format `name`, nested formats included; `stack` holds the formats
    /// that contain it.
    fn size(&mut self, name: &str, stack: &mut Vec<String>) -> Result<usize, String> {
        if let Some(&s) = self.sizes.get(name) {
            return Ok(s);
        }
        if stack.iter().any(|s| s == name) {
            return Err(format!(
                "format '{}' contains itself ({} > {})",
                short(name),
                stack
                    .iter()
                    .map(|s| short(s))
                    .collect::<Vec<_>>()
                    .join(" > "),
                short(name)
            ));
        }
        if stack.len() >= MAX_NESTING {
            return Err(format!(
                "formats nested more than {MAX_NESTING} deep ({} > {})",
                stack
                    .iter()
                    .map(|s| short(s))
                    .collect::<Vec<_>>()
                    .join(" > "),
                short(name)
            ));
        }
        let Some(fields) = self.defs.get(name).cloned() else {
            return Err(match stack.last() {
                Some(outer) => format!(
                    "format '{}' has a field of type '{}', which no format defines",
                    short(outer),
                    short(name)
                ),
                None => format!("no format '{}'", short(name)),
            });
        };
        stack.push(name.to_string());
        let mut total = 0usize;
        for f in &fields {
            let one = match &f.ty {
                FieldType::Base(b) => b.size(),
                FieldType::Nested(n) => self.size(n, stack)?,
            };
            total = one
                .checked_mul(f.count.map_or(1, usize::from))
                .and_then(|s| total.checked_add(s))
                .filter(|&t| t <= MAX_DATA)
                .ok_or_else(|| {
                    format!(
                        "format '{}' is longer than a data message can be ({MAX_DATA} bytes)",
                        short(name)
                    )
                })?;
        }
        stack.pop();
        self.sizes.insert(name.to_string(), total);
        Ok(total)
    }

    /// The top-level fields of format `name` with their offsets, its size, and its size
    /// without trailing `_padding*` fields.
    fn place(&mut self, name: &str) -> Result<Placed, String> {
        let total = self.size(name, &mut Vec::new())?;
        let fields = self.defs.get(name).cloned().unwrap_or_default();
        let mut placed = Vec::with_capacity(fields.len());
        let mut at = 0usize;
        let mut min = 0usize;
        for f in fields {
            let one = match &f.ty {
                FieldType::Base(b) => b.size(),
                FieldType::Nested(n) => self.size(n, &mut vec![name.to_string()])?,
            };
            let size = one.saturating_mul(f.count.map_or(1, usize::from));
            let end = at.saturating_add(size);
            if !f.name.starts_with("_padding") {
                min = end;
            }
            placed.push((f, at));
            at = end;
        }
        Ok(Placed {
            fields: placed,
            max: total,
            min,
        })
    }
}

/// A format's top-level fields with their offsets, its size, and its size without trailing
/// `_padding*` fields.
struct Placed {
    fields: Vec<(FieldDef, usize)>,
    max: usize,
    min: usize,
}

/// `text` cut at 64 characters and escaped, for a message.
fn short(text: &str) -> String {
    let cut: String = text.chars().take(64).collect();
    if cut.len() < text.len() {
        format!("{}...", escaped(&cut))
    } else {
        escaped(&cut)
    }
}

/// A number field: its offset in a data payload and its type.
#[derive(Clone, Copy, Debug)]
struct Num {
    at: usize,
    base: Base,
}

impl Num {
    /// Its value in payload `p`.
    fn read(self, p: &[u8]) -> Option<f64> {
        let at = self.at;
        Some(match self.base {
            Base::I8 => f64::from(i8::from_le_bytes(bytes_at::<1>(p, at)?)),
            Base::U8 | Base::Bool | Base::Char => f64::from(*p.get(at)?),
            Base::I16 => f64::from(i16::from_le_bytes(bytes_at::<2>(p, at)?)),
            Base::U16 => f64::from(u16::from_le_bytes(bytes_at::<2>(p, at)?)),
            Base::I32 => f64::from(i32::from_le_bytes(bytes_at::<4>(p, at)?)),
            Base::U32 => f64::from(u32::from_le_bytes(bytes_at::<4>(p, at)?)),
            Base::I64 => i64::from_le_bytes(bytes_at::<8>(p, at)?) as f64,
            Base::U64 => u64::from_le_bytes(bytes_at::<8>(p, at)?) as f64,
            Base::F32 => f64::from(f32::from_le_bytes(bytes_at::<4>(p, at)?)),
            Base::F64 => f64::from_le_bytes(bytes_at::<8>(p, at)?),
        })
    }
}

/// The u32 at `at` of `p`.
fn u32_le(p: &[u8], at: usize) -> Option<u32> {
    bytes_at::<4>(p, at).map(u32::from_le_bytes)
}

/// The u64 at `at` of `p`.
fn u64_le(p: &[u8], at: usize) -> Option<u64> {
    bytes_at::<8>(p, at).map(u64::from_le_bytes)
}

/// Where a sensor topic's fields are.
#[derive(Clone, Debug)]
struct SensorLayout {
    time: usize,
    device_id: usize,
    xyz: [Num; 3],
    temperature: Option<Num>,
}

/// A sensor topic's message decoded.
struct SensorMessage {
    time_us: f64,
    device_id: u32,
    xyz: [f64; 3],
    temperature: Option<f64>,
}

impl SensorLayout {
    /// The message in payload `p`.
    fn decode(&self, p: &[u8]) -> Option<SensorMessage> {
        let [x, y, z] = self.xyz;
        Some(SensorMessage {
            time_us: u64_le(p, self.time)? as f64,
            device_id: u32_le(p, self.device_id)?,
            xyz: [x.read(p)?, y.read(p)?, z.read(p)?],
            temperature: match self.temperature {
                Some(t) => Some(t.read(p)?),
                None => None,
            },
        })
    }
}

/// Where a FIFO topic's fields are.
#[derive(Clone, Debug)]
struct FifoLayout {
    time: usize,
    device_id: usize,
    dt: Num,
    scale: Num,
    samples: Num,
    /// The length of the x, y, z arrays.
    len: usize,
    /// Where the int16 arrays x, y, z start.
    xyz: [usize; 3],
}

/// A FIFO topic's message decoded: its N samples are read from its payload.
struct FifoMessage<'a> {
    time_us: f64,
    device_id: u32,
    dt: f64,
    scale: f64,
    n: usize,
    xyz: [usize; 3],
    payload: &'a [u8],
}

impl FifoLayout {
    /// The message in `p`: `None` when it claims more samples than its arrays hold, or its
    /// scale or spacing is no IMU's.
    fn decode<'a>(&self, p: &'a [u8]) -> Option<FifoMessage<'a>> {
        let n = self.samples.read(p)?;
        if n > self.len as f64 {
            return None;
        }
        let m = FifoMessage {
            time_us: u64_le(p, self.time)? as f64,
            device_id: u32_le(p, self.device_id)?,
            dt: self.dt.read(p)?,
            scale: self.scale.read(p)?,
            n: n as usize,
            xyz: self.xyz,
            payload: p,
        };
        // (A scale outside (0, 1] per LSB, or a spacing that is no time, is no IMU's: 1 rad/s
        // or m/s^2 a count spans some 3000 g.)
        if !(m.scale > 0.0 && m.scale <= 1.0 && m.dt.is_finite() && m.dt >= 0.0) {
            return None;
        }
        // The arrays are inside the payload (its length was checked against the format).
        let last = self.xyz.iter().max().copied().unwrap_or(0);
        p.get(last..last.checked_add(2 * self.len)?)?;
        Some(m)
    }
}

impl FifoMessage<'_> {
    /// The time of sample `i` in µs: `timestamp_sample - (N-1-i)*dt`.
    fn time(&self, i: usize) -> f64 {
        self.time_us - (self.n.saturating_sub(1).saturating_sub(i)) as f64 * self.dt
    }

    /// The times of its samples, µs, where the last message's last sample came at `after`:
    /// spread evenly from there to `timestamp_sample` where that holds its samples at a
    /// period of one and a half `dt` or less (a FIFO's samples come at the sensor's rate
    /// between its reads, and the stamp of each read jitters alone); else (the first
    /// message, one after messages lost, one stamped before the last) stamped back at `dt`
    /// from `timestamp_sample`.
    fn placed(&self, after: Option<f64>) -> impl Fn(usize) -> f64 + '_ {
        let n = self.n as f64;
        let step = after
            .map(|end| (self.time_us - end) / n)
            .filter(|&step| step > 0.0 && step <= 1.5 * self.dt);
        move |i| match step {
            Some(step) => self.time_us - (n - 1.0 - i as f64) * step,
            None => self.time(i),
        }
    }

    /// The value of sample `i`: `x[i]*scale` for each axis.
    fn value(&self, i: usize) -> [f64; 3] {
        self.xyz.map(|at| {
            let raw = bytes_at::<2>(self.payload, at + 2 * i).map_or(0, i16::from_le_bytes);
            f64::from(raw) * self.scale
        })
    }
}

/// How to read an IMU topic's messages.
#[derive(Clone, Debug)]
enum Layout {
    Sensor(SensorLayout),
    Fifo(FifoLayout),
}

/// An IMU topic subscribed: which topic, and its layout or why it cannot be read.
#[derive(Clone, Debug)]
struct Imu {
    topic: Topic,
    layout: Result<Layout, String>,
}

/// A subscription ('A').
#[derive(Clone, Debug)]
struct Sub {
    name: String,
    multi_id: u8,
    /// The shortest and longest data payload its format allows (trailing padding omitted or
    /// not).
    min: usize,
    max: usize,
    /// Where its `uint64_t timestamp` is.
    timestamp: Option<usize>,
    imu: Option<Imu>,
}

/// The layout of IMU topic `topic` from its format's top-level fields.
fn layout(topic: Topic, fields: &[(FieldDef, usize)]) -> Result<Layout, String> {
    let name = topic.name();
    let find = |field: &str| fields.iter().find(|(f, _)| f.name == field);
    let scalar = |field: &str, allowed: &[Base]| -> Result<Option<Num>, String> {
        let Some((f, at)) = find(field) else {
            return Ok(None);
        };
        match f.ty {
            FieldType::Base(b) if f.count.is_none() && allowed.contains(&b) => {
                Ok(Some(Num { at: *at, base: b }))
            }
            _ => Err(format!(
                "the format of {name} has field '{field}' of type {}, not {}",
                f.type_text(),
                allowed
                    .iter()
                    .map(|b| b.name())
                    .collect::<Vec<_>>()
                    .join(" or ")
            )),
        }
    };
    let need = |field: &str, allowed: &[Base]| -> Result<Num, String> {
        scalar(field, allowed)?.ok_or_else(|| {
            format!(
                "the format of {name} has no field '{field}' ({})",
                allowed
                    .iter()
                    .map(|b| b.name())
                    .collect::<Vec<_>>()
                    .join(" or ")
            )
        })
    };
    let time = match scalar("timestamp_sample", &[Base::U64])? {
        Some(t) => t.at,
        None => need("timestamp", &[Base::U64])?.at,
    };
    let device_id = need("device_id", &[Base::U32])?.at;
    let floats = [Base::F32, Base::F64];
    if !topic.is_fifo() {
        return Ok(Layout::Sensor(SensorLayout {
            time,
            device_id,
            xyz: [
                need("x", &floats)?,
                need("y", &floats)?,
                need("z", &floats)?,
            ],
            temperature: scalar("temperature", &floats)?,
        }));
    }
    let array = |field: &str| -> Result<(usize, usize), String> {
        match find(field) {
            Some((f, at))
                if f.ty == FieldType::Base(Base::I16) && f.count.is_some_and(|n| n > 0) =>
            {
                Ok((*at, f.count.map_or(0, usize::from)))
            }
            Some((f, _)) => Err(format!(
                "the format of {name} has field '{field}' of type {}, not int16_t[N]",
                f.type_text()
            )),
            None => Err(format!(
                "the format of {name} has no field '{field}' (int16_t[N])"
            )),
        }
    };
    let (x, len) = array("x")?;
    let (y, ylen) = array("y")?;
    let (z, zlen) = array("z")?;
    if ylen != len || zlen != len {
        return Err(format!(
            "the format of {name} has arrays x, y, z of lengths {len}, {ylen}, {zlen}"
        ));
    }
    Ok(Layout::Fifo(FifoLayout {
        time,
        device_id,
        dt: need("dt", &floats)?,
        scale: need("scale", &floats)?,
        samples: need("samples", &[Base::U8, Base::U16])?,
        len,
        xyz: [x, y, z],
    }))
}

/// What a pass over the file found besides the IMU messages.
struct Log {
    version: u8,
    start_us: u64,
    appended: bool,
    messages: u64,
    parameters: Vec<Parameter>,
    info: Vec<(String, String)>,
    dropouts: (u64, u64),
    cut: u64,
    truncated: Option<u64>,
}

/// What one pass knows so far.
#[derive(Default)]
struct State {
    formats: Formats,
    subs: HashMap<u16, Sub>,
    parameters: Vec<Parameter>,
    by_name: HashMap<String, usize>,
    info: Vec<(String, String)>,
    dropouts: (u64, u64),
    /// Still in the definitions section (before the first 'A', 'L' or 'C').
    definitions: bool,
    /// The newest data timestamp so far (µs), the header's start time before any.
    last_us: u64,
}

/// What an IMU subscription's message says to a pass: `None` for the subscription itself,
/// the data payload (after its msg_id) for a data message.
type Visit<'a> = dyn FnMut(&Sub, &Imu, Option<&[u8]>) + 'a;

impl State {
    /// One message of type `ty` (the header's flag bits excluded).
    fn message(&mut self, ty: u8, p: &[u8], visit: &mut Visit) -> Result<(), String> {
        if matches!(ty, b'A' | b'L' | b'C') {
            self.definitions = false;
        }
        match ty {
            b'F' => self.formats.add(p),
            b'A' => self.subscribe(p, visit),
            b'R' => {
                if let Some(id) = bytes_at::<2>(p, 0).map(u16::from_le_bytes) {
                    self.subs.remove(&id);
                }
                Ok(())
            }
            b'D' => self.data(p, visit),
            b'P' => self.parameter(p),
            b'I' => {
                self.info(p, false);
                Ok(())
            }
            b'M' => {
                // `uint8 is_continued`, then as 'I'.
                if let Some((&continued, rest)) = p.split_first() {
                    self.info(rest, continued != 0);
                }
                Ok(())
            }
            b'O' => {
                if let Some(ms) = bytes_at::<2>(p, 0).map(u16::from_le_bytes) {
                    self.dropouts.0 += 1;
                    self.dropouts.1 += u64::from(ms);
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// A subscription: `uint8 multi_id; uint16 msg_id; char name[]`.
    fn subscribe(&mut self, p: &[u8], visit: &mut Visit) -> Result<(), String> {
        let (Some(&multi_id), Some(id)) = (p.first(), bytes_at::<2>(p, 1).map(u16::from_le_bytes))
        else {
            return Err(format!("a subscription ('A') of {} bytes", p.len()));
        };
        let name = String::from_utf8_lossy(p.get(3..).unwrap_or_default()).into_owned();
        if let Some(old) = self.subs.get(&id) {
            if old.name == name && old.multi_id == multi_id {
                return Ok(());
            }
            return Err(format!(
                "msg_id {id} is subscribed twice: to '{}' instance {} and to '{}' instance \
                 {multi_id}",
                short(&old.name),
                old.multi_id,
                short(&name)
            ));
        }
        let Placed { fields, max, min } = self
            .formats
            .place(&name)
            .map_err(|e| format!("subscription to '{}' (msg_id {id}): {e}", short(&name)))?;
        let timestamp = fields
            .iter()
            .find(|(f, _)| {
                f.name == "timestamp" && f.ty == FieldType::Base(Base::U64) && f.count.is_none()
            })
            .map(|&(_, at)| at);
        let imu = Topic::of(&name).map(|topic| Imu {
            topic,
            layout: layout(topic, &fields),
        });
        let sub = Sub {
            name,
            multi_id,
            min,
            max,
            timestamp,
            imu,
        };
        if let Some(imu) = &sub.imu {
            visit(&sub, imu, None);
        }
        self.subs.insert(id, sub);
        Ok(())
    }

    /// A data message: `uint16 msg_id` and the payload its format describes.
    fn data(&mut self, p: &[u8], visit: &mut Visit) -> Result<(), String> {
        let id = bytes_at::<2>(p, 0)
            .map(u16::from_le_bytes)
            .ok_or_else(|| format!("a data message ('D') of {} bytes", p.len()))?;
        let sub = self.subs.get(&id).ok_or_else(|| {
            format!("data for msg_id {id}, which no subscription ('A') before it defines")
        })?;
        let body = p.get(2..).unwrap_or_default();
        if body.len() < sub.min || body.len() > sub.max {
            let allowed = if sub.min == sub.max {
                format!("{}", sub.min)
            } else {
                format!("{} to {}", sub.min, sub.max)
            };
            return Err(format!(
                "data of '{}' (msg_id {id}) has {} bytes; its format has {allowed}",
                short(&sub.name),
                body.len()
            ));
        }
        if let Some(t) = sub.timestamp.and_then(|at| u64_le(body, at)) {
            self.last_us = self.last_us.max(t);
        }
        if let Some(imu) = &sub.imu {
            visit(sub, imu, Some(body));
        }
        Ok(())
    }

    /// A parameter: `uint8 key_len; char key[key_len]` = "<type> <name>", then its value.
    fn parameter(&mut self, p: &[u8]) -> Result<(), String> {
        let (key, value) = key_value(p).ok_or_else(|| {
            format!(
                "a parameter ('P') whose key is not '<type> <name>' ({} bytes)",
                p.len()
            )
        })?;
        let (ty, name) = key;
        let value = match (ty, bytes_at::<4>(value, 0), value.len()) {
            ("int32_t", Some(b), 4) => Value::Int(i32::from_le_bytes(b)),
            ("float", Some(b), 4) => Value::Float(f32::from_le_bytes(b)),
            ("int32_t" | "float", _, n) => {
                return Err(format!(
                    "parameter '{}' of type {ty} has {n} value bytes, not 4",
                    short(name)
                ));
            }
            _ => return Ok(()),
        };
        let at = match self.by_name.get(name) {
            Some(&at) => at,
            None => {
                if self.parameters.len() >= MAX_PARAMETERS {
                    return Err(format!("more than {MAX_PARAMETERS} parameters"));
                }
                self.parameters.push(Parameter {
                    name: name.to_string(),
                    initial: None,
                    value,
                    changes: 0,
                    first_changes: Vec::new(),
                });
                self.by_name
                    .insert(name.to_string(), self.parameters.len() - 1);
                self.parameters.len() - 1
            }
        };
        let Some(param) = self.parameters.get_mut(at) else {
            return Ok(());
        };
        if self.definitions {
            param.initial = Some(value);
        } else {
            param.changes += 1;
            if param.first_changes.len() < KEPT_CHANGES {
                param.first_changes.push((self.last_us, value));
            }
        }
        param.value = value;
        Ok(())
    }

    /// An info message ('I', or 'M' continuing the value of its key when `continued`), kept
    /// as text when there is room.
    fn info(&mut self, p: &[u8], continued: bool) {
        let Some(((ty, name), value)) = key_value(p) else {
            return;
        };
        let text = if ty.starts_with("char[") {
            let s = String::from_utf8_lossy(value);
            short_text(s.trim_end_matches('\0'))
        } else {
            let num = Base::of(ty).filter(|b| b.size() == value.len());
            match num.and_then(|base| Num { at: 0, base }.read(value)) {
                Some(v) if ty == "float" || ty == "double" => format!("{v}"),
                Some(_) if ty == "uint64_t" => u64_le(value, 0).unwrap_or(0).to_string(),
                Some(_) if ty == "int64_t" => bytes_at::<8>(value, 0)
                    .map_or(0, i64::from_le_bytes)
                    .to_string(),
                Some(v) => format!("{v}"),
                None => format!("<{} bytes>", value.len()),
            }
        };
        if let Some(entry) = self.info.iter_mut().find(|(k, _)| k == name) {
            if continued {
                let room = MAX_INFO_TEXT.saturating_sub(entry.1.chars().count());
                entry.1.extend(text.chars().take(room));
            } else {
                entry.1 = text;
            }
        } else if self.info.len() < MAX_INFO {
            self.info.push((short_text(name), text));
        }
    }
}

/// `text` cut at 256 characters, control characters escaped.
fn short_text(text: &str) -> String {
    escaped(&text.chars().take(MAX_INFO_TEXT).collect::<String>())
}

/// The key ("<type> <name>") and the value of an info or parameter message.
fn key_value(p: &[u8]) -> Option<((&str, &str), &[u8])> {
    let len = usize::from(*p.first()?);
    let key = std::str::from_utf8(p.get(1..1 + len)?).ok()?;
    let (ty, name) = key.split_once(' ')?;
    if ty.is_empty() || name.is_empty() {
        return None;
    }
    Some(((ty, name), p.get(1 + len..)?))
}

/// Why a file that does not start with the ULog magic is not read.
fn not_ulog(head: &[u8]) -> String {
    if head.starts_with(&[0xa3, 0x95]) {
        "not a ULog file: an ArduPilot DataFlash log (read it as DataFlash)".to_string()
    } else {
        "not a ULog file (it does not start with the ULog magic 'ULog' 01 12 35)".to_string()
    }
}

/// One pass over the ULog file `path`: every IMU subscription and data message to `visit`,
/// the rest gathered.
fn scan(path: &Path, visit: &mut Visit) -> Result<Log, DataError> {
    let fail = |problem: String| data_error(path, problem);
    let io = |e: std::io::Error| data_error(path, format!("cannot read: {e}"));
    let mut win = Window::open(path).map_err(|e| fail(format!("cannot open: {e}")))?;
    let head = win.peek(HEADER_LEN).map_err(io)?.to_vec();
    if !head.starts_with(&MAGIC) {
        if MAGIC.starts_with(&head) {
            return Err(fail(format!(
                "truncated ULog file: {} bytes, shorter than its 16-byte header",
                head.len()
            )));
        }
        return Err(fail(not_ulog(&head)));
    }
    let (Some(&version), Some(start_us)) = (head.get(7), u64_le(&head, 8)) else {
        return Err(fail(format!(
            "truncated ULog file: {} bytes, shorter than its 16-byte header",
            head.len()
        )));
    };
    win.consume(HEADER_LEN);
    let mut state = State {
        definitions: true,
        last_us: start_us,
        ..State::default()
    };
    let mut appended = false;
    // Where appended data begins (DATA_APPENDED), ascending.
    let mut boundaries: Vec<u64> = Vec::new();
    let (mut messages, mut cut, mut truncated) = (0u64, 0u64, None);
    loop {
        let pos = win.pos();
        boundaries.retain(|&b| b > pos);
        let next = boundaries.first().copied();
        let head = win.peek(3).map_err(io)?;
        if head.is_empty() {
            break;
        }
        let skip_to = |win: &mut Window, b: u64| -> Result<(), DataError> {
            let n = usize::try_from(b - pos).unwrap_or(usize::MAX);
            let got = win.peek(n).map_err(io)?.len();
            win.consume(got);
            Ok(())
        };
        if let Some(b) = next
            && b < pos + 3
        {
            skip_to(&mut win, b)?;
            cut += 1;
            continue;
        }
        let [lo, hi, ty] = match <[u8; 3]>::try_from(head) {
            Ok(h) => h,
            Err(_) => {
                truncated = Some(pos);
                break;
            }
        };
        let size = usize::from(u16::from_le_bytes([lo, hi]));
        let at =
            |problem: String| fail(format!("message {} at byte {pos}: {problem}", messages + 1));
        if !ty.is_ascii_alphabetic() {
            if zeros_to_end(&mut win).map_err(io)? {
                // The file ends in zeros (a log cut by a power loss): truncated here.
                truncated = Some(pos);
                break;
            }
            return Err(at(format!(
                "type 0x{ty:02x} is not a ULog message type (a corrupt length before it?)"
            )));
        }
        if let Some(b) = next
            && b < pos + 3 + size as u64
        {
            skip_to(&mut win, b)?;
            cut += 1;
            continue;
        }
        let msg = win.peek(3 + size).map_err(io)?;
        if msg.len() < 3 + size {
            truncated = Some(pos);
            break;
        }
        let payload = msg.get(3..).unwrap_or_default();
        if ty == b'B' && messages == 0 {
            let (flags, offsets) = flag_bits(payload).map_err(&at)?;
            appended = flags;
            if appended {
                boundaries = offsets;
            }
        } else {
            state.message(ty, payload, visit).map_err(&at)?;
        }
        win.consume(3 + size);
        messages += 1;
    }
    let State {
        mut parameters,
        info,
        dropouts,
        ..
    } = state;
    parameters.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(Log {
        version,
        start_us,
        appended,
        messages,
        parameters,
        info,
        dropouts,
        cut,
        truncated,
    })
}

/// The flag bits message: whether DATA_APPENDED is set, and the appended offsets (non-zero,
/// ascending); an error naming an incompatible flag this reader does not know.
fn flag_bits(p: &[u8]) -> Result<(bool, Vec<u64>), String> {
    let incompat = p
        .get(8..16)
        .filter(|_| p.len() >= 40)
        .ok_or_else(|| format!("a flag bits message ('B') of {} bytes, not 40", p.len()))?;
    for (i, &byte) in incompat.iter().enumerate() {
        let unknown = if i == 0 { byte & !1 } else { byte };
        if unknown != 0 {
            let bit = unknown.trailing_zeros();
            return Err(format!(
                "the log sets incompatible flag bit {bit} of byte {i} (incompat_flags[{i}] = \
                 0x{byte:02x}), unknown to this reader (only DATA_APPENDED, bit 0 of byte 0, \
                 is known): it cannot be read"
            ));
        }
    }
    let appended = incompat.first().is_some_and(|b| b & 1 == 1);
    let mut offsets: Vec<u64> = (0..3)
        .filter_map(|k| u64_le(p, 16 + 8 * k))
        .filter(|&o| o != 0)
        .collect();
    offsets.sort_unstable();
    Ok((appended, offsets))
}

/// Whether every byte from the window's position to the end of the file is zero (consumed
/// as it is checked).
fn zeros_to_end(win: &mut Window) -> std::io::Result<bool> {
    loop {
        let chunk = win.peek(READ_SIZE)?;
        if chunk.is_empty() {
            return Ok(true);
        }
        if chunk.iter().any(|&b| b != 0) {
            return Ok(false);
        }
        let n = chunk.len();
        win.consume(n);
    }
}

/// How much of a file is read at a time, at least.
const READ_SIZE: usize = 256 * 1024;

/// A file read front to back through a buffer: what is at the current position, up to a
/// requested length, without reading more than that and a buffer's worth ahead.
pub(crate) struct Window {
    file: File,
    buf: Vec<u8>,
    /// Where the current position is in `buf`.
    at: usize,
    /// The current position in the file.
    pos: u64,
    eof: bool,
}

impl Window {
    /// The file `path`, at its start.
    pub(crate) fn open(path: &Path) -> std::io::Result<Window> {
        Ok(Window {
            file: File::open(path)?,
            buf: Vec::new(),
            at: 0,
            pos: 0,
            eof: false,
        })
    }

    /// The current position in the file.
    pub(crate) fn pos(&self) -> u64 {
        self.pos
    }

    /// The next `n` bytes, fewer at the end of the file.
    pub(crate) fn peek(&mut self, n: usize) -> std::io::Result<&[u8]> {
        if self.buf.len() - self.at < n && !self.eof {
            self.buf.drain(..self.at);
            self.at = 0;
            while self.buf.len() < n && !self.eof {
                let old = self.buf.len();
                self.buf.resize(old + (n - old).max(READ_SIZE), 0);
                match self.file.read(&mut self.buf[old..]) {
                    Ok(0) => {
                        self.buf.truncate(old);
                        self.eof = true;
                    }
                    Ok(k) => self.buf.truncate(old + k),
                    Err(e) if e.kind() == ErrorKind::Interrupted => self.buf.truncate(old),
                    Err(e) => {
                        self.buf.truncate(old);
                        return Err(e);
                    }
                }
            }
        }
        let end = self.at.saturating_add(n).min(self.buf.len());
        Ok(self.buf.get(self.at..end).unwrap_or_default())
    }

    /// Moves past the next `n` bytes (at most those read).
    pub(crate) fn consume(&mut self, n: usize) {
        let n = n.min(self.buf.len() - self.at);
        self.at += n;
        self.pos += n as u64;
    }
}

/// The most temperatures kept to interpolate between.
const MAX_POINTS: usize = 1 << 16;
/// The most samples held back waiting for the temperature after them.
const MAX_PENDING: usize = 1 << 18;

/// Temperatures interpolated linearly in time onto samples that arrive in time order:
/// a sample is held back until a temperature at or after its time is read, then released with
/// the value between the two temperatures around it; before the first temperature and after
/// the last, the nearest one is held.
pub(crate) struct Interp<T> {
    /// (time, temperature), times increasing.
    points: VecDeque<(f64, f64)>,
    /// Samples waiting: (time, sample).
    pending: VecDeque<(f64, T)>,
    /// Samples given a held (not interpolated) temperature.
    held: u64,
}

impl<T> Interp<T> {
    /// No temperatures, no samples.
    pub(crate) fn new() -> Self {
        Interp {
            points: VecDeque::new(),
            pending: VecDeque::new(),
            held: 0,
        }
    }

    /// A temperature `value` at `time`; releases the samples it completes to `out`. A
    /// temperature older than the last one is ignored.
    pub(crate) fn point(&mut self, time: f64, value: f64, out: &mut dyn FnMut(T, Option<f64>)) {
        match self.points.back() {
            Some(&(last, _)) if time < last => return,
            Some(&(last, _)) if time == last => {
                self.points.pop_back();
            }
            _ => {}
        }
        self.points.push_back((time, value));
        if self.points.len() > MAX_POINTS {
            self.points.pop_front();
        }
        while let Some(&(t, _)) = self.pending.front()
            && t <= time
        {
            if let Some((t, item)) = self.pending.pop_front() {
                let v = self.at(t);
                out(item, v);
            }
        }
    }

    /// A sample at `time`: released now when a temperature at or after it is known (and no
    /// sample waits), held back otherwise.
    pub(crate) fn sample(&mut self, time: f64, item: T, out: &mut dyn FnMut(T, Option<f64>)) {
        if self.pending.is_empty() && self.points.back().is_some_and(|&(last, _)| time <= last) {
            let v = self.at(time);
            out(item, v);
            return;
        }
        self.pending.push_back((time, item));
        if self.pending.len() > MAX_PENDING
            && let Some((t, item)) = self.pending.pop_front()
        {
            let v = self.at(t);
            out(item, v);
        }
    }

    /// Releases the samples still waiting, with the last temperature held; returns how many
    /// samples were given a held temperature.
    pub(crate) fn finish(mut self, out: &mut dyn FnMut(T, Option<f64>)) -> u64 {
        while let Some((t, item)) = self.pending.pop_front() {
            let v = self.at(t);
            out(item, v);
        }
        self.held
    }

    /// The temperature at `time`: interpolated between the temperatures around it, the
    /// nearest one outside them (counted as held); `None` without temperatures.
    fn at(&mut self, time: f64) -> Option<f64> {
        let k = self.points.partition_point(|&(t, _)| t <= time);
        let before = k.checked_sub(1).and_then(|i| self.points.get(i)).copied();
        let after = self.points.get(k).copied();
        match (before, after) {
            (Some((t0, v0)), Some((t1, v1))) => Some(v0 + (v1 - v0) * ((time - t0) / (t1 - t0))),
            (Some((t0, v0)), None) => {
                if time != t0 {
                    self.held += 1;
                }
                Some(v0)
            }
            (None, Some((_, v1))) => {
                self.held += 1;
                Some(v1)
            }
            (None, None) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Messages of a FIFO at `rate` Hz read every `read` samples of the counts `reads` gives
    /// (one drawn a message), stamped at their last sample's time plus `late` (us, a draw in
    /// [0, 1)), each lost where `lost` (a draw) says.
    fn fifo_messages(
        rate: f64,
        mut reads: impl FnMut(f64) -> usize,
        mut late: impl FnMut(f64) -> f64,
        mut lost: impl FnMut(f64) -> bool,
    ) -> Vec<(f64, usize)> {
        let mut next = crate::xorshift(0x9e37_79b9_7f4a_7c15);
        let mut draw = move || (next() >> 11) as f64 / (1u64 << 53) as f64;
        let mut sample = 0usize;
        let mut messages = Vec::new();
        while messages.len() < 10_000 {
            let n = reads(draw());
            sample += n;
            let stamp = 1e6 + (sample - 1) as f64 * 1e6 / rate + late(draw());
            if !lost(draw()) {
                messages.push((stamp, n));
            }
        }
        messages
    }

    #[test]
    fn a_fifo_whose_rate_steps_is_two_rates() {
        // 4 samples a message, 1000.37 Hz, then 1050.39 Hz (or 980.36 Hz) for as many
        // messages, the dt field unchanged: read 1025.69 (990.42) Hz with no warning, one
        // line through both halves (pass 44 F1). One rate, jittered, is one.
        // So too 5 % faster from 40 to 60 % of the log (1015.23 Hz), or from 92 % on
        // (1001.31 Hz), which leave the halves alike or nearly (pass 45 F1, F2).
        // And where tenths were each compared with the whole on their lines' slopes (pass 46,
        // 3200 Hz in 8-sample messages, read with no warning): 0.8 % faster from half way
        // (3212.76 Hz, between 3200 and 3225.6), 0.9 % for a tenth across two (3204.10 Hz),
        // 5 % faster for 1.5 % of the log (3203.44 Hz), 30 % slower or 50 % faster for 0.5
        // % of it (3189.75, 3208.02 Hz).
        for (step, from, to) in [
            (1.05, 5_000, 10_000),
            (0.98, 5_000, 10_000),
            (1.05, 4_000, 6_000),
            (1.05, 9_200, 10_000),
            (1.008, 5_000, 10_000),
            (1.009, 5_500, 6_500),
            (1.05, 5_000, 5_150),
            (0.7, 5_020, 5_070),
            (1.5, 5_020, 5_070),
            (1.0, 0, 0),
        ] {
            let mut t = 1e6;
            let mut next = crate::xorshift(7);
            let messages: Vec<(f64, usize)> = (0..10_000)
                .map(|k| {
                    let rate = 1000.37 * if (from..to).contains(&k) { step } else { 1.0 };
                    t += 4.0 * 1e6 / rate;
                    let jitter = (next() >> 11) as f64 / (1u64 << 53) as f64 * 40.0;
                    (t + jitter, 4)
                })
                .collect();
            let (_, _, mixed) = fifo_rate(&messages).unwrap();
            assert_eq!(
                mixed.is_some_and(|m| m.contains("mixed rates")),
                step != 1.0,
                "{step} from {from} to {to}"
            );
        }
        // 1000 messages of 8 samples at 3200 Hz, 0.9 % faster for a tenth of them across two
        // tenths: seen where fortieths are compared (read 3204.10 Hz with no warning when a
        // sample's time a run was allowed for messages that each hold as many).
        let mut t = 1e6;
        let mut next = crate::xorshift(5);
        let messages: Vec<(f64, usize)> = (0..1_000)
            .map(|k| {
                t += 8e6
                    / if (550..650).contains(&k) {
                        3228.8
                    } else {
                        3200.0
                    };
                (t + (next() % 20_000) as f64 * 1e-3, 8)
            })
            .collect();
        let (_, _, mixed) = fifo_rate(&messages).unwrap();
        assert!(
            mixed.is_some_and(|m| m.contains("of 40")),
            "a tenth at 0.9 %"
        );
        // One rate, its stamps heavy-tailed (Student's t of two degrees, 75 us), 2 % of the
        // messages lost unseen among them: read (low by the share lost, with the warning),
        // not refused (the stretches its losses bunch in are no other rate).
        let t2 = |u: f64| 75.0 * (2.0 * u - 1.0) / (2.0 * u * (1.0 - u)).sqrt();
        let (rate, warned, mixed) =
            fifo_rate(&fifo_messages(8000.0, |_| 8, t2, |u| u < 0.02)).unwrap();
        assert!(mixed.is_none(), "{mixed:?}");
        assert!(rate < 8000.0 && warned.is_some(), "{rate} {warned:?}");
    }

    #[test]
    fn a_timer_reading_a_sensor_off_its_nominal_rate_is_one_rate() {
        // Each message the samples a timer's read finds (4 or 8 at a time, now and then one
        // more or fewer), stamped at the read, 15 us of latency: a part of 20 messages moves
        // by the sample it gains or loses, which its line's scatter does not show (pass 48
        // F2: 3200.96 Hz read at 800 Hz, 3000 messages; 1000.6 Hz at 250 Hz; 8000.8 Hz at 1
        // kHz, 1000 messages: refused as mixed rates).
        for (rate, reads, count) in [
            (3200.96, 800.0, 3_000),
            (3200.32, 800.0, 10_000),
            (8000.8, 1000.0, 1_000),
            (1000.6, 250.0, 10_000),
            (1990.0, 1000.0, 10_000),
        ] {
            let mut next = crate::xorshift(48);
            let messages: Vec<(f64, usize)> = crate::timer_reads(rate, reads, count)
                .into_iter()
                .map(|(t, n)| (t + (next() % 15_000) as f64 * 1e-3, n))
                .collect();
            let (read, _, mixed) = fifo_rate(&messages).unwrap();
            assert!(mixed.is_none(), "{rate} Hz: {mixed:?}");
            assert!((read / rate - 1.0).abs() < 1e-4, "{rate} Hz: {read}");
        }
    }

    #[test]
    fn few_messages_heavily_jittered_warn_of_their_rates_standard_error() {
        // 220 messages of 8 samples at 3200 Hz, stamps jittered by 300 us RMS: a standard
        // error of about 1.3e-4 (pass 46 F5: 3200.39 Hz and 3199.54 Hz read with no
        // warning). With 10,000 messages, no such warning.
        for (count, warns) in [(220, true), (10_000, false)] {
            let mut next = crate::xorshift(8);
            let mut normal = move || {
                let u = |x: u64| ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
                let (a, b) = (u(next()), u(next()));
                (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
            };
            let messages: Vec<(f64, usize)> = (1..=count)
                .map(|k| (1e6 + k as f64 * 2500.0 + 300.0 * normal(), 8))
                .collect();
            let (rate, warned, mixed) = fifo_rate(&messages).unwrap();
            assert!(
                mixed.is_none() && (rate / 3200.0 - 1.0).abs() < 1e-3,
                "{rate}"
            );
            assert_eq!(
                warned
                    .as_ref()
                    .is_some_and(|w| w.contains("standard error")),
                warns,
                "{count}: {warned:?}"
            );
        }
    }

    #[test]
    fn a_fifos_rate_leans_on_no_late_stamps_and_sees_small_messages_lost() {
        // 8 kHz read 8 samples at a time, a fifth of the stamps 550 us late (and all
        // jittered by up to 8 us), none lost: runs parted at the late stamps lean, as a run
        // that starts late may not meet another late one (pass 43 F1: such logs read 8044 to
        // 8060 Hz). Read with the warning, as a message lost would hide among late stamps.
        let (rate, warned, _) = fifo_rate(&fifo_messages(
            8000.0,
            |_| 8,
            |u| 8.0 * u + if u < 0.2 { 550.0 } else { 0.0 },
            |_| false,
        ))
        .unwrap();
        assert!((rate / 8000.0 - 1.0).abs() < 2e-5, "{rate}");
        assert!(warned.is_some_and(|w| w.contains("a message lost is not told")));
        // 1 kHz read 1 or 15 samples at a time, 1 % of the messages lost: a lost message of
        // one sample, under half the messages' mean, parted no run, its sample not counted
        // (pass 43 F3: such logs read 999.15 and 999.27 Hz). No warning: the stamps jitter by
        // 5 us.
        let (rate, warned, _) = fifo_rate(&fifo_messages(
            1000.0,
            |u| if u < 0.5 { 1 } else { 15 },
            |u| 5.0 * u,
            |u| u < 0.01,
        ))
        .unwrap();
        assert!(
            (rate / 1000.0 - 1.0).abs() < 2e-5 && warned.is_none(),
            "{rate} {warned:?}"
        );
    }

    /// Runs `f` on an interpolator, collecting what it releases as (sample, temperature).
    fn released(
        f: impl FnOnce(&mut Interp<u32>, &mut dyn FnMut(u32, Option<f64>)),
    ) -> Vec<(u32, Option<f64>)> {
        let mut out = Vec::new();
        let mut interp = Interp::new();
        let mut push = |s: u32, t: Option<f64>| out.push((s, t));
        f(&mut interp, &mut push);
        interp.finish(&mut push);
        out
    }

    #[test]
    fn samples_wait_for_the_temperature_after_them_and_ends_are_held() {
        let out = released(|i, out| {
            i.sample(5.0, 0, out);
            i.point(10.0, 20.0, out);
            i.sample(12.0, 1, out);
            i.sample(15.0, 2, out);
            i.point(20.0, 30.0, out);
            i.sample(20.0, 3, out);
            i.sample(25.0, 4, out);
        });
        assert_eq!(
            out,
            vec![
                (0, Some(20.0)),
                (1, Some(22.0)),
                (2, Some(25.0)),
                (3, Some(30.0)),
                (4, Some(30.0)),
            ]
        );
        // Without temperatures: none.
        assert_eq!(released(|i, out| i.sample(1.0, 7, out)), vec![(7, None)]);
        // A temperature older than the last is ignored; one at the same time replaces it.
        let out = released(|i, out| {
            i.point(10.0, 1.0, out);
            i.point(5.0, 100.0, out);
            i.point(10.0, 2.0, out);
            i.point(20.0, 4.0, out);
            i.sample(15.0, 0, out);
        });
        assert_eq!(out, vec![(0, Some(3.0))]);
    }

    #[test]
    fn formats_refuse_bad_fields_and_redefinitions() {
        let mut f = Formats::default();
        f.add(b"a:uint8_t x;float[3] y;").expect("a format");
        f.add(b"a:uint8_t x;float[3] y;").expect("the same again");
        for bad in [
            &b"a:uint8_t x;"[..],
            b"no colon",
            b":uint8_t x;",
            b"b:uint8_t;",
            b"b:uint8_t[x] y;",
            b"b:uint8_t[3 y;",
            b"b:[3] y;",
            b"\xff:uint8_t x;",
        ] {
            assert!(f.add(bad).is_err(), "{}", String::from_utf8_lossy(bad));
        }
        f.add(b"c:a[2] p;uint16_t[0] none;")
            .expect("a nested format");
        let placed = f.place("c").expect("placed");
        assert_eq!((placed.min, placed.max), (26, 26));
        assert!(f.place("missing").is_err());
    }
}
