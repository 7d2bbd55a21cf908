//! TDK InvenSense ICM-42688-P over SPI.
//!
//! Registers (user bank 0), bits, FIFO packet layout and scale factors from the "ICM-42688-P
//! Datasheet", DS-000347 revision 1.2: section 3.1 (gyro sensitivity), 3.2 (accelerometer
//! sensitivity), section 6 (FIFO packet structure, packet 3) and the bank 0 register
//! descriptions (register addresses below). SPI: bit 7 of the address byte set for a read.

use embedded_hal::spi::{Operation, SpiDevice};
use embedded_hal_async::spi::SpiDevice as AsyncSpiDevice;

use super::chip::{Check, Chip, Map, Packet, Write};
use super::driver::{AsyncDriver, Driver};
use super::io::{Async, SpiIo};
use super::{RawSample, Scale, Thermometer, be_i16, be_i16x3};

/// SPI: bit 7 of the address byte, set for a read.
const SPI_READ: u8 = 0x80;

/// DEVICE_CONFIG.
const DEVICE_CONFIG: u8 = 0x11;
/// DEVICE_CONFIG: SOFT_RESET_CONFIG, bit 0 (1 ms to complete).
const SOFT_RESET_CONFIG: u8 = 0x01;

/// FIFO_CONFIG: FIFO_MODE in bits 7:6 (00 after a reset: bypass).
const FIFO_CONFIG: u8 = 0x16;
/// FIFO_CONFIG: FIFO_MODE = 01, stream-to-FIFO.
const FIFO_MODE_STREAM: u8 = 0x40;

/// TEMP_DATA1: temperature, then ACCEL_DATA_X1 (0x1F) .. GYRO_DATA_Z0 (0x2A), big-endian.
const TEMP_DATA1: u8 = 0x1D;

/// INT_STATUS, cleared by reading.
const INT_STATUS: u8 = 0x2D;
/// INT_STATUS: FIFO_FULL_INT, bit 1.
const FIFO_FULL_INT: u8 = 0x02;

/// FIFO_COUNTH/L: bytes in the FIFO, big-endian (reset value of INTF_CONFIG0).
const FIFO_COUNTH: u8 = 0x2E;

/// FIFO_DATA.
const FIFO_DATA: u8 = 0x30;

/// SIGNAL_PATH_RESET.
const SIGNAL_PATH_RESET: u8 = 0x4B;
/// SIGNAL_PATH_RESET: FIFO_FLUSH, bit 1.
const FIFO_FLUSH: u8 = 0x02;

/// PWR_MGMT0: GYRO_MODE in bits 3:2, ACCEL_MODE in bits 1:0 (00 after a reset: off).
const PWR_MGMT0: u8 = 0x4E;
/// PWR_MGMT0: GYRO_MODE = 11, low noise.
const GYRO_MODE_LN: u8 = 0x0C;
/// PWR_MGMT0: ACCEL_MODE = 11, low noise.
const ACCEL_MODE_LN: u8 = 0x03;

/// GYRO_CONFIG0: GYRO_FS_SEL in bits 7:5, GYRO_ODR in bits 3:0 ([`Odr::odr`]).
const GYRO_CONFIG0: u8 = 0x4F;
/// GYRO_CONFIG0: the lowest bit of GYRO_FS_SEL ([`IcmGyroRange::fs_sel`]).
const GYRO_FS_SEL_SHIFT: u8 = 5;

/// ACCEL_CONFIG0: ACCEL_FS_SEL in bits 7:5, ACCEL_ODR in bits 3:0 ([`Odr::odr`]).
const ACCEL_CONFIG0: u8 = 0x50;
/// ACCEL_CONFIG0: the lowest bit of ACCEL_FS_SEL ([`IcmAccelRange::fs_sel`]).
const ACCEL_FS_SEL_SHIFT: u8 = 5;

/// FIFO_CONFIG1: the data written into the FIFO.
const FIFO_CONFIG1: u8 = 0x5F;
/// FIFO_CONFIG1: FIFO_TEMP_EN, bit 2.
const FIFO_TEMP_EN: u8 = 0x04;
/// FIFO_CONFIG1: FIFO_GYRO_EN, bit 1.
const FIFO_GYRO_EN: u8 = 0x02;
/// FIFO_CONFIG1: FIFO_ACCEL_EN, bit 0.
const FIFO_ACCEL_EN: u8 = 0x01;

/// WHO_AM_I.
const WHO_AM_I: u8 = 0x75;
/// WHO_AM_I of the ICM-42688-P.
const ICM42688_ID: u8 = 0x47;

/// FIFO header: HEADER_MSG, bit 7: "FIFO empty".
const HEADER_MSG: u8 = 0x80;
/// FIFO header: HEADER_ACCEL, bit 6: accelerometer data in the packet.
const HEADER_ACCEL: u8 = 0x40;
/// FIFO header: HEADER_GYRO, bit 5: gyro data in the packet.
const HEADER_GYRO: u8 = 0x20;
/// FIFO header: HEADER_20, bit 4: a 20-byte packet 4.
const HEADER_20: u8 = 0x10;

/// Packet 3: header, accel x/y/z, gyro x/y/z (big-endian), temperature (1 byte), timestamp (2).
const PACKET: usize = 16;
/// Packet 3: the offset of the accelerometer data.
const PACKET_ACCEL: usize = 1;
/// Packet 3: the offset of the gyro data.
const PACKET_GYRO: usize = 7;
/// Packet 3: the offset of the temperature.
const PACKET_TEMP: usize = 13;
/// Packet 3: the 8-bit FIFO temperature times this is the 16-bit register form.
const FIFO_TEMP_SCALE: i16 = 64;
/// FIFO size: 2 KiB.
const FIFO_BYTES: u16 = 2048;
/// The invalid-data marker of a 16-bit FIFO field (TDK's driver: `INVALID_VALUE_FIFO`).
const INVALID: i16 = i16::MIN;
/// The invalid-data marker of the 8-bit FIFO temperature (`INVALID_VALUE_FIFO_1B`).
const INVALID_TEMP: i8 = i8::MIN;

/// FIFO_CONFIG1 with packet 3: temperature, gyro, accelerometer.
const FIFO_PACKET_3: u8 = FIFO_TEMP_EN | FIFO_GYRO_EN | FIFO_ACCEL_EN;

/// PWR_MGMT0 with gyro and accelerometer in low-noise mode.
const LOW_NOISE: u8 = GYRO_MODE_LN | ACCEL_MODE_LN;

/// The soft reset.
const SOFT_RESET: Write = (DEVICE_CONFIG, SOFT_RESET_CONFIG);
/// SOFT_RESET_CONFIG takes 1 ms.
const RESET_MS: u32 = 1;
/// The wait after PWR_MGMT0 switches gyro and accelerometer on, before any further write.
const START_MS: u32 = 1;
/// No related chip is recognised and rejected.
const NO_RELATED_IDS: &[u8] = &[];

/// `enable_fifo` first puts the FIFO in stream mode.
const FIFO_STREAM: &[Write] = &[(FIFO_CONFIG, FIFO_MODE_STREAM)];
/// SIGNAL_PATH_RESET.FIFO_FLUSH between FIFO_CONFIG1 = 0 (channels off) and the channels on
/// again. Neither the datasheet nor ArduPilot asks for the channels to be off for a flush
/// (libraries/AP_InertialSensor/AP_InertialSensor_Invensensev3.cpp,
/// `AP_InertialSensor_Invensensev3::fifo_reset`, writes FIFO_CONFIG1 with accel, gyro and
/// temperature on and then SIGNAL_PATH_RESET = 2); they are taken off here so that nothing
/// enters the FIFO between the count read after this step and the flush, nor while a flush
/// is in doubt (a write that reported a failure may still have been done), which keeps the
/// count of discarded samples exact.
const FIFO_STOP: &[Write] = &[(FIFO_CONFIG1, 0)];
/// The FIFO flush.
const FIFO_FLUSHED: &[Write] = &[(SIGNAL_PATH_RESET, FIFO_FLUSH)];
/// The channels of packet 3 on.
const FIFO_START: &[Write] = &[(FIFO_CONFIG1, FIFO_PACKET_3)];

/// FIFO_CONFIG as a whole: stream mode, the reserved bits clear (a chip reset leaves it in
/// bypass mode).
const STREAMING: Check = Check {
    reg: FIFO_CONFIG,
    fields: &[(u8::MAX, FIFO_MODE_STREAM)],
};

/// FIFO_CONFIG1 as a whole: packet 3's channels on (0 after a chip reset; a write of it
/// corrupted on the wire would leave the FIFO empty for ever).
const CHANNELS_ON: Check = Check {
    reg: FIFO_CONFIG1,
    fields: &[(u8::MAX, FIFO_PACKET_3)],
};

/// PWR_MGMT0: gyro and accelerometer in low-noise mode (off after a chip reset).
const SENSORS_ON: Check = Check {
    reg: PWR_MGMT0,
    fields: &[(LOW_NOISE, LOW_NOISE)],
};

/// Gyro full-scale range (GYRO_FS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IcmGyroRange {
    /// +-2000 deg/s, 16.4 counts per deg/s.
    #[default]
    Dps2000,
    /// +-1000 deg/s, 32.8 counts per deg/s.
    Dps1000,
    /// +-500 deg/s, 65.5 counts per deg/s.
    Dps500,
    /// +-250 deg/s, 131 counts per deg/s.
    Dps250,
    /// +-125 deg/s, 262 counts per deg/s.
    Dps125,
    /// +-62.5 deg/s, 524.3 counts per deg/s.
    Dps62_5,
    /// +-31.25 deg/s, 1048.6 counts per deg/s.
    Dps31_25,
    /// +-15.625 deg/s, 2097.2 counts per deg/s.
    Dps15_625,
}

impl IcmGyroRange {
    /// Counts per deg/s (DS-000347 rev 1.2, section 3.1).
    pub fn counts_per_dps(self) -> f32 {
        match self {
            Self::Dps2000 => 16.4,
            Self::Dps1000 => 32.8,
            Self::Dps500 => 65.5,
            Self::Dps250 => 131.0,
            Self::Dps125 => 262.0,
            Self::Dps62_5 => 524.3,
            Self::Dps31_25 => 1048.6,
            Self::Dps15_625 => 2097.2,
        }
    }

    /// GYRO_FS_SEL (GYRO_CONFIG0 bits 7:5).
    fn fs_sel(self) -> u8 {
        match self {
            Self::Dps2000 => 0,
            Self::Dps1000 => 1,
            Self::Dps500 => 2,
            Self::Dps250 => 3,
            Self::Dps125 => 4,
            Self::Dps62_5 => 5,
            Self::Dps31_25 => 6,
            Self::Dps15_625 => 7,
        }
    }
}

/// Accelerometer full-scale range (ACCEL_FS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IcmAccelRange {
    /// +-16 g, 2048 counts per g.
    #[default]
    G16,
    /// +-8 g, 4096 counts per g.
    G8,
    /// +-4 g, 8192 counts per g.
    G4,
    /// +-2 g, 16384 counts per g.
    G2,
}

impl IcmAccelRange {
    /// Counts per g (DS-000347 rev 1.2, section 3.2).
    pub fn counts_per_g(self) -> f32 {
        match self {
            Self::G16 => 2048.0,
            Self::G8 => 4096.0,
            Self::G4 => 8192.0,
            Self::G2 => 16384.0,
        }
    }

    /// ACCEL_FS_SEL (ACCEL_CONFIG0 bits 7:5).
    fn fs_sel(self) -> u8 {
        match self {
            Self::G16 => 0,
            Self::G8 => 1,
            Self::G4 => 2,
            Self::G2 => 3,
        }
    }
}

/// Output data rate (GYRO_ODR and ACCEL_ODR).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Odr {
    /// 8 kHz.
    Hz8000,
    /// 4 kHz.
    Hz4000,
    /// 2 kHz.
    Hz2000,
    /// 1 kHz.
    Hz1000,
    /// 500 Hz.
    Hz500,
    /// 200 Hz.
    Hz200,
    /// 100 Hz.
    #[default]
    Hz100,
    /// 50 Hz.
    Hz50,
    /// 25 Hz.
    Hz25,
}

impl Odr {
    /// GYRO_ODR and ACCEL_ODR (GYRO_CONFIG0 and ACCEL_CONFIG0 bits 3:0).
    fn odr(self) -> u8 {
        match self {
            Odr::Hz8000 => 3,
            Odr::Hz4000 => 4,
            Odr::Hz2000 => 5,
            Odr::Hz1000 => 6,
            Odr::Hz500 => 15,
            Odr::Hz200 => 7,
            Odr::Hz100 => 8,
            Odr::Hz50 => 9,
            Odr::Hz25 => 10,
        }
    }

    /// The rate in mHz.
    fn millihz(self) -> u32 {
        match self {
            Odr::Hz8000 => 8_000_000,
            Odr::Hz4000 => 4_000_000,
            Odr::Hz2000 => 2_000_000,
            Odr::Hz1000 => 1_000_000,
            Odr::Hz500 => 500_000,
            Odr::Hz200 => 200_000,
            Odr::Hz100 => 100_000,
            Odr::Hz50 => 50_000,
            Odr::Hz25 => 25_000,
        }
    }

    /// The rate in Hz.
    pub fn hz(self) -> f32 {
        match self {
            Odr::Hz8000 => 8000.0,
            Odr::Hz4000 => 4000.0,
            Odr::Hz2000 => 2000.0,
            Odr::Hz1000 => 1000.0,
            Odr::Hz500 => 500.0,
            Odr::Hz200 => 200.0,
            Odr::Hz100 => 100.0,
            Odr::Hz50 => 50.0,
            Odr::Hz25 => 25.0,
        }
    }
}

/// Configuration written by [`Driver::init`] of an [`Icm42688`] (gyro and accelerometer at
/// the same rate).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Icm42688Config {
    /// Gyro range.
    pub gyro_range: IcmGyroRange,
    /// Accelerometer range.
    pub accel_range: IcmAccelRange,
    /// Output data rate of both.
    pub odr: Odr,
}

impl Icm42688Config {
    /// The sensitivities of this configuration.
    pub fn scale(&self) -> Scale {
        Scale {
            gyro_counts_per_dps: self.gyro_range.counts_per_dps(),
            accel_counts_per_g: self.accel_range.counts_per_g(),
        }
    }
}

/// An ICM-42688-P on an SPI device: the [`Driver`] of an [`Icm42688Bus`].
///
/// - `init` probes WHO_AM_I (0x47), soft-resets the chip (DEVICE_CONFIG.SOFT_RESET_CONFIG,
///   then 1 ms), writes ranges and rates (GYRO_CONFIG0, ACCEL_CONFIG0) and puts gyro and
///   accelerometer in low-noise mode (PWR_MGMT0, then 1 ms; the gyro needs about 30 ms more
///   before its data are valid: until then the FIFO carries the invalid marker, and those
///   packets are skipped and counted in [`FifoStats::invalid`](super::FifoStats::invalid)).
///   It returns WHO_AM_I, as `recover` does; pass `recover` the 2 ms of the reset and start
///   in its outage.
/// - `read` is one burst read of TEMP_DATA1 .. GYRO_DATA_Z0; data registers holding the
///   invalid-data marker (-32768, while a sensor is starting) give
///   [`Error::NoData`](super::Error::NoData).
/// - `enable_fifo` puts the FIFO in stream mode (FIFO_CONFIG) with packet 3 (FIFO_CONFIG1:
///   header, accelerometer, gyro, temperature, timestamp: 16 bytes); the FIFO holds 2048
///   bytes, and INT_STATUS.FIFO_FULL_INT flags an overflow. `read_fifo` reads FIFO_COUNT
///   twice and takes the smaller (a count corrupted high on the wire would read past the
///   FIFO's end). A packet carrying the invalid-data marker (-32768, or -128 for the
///   temperature) is skipped and counted as invalid. A header that does not announce
///   accelerometer and gyro data, announces a 20-byte packet (HEADER_20), or has HEADER_MSG
///   set (FIFO empty) inside the counted bytes is malformed: the packets are most likely
///   misaligned, so the call's packets are dropped (the malformed ones counted as such, the
///   others as discarded) and the FIFO is reset, which realigns it
///   ([`Error::FifoResync`](super::Error::FifoResync)). A FIFO reset takes the channels off
///   (FIFO_CONFIG1 = 0), reads FIFO_COUNT,
///   then flushes the FIFO (SIGNAL_PATH_RESET.FIFO_FLUSH) and starts the channels again. An
///   empty FIFO is checked against FIFO_CONFIG (bypass mode after a chip reset) and
///   FIFO_CONFIG1 (its channels: 0 after a chip reset, or wrong after a write corrupted on the
///   wire); a FIFO reset
///   that finds the FIFO empty checks PWR_MGMT0 (sensors off after a chip reset).
///
/// ```
/// # use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
/// # // A register file: writes are kept and read back; WHO_AM_I answers 0x47.
/// # struct Bus([u8; 128]);
/// # impl ErrorType for Bus { type Error = core::convert::Infallible; }
/// # impl SpiDevice for Bus {
/// #     fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
/// #         let mut reg = 0;
/// #         for op in ops {
/// #             match op {
/// #                 Operation::Write(w) => {
/// #                     reg = w[0];
/// #                     if let [r, v] = w[..] { self.0[usize::from(r & 0x7F)] = v; }
/// #                 }
/// #                 Operation::Read(b) => {
/// #                     b.fill(0);
/// #                     b[0] = if reg == 0xF5 { 0x47 } else { self.0[usize::from(reg & 0x7F)] };
/// #                 }
/// #                 _ => {}
/// #             }
/// #         }
/// #         Ok(())
/// #     }
/// # }
/// # struct Delay;
/// # impl embedded_hal::delay::DelayNs for Delay { fn delay_ns(&mut self, _: u32) {} }
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
/// use imu_ar::sensor::{AccelUnit, GyroUnit, Icm42688, Icm42688Config, ImuReader, RawSample};
///
/// let mut imu = Icm42688::new(Bus([0; 128]));
/// assert_eq!(imu.init(&mut Delay, Icm42688Config::default())?, 0x47);
/// imu.enable_fifo()?;
/// let config = Config::new(0.999f32, 0.01).unwrap();
/// // delta about 0.1 x each axis's variance, in its own units: (rad/s)^2 and (m/s^2)^2.
/// let (gyro, accel) = (Channel::new(3e-8).unwrap(), Channel::new(1e-4).unwrap());
/// let mut axes: [Lattice<f32, 4>; 6] =
///     core::array::from_fn(|i| Lattice::new(&config, if i < 3 { &gyro } else { &accel }));
/// let mut batch = [RawSample::default(); 16];
/// let n = imu.read_fifo(&mut batch)?;
/// let scale = imu.scale();
/// for s in &batch[..n] {
///     let gyro = scale.gyro(s.gyro, GyroUnit::RadPerSec);
///     let accel = scale.accel(s.accel, AccelUnit::MetersPerSec2);
///     for (lattice, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
///         lattice.update(&config, x);
///     }
/// }
/// let bus: Bus = imu.destroy();
/// # Ok::<(), imu_ar::sensor::Error<core::convert::Infallible>>(())
/// ```
pub type Icm42688<SPI> = Driver<Icm42688Bus<SPI>>;

impl<SPI: SpiDevice> Icm42688<SPI> {
    /// A reader on `spi` (mode 0 or 3); no bus traffic until `init`.
    pub fn new(spi: SPI) -> Self {
        Driver::with_chip(Icm42688Bus(spi))
    }

    /// Gives the bus back.
    pub fn destroy(self) -> SPI {
        self.into_chip().0
    }

    /// Temperature in deg C from a raw register value: `raw / 132.48 + 25`. FIFO samples carry
    /// the 8-bit FIFO temperature (`t / 2.07 + 25`) scaled by 64 into the same 16-bit form.
    /// It is [`Thermometer::ICM42688`], which [`ImuReader::die_temperature`] applies to a
    /// sample.
    ///
    /// [`ImuReader::die_temperature`]: super::ImuReader::die_temperature
    pub fn temperature_celsius(raw: i16) -> f32 {
        Thermometer::ICM42688.celsius(raw)
    }
}

/// An ICM-42688-P on an async SPI device (`embedded-hal-async`): the [`AsyncDriver`] of an
/// [`Icm42688Bus`], the async twin of [`Icm42688`]: the same registers, checks and counts,
/// awaited.
pub type Icm42688Async<SPI> = AsyncDriver<Icm42688Bus<Async<SPI>>>;

impl<SPI: AsyncSpiDevice> Icm42688Async<SPI> {
    /// A reader on `spi` (mode 0 or 3); no bus traffic until `init`.
    pub fn new(spi: SPI) -> Self {
        AsyncDriver::with_chip(Icm42688Bus(Async(spi)))
    }

    /// Gives the bus back.
    pub fn destroy(self) -> SPI {
        self.into_chip().0.0
    }
}

/// The registers the shared driver uses.
const MAP: Map = Map {
    who_am_i: WHO_AM_I,
    id: ICM42688_ID,
    unsupported: NO_RELATED_IDS,
    reset: SOFT_RESET,
    reset_ms: RESET_MS,
    settle_ms: START_MS,
    data: TEMP_DATA1,
    int_status: INT_STATUS,
    int_fifo_overflow: FIFO_FULL_INT,
    fifo_count: FIFO_COUNTH,
    fifo_data: FIFO_DATA,
    packet: PACKET,
    fifo_bytes: FIFO_BYTES,
    fifo_prepare: FIFO_STREAM,
    fifo_stop: FIFO_STOP,
    stopped: Check {
        reg: FIFO_CONFIG1,
        fields: &[(u8::MAX, 0)],
    },
    fifo_empty: FIFO_FLUSHED,
    fifo_start: FIFO_START,
    fifo_on: &[STREAMING, CHANNELS_ON],
    configured: SENSORS_ON,
    thermometer: Thermometer::ICM42688,
    whole_packets: true,
    verify_setup: true,
};

/// The ICM-42688-P on an SPI device: the chip that an [`Icm42688`] drives.
#[derive(Debug)]
pub struct Icm42688Bus<SPI>(SPI);

impl<SPI: SpiIo> Chip for Icm42688Bus<SPI> {
    type BusError = SPI::Error;
    type Config = Icm42688Config;
    const MAP: Map = MAP;

    async fn write(&mut self, reg: u8, value: u8) -> Result<(), SPI::Error> {
        self.0
            .transaction(&mut [Operation::Write(&[reg, value])])
            .await
    }

    async fn read(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), SPI::Error> {
        let address = [reg | SPI_READ];
        self.0
            .transaction(&mut [Operation::Write(&address), Operation::Read(buf)])
            .await
    }

    /// Ranges and rates, then gyro and accelerometer on in low-noise mode.
    fn setup(c: &Icm42688Config) -> impl IntoIterator<Item = Write> {
        let odr = c.odr.odr();
        [
            (
                GYRO_CONFIG0,
                c.gyro_range.fs_sel() << GYRO_FS_SEL_SHIFT | odr,
            ),
            (
                ACCEL_CONFIG0,
                c.accel_range.fs_sel() << ACCEL_FS_SEL_SHIFT | odr,
            ),
            (PWR_MGMT0, LOW_NOISE),
        ]
    }

    fn scale(c: &Icm42688Config) -> Scale {
        c.scale()
    }

    fn rate(c: &Icm42688Config) -> (u32, u32) {
        (c.odr.millihz(), 1000)
    }

    /// TEMP_DATA1 .. GYRO_DATA_Z0: temperature, accelerometer, gyro.
    fn sample(b: &[u8; 14]) -> Option<RawSample> {
        let s = RawSample {
            temperature: Some(be_i16(b, 0)),
            accel: be_i16x3(b, 2),
            gyro: be_i16x3(b, 8),
        };
        let invalid = s.accel.contains(&INVALID)
            || s.gyro.contains(&INVALID)
            || s.temperature == Some(INVALID);
        (!invalid).then_some(s)
    }

    /// Packet 3 (DS-000347 section 6).
    fn parse(p: &[u8]) -> Packet {
        let header = p.first().copied().unwrap_or(HEADER_MSG);
        if header & HEADER_MSG != 0 {
            return Packet::End;
        }
        let data = HEADER_ACCEL | HEADER_GYRO;
        if header & (data | HEADER_20) != data {
            return Packet::Malformed;
        }
        let (accel, gyro) = (be_i16x3(p, PACKET_ACCEL), be_i16x3(p, PACKET_GYRO));
        let temp = p.get(PACKET_TEMP).map(|&t| t as i8);
        if accel.contains(&INVALID) || gyro.contains(&INVALID) || temp == Some(INVALID_TEMP) {
            return Packet::Invalid;
        }
        Packet::Sample(RawSample {
            accel,
            gyro,
            temperature: temp.map(|t| i16::from(t) * FIFO_TEMP_SCALE),
        })
    }
}
