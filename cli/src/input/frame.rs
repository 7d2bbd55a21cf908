//! One IMU message as the ROS readers ([`super::bag`], [`super::mcap`]) deliver it, what they
//! skipped, and what the two readers share: the little-endian and big-endian field access that
//! cannot panic, and the tally that delivers the finite frames and counts the others.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::input::csv::DataError;

/// One IMU message: the header stamp in nanoseconds since the epoch, and the six axes in the
/// message's SI units (rad/s, m/s^2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The message's `header.stamp` in nanoseconds since the epoch.
    pub stamp_ns: i64,
    /// angular_velocity.x, .y, .z, linear_acceleration.x, .y, .z
    pub axes: [f64; 6],
}

/// What a reader skipped, counted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skipped {
    /// Messages on the topic that could not be decoded (too short, bad encapsulation, ...).
    pub undecodable: u64,
    /// Messages with a NaN or infinite value in one of the six axes.
    pub non_finite: u64,
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
/// Where angular_velocity starts among those float64s.
const ANGULAR: usize = 13;
/// Where linear_acceleration starts among those float64s.
const LINEAR: usize = 25;

/// The six axes of the float64 fields of a `sensor_msgs/Imu` that start at byte `at` of
/// `bytes`: `None` when `bytes` is too short.
pub(crate) fn imu_axes(bytes: &[u8], at: usize, big: bool) -> Option<[f64; 6]> {
    let end = at.checked_add(IMU_F64S * 8)?;
    if bytes.len() < end {
        return None;
    }
    let field = |i: usize| f64_at(bytes, at.checked_add(i * 8)?, big);
    Some([
        field(ANGULAR)?,
        field(ANGULAR + 1)?,
        field(ANGULAR + 2)?,
        field(LINEAR)?,
        field(LINEAR + 1)?,
        field(LINEAR + 2)?,
    ])
}

/// A stamp of `sec` seconds and `nanosec` nanoseconds in nanoseconds (no overflow: `sec` is a
/// 32-bit number).
pub(crate) fn stamp_ns(sec: i64, nanosec: u32) -> i64 {
    sec * 1_000_000_000 + i64::from(nanosec)
}

/// Delivers the finite frames of one read to its consumer and counts the others.
pub(crate) struct Tally<'a> {
    each: &'a mut dyn FnMut(Frame),
    delivered: u64,
    skipped: Skipped,
}

impl<'a> Tally<'a> {
    /// A tally delivering to `each`.
    pub(crate) fn new(each: &'a mut dyn FnMut(Frame)) -> Self {
        Tally {
            each,
            delivered: 0,
            skipped: Skipped::default(),
        }
    }

    /// One message on the topic: delivered when decoded (`Some`) and finite, counted otherwise.
    pub(crate) fn offer(&mut self, frame: Option<Frame>) {
        match frame {
            None => self.skipped.undecodable += 1,
            Some(f) if f.axes.iter().all(|v| v.is_finite()) => {
                self.delivered += 1;
                (self.each)(f);
            }
            Some(_) => self.skipped.non_finite += 1,
        }
    }

    /// What was skipped; an error when no frame was delivered.
    pub(crate) fn finish(self, file: &Path, topic: &str) -> Result<Skipped, DataError> {
        if self.delivered > 0 {
            return Ok(self.skipped);
        }
        let Skipped {
            undecodable,
            non_finite,
        } = self.skipped;
        let problem = if non_finite == 0 {
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
