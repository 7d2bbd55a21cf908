//! Six-axis sensor readers on embedded-hal 1.0: MPU-6050 over I2C, ICM-42688-P over SPI, and
//! a replay source.
//!
//! The estimators need raw counts with exact FIFO accounting and nothing else, so these readers
//! are thin: probe, reset, configure rates and ranges, read one sample or a batch from the
//! FIFO, detect and recover from FIFO overflow (counted, and reported as
//! [`Error::FifoOverflow`], never silently), and give the bus back with `destroy()`. Full driver
//! crates (`mpu6050-dmp`, `icm426xx`, ...) cover far more of the chips (DMP, interrupts, wake on
//! motion) and differ in how much of the FIFO bookkeeping they expose; a firmware that already
//! uses one plugs it in by implementing [`ImuReader`] for a small wrapper around it: `read`
//! returns its latest raw counts, `scale` its configured ranges.
//!
//! Units are typed ([`GyroUnit`], [`AccelUnit`]); the conversion factors are the datasheet
//! sensitivities of the configured full-scale range.

mod icm42688;
mod mpu6050;
mod replay;

use core::fmt;

pub use icm42688::{Icm42688, Icm42688Config, IcmAccelRange, IcmGyroRange, Odr};
pub use mpu6050::{AccelRange, Dlpf, GyroRange, Mpu6050, Mpu6050Config};
pub use replay::Replay;

/// One six-axis reading in raw counts, in the sensor's axes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawSample {
    /// Accelerometer x, y, z.
    pub accel: [i16; 3],
    /// Gyroscope x, y, z.
    pub gyro: [i16; 3],
    /// Raw temperature, where the chip reports one with this sample (see the reader's
    /// `temperature_celsius`).
    pub temperature: Option<i16>,
}

/// The unit of angular rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GyroUnit {
    /// Degrees per second.
    DegPerSec,
    /// Radians per second.
    RadPerSec,
}

/// The unit of specific force.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelUnit {
    /// Standard gravity, 9.80665 m/s^2.
    G,
    /// Metres per second squared.
    MetersPerSec2,
}

/// Sensitivities of the configured full-scale ranges.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Scale {
    /// Counts per degree per second.
    pub gyro_counts_per_dps: f32,
    /// Counts per g.
    pub accel_counts_per_g: f32,
}

impl Scale {
    /// One gyro count in `unit`.
    pub fn gyro_lsb(&self, unit: GyroUnit) -> f32 {
        let dps = 1.0 / self.gyro_counts_per_dps;
        match unit {
            GyroUnit::DegPerSec => dps,
            GyroUnit::RadPerSec => dps * (core::f32::consts::PI / 180.0),
        }
    }

    /// One accelerometer count in `unit`.
    pub fn accel_lsb(&self, unit: AccelUnit) -> f32 {
        let g = 1.0 / self.accel_counts_per_g;
        match unit {
            AccelUnit::G => g,
            AccelUnit::MetersPerSec2 => g * 9.806_65,
        }
    }

    /// The angular rate of `raw` in `unit`.
    ///
    /// ```
    /// use imu_ar::sensor::{GyroUnit, Scale};
    ///
    /// // MPU-6050 at +-250 deg/s: 131 counts per deg/s.
    /// let s = Scale { gyro_counts_per_dps: 131.0, accel_counts_per_g: 16384.0 };
    /// assert_eq!(s.gyro([131, -262, 0], GyroUnit::DegPerSec), [1.0, -2.0, 0.0]);
    /// ```
    pub fn gyro(&self, raw: [i16; 3], unit: GyroUnit) -> [f32; 3] {
        let lsb = self.gyro_lsb(unit);
        raw.map(|c| f32::from(c) * lsb)
    }

    /// The specific force of `raw` in `unit`.
    pub fn accel(&self, raw: [i16; 3], unit: AccelUnit) -> [f32; 3] {
        let lsb = self.accel_lsb(unit);
        raw.map(|c| f32::from(c) * lsb)
    }
}

/// FIFO accounting of a reader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoStats {
    /// Samples delivered from the FIFO.
    pub samples: u64,
    /// FIFO overflows detected (each followed by a FIFO reset).
    pub overflows: u64,
    /// Complete samples that were in the FIFO when it was reset after an overflow, and so
    /// lost. Samples the chip dropped while its FIFO was full are not knowable from the FIFO and
    /// are not included: count the overflows, or compare with the output data rate.
    pub discarded: u64,
    /// FIFO packets rejected as malformed (wrong header) and skipped.
    pub malformed: u64,
    /// Chip resets detected ([`Error::SensorReset`]) and recovered from.
    pub resets: u64,
    /// Samples the chip would have delivered during the outages passed to `recover`: from the
    /// last good FIFO read to the FIFO running again, at the configured output data rate.
    pub lost: u64,
}

/// A reader's error: the bus's own, or one of the reader's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The bus failed; the reader is unchanged and can be used again.
    Bus(E),
    /// WHO_AM_I did not identify a supported chip.
    WrongDevice {
        /// The value read.
        found: u8,
    },
    /// The FIFO had overflowed; it was reset and is collecting again (see [`FifoStats`]).
    FifoOverflow {
        /// Complete samples lost by the reset.
        discarded: u16,
    },
    /// The FIFO is not enabled (call `enable_fifo` first).
    FifoDisabled,
    /// The chip has reset itself (a supply glitch or brown-out): its FIFO is off and its
    /// configuration gone. Call the reader's `recover`.
    SensorReset,
    /// No sample is available (a replay at its end).
    NoData,
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Error::Bus(e)
    }
}

impl<E: fmt::Debug> fmt::Display for Error<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Bus(e) => write!(f, "bus error: {e:?}"),
            Self::WrongDevice { found } => write!(f, "unexpected WHO_AM_I 0x{found:02x}"),
            Self::FifoOverflow { discarded } => {
                write!(f, "FIFO overflow: reset, {discarded} samples discarded")
            }
            Self::FifoDisabled => f.write_str("FIFO is not enabled"),
            Self::SensorReset => f.write_str("the sensor has reset itself: recover it"),
            Self::NoData => f.write_str("no sample available"),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for Error<E> {}

/// A source of six-axis raw samples with known sensitivities.
pub trait ImuReader {
    /// The bus's error type.
    type BusError;

    /// The sensitivities of the configured ranges.
    fn scale(&self) -> Scale;

    /// The latest sample from the data registers.
    ///
    /// # Errors
    ///
    /// [`Error::Bus`] when a transfer fails; [`Error::NoData`] from a source that has none.
    fn read(&mut self) -> Result<RawSample, Error<Self::BusError>>;

    /// Up to `out.len()` samples from the FIFO, oldest first; returns how many were written.
    ///
    /// # Errors
    ///
    /// [`Error::FifoOverflow`] after resetting an overflowed FIFO (nothing is written; call
    /// again), [`Error::SensorReset`] when the FIFO is empty because the chip has reset
    /// itself, [`Error::FifoDisabled`], or [`Error::Bus`].
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<Self::BusError>>;

    /// FIFO accounting so far.
    fn fifo_stats(&self) -> FifoStats;
}

/// Big-endian `i16` at `b[i..i + 2]`.
#[inline]
fn be_i16(b: &[u8], i: usize) -> i16 {
    match b.get(i..i + 2) {
        Some(&[hi, lo]) => i16::from_be_bytes([hi, lo]),
        _ => 0,
    }
}

/// Three big-endian `i16` from `b[i..i + 6]`.
#[inline]
fn be_i16x3(b: &[u8], i: usize) -> [i16; 3] {
    [be_i16(b, i), be_i16(b, i + 2), be_i16(b, i + 4)]
}

/// What a FIFO packet turned out to be.
pub(crate) enum Packet {
    /// A sample.
    Sample(RawSample),
    /// A packet of the wrong layout: skipped and counted.
    Malformed,
    /// The chip's "FIFO empty" marker: the batch ends.
    End,
}

/// Packets read per bus transfer.
const CHUNK: usize = 8;
/// The longest FIFO packet of the supported chips.
const MAX_PACKET: usize = 16;

impl FifoStats {
    /// Counts a recovery after an outage of `outage_us` microseconds at `rate_hz`.
    pub(crate) fn recovered(&mut self, outage_us: u32, rate_hz: f32) {
        self.resets = self.resets.saturating_add(1);
        // `as` saturates (and maps NaN to 0).
        let lost = libm::round(f64::from(outage_us) * f64::from(rate_hz) * 1e-6) as u64;
        self.lost = self.lost.saturating_add(lost);
    }

    /// Counts an overflow whose reset lost the complete packets in `bytes` bytes of FIFO.
    pub(crate) fn overflow<E>(&mut self, bytes: u16, packet: usize) -> Error<E> {
        // Clamped as in `drain`: never a division by zero or a truncated packet size.
        let discarded = bytes / packet.clamp(1, MAX_PACKET) as u16;
        self.overflows = self.overflows.saturating_add(1);
        self.discarded = self.discarded.saturating_add(u64::from(discarded));
        Error::FifoOverflow { discarded }
    }

    /// Reads `available` whole packets of `packet` bytes (at most `out.len()` samples), 8 per
    /// transfer through `read`, and parses them into `out`. A failed transfer loses the
    /// packets read before it: they are counted as discarded.
    pub(crate) fn drain<E>(
        &mut self,
        available: usize,
        packet: usize,
        out: &mut [RawSample],
        mut read: impl FnMut(&mut [u8]) -> Result<(), Error<E>>,
        parse: impl Fn(&[u8]) -> Packet,
    ) -> Result<usize, Error<E>> {
        let packet = packet.clamp(1, MAX_PACKET);
        let mut buf = [0u8; MAX_PACKET * CHUNK];
        let (mut remaining, mut delivered) = (available, 0);
        while remaining > 0 && delivered < out.len() {
            let n = remaining.min(CHUNK).min(out.len() - delivered);
            let bytes = &mut buf[..n * packet];
            if let Err(e) = read(bytes) {
                self.discarded = self.discarded.saturating_add(delivered as u64);
                return Err(e);
            }
            remaining -= n;
            for p in bytes.chunks_exact(packet) {
                match parse(p) {
                    Packet::Sample(s) => {
                        if let Some(slot) = out.get_mut(delivered) {
                            *slot = s;
                            delivered += 1;
                        }
                    }
                    Packet::Malformed => self.malformed = self.malformed.saturating_add(1),
                    Packet::End => {
                        remaining = 0;
                        break;
                    }
                }
            }
        }
        self.samples = self.samples.saturating_add(delivered as u64);
        Ok(delivered)
    }
}
