//! One IMU message as the ROS readers ([`super::bag`], [`super::mcap`]) deliver it, what they
//! skipped, and what the two readers share: the little-endian and big-endian field access that
//! cannot panic, and the tally that delivers the finite frames and counts the others, and the
//! messages that mark their gyro or accelerometer as not provided (the first element of its
//! covariance -1, sensor_msgs/Imu), for [`Skipped::not_provided`] to refuse reading that
//! sensor.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::csv::DataError;
use crate::error::escaped;

/// One IMU message: the header stamp in nanoseconds since the epoch, the six axes in the
/// message's SI units (rad/s, m/s^2), and the sensors it marks as not provided.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// The message's `header.stamp` in nanoseconds since the epoch.
    pub stamp_ns: i64,
    /// angular_velocity.x, .y, .z, linear_acceleration.x, .y, .z
    pub axes: [f64; 6],
    /// The sensors whose values the message says to disregard.
    pub not_provided: NotProvided,
}

/// What a reader skipped, counted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skipped {
    /// Messages on the topic that could not be decoded (too short, bad encapsulation, ...).
    pub undecodable: u64,
    /// Messages with a NaN or infinite value in one of the six axes.
    pub non_finite: u64,
    /// Messages of another IMU on the topic than the one `--frame-id` chose.
    pub other_frame_id: u64,
    /// Messages that mark a sensor read as not provided, among a record whose other messages
    /// provide it (a driver's placeholder while the sensor restarts): their values are not
    /// measurements.
    pub disregarded: u64,
    /// Samples kept in file order though their stamp is not after the one before: a CSV
    /// read at a given rate, its stamps only a check.
    pub backward_kept: u64,
    /// Samples of a log's gyro or accelerometer without a partner of the same time in the
    /// other (a PX4 ULog file's two topics read together).
    pub unpaired: u64,
    /// Logs whose last message the end of the file cuts short (a PX4 ULog file or an
    /// ArduPilot DataFlash log written until the power went): the samples before it are read.
    pub cut_short: u64,
    /// Delivered messages that mark their gyro as not provided
    /// (`angular_velocity_covariance[0] = -1`): their angular_velocity is no measurement.
    pub gyro_not_provided: u64,
    /// Delivered messages that mark their accelerometer as not provided
    /// (`linear_acceleration_covariance[0] = -1`): their linear_acceleration is no
    /// measurement.
    pub accel_not_provided: u64,
}

impl Skipped {
    /// What was lost, in words, when anything was (`None` otherwise): "12 undecodable, 3 not
    /// finite", and the samples kept out of time order. Messages of another IMU
    /// (`other_frame_id`), left out by choice, are not.
    pub fn summary(&self) -> Option<String> {
        let parts: Vec<String> = [
            (
                self.undecodable,
                "undecodable (a batch or message dropped whole)",
            ),
            (self.non_finite, "not finite"),
            (self.disregarded, "marking a sensor read as not provided"),
            (self.unpaired, "without a partner of the other sensor"),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect();
        let skipped =
            (!parts.is_empty()).then(|| format!("messages skipped: {}", parts.join(", ")));
        let kept = (self.backward_kept > 0).then(|| {
            format!(
                "{} samples stamped before the one before kept in file order, as the rate \
                 given reads them (--drop-backward drops them)",
                self.backward_kept
            )
        });
        match (skipped, kept) {
            (Some(s), Some(k)) => Some(format!("{s}; {k}")),
            (s, k) => s.or(k),
        }
    }

    /// The refusal of a read of the gyro's axes (`gyro`) or the accelerometer's (`accel`) of
    /// `total` messages when they mark that sensor as not provided: sensor_msgs/Imu says a
    /// covariance whose first element is -1 means "this estimate is not provided; disregard
    /// it". `None` when no message marks a sensor read.
    ///
    /// ```
    /// use imu_ar_recordings::frame::Skipped;
    /// let gyro_only = Skipped { accel_not_provided: 400, ..Skipped::default() };
    /// assert!(gyro_only.not_provided(true, false, 400).is_none());
    /// let refusal = gyro_only.not_provided(true, true, 400).unwrap();
    /// assert!(refusal.starts_with(
    ///     "the messages mark the accelerometer as not provided: \
    ///      linear_acceleration_covariance[0] = -1 in 400 of the 400"
    /// ));
    /// ```
    pub fn not_provided(&self, gyro: bool, accel: bool, total: u64) -> Option<String> {
        let marked: Vec<String> = [
            (
                gyro,
                self.gyro_not_provided,
                "gyro",
                "angular_velocity",
                "accelerometer's (ax, ay, az)",
            ),
            (
                accel,
                self.accel_not_provided,
                "accelerometer",
                "linear_acceleration",
                "gyro's (gx, gy, gz)",
            ),
        ]
        .iter()
        .filter(|(read, n, ..)| *read && *n > 0)
        .map(|(_, n, sensor, field, other)| {
            format!(
                "the messages mark the {sensor} as not provided: {field}_covariance[0] = -1 \
                 in {n} of the {total} (sensor_msgs/Imu: disregard its values); the {other} \
                 axes can be read alone"
            )
        })
        .collect();
        (!marked.is_empty()).then(|| marked.join("; "))
    }

    /// The warning for a log cut short, when it is.
    pub fn cut_short_warning(&self) -> Option<&'static str> {
        (self.cut_short > 0).then_some(
            "the log ends inside a message (cut short, as when the power goes): the samples \
             before it are read",
        )
    }
}

/// The item of `sorted` (sorted by `name`) named `wanted`.
pub(crate) fn by_name<'a, T>(sorted: &'a [T], wanted: &str, name: fn(&T) -> &str) -> Option<&'a T> {
    let i = sorted.binary_search_by(|t| name(t).cmp(wanted)).ok()?;
    sorted.get(i)
}

/// The `N` bytes at `at`, if `bytes` holds them.
pub(crate) fn bytes_at<const N: usize>(bytes: &[u8], at: usize) -> Option<[u8; N]> {
    let end = at.checked_add(N)?;
    bytes.get(at..end)?.try_into().ok()
}

/// The u32 at `at`, little-endian or (`big`) big-endian.
pub(crate) fn u32_at(bytes: &[u8], at: usize, big: bool) -> Option<u32> {
    let b = bytes_at::<4>(bytes, at)?;
    Some(if big {
        u32::from_be_bytes(b)
    } else {
        u32::from_le_bytes(b)
    })
}

/// The f64 at `at`, little-endian or (`big`) big-endian.
pub(crate) fn f64_at(bytes: &[u8], at: usize, big: bool) -> Option<f64> {
    let b = bytes_at::<8>(bytes, at)?;
    Some(if big {
        f64::from_be_bytes(b)
    } else {
        f64::from_le_bytes(b)
    })
}

/// The float64 fields of `sensor_msgs/Imu` after its header, counted in float64s: orientation
/// (4), its covariance (9), angular_velocity (3), its covariance (9), linear_acceleration (3),
/// its covariance (9).
pub(crate) const IMU_F64S: usize = 37;
/// Where angular_velocity starts among those float64s (its covariance 3 later).
const ANGULAR: usize = 13;
/// Where linear_acceleration starts among those float64s (its covariance 3 later).
const LINEAR: usize = 25;

/// The sensors a `sensor_msgs/Imu` message marks as not provided: the first element of
/// `angular_velocity_covariance`, of `linear_acceleration_covariance`, is -1 ("this estimate
/// is not provided; disregard it").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NotProvided {
    /// `angular_velocity_covariance[0]` is -1.
    pub gyro: bool,
    /// `linear_acceleration_covariance[0]` is -1.
    pub accel: bool,
}

/// The six axes of the float64 fields of a `sensor_msgs/Imu` that start at byte `at` of
/// `bytes`, and the sensors their covariances mark as not provided: `None` when `bytes` is
/// too short.
pub(crate) fn imu_axes(bytes: &[u8], at: usize, big: bool) -> Option<([f64; 6], NotProvided)> {
    let end = at.checked_add(IMU_F64S * 8)?;
    if bytes.len() < end {
        return None;
    }
    let field = |i: usize| f64_at(bytes, at.checked_add(i * 8)?, big);
    let axes = [
        field(ANGULAR)?,
        field(ANGULAR + 1)?,
        field(ANGULAR + 2)?,
        field(LINEAR)?,
        field(LINEAR + 1)?,
        field(LINEAR + 2)?,
    ];
    let not_provided = NotProvided {
        gyro: field(ANGULAR + 3)? == -1.0,
        accel: field(LINEAR + 3)? == -1.0,
    };
    Some((axes, not_provided))
}

/// A stamp of `sec` seconds and `nanosec` nanoseconds in nanoseconds (no overflow: `sec` is a
/// 32-bit number).
pub(crate) fn stamp_ns(sec: i64, nanosec: u32) -> i64 {
    sec * 1_000_000_000 + i64::from(nanosec)
}

/// Which messages of a file to read: those on `topic`, from the publisher whose header
/// frame_id is `frame_id` (when `None`, the topic must carry one IMU).
#[derive(Clone, Copy, Debug)]
pub struct Select<'a> {
    /// The topic.
    pub topic: &'a str,
    /// The frame_id of the IMU to read, when the topic carries several.
    pub frame_id: Option<&'a str>,
    /// Whether messages with a NaN or infinite axis are delivered too (counted all the
    /// same): for a caller that reads their stamps, or the axes that are finite.
    pub non_finite: bool,
}

impl<'a> Select<'a> {
    /// The messages on `topic`, which must carry one IMU.
    pub fn topic(topic: &'a str) -> Self {
        Select {
            topic,
            frame_id: None,
            non_finite: false,
        }
    }
}

/// A publisher seen on the topic: a bag's connection or an MCAP file's channel.
struct Source {
    /// The reader's ID of it.
    id: u32,
    /// Its frame_ids (indices into [`Tally::frame_ids`]), in the order first seen.
    frames: Vec<usize>,
    /// Its first and last stamp among delivered frames.
    span: Option<(i64, i64)>,
}

/// Delivers the finite frames of one read to its consumer and counts the others; keeps
/// apart the IMUs that share the topic (by their header frame_id and their publisher).
pub(crate) struct Tally<'a> {
    each: &'a mut dyn FnMut(Frame),
    frame_id: Option<&'a str>,
    non_finite: bool,
    delivered: u64,
    skipped: Skipped,
    /// Each frame_id seen, with its messages and whether it is the one chosen.
    frame_ids: Vec<(Vec<u8>, u64, bool)>,
    sources: Vec<Source>,
    /// Messages not decoded whose data is a zstd frame (a rosbag2 folder's storage file,
    /// recorded with each message compressed, read without its folder).
    zstd: u64,
}

/// A decoded message: its frame (with the sensors it marks as not provided) and its header's
/// frame_id.
pub(crate) type Decoded<'a> = (Frame, &'a [u8]);

/// A message's decoder: the message decoded, or `None`.
pub(crate) type Decode = fn(&[u8]) -> Option<Decoded<'_>>;

/// The first bytes of a zstd frame.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];

/// The most frame_ids told apart on one topic; more are one error.
const MAX_FRAME_IDS: usize = 16;

impl<'a> Tally<'a> {
    /// A tally delivering the frames `select` asks for to `each`.
    pub(crate) fn new(select: &Select<'a>, each: &'a mut dyn FnMut(Frame)) -> Self {
        Tally {
            each,
            frame_id: select.frame_id,
            non_finite: select.non_finite,
            delivered: 0,
            skipped: Skipped::default(),
            frame_ids: Vec::new(),
            sources: Vec::new(),
            zstd: 0,
        }
    }

    /// [`Tally::offer`] of a message's `data` (none where it is missing), decoded by `decode`.
    pub(crate) fn offer_data(&mut self, source: u32, data: Option<&[u8]>, decode: Decode) {
        let decoded = self.decode(data, decode);
        self.offer(source, decoded);
    }

    /// A message's `data` (none where it is missing) decoded by `decode`, to be offered
    /// later; one that does not decode and is a zstd frame is counted for [`Tally::finish`].
    pub(crate) fn decode<'d>(
        &mut self,
        data: Option<&'d [u8]>,
        decode: Decode,
    ) -> Option<Decoded<'d>> {
        let decoded = data.and_then(decode);
        if decoded.is_none() && data.is_some_and(|d| d.starts_with(&ZSTD_MAGIC)) {
            self.zstd += 1;
        }
        decoded
    }

    /// One message on the topic from publisher `source`, when decoded. Delivered when decoded,
    /// finite (or the selection takes the others too: counted) and of the chosen frame_id
    /// (and counted when it marks a sensor as not provided); counted otherwise.
    pub(crate) fn offer(&mut self, source: u32, decoded: Option<Decoded<'_>>) {
        let Some((frame, frame_id)) = decoded else {
            self.skipped.undecodable += 1;
            return;
        };
        let k = match self.frame_ids.iter().position(|(f, _, _)| f == frame_id) {
            Some(k) => k,
            None if self.frame_ids.len() < MAX_FRAME_IDS => {
                // Chosen as written, or as shown (a frame_id that is not UTF-8).
                let chosen = self
                    .frame_id
                    .is_none_or(|w| w.as_bytes() == frame_id || shown(frame_id) == w);
                self.frame_ids.push((frame_id.to_vec(), 0, chosen));
                self.frame_ids.len() - 1
            }
            None => MAX_FRAME_IDS,
        };
        let chosen = match self.frame_ids.get_mut(k) {
            Some((_, n, chosen)) => {
                *n += 1;
                *chosen
            }
            None => self.frame_id.is_none(),
        };
        if !chosen {
            self.skipped.other_frame_id += 1;
            return;
        }
        if !frame.axes.iter().all(|v| v.is_finite()) {
            self.skipped.non_finite += 1;
            if !self.non_finite {
                return;
            }
        }
        let at = match self.sources.iter().position(|s| s.id == source) {
            Some(at) => at,
            None => {
                self.sources.push(Source {
                    id: source,
                    frames: Vec::new(),
                    span: None,
                });
                self.sources.len() - 1
            }
        };
        if let Some(s) = self.sources.get_mut(at) {
            if !s.frames.contains(&k) {
                s.frames.push(k);
            }
            let t = frame.stamp_ns;
            s.span = Some(s.span.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
        }
        self.delivered += 1;
        self.skipped.gyro_not_provided += u64::from(frame.not_provided.gyro);
        self.skipped.accel_not_provided += u64::from(frame.not_provided.accel);
        (self.each)(frame);
    }

    /// The frame_ids seen, with their messages, for a message.
    fn listed(&self) -> String {
        let mut text: Vec<String> = self
            .frame_ids
            .iter()
            .map(|(f, n, _)| format!("'{}' ({n} messages)", shown(f)))
            .collect();
        if self.frame_ids.len() >= MAX_FRAME_IDS {
            text.push("and more".into());
        }
        text.join(", ")
    }

    /// What was skipped; an error when no frame was delivered, when the topic carries more
    /// than one IMU and none was chosen, or when two publishers of one frame_id overlap in
    /// time. `names` gives a publisher's name by its ID.
    pub(crate) fn finish(
        self,
        file: &Path,
        topic: &str,
        names: &dyn Fn(u32) -> String,
    ) -> Result<Skipped, DataError> {
        if self.frame_id.is_none() && self.frame_ids.len() > 1 {
            return Err(data_error(
                file,
                format!(
                    "{} IMUs publish on '{topic}', told apart by their header frame_id: {}; \
                     read one with --frame-id",
                    if self.frame_ids.len() >= MAX_FRAME_IDS {
                        "more than 16".to_string()
                    } else {
                        self.frame_ids.len().to_string()
                    },
                    self.listed()
                ),
            ));
        }
        let chosen = self.frame_ids.iter().filter(|(_, _, c)| *c).count();
        if let Some(want) = self.frame_id
            && chosen > 1
        {
            return Err(data_error(
                file,
                format!(
                    "--frame-id {}: names more than one IMU on '{topic}' (as written and as \
                     shown: {})",
                    escaped(want),
                    self.listed()
                ),
            ));
        }
        if let Some(want) = self.frame_id
            && chosen == 0
        {
            return Err(data_error(
                file,
                format!(
                    "--frame-id {}: no message on '{topic}' has it (frame_ids: {})",
                    escaped(want),
                    if self.frame_ids.is_empty() {
                        "none".into()
                    } else {
                        self.listed()
                    }
                ),
            ));
        }
        // Publishers of the chosen frame_id whose stamps interleave: two IMUs that cannot be
        // told apart (a publisher that restarted follows the one before, and is read).
        for (i, a) in self.sources.iter().enumerate() {
            for b in self.sources.iter().skip(i + 1) {
                let shared = a.frames.iter().any(|f| b.frames.contains(f));
                if let (true, Some((a0, a1)), Some((b0, b1))) = (shared, a.span, b.span)
                    && a0 <= b1
                    && b0 <= a1
                {
                    return Err(data_error(
                        file,
                        format!(
                            "two publishers on '{topic}' ({} and {}) send the same header \
                             frame_id at interleaved times: two IMUs that the record cannot \
                             tell apart",
                            names(a.id),
                            names(b.id)
                        ),
                    ));
                }
            }
        }
        if self.delivered > 0 {
            return Ok(self.skipped);
        }
        let Skipped {
            undecodable,
            non_finite,
            ..
        } = self.skipped;
        let problem = if non_finite == 0 && self.zstd == undecodable && undecodable > 0 {
            format!(
                "no decodable messages on '{topic}' ({undecodable} undecodable): each is a zstd \
                 frame, as rosbag2 stores messages recorded with --compression-mode message; \
                 they are read through the bag's folder, whose metadata.yaml says \
                 compression_mode: MESSAGE and compression_format: zstd"
            )
        } else if non_finite == 0 {
            format!("no decodable messages on '{topic}' ({undecodable} undecodable)")
        } else {
            format!(
                "no finite messages on '{topic}' ({undecodable} undecodable, {non_finite} with \
                 a NaN or infinite axis)"
            )
        };
        Err(data_error(file, problem))
    }
}

/// A frame_id as messages show it (and `--frame-id` may name it): its text with backslashes
/// and control characters escaped, or, when it is not UTF-8, its bytes with every non-ASCII
/// one as `\xNN` (and a backslash as `\\`).
fn shown(frame_id: &[u8]) -> String {
    match std::str::from_utf8(frame_id) {
        Ok(text) => escaped(&text.replace('\\', "\\\\")),
        Err(_) => frame_id.escape_ascii().to_string(),
    }
}

/// A [`DataError`] about `file` as a whole.
pub(crate) fn data_error(file: &Path, problem: impl Into<String>) -> DataError {
    DataError {
        file: file.to_path_buf(),
        line: None,
        problem: problem.into(),
    }
}

/// `path` opened: the file, its length, and its first `head` bytes (fewer in a shorter file),
/// read; errors name the file.
pub(crate) fn open_head(path: &Path, head: u64) -> Result<(File, u64, Vec<u8>), DataError> {
    let fail = |e: std::io::Error, what: &str| data_error(path, format!("cannot {what}: {e}"));
    let mut file = File::open(path).map_err(|e| fail(e, "open"))?;
    let len = file.metadata().map_err(|e| fail(e, "read"))?.len();
    let mut bytes = Vec::new();
    file.by_ref()
        .take(head)
        .read_to_end(&mut bytes)
        .map_err(|e| fail(e, "read"))?;
    Ok((file, len, bytes))
}

/// The message of a topic that is not in the file: the IMU topics it has (`imu`), or all its
/// topics (`all`) when it has none.
pub(crate) fn absent_topic(imu_type: &str, topic: &str, imu: &[String], all: &[String]) -> String {
    let what = if !imu.is_empty() {
        format!("IMU topics: {}", imu.join(", "))
    } else if !all.is_empty() {
        format!("no IMU topics; topics: {}", all.join(", "))
    } else {
        "no topics".to_string()
    };
    format!("no {imu_type} messages on topic '{topic}' ({what})")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame stamped `t`.
    fn frame(t: i64) -> Frame {
        Frame {
            stamp_ns: t,
            axes: [0.5; 6],
            ..Frame::default()
        }
    }

    #[test]
    fn a_frame_id_named_as_written_and_as_shown_by_two_imus_is_refused() {
        // The text `ab\xffc` (seven characters) and the bytes `ab`, 0xff, `c`: both read
        // `ab\xffc`; shown, the text's backslash is doubled.
        let text: &[u8] = b"ab\\xffc";
        let bytes: &[u8] = b"ab\xffc";
        let file = Path::new("two.bag");
        for (want, result) in [("ab\\xffc", None), ("ab\\\\xffc", Some(10))] {
            let mut got = 0;
            let mut each = |_: Frame| got += 1;
            let select = Select {
                frame_id: Some(want),
                ..Select::topic("/imu")
            };
            let mut tally = Tally::new(&select, &mut each);
            for t in 0..10 {
                tally.offer(1, Some((frame(2 * t), text)));
                tally.offer(2, Some((frame(2 * t + 1), bytes)));
            }
            let finished = tally.finish(file, "/imu", &|id| format!("connection {id}"));
            match result {
                None => {
                    let e = finished.expect_err(want).problem;
                    assert!(e.contains("names more than one IMU"), "{e}");
                }
                Some(other) => {
                    assert_eq!(finished.map(|s| s.other_frame_id), Ok(other));
                    assert_eq!(got, 10);
                }
            }
        }
    }
}
