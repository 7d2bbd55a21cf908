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
//!
//! The two chip readers are one [`Driver`]: [`Mpu6050`] and [`Icm42688`] name it over each
//! chip on its bus ([`Mpu6050Bus`], [`Icm42688Bus`]), whose registers, write sequences and
//! packet layout are all that differs. `init`, `recover`, `enable_fifo` and the FIFO routine
//! (overflow, resync after a failed read, chip-reset detection) are written once.
//!
//! They are written once for async firmware too (embassy, RTIC 2): [`Mpu6050Async`] and
//! [`Icm42688Async`] are the [`AsyncDriver`] over an `embedded-hal-async` bus. The chip logic
//! is `async` code over the chip's transfers; the blocking readers run it over their blocking
//! bus, where every future is ready at its first poll. Both readers make the same transfers and
//! give the same samples and counts.

mod board;
mod chip;
mod driver;
mod fifo;
mod icm42688;
mod io;
mod mpu6050;
mod replay;

use core::fmt;

pub use board::{CycleClock, FifoLoop, Pass, Recover};
pub use driver::{AsyncDriver, Driver};
pub use icm42688::{
    Icm42688, Icm42688Async, Icm42688Bus, Icm42688Config, IcmAccelRange, IcmGyroRange, Odr,
};
pub use io::Async;
pub use mpu6050::{AccelRange, Dlpf, GyroRange, Mpu6050, Mpu6050Async, Mpu6050Bus, Mpu6050Config};
pub use replay::Replay;

/// One six-axis reading in raw counts, in the sensor's axes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawSample {
    /// Accelerometer x, y, z.
    pub accel: [i16; 3],
    /// Gyroscope x, y, z.
    pub gyro: [i16; 3],
    /// Raw temperature, where the chip reports one with this sample: in deg C by
    /// [`ImuReader::die_temperature`] (or the chip's [`Thermometer`]).
    pub temperature: Option<i16>,
}

impl RawSample {
    /// Some gyro axis reads a rail (`i16::MAX` or `i16::MIN`): the chip clipped it.
    pub fn gyro_clipped(&self) -> bool {
        self.gyro.iter().any(|&c| c == i16::MAX || c == i16::MIN)
    }

    /// Some accelerometer axis reads a rail (`i16::MAX` or `i16::MIN`): the chip clipped it.
    pub fn accel_clipped(&self) -> bool {
        self.accel.iter().any(|&c| c == i16::MAX || c == i16::MIN)
    }

    /// Some axis reads a rail: the raw-count test for saturation, which needs no range.
    pub fn clipped(&self) -> bool {
        self.gyro_clipped() || self.accel_clipped()
    }
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

    /// The saturation limit of the gyro axes in `unit`, for
    /// [`Channel::with_saturation`](crate::recursive::Channel::with_saturation): half a count
    /// below the rail `i16::MAX`, so that a clipped reading (`i16::MAX` or `i16::MIN` counts) is
    /// at or beyond it and every reading of at most 32766 counts either way is inside it. (The
    /// estimators' screen is symmetric: -32767 counts, one count from the negative rail, is
    /// rejected too.)
    ///
    /// The nominal range is no limit: at +-1000 deg/s (32.8 counts per deg/s) the rail is
    /// 32767 / 32.8 = 998.99 deg/s, so `with_saturation(1000.0)` never fires.
    ///
    /// ```
    /// use imu_ar::sensor::{GyroUnit, Scale};
    ///
    /// let s = Scale { gyro_counts_per_dps: 32.8, accel_counts_per_g: 2048.0 };
    /// let limit = s.gyro_saturation(GyroUnit::DegPerSec);
    /// assert!(s.gyro([i16::MAX; 3], GyroUnit::DegPerSec)[0] >= limit);
    /// assert!(s.gyro([i16::MAX - 1; 3], GyroUnit::DegPerSec)[0] < limit);
    /// assert!(limit < 1000.0);
    /// ```
    pub fn gyro_saturation(&self, unit: GyroUnit) -> f32 {
        RAIL * self.gyro_lsb(unit)
    }

    /// The saturation limit of the accelerometer axes in `unit`, as
    /// [`Scale::gyro_saturation`].
    pub fn accel_saturation(&self, unit: AccelUnit) -> f32 {
        RAIL * self.accel_lsb(unit)
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

/// A chip's temperature formula: `celsius = raw / counts_per_celsius + offset_celsius`, the
/// linear form both datasheets give.
///
/// | chip | `counts_per_celsius` | `offset_celsius` | source |
/// |---|---|---|---|
/// | MPU-6050 | 340 | 36.53 | RM-MPU-6000A-00 rev 4.2, registers 65-66 (TEMP_OUT) |
/// | ICM-42688-P | 132.48 | 25 | DS-000347 rev 1.8, TEMP_DATA1/0; the 8-bit FIFO temperature `t / 2.07 + 25`, which the reader delivers as `64 t` (132.48 / 64 = 2.07) |
///
/// ```
/// use imu_ar::sensor::Thermometer;
///
/// assert_eq!(Thermometer::MPU6050.celsius(0), 36.53);
/// assert_eq!(Thermometer::ICM42688.celsius(-3312), 0.0); // -3312 / 132.48 = -25
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Thermometer {
    /// Counts per degree Celsius.
    pub counts_per_celsius: f32,
    /// Degrees Celsius at a raw value of 0.
    pub offset_celsius: f32,
}

impl Thermometer {
    /// The MPU-6050's TEMP_OUT: `raw / 340 + 36.53`.
    pub const MPU6050: Self = Self {
        counts_per_celsius: 340.0,
        offset_celsius: 36.53,
    };

    /// The ICM-42688-P's TEMP_DATA: `raw / 132.48 + 25`.
    pub const ICM42688: Self = Self {
        counts_per_celsius: 132.48,
        offset_celsius: 25.0,
    };

    /// The temperature of `raw`, in deg C (rounded once for the division and once for the
    /// sum, in `f32`).
    pub fn celsius(&self, raw: i16) -> f32 {
        f32::from(raw) / self.counts_per_celsius + self.offset_celsius
    }
}

/// Half a count below the positive rail of an `i16` reading.
const RAIL: f32 = 32_766.5;

/// FIFO accounting of a reader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoStats {
    /// Samples delivered from the FIFO.
    pub samples: u64,
    /// FIFO overflows detected (each followed by a FIFO reset, or by the recovery that
    /// replaced it).
    pub overflows: u64,
    /// Complete samples dropped by FIFO resets: those in the FIFO when it was reset after an
    /// overflow or a failed read (counted with the channels off), those already read in a
    /// call that then failed, and those a FIFO left running by a failed `enable_fifo` held
    /// when `enable_fifo` was called again. Samples the chip dropped while its FIFO was full
    /// are not knowable from the FIFO and are not included: count the overflows, or compare
    /// with the output data rate. Samples in the FIFO when `recover` resets the chip are
    /// inside the outage, counted in `lost`.
    pub discarded: u64,
    /// Bytes dropped by FIFO resets, partial packets included.
    pub discarded_bytes: u64,
    /// Samples a data read that failed part-way may have dropped beyond those counted in
    /// `discarded`: `discarded` is exact when this is 0, and short by at most this many
    /// otherwise. The counts before and after a failed transfer tell the bytes it clocked out
    /// only modulo a packet: a sample that entered the FIFO while the transfer clocked out one
    /// packet more leaves the same counts. The smaller number is counted in `discarded`; the
    /// packets the transfer's length leaves room for beyond it are counted here.
    pub unsure: u64,
    /// FIFO resets after a data read that failed part-way ([`Error::FifoResync`]).
    pub resyncs: u64,
    /// FIFO packets rejected as malformed (wrong header, including a "FIFO empty" marker or a
    /// 20-byte packet flag inside the counted bytes) and skipped.
    pub malformed: u64,
    /// FIFO packets skipped because the chip marked their data invalid (the ICM-42688-P writes
    /// -32768, or -128 for the temperature, while a sensor is starting). Data-register reads
    /// (`read`) are not FIFO packets and are not counted here.
    pub invalid: u64,
    /// Delivered samples with some axis at a rail ([`RawSample::clipped`]); they are
    /// delivered, and the estimators' saturation limits decide.
    pub clipped: u64,
    /// Chip resets detected ([`Error::SensorReset`]) and then recovered from: a `recover` that
    /// completes after `read_fifo` (or `enable_fifo`) reported one. A `recover` for any other
    /// reason ([`Error::FifoNotRunning`], a suspected glitch) counts its outage in `lost` but
    /// no reset here.
    pub resets: u64,
    /// Samples the chip would have delivered during the outages passed to `recover`: from the
    /// last `read_fifo` that accounted for the FIFO (`Ok`, [`Error::FifoOverflow`] or
    /// [`Error::FifoResync`]) to the FIFO running again (the end of the successful `recover`,
    /// after its reset delays), at the configured output data rate. Exact when that read
    /// emptied the FIFO (an `out` as large as the FIFO) and the FIFO did not overflow in the
    /// outage.
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
    /// WHO_AM_I identified a chip of the family that this reader does not handle: the
    /// MPU-6500 (0x70) or MPU-9250 (0x71), whose temperature formula, sample-rate divider and
    /// accelerometer filter register differ from the MPU-6050's.
    UnsupportedDevice {
        /// The value read.
        found: u8,
    },
    /// The FIFO had overflowed; it was reset and is collecting again (see [`FifoStats`]).
    FifoOverflow {
        /// Complete samples lost by the reset.
        discarded: u16,
    },
    /// A FIFO data read failed part-way: the FIFO was reset to realign its packets (TDK's own
    /// drivers do the same) and `discarded` complete samples were dropped (see
    /// [`FifoStats`]). Call again.
    FifoResync {
        /// Complete samples dropped.
        discarded: u16,
    },
    /// FIFO_COUNT read above the FIFO's size: no count at all (a bus stuck high, or bit
    /// errors). Nothing was read from the FIFO and nothing counted; call again.
    BadFifoCount {
        /// The value read.
        count: u16,
    },
    /// The FIFO is not enabled (call `enable_fifo` first).
    FifoDisabled,
    /// `enable_fifo` or `recover` before a successful `init`: the chip is not configured.
    NotInitialised,
    /// The FIFO should be on but is not: the last `recover` or `enable_fifo` failed part-way.
    /// Call it again.
    FifoNotRunning,
    /// The chip has reset itself (a supply glitch or brown-out): its FIFO is off and its
    /// configuration gone. Call the reader's `recover`.
    SensorReset,
    /// No sample is available (a replay at its end, or data registers holding the chip's
    /// invalid-data marker).
    NoData,
    /// A register write reported success but did not take: read back, the register (or the
    /// FIFO count a flush should have cleared) says otherwise. SPI has no acknowledge, so a
    /// write corrupted on the wire looks like this, as does a chip that reset itself between
    /// two writes. Nothing was counted for the failed step; call again (`init` or `recover`
    /// for a configuration write, `read_fifo` for a FIFO reset, which is then finished).
    WriteNotApplied {
        /// The register written.
        register: u8,
    },
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
            Self::UnsupportedDevice { found } => write!(
                f,
                "WHO_AM_I 0x{found:02x}: MPU-6500/MPU-9250, not supported by this reader"
            ),
            Self::FifoResync { discarded } => write!(
                f,
                "FIFO read failed part-way: reset, {discarded} samples discarded"
            ),
            Self::FifoNotRunning => f.write_str("FIFO not running: recover again"),
            Self::FifoOverflow { discarded } => {
                write!(f, "FIFO overflow: reset, {discarded} samples discarded")
            }
            Self::BadFifoCount { count } => {
                write!(
                    f,
                    "FIFO_COUNT read {count}, above the FIFO's size: bus fault"
                )
            }
            Self::FifoDisabled => f.write_str("FIFO is not enabled"),
            Self::NotInitialised => f.write_str("the reader is not initialised: call init"),
            Self::SensorReset => f.write_str("the sensor has reset itself: recover it"),
            Self::NoData => f.write_str("no sample available"),
            Self::WriteNotApplied { register } => write!(
                f,
                "the write of register 0x{register:02x} did not take (read back): call again"
            ),
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
    /// [`Error::FifoOverflow`] after resetting an overflowed FIFO and [`Error::FifoResync`]
    /// after resetting it behind a failed read (nothing is written; call again),
    /// [`Error::SensorReset`] when the FIFO is empty because the chip has reset itself,
    /// [`Error::FifoNotRunning`] when a recovery is unfinished, [`Error::FifoDisabled`],
    /// [`Error::BadFifoCount`] when FIFO_COUNT reads above the FIFO's size, or
    /// [`Error::Bus`].
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<Self::BusError>>;

    /// FIFO accounting so far.
    fn fifo_stats(&self) -> FifoStats;

    /// The formula of the raw temperature of this reader's samples: the chip's, for
    /// [`Mpu6050`] and [`Icm42688`]; a [`Replay`]'s when given one
    /// ([`Replay::with_thermometer`]). `None` by default, for a reader that does not know it.
    fn thermometer(&self) -> Option<Thermometer> {
        None
    }

    /// The die temperature of `sample` in deg C, whichever chip it came from: its
    /// [`RawSample::temperature`] through [`ImuReader::thermometer`]. `None` where the sample
    /// carries no temperature (the MPU-6050's FIFO packets hold none: its data registers,
    /// [`ImuReader::read`], do) or the reader has no formula.
    ///
    /// ```
    /// use imu_ar::sensor::{ImuReader, RawSample, Replay, Scale, Thermometer};
    ///
    /// fn celsius(imu: &impl ImuReader, s: &RawSample) -> Option<f32> {
    ///     imu.die_temperature(s)
    /// }
    ///
    /// let scale = Scale { gyro_counts_per_dps: 131.0, accel_counts_per_g: 16384.0 };
    /// let s = RawSample { temperature: Some(3400), ..Default::default() };
    /// let replay = Replay::new(&[], scale).with_thermometer(Thermometer::MPU6050);
    /// assert_eq!(celsius(&replay, &s), Some(46.53));
    /// assert_eq!(celsius(&replay, &RawSample::default()), None);
    /// ```
    fn die_temperature(&self, sample: &RawSample) -> Option<f32> {
        Some(self.thermometer()?.celsius(sample.temperature?))
    }
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
