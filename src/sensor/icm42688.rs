//! TDK InvenSense ICM-42688-P over SPI.
//!
//! Registers (user bank 0), bits, FIFO packet layout and scale factors from the "ICM-42688-P
//! Datasheet", DS-000347 revision 1.2: section 3.1 (gyro sensitivity), 3.2 (accelerometer
//! sensitivity), section 6 (FIFO packet structure, packet 3) and the bank 0 register
//! descriptions (register addresses below). SPI: bit 7 of the address byte set for a read.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use super::fifo::{self, FifoChip, FifoState};
use super::{Error, FifoStats, ImuReader, Packet, RawSample, Scale, be_i16, be_i16x3};

/// DEVICE_CONFIG: SOFT_RESET_CONFIG in bit 0 (1 ms to complete).
const DEVICE_CONFIG: u8 = 0x11;
/// FIFO_CONFIG: FIFO_MODE in bits 7:6 (01 stream-to-FIFO).
const FIFO_CONFIG: u8 = 0x16;
/// TEMP_DATA1: temperature, then ACCEL_DATA_X1 (0x1F) .. GYRO_DATA_Z0 (0x2A), big-endian.
const TEMP_DATA1: u8 = 0x1D;
/// INT_STATUS: FIFO_FULL_INT in bit 1, cleared by reading.
const INT_STATUS: u8 = 0x2D;
/// FIFO_COUNTH/L: bytes in the FIFO, big-endian (reset value of INTF_CONFIG0).
const FIFO_COUNTH: u8 = 0x2E;
/// FIFO_DATA.
const FIFO_DATA: u8 = 0x30;
/// SIGNAL_PATH_RESET: FIFO_FLUSH in bit 1.
const SIGNAL_PATH_RESET: u8 = 0x4B;
/// PWR_MGMT0: GYRO_MODE bits 3:2, ACCEL_MODE bits 1:0 (11 = low noise).
const PWR_MGMT0: u8 = 0x4E;
/// GYRO_CONFIG0: GYRO_FS_SEL bits 7:5, GYRO_ODR bits 3:0.
const GYRO_CONFIG0: u8 = 0x4F;
/// ACCEL_CONFIG0: ACCEL_FS_SEL bits 7:5, ACCEL_ODR bits 3:0.
const ACCEL_CONFIG0: u8 = 0x50;
/// FIFO_CONFIG1: FIFO_TEMP_EN (2), FIFO_GYRO_EN (1), FIFO_ACCEL_EN (0).
const FIFO_CONFIG1: u8 = 0x5F;
/// WHO_AM_I, 0x47.
const WHO_AM_I: u8 = 0x75;

/// WHO_AM_I of the ICM-42688-P.
const ID: u8 = 0x47;
/// SPI: bit 7 of the address byte set for a read.
const READ: u8 = 0x80;
/// DEVICE_CONFIG: SOFT_RESET_CONFIG.
const SOFT_RESET: u8 = 1 << 0;
/// INT_STATUS: FIFO_FULL_INT.
const INT_FIFO_FULL: u8 = 1 << 1;
/// SIGNAL_PATH_RESET: FIFO_FLUSH.
const FIFO_FLUSH: u8 = 1 << 1;
/// FIFO_CONFIG: stream-to-FIFO mode (0 after a reset: bypass).
const FIFO_STREAM: u8 = 0b0100_0000;
/// FIFO_CONFIG1: FIFO_TEMP_EN, FIFO_GYRO_EN, FIFO_ACCEL_EN (packet 3).
const FIFO_TEMP_GYRO_ACCEL: u8 = 0b0000_0111;
/// PWR_MGMT0: GYRO_MODE and ACCEL_MODE low noise.
const PWR_LOW_NOISE: u8 = 0b0000_1111;
/// Packet 3: header, accel x/y/z, gyro x/y/z (big-endian), temperature (1 byte), timestamp (2).
const PACKET: usize = 16;
/// FIFO size: 2 KiB.
const FIFO_BYTES: u16 = 2048;
/// Header bits: HEADER_MSG (7, FIFO empty), HEADER_ACCEL (6), HEADER_GYRO (5), HEADER_20 (4,
/// a 20-byte packet 4).
const HEADER_EMPTY: u8 = 1 << 7;
const HEADER_ACCEL_GYRO: u8 = 0b0110_0000;
const HEADER_20: u8 = 1 << 4;
/// The invalid-data marker of a 16-bit FIFO field (TDK's driver: `INVALID_VALUE_FIFO`).
const INVALID: i16 = i16::MIN;
/// The invalid-data marker of the 8-bit FIFO temperature (`INVALID_VALUE_FIFO_1B`).
const INVALID_TEMP: i8 = i8::MIN;

/// Gyro full-scale range (GYRO_FS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IcmGyroRange {
    /// +-2000 deg/s, 16.4 counts per deg/s.
    #[default]
    Dps2000 = 0,
    /// +-1000 deg/s, 32.8 counts per deg/s.
    Dps1000 = 1,
    /// +-500 deg/s, 65.5 counts per deg/s.
    Dps500 = 2,
    /// +-250 deg/s, 131 counts per deg/s.
    Dps250 = 3,
    /// +-125 deg/s, 262 counts per deg/s.
    Dps125 = 4,
    /// +-62.5 deg/s, 524.3 counts per deg/s.
    Dps62_5 = 5,
    /// +-31.25 deg/s, 1048.6 counts per deg/s.
    Dps31_25 = 6,
    /// +-15.625 deg/s, 2097.2 counts per deg/s.
    Dps15_625 = 7,
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
}

/// Accelerometer full-scale range (ACCEL_FS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IcmAccelRange {
    /// +-16 g, 2048 counts per g.
    #[default]
    G16 = 0,
    /// +-8 g, 4096 counts per g.
    G8 = 1,
    /// +-4 g, 8192 counts per g.
    G4 = 2,
    /// +-2 g, 16384 counts per g.
    G2 = 3,
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
}

/// Output data rate (GYRO_ODR / ACCEL_ODR codes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Odr {
    /// 8 kHz.
    Hz8000 = 3,
    /// 4 kHz.
    Hz4000 = 4,
    /// 2 kHz.
    Hz2000 = 5,
    /// 1 kHz.
    Hz1000 = 6,
    /// 500 Hz.
    Hz500 = 15,
    /// 200 Hz.
    Hz200 = 7,
    /// 100 Hz.
    #[default]
    Hz100 = 8,
    /// 50 Hz.
    Hz50 = 9,
    /// 25 Hz.
    Hz25 = 10,
}

impl Odr {
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

/// Configuration written by [`Icm42688::init`] (gyro and accelerometer at the same rate).
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

/// An ICM-42688-P on an SPI device.
///
/// ```
/// # use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
/// # struct Bus;
/// # impl ErrorType for Bus { type Error = core::convert::Infallible; }
/// # impl SpiDevice for Bus {
/// #     fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
/// #         let mut reg = 0;
/// #         for op in ops {
/// #             match op {
/// #                 Operation::Write(w) => reg = w[0],
/// #                 Operation::Read(b) => {
/// #                     b.fill(0);
/// #                     if reg == 0xF5 { b[0] = 0x47; } // WHO_AM_I
/// #                     if reg == 0x96 { b[0] = 0x40; } // FIFO_CONFIG: stream mode
/// #                     if reg == 0xCE { b[0] = 0x0F; } // PWR_MGMT0: low noise
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
/// let mut imu = Icm42688::new(Bus);
/// imu.init(&mut Delay, Icm42688Config::default())?;
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
#[derive(Debug)]
pub struct Icm42688<SPI> {
    spi: SPI,
    config: Icm42688Config,
    fifo: FifoState,
}

impl<SPI: SpiDevice> Icm42688<SPI> {
    /// A reader on `spi` (mode 0 or 3); no bus traffic until `init`.
    pub fn new(spi: SPI) -> Self {
        Self {
            spi,
            config: Icm42688Config::default(),
            fifo: FifoState::default(),
        }
    }

    /// Gives the bus back.
    pub fn destroy(self) -> SPI {
        self.spi
    }

    fn write(&mut self, reg: u8, value: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg, value])?;
        Ok(())
    }

    fn read_regs(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg | READ]), Operation::Read(buf)])?;
        Ok(())
    }

    /// WHO_AM_I.
    ///
    /// # Errors
    ///
    /// [`Error::Bus`].
    pub fn who_am_i(&mut self) -> Result<u8, Error<SPI::Error>> {
        let mut id = [0];
        self.read_regs(WHO_AM_I, &mut id)?;
        Ok(id[0])
    }

    /// Probes WHO_AM_I (0x47), soft-resets the chip (1 ms), writes ranges and rates and puts
    /// gyro and accelerometer in low-noise mode (then 1 ms; the gyro needs about 30 ms more
    /// before its data are valid: until then the FIFO carries the invalid marker, and those
    /// packets are skipped and counted in [`FifoStats::invalid`]). The FIFO is off afterwards.
    /// `enable_fifo` and `recover` need a successful `init` first.
    ///
    /// # Errors
    ///
    /// [`Error::WrongDevice`] or [`Error::Bus`]; after a bus error `init` can be called again.
    pub fn init(
        &mut self,
        delay: &mut impl DelayNs,
        config: Icm42688Config,
    ) -> Result<(), Error<SPI::Error>> {
        self.fifo.off();
        self.configure(delay, config)?;
        self.fifo.initialised = true;
        Ok(())
    }

    fn configure(
        &mut self,
        delay: &mut impl DelayNs,
        config: Icm42688Config,
    ) -> Result<(), Error<SPI::Error>> {
        let id = self.who_am_i()?;
        if id != ID {
            return Err(Error::WrongDevice { found: id });
        }
        self.write(DEVICE_CONFIG, SOFT_RESET)?;
        delay.delay_ms(1);
        self.write(
            GYRO_CONFIG0,
            (config.gyro_range as u8) << 5 | config.odr as u8,
        )?;
        self.write(
            ACCEL_CONFIG0,
            (config.accel_range as u8) << 5 | config.odr as u8,
        )?;
        self.write(PWR_MGMT0, PWR_LOW_NOISE)?;
        delay.delay_ms(1);
        self.config = config;
        Ok(())
    }

    /// Brings the chip back after [`Error::SensorReset`], [`Error::FifoNotRunning`] (or any
    /// suspected glitch): probes WHO_AM_I, writes the last configuration again and re-enables
    /// the FIFO if `enable_fifo` was called since `init`. `outage_us` is the time in
    /// microseconds from the last `read_fifo` that accounted for the FIFO (see
    /// [`FifoStats::lost`]) to the FIFO running again, by the caller's clock: the time of the
    /// call plus the 2 ms of the chip reset and start; the samples the chip produced in it are
    /// counted in [`FifoStats::lost`]. A recovery after [`Error::SensorReset`] is counted in
    /// [`FifoStats::resets`]. A FIFO reset still pending (an overflow, a failed read) is
    /// replaced by the recovery and counted as done; its samples are inside the outage.
    ///
    /// # Errors
    ///
    /// [`Error::NotInitialised`] before `init`; otherwise as [`Icm42688::init`]; nothing is
    /// counted until the recovery succeeds, and until then `read_fifo` returns
    /// [`Error::FifoNotRunning`]: it can simply be called again.
    pub fn recover(
        &mut self,
        delay: &mut impl DelayNs,
        outage_us: u64,
    ) -> Result<(), Error<SPI::Error>> {
        if !self.fifo.initialised {
            return Err(Error::NotInitialised);
        }
        self.fifo.recovering();
        self.configure(delay, self.config)?;
        if self.fifo.wanted {
            self.enable_fifo()?;
        }
        self.fifo
            .recovered(outage_us, self.config.odr.millihz(), 1000);
        Ok(())
    }

    /// The configuration written by the last `init`.
    pub fn config(&self) -> &Icm42688Config {
        &self.config
    }

    /// Enables the FIFO in stream mode with packet 3 (accelerometer, gyro, temperature,
    /// timestamp: 16 bytes) and flushes it. Samples in the FIFO (one left running by an earlier
    /// call that failed part-way) are counted in [`FifoStats::discarded`].
    ///
    /// # Errors
    ///
    /// [`Error::NotInitialised`] before `init`; [`Error::SensorReset`] when the chip has
    /// reset itself (call `recover`); [`Error::Bus`] (or [`Error::BadFifoCount`]): until a
    /// later call (or `recover`) succeeds, `read_fifo` returns [`Error::FifoNotRunning`].
    pub fn enable_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        fifo::enable(self)
    }

    /// Temperature in deg C from a raw register value: `raw / 132.48 + 25`. FIFO samples carry
    /// the 8-bit FIFO temperature (`t / 2.07 + 25`) scaled by 64 into the same 16-bit form.
    pub fn temperature_celsius(raw: i16) -> f32 {
        f32::from(raw) / 132.48 + 25.0
    }

    fn fifo_count(&mut self) -> Result<u16, Error<SPI::Error>> {
        let mut b = [0; 2];
        self.read_regs(FIFO_COUNTH, &mut b)?;
        Ok(u16::from_be_bytes(b))
    }
}

impl<SPI: SpiDevice> FifoChip for Icm42688<SPI> {
    type BusError = SPI::Error;
    const PACKET: usize = PACKET;
    const FIFO_BYTES: u16 = FIFO_BYTES;
    const CONFIRM_COUNT: bool = false;

    fn state(&mut self) -> &mut FifoState {
        &mut self.fifo
    }

    fn overflow_flag(&mut self) -> Result<bool, Error<SPI::Error>> {
        let mut status = [0];
        self.read_regs(INT_STATUS, &mut status)?;
        Ok(status[0] & INT_FIFO_FULL != 0)
    }

    fn fifo_count(&mut self) -> Result<u16, Error<SPI::Error>> {
        Icm42688::fifo_count(self)
    }

    fn fifo_configured(&mut self) -> Result<bool, Error<SPI::Error>> {
        let mut mode = [0];
        self.read_regs(FIFO_CONFIG, &mut mode)?;
        Ok(mode[0] == FIFO_STREAM)
    }

    /// PWR_MGMT0: gyro and accelerometer not in low-noise mode (off after a reset).
    fn chip_reset(&mut self) -> Result<bool, Error<SPI::Error>> {
        let mut pwr = [0];
        self.read_regs(PWR_MGMT0, &mut pwr)?;
        Ok(pwr[0] & PWR_LOW_NOISE != PWR_LOW_NOISE)
    }

    fn prepare_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write(FIFO_CONFIG, FIFO_STREAM)
    }

    /// SIGNAL_PATH_RESET.FIFO_FLUSH between FIFO_CONFIG1 = 0 (channels off) and the channels
    /// on again. Neither the datasheet nor ArduPilot asks for the channels to be off for a
    /// flush (libraries/AP_InertialSensor/AP_InertialSensor_Invensensev3.cpp,
    /// `AP_InertialSensor_Invensensev3::fifo_reset`, writes FIFO_CONFIG1 with accel, gyro and
    /// temperature on and then SIGNAL_PATH_RESET = 2); they are taken off here so that nothing
    /// enters the FIFO between the count read after this step and the flush, nor while a
    /// flush is in doubt (a write that reported a failure may still have been done), which
    /// keeps the count of discarded samples exact.
    fn stop_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write(FIFO_CONFIG1, 0)
    }

    fn empty_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write(SIGNAL_PATH_RESET, FIFO_FLUSH)
    }

    fn start_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write(FIFO_CONFIG1, FIFO_TEMP_GYRO_ACCEL)
    }

    fn read_data(&mut self, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.read_regs(FIFO_DATA, buf)
    }

    fn parse(p: &[u8]) -> Packet {
        let header = p.first().copied().unwrap_or(HEADER_EMPTY);
        if header & HEADER_EMPTY != 0 {
            return Packet::End;
        }
        if header & (HEADER_ACCEL_GYRO | HEADER_20) != HEADER_ACCEL_GYRO {
            return Packet::Malformed;
        }
        let (accel, gyro) = (be_i16x3(p, 1), be_i16x3(p, 7));
        let temp = p.get(13).map(|&t| t as i8);
        if accel.contains(&INVALID) || gyro.contains(&INVALID) || temp == Some(INVALID_TEMP) {
            return Packet::Invalid;
        }
        Packet::Sample(RawSample {
            accel,
            gyro,
            temperature: temp.map(|t| i16::from(t) * 64),
        })
    }
}

impl<SPI: SpiDevice> ImuReader for Icm42688<SPI> {
    type BusError = SPI::Error;

    fn scale(&self) -> Scale {
        self.config.scale()
    }

    /// One burst read of TEMP_DATA1 .. GYRO_DATA_Z0. Data registers holding the invalid-data
    /// marker (-32768, while a sensor is starting) give [`Error::NoData`]; they are no FIFO
    /// packet, and are not counted in [`FifoStats::invalid`].
    fn read(&mut self) -> Result<RawSample, Error<SPI::Error>> {
        let mut b = [0u8; 14];
        self.read_regs(TEMP_DATA1, &mut b)?;
        let s = RawSample {
            temperature: Some(be_i16(&b, 0)),
            accel: be_i16x3(&b, 2),
            gyro: be_i16x3(&b, 8),
        };
        if s.accel.contains(&INVALID) || s.gyro.contains(&INVALID) || s.temperature == Some(INVALID)
        {
            return Err(Error::NoData);
        }
        Ok(s)
    }

    /// Reads INT_STATUS and FIFO_COUNT first. On FIFO_FULL_INT, or a count at or above the
    /// FIFO's 2048 bytes, the FIFO is flushed (its complete packets are counted as discarded)
    /// and [`Error::FifoOverflow`] is returned. Otherwise whole packets (up to `out.len()`)
    /// are read, 8 per SPI transaction; a packet whose header does not announce accelerometer
    /// and gyro data, or announces a 20-byte packet (HEADER_20), is skipped and counted as
    /// malformed, one carrying the invalid-data marker (-32768, or -128 for the temperature)
    /// is skipped and counted as invalid, and a header with HEADER_MSG set (FIFO empty) inside
    /// the counted bytes is a damaged header: counted as malformed, the packets after it in
    /// the same transaction parsed, and the batch ended (the rest stays in the FIFO). A count
    /// above the FIFO's 2048 bytes is no count ([`Error::BadFifoCount`], nothing read). A read that fails part-way is followed
    /// by a flush, as TDK's driver does: the samples of the call and those left in the FIFO
    /// are counted as discarded and [`Error::FifoResync`] is returned. A flush that meets a bus
    /// error itself is remembered and finished by the next call.
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<SPI::Error>> {
        fifo::read_fifo(self, out)
    }

    fn fifo_stats(&self) -> FifoStats {
        self.fifo.stats
    }
}
