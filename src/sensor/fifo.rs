//! The FIFO routine shared by the chip readers: overflow detection and handling, whole-packet
//! reads, and the FIFO reset that realigns the packets after a failed read.
//!
//! Each reader implements [`FifoChip`] (its registers) and keeps a [`FifoState`]; the routine
//! below is the same for every chip. It is written so that a bus error at any transfer leaves
//! a state from which the next call carries on:
//!
//! - "the FIFO should be on" ([`FifoState::wanted`]) is kept apart from "the FIFO is on"
//!   ([`FifoState::running`]): a recovery or `enable_fifo` that fails part-way leaves the second
//!   false, and `read_fifo` says so ([`Error::FifoNotRunning`]) until a retry completes;
//! - a FIFO reset, once decided (an overflow seen in INT_STATUS or in FIFO_COUNT, or a failed
//!   data read), is remembered in [`FifoState::pending`] until it has been carried out, so an
//!   overflow flag cleared by its read is never lost.

use super::{Error, FifoStats, Packet, RawSample};

/// Packets read per bus transfer.
const CHUNK: usize = 8;
/// The longest FIFO packet of the supported chips.
pub(crate) const MAX_PACKET: usize = 16;
/// Tries at reading FIFO_COUNT right after a failed data read (to learn how many bytes it
/// took out of the FIFO).
const COUNT_TRIES: usize = 4;

/// A FIFO reset that has been decided but not yet carried out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct PendingReset {
    /// The reset is for an overflow (otherwise for a failed data read).
    overflow: bool,
    /// Bytes of the dropped packets already taken out of the FIFO: read before a failed
    /// transfer, or clocked out by it.
    consumed: u16,
    /// The most bytes the FIFO was seen to hold since the reset was decided, or since a reset
    /// attempt last emptied it. Each reset takes the channels off the FIFO before emptying
    /// it, and goes no further when that fails: until the emptying step succeeds, the count
    /// only grows (channels on) or stays (channels off, or emptied by a write that reported a
    /// failure, leaving 0), so the largest count seen is what the reset drops. Once it has
    /// succeeded these bytes are dropped for sure and move to `consumed`; later counts are
    /// samples written since.
    held: u16,
}

/// A reader's FIFO bookkeeping.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FifoState {
    /// The FIFO should be on: `enable_fifo` was called since the last `init`.
    pub(crate) wanted: bool,
    /// The FIFO is on: the last `enable_fifo` or recovery completed.
    pub(crate) running: bool,
    /// A FIFO reset still to be carried out.
    pub(crate) pending: Option<PendingReset>,
    /// The counts.
    pub(crate) stats: FifoStats,
}

impl FifoState {
    /// `init`: the chip has been reset, its FIFO is off and nobody asked for it.
    pub(crate) fn off(&mut self) {
        self.wanted = false;
        self.running = false;
        self.pending = None;
    }

    /// A recovery or `enable_fifo` begins: the chip's FIFO is not known to be on.
    pub(crate) fn restarting(&mut self) {
        self.running = false;
        self.pending = None;
    }

    fn mark_overflow(&mut self) {
        self.pending
            .get_or_insert_with(PendingReset::default)
            .overflow = true;
    }
}

/// The registers of one chip, as the FIFO routine needs them.
pub(crate) trait FifoChip {
    /// The bus's error type.
    type BusError;
    /// Bytes per FIFO packet (at most [`MAX_PACKET`]).
    const PACKET: usize;
    /// The FIFO's size in bytes: a count at or above it is an overflow.
    const FIFO_BYTES: u16;

    /// The reader's FIFO bookkeeping.
    fn state(&mut self) -> &mut FifoState;
    /// Reads the interrupt status (which clears it): `true` on a FIFO overflow.
    fn overflow_flag(&mut self) -> Result<bool, Error<Self::BusError>>;
    /// Reads FIFO_COUNT, in bytes.
    fn fifo_count(&mut self) -> Result<u16, Error<Self::BusError>>;
    /// Reads back the FIFO mode after an empty count: `false` when the chip has reset itself.
    fn fifo_configured(&mut self) -> Result<bool, Error<Self::BusError>>;
    /// Takes the channels off the FIFO, empties it (setting `emptied` once that write has
    /// succeeded) and starts it again. Every step can be repeated: after a failure the whole
    /// sequence is simply run again.
    fn reset_fifo(&mut self, emptied: &mut bool) -> Result<(), Error<Self::BusError>>;
    /// Reads `buf.len()` bytes from the FIFO data register.
    fn read_data(&mut self, buf: &mut [u8]) -> Result<(), Error<Self::BusError>>;
    /// Classifies one packet.
    fn parse(packet: &[u8]) -> Packet;
}

/// `ImuReader::read_fifo` of every chip; see the readers' documentation.
pub(crate) fn read_fifo<C: FifoChip>(
    chip: &mut C,
    out: &mut [RawSample],
) -> Result<usize, Error<C::BusError>> {
    let packet = C::PACKET.clamp(1, MAX_PACKET);
    let state = chip.state();
    if !state.wanted {
        return Err(Error::FifoDisabled);
    }
    if !state.running {
        return Err(Error::FifoNotRunning);
    }
    if chip.overflow_flag()? {
        chip.state().mark_overflow();
    }
    let count = chip.fifo_count()?;
    if count >= C::FIFO_BYTES {
        // A full FIFO overwrites its oldest bytes: its packets are no longer aligned. A count
        // above the size (a bus stuck high) is no count at all.
        chip.state().mark_overflow();
    }
    let count = count.min(C::FIFO_BYTES);
    if let Some(p) = chip.state().pending.as_mut() {
        p.held = p.held.max(count);
        return finish_reset(chip, packet);
    }
    let available = usize::from(count) / packet;
    if available == 0 {
        // An empty FIFO may be a chip that reset itself: its FIFO is then off.
        return if chip.fifo_configured()? {
            Ok(0)
        } else {
            Err(Error::SensorReset)
        };
    }
    let mut buf = [0u8; MAX_PACKET * CHUNK];
    let (mut remaining, mut delivered) = (available, 0usize);
    let (mut taken, mut invalid, mut malformed, mut clipped) = (0usize, 0u64, 0u64, 0u64);
    while remaining > 0 && delivered < out.len() {
        let n = remaining.min(CHUNK).min(out.len() - delivered);
        let bytes = &mut buf[..n * packet];
        if let Err(e) = chip.read_data(bytes) {
            resync(chip, count, taken + n * packet);
            return match finish_reset(chip, packet) {
                Err(Error::Bus(_)) => Err(e),
                other => other,
            };
        }
        taken += n * packet;
        remaining -= n;
        for p in bytes.chunks_exact(packet) {
            match C::parse(p) {
                Packet::Sample(s) => {
                    if let Some(slot) = out.get_mut(delivered) {
                        clipped += u64::from(s.clipped());
                        *slot = s;
                        delivered += 1;
                    }
                }
                Packet::Invalid => invalid += 1,
                Packet::Malformed => malformed += 1,
                Packet::End => {
                    remaining = 0;
                    break;
                }
            }
        }
    }
    let stats = &mut chip.state().stats;
    stats.samples += delivered as u64;
    stats.invalid += invalid;
    stats.malformed += malformed;
    stats.clipped += clipped;
    Ok(delivered)
}

/// A data read failed with `count` bytes in the FIFO at the start of the call and at most
/// `at_most` of them taken out: decides a reset, and learns from FIFO_COUNT how many bytes the
/// failed transfer clocked out. Without a count, the whole failed transfer is taken as read.
fn resync<C: FifoChip>(chip: &mut C, count: u16, at_most: usize) {
    let mut left = None;
    for _ in 0..COUNT_TRIES {
        if let Ok(c) = chip.fifo_count() {
            left = Some(c.min(C::FIFO_BYTES));
            break;
        }
    }
    let at_most = u16::try_from(at_most).unwrap_or(u16::MAX).min(count);
    let (consumed, held) = match left {
        Some(left) => (count.saturating_sub(left), left),
        None => (at_most, count - at_most),
    };
    let pending = chip
        .state()
        .pending
        .get_or_insert_with(PendingReset::default);
    pending.consumed = consumed;
    pending.held = pending.held.max(held);
}

/// Carries out the pending reset and counts it: [`Error::FifoOverflow`] or
/// [`Error::FifoResync`]; a bus error keeps it pending.
fn finish_reset<C: FifoChip>(chip: &mut C, packet: usize) -> Result<usize, Error<C::BusError>> {
    let mut emptied = false;
    let result = chip.reset_fifo(&mut emptied);
    let state = chip.state();
    if emptied && let Some(p) = state.pending.as_mut() {
        p.consumed = p.consumed.saturating_add(p.held);
        p.held = 0;
    }
    result?;
    let Some(p) = state.pending.take() else {
        return Ok(0);
    };
    let bytes = u32::from(p.consumed) + u32::from(p.held);
    let discarded = bytes / u32::try_from(packet).unwrap_or(1);
    let stats = &mut state.stats;
    stats.discarded += u64::from(discarded);
    stats.discarded_bytes += u64::from(bytes);
    let discarded = u16::try_from(discarded).unwrap_or(u16::MAX);
    if p.overflow {
        stats.overflows += 1;
        Err(Error::FifoOverflow { discarded })
    } else {
        stats.resyncs += 1;
        Err(Error::FifoResync { discarded })
    }
}
