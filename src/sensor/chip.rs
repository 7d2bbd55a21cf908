//! What the shared driver ([`Driver`](super::Driver)) and FIFO routine (`fifo.rs`) need to know
//! of one chip: its registers as data ([`Map`]), and the few things that differ in code
//! ([`Chip`]): the bus transfers, the configuration writes, and the layout of a sample.
//!
//! The trait is public only in name: it lives in a private module, so no type outside this
//! crate can implement it, and its items are not part of the crate's API.

use super::{Error, RawSample, Scale, Thermometer};

/// A register write: the register, then the value.
pub type Write = (u8, u8);

/// A read-back of consecutive registers in one transfer: register `reg + i` holds `value` in
/// the bits of `mask`, for each `(mask, value)` of `fields`.
#[derive(Clone, Copy, Debug)]
pub struct Check {
    /// The first register read.
    pub reg: u8,
    /// `(mask, value)` of each register from `reg` on (at most [`CHECK_REGS`]).
    pub fields: &'static [(u8, u8)],
}

/// The most registers a [`Check`] reads.
pub const CHECK_REGS: usize = 2;

/// A chip's registers, as the shared driver and FIFO routine use them.
#[derive(Clone, Copy, Debug)]
pub struct Map {
    /// WHO_AM_I.
    pub who_am_i: u8,
    /// WHO_AM_I of the chip.
    pub id: u8,
    /// WHO_AM_I of related chips that the reader recognises and rejects
    /// ([`Error::UnsupportedDevice`]).
    pub unsupported: &'static [u8],
    /// The write that resets the chip.
    pub reset: Write,
    /// Milliseconds the reset takes.
    pub reset_ms: u32,
    /// Milliseconds the chip needs after the configuration writes (0: none).
    pub settle_ms: u32,
    /// The first data register: 14 bytes from it hold one sample.
    pub data: u8,
    /// INT_STATUS, cleared by reading it.
    pub int_status: u8,
    /// The FIFO overflow bit of INT_STATUS.
    pub int_fifo_overflow: u8,
    /// FIFO_COUNTH: with FIFO_COUNTL after it, the bytes in the FIFO, big-endian.
    pub fifo_count: u8,
    /// The FIFO data register.
    pub fifo_data: u8,
    /// Bytes per FIFO packet (at most `fifo::MAX_PACKET`).
    pub packet: usize,
    /// The FIFO's size in bytes: a count at it is an overflow, a count above it no count.
    pub fifo_bytes: u16,
    /// The first writes of `enable_fifo`, before its FIFO reset.
    pub fifo_prepare: &'static [Write],
    /// Takes the channels off the FIFO (and, where needed, the FIFO itself).
    pub fifo_stop: &'static [Write],
    /// The channels are off: read back after `fifo_stop`, before the count that the reset
    /// relies on to stay still.
    pub stopped: Check,
    /// Empties the FIFO, its channels off.
    pub fifo_empty: &'static [Write],
    /// Starts the FIFO and its channels.
    pub fifo_start: &'static [Write],
    /// The FIFO is on: read back after an empty count, one of them fails when the chip has
    /// reset itself (or a configuration write was corrupted on the wire, leaving the FIFO off).
    pub fifo_on: &'static [Check],
    /// A register of the configuration that no FIFO reset writes: read back when a FIFO reset
    /// finds the FIFO empty, it fails when the chip has reset itself.
    pub configured: Check,
    /// The formula of the raw temperature of the chip's samples.
    pub thermometer: Thermometer,
    /// The chip writes whole packets into its FIFO, so its byte count is a whole number of
    /// packets: a remainder means a byte lost or added on the wire (an SPI slip), and the
    /// packets are misaligned.
    pub whole_packets: bool,
    /// The configuration writes of `init` are read back (SPI, whose writes have no
    /// acknowledge; an I2C chip acknowledges every byte, and one that resets between them is
    /// found asleep).
    pub verify_setup: bool,
}

/// What a FIFO packet turned out to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Packet {
    /// A sample.
    Sample(RawSample),
    /// A packet the chip marked invalid: skipped and counted.
    Invalid,
    /// A packet of the wrong layout, most likely misaligned: counted, and the call's other
    /// packets dropped (counted as discarded) by a FIFO reset that realigns them.
    Malformed,
    /// The chip's "FIFO empty" marker: inside the counted bytes, a damaged header (as
    /// [`Packet::Malformed`]).
    End,
}

/// One chip on its bus: implemented by [`Mpu6050Bus`](super::Mpu6050Bus) and
/// [`Icm42688Bus`](super::Icm42688Bus), over a blocking bus or an async one
/// ([`Async`](super::Async)). Its transfers are `async`: the chip logic is written once over
/// them (see `io.rs`).
#[allow(async_fn_in_trait)]
pub trait Chip {
    /// The bus's error type.
    type BusError;
    /// The configuration written by `init`.
    type Config: Copy + Default + core::fmt::Debug;
    /// The chip's registers.
    const MAP: Map;

    /// Writes `value` to register `reg`.
    async fn write(&mut self, reg: u8, value: u8) -> Result<(), Self::BusError>;

    /// Reads `buf.len()` bytes from register `reg` on (from the FIFO, for its data register).
    async fn read(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Self::BusError>;

    /// The configuration writes of `init`, in order, after the reset.
    fn setup(config: &Self::Config) -> impl IntoIterator<Item = Write>;

    /// The sensitivities of `config`.
    fn scale(config: &Self::Config) -> Scale;

    /// The output data rate of `config`: `(hz, div)` for `hz / div` samples per second.
    fn rate(config: &Self::Config) -> (u32, u32);

    /// The sample in the 14 bytes of the data registers; `None` when they hold the chip's
    /// invalid-data marker.
    fn sample(data: &[u8; 14]) -> Option<RawSample>;

    /// Classifies one FIFO packet of [`Map::packet`] bytes.
    fn parse(packet: &[u8]) -> Packet;

    /// Writes `writes` in order; stops at the first that fails.
    async fn write_all(&mut self, writes: &[Write]) -> Result<(), Error<Self::BusError>> {
        for &(reg, value) in writes {
            self.write(reg, value).await?;
        }
        Ok(())
    }

    /// Reads register `reg`.
    async fn read_u8(&mut self, reg: u8) -> Result<u8, Error<Self::BusError>> {
        let mut b = [0];
        self.read(reg, &mut b).await?;
        Ok(b[0])
    }

    /// Reads the registers of `check` in one transfer: `true` when every field holds its value.
    async fn check(&mut self, check: Check) -> Result<bool, Error<Self::BusError>> {
        let mut b = [0u8; CHECK_REGS];
        let regs = b.get_mut(..check.fields.len()).unwrap_or_default();
        self.read(check.reg, regs).await?;
        Ok(regs
            .iter()
            .zip(check.fields)
            .all(|(&r, &(mask, value))| r & mask == value))
    }

    /// Reads FIFO_COUNT, in bytes.
    async fn fifo_count(&mut self) -> Result<u16, Error<Self::BusError>> {
        let mut b = [0; 2];
        self.read(Self::MAP.fifo_count, &mut b).await?;
        Ok(u16::from_be_bytes(b))
    }
}
