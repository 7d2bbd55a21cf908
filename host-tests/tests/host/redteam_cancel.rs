//! Red team: async `read_fifo` futures cancelled part-way (embassy `select` / `with_timeout`).
//! A cancelled future is dropped at one of its suspension points; the reader must stay
//! consistent and every sample the chip wrote must still be delivered or counted.

use std::cell::RefCell;
use std::future::Future;
use std::pin::{Pin, pin};
use std::rc::Rc;
use std::task::{Context, Poll, Waker};

use embedded_hal::i2c::{self, I2c};
use embedded_hal::spi::{self, Operation, SpiDevice};
use imu_ar::sensor::{
    Dlpf, Error, Icm42688Async, Icm42688Config, Mpu6050Async, Mpu6050Config, Odr, RawSample,
};

use crate::sim::asynch::{AsyncBus, AsyncNoDelay, block_on};
use crate::sim::icm42688::{self as icm, SimSpi};
use crate::sim::mpu6050::SimI2c;
use crate::sim::{Model, Sim, decode};

fn mpu_config() -> Mpu6050Config {
    Mpu6050Config {
        dlpf: Dlpf::Hz44,
        sample_rate_divider: 0,
        ..Mpu6050Config::default()
    }
}

fn icm_config() -> Icm42688Config {
    Icm42688Config {
        odr: Odr::Hz1000,
        ..Icm42688Config::default()
    }
}

/// Polls `fut` `polls` times (or until ready), then drops it: `Some(output)` if it completed.
fn poll_then_drop<F: Future>(fut: F, polls: usize) -> Option<F::Output> {
    let mut fut = pin!(fut);
    let mut cx = Context::from_waker(Waker::noop());
    for _ in 0..polls {
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return Some(v);
        }
    }
    None
}

/// MPU-6050 async reader: 20 samples in the FIFO; the `read_fifo` future is polled `polls`
/// times and dropped (a timeout); then the chip writes 5 more and the reader is called until
/// the FIFO is drained. Returns (produced, delivered + counted, stats) for each cut.
#[test]
fn mpu_cancelled_read_fifo_loses_no_sample_uncounted() {
    let mut failures = Vec::new();
    for polls in 1..=12 {
        let sim = Sim::new(Model::Mpu6050, 700 + polls as u64);
        let mut imu = Mpu6050Async::new(AsyncBus(SimI2c(sim.clone())), 0x68);
        block_on(imu.init(&mut AsyncNoDelay, mpu_config())).unwrap();
        block_on(imu.enable_fifo()).unwrap();
        let mut out = [RawSample::default(); 128];
        sim.borrow_mut().tick(20);
        let first = poll_then_drop(imu.read_fifo(&mut out), polls);
        let mut delivered = 0u64;
        if let Some(Ok(k)) = first {
            delivered += k as u64;
        }
        sim.borrow_mut().tick(5);
        for _ in 0..3 {
            match block_on(imu.read_fifo(&mut out)) {
                Ok(k) => {
                    assert!(out[..k].iter().all(|s| decode(s).is_some()), "garbage");
                    delivered += k as u64;
                }
                Err(Error::FifoOverflow { .. } | Error::FifoResync { .. }) => {}
                Err(e) => panic!("cut after {polls} polls: {e:?}"),
            }
        }
        let s = imu.fifo_stats();
        let sim = sim.borrow();
        let counted =
            delivered + s.discarded + s.invalid + s.malformed + s.lost + sim.fifo_packets();
        if counted != sim.produced {
            failures.push(format!(
                "cut after {polls} polls ({} transfers done): chip wrote {}, accounted {counted} \
                 (delivered {delivered}, discarded {})",
                polls - 1,
                sim.produced,
                s.discarded
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "samples lost uncounted by a cancelled read_fifo:\n{}",
        failures.join("\n")
    );
}

/// The same on the ICM-42688-P async reader.
#[test]
fn icm_cancelled_read_fifo_loses_no_sample_uncounted() {
    let mut failures = Vec::new();
    for polls in 1..=14 {
        let sim = Sim::new(Model::Icm42688, 800 + polls as u64);
        let mut imu = Icm42688Async::new(AsyncBus(SimSpi(sim.clone())));
        block_on(imu.init(&mut AsyncNoDelay, icm_config())).unwrap();
        block_on(imu.enable_fifo()).unwrap();
        let mut out = [RawSample::default(); 160];
        sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
        assert_eq!(block_on(imu.read_fifo(&mut out)), Ok(0));
        let base = imu.fifo_stats();
        let produced0 = sim.borrow().produced;
        sim.borrow_mut().tick(20);
        let first = poll_then_drop(imu.read_fifo(&mut out), polls);
        let mut delivered = 0u64;
        if let Some(Ok(k)) = first {
            delivered += k as u64;
        }
        sim.borrow_mut().tick(5);
        for _ in 0..3 {
            match block_on(imu.read_fifo(&mut out)) {
                Ok(k) => {
                    assert!(out[..k].iter().all(|s| decode(s).is_some()), "garbage");
                    delivered += k as u64;
                }
                Err(Error::FifoOverflow { .. } | Error::FifoResync { .. }) => {}
                Err(e) => panic!("cut after {polls} polls: {e:?}"),
            }
        }
        let s = imu.fifo_stats();
        let sim = sim.borrow();
        let counted = delivered
            + (s.discarded - base.discarded)
            + (s.invalid - base.invalid)
            + (s.malformed - base.malformed)
            + sim.fifo_packets();
        let produced = sim.produced - produced0;
        if counted != produced {
            failures.push(format!(
                "cut after {polls} polls ({} transfers done): chip wrote {produced}, accounted \
                 {counted} (delivered {delivered}, discarded {})",
                polls - 1,
                s.discarded - base.discarded
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "samples lost uncounted by a cancelled read_fifo:\n{}",
        failures.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// A DMA-style bus: the transfer runs at the first poll (the hardware moves the bytes), and the
// future completes at the next poll (the completion interrupt). A future dropped in between has
// had its transfer done: the bytes are out of the chip, INT_STATUS is cleared.

struct DoneThenYield(bool);

impl Future for DoneThenYield {
    type Output = ();
    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        if self.0 {
            Poll::Ready(())
        } else {
            self.0 = true;
            cx.waker().wake_by_ref();
            Poll::Pending
        }
    }
}

pub struct DmaBus<B>(pub B);

impl<B: i2c::ErrorType> i2c::ErrorType for DmaBus<B> {
    type Error = B::Error;
}

impl<B: I2c> embedded_hal_async::i2c::I2c for DmaBus<B> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [i2c::Operation<'_>],
    ) -> Result<(), Self::Error> {
        let r = self.0.transaction(address, operations);
        DoneThenYield(false).await;
        r
    }
}

impl<B: spi::ErrorType> spi::ErrorType for DmaBus<B> {
    type Error = B::Error;
}

impl<B: SpiDevice> embedded_hal_async::spi::SpiDevice for DmaBus<B> {
    async fn transaction(
        &mut self,
        operations: &mut [Operation<'_, u8>],
    ) -> Result<(), Self::Error> {
        let r = self.0.transaction(operations);
        DoneThenYield(false).await;
        r
    }
}

/// MPU-6050 async reader on a DMA-style bus: 85 packets (1020 bytes) in the FIFO, one sample
/// arrives before the data read, overwriting 8 bytes: the read is misaligned, and the closing
/// INT_STATUS read says so. The future is dropped right after that INT_STATUS transfer ran
/// (a timeout firing together with the DMA completion). The flag is gone; 4 bytes are left in
/// the FIFO, so every later packet is shifted by 4 bytes.
/// Expected: no misaligned (garbage) sample is ever delivered.
#[test]
fn mpu_cancel_after_closing_int_status_delivers_no_garbage() {
    let sim = Sim::new(Model::Mpu6050, 901);
    let hooks = crate::sim::hooks::Hooks::default();
    let bus = crate::sim::hooks::HookedI2c {
        sim: sim.clone(),
        inner: SimI2c(sim.clone()),
        hooks: hooks.clone(),
    };
    let mut imu = Mpu6050Async::new(DmaBus(bus), 0x68);
    block_on(imu.init(&mut AsyncNoDelay, mpu_config())).unwrap();
    block_on(imu.enable_fifo()).unwrap();
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(85);
    hooks.add(
        crate::sim::Kind::Read(crate::sim::mpu6050::FIFO_R_W),
        0,
        crate::sim::hooks::Action::TickBefore(1),
    );
    // Transfers: INT_STATUS, FIFO_COUNT x2, FIFO_R_W x11 (85 packets), INT_STATUS: 15. Each
    // runs at a poll and completes at the next; the 15th has run after 15 polls.
    let before = sim.borrow().transfers.values().sum::<u64>();
    let r = poll_then_drop(imu.read_fifo(&mut out), 15);
    let ran = sim.borrow().transfers.values().sum::<u64>() - before;
    assert!(r.is_none() && ran == 15, "{r:?}, {ran} transfers");
    // The next calls, with the chip writing on.
    let mut garbage = 0;
    let mut good = 0;
    for _ in 0..5 {
        sim.borrow_mut().tick(20);
        if let Ok(k) = block_on(imu.read_fifo(&mut out)) {
            garbage += out[..k].iter().filter(|s| decode(s).is_none()).count();
            good += out[..k].iter().filter(|s| decode(s).is_some()).count();
        }
    }
    assert_eq!(
        garbage, 0,
        "{garbage} misaligned samples delivered ({good} good) after a cancelled read_fifo"
    );
    // The chip overflowed (its flag was read, and cleared, by the cancelled call): README
    // "every overflow is counted".
    assert_eq!(
        imu.fifo_stats().overflows,
        1,
        "the overflow seen by the cancelled call's INT_STATUS read is lost: {:?}",
        imu.fifo_stats()
    );
}

/// Smoke: the DMA-style bus runs the reader normally when nothing is cancelled.
#[test]
fn dma_bus_reader_works_uncancelled() {
    let sim = Sim::new(Model::Mpu6050, 902);
    let mut imu = Mpu6050Async::new(DmaBus(SimI2c(sim.clone())), 0x68);
    block_on(imu.init(&mut AsyncNoDelay, mpu_config())).unwrap();
    block_on(imu.enable_fifo()).unwrap();
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(30);
    assert_eq!(block_on(imu.read_fifo(&mut out)), Ok(30));
    let _ = Rc::clone(&sim);
    let _: Option<RefCell<()>> = None;
}
