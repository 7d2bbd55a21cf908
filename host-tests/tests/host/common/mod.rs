//! Checks shared by the per-chip reader tests (`sensor_mpu6050.rs`, `sensor_icm42688.rs`): the
//! same guarantee, checked the same way on either chip, with the chip's own numbers. Each
//! takes the reader as an [`ImuReader`] (and, where a step is the chip's own, a closure), so
//! that a check reads the same for both readers.

#![allow(dead_code)]

use std::cell::RefCell;
use std::fmt::Debug;
use std::rc::Rc;

use imu_ar::sensor::{Error, ImuReader, RawSample};

use crate::sim::run::{Figures, fault_run};
use crate::sim::{Kind, Sim, decode};

/// Each `(range, counts)` of `table`: `sensitivity(range)` is exactly `counts`, the datasheet's
/// value.
pub fn assert_sensitivities<R: Copy + Debug>(table: &[(R, f32)], sensitivity: fn(R) -> f32) {
    for &(range, counts) in table {
        assert_eq!(sensitivity(range), counts, "{range:?}");
    }
}

/// A FIFO read that finds the FIFO overflowed resets it and counts its `discarded` samples;
/// the next read delivers the one sample written since.
pub fn overflow_then_one_sample<R: ImuReader>(imu: &mut R, discarded: u16)
where
    R::BusError: Debug + PartialEq,
{
    let mut out = [RawSample::default(); 4];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded })
    );
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    let stats = imu.fifo_stats();
    assert_eq!(
        (stats.overflows, stats.discarded, stats.samples),
        (1, u64::from(discarded), 1)
    );
}

/// Lets the chip produce `n` samples, reads once, and checks that exactly those come out,
/// well-formed and in order.
pub fn expect_samples<R: ImuReader>(sim: &Rc<RefCell<Sim>>, imu: &mut R, n: u64)
where
    R::BusError: Debug,
{
    let first = sim.borrow().ticks;
    sim.borrow_mut().tick(n);
    let mut out = [RawSample::default(); 160];
    let k = imu.read_fifo(&mut out).expect("samples flow");
    let seqs: Vec<Option<u64>> = out[..k].iter().map(decode).collect();
    let expected: Vec<Option<u64>> = (first..first + n).map(Some).collect();
    assert_eq!(seqs, expected, "the samples the chip produced, well-formed");
}

/// The chip resets itself and `read_fifo` says so; a `recover` that meets the fault
/// scheduled at the `skip`-th next transfer of `fault` fails, and leaves `read_fifo` saying
/// that the FIFO is not running; the next `recover` succeeds and returns WHO_AM_I, `id`.
pub fn recover_after_a_failed_recover<R: ImuReader>(
    sim: &Rc<RefCell<Sim>>,
    imu: &mut R,
    (fault, skip): (Kind, u32),
    mut recover: impl FnMut(&mut R, u64) -> Result<u8, Error<R::BusError>>,
    id: u8,
) where
    R::BusError: Debug + PartialEq,
{
    sim.borrow_mut().glitch();
    let mut out = [RawSample::default(); 16];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    sim.borrow_mut().fail(fault, skip, 0);
    assert!(matches!(recover(imu, 10_000), Err(Error::Bus(_))));
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoNotRunning));
    assert_eq!(recover(imu, 20_000), Ok(id));
}

/// The read that meets the scheduled bus fault fails; the next one finds the overflow that
/// was kept pending, resets the FIFO and counts its `discarded` samples.
pub fn overflow_after_a_bus_error<R: ImuReader>(imu: &mut R, out: &mut [RawSample], discarded: u16)
where
    R::BusError: Debug + PartialEq,
{
    assert!(matches!(imu.read_fifo(out), Err(Error::Bus(_))));
    assert_eq!(imu.read_fifo(out), Err(Error::FifoOverflow { discarded }));
}

/// A FIFO data read fails after clocking out `clock_out` bytes: the FIFO is reset to
/// realign its packets, and its `discarded` samples are counted.
pub fn resync_after_a_failed_data_read<R: ImuReader>(
    sim: &Rc<RefCell<Sim>>,
    imu: &mut R,
    out: &mut [RawSample],
    (data, clock_out): (Kind, usize),
    discarded: u16,
) where
    R::BusError: Debug + PartialEq,
{
    sim.borrow_mut().fail(data, 0, clock_out);
    assert_eq!(imu.read_fifo(out), Err(Error::FifoResync { discarded }));
}

/// With the bus stuck high, FIFO_COUNT reads 0xFFFF: no count. Each of `reads` calls reads
/// and counts nothing; once the bus is back, the overflow flag read as set is kept, and the
/// FIFO's `discarded` real samples are counted.
pub fn stuck_high_count_is_no_count<R: ImuReader>(
    sim: &Rc<RefCell<Sim>>,
    imu: &mut R,
    out: &mut [RawSample],
    reads: usize,
    discarded: u16,
) where
    R::BusError: Debug + PartialEq,
{
    sim.borrow_mut().stuck_high = true;
    for _ in 0..reads {
        assert_eq!(
            imu.read_fifo(out),
            Err(Error::BadFifoCount { count: 0xFFFF })
        );
    }
    assert_eq!(imu.fifo_stats().discarded, 0);
    sim.borrow_mut().stuck_high = false;
    assert_eq!(imu.read_fifo(out), Err(Error::FifoOverflow { discarded }));
}

/// Issue 24 acceptance: at least 10^5 samples with faults at 1 % of every kind of transfer
/// ([`fault_run`] checks that every sample is delivered well-formed or counted, exactly, and
/// that samples flow again after one recover), with overflows and resyncs among them.
pub fn random_bus_faults<R: ImuReader>(
    sim: &Rc<RefCell<Sim>>,
    imu: &mut R,
    recover: impl FnMut(&mut R, u64) -> Result<(), Error<R::BusError>>,
    seed: u64,
    chip: &str,
) -> Figures
where
    R::BusError: Debug,
{
    let figures = fault_run(sim, imu, recover, seed, 0.01, 100_000);
    println!("{chip} {figures:#?}");
    assert!(figures.delivered >= 100_000);
    assert!(figures.stats.overflows > 0 && figures.stats.resyncs > 0);
    figures
}
