//! The driver shared by the chip readers: probe, reset and configure, recover after a chip
//! reset, and the FIFO routine (`fifo.rs`), over the chip's registers ([`Chip`]).

use embedded_hal::delay::DelayNs;
use embedded_hal_async::delay::DelayNs as AsyncDelayNs;

use super::chip::{CHECK_REGS, Chip};
use super::fifo::{self, FifoState, MAX_PACKET};
use super::io::{AsyncWait, BlockingWait, Wait, block};
use super::{Error, FifoStats, ImuReader, RawSample, Scale, Thermometer};

/// A six-axis reader of the chip `C` on its bus: [`Mpu6050`](super::Mpu6050) (I2C) and
/// [`Icm42688`](super::Icm42688) (SPI) are this driver over their chips, and every method
/// below works the same for both. `new` and `destroy` are the chips' own (they take and give
/// back the bus); the register sequences, delays and packet layouts of each chip are listed
/// on its type.
///
/// `init` and `recover` both return the WHO_AM_I value that identified the chip (0x68 for the
/// MPU-6050, 0x47 for the ICM-42688-P).
#[derive(Debug)]
pub struct Driver<C: Chip> {
    core: Core<C>,
}

/// What the blocking and the async drivers share: the chip, its configuration and the FIFO's
/// bookkeeping, with every step written once as an `async` function over the chip's transfers.
#[derive(Debug)]
struct Core<C: Chip> {
    chip: C,
    config: C::Config,
    fifo: FifoState,
}

impl<C: Chip> Core<C> {
    fn new(chip: C) -> Self {
        const {
            assert!(C::MAP.packet > 0 && C::MAP.packet <= MAX_PACKET);
            let mut i = 0;
            while i < C::MAP.fifo_on.len() {
                assert!(C::MAP.fifo_on[i].fields.len() <= CHECK_REGS);
                i += 1;
            }
            assert!(C::MAP.configured.fields.len() <= CHECK_REGS);
        }
        Self {
            chip,
            config: C::Config::default(),
            fifo: FifoState::default(),
        }
    }

    async fn who_am_i(&mut self) -> Result<u8, Error<C::BusError>> {
        self.chip.read_u8(C::MAP.who_am_i).await
    }

    async fn init(
        &mut self,
        wait: &mut impl Wait,
        config: C::Config,
    ) -> Result<u8, Error<C::BusError>> {
        self.fifo.off();
        let id = self.configure(wait, config).await?;
        self.fifo.initialised = true;
        Ok(id)
    }

    async fn configure(
        &mut self,
        wait: &mut impl Wait,
        config: C::Config,
    ) -> Result<u8, Error<C::BusError>> {
        let map = C::MAP;
        let id = self.who_am_i().await?;
        if map.unsupported.contains(&id) {
            return Err(Error::UnsupportedDevice { found: id });
        }
        if id != map.id {
            return Err(Error::WrongDevice { found: id });
        }
        let (reg, value) = map.reset;
        self.chip.write(reg, value).await?;
        wait.ms(map.reset_ms).await;
        for (reg, value) in C::setup(&config) {
            self.chip.write(reg, value).await?;
        }
        if map.verify_setup {
            for (reg, value) in C::setup(&config) {
                if self.chip.read_u8(reg).await? != value {
                    return Err(Error::WriteNotApplied { register: reg });
                }
            }
        }
        if map.settle_ms > 0 {
            wait.ms(map.settle_ms).await;
        }
        self.config = config;
        Ok(id)
    }

    async fn recover(
        &mut self,
        wait: &mut impl Wait,
        outage_us: u64,
    ) -> Result<u8, Error<C::BusError>> {
        if !self.fifo.initialised {
            return Err(Error::NotInitialised);
        }
        self.fifo.recovering();
        let id = self.configure(wait, self.config).await?;
        if self.fifo.wanted {
            self.enable_fifo().await?;
        }
        let (hz, div) = C::rate(&self.config);
        self.fifo.recovered(outage_us, hz, div);
        Ok(id)
    }

    async fn enable_fifo(&mut self) -> Result<(), Error<C::BusError>> {
        fifo::enable(&mut self.chip, &mut self.fifo).await
    }

    async fn read(&mut self) -> Result<RawSample, Error<C::BusError>> {
        let mut b = [0u8; 14];
        self.chip.read(C::MAP.data, &mut b).await?;
        C::sample(&b).ok_or(Error::NoData)
    }

    async fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<C::BusError>> {
        fifo::read_fifo(&mut self.chip, &mut self.fifo, out).await
    }
}

impl<C: Chip> Driver<C> {
    /// A reader of `chip` with the default configuration; no bus traffic until `init`.
    pub(crate) fn with_chip(chip: C) -> Self {
        Self {
            core: Core::new(chip),
        }
    }

    /// The chip, for `destroy` to give its bus back.
    pub(crate) fn into_chip(self) -> C {
        self.core.chip
    }

    /// Reads WHO_AM_I.
    ///
    /// # Errors
    ///
    /// [`Error::Bus`].
    pub fn who_am_i(&mut self) -> Result<u8, Error<C::BusError>> {
        block(self.core.who_am_i())
    }

    /// Probes WHO_AM_I, resets the chip (and waits for the reset to complete), writes
    /// `config` and returns the WHO_AM_I value (the ICM-42688-P's configuration writes read
    /// back). The FIFO is off afterwards, and its counts ([`FifoStats`]) start from zero: a
    /// new session. `enable_fifo` and `recover` need a successful `init` first.
    ///
    /// # Errors
    ///
    /// [`Error::UnsupportedDevice`] for a related chip that this reader rejects (the MPU-6500
    /// and MPU-9250, 0x70 and 0x71, for [`Mpu6050`](super::Mpu6050)),
    /// [`Error::WrongDevice`] for any other WHO_AM_I, [`Error::WriteNotApplied`] for a
    /// configuration write read back otherwise, or [`Error::Bus`]; after either of the last two
    /// `init` can simply be called again.
    pub fn init(
        &mut self,
        delay: &mut impl DelayNs,
        config: C::Config,
    ) -> Result<u8, Error<C::BusError>> {
        block(self.core.init(&mut BlockingWait(delay), config))
    }

    /// Brings the chip back after [`Error::SensorReset`], [`Error::FifoNotRunning`] (or any
    /// suspected glitch): probes WHO_AM_I, resets the chip and writes the last configuration
    /// again as `init` does, and re-enables the FIFO if `enable_fifo` was called since `init`.
    /// Returns WHO_AM_I.
    ///
    /// `outage_us` is the time in microseconds from the last `read_fifo` that accounted for
    /// the FIFO (see [`FifoStats::lost`]) to the FIFO running again, by the caller's clock:
    /// the time of the call plus the delays of the chip's reset and start (100 ms on the
    /// MPU-6050, 2 ms on the ICM-42688-P), since the caller cannot read its clock after
    /// `recover` and still count on it. The samples the chip produced in it are counted in
    /// [`FifoStats::lost`]. A recovery after [`Error::SensorReset`] is counted in
    /// [`FifoStats::resets`]. A FIFO reset still pending (an overflow, a failed read) is
    /// replaced by the recovery and counted as done; its samples are inside the outage.
    ///
    /// # Errors
    ///
    /// [`Error::NotInitialised`] before `init`; otherwise as [`Driver::init`] and
    /// [`Driver::enable_fifo`]. Nothing is counted until the recovery succeeds, and until then
    /// `read_fifo` returns [`Error::FifoNotRunning`]: `recover` can simply be called again.
    pub fn recover(
        &mut self,
        delay: &mut impl DelayNs,
        outage_us: u64,
    ) -> Result<u8, Error<C::BusError>> {
        block(self.core.recover(&mut BlockingWait(delay), outage_us))
    }

    /// The configuration written by the last `init`.
    pub fn config(&self) -> &C::Config {
        &self.core.config
    }

    /// Enables the FIFO (with the chip's overflow flag, in the chip's packet layout), and
    /// resets it. Samples in the FIFO (one left running by an earlier call that failed
    /// part-way) are counted in [`FifoStats::discarded`].
    ///
    /// # Errors
    ///
    /// [`Error::NotInitialised`] before `init`; [`Error::SensorReset`] when the chip has
    /// reset itself (call `recover`); [`Error::Bus`] (or [`Error::BadFifoCount`]): until a
    /// later call (or `recover`) succeeds, `read_fifo` returns [`Error::FifoNotRunning`].
    pub fn enable_fifo(&mut self) -> Result<(), Error<C::BusError>> {
        block(self.core.enable_fifo())
    }
}

/// The async reader of the chip `C` on an `embedded-hal-async` bus:
/// [`Mpu6050Async`](super::Mpu6050Async) and [`Icm42688Async`](super::Icm42688Async). Every
/// method is its blocking twin's ([`Driver`]), awaiting the bus instead of blocking on it: the
/// same code decides every register access, packet check, count and recovery, so the two give
/// the same samples and counts on the same bus.
#[derive(Debug)]
pub struct AsyncDriver<C: Chip> {
    core: Core<C>,
}

impl<C: Chip> AsyncDriver<C> {
    /// A reader of `chip` with the default configuration; no bus traffic until `init`.
    pub(crate) fn with_chip(chip: C) -> Self {
        Self {
            core: Core::new(chip),
        }
    }

    /// The chip, for `destroy` to give its bus back.
    pub(crate) fn into_chip(self) -> C {
        self.core.chip
    }

    /// [`Driver::who_am_i`].
    ///
    /// # Errors
    ///
    /// As [`Driver::who_am_i`].
    pub async fn who_am_i(&mut self) -> Result<u8, Error<C::BusError>> {
        self.core.who_am_i().await
    }

    /// [`Driver::init`], with an async delay.
    ///
    /// # Errors
    ///
    /// As [`Driver::init`].
    pub async fn init(
        &mut self,
        delay: &mut impl AsyncDelayNs,
        config: C::Config,
    ) -> Result<u8, Error<C::BusError>> {
        self.core.init(&mut AsyncWait(delay), config).await
    }

    /// [`Driver::recover`], with an async delay.
    ///
    /// # Errors
    ///
    /// As [`Driver::recover`].
    pub async fn recover(
        &mut self,
        delay: &mut impl AsyncDelayNs,
        outage_us: u64,
    ) -> Result<u8, Error<C::BusError>> {
        self.core.recover(&mut AsyncWait(delay), outage_us).await
    }

    /// The configuration written by the last `init`.
    pub fn config(&self) -> &C::Config {
        &self.core.config
    }

    /// [`Driver::enable_fifo`].
    ///
    /// # Errors
    ///
    /// As [`Driver::enable_fifo`].
    pub async fn enable_fifo(&mut self) -> Result<(), Error<C::BusError>> {
        self.core.enable_fifo().await
    }

    /// [`ImuReader::read`] of the blocking reader.
    ///
    /// # Errors
    ///
    /// As [`ImuReader::read`].
    pub async fn read(&mut self) -> Result<RawSample, Error<C::BusError>> {
        self.core.read().await
    }

    /// [`ImuReader::read_fifo`] of the blocking reader ([`Driver`]'s, which describes it).
    ///
    /// # Errors
    ///
    /// As [`ImuReader::read_fifo`].
    pub async fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<C::BusError>> {
        self.core.read_fifo(out).await
    }

    /// The sensitivities of the configuration.
    pub fn scale(&self) -> Scale {
        C::scale(&self.core.config)
    }

    /// The FIFO's counts ([`ImuReader::fifo_stats`]).
    pub fn fifo_stats(&self) -> FifoStats {
        self.core.fifo.stats
    }

    /// The chip's temperature formula ([`ImuReader::thermometer`]).
    pub fn thermometer(&self) -> Thermometer {
        C::MAP.thermometer
    }
}

impl<C: Chip> ImuReader for Driver<C> {
    type BusError = C::BusError;

    fn scale(&self) -> Scale {
        C::scale(&self.core.config)
    }

    /// One burst read of the 14 bytes of the data registers. Registers holding the chip's
    /// invalid-data marker (the ICM-42688-P's -32768, while a sensor is starting) give
    /// [`Error::NoData`]; they are no FIFO packet, and are not counted in
    /// [`FifoStats::invalid`].
    fn read(&mut self) -> Result<RawSample, Error<C::BusError>> {
        block(self.core.read())
    }

    /// Reads INT_STATUS and FIFO_COUNT first (the count twice when it holds a packet, and the
    /// smaller taken: a count corrupted high would read past the FIFO's end). A count above
    /// the FIFO's size is no count
    /// ([`Error::BadFifoCount`], nothing read). On the FIFO overflow flag, or a count at the
    /// FIFO's size (a full FIFO overwrites its oldest bytes, so its packets are misaligned),
    /// the FIFO is reset (its complete packets are counted as discarded) and
    /// [`Error::FifoOverflow`] is returned. An empty FIFO is checked against a chip reset (the
    /// chip's FIFO configuration read back): a chip that has reset itself has its FIFO off,
    /// and [`Error::SensorReset`] is returned (see [`Driver::recover`]); a FIFO reset finds
    /// such a chip by its power mode, and returns the same. Otherwise the whole packets in the
    /// FIFO (up to `out.len()`) are read, 8 per bus transfer; a partial packet stays in the
    /// FIFO for the next call. A sample arriving during the read may overwrite bytes not yet
    /// read: INT_STATUS is read after every read, and on the overflow flag (or a bus error
    /// there) the samples read are counted as discarded instead of delivered, the FIFO is
    /// reset, and [`Error::FifoOverflow`] ([`Error::FifoResync`] after the bus error) is
    /// returned. Packets are parsed as the
    /// chip's type describes: packets the chip marked invalid are skipped and counted in
    /// [`FifoStats::invalid`]. A header that is
    /// not one (the ICM-42688-P's) most likely means misaligned packets (a byte lost or added
    /// on the wire): the call's packets are dropped, the malformed ones counted in
    /// [`FifoStats::malformed`] and the rest in [`FifoStats::discarded`], the FIFO is reset,
    /// which realigns it, and [`Error::FifoResync`] is returned.
    ///
    /// A read that fails part-way would leave the FIFO misaligned for good (the MPU-6050's
    /// packets have no header). So, as TDK's drivers do, the FIFO is then reset: the samples
    /// of the call and those left in the FIFO are counted as discarded and
    /// [`Error::FifoResync`] is returned; what the failed transfer clocked out is counted as
    /// [`FifoStats::discarded`] and [`FifoStats::unsure`]. A reset that meets a bus error
    /// itself is remembered
    /// and finished by the next call, so an overflow, whose flag is cleared by reading it, is
    /// never lost.
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<C::BusError>> {
        block(self.core.read_fifo(out))
    }

    fn fifo_stats(&self) -> FifoStats {
        self.core.fifo.stats
    }

    /// The chip's temperature formula ([`Thermometer::MPU6050`], [`Thermometer::ICM42688`]).
    fn thermometer(&self) -> Option<Thermometer> {
        Some(C::MAP.thermometer)
    }
}
