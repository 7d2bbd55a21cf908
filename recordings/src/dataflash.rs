//! Streaming IMU samples out of an ArduPilot DataFlash log (`.bin`): the `IMU` messages, six
//! axes with temperature, and the batch sampler's `ISBH`/`ISBD` messages rebuilt into samples
//! at the full sensor rate.
//!
//! Format (ArduPilot `libraries/AP_Logger/LogStructure.h`; reference reader pymavlink
//! `DFReader.py`, <https://github.com/ArduPilot/pymavlink>): no file header, a stream of
//! messages `A3 95 <type>` and the fixed-length payload the type's `FMT` message (type 128,
//! 89 bytes, "BBnNZ": type, length with the 3 header bytes, name, format, columns) gives.
//! Format characters: a int16\[32\], b int8, B uint8, h int16, H uint16, i int32, I uint32,
//! f float, d double, g float16, n char\[4\], N char\[16\], Z char\[64\], c int16 and C uint16
//! (×0.01), e int32 and E uint32 (×0.01), L int32 (1e-7 degrees), M uint8, q int64, Q uint64.
//! Fields are looked up by their column name and type, never by position. `FMTU` gives each
//! field a unit id (`UNIT`) and multiplier id (`MULT`): an `IMU` format whose units are not
//! rad/s, m/s/s and degC is not read. `PARM` ("QNf", or "QNff" with the default) gives the
//! parameters and their changes.
//!
//! Bytes that do not start a message (not `A3 95`, or a type no `FMT` defines, or a `FMT`
//! that contradicts itself) are skipped one by one until a message head is found again, as
//! DFReader does, and counted; a last message cut short by the end of the file is reported.
//! An `IMU` message whose TimeUS no clock since boot reaches (past [`MAX_TIME_US`]) or whose
//! `I` names no IMU an INS holds (not below [`MAX_IMUS`]) is corrupt, as an SD card's write
//! error leaves one: it is skipped and counted ([`Survey::corrupt`], [`Report::corrupt`]),
//! neither a sample nor an instance of its own. A batch header whose sample times do so is
//! an undecodable batch.
//!
//! `IMU` ("QBffffffIIfBBHH": TimeUS, I, GyrX..GyrZ rad/s, AccX..AccZ m/s^2, EG, EA, T °C, ...;
//! older logs: `IMU`, `IMU2`, `IMU3` without `I`) holds the filtered, fully corrected samples
//! (`AP_InertialSensor_Logging.cpp`). `ISBH` ("QHBBHHQf": TimeUS, N, type 0 accel / 1 gyro,
//! instance, mul, smp_cnt, SampleUS, smp_rate) opens batch N and `ISBD` ("QHHaaa": TimeUS, N,
//! seqno, x, y, z) carries its blocks of 32 samples: sample `j = seqno*32 + i` is
//! `raw / mul` at `SampleUS + j * 1e6 / smp_rate` µs (pymavlink `tools/isb_extract.py`,
//! `tools/extract_batch_imu.py`); samples past smp_cnt are not delivered. A batch whose blocks
//! do not come as 0, 1, 2, ... (a block missing or repeated) is dropped whole and counted,
//! never delivered with a gap. Batch samples take the temperature of the `IMU` messages of the
//! same instance, interpolated linearly in time (held at the nearest value outside their
//! span). With pre- and post-filter batch logging (`INS_LOG_BAT_OPT` bit 2) the post-filter
//! batches are numbered after the IMUs (`Write_ISBH`): their instance is not an IMU's.
//!
//! What the autopilot already corrected (`AP_InertialSensor_Backend.cpp`,
//! `AP_InertialSensor_tempcal.cpp`): `IMU` samples and ordinary batch samples include the
//! temperature correction when `INS_TCALn_ENABLE` is 1 (n = instance + 1; `INS4_TCAL_ENABLE`,
//! `INS5_TCAL_ENABLE` for the 4th and 5th IMU), the INS offsets and scale, and the
//! AHRS_ORIENTATION rotation; sensor-rate batch samples (`INS_LOG_BAT_OPT` bit 0) are only
//! rotated by the sensor orientation. [`Survey::temperature_corrected`] says which applies.
//!
//! The file is read front to back through a buffer of 256 KiB: memory is bounded by the
//! parameters (at most 2^16) and the open batches (at most 16), whatever its length.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use crate::csv::DataError;
use crate::error::escaped;
use crate::frame::{bytes_at, data_error};
use crate::ulog::{Interp, Window};

/// The two bytes that start every message.
pub const HEAD: [u8; 2] = [0xa3, 0x95];

/// The message type of `FMT`, the format of the formats.
pub const FMT_TYPE: u8 = 128;

/// The length of an `FMT` message, its 3 header bytes included.
const FMT_LEN: usize = 89;
/// The most parameters kept.
const MAX_PARAMETERS: usize = 1 << 16;
/// The changes of a parameter kept with their time (all are counted).
const KEPT_CHANGES: usize = 16;
/// The most batches open at once; opening one more drops the oldest.
const MAX_OPEN: usize = 16;
/// Samples per `ISBD` block.
const BLOCK: usize = 32;

/// The latest sample time (µs since boot) a message can carry: 2^53 µs (285 years), the
/// largest whole number of microseconds a double holds exactly, whose nanoseconds (9.0e18) an
/// i64 also holds. A later TimeUS is the garbage of a corrupt message (14047262688061562948 µs,
/// year 447110, from an SD card's write error), no time of any clock.
pub const MAX_TIME_US: u64 = 1 << 53;

/// The most IMUs an ArduPilot INS holds: `INS_MAX_INSTANCES` is 3 + `INS_AUX_INSTANCES`
/// (`libraries/AP_InertialSensor/AP_InertialSensor_config.h`), and its parameters go up to
/// the fifth IMU (`INS4_`, `INS5_` in `AP_InertialSensor.cpp`). An `IMU` message's `I` is
/// below it; one that is not is a corrupt message.
pub const MAX_IMUS: u8 = 5;

/// The IMU data read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// `IMU` messages: gyro and accel of one IMU with its temperature.
    Imu,
    /// Batch sampler accel batches (`ISBH` type 0).
    BatchAccel,
    /// Batch sampler gyro batches (`ISBH` type 1).
    BatchGyro,
}

impl Kind {
    /// Every kind, in this order.
    pub const ALL: [Kind; 3] = [Kind::Imu, Kind::BatchAccel, Kind::BatchGyro];

    /// Its name in messages (`IMU`, `ISB accel`, `ISB gyro`).
    pub fn name(self) -> &'static str {
        match self {
            Kind::Imu => "IMU",
            Kind::BatchAccel => "ISB accel",
            Kind::BatchGyro => "ISB gyro",
        }
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which samples to read: a kind, and which IMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Select {
    /// The kind.
    pub kind: Kind,
    /// The IMU instance (0-based); `None`: the kind's one instance, an error when it has
    /// several.
    pub instance: Option<u8>,
}

/// One IMU sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The sample time in µs since boot (TimeUS of an `IMU` message; fractional for batch
    /// samples).
    pub time_us: f64,
    /// Angular rate x, y, z in rad/s (`IMU`, gyro batches).
    pub gyro: Option<[f64; 3]>,
    /// Specific force x, y, z in m/s^2 (`IMU`, accel batches).
    pub accel: Option<[f64; 3]>,
    /// The IMU's temperature in °C (interpolated for batch samples); `None` when the log
    /// gives none.
    pub temperature: Option<f64>,
    /// The IMU instance.
    pub instance: u8,
}

/// A parameter of the log.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Its name (`INS_TCAL1_ENABLE`, ...).
    pub name: String,
    /// Its value in its first `PARM` message.
    pub first: f64,
    /// Its last value.
    pub value: f64,
    /// Its default, when the log gives it ("QNff").
    pub default: Option<f64>,
    /// How many later `PARM` messages changed its value.
    pub changes: u64,
    /// The first 16 changes: TimeUS and the new value.
    pub first_changes: Vec<(u64, f64)>,
}

impl Parameter {
    /// Whether its value changed during the log.
    pub fn changed(&self) -> bool {
        self.changes > 0
    }
}

/// What the log holds of one kind and IMU instance.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceSurvey {
    /// The kind.
    pub kind: Kind,
    /// The IMU instance.
    pub instance: u8,
    /// Its messages: `IMU` messages, or `ISBD` blocks.
    pub messages: u64,
    /// The samples that can be delivered: decodable `IMU` messages, or the samples of
    /// complete batches.
    pub samples: u64,
    /// The first and last sample time in µs.
    pub span_us: Option<(f64, f64)>,
    /// Whether its samples have a temperature (for batches: the `IMU` messages of the
    /// instance do).
    pub temperature: bool,
    /// Complete batches.
    pub batches: u64,
    /// Batches dropped: a block missing or repeated, or cut by the end of the log.
    pub dropped_batches: u64,
    /// The sample rate of its first batch (Hz).
    pub rate_hz: Option<f64>,
}

/// Whether samples include the autopilot's temperature correction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corrected {
    /// All of them.
    Yes,
    /// None of them.
    No,
    /// Some: the deciding parameter changed during the log.
    Mixed,
    /// The log does not say.
    Unknown,
}

/// Whether samples include the temperature correction, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Correction {
    /// The answer.
    pub corrected: Corrected,
    /// The parameters it rests on, in words.
    pub reason: String,
}

/// What a DataFlash log holds, without its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Survey {
    /// Messages read.
    pub messages: u64,
    /// The kinds and instances with messages, by kind then instance.
    pub sources: Vec<SourceSurvey>,
    /// The parameters, by name.
    pub parameters: Vec<Parameter>,
    /// Why an IMU, ISBH or ISBD format cannot be read (a field missing, of another type, or
    /// of another unit), one line each.
    pub unreadable: Vec<String>,
    /// Bytes skipped that do not start a message.
    pub skipped_bytes: u64,
    /// Runs of skipped bytes (each ended by a message found again, or by the end).
    pub resyncs: u64,
    /// The byte offset of the last message when it is cut short by the end of the file.
    pub truncated: Option<u64>,
    /// Corrupt `IMU` messages (of every instance): a TimeUS past [`MAX_TIME_US`], or an `I`
    /// not below [`MAX_IMUS`]. They are in no source.
    pub corrupt: u64,
    /// Batch headers of a sensor type that cannot be rebuilt (no samples, mul 0, a sample
    /// rate that is not a positive number, sample times no clock reaches): in no source.
    pub undecodable_batches: u64,
}

impl Survey {
    /// The parameter `name`.
    pub fn parameter(&self, name: &str) -> Option<&Parameter> {
        crate::frame::by_name(&self.parameters, name, |p| &p.name)
    }

    /// The instances of `kind` with messages.
    pub fn instances(&self, kind: Kind) -> Vec<&SourceSurvey> {
        self.sources
            .iter()
            .filter(|s| s.kind == kind && s.messages > 0)
            .collect()
    }

    /// Whether the samples of `kind` from IMU `instance` include the autopilot's temperature
    /// correction (`INS_TCALn_ENABLE` = 1, n = instance + 1), and why: sensor-rate batch
    /// samples (`INS_LOG_BAT_OPT` bit 0) never do; a deciding parameter that changed during
    /// the log gives [`Corrected::Mixed`]; a log without `PARM` messages, [`Corrected::Unknown`].
    /// Samples that include it also include the INS offsets and scale and the
    /// AHRS_ORIENTATION rotation.
    pub fn temperature_corrected(&self, kind: Kind, instance: u8) -> Correction {
        let answer = |corrected, reason: String| Correction { corrected, reason };
        if self.parameters.is_empty() {
            return answer(
                Corrected::Unknown,
                "the log has no parameters (PARM messages)".into(),
            );
        }
        if kind != Kind::Imu {
            let Some(opt) = self.parameter("INS_LOG_BAT_OPT") else {
                return answer(
                    Corrected::Unknown,
                    "the log has no INS_LOG_BAT_OPT parameter".into(),
                );
            };
            if opt.changed() {
                return answer(
                    Corrected::Mixed,
                    format!(
                        "INS_LOG_BAT_OPT changed during the log (from {} to {}): sensor-rate \
                         batches (bit 0) are not corrected, the others may be",
                        opt.first, opt.value
                    ),
                );
            }
            if opt.value as i64 & 1 == 1 {
                return answer(
                    Corrected::No,
                    format!(
                        "INS_LOG_BAT_OPT = {} (bit 0, sensor-rate logging): batch samples are \
                         only rotated by the sensor orientation, not corrected",
                        opt.value
                    ),
                );
            }
        }
        let Some(name) = tcal_enable(instance) else {
            return answer(
                Corrected::Unknown,
                format!(
                    "instance {instance}: ArduPilot has temperature calibrations for IMUs 1 to 5"
                ),
            );
        };
        let Some(enable) = self.parameter(&name) else {
            return answer(
                Corrected::No,
                format!(
                    "the log has no {name} parameter (firmware without temperature calibration, \
                     or no IMU {})",
                    u16::from(instance) + 1
                ),
            );
        };
        let also = "also INS offsets, scale and AHRS_ORIENTATION";
        if enable.changed() {
            return answer(
                Corrected::Mixed,
                format!(
                    "{name} changed during the log (from {} to {}): the correction applies \
                     while it is 1",
                    enable.first, enable.value
                ),
            );
        }
        match enable.value {
            1.0 => answer(
                Corrected::Yes,
                format!("{name} = 1: the temperature correction is applied ({also})"),
            ),
            0.0 => answer(
                Corrected::No,
                format!("{name} = 0: temperature calibration disabled ({also} are applied)"),
            ),
            2.0 => answer(
                Corrected::No,
                format!("{name} = 2: learning a calibration, none applied ({also} are applied)"),
            ),
            v => answer(
                Corrected::Unknown,
                format!("{name} = {v}: not a known value"),
            ),
        }
    }
}

/// The name of the parameter that enables IMU `instance`'s temperature calibration.
fn tcal_enable(instance: u8) -> Option<String> {
    match instance {
        0..=2 => Some(format!("INS_TCAL{}_ENABLE", instance + 1)),
        3 | 4 => Some(format!("INS{}_TCAL_ENABLE", instance + 1)),
        _ => None,
    }
}

/// What a read delivered and skipped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Samples delivered.
    pub delivered: u64,
    /// Samples with a NaN or infinite value, not delivered.
    pub non_finite: u64,
    /// Batches of the selection dropped (a block missing or repeated, or cut by the end of
    /// the log), and their samples not delivered.
    pub dropped_batches: u64,
    /// Batch headers of the selection that cannot be rebuilt (mul 0, a sample rate that is not
    /// a positive number).
    pub undecodable_batches: u64,
    /// Samples delivered without a temperature.
    pub without_temperature: u64,
    /// Batch samples outside the span of the `IMU` temperatures, given the nearest one.
    pub held_temperature: u64,
    /// Bytes skipped that do not start a message.
    pub skipped_bytes: u64,
    /// Runs of skipped bytes.
    pub resyncs: u64,
    /// The byte offset of the last message when it is cut short by the end of the file.
    pub truncated: Option<u64>,
    /// Corrupt `IMU` messages skipped: the instance's own with a TimeUS past
    /// [`MAX_TIME_US`], and those whose `I` is not below [`MAX_IMUS`] (whose instance the
    /// garbage hides); none for a read of batches.
    pub corrupt: u64,
    /// The least, the most and the mean (by samples) `smp_rate` of the batches delivered
    /// (Hz); none for a read of `IMU` messages.
    pub batch_rates: Option<(f64, f64, f64)>,
}

/// What the log holds of IMU data and its parameters, read in one pass without delivering
/// samples. An error when the file cannot be read, holds no message at all (not a DataFlash
/// log), or more than 2^16 parameters.
pub fn survey(path: &Path) -> Result<Survey, DataError> {
    let mut sources: Vec<SourceSurvey> = Vec::new();
    let mut batches = Batches::new(false);
    let mut undecodable = 0u64;
    let mut visit = |event: Event| {
        let entry = |sources: &mut Vec<SourceSurvey>, kind: Kind, instance: u8| match sources
            .iter()
            .position(|s| s.kind == kind && s.instance == instance)
        {
            Some(at) => at,
            None => {
                sources.push(SourceSurvey {
                    kind,
                    instance,
                    messages: 0,
                    samples: 0,
                    span_us: None,
                    temperature: false,
                    batches: 0,
                    dropped_batches: 0,
                    rate_hz: None,
                });
                sources.len() - 1
            }
        };
        let span = |s: &mut SourceSurvey, a: f64, b: f64| {
            if a.is_finite() && b.is_finite() {
                s.span_us = Some(s.span_us.map_or((a, b), |(x, y)| (x.min(a), y.max(b))));
            }
        };
        let closed = |sources: &mut Vec<SourceSurvey>, c: Closed| {
            let at = entry(sources, c.kind, c.instance);
            if let Some(s) = sources.get_mut(at) {
                if c.complete {
                    s.batches += 1;
                    s.samples += c.count as u64;
                    if c.count > 0 {
                        span(s, c.time(0), c.time(c.count - 1));
                    }
                    if s.rate_hz.is_none() {
                        s.rate_hz = Some(c.rate);
                    }
                } else {
                    s.dropped_batches += 1;
                }
            }
        };
        match event {
            Event::Imu(m) => {
                let at = entry(&mut sources, Kind::Imu, m.instance);
                if let Some(s) = sources.get_mut(at) {
                    s.messages += 1;
                    s.samples += 1;
                    span(s, m.time_us, m.time_us);
                    if m.temperature.is_some_and(f64::is_finite) {
                        s.temperature = true;
                    }
                }
            }
            Event::Isbh(h) => {
                undecodable += u64::from(h.kind.is_some() && !h.valid());
                for c in batches.open(h) {
                    closed(&mut sources, c);
                }
            }
            Event::Isbd(d) => {
                let (source, done) = batches.block(&d);
                if let Some((kind, instance)) = source {
                    let at = entry(&mut sources, kind, instance);
                    if let Some(s) = sources.get_mut(at) {
                        s.messages += 1;
                    }
                }
                if let Some(c) = done {
                    closed(&mut sources, c);
                }
            }
        }
    };
    let log = scan(path, &mut visit)?;
    for c in batches.close_all() {
        let at = sources
            .iter()
            .position(|s| s.kind == c.kind && s.instance == c.instance);
        if let Some(s) = at.and_then(|at| sources.get_mut(at)) {
            s.dropped_batches += 1;
        }
    }
    sources.sort_by_key(|s| (s.kind, s.instance));
    let temperatures: Vec<(u8, bool)> = sources
        .iter()
        .filter(|s| s.kind == Kind::Imu)
        .map(|s| (s.instance, s.temperature))
        .collect();
    for s in sources.iter_mut().filter(|s| s.kind != Kind::Imu) {
        s.temperature = temperatures.contains(&(s.instance, true));
    }
    Ok(Survey {
        messages: log.messages,
        sources,
        parameters: log.parameters,
        unreadable: log.unreadable,
        skipped_bytes: log.skipped_bytes,
        resyncs: log.resyncs,
        truncated: log.truncated,
        corrupt: log.corrupt,
        undecodable_batches: undecodable,
    })
}

/// Calls `each` with every finite sample that `select` asks for, in file order (a batch's
/// samples when its last block is read, held back until the `IMU` temperature after them is
/// read), and returns what was delivered and skipped. The file is surveyed first
/// ([`survey`]), so that a selection the log cannot satisfy is an error before any sample: a
/// kind without messages, an instance it does not have, no instance named when it has
/// several, a format that cannot be read; also an error when no sample is delivered.
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
    let instance = choose(survey, select).map_err(|e| data_error(path, e))?;
    let kind = select.kind;
    let temperature = kind != Kind::Imu
        && survey
            .sources
            .iter()
            .any(|s| s.kind == Kind::Imu && s.instance == instance && s.temperature);
    let mut interp: Option<Interp<Sample>> = temperature.then(Interp::new);
    let mut batches = Batches::new(true);
    let (mut delivered, mut without_temperature, mut non_finite) = (0u64, 0u64, 0u64);
    let (mut dropped, mut undecodable) = (0u64, 0u64);
    let mut deliver = |s: Sample, temperature: Option<f64>| {
        delivered += 1;
        if temperature.is_none() {
            without_temperature += 1;
        }
        each(Sample { temperature, ..s });
    };
    // The last complete batch's first and last sample times and its count; the first batch
    // that starts within it.
    let mut previous: Option<(f64, f64, usize)> = None;
    let mut overlap: Option<Overlap> = None;
    let mut batch_rates: Option<(f64, f64)> = None;
    // The batches' samples and the sum of their rates, each a sample's.
    let mut weighed = (0.0f64, 0.0f64);
    let mut batch = |c: Closed,
                     interp: &mut Option<Interp<Sample>>,
                     deliver: &mut dyn FnMut(Sample, Option<f64>)| {
        if c.kind != kind || c.instance != instance {
            return;
        }
        if !c.complete {
            dropped += 1;
            return;
        }
        if let Some((first, last, count)) = previous
            && c.sample_us > first
            && c.sample_us <= last
        {
            overlap.get_or_insert(Overlap {
                first,
                last,
                count,
                next: c.sample_us,
                rate: c.rate,
            });
        }
        if c.count > 0 {
            previous = Some((c.sample_us, c.time(c.count - 1), c.count));
            let (least, most) = batch_rates.get_or_insert((c.rate, c.rate));
            (*least, *most) = (least.min(c.rate), most.max(c.rate));
            weighed.0 += c.count as f64;
            weighed.1 += c.count as f64 * c.rate;
        }
        for (j, raw) in c.samples.iter().enumerate().take(c.count) {
            let xyz = raw.map(|r| f64::from(r) / c.mul);
            let s = Sample {
                time_us: c.time(j),
                gyro: (kind == Kind::BatchGyro).then_some(xyz),
                accel: (kind == Kind::BatchAccel).then_some(xyz),
                temperature: None,
                instance,
            };
            match interp {
                Some(i) => i.sample(s.time_us, s, &mut *deliver),
                None => deliver(s, None),
            }
        }
    };
    let mut visit = |event: Event| match event {
        Event::Imu(m) => {
            if m.instance != instance {
                return;
            }
            if kind == Kind::Imu {
                if !m.gyro.iter().chain(&m.accel).all(|v| v.is_finite()) {
                    non_finite += 1;
                    return;
                }
                let s = Sample {
                    time_us: m.time_us,
                    gyro: Some(m.gyro),
                    accel: Some(m.accel),
                    temperature: None,
                    instance,
                };
                deliver(s, m.temperature.filter(|t| t.is_finite()));
            } else if let (Some(i), Some(t)) =
                (interp.as_mut(), m.temperature.filter(|t| t.is_finite()))
            {
                i.point(m.time_us, t, &mut deliver);
            }
        }
        Event::Isbh(h) => {
            if h.kind == Some(kind) && h.instance == instance && !h.valid() {
                undecodable += 1;
            }
            for c in batches.open(h) {
                batch(c, &mut interp, &mut deliver);
            }
        }
        Event::Isbd(d) => {
            if let (_, Some(c)) = batches.block(&d) {
                batch(c, &mut interp, &mut deliver);
            }
        }
    };
    let log = scan(path, &mut visit)?;
    for c in batches.close_all() {
        batch(c, &mut interp, &mut deliver);
    }
    let held = interp.map_or(0, |i| i.finish(&mut deliver));
    if let Some(o) = overlap {
        return Err(data_error(path, o.to_string()));
    }
    if delivered == 0 {
        return Err(data_error(
            path,
            format!(
                "no finite samples of {kind} instance {instance} ({non_finite} with a NaN or \
                 infinite value, {dropped} batches dropped, {undecodable} batch headers \
                 undecodable)"
            ),
        ));
    }
    Ok(Report {
        delivered,
        non_finite,
        dropped_batches: dropped,
        undecodable_batches: undecodable,
        without_temperature,
        held_temperature: held,
        skipped_bytes: log.skipped_bytes,
        resyncs: log.resyncs,
        truncated: log.truncated,
        batch_rates: batch_rates
            .map(|(least, most)| (least, most, (weighed.1 / weighed.0).clamp(least, most))),
        // Its own, and those that name no IMU (any instance's); a batch read reads none.
        corrupt: if kind == Kind::Imu {
            log.corrupt_of
                .get(usize::from(instance))
                .copied()
                .unwrap_or(0)
                + (log.corrupt - log.corrupt_of.iter().sum::<u64>())
        } else {
            0
        },
    })
}

/// A batch whose samples, placed at its header's rate, run past the first sample of the
/// next batch of the same sensor.
struct Overlap {
    /// Its first and last sample times (µs) and its samples.
    first: f64,
    last: f64,
    count: usize,
    /// The next batch's first sample time (µs) and its header's rate (Hz).
    next: f64,
    rate: f64,
}

impl fmt::Display for Overlap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "a batch of {} samples from {:.0} us runs to {:.0} us at the batch header's sample \
             rate, {} Hz, past the next batch's first sample at {:.0} us: the headers' rate is not the \
             one their sample times keep (the batch's samples and the next one's start give \
             {} Hz or more); the batches cannot be placed in time",
            self.count,
            self.first,
            self.last,
            self.rate,
            self.next,
            ((self.count - 1) as f64 * 1e6 / (self.next - self.first) * 1e3).round() / 1e3
        )
    }
}

/// The instance `select` reads, or why none.
fn choose(survey: &Survey, select: &Select) -> Result<u8, String> {
    let kind = select.kind;
    let present = survey.instances(kind);
    let listed = |list: &[&SourceSurvey]| {
        list.iter()
            .map(|s| format!("instance {} ({} messages)", s.instance, s.messages))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if present.is_empty() {
        let others: Vec<String> = Kind::ALL
            .into_iter()
            .filter(|&k| !survey.instances(k).is_empty())
            .map(|k| format!("{k} ({} instances)", survey.instances(k).len()))
            .collect();
        let mut problem = format!(
            "no {kind} messages in the log (IMU data: {})",
            if others.is_empty() {
                "none".into()
            } else {
                others.join(", ")
            }
        );
        if !survey.unreadable.is_empty() {
            problem.push_str(&format!("; {}", survey.unreadable.join("; ")));
        }
        return Err(problem);
    }
    match select.instance {
        None => match present.as_slice() {
            [one] => Ok(one.instance),
            _ => Err(format!(
                "{kind} has {} instances: {}; choose one with --instance",
                present.len(),
                listed(&present)
            )),
        },
        Some(i) if present.iter().any(|s| s.instance == i) => Ok(i),
        Some(i) => Err(format!(
            "{kind} has no instance {i} with messages ({})",
            listed(&present)
        )),
    }
}

/// A format character's size in bytes; `None` for an unknown one.
fn char_size(c: u8) -> Option<usize> {
    Some(match c {
        b'b' | b'B' | b'M' => 1,
        b'h' | b'H' | b'c' | b'C' | b'g' => 2,
        b'i' | b'I' | b'f' | b'e' | b'E' | b'L' | b'n' => 4,
        b'd' | b'q' | b'Q' => 8,
        b'N' => 16,
        b'a' | b'Z' => 64,
        _ => return None,
    })
}

/// A field of a format: where it starts in the payload and its format character.
#[derive(Clone, Copy, Debug)]
struct Field {
    at: usize,
    ch: u8,
}

impl Field {
    /// Its raw number in payload `p` (no ×0.01 or 1e-7 applied); `None` for strings and arrays.
    fn num(self, p: &[u8]) -> Option<f64> {
        let at = self.at;
        Some(match self.ch {
            b'b' => f64::from(i8::from_le_bytes(bytes_at::<1>(p, at)?)),
            b'B' | b'M' => f64::from(*p.get(at)?),
            b'h' | b'c' => f64::from(i16::from_le_bytes(bytes_at::<2>(p, at)?)),
            b'H' | b'C' => f64::from(u16::from_le_bytes(bytes_at::<2>(p, at)?)),
            b'i' | b'e' | b'L' => f64::from(i32::from_le_bytes(bytes_at::<4>(p, at)?)),
            b'I' | b'E' => f64::from(u32::from_le_bytes(bytes_at::<4>(p, at)?)),
            b'f' => f64::from(f32::from_le_bytes(bytes_at::<4>(p, at)?)),
            b'd' => f64::from_le_bytes(bytes_at::<8>(p, at)?),
            b'g' => f16(u16::from_le_bytes(bytes_at::<2>(p, at)?)),
            b'q' => i64::from_le_bytes(bytes_at::<8>(p, at)?) as f64,
            b'Q' => u64::from_le_bytes(bytes_at::<8>(p, at)?) as f64,
            _ => return None,
        })
    }

    /// Its u64 in payload `p` (a `Q` field).
    fn u64(self, p: &[u8]) -> Option<u64> {
        bytes_at::<8>(p, self.at).map(u64::from_le_bytes)
    }

    /// Its time in µs in payload `p` (a `Q` field of µs since boot): `None` past
    /// [`MAX_TIME_US`], where no clock since boot reaches.
    fn time_us(self, p: &[u8]) -> Option<u64> {
        self.u64(p).filter(|&t| t <= MAX_TIME_US)
    }

    /// Its text in payload `p` (an `n`, `N` or `Z` field), up to the first NUL.
    fn text(self, p: &[u8]) -> Option<String> {
        let bytes = p.get(self.at..self.at.checked_add(char_size(self.ch)?)?)?;
        let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
        Some(String::from_utf8_lossy(bytes.get(..end)?).into_owned())
    }

    /// Its 32 int16 in payload `p` (an `a` field).
    fn array(self, p: &[u8]) -> Option<[i16; BLOCK]> {
        let mut out = [0i16; BLOCK];
        for (k, v) in out.iter_mut().enumerate() {
            *v = i16::from_le_bytes(bytes_at::<2>(p, self.at + 2 * k)?);
        }
        Some(out)
    }
}

/// An IEEE 754 half-precision number.
fn f16(bits: u16) -> f64 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let fraction = f64::from(bits & 0x3ff);
    sign * match exponent {
        0 => fraction * 2f64.powi(-24),
        31 if fraction == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        e => (1.0 + fraction / 1024.0) * 2f64.powi(e - 15),
    }
}

/// A message format from `FMT`.
#[derive(Clone, Debug)]
struct Format {
    name: String,
    /// The message length, its 3 header bytes included.
    len: usize,
    /// Column name, and field.
    fields: Vec<(String, Field)>,
    role: Role,
}

impl Format {
    /// The field named `name`, if it has one of the format characters `allowed`; an error
    /// naming what is wrong.
    fn field(&self, name: &str, allowed: &[u8]) -> Result<Option<Field>, String> {
        match self.fields.iter().find(|(n, _)| n == name) {
            None => Ok(None),
            Some((_, f)) if allowed.contains(&f.ch) => Ok(Some(*f)),
            Some((_, f)) => Err(format!(
                "{} field {name} has format character '{}', not '{}'",
                self.name,
                char::from(f.ch),
                allowed.iter().map(|&c| char::from(c)).collect::<String>()
            )),
        }
    }

    /// The field named `name`, which it must have.
    fn need(&self, name: &str, allowed: &[u8]) -> Result<Field, String> {
        self.field(name, allowed)?
            .ok_or_else(|| format!("{} has no field {name}", self.name))
    }
}

/// What a message type is to the reader.
#[derive(Clone, Debug)]
enum Role {
    Fmt,
    Parm {
        time: Field,
        name: Field,
        value: Field,
        default: Option<Field>,
    },
    Fmtu {
        ty: Field,
        units: Field,
        mults: Field,
    },
    Unit {
        id: Field,
        label: Field,
    },
    Mult {
        id: Field,
        mult: Field,
    },
    Imu(ImuFields),
    Isbh(IsbhFields),
    Isbd(IsbdFields),
    /// An IMU, ISBH or ISBD format that cannot be read, and why.
    Unreadable(String),
    Other,
}

/// Where an `IMU` message's fields are.
#[derive(Clone, Debug)]
struct ImuFields {
    time: Field,
    /// The `I` field, or the instance the name gives (`IMU2` is instance 1).
    instance: Result<Field, u8>,
    gyro: [Field; 3],
    accel: [Field; 3],
    temperature: Option<Field>,
    /// Column indices of GyrX..AccZ and T, for FMTU.
    columns: [usize; 7],
}

/// Where an `ISBH` message's fields are.
#[derive(Clone, Debug)]
struct IsbhFields {
    n: Field,
    ty: Field,
    instance: Field,
    mul: Field,
    count: Field,
    sample_us: Field,
    rate: Field,
}

/// Where an `ISBD` message's fields are.
#[derive(Clone, Debug)]
struct IsbdFields {
    n: Field,
    seqno: Field,
    xyz: [Field; 3],
}

/// Integer format characters.
const INTS: &[u8] = b"bBhHiIqQM";

/// The role of format `f` by its name.
fn role(f: &Format) -> Role {
    let unreadable = |r: Result<Role, String>| r.unwrap_or_else(Role::Unreadable);
    match f.name.as_str() {
        "FMT" => Role::Fmt,
        "PARM" => (|| -> Result<Role, String> {
            Ok(Role::Parm {
                time: f.need("TimeUS", b"Q")?,
                name: f.need("Name", b"nNZ")?,
                value: f.need("Value", b"fd")?,
                default: f.field("Default", b"fd")?,
            })
        })()
        .unwrap_or(Role::Other),
        "FMTU" => (|| -> Result<Role, String> {
            Ok(Role::Fmtu {
                ty: f.need("FmtType", b"B")?,
                units: f.need("UnitIds", b"nNZ")?,
                mults: f.need("MultIds", b"nNZ")?,
            })
        })()
        .unwrap_or(Role::Other),
        "UNIT" => (|| -> Result<Role, String> {
            Ok(Role::Unit {
                id: f.need("Id", b"bB")?,
                label: f.need("Label", b"nNZ")?,
            })
        })()
        .unwrap_or(Role::Other),
        "MULT" => (|| -> Result<Role, String> {
            Ok(Role::Mult {
                id: f.need("Id", b"bB")?,
                mult: f.need("Mult", b"fd")?,
            })
        })()
        .unwrap_or(Role::Other),
        "IMU" | "IMU2" | "IMU3" => unreadable((|| {
            let column = |name: &str| f.fields.iter().position(|(n, _)| n == name).unwrap_or(0);
            let names = ["GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ", "T"];
            let instance = match f.field("I", INTS)? {
                Some(i) => Ok(i),
                None => Err(match f.name.as_str() {
                    "IMU2" => 1,
                    "IMU3" => 2,
                    _ => 0,
                }),
            };
            Ok(Role::Imu(ImuFields {
                time: f.need("TimeUS", b"Q")?,
                instance,
                gyro: [
                    f.need("GyrX", b"f")?,
                    f.need("GyrY", b"f")?,
                    f.need("GyrZ", b"f")?,
                ],
                accel: [
                    f.need("AccX", b"f")?,
                    f.need("AccY", b"f")?,
                    f.need("AccZ", b"f")?,
                ],
                temperature: f.field("T", b"f")?,
                columns: names.map(column),
            }))
        })()),
        "ISBH" => unreadable((|| {
            Ok(Role::Isbh(IsbhFields {
                n: f.need("N", INTS)?,
                ty: f.need("type", INTS)?,
                instance: f.need("instance", INTS)?,
                mul: f.need("mul", b"HIf")?,
                count: f.need("smp_cnt", INTS)?,
                sample_us: f.need("SampleUS", b"Q")?,
                rate: f.need("smp_rate", b"fd")?,
            }))
        })()),
        "ISBD" => unreadable((|| {
            Ok(Role::Isbd(IsbdFields {
                n: f.need("N", INTS)?,
                seqno: f.need("seqno", INTS)?,
                xyz: [f.need("x", b"a")?, f.need("y", b"a")?, f.need("z", b"a")?],
            }))
        })()),
        _ => Role::Other,
    }
}

/// The format an `FMT` payload defines (type, then the format), or `None` when it
/// contradicts itself: an unknown format character, a length that is not the fields' sum and
/// the header, columns that do not name every field, or an `FMT` of `FMT` that is not 89
/// bytes of "BBnNZ".
fn parse_fmt(p: &[u8]) -> Option<(u8, Format)> {
    let text = |at: usize, len: usize| -> Option<String> {
        let bytes = p.get(at..at + len)?;
        let end = bytes.iter().position(|&b| b == 0).unwrap_or(len);
        Some(String::from_utf8_lossy(bytes.get(..end)?).into_owned())
    };
    let ty = *p.first()?;
    let len = usize::from(*p.get(1)?);
    let name = text(2, 4)?;
    let chars = text(6, 16)?;
    let columns = text(22, 64)?;
    let names: Vec<&str> = if columns.is_empty() {
        Vec::new()
    } else {
        columns.split(',').collect()
    };
    if name.is_empty() || names.len() != chars.len() {
        return None;
    }
    let mut fields = Vec::with_capacity(chars.len());
    let mut at = 0usize;
    for (&ch, column) in chars.as_bytes().iter().zip(&names) {
        fields.push((column.to_string(), Field { at, ch }));
        at += char_size(ch)?;
    }
    if at + 3 != len || (ty == FMT_TYPE && (len != FMT_LEN || chars != "BBnNZ")) {
        return None;
    }
    let mut format = Format {
        name,
        len,
        fields,
        role: Role::Other,
    };
    format.role = role(&format);
    Some((ty, format))
}

/// An `IMU` message decoded.
struct ImuMessage {
    time_us: f64,
    instance: u8,
    gyro: [f64; 3],
    accel: [f64; 3],
    temperature: Option<f64>,
}

/// An `ISBH` message decoded.
#[derive(Clone, Copy)]
struct Header {
    n: u16,
    /// `None`: a sensor type other than 0 (accel) or 1 (gyro).
    kind: Option<Kind>,
    instance: u8,
    mul: f64,
    count: usize,
    sample_us: f64,
    rate: f64,
}

impl Header {
    /// Whether its samples can be rebuilt: a sensor type, samples, a multiplier and a sample
    /// rate that are positive numbers, and sample times up to [`MAX_TIME_US`].
    fn valid(&self) -> bool {
        self.kind.is_some()
            && self.count > 0
            && self.mul > 0.0
            && self.mul.is_finite()
            && self.rate > 0.0
            && self.rate.is_finite()
            && self.sample_us + self.count as f64 * 1e6 / self.rate <= MAX_TIME_US as f64
    }
}

/// An `ISBD` message decoded.
struct Block {
    n: u16,
    seqno: u64,
    xyz: [[i16; BLOCK]; 3],
}

/// An IMU message for a pass.
enum Event {
    Imu(ImuMessage),
    Isbh(Header),
    Isbd(Block),
}

/// A batch closed: complete (its samples when kept) or dropped.
struct Closed {
    kind: Kind,
    instance: u8,
    complete: bool,
    count: usize,
    mul: f64,
    sample_us: f64,
    rate: f64,
    samples: Vec<[i16; 3]>,
}

impl Closed {
    /// The time of sample `j` in µs.
    fn time(&self, j: usize) -> f64 {
        self.sample_us + j as f64 * 1e6 / self.rate
    }
}

/// A batch being read.
struct Open {
    header: Header,
    kind: Kind,
    /// The next block expected.
    next: u64,
    /// A block came out of order: the batch is dropped.
    holed: bool,
    samples: Vec<[i16; 3]>,
}

impl Open {
    /// Blocks the batch holds.
    fn blocks(&self) -> u64 {
        self.header.count.div_ceil(BLOCK) as u64
    }

    /// The batch closed, `complete` or dropped.
    fn close(self, complete: bool) -> Closed {
        Closed {
            kind: self.kind,
            instance: self.header.instance,
            complete,
            count: self.header.count,
            mul: self.header.mul,
            sample_us: self.header.sample_us,
            rate: self.header.rate,
            samples: self.samples,
        }
    }
}

/// The batches being read, their samples kept (`keep`) or only counted.
struct Batches {
    open: Vec<Open>,
    keep: bool,
}

impl Batches {
    /// None open; samples kept when `keep`.
    fn new(keep: bool) -> Self {
        Batches {
            open: Vec::new(),
            keep,
        }
    }

    /// A batch header: opens its batch, and closes (dropped) a batch of the same sensor or
    /// number still open, and the oldest when too many are open.
    fn open(&mut self, h: Header) -> Vec<Closed> {
        let mut closed = Vec::new();
        let mut k = 0;
        while k < self.open.len() {
            let o = &self.open[k];
            if o.header.n == h.n || (Some(o.kind) == h.kind && o.header.instance == h.instance) {
                closed.push(self.open.remove(k).close(false));
            } else {
                k += 1;
            }
        }
        let Some(kind) = h.kind.filter(|_| h.valid()) else {
            return closed;
        };
        if self.open.len() >= MAX_OPEN {
            closed.push(self.open.remove(0).close(false));
        }
        let open = Open {
            header: h,
            kind,
            next: 0,
            holed: false,
            samples: Vec::new(),
        };
        if open.blocks() == 0 {
            closed.push(open.close(true));
        } else {
            self.open.push(open);
        }
        closed
    }

    /// A block: the sensor of its batch (`None` for a block of no open batch), and the batch
    /// when this block completes it.
    fn block(&mut self, b: &Block) -> (Option<(Kind, u8)>, Option<Closed>) {
        let Some(k) = self.open.iter().position(|o| o.header.n == b.n) else {
            return (None, None);
        };
        let Some(o) = self.open.get_mut(k) else {
            return (None, None);
        };
        let source = Some((o.kind, o.header.instance));
        if o.holed {
            return (source, None);
        }
        if b.seqno != o.next {
            o.holed = true;
            return (source, None);
        }
        if self.keep {
            let first = o.next as usize * BLOCK;
            let take = o.header.count.saturating_sub(first).min(BLOCK);
            for i in 0..take {
                o.samples.push([b.xyz[0][i], b.xyz[1][i], b.xyz[2][i]]);
            }
        }
        o.next += 1;
        if o.next == o.blocks() {
            let done = self.open.remove(k).close(true);
            return (source, Some(done));
        }
        (source, None)
    }

    /// Closes every batch still open (dropped).
    fn close_all(&mut self) -> Vec<Closed> {
        self.open.drain(..).map(|o| o.close(false)).collect()
    }
}

/// What a pass found besides the IMU messages.
struct Log {
    messages: u64,
    /// Corrupt `IMU` messages, not passed on.
    corrupt: u64,
    /// Of them, those of each instance (a time no clock reaches; the others name no IMU).
    corrupt_of: [u64; MAX_IMUS as usize],
    parameters: Vec<Parameter>,
    unreadable: Vec<String>,
    skipped_bytes: u64,
    resyncs: u64,
    truncated: Option<u64>,
}

/// The unit ids an `IMU` message's GyrX..AccZ and T must have (`log_Units`): rad/s, m/s/s,
/// degC.
const IMU_UNITS: [u8; 7] = [b'E', b'E', b'E', b'o', b'o', b'o', b'O'];

/// What one pass knows so far.
struct State {
    formats: HashMap<u8, Format>,
    parameters: Vec<Parameter>,
    by_name: HashMap<String, usize>,
    /// Unit labels by id (`UNIT`).
    units: HashMap<u8, String>,
    /// Multipliers by id (`MULT`).
    mults: HashMap<u8, f64>,
}

impl State {
    /// The `FMT` format, which every log starts with and which pymavlink assumes.
    fn new() -> Self {
        let mut fmt = [0u8; FMT_LEN - 3];
        fmt[0] = FMT_TYPE;
        fmt[1] = FMT_LEN as u8;
        fmt[2..5].copy_from_slice(b"FMT");
        fmt[6..11].copy_from_slice(b"BBnNZ");
        let columns = b"Type,Length,Name,Format,Columns";
        fmt[22..22 + columns.len()].copy_from_slice(columns);
        let mut formats = HashMap::new();
        if let Some((ty, f)) = parse_fmt(&fmt) {
            formats.insert(ty, f);
        }
        State {
            formats,
            parameters: Vec::new(),
            by_name: HashMap::new(),
            units: HashMap::new(),
            mults: HashMap::new(),
        }
    }

    /// A `PARM` message.
    fn parameter(&mut self, time: u64, name: String, value: f64, default: Option<f64>) -> bool {
        match self.by_name.get(&name) {
            Some(&at) => {
                if let Some(p) = self.parameters.get_mut(at) {
                    if value.to_bits() != p.value.to_bits() {
                        p.changes += 1;
                        if p.first_changes.len() < KEPT_CHANGES {
                            p.first_changes.push((time, value));
                        }
                    }
                    p.value = value;
                    if default.is_some() {
                        p.default = default;
                    }
                }
                true
            }
            None if self.parameters.len() >= MAX_PARAMETERS => false,
            None => {
                self.by_name.insert(name.clone(), self.parameters.len());
                self.parameters.push(Parameter {
                    name,
                    first: value,
                    value,
                    default,
                    changes: 0,
                    first_changes: Vec::new(),
                });
                true
            }
        }
    }

    /// An `FMTU` message for type `ty`: an `IMU` format whose units are not those expected,
    /// or whose multipliers are not 1 (`0`, or `-`/`?` for none/unknown), becomes unreadable.
    fn units(&mut self, ty: u8, units: &str, mults: &str) {
        let labels = &self.units;
        let factors = &self.mults;
        let Some(f) = self.formats.get_mut(&ty) else {
            return;
        };
        let Role::Imu(fields) = &f.role else {
            return;
        };
        for (column, &want) in fields.columns.iter().zip(&IMU_UNITS) {
            if let Some(&m) = mults.as_bytes().get(*column) {
                // '-' is no multiplier and '?' an unknown one (`log_Multipliers`).
                let one = match factors.get(&m) {
                    _ if matches!(m, b'-' | b'?') => true,
                    Some(&x) => x == 1.0,
                    None => m == b'0',
                };
                if !one {
                    let name = f.fields.get(*column).map_or("?", |(n, _)| n.as_str());
                    f.role = Role::Unreadable(format!(
                        "{}: FMTU gives {name} the multiplier '{}'{}, not 1",
                        f.name,
                        escaped(&char::from(m).to_string()),
                        factors.get(&m).map_or(String::new(), |x| format!(" ({x})"))
                    ));
                    return;
                }
            }
            let Some(&got) = units.as_bytes().get(*column) else {
                continue;
            };
            if got != want {
                let name = f.fields.get(*column).map_or("?", |(n, _)| n.as_str());
                let label = |id: u8| {
                    labels
                        .get(&id)
                        .map_or(String::new(), |l| format!(" ({})", escaped(l)))
                };
                f.role = Role::Unreadable(format!(
                    "{}: FMTU gives {name} the unit '{}'{}, not '{}'{}",
                    f.name,
                    escaped(&char::from(got).to_string()),
                    label(got),
                    char::from(want),
                    match want {
                        b'E' => " (rad/s)",
                        b'o' => " (m/s/s)",
                        _ => " (degC)",
                    }
                ));
                return;
            }
        }
    }
}

/// One pass over the DataFlash log `path`: every `IMU`, `ISBH` and `ISBD` message to `visit`,
/// the rest gathered.
fn scan(path: &Path, visit: &mut dyn FnMut(Event)) -> Result<Log, DataError> {
    let fail = |problem: String| data_error(path, problem);
    let io = |e: std::io::Error| data_error(path, format!("cannot read: {e}"));
    let mut win = Window::open(path).map_err(|e| fail(format!("cannot open: {e}")))?;
    let mut state = State::new();
    let (mut messages, mut skipped, mut resyncs, mut corrupt) = (0u64, 0u64, 0u64, 0u64);
    let mut corrupt_of = [0u64; MAX_IMUS as usize];
    let mut skipping = false;
    let mut truncated = None;
    let mut unreadable: Vec<String> = Vec::new();
    let head = win.peek(16).map_err(io)?;
    if head.starts_with(&crate::ulog::MAGIC) {
        return Err(fail(
            "not a DataFlash log: a PX4 ULog file (read it as ULog)".into(),
        ));
    }
    loop {
        let pos = win.pos();
        let head = win.peek(3).map_err(io)?;
        let len = match head {
            [a, b, ty] if [*a, *b] == HEAD => state.formats.get(ty).map(|f| f.len),
            _ => None,
        };
        let Some(len) = len else {
            if head.len() < 3 {
                // Fewer than 3 bytes left: the head of a message cut short, or garbage.
                if head.starts_with(&HEAD[..head.len().min(2)]) && !head.is_empty() {
                    truncated = Some(pos);
                } else if !head.is_empty() {
                    skipped += head.len() as u64;
                    resyncs += u64::from(!skipping);
                }
                break;
            }
            skipped += 1;
            if !skipping {
                skipping = true;
                resyncs += 1;
            }
            win.consume(1);
            continue;
        };
        let msg = win.peek(len).map_err(io)?;
        if msg.len() < len {
            truncated = Some(pos);
            break;
        }
        let ty = msg[2];
        let p = msg.get(3..).unwrap_or_default();
        let Some(role) = state.formats.get(&ty).map(|f| f.role.clone()) else {
            break;
        };
        match role {
            Role::Fmt => {
                let Some((defined, f)) = parse_fmt(p) else {
                    // An FMT that contradicts itself does not start a message.
                    skipped += 1;
                    if !skipping {
                        skipping = true;
                        resyncs += 1;
                    }
                    win.consume(1);
                    continue;
                };
                if let Role::Unreadable(why) = &f.role
                    && !unreadable.contains(why)
                {
                    unreadable.push(why.clone());
                }
                state.formats.insert(defined, f);
            }
            Role::Parm {
                time,
                name,
                value,
                default,
            } => {
                if let (Some(t), Some(n), Some(v)) = (time.u64(p), name.text(p), value.num(p)) {
                    let d = default.and_then(|d| d.num(p));
                    if !state.parameter(t, n, v, d) {
                        return Err(fail(format!(
                            "message {} at byte {pos}: more than {MAX_PARAMETERS} parameters",
                            messages + 1
                        )));
                    }
                }
            }
            Role::Fmtu { ty, units, mults } => {
                if let (Some(t), Some(u), Some(m)) = (ty.num(p), units.text(p), mults.text(p)) {
                    state.units(t as u8, &u, &m);
                    if let Some(Format {
                        role: Role::Unreadable(why),
                        ..
                    }) = state.formats.get(&(t as u8))
                        && !unreadable.contains(why)
                    {
                        unreadable.push(why.clone());
                    }
                }
            }
            Role::Unit { id, label } => {
                if let (Some(i), Some(l)) = (id.num(p), label.text(p)) {
                    state.units.insert(i as u8, l);
                }
            }
            Role::Mult { id, mult } => {
                if let (Some(i), Some(m)) = (id.num(p), mult.num(p)) {
                    state.mults.insert(i as u8, m);
                }
            }
            Role::Imu(f) => {
                // An instance no INS holds, or a time no clock reaches: a corrupt message.
                let instance = match f.instance {
                    Ok(i) => i
                        .num(p)
                        .filter(|i| (0.0..f64::from(MAX_IMUS)).contains(i))
                        .map(|i| i as u8),
                    Err(i) => Some(i),
                };
                let num = |f: Field| f.num(p).unwrap_or(f64::NAN);
                if let (Some(time), Some(instance)) = (f.time.time_us(p), instance) {
                    visit(Event::Imu(ImuMessage {
                        time_us: time as f64,
                        instance,
                        gyro: f.gyro.map(num),
                        accel: f.accel.map(num),
                        temperature: f.temperature.map(num),
                    }));
                } else {
                    corrupt += 1;
                    if let Some(i) = instance {
                        corrupt_of[usize::from(i)] += 1;
                    }
                }
            }
            Role::Isbh(f) => {
                let num = |f: Field| f.num(p).unwrap_or(f64::NAN);
                visit(Event::Isbh(Header {
                    n: num(f.n) as u16,
                    kind: match num(f.ty) {
                        0.0 => Some(Kind::BatchAccel),
                        1.0 => Some(Kind::BatchGyro),
                        _ => None,
                    },
                    instance: num(f.instance) as u8,
                    mul: num(f.mul),
                    count: num(f.count) as usize,
                    sample_us: f.sample_us.time_us(p).map_or(f64::NAN, |t| t as f64),
                    rate: num(f.rate),
                }));
            }
            Role::Isbd(f) => {
                let [x, y, z] = f.xyz;
                if let (Some(n), Some(seqno), Some(x), Some(y), Some(z)) = (
                    f.n.num(p),
                    f.seqno.num(p),
                    x.array(p),
                    y.array(p),
                    z.array(p),
                ) {
                    visit(Event::Isbd(Block {
                        n: n as u16,
                        seqno: seqno as u64,
                        xyz: [x, y, z],
                    }));
                }
            }
            Role::Unreadable(_) | Role::Other => {}
        }
        skipping = false;
        win.consume(len);
        messages += 1;
    }
    if let (0, Some(at)) = (messages, truncated) {
        return Err(fail(format!(
            "truncated ArduPilot DataFlash log: it ends inside its first message (at byte {at})"
        )));
    }
    if messages == 0 {
        return Err(fail(format!(
            "not an ArduPilot DataFlash log: no message (A3 95 and a known type) in its {} bytes",
            win.pos()
        )));
    }
    let mut parameters = state.parameters;
    parameters.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(Log {
        messages,
        corrupt,
        corrupt_of,
        parameters,
        unreadable,
        skipped_bytes: skipped,
        resyncs,
        truncated,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scratch;

    #[test]
    fn half_precision_numbers_decode_as_ieee_754_says() {
        for (bits, want) in [
            (0x3c00, 1.0),
            (0xc000, -2.0),
            (0x7bff, 65504.0),
            (0x0001, 2f64.powi(-24)),
            (0x0400, 2f64.powi(-14)),
            (0x3555, 0.333_251_953_125),
            (0x8000, -0.0),
            (0x7c00, f64::INFINITY),
            (0xfc00, f64::NEG_INFINITY),
        ] {
            assert_eq!(f16(bits), want, "{bits:#06x}");
        }
        assert!(f16(0x7e00).is_nan());
    }

    #[test]
    fn a_format_that_contradicts_itself_is_no_format() {
        let fmt = |ty: u8, len: u8, name: &str, chars: &str, columns: &str| {
            let mut p = vec![ty, len];
            for (text, n) in [(name, 4), (chars, 16), (columns, 64)] {
                let mut b = text.as_bytes().to_vec();
                b.resize(n, 0);
                p.extend_from_slice(&b);
            }
            parse_fmt(&p).map(|(t, f)| (t, f.len, f.fields.len()))
        };
        assert_eq!(fmt(9, 3 + 12, "X", "Qf", "A,B"), Some((9, 15, 2)));
        assert_eq!(fmt(9, 3 + 13, "X", "Qf", "A,B"), None);
        assert_eq!(fmt(9, 3 + 12, "X", "Qf", "A"), None);
        assert_eq!(fmt(9, 3 + 12, "X", "Qx", "A,B"), None);
        assert_eq!(fmt(9, 3 + 12, "", "Qf", "A,B"), None);
        assert_eq!(fmt(FMT_TYPE, 15, "FMT", "Qf", "A,B"), None);
        assert_eq!(
            fmt(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns"),
            Some((128, 89, 5))
        );
    }

    /// The `IMU` message type of the logs [`imu_log`] writes.
    const IMU_TYPE: u8 = 150;

    /// An `FMT` message defining type `ty`, as ArduPilot writes it.
    fn fmt_message(bytes: &mut Vec<u8>, ty: u8, name: &str, chars: &str, columns: &str) {
        let len = 3 + chars
            .bytes()
            .map(|c| char_size(c).unwrap_or(0))
            .sum::<usize>();
        bytes.extend_from_slice(&[HEAD[0], HEAD[1], FMT_TYPE, ty, len as u8]);
        for (text, n) in [(name, 4), (chars, 16), (columns, 64)] {
            let mut b = text.as_bytes().to_vec();
            b.resize(n, 0);
            bytes.extend_from_slice(&b);
        }
    }

    /// A DataFlash log as ArduPilot writes it (the `FMT` of `FMT`, the `FMT` of `IMU` with its
    /// real format string), then one `IMU` message for each (TimeUS, I) of `imus`, with
    /// plausible axes and temperature.
    fn imu_log(imus: &[(u64, u8)]) -> Vec<u8> {
        let mut bytes = Vec::new();
        fmt_message(
            &mut bytes,
            FMT_TYPE,
            "FMT",
            "BBnNZ",
            "Type,Length,Name,Format,Columns",
        );
        fmt_message(
            &mut bytes,
            IMU_TYPE,
            "IMU",
            "QBffffffIIfBBHH",
            "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
        );
        for (k, &(time, instance)) in imus.iter().enumerate() {
            bytes.extend_from_slice(&[HEAD[0], HEAD[1], IMU_TYPE]);
            bytes.extend_from_slice(&time.to_le_bytes());
            bytes.push(instance);
            let wobble = (k % 7) as f32 * 1e-3;
            for v in [0.01 + wobble, -0.02, 0.005, 0.1, -0.2 + wobble, 9.81] {
                bytes.extend_from_slice(&f32::to_le_bytes(v));
            }
            bytes.extend_from_slice(&[0; 8]);
            bytes.extend_from_slice(&30f32.to_le_bytes());
            bytes.extend_from_slice(&[1, 1]);
            bytes.extend_from_slice(&400u16.to_le_bytes());
            bytes.extend_from_slice(&400u16.to_le_bytes());
        }
        bytes
    }

    /// The `IMU` samples of `path`'s one instance (none named), or the read's error.
    fn imu_samples(path: &Path) -> Result<(Vec<Sample>, Report), String> {
        let select = Select {
            kind: Kind::Imu,
            instance: None,
        };
        let mut samples = Vec::new();
        let report =
            read(path, &select, &mut |s| samples.push(s)).map_err(|e| e.problem.clone())?;
        Ok((samples, report))
    }

    /// 400 Hz from 5 s since boot: the times of `n` good `IMU` messages of instance 0.
    fn good(n: u64) -> Vec<(u64, u8)> {
        (0..n).map(|k| (5_000_000 + 2_500 * k, 0)).collect()
    }

    #[test]
    fn an_imu_message_whose_time_no_clock_reaches_is_corrupt_and_skipped() {
        // One message of an SD card's write error in the middle of 400 good ones: TimeUS
        // 14047262688061562948 µs (year 447110), past what i64 nanoseconds hold; and one just
        // past 2^53 µs, which a double no longer holds exactly.
        for bad in [14_047_262_688_061_562_948, u64::MAX, (1 << 53) + 1] {
            let mut imus = good(400);
            imus.insert(200, (bad, 0));
            let file = Scratch::new(&imu_log(&imus), "bin");
            let survey = survey(&file.0).expect("a survey");
            let found = survey.instances(Kind::Imu);
            assert_eq!(found.len(), 1, "{bad}");
            assert_eq!(found[0].messages, 400, "{bad}");
            assert_eq!(
                found[0].span_us,
                Some((5e6, 5e6 + 2_500.0 * 399.0)),
                "{bad}"
            );
            assert_eq!(survey.corrupt, 1, "{bad}");
            let (samples, report) = imu_samples(&file.0).expect("the good samples");
            assert_eq!(report.delivered, 400, "{bad}");
            assert_eq!(report.corrupt, 1, "{bad}");
            assert!(
                samples
                    .windows(2)
                    .all(|w| w[1].time_us - w[0].time_us == 2_500.0),
                "{bad}: one clock, one sample missing"
            );
        }
        // The latest time a message can carry is read.
        let file = Scratch::new(&imu_log(&[(1 << 53, 0)]), "bin");
        let (samples, report) = imu_samples(&file.0).expect("a sample");
        assert_eq!(samples[0].time_us, 2f64.powi(53));
        assert_eq!(report.corrupt, 0);
    }

    #[test]
    fn a_batch_whose_sample_times_no_clock_reaches_is_undecodable() {
        // Two gyro batches of 32 samples at 1 kHz (ISBH, one ISBD block each): the first good,
        // the second's SampleUS the garbage of a corrupt header. Two corrupt IMU messages
        // besides, which a batch read does not count (it counted them before).
        let mut bytes = batch_log(&[(u64::MAX, 0), (5_000_000, 107)]);
        gyro_batches(
            &mut bytes,
            &[(5_000_000, 1000.0), (14_047_262_688_061_562_948, 1000.0)],
        );
        let (times, report) = gyro_batch_times(&bytes).expect("a batch");
        assert_eq!((report.delivered, report.undecodable_batches), (32, 1));
        assert_eq!(report.corrupt, 0);
        assert_eq!(times.last(), Some(&(5e6 + 31_000.0)));
    }

    /// [`imu_log`] with the formats of `ISBH` (151) and `ISBD` (152) after its messages.
    fn batch_log(imus: &[(u64, u8)]) -> Vec<u8> {
        let mut bytes = imu_log(imus);
        fmt_message(
            &mut bytes,
            151,
            "ISBH",
            "QHBBHHQf",
            "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate",
        );
        fmt_message(&mut bytes, 152, "ISBD", "QHHaaa", "TimeUS,N,seqno,x,y,z");
        bytes
    }

    /// Gyro batches of instance 0 (`ISBH` 151, `ISBD` 152, formats of [`batch_log`]), 32
    /// samples each (one block), each at its SampleUS and smp_rate.
    fn gyro_batches(bytes: &mut Vec<u8>, batches: &[(u64, f32)]) {
        gyro_batches_counted(bytes, batches, 32);
    }

    /// [`gyro_batches`] whose headers say `smp_cnt` samples (one block of 32 each).
    fn gyro_batches_counted(bytes: &mut Vec<u8>, batches: &[(u64, f32)], smp_cnt: u16) {
        for (n, &(sample_us, rate)) in (1u16..).zip(batches) {
            bytes.extend_from_slice(&[HEAD[0], HEAD[1], 151]);
            bytes.extend_from_slice(&5_100_000u64.to_le_bytes());
            bytes.extend_from_slice(&n.to_le_bytes());
            bytes.extend_from_slice(&[1, 0]);
            bytes.extend_from_slice(&1u16.to_le_bytes());
            bytes.extend_from_slice(&smp_cnt.to_le_bytes());
            bytes.extend_from_slice(&sample_us.to_le_bytes());
            bytes.extend_from_slice(&rate.to_le_bytes());
            bytes.extend_from_slice(&[HEAD[0], HEAD[1], 152]);
            bytes.extend_from_slice(&5_100_000u64.to_le_bytes());
            bytes.extend_from_slice(&n.to_le_bytes());
            bytes.extend_from_slice(&0u16.to_le_bytes());
            for v in 0..96i16 {
                bytes.extend_from_slice(&(v % 13 - 6).to_le_bytes());
            }
        }
    }

    /// The sample times of the gyro batches of instance 0 in the log `bytes`, and the report.
    fn gyro_batch_times(bytes: &[u8]) -> Result<(Vec<f64>, Report), DataError> {
        let file = Scratch::new(bytes, "bin");
        let select = Select {
            kind: Kind::BatchGyro,
            instance: Some(0),
        };
        let mut times = Vec::new();
        let report = read(&file.0, &select, &mut |s| times.push(s.time_us))?;
        Ok((times, report))
    }

    #[test]
    fn batches_their_blocks_leave_short_are_named_where_nothing_else_is_read() {
        // Headers of 64 samples, one block of 32 each, and no IMU messages: the log was said
        // to hold no IMU messages, before.
        let mut bytes = batch_log(&[]);
        let batches: Vec<(u64, f32)> = (0..4).map(|k| (6_000_000 + k * 100_000, 1000.0)).collect();
        gyro_batches_counted(&mut bytes, &batches, 64);
        let e = crate::source::refusal(&bytes, "bin", &["gx", "gy", "gz"]);
        assert!(
            e.contains("no finite samples of ISB gyro") && e.contains("4 batches dropped"),
            "{e}"
        );
    }

    #[test]
    fn batch_headers_that_cannot_be_rebuilt_are_counted_in_the_survey() {
        // Rates of 0, NaN, -1000 and a good one: three undecodable, one batch (the log was
        // said to hold no ISB gyro batches, before).
        let mut bytes = batch_log(&[(5_000_000, 0)]);
        let rates = [0.0, f32::NAN, -1000.0, 1000.0];
        let batches: Vec<(u64, f32)> = (0..4)
            .map(|k| (6_000_000 + k * 100_000, rates[k as usize]))
            .collect();
        gyro_batches(&mut bytes, &batches);
        let file = Scratch::new(&bytes, "bin");
        let survey = survey(&file.0).expect("a survey");
        assert_eq!(survey.undecodable_batches, 3);
        assert_eq!(survey.instances(Kind::BatchGyro)[0].batches, 1);
    }

    #[test]
    fn batches_whose_rate_runs_one_into_the_next_are_refused_naming_the_rate() {
        // Two batches of 32 at a header rate of 1 kHz, the second starting 30.5 ms after the
        // first, whose last sample lies at 31 ms: its samples interleaved the next's, refused
        // as "not after" with the --drop-backward hint, which dropped half a batch, before.
        let mut bytes = batch_log(&[(5_000_000, 0)]);
        let mut apart = bytes.clone();
        gyro_batches(&mut bytes, &[(5_000_000, 1000.0), (5_030_500, 1000.0)]);
        let e = gyro_batch_times(&bytes).unwrap_err().to_string();
        assert!(
            e.contains("runs to 5031000 us") && e.contains("1016.393 Hz or more"),
            "{e}"
        );
        // A sample's length apart, or just past the last sample, they are read.
        gyro_batches(&mut apart, &[(5_000_000, 1000.0), (5_031_001, 1000.0)]);
        let (times, report) = gyro_batch_times(&apart).expect("two batches");
        assert_eq!(report.delivered, 64);
        assert!(times.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn an_instance_counts_its_own_corrupt_messages_and_those_that_name_none() {
        // Three IMUs, 100 messages each, every tenth of each with a TimeUS no clock reaches,
        // and one whose I byte reads 107: instance 0 lost 10 (and perhaps the stray one), not
        // the log's 31 (30 before).
        let mut imus: Vec<(u64, u8)> = (0..100u64)
            .flat_map(|k| {
                (0..3).map(move |i| {
                    let t = if k % 10 == 5 {
                        u64::MAX
                    } else {
                        5_000_000 + 2_500 * k
                    };
                    (t, i)
                })
            })
            .collect();
        imus.push((5_000_000 + 2_500 * 100, 107));
        let file = Scratch::new(&imu_log(&imus), "bin");
        assert_eq!(survey(&file.0).expect("a survey").corrupt, 31);
        for instance in 0..3 {
            let select = Select {
                kind: Kind::Imu,
                instance: Some(instance),
            };
            let report = read(&file.0, &select, &mut |_| {}).expect("an instance");
            assert_eq!((report.delivered, report.corrupt), (90, 11), "{instance}");
        }
    }

    #[test]
    fn an_imu_instance_past_ardupilots_five_imus_is_corrupt_and_skipped() {
        // One message whose I byte reads 107 (and one 5, the sixth IMU no INS holds) among 400
        // of instance 0: one IMU, read without --instance.
        let mut imus = good(400);
        imus.insert(200, (5_000_000 + 2_500 * 200 + 1_000, 107));
        imus.insert(300, (5_000_000 + 2_500 * 300 + 1_000, 5));
        let file = Scratch::new(&imu_log(&imus), "bin");
        let survey = survey(&file.0).expect("a survey");
        let found: Vec<(u8, u64)> = survey
            .instances(Kind::Imu)
            .iter()
            .map(|s| (s.instance, s.messages))
            .collect();
        assert_eq!(found, vec![(0, 400)]);
        assert_eq!(survey.corrupt, 2);
        let (samples, report) = imu_samples(&file.0).expect("instance 0, the only one");
        assert_eq!((samples.len(), report.corrupt), (400, 2));
        // Five IMUs (instances 0 to 4) are ArduPilot's most: each is one, and without
        // --instance the refusal gives each one's messages.
        let imus: Vec<(u64, u8)> = (0..50u64)
            .flat_map(|k| (0..5).map(move |i| (5_000_000 + 2_500 * k, i)))
            .collect();
        let file = Scratch::new(&imu_log(&imus), "bin");
        let survey = super::survey(&file.0).expect("a survey");
        assert_eq!(survey.instances(Kind::Imu).len(), 5);
        assert_eq!(survey.corrupt, 0);
        let e = imu_samples(&file.0).expect_err("five instances");
        assert!(e.contains("instance 4 (50 messages)"), "{e}");
    }
}
