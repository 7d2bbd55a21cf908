//! The loop a board runs around a FIFO reader, written once so that the same code runs on the
//! board and, against the project's chip simulator, on the host: each pass reads the board's
//! clock, then the FIFO, and recovers the chip when the reader asks for it, passing the outage
//! since the last read that accounted for the FIFO ([`Driver::recover`]).

use embedded_hal::delay::DelayNs;
use embedded_hal_async::delay::DelayNs as AsyncDelayNs;

use super::chip::Chip;
use super::{AsyncDriver, Driver, Error, ImuReader, RawSample};

/// Microseconds since start from a wrapping 32-bit cycle counter (the Cortex-M DWT's CYCCNT),
/// extended to 64 bits. Exact as long as the counter is read at least once per wrap (51 s at
/// 84 MHz, 21 s at 200 MHz): [`FifoLoop::pass`] reads it on every pass, whatever the pass
/// meets.
#[derive(Clone, Copy, Debug)]
pub struct CycleClock {
    cycles_per_us: u64,
    last: u32,
    cycles: u64,
}

impl CycleClock {
    /// A clock counting `cycles_per_us` cycles per microsecond (at least 1), started at the
    /// counter's value `counter`.
    pub fn new(cycles_per_us: u32, counter: u32) -> Self {
        Self {
            cycles_per_us: u64::from(cycles_per_us.max(1)),
            last: counter,
            cycles: 0,
        }
    }

    /// Microseconds since the start, with the counter now at `counter`.
    pub fn now_us(&mut self, counter: u32) -> u64 {
        self.cycles = self
            .cycles
            .saturating_add(u64::from(counter.wrapping_sub(self.last)));
        self.last = counter;
        self.cycles / self.cycles_per_us
    }
}

/// A reader that can bring its chip back after a reset or an outage: [`Driver::recover`].
pub trait Recover: ImuReader {
    /// [`Driver::recover`].
    ///
    /// # Errors
    ///
    /// As [`Driver::recover`].
    fn recover(
        &mut self,
        delay: &mut impl DelayNs,
        outage_us: u64,
    ) -> Result<u8, Error<Self::BusError>>;
}

impl<C: Chip> Recover for Driver<C> {
    fn recover(
        &mut self,
        delay: &mut impl DelayNs,
        outage_us: u64,
    ) -> Result<u8, Error<Self::BusError>> {
        Driver::recover(self, delay, outage_us)
    }
}

/// What one [`FifoLoop::pass`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass<E> {
    /// This many samples were read into `out`.
    Samples(usize),
    /// The reader dropped and counted the FIFO's samples ([`Error::FifoOverflow`],
    /// [`Error::FifoResync`]): nothing to process.
    Dropped(Error<E>),
    /// The chip was recovered ([`Error::SensorReset`], [`Error::FifoNotRunning`]); the
    /// samples of the outage are counted in [`FifoStats::lost`](super::FifoStats::lost).
    Recovered {
        /// The outage passed to `recover`, microseconds.
        outage_us: u64,
    },
    /// A recovery failed; the next pass tries again.
    RecoveryFailed(Error<E>),
    /// Any other error (a bus error: the sensor unplugged, say); the next pass tries again.
    Failed(Error<E>),
}

/// The FIFO loop of a board: call [`FifoLoop::pass`] once per loop iteration.
#[derive(Clone, Copy, Debug)]
pub struct FifoLoop {
    clock: CycleClock,
    /// When a read last accounted for the FIFO, or a recovery started it again, by the clock.
    accounted_us: u64,
    recovery_us: u64,
}

impl FifoLoop {
    /// A loop on `clock`, from the counter's value `counter` (the FIFO accounted for then);
    /// `recovery_us` is the time from the call of `recover` to the FIFO running again (the
    /// chip's reset and start delays: 100 ms on the MPU-6050, 2 ms on the ICM-42688-P).
    pub fn new(mut clock: CycleClock, counter: u32, recovery_us: u64) -> Self {
        let accounted_us = clock.now_us(counter);
        Self {
            clock,
            accounted_us,
            recovery_us,
        }
    }

    /// One pass, reading the cycle counter with `counter`: reads the clock (on every pass, so
    /// that it never misses a wrap however long the sensor is away), then the FIFO into `out`,
    /// then the clock again; on [`Error::SensorReset`] or [`Error::FifoNotRunning`] recovers
    /// the chip, passing the outage from the last accounting to the end of the recovery.
    ///
    /// A read that returns samples accounts for the FIFO as it was when the read began (the
    /// samples that arrive during it stay in the FIFO for the next pass); a FIFO reset
    /// ([`Pass::Dropped`]) accounts for it as it was when the read ended (the reset drops, and
    /// counts, what arrived during the read).
    pub fn pass<R: Recover>(
        &mut self,
        mut counter: impl FnMut() -> u32,
        imu: &mut R,
        delay: &mut impl DelayNs,
        out: &mut [RawSample],
    ) -> Pass<R::BusError> {
        let before = self.clock.now_us(counter());
        let result = imu.read_fifo(out);
        let after = self.clock.now_us(counter());
        match self.read(before, after, result) {
            Next::Done(pass) => pass,
            Next::Recover { outage_us } => {
                let result = imu.recover(delay, outage_us);
                self.recovered(after, outage_us, result)
            }
        }
    }

    /// [`FifoLoop::pass`] with an async reader ([`AsyncDriver`]): the same steps and
    /// decisions, awaited.
    pub async fn pass_async<C: Chip>(
        &mut self,
        mut counter: impl FnMut() -> u32,
        imu: &mut AsyncDriver<C>,
        delay: &mut impl AsyncDelayNs,
        out: &mut [RawSample],
    ) -> Pass<C::BusError> {
        let before = self.clock.now_us(counter());
        let result = imu.read_fifo(out).await;
        let after = self.clock.now_us(counter());
        match self.read(before, after, result) {
            Next::Done(pass) => pass,
            Next::Recover { outage_us } => {
                let result = imu.recover(delay, outage_us).await;
                self.recovered(after, outage_us, result)
            }
        }
    }

    /// What a FIFO read that began at `before` and ended at `after` (µs) leads to.
    fn read<E>(&mut self, before: u64, after: u64, result: Result<usize, Error<E>>) -> Next<E> {
        match result {
            Ok(n) => {
                self.accounted_us = before;
                Next::Done(Pass::Samples(n))
            }
            Err(e @ (Error::FifoOverflow { .. } | Error::FifoResync { .. })) => {
                self.accounted_us = after;
                Next::Done(Pass::Dropped(e))
            }
            Err(Error::SensorReset | Error::FifoNotRunning) => Next::Recover {
                outage_us: after
                    .saturating_sub(self.accounted_us)
                    .saturating_add(self.recovery_us),
            },
            Err(e) => Next::Done(Pass::Failed(e)),
        }
    }

    /// What a recovery called at `after` (µs) with `outage_us` gave.
    fn recovered<E>(
        &mut self,
        after: u64,
        outage_us: u64,
        result: Result<u8, Error<E>>,
    ) -> Pass<E> {
        match result {
            Ok(_) => {
                self.accounted_us = after.saturating_add(self.recovery_us);
                Pass::Recovered { outage_us }
            }
            Err(e) => Pass::RecoveryFailed(e),
        }
    }
}

/// What follows a FIFO read in a pass.
enum Next<E> {
    /// The pass is over.
    Done(Pass<E>),
    /// The chip is to be recovered, with this outage.
    Recover { outage_us: u64 },
}
