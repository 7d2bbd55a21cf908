//! InvenSense MPU-6050 over I2C. The MPU-6500 and MPU-9250 answer the same protocol but differ
//! in their temperature formula, in how SMPLRT_DIV applies with the 260 Hz filter and in their
//! accelerometer filter register (ACCEL_CONFIG2, 0x1D): they are rejected with
//! [`Error::UnsupportedDevice`](super::Error::UnsupportedDevice) rather than handled with
//! MPU-6050 formulas.
//!
//! Registers, bits and scale factors from "MPU-6000 and MPU-6050 Register Map and
//! Descriptions", RM-MPU-6000A-00 revision 4.2 (register numbers below), and "MPU-6000 and
//! MPU-6050 Product Specification", PS-MPU-6000A-00 revision 3.4, sections 6.1 (gyro
//! sensitivity) and 6.2 (accelerometer sensitivity).

use embedded_hal::i2c::I2c;
use embedded_hal_async::i2c::I2c as AsyncI2c;

use super::chip::{Check, Chip, Map, Packet, Write};
use super::driver::{AsyncDriver, Driver};
use super::io::{Async, I2cIo};
use super::{RawSample, Scale, Thermometer, be_i16, be_i16x3};

/// Register 25, SMPLRT_DIV: sample rate = gyro output rate / (1 + SMPLRT_DIV).
const SMPLRT_DIV: u8 = 0x19;

/// Register 26, CONFIG: DLPF_CFG in bits 2:0 ([`Dlpf::dlpf_cfg`]).
const CONFIG: u8 = 0x1A;

/// Register 27, GYRO_CONFIG.
const GYRO_CONFIG: u8 = 0x1B;
/// GYRO_CONFIG: FS_SEL in bits 4:3 ([`GyroRange::fs_sel`]).
const FS_SEL_SHIFT: u8 = 3;

/// Register 28, ACCEL_CONFIG.
const ACCEL_CONFIG: u8 = 0x1C;
/// ACCEL_CONFIG: AFS_SEL in bits 4:3 ([`AccelRange::afs_sel`]).
const AFS_SEL_SHIFT: u8 = 3;

/// Register 35, FIFO_EN: the channels written into the FIFO.
const FIFO_EN: u8 = 0x23;
/// FIFO_EN: XG_FIFO_EN, bit 6.
const XG_FIFO_EN: u8 = 0x40;
/// FIFO_EN: YG_FIFO_EN, bit 5.
const YG_FIFO_EN: u8 = 0x20;
/// FIFO_EN: ZG_FIFO_EN, bit 4.
const ZG_FIFO_EN: u8 = 0x10;
/// FIFO_EN: ACCEL_FIFO_EN, bit 3.
const ACCEL_FIFO_EN: u8 = 0x08;
/// Each FIFO packet is accel x, y, z then gyro x, y, z (register order).
const ACCEL_GYRO_FIFO_EN: u8 = XG_FIFO_EN | YG_FIFO_EN | ZG_FIFO_EN | ACCEL_FIFO_EN;

/// Register 56, INT_ENABLE.
const INT_ENABLE: u8 = 0x38;
/// INT_ENABLE: FIFO_OFLOW_EN, bit 4.
const FIFO_OFLOW_EN: u8 = 0x10;

/// Register 58, INT_STATUS, cleared by reading.
const INT_STATUS: u8 = 0x3A;
/// INT_STATUS: FIFO_OFLOW_INT, bit 4.
const FIFO_OFLOW_INT: u8 = 0x10;

/// Registers 59-72: ACCEL_XOUT_H .. GYRO_ZOUT_L, big-endian, temperature at 65-66.
const ACCEL_XOUT_H: u8 = 0x3B;

/// Register 106, USER_CTRL.
const USER_CTRL: u8 = 0x6A;
/// USER_CTRL: FIFO_EN, bit 6.
const USER_CTRL_FIFO_EN: u8 = 0x40;
/// USER_CTRL: FIFO_RESET, bit 2 (self-clearing; resets the FIFO "while FIFO_EN equals 0").
const FIFO_RESET: u8 = 0x04;

/// Register 107, PWR_MGMT_1.
const PWR_MGMT_1: u8 = 0x6B;
/// PWR_MGMT_1: DEVICE_RESET, bit 7.
const DEVICE_RESET: u8 = 0x80;
/// PWR_MGMT_1: SLEEP, bit 6 (set at power-on).
const SLEEP: u8 = 0x40;
/// PWR_MGMT_1: CLKSEL, bits 2:0 (0 at power-on: the internal oscillator).
const CLKSEL: u8 = 0x07;
/// PWR_MGMT_1: CLKSEL = 1, the PLL with the X-gyro reference (and SLEEP clear: awake).
const CLKSEL_PLL_XGYRO: u8 = 0x01;

/// Registers 114-115, FIFO_COUNTH/L: bytes in the FIFO, big-endian.
const FIFO_COUNTH: u8 = 0x72;

/// Register 116, FIFO_R_W.
const FIFO_R_W: u8 = 0x74;

/// Register 117, WHO_AM_I.
const WHO_AM_I: u8 = 0x75;
/// WHO_AM_I of the MPU-6050.
const MPU6050_ID: u8 = 0x68;
/// WHO_AM_I of the MPU-6500 and MPU-9250: recognised, and rejected.
const MPU6500_MPU9250_IDS: [u8; 2] = [0x70, 0x71];

/// Bytes per FIFO packet with accelerometer and gyro enabled.
const PACKET: usize = 12;
/// FIFO size (register map, FIFO_COUNT: 1024 bytes).
const FIFO_BYTES: u16 = 1024;
/// The wait after DEVICE_RESET (the register map's reset sequence waits 100 ms).
const RESET_MS: u32 = 100;

/// The chip reset.
const CHIP_RESET: Write = (PWR_MGMT_1, DEVICE_RESET);
/// The configuration writes need no wait.
const NO_SETTLE: u32 = 0;

/// `enable_fifo` first enables the overflow flag.
const OVERFLOW_FLAG_ON: &[Write] = &[(INT_ENABLE, FIFO_OFLOW_EN)];
/// The channels are taken off the FIFO before it is reset, as ArduPilot does
/// (libraries/AP_InertialSensor/AP_InertialSensor_Invensense.cpp,
/// `AP_InertialSensor_Invensense::_fifo_reset`: FIFO_EN = 0, USER_CTRL without FIFO_EN,
/// USER_CTRL | FIFO_RESET, USER_CTRL | FIFO_EN, then the FIFO_EN channels), and as the
/// register map requires of USER_CTRL (FIFO_RESET "resets the FIFO buffer when set to 1 while
/// FIFO_EN equals 0"). With the channels off first, nothing enters the FIFO between the count
/// read after this step and the reset, which makes the count of discarded samples exact.
const FIFO_STOP: &[Write] = &[(FIFO_EN, 0), (USER_CTRL, 0)];
/// The FIFO reset, with FIFO_EN clear.
const FIFO_EMPTY: &[Write] = &[(USER_CTRL, FIFO_RESET)];
/// The FIFO on, then its channels.
const FIFO_START: &[Write] = &[
    (USER_CTRL, USER_CTRL_FIFO_EN),
    (FIFO_EN, ACCEL_GYRO_FIFO_EN),
];

/// The FIFO on and the chip awake on its PLL clock: USER_CTRL and PWR_MGMT_1 in one read (a
/// chip reset leaves it asleep; `enable_fifo` could have set USER_CTRL.FIFO_EN on it).
const FIFO_ON: Check = Check {
    reg: USER_CTRL,
    fields: &[
        (USER_CTRL_FIFO_EN, USER_CTRL_FIFO_EN),
        (SLEEP | CLKSEL, CLKSEL_PLL_XGYRO),
    ],
};

/// PWR_MGMT_1: awake, on the PLL clock (a chip reset leaves it asleep on the oscillator).
const AWAKE_ON_PLL: Check = Check {
    reg: PWR_MGMT_1,
    fields: &[(SLEEP | CLKSEL, CLKSEL_PLL_XGYRO)],
};

/// Gyro full-scale range (FS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GyroRange {
    /// +-250 deg/s, 131 counts per deg/s.
    #[default]
    Dps250,
    /// +-500 deg/s, 65.5 counts per deg/s.
    Dps500,
    /// +-1000 deg/s, 32.8 counts per deg/s.
    Dps1000,
    /// +-2000 deg/s, 16.4 counts per deg/s.
    Dps2000,
}

impl GyroRange {
    /// Counts per deg/s (PS-MPU-6000A-00 rev 3.4, section 6.1).
    pub fn counts_per_dps(self) -> f32 {
        match self {
            Self::Dps250 => 131.0,
            Self::Dps500 => 65.5,
            Self::Dps1000 => 32.8,
            Self::Dps2000 => 16.4,
        }
    }

    /// FS_SEL (GYRO_CONFIG, register 27).
    fn fs_sel(self) -> u8 {
        match self {
            Self::Dps250 => 0,
            Self::Dps500 => 1,
            Self::Dps1000 => 2,
            Self::Dps2000 => 3,
        }
    }
}

/// Accelerometer full-scale range (AFS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelRange {
    /// +-2 g, 16384 counts per g.
    #[default]
    G2,
    /// +-4 g, 8192 counts per g.
    G4,
    /// +-8 g, 4096 counts per g.
    G8,
    /// +-16 g, 2048 counts per g.
    G16,
}

impl AccelRange {
    /// Counts per g (PS-MPU-6000A-00 rev 3.4, section 6.2).
    pub fn counts_per_g(self) -> f32 {
        match self {
            Self::G2 => 16384.0,
            Self::G4 => 8192.0,
            Self::G8 => 4096.0,
            Self::G16 => 2048.0,
        }
    }

    /// AFS_SEL (ACCEL_CONFIG, register 28).
    fn afs_sel(self) -> u8 {
        match self {
            Self::G2 => 0,
            Self::G4 => 1,
            Self::G8 => 2,
            Self::G16 => 3,
        }
    }
}

/// Digital low-pass filter (DLPF_CFG); the accelerometer bandwidth is given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Dlpf {
    /// 260 Hz, gyro output rate 8 kHz.
    Hz260,
    /// 184 Hz.
    Hz184,
    /// 94 Hz.
    Hz94,
    /// 44 Hz.
    #[default]
    Hz44,
    /// 21 Hz.
    Hz21,
    /// 10 Hz.
    Hz10,
    /// 5 Hz.
    Hz5,
}

impl Dlpf {
    /// The gyro output rate in Hz: 8 kHz with [`Dlpf::Hz260`], otherwise 1 kHz.
    fn gyro_rate_hz(self) -> u32 {
        if self == Self::Hz260 { 8000 } else { 1000 }
    }

    /// DLPF_CFG (CONFIG, register 26).
    fn dlpf_cfg(self) -> u8 {
        match self {
            Self::Hz260 => 0,
            Self::Hz184 => 1,
            Self::Hz94 => 2,
            Self::Hz44 => 3,
            Self::Hz21 => 4,
            Self::Hz10 => 5,
            Self::Hz5 => 6,
        }
    }
}

/// Configuration written by [`Driver::init`] of an [`Mpu6050`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mpu6050Config {
    /// Gyro range.
    pub gyro_range: GyroRange,
    /// Accelerometer range.
    pub accel_range: AccelRange,
    /// Low-pass filter.
    pub dlpf: Dlpf,
    /// Sample rate = gyro output rate (1 kHz, or 8 kHz with [`Dlpf::Hz260`]) / (1 + this).
    pub sample_rate_divider: u8,
}

impl Default for Mpu6050Config {
    /// +-250 deg/s, +-2 g, 44 Hz filter, 100 Hz sample rate.
    fn default() -> Self {
        Self {
            gyro_range: GyroRange::Dps250,
            accel_range: AccelRange::G2,
            dlpf: Dlpf::Hz44,
            sample_rate_divider: 9,
        }
    }
}

impl Mpu6050Config {
    /// The sample rate in Hz.
    pub fn sample_rate_hz(&self) -> f32 {
        self.dlpf.gyro_rate_hz() as f32 / (1.0 + f32::from(self.sample_rate_divider))
    }

    /// The sensitivities of this configuration.
    pub fn scale(&self) -> Scale {
        Scale {
            gyro_counts_per_dps: self.gyro_range.counts_per_dps(),
            accel_counts_per_g: self.accel_range.counts_per_g(),
        }
    }
}

/// An MPU-6050 on an I2C bus: the [`Driver`] of an [`Mpu6050Bus`].
///
/// - `init` probes WHO_AM_I (0x68; the MPU-6500 and MPU-9250 are rejected), resets the chip
///   (PWR_MGMT_1.DEVICE_RESET, then 100 ms), wakes it on the X-gyro PLL clock and writes
///   SMPLRT_DIV, CONFIG, GYRO_CONFIG and ACCEL_CONFIG. It returns WHO_AM_I, as `recover`
///   does; pass `recover` the 100 ms of the reset in its outage.
/// - `read` is one burst read of registers 59-72 (accelerometer, temperature, gyro).
/// - `enable_fifo` enables FIFO_OFLOW_INT and the FIFO with accelerometer and gyro samples
///   (12 bytes each, no header). `read_fifo` reads FIFO_COUNT twice and takes the smaller
///   (a count corrupted on the wire would otherwise have the reader read past the FIFO's end
///   and deliver its repeated last byte as samples); its FIFO holds 1024 bytes. A FIFO reset
///   takes the channels off (FIFO_EN, USER_CTRL), reads FIFO_COUNT, then sets
///   USER_CTRL.FIFO_RESET and starts the FIFO and its channels again. An empty FIFO is
///   checked against USER_CTRL and PWR_MGMT_1 (a chip that has reset itself has its FIFO off
///   and is asleep); a FIFO reset that finds the FIFO empty checks PWR_MGMT_1.
///
/// ```
/// # use embedded_hal::i2c::{ErrorType, I2c, Operation};
/// # struct Bus;
/// # impl ErrorType for Bus { type Error = core::convert::Infallible; }
/// # impl I2c for Bus {
/// #     fn transaction(&mut self, _: u8, ops: &mut [Operation<'_>]) -> Result<(), Self::Error> {
/// #         for op in ops { if let Operation::Read(b) = op { b.fill(0); b[0] = 0x68; } }
/// #         Ok(())
/// #     }
/// # }
/// # struct Delay;
/// # impl embedded_hal::delay::DelayNs for Delay { fn delay_ns(&mut self, _: u32) {} }
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
/// use imu_ar::sensor::{GyroUnit, ImuReader, Mpu6050, Mpu6050Config};
///
/// let mut imu = Mpu6050::new(Bus, 0x68);
/// assert_eq!(imu.init(&mut Delay, Mpu6050Config::default())?, 0x68);
/// let config = Config::new(0.999f32, 0.01).unwrap();
/// // delta about 0.1 x each axis's variance, in its own units: (deg/s)^2 and g^2.
/// let (gyro, accel) = (Channel::new(1e-4).unwrap(), Channel::new(1e-6).unwrap());
/// let mut axes: [Lattice<f32, 4>; 6] =
///     core::array::from_fn(|i| Lattice::new(&config, if i < 3 { &gyro } else { &accel }));
/// let sample = imu.read()?;
/// let gyro = imu.scale().gyro(sample.gyro, GyroUnit::DegPerSec);
/// let accel = imu.scale().accel(sample.accel, imu_ar::sensor::AccelUnit::G);
/// for (lattice, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
///     lattice.update(&config, x);
/// }
/// let bus: Bus = imu.destroy();
/// # Ok::<(), imu_ar::sensor::Error<core::convert::Infallible>>(())
/// ```
pub type Mpu6050<I2C> = Driver<Mpu6050Bus<I2C>>;

impl<I2C: I2c> Mpu6050<I2C> {
    /// A reader at `address` (0x68, or 0x69 with AD0 high); no bus traffic until `init`.
    pub fn new(i2c: I2C, address: u8) -> Self {
        Driver::with_chip(Mpu6050Bus { i2c, address })
    }

    /// Gives the bus back.
    pub fn destroy(self) -> I2C {
        self.into_chip().i2c
    }

    /// Temperature in deg C from the raw value: `raw / 340 + 36.53` (register map, registers
    /// 65-66): [`Thermometer::MPU6050`], which [`ImuReader::die_temperature`] applies to a
    /// sample.
    ///
    /// [`ImuReader::die_temperature`]: super::ImuReader::die_temperature
    pub fn temperature_celsius(raw: i16) -> f32 {
        Thermometer::MPU6050.celsius(raw)
    }
}

/// An MPU-6050 on an async I2C bus (`embedded-hal-async`): the [`AsyncDriver`] of an
/// [`Mpu6050Bus`], the async twin of [`Mpu6050`]: the same registers, checks and counts,
/// awaited.
///
/// ```
/// # use embedded_hal_async::i2c::{ErrorType, I2c, Operation};
/// # struct Bus;
/// # impl ErrorType for Bus { type Error = core::convert::Infallible; }
/// # impl I2c for Bus {
/// #     async fn transaction(&mut self, _: u8, ops: &mut [Operation<'_>]) -> Result<(), Self::Error> {
/// #         for op in ops { if let Operation::Read(b) = op { b.fill(0); b[0] = 0x68; } }
/// #         Ok(())
/// #     }
/// # }
/// # struct Delay;
/// # impl embedded_hal_async::delay::DelayNs for Delay { async fn delay_ns(&mut self, _: u32) {} }
/// use imu_ar::sensor::{Mpu6050Async, Mpu6050Config};
///
/// async fn first_sample() -> Result<(), imu_ar::sensor::Error<core::convert::Infallible>> {
///     let mut imu = Mpu6050Async::new(Bus, 0x68);
///     imu.init(&mut Delay, Mpu6050Config::default()).await?;
///     let sample = imu.read().await?;
///     let _gyro = imu.scale().gyro(sample.gyro, imu_ar::sensor::GyroUnit::DegPerSec);
///     Ok(())
/// }
/// ```
pub type Mpu6050Async<I2C> = AsyncDriver<Mpu6050Bus<Async<I2C>>>;

impl<I2C: AsyncI2c> Mpu6050Async<I2C> {
    /// A reader at `address` (0x68, or 0x69 with AD0 high); no bus traffic until `init`.
    pub fn new(i2c: I2C, address: u8) -> Self {
        AsyncDriver::with_chip(Mpu6050Bus {
            i2c: Async(i2c),
            address,
        })
    }

    /// Gives the bus back.
    pub fn destroy(self) -> I2C {
        self.into_chip().i2c.0
    }
}

/// The registers the shared driver uses.
const MAP: Map = Map {
    who_am_i: WHO_AM_I,
    id: MPU6050_ID,
    unsupported: &MPU6500_MPU9250_IDS,
    reset: CHIP_RESET,
    reset_ms: RESET_MS,
    settle_ms: NO_SETTLE,
    data: ACCEL_XOUT_H,
    int_status: INT_STATUS,
    int_fifo_overflow: FIFO_OFLOW_INT,
    fifo_count: FIFO_COUNTH,
    fifo_data: FIFO_R_W,
    packet: PACKET,
    fifo_bytes: FIFO_BYTES,
    fifo_prepare: OVERFLOW_FLAG_ON,
    fifo_stop: FIFO_STOP,
    stopped: Check {
        reg: FIFO_EN,
        fields: &[(u8::MAX, 0)],
    },
    fifo_empty: FIFO_EMPTY,
    fifo_start: FIFO_START,
    fifo_on: &[FIFO_ON],
    configured: AWAKE_ON_PLL,
    thermometer: Thermometer::MPU6050,
    whole_packets: false,
    verify_setup: false,
};

/// The MPU-6050 at its address on an I2C bus: the chip that an [`Mpu6050`] drives.
#[derive(Debug)]
pub struct Mpu6050Bus<I2C> {
    i2c: I2C,
    address: u8,
}

impl<I2C: I2cIo> Chip for Mpu6050Bus<I2C> {
    type BusError = I2C::Error;
    type Config = Mpu6050Config;
    const MAP: Map = MAP;

    async fn write(&mut self, reg: u8, value: u8) -> Result<(), I2C::Error> {
        self.i2c.write(self.address, &[reg, value]).await
    }

    async fn read(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), I2C::Error> {
        self.i2c.write_read(self.address, &[reg], buf).await
    }

    /// Awake on the X-gyro PLL clock, then rate, filter and ranges.
    fn setup(c: &Mpu6050Config) -> impl IntoIterator<Item = Write> {
        [
            (PWR_MGMT_1, CLKSEL_PLL_XGYRO),
            (SMPLRT_DIV, c.sample_rate_divider),
            (CONFIG, c.dlpf.dlpf_cfg()),
            (GYRO_CONFIG, c.gyro_range.fs_sel() << FS_SEL_SHIFT),
            (ACCEL_CONFIG, c.accel_range.afs_sel() << AFS_SEL_SHIFT),
        ]
    }

    fn scale(c: &Mpu6050Config) -> Scale {
        c.scale()
    }

    fn rate(c: &Mpu6050Config) -> (u32, u32) {
        (c.dlpf.gyro_rate_hz(), 1 + u32::from(c.sample_rate_divider))
    }

    /// Registers 59-72: accelerometer, temperature, gyro.
    fn sample(b: &[u8; 14]) -> Option<RawSample> {
        Some(RawSample {
            accel: be_i16x3(b, 0),
            temperature: Some(be_i16(b, 6)),
            gyro: be_i16x3(b, 8),
        })
    }

    /// Accelerometer then gyro, no header: every packet is a sample.
    fn parse(p: &[u8]) -> Packet {
        Packet::Sample(RawSample {
            accel: be_i16x3(p, 0),
            gyro: be_i16x3(p, 6),
            temperature: None,
        })
    }
}
