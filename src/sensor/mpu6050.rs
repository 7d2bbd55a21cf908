//! InvenSense MPU-6050 over I2C (and the register-compatible subset of MPU-6500/MPU-9250).
//!
//! Registers, bits and scale factors from "MPU-6000 and MPU-6050 Register Map and
//! Descriptions", RM-MPU-6000A-00 revision 4.2 (register numbers below), and "MPU-6000 and
//! MPU-6050 Product Specification", PS-MPU-6000A-00 revision 3.4, sections 6.1 (gyro
//! sensitivity) and 6.2 (accelerometer sensitivity).

use embedded_hal::delay::DelayNs;
use embedded_hal::i2c::I2c;

use super::{Error, FifoStats, ImuReader, Packet, RawSample, Scale, be_i16, be_i16x3};

/// Register 25, SMPLRT_DIV: sample rate = gyro output rate / (1 + SMPLRT_DIV).
const SMPLRT_DIV: u8 = 0x19;
/// Register 26, CONFIG: DLPF_CFG in bits 2:0.
const CONFIG: u8 = 0x1A;
/// Register 27, GYRO_CONFIG: FS_SEL in bits 4:3.
const GYRO_CONFIG: u8 = 0x1B;
/// Register 28, ACCEL_CONFIG: AFS_SEL in bits 4:3.
const ACCEL_CONFIG: u8 = 0x1C;
/// Register 35, FIFO_EN: XG (6), YG (5), ZG (4), ACCEL (3).
const FIFO_EN: u8 = 0x23;
/// Register 56, INT_ENABLE: FIFO_OFLOW_EN in bit 4.
const INT_ENABLE: u8 = 0x38;
/// Register 58, INT_STATUS: FIFO_OFLOW_INT in bit 4, cleared by reading.
const INT_STATUS: u8 = 0x3A;
/// Registers 59-72: ACCEL_XOUT_H .. GYRO_ZOUT_L, big-endian, temperature at 65-66.
const ACCEL_XOUT_H: u8 = 0x3B;
/// Register 106, USER_CTRL: FIFO_EN (6), FIFO_RESET (2).
const USER_CTRL: u8 = 0x6A;
/// Register 107, PWR_MGMT_1: DEVICE_RESET (7), SLEEP (6), CLKSEL (2:0).
const PWR_MGMT_1: u8 = 0x6B;
/// Registers 114-115, FIFO_COUNTH/L: bytes in the FIFO, big-endian.
const FIFO_COUNTH: u8 = 0x72;
/// Register 116, FIFO_R_W.
const FIFO_R_W: u8 = 0x74;
/// Register 117, WHO_AM_I.
const WHO_AM_I: u8 = 0x75;

const FIFO_OFLOW: u8 = 1 << 4;
const USER_CTRL_FIFO_EN: u8 = 1 << 6;
const USER_CTRL_FIFO_RESET: u8 = 1 << 2;
/// XG | YG | ZG | ACCEL: each FIFO packet is accel x, y, z then gyro x, y, z (register order).
const FIFO_EN_ACCEL_GYRO: u8 = 0b0111_1000;
/// Bytes per FIFO packet with accelerometer and gyro enabled.
const PACKET: usize = 12;

/// WHO_AM_I of the MPU-6050, MPU-6500 and MPU-9250.
const KNOWN_IDS: [u8; 3] = [0x68, 0x70, 0x71];

/// Gyro full-scale range (FS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GyroRange {
    /// +-250 deg/s, 131 counts per deg/s.
    #[default]
    Dps250 = 0,
    /// +-500 deg/s, 65.5 counts per deg/s.
    Dps500 = 1,
    /// +-1000 deg/s, 32.8 counts per deg/s.
    Dps1000 = 2,
    /// +-2000 deg/s, 16.4 counts per deg/s.
    Dps2000 = 3,
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
}

/// Accelerometer full-scale range (AFS_SEL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelRange {
    /// +-2 g, 16384 counts per g.
    #[default]
    G2 = 0,
    /// +-4 g, 8192 counts per g.
    G4 = 1,
    /// +-8 g, 4096 counts per g.
    G8 = 2,
    /// +-16 g, 2048 counts per g.
    G16 = 3,
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
}

/// Digital low-pass filter (DLPF_CFG); the accelerometer bandwidth is given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Dlpf {
    /// 260 Hz, gyro output rate 8 kHz.
    Hz260 = 0,
    /// 184 Hz.
    Hz184 = 1,
    /// 94 Hz.
    Hz94 = 2,
    /// 44 Hz.
    #[default]
    Hz44 = 3,
    /// 21 Hz.
    Hz21 = 4,
    /// 10 Hz.
    Hz10 = 5,
    /// 5 Hz.
    Hz5 = 6,
}

/// Configuration written by [`Mpu6050::init`].
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
        let gyro_rate = if self.dlpf == Dlpf::Hz260 {
            8000.0
        } else {
            1000.0
        };
        gyro_rate / (1.0 + f32::from(self.sample_rate_divider))
    }

    /// The sensitivities of this configuration.
    pub fn scale(&self) -> Scale {
        Scale {
            gyro_counts_per_dps: self.gyro_range.counts_per_dps(),
            accel_counts_per_g: self.accel_range.counts_per_g(),
        }
    }
}

/// An MPU-6050 on an I2C bus.
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
/// use imu_ar::recursive::{Config, Lattice};
/// use imu_ar::sensor::{GyroUnit, ImuReader, Mpu6050, Mpu6050Config};
///
/// let mut imu = Mpu6050::new(Bus, 0x68);
/// imu.init(&mut Delay, Mpu6050Config::default())?;
/// let config = Config::new(0.999f32, 1e-4, 0.01).unwrap();
/// let mut axes = [Lattice::<f32, 4>::new(&config); 6];
/// let sample = imu.read()?;
/// let gyro = imu.scale().gyro(sample.gyro, GyroUnit::DegPerSec);
/// let accel = imu.scale().accel(sample.accel, imu_ar::sensor::AccelUnit::G);
/// for (lattice, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
///     lattice.update(&config, x);
/// }
/// let bus: Bus = imu.destroy();
/// # Ok::<(), imu_ar::sensor::Error<core::convert::Infallible>>(())
/// ```
#[derive(Debug)]
pub struct Mpu6050<I2C> {
    i2c: I2C,
    address: u8,
    config: Mpu6050Config,
    fifo: bool,
    stats: FifoStats,
}

impl<I2C: I2c> Mpu6050<I2C> {
    /// A reader at `address` (0x68, or 0x69 with AD0 high); no bus traffic until `init`.
    pub fn new(i2c: I2C, address: u8) -> Self {
        Self {
            i2c,
            address,
            config: Mpu6050Config::default(),
            fifo: false,
            stats: FifoStats::default(),
        }
    }

    /// Gives the bus back.
    pub fn destroy(self) -> I2C {
        self.i2c
    }

    fn write(&mut self, reg: u8, value: u8) -> Result<(), Error<I2C::Error>> {
        self.i2c.write(self.address, &[reg, value])?;
        Ok(())
    }

    fn read_regs(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Error<I2C::Error>> {
        self.i2c.write_read(self.address, &[reg], buf)?;
        Ok(())
    }

    /// WHO_AM_I (register 117).
    ///
    /// # Errors
    ///
    /// [`Error::Bus`].
    pub fn who_am_i(&mut self) -> Result<u8, Error<I2C::Error>> {
        let mut id = [0];
        self.read_regs(WHO_AM_I, &mut id)?;
        Ok(id[0])
    }

    /// Probes WHO_AM_I, resets the chip (DEVICE_RESET, then 100 ms), wakes it on the X-gyro
    /// PLL clock and writes `config`. Returns the WHO_AM_I value (0x68 MPU-6050, 0x70
    /// MPU-6500, 0x71 MPU-9250). The FIFO is off afterwards.
    ///
    /// # Errors
    ///
    /// [`Error::WrongDevice`] or [`Error::Bus`]; after a bus error `init` can simply be called
    /// again.
    pub fn init(
        &mut self,
        delay: &mut impl DelayNs,
        config: Mpu6050Config,
    ) -> Result<u8, Error<I2C::Error>> {
        let id = self.who_am_i()?;
        if !KNOWN_IDS.contains(&id) {
            return Err(Error::WrongDevice { found: id });
        }
        self.write(PWR_MGMT_1, 0x80)?;
        delay.delay_ms(100);
        self.write(PWR_MGMT_1, 0x01)?;
        self.write(SMPLRT_DIV, config.sample_rate_divider)?;
        self.write(CONFIG, config.dlpf as u8)?;
        self.write(GYRO_CONFIG, (config.gyro_range as u8) << 3)?;
        self.write(ACCEL_CONFIG, (config.accel_range as u8) << 3)?;
        self.config = config;
        self.fifo = false;
        Ok(id)
    }

    /// Brings the chip back after [`Error::SensorReset`] (or any suspected glitch): probes
    /// WHO_AM_I, writes the last configuration again and re-enables the FIFO if it was on.
    /// `outage_us` is the time from the last good FIFO read to now, by the caller's clock; the
    /// samples the chip produced in it are counted in [`FifoStats::lost`]. Returns WHO_AM_I.
    ///
    /// # Errors
    ///
    /// As [`Mpu6050::init`]; nothing is counted until the recovery succeeds, so it can simply
    /// be called again.
    pub fn recover(
        &mut self,
        delay: &mut impl DelayNs,
        outage_us: u32,
    ) -> Result<u8, Error<I2C::Error>> {
        let fifo = self.fifo;
        let id = self.init(delay, self.config)?;
        if fifo {
            self.enable_fifo()?;
        }
        self.stats
            .recovered(outage_us, self.config.sample_rate_hz());
        Ok(id)
    }

    /// The configuration written by the last `init`.
    pub fn config(&self) -> &Mpu6050Config {
        &self.config
    }

    /// Resets and enables the FIFO with accelerometer and gyro samples (12 bytes each) and the
    /// overflow flag.
    ///
    /// # Errors
    ///
    /// [`Error::Bus`].
    pub fn enable_fifo(&mut self) -> Result<(), Error<I2C::Error>> {
        self.write(USER_CTRL, USER_CTRL_FIFO_RESET)?;
        self.write(FIFO_EN, FIFO_EN_ACCEL_GYRO)?;
        self.write(INT_ENABLE, FIFO_OFLOW)?;
        self.write(USER_CTRL, USER_CTRL_FIFO_EN)?;
        self.fifo = true;
        Ok(())
    }

    /// Temperature in deg C from the raw value: `raw / 340 + 36.53` (register map, registers
    /// 65-66).
    pub fn temperature_celsius(raw: i16) -> f32 {
        f32::from(raw) / 340.0 + 36.53
    }

    fn fifo_count(&mut self) -> Result<u16, Error<I2C::Error>> {
        let mut b = [0; 2];
        self.read_regs(FIFO_COUNTH, &mut b)?;
        Ok(u16::from_be_bytes(b))
    }
}

impl<I2C: I2c> ImuReader for Mpu6050<I2C> {
    type BusError = I2C::Error;

    fn scale(&self) -> Scale {
        self.config.scale()
    }

    /// One burst read of registers 59-72.
    fn read(&mut self) -> Result<RawSample, Error<I2C::Error>> {
        let mut b = [0u8; 14];
        self.read_regs(ACCEL_XOUT_H, &mut b)?;
        Ok(RawSample {
            accel: be_i16x3(&b, 0),
            temperature: Some(be_i16(&b, 6)),
            gyro: be_i16x3(&b, 8),
        })
    }

    /// Reads INT_STATUS first: on FIFO_OFLOW_INT the FIFO is reset (its complete packets are
    /// counted as discarded) and [`Error::FifoOverflow`] is returned. An empty FIFO is checked
    /// against USER_CTRL: a chip that has reset itself has its FIFO off, and
    /// [`Error::SensorReset`] is returned (see [`Mpu6050::recover`]). Otherwise the whole
    /// packets in the FIFO (up to `out.len()`) are read, 8 per I2C transfer; a partial packet
    /// stays in the FIFO for the next call. A bus error after some packets were read loses them:
    /// they are counted in [`FifoStats::discarded`].
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<I2C::Error>> {
        if !self.fifo {
            return Err(Error::FifoDisabled);
        }
        let mut status = [0];
        self.read_regs(INT_STATUS, &mut status)?;
        if status[0] & FIFO_OFLOW != 0 {
            let bytes = self.fifo_count()?;
            self.write(USER_CTRL, USER_CTRL_FIFO_RESET)?;
            self.write(USER_CTRL, USER_CTRL_FIFO_EN)?;
            return Err(self.stats.overflow(bytes, PACKET));
        }
        let available = usize::from(self.fifo_count()?) / PACKET;
        if available == 0 {
            // An empty FIFO may be a chip that reset itself: its FIFO is then off.
            let mut user_ctrl = [0];
            self.read_regs(USER_CTRL, &mut user_ctrl)?;
            if user_ctrl[0] & USER_CTRL_FIFO_EN == 0 {
                return Err(Error::SensorReset);
            }
        }
        let (i2c, address) = (&mut self.i2c, self.address);
        let read = |buf: &mut [u8]| {
            i2c.write_read(address, &[FIFO_R_W], buf)
                .map_err(Error::Bus)
        };
        self.stats.drain(available, PACKET, out, read, |p| {
            Packet::Sample(RawSample {
                accel: be_i16x3(p, 0),
                gyro: be_i16x3(p, 6),
                temperature: None,
            })
        })
    }

    fn fifo_stats(&self) -> FifoStats {
        self.stats
    }
}
