//! The FIFO routine shared by the chip readers: overflow detection and handling, whole-packet
//! reads, and the FIFO reset that realigns the packets after a failed read.
//!
//! Each chip describes its FIFO registers ([`Chip`], [`Map`](super::chip::Map)) and each reader
//! keeps a [`FifoState`]; the routine below is the same for every chip. It is written so that a
//! bus error at any transfer leaves a state from which the next call carries on:
//!
//! - "the FIFO should be on" ([`FifoState::wanted`]) is kept apart from "the FIFO is on"
//!   ([`FifoState::running`]): a recovery or `enable_fifo` that fails part-way leaves the second
//!   false, and `read_fifo` says so ([`Error::FifoNotRunning`]) until a retry completes;
//! - a FIFO reset, once decided (an overflow seen in INT_STATUS or in FIFO_COUNT, or a failed
//!   data read), is remembered in [`FifoState::pending`] until it has been carried out, so an
//!   overflow flag cleared by its read is never lost;
//! - every reset takes the channels off, then reads FIFO_COUNT (stable from then on), then
//!   empties the FIFO: what it drops is counted exactly, and an empty FIFO is first checked
//!   against a chip reset, so that starting the FIFO again never hides one.

use super::chip::{Chip, Packet};
use super::{Error, FifoStats, RawSample};

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
    /// The reset is for an overflow.
    overflow: bool,
    /// The reset is for a failed data read.
    resync: bool,
    /// The INT_STATUS read that closes a FIFO read failed: an overflow during the read may
    /// have set its flag, and the failed read may have cleared it. The reset counts an
    /// overflow when the bytes it drops reach the FIFO's size (the FIFO may have filled up).
    flag_unknown: bool,
    /// Bytes of the dropped packets already taken out of the FIFO: read before a failed
    /// transfer, or clocked out by it.
    consumed: u32,
    /// The most bytes the FIFO was seen to hold since the reset was decided, or since a reset
    /// attempt last emptied it. Each reset takes the channels off the FIFO and reads the count
    /// before emptying it, and goes no further when that fails: until the emptying step
    /// succeeds, the count only grows (channels on) or stays (channels off, or emptied by a
    /// write that reported a failure, leaving 0), so the largest count seen is what the reset
    /// drops. Once it has succeeded these bytes are dropped for sure and move to `consumed`;
    /// later counts are samples written since.
    held: u16,
    /// A failed data read whose clocked-out bytes are not known yet: resolved by the next
    /// count read.
    unresolved: Option<Unresolved>,
    /// Whole packets a failed data read may have clocked out beyond those counted in
    /// `consumed` (see [`PendingReset::observe`]).
    unsure: u32,
    /// Malformed packets of the dropped call, not in `consumed`: counted when the reset is
    /// carried out (a recovery that replaces it counts them in its outage).
    malformed: u64,
}

/// A failed data read not yet matched with a count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Unresolved {
    /// Bytes in the FIFO at the last count before the failed transfer, less those read since.
    left: u16,
    /// Bytes the failed transfer asked for: it clocked out at most these.
    len: u16,
}

impl PendingReset {
    /// A count of the FIFO read while the reset is pending (before it empties the FIFO).
    ///
    /// The bytes a failed transfer clocked out are `left - count` when nothing entered the
    /// FIFO in between. Samples that entered are whole packets, so the bytes clocked out are
    /// congruent to `left - count` modulo the packet size: the smallest such number is counted
    /// (exact when no sample entered between the last count and this one, or when the count
    /// grew), and the whole packets by which the transfer's length leaves room for more are
    /// counted as unsure (a sample that entered while a transfer clocked out one packet more
    /// looks the same to the counts).
    fn observe(&mut self, count: u16, packet: usize) {
        if let Some(u) = self.unresolved.take() {
            let out = if u.left >= count {
                (u.left - count).min(u.len)
            } else {
                let grown = usize::from(count - u.left) % packet;
                let out = (packet - grown) % packet;
                u16::try_from(out).unwrap_or(0).min(u.len)
            };
            self.consumed = self.consumed.saturating_add(u32::from(out));
            let room = usize::from(u.len - out) / packet;
            self.unsure = self
                .unsure
                .saturating_add(u32::try_from(room).unwrap_or(u32::MAX));
        }
        self.held = self.held.max(count);
    }
}

/// A FIFO read under way: its data transfers have begun. An async `read_fifo` whose future is
/// dropped there (a timeout, a `select`) leaves it behind, and the next call settles it as a
/// failed read ([`settle_cancelled`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct InCall {
    /// Bytes in the FIFO at the count the call read by.
    latest: u16,
    /// Bytes read by its completed transfers.
    taken: u16,
    /// Bytes the transfer under way asks for (0 between transfers).
    len: u16,
}

/// A reader's FIFO bookkeeping.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FifoState {
    /// A read whose data transfers began and that has not returned.
    in_call: Option<InCall>,
    /// `init` has completed: the chip is configured.
    pub(crate) initialised: bool,
    /// The FIFO should be on: `enable_fifo` was called since the last `init`.
    pub(crate) wanted: bool,
    /// The FIFO is on: the last `enable_fifo` or recovery completed.
    pub(crate) running: bool,
    /// A FIFO reset still to be carried out.
    pub(crate) pending: Option<PendingReset>,
    /// `read_fifo` reported [`Error::SensorReset`] and no recovery has completed since.
    pub(crate) reset_seen: bool,
    /// The counts.
    pub(crate) stats: FifoStats,
}

impl FifoState {
    /// `init` begins: the chip is being reset, its FIFO is off and nobody asked for it.
    pub(crate) fn off(&mut self) {
        // A new session: the counts start again (an overflow or a read still pending belongs
        // to the session `init` ends, whose samples the chip reset drops).
        self.stats = FifoStats::default();
        self.in_call = None;
        self.initialised = false;
        self.wanted = false;
        self.running = false;
        self.pending = None;
        self.reset_seen = false;
    }

    /// A recovery begins: the chip is reset and configured again, which empties its FIFO.
    /// The bytes of a pending reset are inside the outage (counted in [`FifoStats::lost`]);
    /// its cause (an overflow, a failed read) is kept, and counted when the FIFO runs again.
    pub(crate) fn recovering(&mut self) {
        self.running = false;
        // The samples of a read cancelled part-way are inside the outage.
        self.in_call = None;
        self.pending = self.pending.map(|p| PendingReset {
            overflow: p.overflow,
            resync: p.resync,
            ..PendingReset::default()
        });
    }

    /// A recovery has succeeded after an outage of `outage_us` microseconds at `hz / div`
    /// samples per second: counts the samples of the outage, rounded to the nearest, and the
    /// chip reset when one was reported ([`Error::SensorReset`]).
    pub(crate) fn recovered(&mut self, outage_us: u64, hz: u32, div: u32) {
        let chip_reset = core::mem::take(&mut self.reset_seen);
        let den = 1_000_000u128 * u128::from(div.max(1));
        // Without the FIFO nothing was to be read, and nothing is lost.
        let lost = if self.wanted {
            (u128::from(outage_us) * u128::from(hz) + den / 2) / den
        } else {
            0
        };
        let stats = &mut self.stats;
        stats.resets = stats.resets.saturating_add(u64::from(chip_reset));
        stats.lost = stats
            .lost
            .saturating_add(u64::try_from(lost).unwrap_or(u64::MAX));
    }

    fn mark_overflow(&mut self) {
        self.pending
            .get_or_insert_with(PendingReset::default)
            .overflow = true;
    }
}

/// Bytes per FIFO packet of `C`, kept within 1 ..= [`MAX_PACKET`].
fn packet<C: Chip>() -> usize {
    C::MAP.packet.clamp(1, MAX_PACKET)
}

/// Reads FIFO_COUNT; a count above the FIFO's size is [`Error::BadFifoCount`].
async fn count<C: Chip>(chip: &mut C) -> Result<u16, Error<C::BusError>> {
    let count = chip.fifo_count().await?;
    if count > C::MAP.fifo_bytes {
        return Err(Error::BadFifoCount { count });
    }
    Ok(count)
}

/// A count read while a reset is pending.
fn observe<C: Chip>(state: &mut FifoState, count: u16) {
    if let Some(p) = state.pending.as_mut() {
        p.observe(count, packet::<C>());
    }
}

/// A read left part-way by a dropped future: its packets were taken out of the FIFO (the
/// completed transfers' bytes, and up to the whole of a transfer under way) and never
/// delivered. Settled as a failed data read: a FIFO reset realigns the packets and counts them,
/// the bytes of the transfer under way reckoned from the next count ([`PendingReset::observe`]).
fn settle_cancelled(state: &mut FifoState) {
    if let Some(c) = state.in_call.take() {
        let pending = state.pending.get_or_insert_with(PendingReset::default);
        pending.resync = true;
        // The read may have been dropped after its closing INT_STATUS read cleared an
        // overflow flag it never acted on.
        pending.flag_unknown = true;
        pending.consumed = pending.consumed.saturating_add(u32::from(c.taken));
        if c.len > 0 {
            pending.unresolved = Some(Unresolved {
                left: c.latest.saturating_sub(c.taken),
                len: c.len,
            });
        }
    }
}

/// `enable_fifo` of every chip: the chip's first write, then a FIFO reset. A FIFO that an
/// earlier attempt left running is emptied by it: its samples are counted as discarded, and a
/// reset still pending (an overflow, a failed read) is counted as done.
pub(crate) async fn enable<C: Chip>(
    chip: &mut C,
    state: &mut FifoState,
) -> Result<(), Error<C::BusError>> {
    if !state.initialised {
        return Err(Error::NotInitialised);
    }
    settle_cancelled(state);
    state.wanted = true;
    state.running = false;
    state.pending.get_or_insert_with(PendingReset::default);
    chip.write_all(C::MAP.fifo_prepare).await?;
    reset(chip, state).await?;
    state.running = true;
    if let Some(p) = state.pending.take() {
        count_reset::<C>(&mut state.stats, p);
    }
    Ok(())
}

/// `ImuReader::read_fifo` of every chip; see the readers' documentation.
pub(crate) async fn read_fifo<C: Chip>(
    chip: &mut C,
    state: &mut FifoState,
    out: &mut [RawSample],
) -> Result<usize, Error<C::BusError>> {
    settle_cancelled(state);
    let result = read_fifo_once(chip, state, out).await;
    state.in_call = None;
    result
}

/// [`read_fifo`] once an earlier call cancelled part-way is settled.
async fn read_fifo_once<C: Chip>(
    chip: &mut C,
    state: &mut FifoState,
    out: &mut [RawSample],
) -> Result<usize, Error<C::BusError>> {
    let packet = packet::<C>();
    if !state.wanted {
        return Err(Error::FifoDisabled);
    }
    if !state.running {
        return Err(Error::FifoNotRunning);
    }
    if chip.read_u8(C::MAP.int_status).await? & C::MAP.int_fifo_overflow != 0 {
        state.mark_overflow();
    }
    let first = count(chip).await?;
    // The count the data are read by, and the latest count, which the bytes of a failed read
    // are reckoned from. The count is confirmed (a count corrupted high on the wire would be
    // read past the FIFO's end, or dropped by a pending reset as samples never written): the
    // smaller of two is taken.
    let (mut readable, mut latest) = (first, first);
    if usize::from(first) >= packet || state.pending.is_some() {
        latest = count(chip).await?;
        readable = readable.min(latest);
    }
    observe::<C>(state, readable);
    if readable >= C::MAP.fifo_bytes {
        // A full FIFO overwrites its oldest bytes: its packets are no longer aligned. (The
        // confirmed count: one corrupted high on the wire is no overflow.)
        state.mark_overflow();
    }
    if state.pending.is_some() {
        return finish_reset(chip, state).await;
    }
    if C::MAP.whole_packets && usize::from(readable) % packet != 0 {
        // A chip that writes whole packets holds part of one: a byte was lost or added on the
        // wire (an SPI slip), and every packet after it is misaligned.
        return drop_call(chip, state, 0, |p| p.resync = true).await;
    }
    let available = usize::from(readable) / packet;
    if available == 0 {
        // An empty FIFO may be a chip that reset itself: its FIFO is then off.
        for &check in C::MAP.fifo_on {
            if !chip.check(check).await? {
                state.reset_seen = true;
                return Err(Error::SensorReset);
            }
        }
        return Ok(0);
    }
    let mut buf = [0u8; MAX_PACKET * CHUNK];
    let mut batch = Batch::default();
    let (mut remaining, mut taken) = (available, 0usize);
    while remaining > 0 && batch.delivered < out.len() {
        let n = remaining.min(CHUNK).min(out.len() - batch.delivered);
        let bytes = &mut buf[..n * packet];
        let u16_of = |v: usize| u16::try_from(v).unwrap_or(u16::MAX);
        state.in_call = Some(InCall {
            latest,
            taken: u16_of(taken),
            len: u16_of(n * packet),
        });
        if let Err(e) = chip.read(C::MAP.fifo_data, bytes).await {
            state.in_call = None;
            resync(chip, state, latest, taken, n * packet).await;
            return match finish_reset(chip, state).await {
                Err(Error::Bus(_)) => Err(Error::Bus(e)),
                other => other,
            };
        }
        taken += n * packet;
        remaining -= n;
        state.in_call = Some(InCall {
            latest,
            taken: u16_of(taken),
            len: 0,
        });
        batch.parse::<C>(bytes, out);
        if batch.malformed > 0 {
            // A header that is not one (the "FIFO empty" marker inside the counted bytes
            // too): the packets are most likely misaligned (a byte lost or added on the
            // wire), and a misaligned packet passes the header test now and then. The call's
            // packets are dropped, the malformed ones counted as such.
            let malformed = batch.malformed;
            let bad = usize::try_from(malformed).map_or(usize::MAX, |m| m.saturating_mul(packet));
            return drop_call(chip, state, taken.saturating_sub(bad), |p| {
                p.resync = true;
                p.malformed = p.malformed.saturating_add(malformed);
            })
            .await;
        }
    }
    // Samples keep arriving while the FIFO is read (a 96-byte transfer takes 2.4 ms at
    // 400 kHz, 9.6 ms at 100 kHz): one that overwrote bytes not yet read misaligned every
    // packet after them. The overflow flag says; with it (or when it cannot be read) the
    // call's packets are dropped.
    let flag = chip.read_u8(C::MAP.int_status).await;
    if !matches!(flag, Ok(f) if f & C::MAP.int_fifo_overflow == 0) {
        return drop_call(chip, state, taken, |p| {
            p.overflow |= flag.is_ok();
            p.resync |= flag.is_err();
            p.flag_unknown |= flag.is_err();
        })
        .await;
    }
    // A chip that reset itself during the read left its FIFO off, and the bytes read after
    // the reset are no samples (an empty FIFO repeats a byte): its FIFO mode says. The call's
    // samples are not delivered; the recovery's outage counts them.
    for &check in C::MAP.fifo_on {
        match chip.check(check).await {
            Ok(true) => {}
            Ok(false) => {
                state.reset_seen = true;
                return Err(Error::SensorReset);
            }
            Err(_) => return drop_call(chip, state, taken, |p| p.resync = true).await,
        }
    }
    // A byte slipped during the read misaligned the packets after it: the FIFO then holds part
    // of a packet.
    if C::MAP.whole_packets && !matches!(count(chip).await, Ok(c) if usize::from(c) % packet == 0) {
        return drop_call(chip, state, taken, |p| p.resync = true).await;
    }
    batch.count(&mut state.stats);
    Ok(batch.delivered)
}

/// The packets of one `read_fifo`.
#[derive(Default)]
struct Batch {
    delivered: usize,
    invalid: u64,
    malformed: u64,
    clipped: u64,
}

impl Batch {
    /// Parses the packets in `bytes` into `out`, after the samples already delivered.
    fn parse<C: Chip>(&mut self, bytes: &[u8], out: &mut [RawSample]) {
        for p in bytes.chunks_exact(packet::<C>()) {
            match C::parse(p) {
                Packet::Sample(s) => {
                    if let Some(slot) = out.get_mut(self.delivered) {
                        self.clipped += u64::from(s.clipped());
                        *slot = s;
                        self.delivered += 1;
                    }
                }
                Packet::Invalid => self.invalid += 1,
                // The "FIFO empty" marker inside the counted bytes is a damaged header.
                Packet::Malformed | Packet::End => self.malformed += 1,
            }
        }
    }

    /// Adds a batch that is delivered (one without malformed packets) to `stats`.
    fn count(&self, stats: &mut FifoStats) {
        stats.samples = stats.samples.saturating_add(self.delivered as u64);
        stats.invalid = stats.invalid.saturating_add(self.invalid);
        stats.clipped = stats.clipped.saturating_add(self.clipped);
    }
}

/// A data read of `len` bytes failed with `latest` bytes in the FIFO at the last count and
/// `taken` of them read before: decides a reset, and learns from FIFO_COUNT how many bytes the
/// failed transfer clocked out. Without a count, the first count read later (before the FIFO
/// is emptied) settles it.
async fn resync<C: Chip>(
    chip: &mut C,
    state: &mut FifoState,
    latest: u16,
    taken: usize,
    len: usize,
) {
    let taken = u16::try_from(taken).unwrap_or(u16::MAX).min(latest);
    let pending = state.pending.get_or_insert_with(PendingReset::default);
    pending.resync = true;
    pending.consumed = pending.consumed.saturating_add(u32::from(taken));
    pending.unresolved = Some(Unresolved {
        left: latest - taken,
        len: u16::try_from(len).unwrap_or(u16::MAX),
    });
    for _ in 0..COUNT_TRIES {
        match count(chip).await {
            Ok(c) => {
                observe::<C>(state, c);
                break;
            }
            Err(Error::BadFifoCount { .. }) => break,
            Err(_) => {}
        }
    }
}

/// Drops the packets of a call instead of delivering them: their `bytes` (already read) are
/// counted as discarded by the FIFO reset that follows, whose cause `mark` sets.
async fn drop_call<C: Chip>(
    chip: &mut C,
    state: &mut FifoState,
    bytes: usize,
    mark: impl FnOnce(&mut PendingReset),
) -> Result<usize, Error<C::BusError>> {
    // The call's bytes are the pending reset's now, whatever becomes of this future.
    state.in_call = None;
    let pending = state.pending.get_or_insert_with(PendingReset::default);
    mark(pending);
    pending.consumed = pending
        .consumed
        .saturating_add(u32::try_from(bytes).unwrap_or(u32::MAX));
    finish_reset(chip, state).await
}

/// The FIFO reset: channels off, the count of what it drops (stable now), a check that the
/// chip has not reset itself when the FIFO is empty, then empty and start. Every step can be
/// repeated: after a failure the whole sequence is simply run again.
async fn reset<C: Chip>(chip: &mut C, state: &mut FifoState) -> Result<(), Error<C::BusError>> {
    chip.write_all(C::MAP.fifo_stop).await?;
    if !chip.check(C::MAP.stopped).await? {
        // The channels are still on (a write corrupted on the wire): the count would not stay
        // still, and a sample written before the flush would go uncounted.
        return Err(Error::WriteNotApplied {
            register: C::MAP.stopped.reg,
        });
    }
    // The count, stable with the channels off, confirmed: one corrupted high on the wire would
    // count samples never written.
    let held = count(chip).await?.min(count(chip).await?);
    observe::<C>(state, held);
    // A sample that arrived after the call's INT_STATUS read and before the channels went off
    // may have raised the overflow flag again: read (and clear) it now, for this reset, which
    // drops what it is about.
    if chip.read_u8(C::MAP.int_status).await? & C::MAP.int_fifo_overflow != 0 {
        state.mark_overflow();
    }
    if held >= C::MAP.fifo_bytes {
        // A full FIFO has overwritten its oldest bytes: an overflow, whether or not its flag
        // was read (a read of INT_STATUS that failed may have cleared it).
        state.mark_overflow();
    }
    if held == 0 && !chip.check(C::MAP.configured).await? {
        // A chip that reset itself: starting its FIFO would hide the reset (the FIFO would
        // look configured, and stay empty).
        state.reset_seen = true;
        return Err(Error::SensorReset);
    }
    chip.write_all(C::MAP.fifo_empty).await?;
    // A flush that reported success but did not take (a write corrupted on the wire) leaves
    // the FIFO as it was: its bytes are not dropped yet, and are not counted as dropped.
    let left = count(chip).await?;
    if left != 0 {
        observe::<C>(state, left);
        return Err(Error::WriteNotApplied {
            register: C::MAP.fifo_empty.first().map_or(0, |w| w.0),
        });
    }
    if let Some(p) = state.pending.as_mut() {
        p.consumed = p.consumed.saturating_add(u32::from(p.held));
        p.held = 0;
    }
    chip.write_all(C::MAP.fifo_start).await
}

/// Counts a reset that has been carried out: its bytes as discarded, its cause. Returns the
/// complete samples discarded, and whether the cause is an overflow.
fn count_reset<C: Chip>(stats: &mut FifoStats, p: PendingReset) -> (u16, bool) {
    let bytes = p.consumed.saturating_add(u32::from(p.held));
    let discarded = bytes / u32::try_from(packet::<C>()).unwrap_or(1);
    let overflow = p.overflow || (p.flag_unknown && bytes >= u32::from(C::MAP.fifo_bytes));
    stats.discarded = stats.discarded.saturating_add(u64::from(discarded));
    stats.discarded_bytes = stats.discarded_bytes.saturating_add(u64::from(bytes));
    stats.unsure = stats.unsure.saturating_add(u64::from(p.unsure));
    stats.malformed = stats.malformed.saturating_add(p.malformed);
    if overflow {
        stats.overflows = stats.overflows.saturating_add(1);
    } else if p.resync {
        stats.resyncs = stats.resyncs.saturating_add(1);
    }
    (u16::try_from(discarded).unwrap_or(u16::MAX), overflow)
}

/// Carries out the pending reset and counts it: [`Error::FifoOverflow`] or
/// [`Error::FifoResync`]; a bus error keeps it pending.
async fn finish_reset<C: Chip>(
    chip: &mut C,
    state: &mut FifoState,
) -> Result<usize, Error<C::BusError>> {
    reset(chip, state).await?;
    let Some(p) = state.pending.take() else {
        return Ok(0);
    };
    let (discarded, overflow) = count_reset::<C>(&mut state.stats, p);
    if overflow {
        Err(Error::FifoOverflow { discarded })
    } else {
        Err(Error::FifoResync { discarded })
    }
}
