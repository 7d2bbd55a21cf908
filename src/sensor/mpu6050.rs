//! InvenSense MPU-6050 over I2C. The MPU-6500 and MPU-9250 answer the same protocol but differ
//! in their temperature formula, in how SMPLRT_DIV applies with the 260 Hz filter and in their
//! accelerometer filter register (ACCEL_CONFIG2, 0x1D): they are rejected with
//! [`Error::UnsupportedDevice`] rather than handled with MPU-6050 formulas.
//!
//! Registers, bits and scale factors from "MPU-6000 and MPU-6050 Register Map and
//! Descriptions", RM-MPU-6000A-00 revision 4.2 (register numbers below), and "MPU-6000 and
//! MPU-6050 Product Specification", PS-MPU-6000A-00 revision 3.4, sections 6.1 (gyro
//! sensitivity) and 6.2 (accelerometer sensitivity).

use embedded_hal::delay::DelayNs;
use embedded_hal::i2c::I2c;

use super::fifo::{self, FifoChip, FifoState};
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

/// INT_STATUS and INT_ENABLE: FIFO_OFLOW_INT / FIFO_OFLOW_EN.
const INT_FIFO_OFLOW: u8 = 1 << 4;
/// USER_CTRL: FIFO_EN.
const USER_CTRL_FIFO_EN: u8 = 1 << 6;
/// USER_CTRL: FIFO_RESET (self-clearing; resets the FIFO "while FIFO_EN equals 0").
const USER_CTRL_FIFO_RESET: u8 = 1 << 2;
/// PWR_MGMT_1: DEVICE_RESET.
const PWR_DEVICE_RESET: u8 = 1 << 7;
/// PWR_MGMT_1: awake (SLEEP clear), clock from the X-gyro PLL (CLKSEL = 1).
const PWR_CLK_PLL_X: u8 = 0x01;
/// PWR_MGMT_1: SLEEP and CLKSEL, compared with [`PWR_CLK_PLL_X`] to detect a chip reset (its
/// power-on value is SLEEP set, CLKSEL 0).
const PWR_SLEEP_CLKSEL: u8 = 0x47;
/// FIFO_EN: XG_FIFO_EN.
const FIFO_EN_XG: u8 = 1 << 6;
/// FIFO_EN: YG_FIFO_EN.
const FIFO_EN_YG: u8 = 1 << 5;
/// FIFO_EN: ZG_FIFO_EN.
const FIFO_EN_ZG: u8 = 1 << 4;
/// FIFO_EN: ACCEL_FIFO_EN.
const FIFO_EN_ACCEL: u8 = 1 << 3;
/// Each FIFO packet is accel x, y, z then gyro x, y, z (register order).
const FIFO_EN_ACCEL_GYRO: u8 = FIFO_EN_XG | FIFO_EN_YG | FIFO_EN_ZG | FIFO_EN_ACCEL;
/// Bytes per FIFO packet with accelerometer and gyro enabled.
const PACKET: usize = 12;
/// FIFO size (register map, FIFO_COUNT: 1024 bytes).
const FIFO_BYTES: u16 = 1024;

/// WHO_AM_I of the MPU-6050.
const MPU6050_ID: u8 = 0x68;
/// WHO_AM_I of the MPU-6500 and MPU-9250: recognised, and rejected.
const UNSUPPORTED_IDS: [u8; 2] = [0x70, 0x71];

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

impl Dlpf {
    /// The gyro output rate in Hz: 8 kHz with [`Dlpf::Hz260`], otherwise 1 kHz.
    fn gyro_rate_hz(self) -> u32 {
        if self == Self::Hz260 { 8000 } else { 1000 }
    }
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
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
/// use imu_ar::sensor::{GyroUnit, ImuReader, Mpu6050, Mpu6050Config};
///
/// let mut imu = Mpu6050::new(Bus, 0x68);
/// imu.init(&mut Delay, Mpu6050Config::default())?;
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
#[derive(Debug)]
pub struct Mpu6050<I2C> {
    i2c: I2C,
    address: u8,
    config: Mpu6050Config,
    fifo: FifoState,
}

impl<I2C: I2c> Mpu6050<I2C> {
    /// A reader at `address` (0x68, or 0x69 with AD0 high); no bus traffic until `init`.
    pub fn new(i2c: I2C, address: u8) -> Self {
        Self {
            i2c,
            address,
            config: Mpu6050Config::default(),
            fifo: FifoState::default(),
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
    /// PLL clock and writes `config`. Returns the WHO_AM_I value, 0x68. The FIFO is off
    /// afterwards. `enable_fifo` and `recover` need a successful `init` first.
    ///
    /// # Errors
    ///
    /// [`Error::UnsupportedDevice`] for an MPU-6500 or MPU-9250 (0x70, 0x71),
    /// [`Error::WrongDevice`] for anything else, or [`Error::Bus`]; after a bus error `init`
    /// can simply be called again.
    pub fn init(
        &mut self,
        delay: &mut impl DelayNs,
        config: Mpu6050Config,
    ) -> Result<u8, Error<I2C::Error>> {
        self.fifo.off();
        let id = self.configure(delay, config)?;
        self.fifo.initialised = true;
        Ok(id)
    }

    fn configure(
        &mut self,
        delay: &mut impl DelayNs,
        config: Mpu6050Config,
    ) -> Result<u8, Error<I2C::Error>> {
        let id = self.who_am_i()?;
        if UNSUPPORTED_IDS.contains(&id) {
            return Err(Error::UnsupportedDevice { found: id });
        }
        if id != MPU6050_ID {
            return Err(Error::WrongDevice { found: id });
        }
        self.write(PWR_MGMT_1, PWR_DEVICE_RESET)?;
        delay.delay_ms(100);
        self.write(PWR_MGMT_1, PWR_CLK_PLL_X)?;
        self.write(SMPLRT_DIV, config.sample_rate_divider)?;
        self.write(CONFIG, config.dlpf as u8)?;
        self.write(GYRO_CONFIG, (config.gyro_range as u8) << 3)?;
        self.write(ACCEL_CONFIG, (config.accel_range as u8) << 3)?;
        self.config = config;
        Ok(id)
    }

    /// Brings the chip back after [`Error::SensorReset`], [`Error::FifoNotRunning`] (or any
    /// suspected glitch): probes WHO_AM_I, writes the last configuration again and re-enables
    /// the FIFO if `enable_fifo` was called since `init`. `outage_us` is the time in
    /// microseconds from the last `read_fifo` that accounted for the FIFO (see
    /// [`FifoStats::lost`]) to the FIFO running again, by the caller's clock: the time of the
    /// call plus the 100 ms of the chip reset (the caller cannot read its clock after
    /// `recover` and still count on it); the samples the chip produced in it are counted in
    /// [`FifoStats::lost`]. A recovery after [`Error::SensorReset`] is counted in
    /// [`FifoStats::resets`]. A FIFO reset still pending (an overflow, a failed read) is
    /// replaced by the recovery and counted as done; its samples are inside the outage.
    /// Returns WHO_AM_I.
    ///
    /// # Errors
    ///
    /// [`Error::NotInitialised`] before `init`; otherwise as [`Mpu6050::init`]; nothing is
    /// counted until the recovery succeeds, and until then `read_fifo` returns
    /// [`Error::FifoNotRunning`]: it can simply be called again.
    pub fn recover(
        &mut self,
        delay: &mut impl DelayNs,
        outage_us: u64,
    ) -> Result<u8, Error<I2C::Error>> {
        if !self.fifo.initialised {
            return Err(Error::NotInitialised);
        }
        self.fifo.recovering();
        let id = self.configure(delay, self.config)?;
        if self.fifo.wanted {
            self.enable_fifo()?;
        }
        self.fifo.recovered(
            outage_us,
            self.config.dlpf.gyro_rate_hz(),
            1 + u32::from(self.config.sample_rate_divider),
        );
        Ok(id)
    }

    /// The configuration written by the last `init`.
    pub fn config(&self) -> &Mpu6050Config {
        &self.config
    }

    /// Enables the overflow flag and resets and enables the FIFO with accelerometer and gyro
    /// samples (12 bytes each). Samples in the FIFO (one left running by an earlier call that
    /// failed part-way) are counted in [`FifoStats::discarded`].
    ///
    /// # Errors
    ///
    /// [`Error::NotInitialised`] before `init`; [`Error::SensorReset`] when the chip has
    /// reset itself (call `recover`); [`Error::Bus`] (or [`Error::BadFifoCount`]): until a
    /// later call (or `recover`) succeeds, `read_fifo` returns [`Error::FifoNotRunning`].
    pub fn enable_fifo(&mut self) -> Result<(), Error<I2C::Error>> {
        fifo::enable(self)
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

impl<I2C: I2c> FifoChip for Mpu6050<I2C> {
    type BusError = I2C::Error;
    const PACKET: usize = PACKET;
    const FIFO_BYTES: u16 = FIFO_BYTES;
    const CONFIRM_COUNT: bool = true;

    fn state(&mut self) -> &mut FifoState {
        &mut self.fifo
    }

    fn overflow_flag(&mut self) -> Result<bool, Error<I2C::Error>> {
        let mut status = [0];
        self.read_regs(INT_STATUS, &mut status)?;
        Ok(status[0] & INT_FIFO_OFLOW != 0)
    }

    fn fifo_count(&mut self) -> Result<u16, Error<I2C::Error>> {
        Mpu6050::fifo_count(self)
    }

    /// USER_CTRL and PWR_MGMT_1 in one read: the FIFO on, and the chip awake on its PLL clock
    /// (a chip reset leaves it asleep; `enable_fifo` could have set USER_CTRL.FIFO_EN on it).
    fn fifo_configured(&mut self) -> Result<bool, Error<I2C::Error>> {
        let mut b = [0; 2];
        self.read_regs(USER_CTRL, &mut b)?;
        Ok(b[0] & USER_CTRL_FIFO_EN != 0 && b[1] & PWR_SLEEP_CLKSEL == PWR_CLK_PLL_X)
    }

    /// PWR_MGMT_1: asleep, or not on the PLL clock.
    fn chip_reset(&mut self) -> Result<bool, Error<I2C::Error>> {
        let mut pwr = [0];
        self.read_regs(PWR_MGMT_1, &mut pwr)?;
        Ok(pwr[0] & PWR_SLEEP_CLKSEL != PWR_CLK_PLL_X)
    }

    fn prepare_fifo(&mut self) -> Result<(), Error<I2C::Error>> {
        self.write(INT_ENABLE, INT_FIFO_OFLOW)
    }

    /// The channels are taken off the FIFO before it is reset, as ArduPilot does
    /// (libraries/AP_InertialSensor/AP_InertialSensor_Invensense.cpp,
    /// `AP_InertialSensor_Invensense::_fifo_reset`: FIFO_EN = 0, USER_CTRL without FIFO_EN,
    /// USER_CTRL | FIFO_RESET, USER_CTRL | FIFO_EN, then the FIFO_EN channels), and as the
    /// register map requires of USER_CTRL (FIFO_RESET "resets the FIFO buffer when set to 1
    /// while FIFO_EN equals 0"). With the channels off first, nothing enters the FIFO between
    /// the count read after this step and the reset, which makes the count of discarded
    /// samples exact.
    fn stop_fifo(&mut self) -> Result<(), Error<I2C::Error>> {
        self.write(FIFO_EN, 0)?;
        self.write(USER_CTRL, 0)
    }

    fn empty_fifo(&mut self) -> Result<(), Error<I2C::Error>> {
        self.write(USER_CTRL, USER_CTRL_FIFO_RESET)
    }

    fn start_fifo(&mut self) -> Result<(), Error<I2C::Error>> {
        self.write(USER_CTRL, USER_CTRL_FIFO_EN)?;
        self.write(FIFO_EN, FIFO_EN_ACCEL_GYRO)
    }

    fn read_data(&mut self, buf: &mut [u8]) -> Result<(), Error<I2C::Error>> {
        self.read_regs(FIFO_R_W, buf)
    }

    fn parse(p: &[u8]) -> Packet {
        Packet::Sample(RawSample {
            accel: be_i16x3(p, 0),
            gyro: be_i16x3(p, 6),
            temperature: None,
        })
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

    /// Reads INT_STATUS and FIFO_COUNT first; a non-empty count is read a second time and the
    /// smaller taken (the packets have no header: a count corrupted on the wire would
    /// otherwise have the reader read past the FIFO's end and deliver its repeated last byte
    /// as samples). A count above the FIFO's 1024 bytes is no count ([`Error::BadFifoCount`],
    /// nothing read). On FIFO_OFLOW_INT, or a count of 1024 bytes, the FIFO is reset (its
    /// complete packets are counted as discarded) and [`Error::FifoOverflow`] is returned. An
    /// empty FIFO is checked against USER_CTRL and PWR_MGMT_1: a chip that has reset itself
    /// has its FIFO off and is asleep, and [`Error::SensorReset`] is returned (see
    /// [`Mpu6050::recover`]); a FIFO reset finds such a chip by PWR_MGMT_1, and returns the
    /// same. Otherwise the whole packets in the FIFO (up to `out.len()`) are read, 8 per I2C
    /// transfer; a partial packet stays in the FIFO for the next call.
    ///
    /// MPU packets have no header: a read that fails part-way would leave the FIFO misaligned
    /// for good. So, as TDK's drivers do, the FIFO is then reset: the samples of the call and
    /// those left in the FIFO are counted as discarded and [`Error::FifoResync`] is returned.
    /// A reset that meets a bus error itself is remembered and finished by the next call, so
    /// an overflow, whose flag is cleared by reading it, is never lost.
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<I2C::Error>> {
        fifo::read_fifo(self, out)
    }

    fn fifo_stats(&self) -> FifoStats {
        self.fifo.stats
    }
}
